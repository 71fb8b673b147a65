#!/bin/sh
# ui.sh - the web console (web/, compiled into qdcd): what qdcd serves at / and
# /ui/ (media types, Content-Security-Policy, ETag and 304, 404s, no token
# needed for the page), then the page itself in Debian's chromium driven by
# playwright-core (tests/ui/console.mjs, installed by `npm ci` from
# tests/ui/package-lock.json into build/uitest): first paint, the sample
# submitted through the file input, the chart growing while a job runs, the
# histograms, downloads checked with `qdc quality`, cancel/delete/filter, a
# phone-sized layout, no console errors, and the token prompt with --tokens.
# Screenshots of the list and of a job go to docs/ui-list.png, docs/ui-job.png.
# Without chromium or npm the browser part prints # SKIP lines.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

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

# ---------------------------------------------------------------- browser --
CHROMIUM=${CHROMIUM:-/usr/bin/chromium}
if [ ! -x "$CHROMIUM" ]; then
    echo "ok - browser tests # SKIP no $CHROMIUM (scripts/deps.sh installs chromium)"
    stop_qdcd
    exit $((NFAIL > 0))
fi
if ! command -v npm > /dev/null 2>&1 || ! command -v node > /dev/null 2>&1; then
    echo "ok - browser tests # SKIP no node/npm (scripts/deps.sh installs them)"
    stop_qdcd
    exit $((NFAIL > 0))
fi
MODS=$ROOT/build/uitest
if ! cmp -s "$ROOT/tests/ui/package-lock.json" "$MODS/package-lock.json" ||
    [ ! -d "$MODS/node_modules/playwright-core" ]; then
    mkdir -p "$MODS"
    cp "$ROOT/tests/ui/package.json" "$ROOT/tests/ui/package-lock.json" "$MODS/"
    if ! (cd "$MODS" && npm ci --no-audit --no-fund --ignore-scripts > "$TMP/npm.log" 2>&1); then
        rm -f "$MODS/package-lock.json"
        if grep -Eqi 'ENOTFOUND|EAI_AGAIN|ECONNREFUSED|ETIMEDOUT|network' "$TMP/npm.log"; then
            echo "ok - browser tests # SKIP npm ci: no registry ($(grep -m1 -i err "$TMP/npm.log"))"
            stop_qdcd
            exit $((NFAIL > 0))
        fi
        fail "npm ci" "$(tail -3 "$TMP/npm.log")"
        exit 1
    fi
fi
pass "playwright-core $(node -p "require('$MODS/node_modules/playwright-core/package.json').version") installed by npm ci from tests/ui/package-lock.json"

"$BIN/qdc" options > "$TMP/options.json"
mkdir -p "$TMP/out"
export UI_MODULES="$MODS" QDC_URL="$URL" UI_OUT="$TMP/out" OPTIONS_JSON="$TMP/options.json" CHROMIUM
export SAMPLE="$ROOT/tests/data/sample/cube.mesh" BIG="$DEV/bunny_low_100k.mesh.gz"
# screenshots: build/ui-shots unless UI_SHOTS names a directory (UI_SHOTS=docs
# remakes the ones in the README)
UI_SHOTS=${UI_SHOTS:-$ROOT/build/ui-shots}
case $UI_SHOTS in /*) ;; *) UI_SHOTS=$ROOT/$UI_SHOTS ;; esac
mkdir -p "$UI_SHOTS"
export UI_SHOTS
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
[ -n "$UI_SHOTS" ] && for s in ui-list ui-job; do
    if [ -s "$UI_SHOTS/$s.png" ] && [ "$(head -c 8 "$UI_SHOTS/$s.png" | od -An -tx1 | tr -d ' ')" = 89504e470d0a1a0a ]; then
        pass "screenshot $UI_SHOTS/$s.png ($(wc -c < "$UI_SHOTS/$s.png") bytes)"
    else
        fail "screenshot $s" "missing"
    fi
done
stop_qdcd || fail "SIGTERM" "exit status $?"

# --tokens: the page asks for a token, keeps it in sessionStorage
TOKEN=ui-test-$(od -An -N8 -tx1 /dev/urandom | tr -d ' \n')
"$QDCD" --hash-token "$TOKEN" > "$TMP/tokens"
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
stop_qdcd || fail "SIGTERM (tokens)" "exit status $?"
echo "# figures: $(tr -d '\n ' < "$TMP/out/figures-open.json")"
exit $((NFAIL > 0))
