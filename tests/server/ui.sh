#!/bin/sh
# ui.sh - the web console (web/, compiled into qdcd): what qdcd serves at / and
# /ui/ (media types, Content-Security-Policy, ETag and 304, 404s, no token
# needed for the page), then the page itself in Debian's chromium driven by
# playwright-core (tests/ui/console.mjs, installed by `npm ci` from
# tests/ui/package-lock.json into build/uitest): first paint, the sample
# submitted through the file input, the chart growing while a job runs, the
# histograms, downloads checked with `qdc quality`, cancel/delete/filter, a
# phone-sized layout (no table column cut), the charts' axes, tooltips, log
# scales and rerun notes, the 3D view's fit, reset, clip plane, click-to-inspect
# and lighter detail while turning (its first frame and frame rates measured),
# ARIA roles and live regions, axe-core (0 serious violations), no console
# errors, XDMF+HDF5 (with qdc-h5 built: the .xdmf alone gets a message asking
# for its .h5, the two picked together are sent as FormData and the job
# succeeds; a gzipped .xmf.gz + .h5.gz pair is gunzipped by the page and sent
# the same), and the token prompt with --tokens; a page served from another
# origin whose script POSTs a mesh gets 403 (tests/ui/crossorigin.mjs).
# Before the browser: GET /v1/options (the form's table) and GET /input (the
# job's input mesh: every format, Accept, ETag, 404/409, a surface's TetGen
# mesh) with curl; their token rules on the --tokens daemon. The screenshot
# job is a default-mode run submitted with the form untouched; its 3D view
# must show the input's worst tets (orange) and the result's (red).
# Screenshots go to build/ui-shots, or to UI_SHOTS (UI_SHOTS=docs remakes
# docs/ui-list.png, ui-job.png, ui-phone.png for the README). UI_1M=1 adds the
# view of a finished ~1M-tet job (a few minutes; not in the default run).
# Without chromium or npm the browser part prints # SKIP lines.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"
SAMPLE=$ROOT/tests/data/sample/cube.mesh

start_qdcd "$TMP/d" --workers 1 || { fail "start" "$(tail -3 "$TMP/d.log")"; exit 1; }

# ------------------------------------------------------------ headers (curl) --
for p in /:text/html /ui/app.js:text/javascript /ui/style.css:text/css /ui/icon.svg:image/svg+xml \
    /ui/jobs/0123456789abcdef0123456789abcdef:text/html; do
    path=${p%%:*}
    want=${p#*:}
    code=$(req GET "$path" "$TMP/h")
    ct=$(hdr "$TMP/h" Content-Type)
    csp=$(hdr "$TMP/h" Content-Security-Policy)
    case "$code $ct" in
    "200 $want"*) pass "GET $path: 200 $ct" ;;
    *) fail "GET $path" "status $code, Content-Type '$ct'" ;;
    esac
    case "$csp" in
    *"default-src 'self'"*"script-src 'self'"*"frame-ancestors 'none'"*)
        case "$csp" in
        *unsafe*) fail "CSP $path" "$csp" ;;
        *) pass "GET $path: strict Content-Security-Policy (self only, no inline code, no framing)" ;;
        esac ;;
    *) fail "CSP $path" "'$csp'" ;;
    esac
done
code=$(req GET /ui/app.js "$TMP/js")
etag=$(hdr "$TMP/js" ETag)
cc=$(hdr "$TMP/js" Cache-Control)
if [ "$code" = 200 ] && [ "$cc" = no-cache ] && expr "$etag" : '"[0-9a-f]\{32\}"$' > /dev/null &&
    [ "$(sha256sum < "$ROOT/web/app.js" | cut -c1-32)" = "$(echo "$etag" | tr -d '"')" ]; then
    pass "app.js: Cache-Control no-cache, strong ETag = SHA-256 prefix of web/app.js ($etag)"
else
    fail "ETag" "status $code, ETag '$etag', Cache-Control '$cc'"
fi
if cmp -s "$TMP/js" "$ROOT/web/app.js"; then
    pass "app.js served byte for byte as in web/ (compiled in)"
else
    fail "app.js content" "differs from web/app.js (rebuild qdcd?)"
fi
code=$(req GET /ui/app.js "$TMP/js304" -H "If-None-Match: $etag")
if [ "$code" = 304 ] && [ ! -s "$TMP/js304" ] && [ "$(hdr "$TMP/js304" ETag)" = "$etag" ]; then
    pass "If-None-Match: 304, empty body, same ETag"
else
    fail "304" "status $code"
fi
code=$(req GET /ui/app.js "$TMP/js200" -H 'If-None-Match: "0000"')
[ "$code" = 200 ] && pass "a stale ETag gets 200" || fail "stale ETag" "status $code"
code=$(req HEAD / "$TMP/head" -I)
[ "$code" = 200 ] && [ "$(hdr "$TMP/head" ETag)" != "" ] && pass "HEAD /: 200 with the ETag" || fail "HEAD /" "status $code"
for p in /ui/nope.js /ui/jobs/xyz /ui/jobs/0123456789ABCDEF0123456789ABCDEF /ui/../v1/jobs; do
    code=$(req GET "$p" "$TMP/nf" --path-as-is)
    [ "$code" = 404 ] && pass "GET $p: 404" || fail "GET $p" "status $code"
done
code=$(req POST / "$TMP/post")
[ "$code" = 405 ] && [ "$(hdr "$TMP/post" Allow)" = GET ] && pass "POST /: 405, Allow: GET" || fail "POST /" "status $code"
# the page references only its own files (no network beyond qdcd)
if grep -Eq '(src|href)="(https?:)?//' "$ROOT/web/index.html" || grep -Eq "https?://" "$ROOT/web/app.js" "$ROOT/web/style.css"; then
    fail "no external resources" "web/ names another origin"
else
    pass "web/ names no other origin (the page needs nothing beyond qdcd)"
fi

# --------------------------------------------- /v1/options, /input (curl) --
# the page's form is built from /v1/options: the library's table as `qdc options`
"$BIN/qdc" options > "$TMP/options.json"
code=$(req GET /v1/options "$TMP/opts")
if [ "$code" = 200 ] && jq -e --slurpfile t "$TMP/options.json" \
    '[.options[] | select(.surface | not)] == $t[0] and ([.options[] | select(.surface) | .name] == ["tetgen_quality", "max_volume"])' \
    "$TMP/opts" > /dev/null; then
    pass "GET /v1/options: the $(jq length "$TMP/options.json") options of \`qdc options\` (same members), then tetgen_quality and max_volume for surfaces"
else
    fail "/v1/options" "status $code $(head -c 300 "$TMP/opts")"
fi

ext_of() { case $1 in medit) echo mesh ;; gmsh*) echo msh ;; vtk*) echo vtk ;; vtu*) echo vtu ;; *) echo "$1" ;; esac; }
# the input (sample cube) and what qdc quality says of it, without the file name
"$BIN/qdc" quality "$SAMPLE" 2>&1 | sed 1s/^[^:]*:// > "$TMP/q.in"
# a long job holds the one worker: the surface behind it is still queued
code=$(submit "$SAMPLE" model/x-medit "max_iter=10000&mode=literal&finish=off&tol_move=0&time_limit=30" "$TMP/hold")
HOLD=$(jf "$TMP/hold" .id)
code2=$(submit "$SAMPLE" model/x-medit "max_iter=3" "$TMP/sub")
SJ=$(jf "$TMP/sub" .id)
$PY "$ROOT/tests/server/surfaces.py" stl cube "$TMP/cube.stl"
$PY "$ROOT/tests/server/surfaces.py" stl selfx "$TMP/selfx.stl"
code3=$(submit "$TMP/cube.stl" model/stl "tetgen_quality=1.4&max_volume=0.005" "$TMP/subs")
SS=$(jf "$TMP/subs" .id)
code4=$(submit "$TMP/selfx.stl" model/stl "" "$TMP/subx")
SX=$(jf "$TMP/subx" .id)
[ "$code$code2$code3$code4" = 202202202202 ] || fail "submit for /input" "$code $code2 $code3 $code4"
# at once, while queued: the uploaded mesh is there; the surface's tets are not yet
code=$(req GET "/v1/jobs/$SJ/input" "$TMP/in.qmesh")
if [ "$code" = 200 ] && [ "$(curl -s "$URL/v1/jobs/$SJ" | jq -r .state)" = queued ] &&
    [ "$(hdr "$TMP/in.qmesh" Content-Type)" = application/vnd.qdc.mesh ] &&
    "$BIN/qdc" quality "$TMP/in.qmesh" 2>&1 | sed 1s/^[^:]*:// | cmp -s - "$TMP/q.in"; then
    pass "GET /input of a queued job: 200, the binary by default, qdc quality reads the sample's figures ($(head -1 "$TMP/q.in" | cut -c1-40)...)"
else
    fail "/input queued" "status $code $(head -c 200 "$TMP/in.qmesh")"
fi
code=$(req GET "/v1/jobs/$SS/input" "$TMP/sin")
if [ "$code" = 409 ] && [ "$(hdr "$TMP/sin" Retry-After)" = 2 ] && jq -e '.type | endswith("not-ready")' "$TMP/sin" > /dev/null; then
    pass "GET /input of a queued surface job: 409 not-ready with Retry-After (no tets yet)"
else
    fail "/input queued surface" "status $code $(head -c 200 "$TMP/sin")"
fi
curl -s -X POST "$URL/v1/jobs/$HOLD:cancel" > /dev/null
st1=$(wait_done "$SJ")
st2=$(wait_done "$SS")
st3=$(wait_done "$SX")
[ "$st1 $st2 $st3" = "succeeded succeeded failed" ] || fail "jobs for /input" "$st1 $st2 $st3"
# every format of /result, by name: the same media type as /result, read back by qdc quality
formats=$(curl -s "$URL/v1/jobs/$SJ/input?format=none" | jq -r '.formats[]')
bad=
n=0
for f in $formats; do
    [ "$f" = binary ] || [ "$f" = mesh ] && continue
    x=$(ext_of "$f")
    code=$(req GET "/v1/jobs/$SJ/input?format=$f" "$TMP/in-$f.$x")
    req GET "/v1/jobs/$SJ/result?format=$f" "$TMP/out-$f.$x" > /dev/null
    if [ "$code" != 200 ] || [ "$(hdr "$TMP/in-$f.$x" Content-Type)" != "$(hdr "$TMP/out-$f.$x" Content-Type)" ] ||
        ! "$BIN/qdc" quality "$TMP/in-$f.$x" 2>&1 | sed 1s/^[^:]*:// | cmp -s - "$TMP/q.in"; then
        bad="$bad $f:$code:$(hdr "$TMP/in-$f.$x" Content-Type)"
    fi
    n=$((n + 1))
done
[ -z "$bad" ] && [ $n -ge 10 ] && pass "GET /input?format=F: all $n formats, media types as /result, each read back by qdc quality as the uploaded sample" ||
    fail "/input formats" "$bad (of $n)"
# Accept, ETag, 304, Vary, 400/406 as /result
code=$(req GET "/v1/jobs/$SJ/input" "$TMP/in22" -H 'Accept: image/png, model/vnd.gmsh;version=2.2')
etag=$(hdr "$TMP/in22" ETag)
if [ "$code" = 200 ] && [ "$(sed -n 2p "$TMP/in22" | cut -c1-3)" = 2.2 ] && [ "$(hdr "$TMP/in22" Vary)" = Accept ] &&
    [ "\"$(sha256sum < "$TMP/in22" | cut -c1-64)\"" = "$etag" ]; then
    pass "GET /input, Accept: image/png, model/vnd.gmsh;version=2.2: MSH 2.2, Vary: Accept, strong ETag = SHA-256 of the body"
else
    fail "/input Accept" "status $code ETag $etag $(head -c 100 "$TMP/in22")"
fi
code=$(req GET "/v1/jobs/$SJ/input" "$TMP/in304" -H 'Accept: model/vnd.gmsh;version=2.2' -H "If-None-Match: $etag")
[ "$code" = 304 ] && [ ! -s "$TMP/in304" ] && pass "GET /input with If-None-Match: 304" || fail "/input 304" "status $code"
code=$(req GET "/v1/jobs/$SJ/input" "$TMP/in406" -H 'Accept: image/png')
code2=$(req GET "/v1/jobs/$SJ/input?format=png" "$TMP/in400")
[ "$code $code2" = "406 400" ] && jq -e '.formats | length >= 10' "$TMP/in400" > /dev/null &&
    pass "GET /input: 406 for Accept: image/png, 400 listing the formats for ?format=png" || fail "/input 406/400" "$code $code2"
for p in "/v1/jobs/0123456789abcdef0123456789abcdef/input" "/v1/jobs/xyz/input"; do
    code=$(req GET "$p" "$TMP/in404")
    [ "$code" = 404 ] && jq -e '.status == 404' "$TMP/in404" > /dev/null && pass "GET $p: 404 problem" || fail "GET $p" "status $code"
done
code=$(req POST "/v1/jobs/$SJ/input" "$TMP/in405")
[ "$code" = 405 ] && pass "POST /input: 405" || fail "POST /input" "status $code"
# the surface job's input is TetGen's mesh: the tets the report's "before" counts
code=$(req GET "/v1/jobs/$SS/input?format=medit" "$TMP/sin.mesh")
nt=$("$BIN/qdc" quality "$TMP/sin.mesh" 2> /dev/null | sed -n '1s/.* \([0-9]*\) tets.*/\1/p')
bt=$(curl -s "$URL/v1/jobs/$SS/report" | jq -r .before.n_tets)
[ "$code" = 200 ] && [ -n "$nt" ] && [ "$nt" = "$bt" ] && [ "$nt" = "$(jf "$TMP/job.$SS" .mesh.tets)" ] &&
    pass "GET /input of a surface job: TetGen's mesh ($nt tets, as the report's before and the job)" ||
    fail "/input surface" "status $code, $nt tets, report $bt"
code=$(req GET "/v1/jobs/$SX/input" "$TMP/xin")
[ "$code" = 409 ] && jq -e '.title | test("no input")' "$TMP/xin" > /dev/null &&
    pass "GET /input of a surface job TetGen failed on: 409 (no input mesh)" || fail "/input failed surface" "status $code $(head -c 200 "$TMP/xin")"
code=$(req GET "/v1/jobs/$HOLD/input" "$TMP/hin")
[ "$code" = 200 ] && pass "GET /input of a cancelled job: 200 (the input stays until the job expires)" || fail "/input cancelled" "status $code"
# the page starts from an empty list
for j in $HOLD $SJ $SS $SX; do curl -s -X DELETE "$URL/v1/jobs/$j" > /dev/null; done

# ---------------------------------------------------------------- browser --
. "$(dirname "$0")/uimods.inc"
ui_modules || { stop_qdcd; exit $((NFAIL > 0)); }

mkdir -p "$TMP/out"
export UI_MODULES="$MODS" QDC_URL="$URL" UI_OUT="$TMP/out" OPTIONS_JSON="$TMP/options.json" CHROMIUM
export SAMPLE BIG="$DEV/bunny_low_100k.mesh.gz" SHOT="$DEV/torus_h0.1_noisy.mesh.gz" TANGLED="$DEV/bunny_tangled-low_10k.mesh.gz"
# screenshots: build/ui-shots unless UI_SHOTS names a directory (UI_SHOTS=docs
# remakes the ones in the README)
UI_SHOTS=${UI_SHOTS:-$ROOT/build/ui-shots}
case $UI_SHOTS in /*) ;; *) UI_SHOTS=$ROOT/$UI_SHOTS ;; esac
mkdir -p "$UI_SHOTS"
export UI_SHOTS
# XDMF with its heavy data in HDF5 (when qdc-h5 is built): the two files
# picked together
XDMF_H5=
if [ -x "$BIN/qdc-h5" ]; then
    mkdir -p "$TMP/xh5"
    gzip -dc "$ROOT/tests/data/real/meshio_h5.xdmf.gz" > "$TMP/xh5/meshio_h5.xdmf"
    gzip -dc "$ROOT/tests/data/real/meshio_h5.h5.gz" > "$TMP/xh5/meshio_h5.h5"
    mkdir -p "$TMP/xh5gz" # the pair gzipped, the .xdmf as .xmf
    gzip -c "$TMP/xh5/meshio_h5.xdmf" > "$TMP/xh5gz/meshio_h5.xmf.gz"
    cp "$ROOT/tests/data/real/meshio_h5.h5.gz" "$TMP/xh5gz/"
    XDMF_H5=$TMP/xh5/meshio_h5.xdmf
fi
export XDMF_H5
UI_MODE=open node "$ROOT/tests/ui/console.mjs" > "$TMP/open.out" 2>&1
rc=$?
cat "$TMP/open.out"
if [ $rc -ne 0 ] && ! grep -q '^FAIL - ' "$TMP/open.out"; then
    fail "console.mjs" "exit $rc"
fi
NFAIL=$((NFAIL + $(grep -c '^FAIL - ' "$TMP/open.out")))

# the downloads, read back by qdc quality: the report's tet count, nothing inverted
for f in sample-out.mesh sample-out.qmesh big-out.mesh; do
    if [ ! -s "$TMP/out/$f" ]; then
        fail "download $f" "not saved"
        continue
    fi
    case $f in
    sample*) id=$(jq -r .ids.sample "$TMP/out/figures-open.json") ;;
    *) id=$(jq -r .ids.big "$TMP/out/figures-open.json") ;;
    esac
    curl -s "$URL/v1/jobs/$id/report" > "$TMP/rep.json"
    nt=$(jq -r .after.n_tets "$TMP/rep.json")
    mr=$(jq -r '.after.mean_ratio_mean * 10000 | round / 10000' "$TMP/rep.json")
    if "$BIN/qdc" quality "$TMP/out/$f" > "$TMP/q.txt" 2>&1 &&
        grep -q " $nt tets, 0 inverted" "$TMP/q.txt" &&
        grep -Eq "mean ratio: mean $(printf %.4f "$mr")" "$TMP/q.txt"; then
        pass "qdc quality reads the downloaded $f: $nt tets, 0 inverted, mean ratio $(printf %.4f "$mr") as the report"
    else
        fail "qdc quality $f" "$(head -2 "$TMP/q.txt" | tr '\n' ' ') (report: $nt tets, $mr)"
    fi
done
# a page on another origin cannot submit (the daemon's own, above, could)
node "$ROOT/tests/ui/crossorigin.mjs" > "$TMP/cross.out" 2>&1
rc=$?
cat "$TMP/cross.out"
if [ $rc -ne 0 ] && ! grep -q '^FAIL - ' "$TMP/cross.out"; then
    fail "crossorigin.mjs" "exit $rc $(tail -2 "$TMP/cross.out")"
fi
NFAIL=$((NFAIL + $(grep -c '^FAIL - ' "$TMP/cross.out")))
[ -n "$UI_SHOTS" ] && for s in ui-list ui-job ui-phone; do
    if [ -s "$UI_SHOTS/$s.png" ] && [ "$(head -c 8 "$UI_SHOTS/$s.png" | od -An -tx1 | tr -d ' ')" = 89504e470d0a1a0a ]; then
        pass "screenshot $UI_SHOTS/$s.png ($(wc -c < "$UI_SHOTS/$s.png") bytes)"
    else
        fail "screenshot $s" "missing"
    fi
done
stop_qdcd || fail "SIGTERM" "exit status $?"

# --tokens: the page asks for a token, keeps it in sessionStorage
TOKEN=ui-test-$(od -An -N8 -tx1 /dev/urandom | tr -d ' \n')
TOKEN2=ui-other-$(od -An -N8 -tx1 /dev/urandom | tr -d ' \n')
"$QDCD" --hash-token "$TOKEN" > "$TMP/tokens"
"$QDCD" --hash-token "$TOKEN2" >> "$TMP/tokens"
start_qdcd "$TMP/t" --workers 1 --tokens "$TMP/tokens" || { fail "start --tokens" "$(tail -3 "$TMP/t.log")"; exit 1; }
code=$(req GET / "$TMP/tp")
[ "$code" = 200 ] && pass "--tokens: / loads without a token (the page asks for one)" || fail "--tokens: /" "status $code"
QDC_URL=$URL UI_MODE=tokens UI_TOKEN=$TOKEN node "$ROOT/tests/ui/console.mjs" > "$TMP/tok.out" 2>&1
rc=$?
cat "$TMP/tok.out"
if [ $rc -ne 0 ] && ! grep -q '^FAIL - ' "$TMP/tok.out"; then
    fail "console.mjs --tokens" "exit $rc"
fi
NFAIL=$((NFAIL + $(grep -c '^FAIL - ' "$TMP/tok.out")))
if "$BIN/qdc" quality "$TMP/out/tok.mesh" 2>&1 | grep -q " 750 tets, 0 inverted"; then
    pass "--tokens: the result downloaded with the token is the optimized sample (qdc quality)"
else
    fail "--tokens download" "$(ls -la "$TMP/out")"
fi
# /input and /v1/options follow the token rules of /result
code=$(submit "$SAMPLE" model/x-medit "max_iter=2" "$TMP/tsub" -H "Authorization: Bearer $TOKEN")
TJ=$(jf "$TMP/tsub" .id)
c1=$(req GET "/v1/jobs/$TJ/input" "$TMP/ti1")
c2=$(req GET "/v1/jobs/$TJ/input" "$TMP/ti2" -H "Authorization: Bearer $TOKEN2")
c3=$(req GET "/v1/jobs/$TJ/input?format=medit" "$TMP/ti3.mesh" -H "Authorization: Bearer $TOKEN")
c4=$(req GET /v1/options "$TMP/to1")
c5=$(req GET /v1/options "$TMP/to2" -H "Authorization: Bearer $TOKEN2")
if [ "$code $c1 $c2 $c3 $c4 $c5" = "202 401 404 200 401 200" ] && [ "$(hdr "$TMP/ti1" WWW-Authenticate)" != "" ] &&
    "$BIN/qdc" quality "$TMP/ti3.mesh" 2>&1 | sed 1s/^[^:]*:// | cmp -s - "$TMP/q.in"; then
    pass "--tokens: GET /input is 401 without a token, 404 for another token, the sample for the owner; /v1/options needs a token"
else
    fail "--tokens /input" "submit $code, input $c1 $c2 $c3, options $c4 $c5"
fi
stop_qdcd || fail "SIGTERM (tokens)" "exit status $?"

# UI_1M=1: the view of a finished ~1M-tet job (scripts/corpus.py ball-lowq,
# ~800k tets: ~1 min to make, ~20 s to optimize); not in the default run
if [ -n "${UI_1M:-}" ]; then
    if ! /usr/bin/python3 "$ROOT/scripts/corpus.py" "$TMP/c1m" --tets 1000000 --only ball-lowq > "$TMP/c1m.log" 2>&1; then
        echo "ok - 1M-tet job view # SKIP scripts/corpus.py failed: $(tail -1 "$TMP/c1m.log")"
    else
        start_qdcd "$TMP/b" --workers 1 || { fail "start (1M)" "$(tail -3 "$TMP/b.log")"; exit 1; }
        code=$(submit "$TMP/c1m/ball-lowq.mesh" model/x-medit "" "$TMP/bsub")
        BJ=$(jf "$TMP/bsub" .id)
        st=$(wait_done "$BJ")
        [ "$code $st" = "202 succeeded" ] || fail "1M-tet job" "$code $st"
        BIG_ID=$BJ BIG_RECORDS=$(($(jf "$TMP/job.$BJ" .iterations) + 1)) QDC_URL=$URL UI_MODE=big \
            node "$ROOT/tests/ui/console.mjs" > "$TMP/big.out" 2>&1
        rc=$?
        cat "$TMP/big.out"
        [ $rc -ne 0 ] && ! grep -q '^FAIL - ' "$TMP/big.out" && fail "console.mjs big" "exit $rc"
        NFAIL=$((NFAIL + $(grep -c '^FAIL - ' "$TMP/big.out")))
        stop_qdcd || fail "SIGTERM (1M)" "exit status $?"
        echo "# figures (1M): $(tr -d '\n ' < "$TMP/out/figures-big.json")"
    fi
fi
echo "# figures: $(tr -d '\n ' < "$TMP/out/figures-open.json")"
exit $((NFAIL > 0))
