#!/bin/sh
# faults/recovery.sh - a job that used all its attempts in crashes is failed
# at start-up and kept for --retention like any finished job (it was kept for
# a fixed 86400 s whatever --retention said).
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
$MT qmesh "$ROOT/tests/data/sample/cube.mesh" "$TMP/c.qmesh" || { fail "recovery: sample" "meshtool"; exit 1; }
start_qdcd "$TMP/d" --workers 1 --max-attempts 1 --retention 7 || { fail "recovery: start" "$(tail -3 "$TMP/d.log")"; exit 1; }
submit "$TMP/c.qmesh" application/vnd.qdc.mesh "max_iter=10000&finish=0&tol_move=0&mode=literal&ls_halvings=0" "$TMP/j" > /dev/null
id=$(jf "$TMP/j" .id)
curl -s -m 30 "$URL/v1/jobs/$id/progress?after=0&wait=20" > /dev/null
kill -9 "$QPID"
wait "$QPID" 2> /dev/null
QPID=
start_qdcd "$TMP/d" --workers 1 --max-attempts 1 --retention 7 || { fail "recovery: restart" "$(tail -3 "$TMP/d.log")"; exit 1; }
req GET "/v1/jobs/$id" "$TMP/g" > /dev/null
st=$(jf "$TMP/g" .state)
keep=$(jq -r '.expires - .finished' "$TMP/g")
if [ "$st" = failed ] && awk -v k="$keep" 'BEGIN { exit !(k > 6.9 && k < 7.1) }'; then
    pass "recovery: the crashed job failed after its 1 attempt and is kept for --retention ($keep s)"
else
    fail "recovery: retention" "state $st, kept for $keep s (want 7)"
fi
stop_qdcd || fail "recovery: stop" "exit $?"
exit 0
