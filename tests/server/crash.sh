#!/bin/sh
# crash.sh - durability: kill -9 while a job runs, restart on the same data
# directory: the job is re-queued (attempt 2), completes, and its result is the
# one an uninterrupted run gives (same quality: opt_run is not bit-reproducible
# from run to run, see the report). A job that keeps dying with the daemon fails
# after --max-attempts with a clear error.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

MESH=$(devmesh cube_h0.1_lowq)
$MT qmesh "$MESH" "$TMP/in.qmesh"
D=$TMP/d
Q="max_iter=5"

# wait_records ID N: long-poll until the job has published more than N records
wait_records() {
    curl -s -m 60 "$URL/v1/jobs/$1/progress?after=$2&wait=50" > "$TMP/wr"
    [ "$(jq -r .count "$TMP/wr")" -ge 1 ] && [ "$(jq -r .state "$TMP/wr")" = running ]
}

start_qdcd "$D" --workers 1 || { fail "start" "$(tail -3 "$D.log")"; exit 1; }
code=$(submit "$TMP/in.qmesh" application/vnd.qdc.mesh "$Q" "$TMP/sub")
id=$(jf "$TMP/sub" .id)
if [ "$code" = 202 ] && wait_records "$id" 1; then
    kill -9 "$QPID"
    wait "$QPID" 2> /dev/null
    QPID=
    pass "kill -9 while job $id was running (after record $(jq -r .next_after "$TMP/wr"))"
else
    fail "job running before the kill" "code $code, $(head -c 200 "$TMP/wr")"
fi

start_qdcd "$D" --workers 1 || { fail "restart" "$(tail -3 "$D.log")"; exit 1; }
grep -q "1 job(s) re-queued" "$D.log" && pass "restart: the running job was re-queued" ||
    fail "restart recovery" "$(tail -2 "$D.log")"
# a reader that had records of the first run resumes with after= and the
# attempt they came from: it is told the job runs again and gets this run's
# records from the start, each saying its attempt
curl -s -m 60 "$URL/v1/jobs/$id/progress?after=1&attempt=1&wait=50" > "$TMP/resume"
if jq -e '.restarted == {"from_attempt": 1, "attempt": 2} and .attempt == 2 and .after == -1 and
    .records[0].seq == 0 and ([.records[].attempt] | all(. == 2))' "$TMP/resume" > /dev/null; then
    pass "resume with after=1&attempt=1 after the restart: restarted from attempt 1, records of attempt 2 from seq 0"
else
    fail "resume across the restart" "$(head -c 300 "$TMP/resume")"
fi
curl -s -m 60 "$URL/v1/jobs/$id/progress?after=-1&attempt=2&wait=50" > "$TMP/same"
jq -e 'has("restarted") | not' "$TMP/same" > /dev/null && [ "$(jf "$TMP/same" .attempt)" = 2 ] &&
    pass "resume with the current attempt: no restart" || fail "same attempt" "$(head -c 300 "$TMP/same")"
curl -s -N -m 5 -H "Last-Event-ID: 1" "$URL/v1/jobs/$id/events?attempt=1" > "$TMP/sse" 2> /dev/null
if [ "$(sed -n 1p "$TMP/sse")" = "event: restart" ] &&
    [ "$(sed -n 2p "$TMP/sse")" = 'data: {"from_attempt":1,"attempt":2}' ] &&
    grep -q '^id: 0$' "$TMP/sse"; then
    pass "event stream with Last-Event-ID: 1 and attempt=1: a restart event, then this run's records from id 0"
else
    fail "SSE across the restart" "$(head -c 300 "$TMP/sse")"
fi
state=$(poll_all "$id")
req GET "/v1/jobs/$id" "$TMP/job" > /dev/null
if [ "$state" = succeeded ] && [ "$(jf "$TMP/job" .attempts)" = 2 ] && seqs_ok "$id"; then
    pass "after restart: succeeded on attempt 2, $(wc -l < "$TMP/seqs.$id") records in order"
else
    fail "after restart" "state $state attempts $(jf "$TMP/job" .attempts)"
fi
[ -z "$(ls "$D/tmp")" ] && pass "no upload left over in DATA/tmp" || fail "tmp cleanup" "$(ls "$D/tmp")"

# The same job uninterrupted gives a mesh of the same quality.
code=$(submit "$TMP/in.qmesh" application/vnd.qdc.mesh "$Q" "$TMP/sub2")
id2=$(jf "$TMP/sub2" .id)
state2=$(poll_all "$id2")
req GET "/v1/jobs/$id/result?format=medit" "$TMP/r1.mesh" > /dev/null
req GET "/v1/jobs/$id/report" "$TMP/report.json" > /dev/null
req GET "/v1/jobs/$id2/report" "$TMP/report2.json" > /dev/null
moved=$($MT same "$TMP/r1.mesh" "$MESH")
if [ "$state2" = succeeded ] && awk -v m="$moved" 'BEGIN { exit !(m > 1e-4) }' &&
    jq -e -s '.[0].after as $a | .[1].after as $b |
        ($a.mean_ratio_min - $b.mean_ratio_min | fabs) <= 0.05 * $b.mean_ratio_min and
        ($a.mean_ratio_mean - $b.mean_ratio_mean | fabs) <= 0.01 * $b.mean_ratio_mean' \
        "$TMP/report.json" "$TMP/report2.json" > /dev/null; then
    pass "result after the crash matches an uninterrupted run: eta min $(jf "$TMP/report.json" .after.mean_ratio_min) vs $(jf "$TMP/report2.json" .after.mean_ratio_min), mean $(jf "$TMP/report.json" .after.mean_ratio_mean) vs $(jf "$TMP/report2.json" .after.mean_ratio_mean)"
else
    fail "result after the crash" "state $state2 moved '$moved' after $(jq -c '.after | [.mean_ratio_min, .mean_ratio_mean]' "$TMP/report.json") vs $(jq -c '.after | [.mean_ratio_min, .mean_ratio_mean]' "$TMP/report2.json")"
fi
$PY "$QUALITY" "$TMP/r1.mesh" --orig "$MESH" > "$TMP/q.json"
if jq -e -s '.[0].after as $a | .[1] as $q | ($a.mean_ratio_min - $q.eta_min | fabs) < 1e-6 and
        $q.n_inverted == 0 and $q.same_connectivity and $a.mean_ratio_min > .[0].before.mean_ratio_min' \
        "$TMP/report.json" "$TMP/q.json" > /dev/null; then
    pass "recovered result: quality.py eta_min $(jf "$TMP/q.json" .eta_min) = report, same connectivity, no inverted tets, better than input"
else
    fail "recovered result quality" "$(jq -c '.after.mean_ratio_min' "$TMP/report.json") vs $(jf "$TMP/q.json" .eta_min)"
fi

# A job that takes the daemon down on every attempt ends up failed.
code=$(submit "$TMP/in.qmesh" application/vnd.qdc.mesh "$Q" "$TMP/sub3")
id3=$(jf "$TMP/sub3" .id)
wait_records "$id3" 0 || fail "third job running" "$(head -c 200 "$TMP/wr")"
kill -9 "$QPID"
wait "$QPID" 2> /dev/null
QPID=
start_qdcd "$D" --workers 1 --max-attempts 1 || { fail "restart 2" "$(tail -3 "$D.log")"; exit 1; }
code=$(req GET "/v1/jobs/$id3" "$TMP/job3")
rcode=$(req GET "/v1/jobs/$id3/result" "$TMP/res3")
if [ "$(jf "$TMP/job3" .state)" = failed ] && jf "$TMP/job3" .error.type | grep -q attempts-exhausted &&
    [ "$rcode" = 409 ] && [ "$(jf "$TMP/res3" .state)" = failed ]; then
    pass "attempts exhausted: failed with '$(jf "$TMP/job3" .error.detail)'; result -> 409"
else
    fail "attempts exhausted" "$(head -c 300 "$TMP/job3") result $rcode"
fi
# the earlier jobs survived both crashes, progress records included
n1=$(wc -l < "$TMP/seqs.$id")
req GET "/v1/jobs/$id/progress?after=0" "$TMP/pr" > /dev/null
if [ "$(jf "$TMP/pr" .count)" = $((n1 - 1)) ] && [ "$(jq -r '.records[0].seq' "$TMP/pr")" = 1 ] &&
    [ "$(jf "$TMP/pr" .done)" = true ]; then
    pass "after a restart, progress?after=0 of a finished job still returns its $((n1 - 1)) later records"
else
    fail "progress after restart" "$(head -c 300 "$TMP/pr")"
fi
req GET "/v1/jobs/$id" "$TMP/job" > /dev/null
[ "$(jf "$TMP/job" .state)" = succeeded ] && [ "$(req GET "/v1/jobs/$id/result" "$TMP/r.q")" = 200 ] &&
    pass "finished jobs and results survive restarts" || fail "finished job after restart" "$(head -c 200 "$TMP/job")"
stop_qdcd || fail "SIGTERM" "exit status $?"
exit $((NFAIL > 0))
