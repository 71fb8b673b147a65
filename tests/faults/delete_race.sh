#!/bin/sh
# faults/delete_race.sh - DELETE right after the 202 cancels the job even when
# a worker claims it between the handler's read and its delete: the old
# daemon answered 204 and 404 but let the worker run the deleted job's whole
# budget (2 of 4 tries). 10 tries, each with a job that would run for minutes;
# after each, no worker may stay busy and the job's directory must go.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
start_qdcd "$TMP/d" --workers 1 || { fail "delete race: start" "$(tail -3 "$TMP/d.log")"; exit 1; }
$MT qmesh "$ROOT/tests/data/sample/cube.mesh" "$TMP/c.qmesh" || { fail "delete race: sample" "meshtool"; exit 1; }
bad=
for i in 1 2 3 4 5 6 7 8 9 10; do
    code=$(submit "$TMP/c.qmesh" application/vnd.qdc.mesh "max_iter=10000&finish=0&tol_move=0&mode=literal&ls_halvings=0" "$TMP/j$i")
    id=$(jf "$TMP/j$i" .id)
    del=$(req DELETE "/v1/jobs/$id" "$TMP/del$i")
    n=0
    busy=1
    while [ $n -lt 30 ]; do
        busy=$(curl -s "$URL/metrics" | awk '$1 == "qdcd_workers_busy" { print $2 }')
        [ "$busy" = 0 ] && [ ! -e "$TMP/d/jobs/$id" ] && break
        sleep 0.1
        n=$((n + 1))
    done
    get=$(req GET "/v1/jobs/$id" "$TMP/g$i")
    [ "$code$del$get" = 202204404 ] && [ "$busy" = 0 ] && [ ! -e "$TMP/d/jobs/$id" ] ||
        bad="$bad try $i: $code $del $get busy $busy dir $(ls -d "$TMP/d/jobs/$id" 2> /dev/null);"
done
[ -z "$bad" ] && pass "delete race: 10 DELETEs right after the 202: each 204 then 404, no worker left busy, no directory left" ||
    fail "delete race" "$bad"
stop_qdcd || fail "delete race: stop" "exit $?"
exit 0
