#!/bin/sh
# badinput.sh - every malformed request gets the right 4xx as RFC 9457
# problem+json (type, title, status, detail and the member that says where),
# and the daemon keeps serving: afterwards a good mesh still runs to the end.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

MESH=$(devmesh cube_h0.1_lowq)
GOOD=$(devmesh cube_h0.1_good)
for k in truncated magic sizes index nan empty badjson jsonindex mediterr garbage; do
    $MT bad $k "$MESH" "$TMP/bad.$k"
done
$MT json "$MESH" "$TMP/big.json"   # ~1.3 MB, over the 1 MB JSON cap below
# Nastran with a malformed coordinate on line 4, I-DEAS with a linear (FE 111)
# and a parabolic (FE 118) tet in one file (line 10)
printf '$ Nastran\nBEGIN BULK\nGRID    1       0       0.      0.      0.\nGRID    2       0       1.x     0.      0.\n' > "$TMP/bad.bdf"
printf '    -1\n  2411\n%10d%10d%10d%10d\n%25s%25s%25s\n    -1\n    -1\n  2412\n%10d%10d%10d%10d%10d%10d\n%10d%10d%10d%10d\n%10d%10d%10d%10d%10d%10d\n' \
    1 1 1 11 0.0D+00 0.0D+00 0.0D+00 1 111 1 1 7 4 1 1 1 1 2 118 1 1 7 10 > "$TMP/bad.unv"

start_qdcd "$TMP/d" --workers 1 --max-json 1000000 --max-body 3000000 --max-tets 30000 ||
    { fail "start" "$(tail -3 "$TMP/d.log")"; exit 1; }

# expect NAME STATUS JQ-CONDITION (on the problem) -- after a req into $TMP/out
expect() {
    _name=$1; _want=$2; _cond=$3; _got=$4
    _ct=$(hdr "$TMP/out" Content-Type)
    if [ "$_got" = "$_want" ] && [ "$_ct" = application/problem+json ] &&
        jq -e --argjson s "$_want" '(.status == $s) and (.type | startswith("/problems/")) and
            (.title | length > 0) and (.detail | length > 0) and ('"$_cond"')' "$TMP/out" > /dev/null 2>&1; then
        pass "$_name: $_got $(jq -c 'del(.type, .title, .status)' "$TMP/out" | head -c 200)"
    else
        fail "$_name" "status $_got (want $_want), type '$_ct', body $(head -c 300 "$TMP/out")"
    fi
}
Q=application/vnd.qdc.mesh

expect "truncated binary" 400 '.offset >= 0' "$(submit "$TMP/bad.truncated" $Q "" "$TMP/out")"
expect "wrong magic" 400 '.offset == 0 and (.detail | test("magic"))' "$(submit "$TMP/bad.magic" $Q "" "$TMP/out")"
expect "sizes disagree with the body" 400 '.detail | test("size")' "$(submit "$TMP/bad.sizes" $Q "" "$TMP/out")"
expect "tet index out of range" 400 '.index == 5 and .kind == "tet"' "$(submit "$TMP/bad.index" $Q "" "$TMP/out")"
expect "NaN coordinate" 400 '.index == 3 and .kind == "vertex"' "$(submit "$TMP/bad.nan" $Q "" "$TMP/out")"
expect "empty mesh" 422 '.type | endswith("invalid-mesh")' "$(submit "$TMP/bad.empty" $Q "" "$TMP/out")"
expect "malformed JSON" 400 '.line >= 1 and .column >= 1' "$(submit "$TMP/bad.badjson" application/json "" "$TMP/out")"
expect "JSON tet index out of range" 400 '.index == 1' "$(submit "$TMP/bad.jsonindex" application/json "" "$TMP/out")"
expect "Medit syntax error" 400 '.line > 4' "$(submit "$TMP/bad.mediterr" model/x-medit "" "$TMP/out")"
expect "Nastran malformed number (sniffed)" 400 '.line == 4 and .column == 25 and (.detail | test("1.x"))' \
    "$(submit "$TMP/bad.bdf" application/octet-stream "" "$TMP/out")"
expect "I-DEAS linear and parabolic tets (?format=unv): unsupported" 415 '.line == 10 and (.detail | test("FE descriptor 111"))' \
    "$(submit "$TMP/bad.unv" application/octet-stream "format=unv" "$TMP/out")"
expect "JSON over the cap" 413 '.max_bytes == 1000000 and .use == "application/vnd.qdc.mesh" and (.detail | test("vnd.qdc.mesh"))' \
    "$(submit "$TMP/big.json" application/json "" "$TMP/out")"
# chunked: no Content-Length, so the cap is enforced while streaming
expect "JSON over the cap, chunked" 413 '.max_bytes == 1000000' \
    "$(req POST /v1/jobs "$TMP/out" -H 'Content-Type: application/json' -H 'Transfer-Encoding: chunked' --data-binary "@$TMP/big.json")"
head -c 3500000 /dev/zero > "$TMP/huge"
expect "body over --max-body" 413 '.max_bytes == 3000000' "$(submit "$TMP/huge" $Q "" "$TMP/out")"
expect "mesh over --max-tets" 413 '.tets == 33574 and .max_tets == 30000' "$(submit "$MESH" model/x-medit "" "$TMP/out")"
expect "unknown media type" 415 '.accepted | index("application/vnd.qdc.mesh") != null' "$(submit "$GOOD" image/png "" "$TMP/out")"
expect "unrecognisable body as octet-stream" 415 'true' "$(submit "$TMP/bad.garbage" application/octet-stream "" "$TMP/out")"
: > "$TMP/empty"
expect "empty body" 400 'true' "$(submit "$TMP/empty" $Q "" "$TMP/out")"
expect "unknown option" 400 '.detail | test("colour")' "$(submit "$GOOD" model/x-medit "colour=red" "$TMP/out")"
expect "bad option value" 400 '.detail | test("max_iter")' "$(submit "$GOOD" model/x-medit "max_iter=lots" "$TMP/out")"
expect "unknown job id" 404 'true' "$(req GET /v1/jobs/0123456789abcdef0123456789abcdef "$TMP/out")"
expect "malformed job id" 404 'true' "$(req GET /v1/jobs/nope/progress "$TMP/out")"
expect "unknown path" 404 'true' "$(req GET /v2/things "$TMP/out")"
expect "wrong method" 405 'true' "$(req PUT /v1/jobs "$TMP/out")"
[ "$(hdr "$TMP/out" Allow)" = "GET, POST" ] && pass "405 carries Allow: GET, POST" || fail "405 Allow" "$(hdr "$TMP/out" Allow)"

# A good job, then the job-level parameter errors against it.
code=$(submit "$GOOD" model/x-medit "max_iter=2" "$TMP/sub")
id=$(jf "$TMP/sub" .id)
[ "$code" = 202 ] && pass "after all that, a good mesh is accepted (202)" || fail "good submit" "$code $(head -c 200 "$TMP/sub")"
expect "bad wait (word)" 400 '.parameter == "wait"' "$(req GET "/v1/jobs/$id/progress?wait=soon" "$TMP/out")"
expect "bad wait (negative)" 400 '.parameter == "wait"' "$(req GET "/v1/jobs/$id/progress?wait=-1" "$TMP/out")"
expect "bad after" 400 '.parameter == "after"' "$(req GET "/v1/jobs/$id/progress?after=x" "$TMP/out")"
expect "bad Last-Event-ID" 400 '.parameter == "after"' "$(req GET "/v1/jobs/$id/events" "$TMP/out" -H 'Last-Event-ID: zz')"
expect "bad result format" 400 '.parameter == "format"' "$(req GET "/v1/jobs/$id/result?format=stl" "$TMP/out")"
expect "bad page_size" 400 '.parameter == "page_size"' "$(req GET "/v1/jobs?page_size=0" "$TMP/out")"

state=$(poll_all "$id")
if kill -0 "$QPID" 2> /dev/null && [ "$state" = succeeded ] && seqs_ok "$id" &&
    [ "$(req GET /livez "$TMP/out")" = 200 ]; then
    pass "daemon still serves: the good job succeeded with $(wc -l < "$TMP/seqs.$id") records, /livez 200"
else
    fail "daemon still serves" "state '$state', alive $(kill -0 "$QPID" 2> /dev/null && echo yes || echo no)"
fi
rej=$(curl -s "$URL/metrics" | awk '$1 == "qdcd_jobs_rejected_total" { print $2 }')
[ "${rej:-0}" -ge 14 ] && pass "metrics: $rej rejected submissions counted" || fail "rejected metric" "'$rej'"
stop_qdcd || fail "SIGTERM" "exit status $?"
exit $((NFAIL > 0))
