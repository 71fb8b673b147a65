#!/bin/sh
# remote.sh - `qdc submit|status|watch|fetch|cancel|jobs` against a real qdcd:
# results valid and in the -o file's format, reports present, a file sent as it
# is (TetGen's two files as the binary mesh), `submit IN -o OUT`
# byte for byte what `qdc optimize IN OUT` writes for 13 files of
# other tools (and with --topology flips, which changes the tets), progress
# lines (plain and on a terminal), Idempotency-Key,
# tokens, and the exit codes 1, 2, 10, 11, 12.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
QDC=$BIN/qdc

MESH=$(devmesh bunny_low_10k)
BIG=$(devmesh bunny_low_100k)
$MT json "$MESH" "$TMP/in.json"
NT=9033

start_qdcd "$TMP/d" --workers 2 || { fail "start" "qdcd did not come up: $(tail -3 "$TMP/d.log")"; exit 1; }
S="--server $URL"

# valid OUT: readable by qdc, no inverted tet, same connectivity as the input
valid() { # OUT
    "$QDC" quality "$1" > "$TMP/q.txt" 2>&1 && grep -q ": [0-9]* vertices, $NT tets, 0 inverted" "$TMP/q.txt" &&
        case $1 in *.node) ;; *) $MT same "$MESH" "$1" > /dev/null 2>&1 ;; esac
}

# 1. submit --wait -o OUT.mesh --report R.json, Medit input
id=$("$QDC" submit "$MESH" $S --max-iter 3 -o "$TMP/out.mesh" --report "$TMP/r.json" 2> "$TMP/sub.err")
rc=$?
nlines=$(grep -c 'q mean' "$TMP/sub.err")
if [ $rc = 0 ] && printf '%s' "$id" | grep -Eq '^[0-9a-f]{32}$' && valid "$TMP/out.mesh" &&
    [ "$(jq -r .after.n_tets "$TMP/r.json")" = $NT ] && jq -e '.boundary_error' "$TMP/r.json" > /dev/null &&
    [ "$nlines" -ge 3 ] && grep -q "job $id succeeded" "$TMP/sub.err"; then
    pass "submit --wait: id on stdout, $nlines progress lines, result valid Medit, report present"
else
    fail "submit --wait" "rc $rc id '$id' lines $nlines: $(tail -3 "$TMP/sub.err") $(tail -2 "$TMP/q.txt")"
fi
ID1=$id

# 2. JSON input goes up as binary; .qmesh output
id=$("$QDC" submit "$TMP/in.json" $S --max-iter 2 --boundary fixed -q -o "$TMP/out.qmesh" 2> "$TMP/sub2.err")
rc=$?
req GET "/v1/jobs/$id" "$TMP/job2" > /dev/null
if [ $rc = 0 ] && [ "$(jf "$TMP/job2" .mesh.format)" = qmesh ] &&
    [ "$(jf "$TMP/job2" .options.boundary)" = fixed ] && valid "$TMP/out.qmesh" && [ ! -s "$TMP/sub2.err" ]; then
    pass "submit JSON mesh: uploaded as qmesh, options passed (boundary fixed), .qmesh result valid, -q silent"
else
    fail "submit JSON" "rc $rc format $(jf "$TMP/job2" .mesh.format) $(cat "$TMP/sub2.err")"
fi

# 3. submit, then watch / status / fetch (server from QDC_SERVER)
export QDC_SERVER=$URL
id=$("$QDC" submit "$MESH" --max-iter 3)
rc=$?
"$QDC" watch "$id" > "$TMP/watch.out" 2>&1
rcw=$?
n=$(grep -c 'q mean .* min .* inverted [0-9]* .*s$' "$TMP/watch.out")
if [ $rc = 0 ] && [ $rcw = 0 ] && [ "$n" -ge 3 ] && ! grep -q "$(printf '\r')" "$TMP/watch.out" &&
    tail -1 "$TMP/watch.out" | grep -q "job $id succeeded"; then
    pass "watch (not a terminal): $n plain progress lines, ends 'succeeded', exit 0"
else
    fail "watch" "rc $rc/$rcw lines $n: $(tail -3 "$TMP/watch.out")"
fi
"$QDC" status "$id" > "$TMP/status.out"
rc=$?
if [ $rc = 0 ] && grep -q "^$id  succeeded .* $NT tets .* q mean" "$TMP/status.out"; then
    pass "status: one line with state, size and quality"
else
    fail "status" "rc $rc: $(cat "$TMP/status.out")"
fi
"$QDC" status "$id" --json > "$TMP/status.json"
[ "$(jf "$TMP/status.json" .state)" = succeeded ] && pass "status --json: the job object" ||
    fail "status --json" "$(head -c 200 "$TMP/status.json")"
"$QDC" fetch "$id" -o "$TMP/f.json" --report "$TMP/f.report.json"
rc=$?
req GET "/v1/jobs/$id/result?format=json" "$TMP/srv.json" > /dev/null
d=$($MT same "$TMP/f.json" "$TMP/srv.json")
if [ $rc = 0 ] && awk -v d="$d" 'BEGIN { exit !(d != "" && d + 0 == 0) }' &&
    [ "$(jq -r .after.n_tets "$TMP/f.report.json")" = $NT ]; then
    pass "fetch -o .json --report: identical to the server's JSON result (diff $d), report present"
else
    fail "fetch" "rc $rc diff '$d'"
fi
"$QDC" fetch "$id" -o "$TMP/f.node" && valid "$TMP/f.node" && pass "fetch -o .node: TetGen output valid" ||
    fail "fetch tetgen" "$(tail -2 "$TMP/q.txt")"
# a pipeline: the mesh on standard input, the result on standard output (the
# job id then goes to stderr)
gzip -c "$MESH" | "$QDC" submit - -o - --out-format medit --max-iter 2 -q > "$TMP/p.mesh" 2> "$TMP/p.err"
rc=$?
if [ $rc = 0 ] && valid "$TMP/p.mesh" && grep -q '^qdc: job [0-9a-f]\{32\}$' "$TMP/p.err" && [ ! -e ./- ]; then
    pass "submit - -o - --out-format medit: gzip on standard input, the result on standard output, '$(cat "$TMP/p.err")' on stderr"
else
    fail "submit pipeline" "rc $rc: $(head -c 200 "$TMP/p.err")"
fi
req DELETE "/v1/jobs/$(sed -n 's/^qdc: job //p' "$TMP/p.err")" "$TMP/del" > /dev/null # the job counts below
# to /dev/stdout (written straight into, the link left alone) and to a link
"$QDC" fetch "$id" -o /dev/stdout --out-format medit --report "$TMP/f2.report.json" > "$TMP/f.out.mesh"
rc=$?
"$QDC" fetch "$id" -o "$TMP/f2.json" --report /dev/stdout > "$TMP/f.out.report"
rc2=$?
ln -s f.linked.mesh "$TMP/link.mesh"
"$QDC" fetch "$id" -o "$TMP/link.mesh"
rc3=$?
if [ $rc = 0 ] && valid "$TMP/f.out.mesh" && [ $rc2 = 0 ] && cmp -s "$TMP/f.out.report" "$TMP/f2.report.json" &&
    [ -L /dev/stdout ] && [ $rc3 = 0 ] && [ -L "$TMP/link.mesh" ] && cmp -s "$TMP/f.linked.mesh" "$TMP/f.out.mesh"; then
    pass "fetch -o /dev/stdout and --report /dev/stdout: written into the redirection, /dev/stdout still a link; -o a link: the link kept"
else
    fail "fetch to /dev/stdout" "rc $rc $rc2 $rc3, $(ls -l /dev/stdout "$TMP/link.mesh" 2>&1 | tr '\n' ' ')"
fi

# 4. on a terminal: one line redrawn with \r
if script -qec "$QDC watch $id" /dev/null > "$TMP/tty.out" 2>&1 && grep -q "$(printf '\r')global" "$TMP/tty.out"; then
    pass "watch on a terminal: one progress line redrawn in place"
else
    fail "watch tty" "$(od -c "$TMP/tty.out" | head -3)"
fi

# 5. jobs lists every job
"$QDC" jobs > "$TMP/jobs.out"
rc=$?
if [ $rc = 0 ] && grep -q "^$ID1  succeeded" "$TMP/jobs.out" && grep -q "^$id " "$TMP/jobs.out" &&
    [ "$(wc -l < "$TMP/jobs.out")" = 3 ]; then
    pass "jobs: the 3 jobs, one line each"
else
    fail "jobs" "rc $rc: $(cat "$TMP/jobs.out")"
fi

# 6. Idempotency-Key: the same key twice is the same job
a=$("$QDC" submit "$MESH" --max-iter 1 --idempotency-key k-$$)
b=$("$QDC" submit "$MESH" --max-iter 1 --idempotency-key k-$$)
n=$("$QDC" jobs | wc -l)
[ -n "$a" ] && [ "$a" = "$b" ] && [ "$n" = 4 ] && pass "Idempotency-Key: a re-run returns job $a, no second job" ||
    fail "idempotency" "'$a' vs '$b', $n jobs"
"$QDC" submit "$MESH" --max-iter 2 --idempotency-key k-$$ > /dev/null 2> "$TMP/idem.err"
rc=$?
[ $rc = 10 ] && pass "Idempotency-Key reused with other options: exit 10" || fail "idempotency reuse" "rc $rc $(cat "$TMP/idem.err")"

# 7. cancel: watch and fetch then report the job's end (11); a job cancelled
# while the optimizer ran keeps its best mesh so far, which fetch writes
id=$("$QDC" submit "$BIG" --max-iter 1000 -q)
"$QDC" cancel "$id" > "$TMP/cancel.out"
rc=$?
"$QDC" watch "$id" > /dev/null 2> "$TMP/cw.err"
rcw=$?
"$QDC" fetch "$id" -o "$TMP/c.mesh" 2> "$TMP/cf.err"
rcf=$?
if curl -s "$QDC_SERVER/v1/jobs/$id" | jq -e '.links.result' > /dev/null; then
    kept() { grep -q "best mesh so far" "$TMP/cf.err" && "$QDC" quality "$TMP/c.mesh" > /dev/null 2>&1; }
else
    kept() { [ ! -e "$TMP/c.mesh" ]; }
fi
if [ $rc = 0 ] && grep -Eq "^$id  (queued|running|cancelled) " "$TMP/cancel.out" &&
    grep -q "job $id cancelled" "$TMP/cw.err" && [ $rcw = 11 ] && [ $rcf = 11 ] && kept; then
    pass "cancel: exit 0; then watch and fetch exit 11 ($(cat "$TMP/cw.err"))"
else
    fail "cancel" "rc $rc/$rcw/$rcf: $(cat "$TMP/cancel.out" "$TMP/cw.err" "$TMP/cf.err")"
fi

# 7b. Ctrl-C while waiting: exit 5, the job goes on on the server
"$QDC" submit "$BIG" --max-iter 1000 --wait -o "$TMP/int.mesh" > "$TMP/int.id" 2> "$TMP/int.err" &
QP=$!
i=0
# (the handler is installed before the id is printed: no pause needed)
while [ $i -lt 600 ] && [ ! -s "$TMP/int.id" ]; do sleep 0.1; i=$((i + 1)); done
kill -INT $QP
wait $QP
rc=$?
id=$(cat "$TMP/int.id")
st=$("$QDC" status "$id" 2> /dev/null | awk '{ print $2 }')
if [ $rc = 5 ] && grep -q "job $id goes on on the server" "$TMP/int.err" && { [ "$st" = running ] || [ "$st" = queued ]; }; then
    pass "SIGINT during submit --wait: exit 5 at once, says the job ($st) goes on"
else
    fail "SIGINT" "rc $rc state '$st': $(tail -2 "$TMP/int.err")"
fi
"$QDC" cancel "$id" > /dev/null 2>&1

# 7c. files of other tools: submit -o in their own format gives what the local
# run writes, byte for byte (names, tags, arrays, comments kept): sent as they
# are (by media type, or by name: Gmsh 2.2 binary and 4.0, DOLFIN, Abaqus,
# Netgen, Medit binary), and qdcd writes the upload back
bad=
nraw=0
for f in gmsh41.msh gmsh41_bin.msh gmsh22.msh gmsh22_bin.msh gmsh40.msh gmsh.mesh gmsh.vtk \
    meshio_ascii.vtu meshio_zlib.vtu dolfin.xml calculix.inp meshio.vol meshio.meshb; do
    gzip -dc "$ROOT/tests/data/real/$f.gz" > "$TMP/$f"
    "$QDC" optimize "$TMP/$f" "$TMP/local.$f" --max-iter 3 --quiet || bad="$bad $f:local"
    id=$("$QDC" submit "$TMP/$f" --max-iter 3 -q -o "$TMP/remote.$f") || bad="$bad $f:submit"
    cmp -s "$TMP/local.$f" "$TMP/remote.$f" || bad="$bad $f:differs"
    req GET "/v1/jobs/$id" "$TMP/job.json" > /dev/null
    [ "$(jf "$TMP/job.json" .mesh.format)" = qmesh ] || nraw=$((nraw + 1))
done
if [ -z "$bad" ] && [ $nraw = 13 ]; then
    pass "submit -o in the input's format: 13 files of other tools byte for byte as qdc optimize writes them, each sent as it is"
else
    fail "submit, files of other tools" "$bad; $nraw sent as they are (want 13)"
fi
# the same through standard input and output, no --out-format: the input's
# format (Gmsh 2.2 binary, named in the query, and 4.1 come back from the
# server, written over the upload); fetch -o - gives the job's
"$QDC" submit - --max-iter 3 -q -o - < "$TMP/gmsh22_bin.msh" > "$TMP/s22.msh" 2> /dev/null
rc=$?
"$QDC" submit - --max-iter 3 -q -o - < "$TMP/gmsh41.msh" > "$TMP/s41.msh" 2> "$TMP/s41.err"
rc2=$?
"$QDC" fetch "$(sed -n 's/^qdc: job //p' "$TMP/s41.err")" -o - > "$TMP/f41.msh"
rc3=$?
if [ $rc$rc2$rc3 = 000 ] && cmp -s "$TMP/s22.msh" "$TMP/local.gmsh22_bin.msh" &&
    cmp -s "$TMP/s41.msh" "$TMP/local.gmsh41.msh" && cmp -s "$TMP/f41.msh" "$TMP/local.gmsh41.msh"; then
    pass "submit - -o - and fetch -o - (no --out-format): the input's format, byte for byte the local run's (Gmsh 2.2 binary, 4.1)"
else
    fail "submit/fetch -o -" "rc $rc $rc2 $rc3"
fi
# a JSON or binary-mesh input has no file of its own to write back: -o - is
# Medit, as the local run writes it on standard output
bad=
for f in json qmesh; do
    "$QDC" convert "$ROOT/tests/data/sample/cube.mesh" "$TMP/c.$f" 2> /dev/null
    "$QDC" optimize "$TMP/c.$f" - --max-iter 2 --quiet > "$TMP/c.$f.local" || bad="$bad $f:local"
    "$QDC" submit "$TMP/c.$f" --max-iter 2 -q -o - > "$TMP/c.$f.remote" 2> /dev/null || bad="$bad $f:submit"
    cmp -s "$TMP/c.$f.local" "$TMP/c.$f.remote" && head -1 "$TMP/c.$f.remote" | grep -q MeshVersionFormatted ||
        bad="$bad $f:differs"
done
[ -z "$bad" ] && pass "submit IN.json|IN.qmesh -o -: Medit, byte for byte what qdc optimize IN - writes" ||
    fail "submit json/qmesh -o -" "$bad"

# 7d. --topology flips passes through: -o in the input's format (Gmsh 4.1,
# Medit; written by qdcd with qdc's own writer, the tets changed) is what the
# local run writes, byte for byte; TetGen's pair (sent as the binary mesh)
# gets the result's tets here, with a note
bad=
for f in gmsh41.msh gmsh.mesh; do
    "$QDC" optimize "$TMP/$f" "$TMP/tlocal.$f" --topology flips --max-iter 3 --quiet ||
        bad="$bad $f:local"
    "$QDC" submit "$TMP/$f" --topology flips --max-iter 3 -q -o "$TMP/tremote.$f" \
        --report "$TMP/t.$f.json" > /dev/null || bad="$bad $f:submit"
    cmp -s "$TMP/tlocal.$f" "$TMP/tremote.$f" || bad="$bad $f:differs"
    jq -e '.options.topology == "flips" and .run.topology.tets_in > 0' "$TMP/t.$f.json" \
        > /dev/null || bad="$bad $f:report"
done
"$QDC" convert "$MESH" "$TMP/tp.node" 2> /dev/null
"$QDC" submit "$TMP/tp.node" --topology flips --max-iter 3 -o "$TMP/tpo.node" \
    --report "$TMP/tp.json" > /dev/null 2> "$TMP/tp.err" || bad="$bad node:submit"
tout=$(jq -r .run.topology.tets_out "$TMP/tp.json")
"$QDC" quality "$TMP/tpo.node" 2>&1 | grep -q ": [0-9]* vertices, $tout tets, 0 inverted" &&
    [ "$tout" != $NT ] && grep -q "note: .*own writer" "$TMP/tp.err" || bad="$bad node:result"
[ -z "$bad" ] &&
    pass "submit --topology flips: Gmsh 4.1 and Medit -o byte for byte as qdc optimize --topology flips writes them; TetGen pair: $NT -> $tout tets, 0 inverted, with a note" ||
    fail "submit --topology flips" "$bad $(tail -2 "$TMP/tp.err")"

# a closed surface goes up as it is (qdcd tetrahedralizes it; TetGen's options
# pass through); an open one is refused here (exit 2), before any job
printf 'OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n' > "$TMP/open.off"
"$QDC" submit - --max-volume 0.01 -q -o - < "$ROOT/tests/data/sample/cube.off" > "$TMP/cube.out.mesh" 2> "$TMP/cube.err"
rc=$?
sid=$(sed -n 's/^qdc: job //p' "$TMP/cube.err")
req GET "/v1/jobs/$sid" "$TMP/cube.job" > /dev/null
n0=$("$QDC" jobs | wc -l)
"$QDC" submit "$TMP/open.off" -q 2> "$TMP/open.err"
rc2=$?
n1=$("$QDC" jobs | wc -l)
if [ $rc = 0 ] && "$QDC" quality "$TMP/cube.out.mesh" | grep -q ' 0 inverted' && [ "$(jf "$TMP/cube.job" .mesh.format)" = off ] &&
    [ $rc2 = 2 ] && grep -q 'not closed' "$TMP/open.err" && [ "$n0" = "$n1" ]; then
    pass "submit a closed surface (OFF on standard input, --max-volume passed): tetrahedralized by qdcd, result valid Medit on standard output; an open one: exit 2, no job"
else
    fail "submit surface" "rc $rc $rc2, format $(jf "$TMP/cube.job" .mesh.format), jobs $n0 $n1: $(cat "$TMP/open.err")"
fi
req DELETE "/v1/jobs/$sid" "$TMP/del" > /dev/null

# 8. exit codes
"$QDC" submit "$MESH" --metric nope -q 2> "$TMP/e.err"
rc=$?
[ $rc = 10 ] && grep -q "metric" "$TMP/e.err" && pass "bad option value: server 400, exit 10, says why" ||
    fail "exit 10 option" "rc $rc $(cat "$TMP/e.err")"
"$QDC" status 0123456789abcdef0123456789abcdef 2> "$TMP/e.err"
rc=$?
[ $rc = 10 ] && grep -q 404 "$TMP/e.err" && pass "unknown job: exit 10" || fail "exit 10 404" "rc $rc $(cat "$TMP/e.err")"
"$QDC" submit "$MESH" -o - --report - > "$TMP/both.out" 2> "$TMP/e.err"
rc=$?
[ $rc = 1 ] && grep -q "cannot both be standard output" "$TMP/e.err" && [ ! -s "$TMP/both.out" ] &&
    pass "-o - with --report -: exit 1 before any upload" || fail "-o - --report -" "rc $rc $(cat "$TMP/e.err")"
printf 'MeshVersionFormatted 1\nDimension 3\nVertices\n2\n0 0 0 0\n' > "$TMP/bad.mesh"
"$QDC" submit "$TMP/bad.mesh" 2> "$TMP/e.err"
rc=$?
[ $rc = 2 ] && grep -q "bad.mesh:" "$TMP/e.err" && pass "malformed local file: exit 2 before any upload ($(cat "$TMP/e.err"))" ||
    fail "exit 2" "rc $rc $(cat "$TMP/e.err")"
"$QDC" submit "$MESH" -o "$TMP/x.xyz" 2> /dev/null
rc1=$?
"$QDC" fetch 2> /dev/null
rc2=$?
[ $rc1 = 1 ] && [ $rc2 = 1 ] && pass "bad command line (unknown output format, missing job): exit 1" ||
    fail "exit 1" "rc $rc1 $rc2"
# a port nobody listens on: the daemon's, once it is stopped
DEAD=$URL
if "$QDC" jobs --server "$DEAD/" --retries 0 > /dev/null 2>&1; then
    pass "--server URL/ (trailing slash) works"
else
    fail "trailing slash" "jobs --server URL/ failed"
fi

stop_qdcd
t0=$(date +%s)
"$QDC" submit "$MESH" --server "$DEAD" --retries 2 2> "$TMP/e.err"
rc=$?
nret=$(grep -c 'retrying' "$TMP/e.err")
[ $rc = 12 ] && [ "$nret" = 2 ] && pass "server down: 2 retries with backoff, then exit 12 in $(( $(date +%s) - t0 )) s" ||
    fail "exit 12" "rc $rc retries $nret $(tail -1 "$TMP/e.err")"

# 9. bearer tokens: QDC_TOKEN or --token; another token sees nothing
TOKEN=secret-$$
"$QDCD" --hash-token "$TOKEN" > "$TMP/tokens"
start_qdcd "$TMP/t" --workers 1 --tokens "$TMP/tokens" || { fail "start tokens" "$(tail -3 "$TMP/t.log")"; exit 1; }
id=$(QDC_TOKEN=$TOKEN "$QDC" submit "$MESH" --server "$URL" --max-iter 1 -q)
rc1=$?
QDC_TOKEN=$TOKEN "$QDC" fetch "$id" --server "$URL" --wait -q --report "$TMP/t.json"
rc2=$?
"$QDC" status "$id" --server "$URL" --token wrong 2> "$TMP/e.err"
rc3=$?
[ $rc1 = 0 ] && [ $rc2 = 0 ] && [ -s "$TMP/t.json" ] && [ $rc3 = 10 ] && grep -q 401 "$TMP/e.err" &&
    pass "tokens: QDC_TOKEN submits and fetches; a wrong --token gets 401, exit 10" ||
    fail "tokens" "rc $rc1 $rc2 $rc3 $(cat "$TMP/e.err")"
stop_qdcd
exit 0
