#!/bin/sh
# e2e.sh - qdcd end to end: submit a dev mesh as binary, JSON and Medit, follow
# each job by long-poll (records in order, none skipped), fetch results in the
# three formats and the report, check quality with the library's report and
# with quality.py, ETag/304, content negotiation, SSE, listing and metrics.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

MESH=$(devmesh cube_h0.1_lowq)
$MT qmesh "$MESH" "$TMP/in.qmesh"
$MT json "$MESH" "$TMP/in.json"
Q="max_iter=4"

start_qdcd "$TMP/d" --workers 2 || { fail "start" "qdcd did not come up: $(tail -3 "$TMP/d.log")"; exit 1; }
pass "start: /livez answers on port $PORT"

for f in qmesh:application/vnd.qdc.mesh json:application/json medit:model/x-medit; do
    kind=${f%%:*}
    ct=${f#*:}
    src=$TMP/in.$kind
    [ "$kind" = medit ] && src=$MESH
    code=$(submit "$src" "$ct" "$Q" "$TMP/sub.$kind")
    id=$(jf "$TMP/sub.$kind" .id)
    loc=$(hdr "$TMP/sub.$kind" Location)
    if [ "$code" = 202 ] && [ "$loc" = "/v1/jobs/$id" ] && [ "$(jf "$TMP/sub.$kind" .mesh.format)" = "$kind" ] &&
        [ "$(jf "$TMP/sub.$kind" .mesh.tets)" = 33574 ] && [ "$(jf "$TMP/sub.$kind" .done)" = false ]; then
        pass "submit $kind: 202, Location $loc, 33574 tets"
    else
        fail "submit $kind" "status $code, location '$loc', body $(head -c 300 "$TMP/sub.$kind")"
    fi
    eval "ID_$kind=$id"
done

for kind in qmesh json medit; do
    eval "id=\$ID_$kind"
    state=$(poll_all "$id")
    n=$(wc -l < "$TMP/seqs.$id")
    if [ "$state" = succeeded ] && seqs_ok "$id" && [ "$n" -ge 3 ]; then
        pass "long-poll $kind: $n records, seq 0..$((n - 1)) in order, none skipped"
    else
        fail "long-poll $kind" "state $state, seqs $(tr '\n' ' ' < "$TMP/seqs.$id")"
    fi
    # the iteration numbers of the optimizer never go backwards either
    req GET "/v1/jobs/$id/progress?after=-1" "$TMP/all.$id" > /dev/null
    if jq -e '[.records[].iteration] as $i | ($i | length) > 0 and $i == ($i | sort) and .count == ($i | length)' \
        "$TMP/all.$id" > /dev/null; then
        pass "progress $kind: iteration numbers non-decreasing, after=-1 replays all $n"
    else
        fail "progress $kind" "$(jq -c '[.records[].iteration]' "$TMP/all.$id")"
    fi
    code=$(req GET "/v1/jobs/$id" "$TMP/job.$id")
    if [ "$code" = 200 ] && [ "$(jf "$TMP/job.$id" .state)" = succeeded ] &&
        [ "$(jf "$TMP/job.$id" .iterations)" = $((n - 1)) ] && [ "$(jf "$TMP/job.$id" .progress.seq)" = $((n - 1)) ] &&
        [ "$(jf "$TMP/job.$id" .progress.iteration)" = $((n - 1)) ] && [ "$(jf "$TMP/job.$id" .done)" = true ]; then
        pass "job $kind: succeeded, done, $n records: iterations $((n - 1)), the latest record's seq and iteration"
    else
        fail "job $kind" "$code $(head -c 400 "$TMP/job.$id")"
    fi
done

# Results: binary (default), JSON and Medit hold the same mesh; it moved.
id=$ID_qmesh
c1=$(req GET "/v1/jobs/$id/result" "$TMP/r.qmesh")
c2=$(req GET "/v1/jobs/$id/result?format=json" "$TMP/r.json")
c3=$(req GET "/v1/jobs/$id/result" "$TMP/r.mesh" -H "Accept: model/x-medit")
t1=$(hdr "$TMP/r.qmesh" Content-Type)
t3=$(hdr "$TMP/r.mesh" Content-Type)
if [ "$c1$c2$c3" = 200200200 ] && [ "$t1" = application/vnd.qdc.mesh ] && [ "$t3" = model/x-medit ]; then
    pass "result: binary, JSON and Medit served with their media types"
else
    fail "result" "codes $c1 $c2 $c3 types '$t1' '$t3'"
fi
d12=$($MT same "$TMP/r.qmesh" "$TMP/r.json")
d13=$($MT same "$TMP/r.qmesh" "$TMP/r.mesh")
din=$($MT same "$TMP/r.qmesh" "$MESH")
if awk -v a="$d12" -v b="$d13" -v c="$din" 'BEGIN { exit !(a < 1e-9 && b < 1e-9 && c > 1e-4) }'; then
    pass "result: formats agree (max diff $d12, $d13), same connectivity as the input, vertices moved by up to $din"
else
    fail "result formats" "diffs '$d12' '$d13', moved '$din'"
fi

# ETag is strong, per representation, and If-None-Match gives 304.
e1=$(hdr "$TMP/r.qmesh" ETag)
e2=$(hdr "$TMP/r.json" ETag)
sha=$(sha256sum "$TMP/r.qmesh" | cut -c1-64)
c304=$(req GET "/v1/jobs/$id/result" "$TMP/r304" -H "If-None-Match: $e1")
c200=$(req GET "/v1/jobs/$id/result" "$TMP/r200" -H "If-None-Match: \"0000\"")
if [ "$e1" = "\"$sha\"" ] && [ "$e1" != "$e2" ] && [ "$c304" = 304 ] && [ ! -s "$TMP/r304" ] && [ "$c200" = 200 ]; then
    pass "ETag: SHA-256 of the body, differs per format, If-None-Match -> 304 (other tag -> 200)"
else
    fail "ETag" "etag $e1 sha $sha json $e2, 304? $c304, 200? $c200"
fi
c406=$(req GET "/v1/jobs/$id/result" "$TMP/r406" -H "Accept: image/png")
cj=$(req GET "/v1/jobs/$id/result" "$TMP/rj" -H "Accept: image/png, application/json;q=0.5")
if [ "$c406" = 406 ] && [ "$(hdr "$TMP/r406" Content-Type)" = application/problem+json ] && [ "$cj" = 200 ] &&
    [ "$(hdr "$TMP/rj" Content-Type)" = application/json ]; then
    pass "content negotiation: unsupported Accept -> 406 problem, acceptable alternative served"
else
    fail "content negotiation" "$c406 $cj"
fi

# Report vs the library's own numbers and the independent evaluator.
code=$(req GET "/v1/jobs/$id/report" "$TMP/report.json")
$PY "$QUALITY" "$TMP/r.mesh" --orig "$MESH" > "$TMP/q.json" 2> "$TMP/q.err"
if [ "$code" = 200 ] && jq -e -s '
      .[0] as $r | .[1] as $q |
      ($r.after.mean_ratio_min - $q.eta_min | fabs) < 1e-6 and
      ($r.after.mean_ratio_mean - $q.eta_mean | fabs) < 1e-6 and
      ($r.after.dihedral_min - $q.dihedral_min | fabs) < 1e-4 and
      $r.after.n_inverted == $q.n_inverted and $q.n_inverted == 0 and
      $q.same_connectivity == true and
      $r.after.mean_ratio_min > $r.before.mean_ratio_min and
      $r.after.mean_ratio_mean > $r.before.mean_ratio_mean' \
        "$TMP/report.json" "$TMP/q.json" > /dev/null; then
    pass "report: after = quality.py (eta min $(jf "$TMP/q.json" .eta_min), mean $(jf "$TMP/q.json" .eta_mean)), better than before ($(jf "$TMP/report.json" .before.mean_ratio_min))"
else
    fail "report vs quality.py" "code $code report.after $(jq -c '.after | del(.dihedral_histogram)' "$TMP/report.json" 2>&1 | head -c 300) quality $(head -c 300 "$TMP/q.json")"
fi
if jq -e -s '.[0].boundary_error as $b | .[1] as $q | $b != null and $b.hausdorff >= 0 and
      ($b.hausdorff - $q.boundary_hausdorff | fabs) <= 0.25 * $q.boundary_hausdorff + 1e-9' \
        "$TMP/report.json" "$TMP/q.json" > /dev/null; then
    pass "report: boundary Hausdorff $(jf "$TMP/report.json" .boundary_error.hausdorff) within 25% of quality.py's $(jf "$TMP/q.json" .boundary_hausdorff)"
else
    fail "report boundary error" "report $(jq -c .boundary_error "$TMP/report.json") quality.py $(jf "$TMP/q.json" .boundary_hausdorff)"
fi

# SSE: every record as an event with id = seq, then an end event; Last-Event-ID resumes.
id=$ID_json
n=$(wc -l < "$TMP/seqs.$id")
curl -s -N -m 20 "$URL/v1/jobs/$id/events" > "$TMP/sse"
curl -s -N -m 20 -H "Last-Event-ID: 1" "$URL/v1/jobs/$id/events" > "$TMP/sse2"
ids=$(grep '^id: ' "$TMP/sse" | cut -c5- | tr '\n' ' ')
want=$(seq 0 $((n - 1)) | tr '\n' ' ')
ids2=$(grep '^id: ' "$TMP/sse2" | cut -c5- | tr '\n' ' ')
want2=$(seq 2 $((n - 1)) | tr '\n' ' ')
if [ "$ids" = "$want" ] && grep -q '^event: end' "$TMP/sse" && [ "$ids2" = "$want2" ] &&
    [ "$(grep -c '^data: {' "$TMP/sse")" = $((n + 1)) ]; then
    pass "SSE: $n progress events with id = seq and an end event; Last-Event-ID: 1 resumes at 2"
else
    fail "SSE" "ids '$ids' want '$want'; after 1: '$ids2'"
fi

# SSE live: follow a running job until its end event.
code=$(submit "$TMP/in.qmesh" application/vnd.qdc.mesh "max_iter=3" "$TMP/sub.live")
lid=$(jf "$TMP/sub.live" .id)
curl -s -N -m 60 "$URL/v1/jobs/$lid/events" > "$TMP/sse3"
nl=$(grep -c '^id: ' "$TMP/sse3")
st=$(grep -A1 '^event: end' "$TMP/sse3" | sed -n 's/^data: //p' | jq -r .state)
if [ "$code" = 202 ] && [ "$st" = succeeded ] && [ "$nl" -ge 2 ] &&
    [ "$(grep '^id: ' "$TMP/sse3" | cut -c5- | tr '\n' ' ')" = "$(seq 0 $((nl - 1)) | tr '\n' ' ')" ]; then
    pass "SSE live: $nl events in order while the job ran, then end (succeeded)"
else
    fail "SSE live" "code $code end state '$st' events $nl"
fi

# Listing, paged.
c1=$(req GET "/v1/jobs?page_size=3" "$TMP/l1")
tok=$(jf "$TMP/l1" .next_page_token)
c2=$(req GET "/v1/jobs?page_size=3&page_token=$tok" "$TMP/l2")
if [ "$c1$c2" = 200200 ] && [ "$(jq '.jobs | length' "$TMP/l1")" = 3 ] && [ "$(jq '.jobs | length' "$TMP/l2")" = 1 ] &&
    [ "$(jq -r '.jobs[0].id' "$TMP/l1")" = "$ID_qmesh" ] && [ "$(jq -r '.jobs[0].id' "$TMP/l2")" = "$lid" ]; then
    pass "list: 4 jobs in 2 pages of 3, submission order"
else
    fail "list" "$c1 $c2 $(head -c 200 "$TMP/l1")"
fi

# Metrics and readiness.
req GET /metrics "$TMP/metrics" > /dev/null
succ=$(awk '$1 == "qdcd_jobs{state=\"succeeded\"}" { print $2 }' "$TMP/metrics")
iters=$(awk '$1 == "qdcd_records_total" { print $2 }' "$TMP/metrics")
cnt=$(awk '$1 == "qdcd_http_request_duration_seconds_count" { print $2 }' "$TMP/metrics")
total=$(cat "$TMP"/seqs.* | wc -l)
if [ "$succ" = 4 ] && [ "$iters" -ge "$total" ] && [ "$cnt" -gt 10 ] &&
    grep -q '^qdcd_upload_bytes_total [1-9]' "$TMP/metrics" && grep -q '^qdcd_queue_depth 0$' "$TMP/metrics"; then
    pass "metrics: 4 succeeded, $iters progress records (>= $total polled), $cnt timed requests, queue depth 0"
else
    fail "metrics" "succeeded '$succ' records '$iters' count '$cnt'"
fi
code=$(req GET /readyz "$TMP/ready")
[ "$code" = 200 ] && pass "readyz: 200" || fail "readyz" "$code"

if stop_qdcd; then pass "SIGTERM: clean exit 0"; else fail "SIGTERM" "exit status $?: $(tail -3 "$TMP/d.log")"; fi
exit $((NFAIL > 0))
