#!/bin/sh
# startup.sh - start-up in order: the data directory's lock, then the port,
# then the store and the workers. A qdcd whose port is taken exits non-zero
# naming the address and port, before it opens the store: the job it would
# have recovered stays as it was and the queued one stays unclaimed
# (attempts 0, never started; before, it claimed and ran a job first). A
# second qdcd on the same --data stops at the lock, whatever its store.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

MESH=$(devmesh cube_h0.1_lowq)
$MT qmesh "$MESH" "$TMP/big.qmesh"
QM=application/vnd.qdc.mesh
D=$TMP/d

# row ID: "state attempts started" of a job, read from the SQLite store
row() {
    $PY - "$D/qdcd.db" "$1" << 'EOF'
import sqlite3, sys
c = sqlite3.connect("file:%s?mode=ro" % sys.argv[1], uri=True)
r = c.execute("SELECT state, attempts, started FROM jobs WHERE id = ?", (sys.argv[2],)).fetchone()
print("%d %d %s" % (r[0], r[1], "set" if r[2] else "unset"))
EOF
}

# A: one worker busy with a long job, a second job queued behind it; then
# killed (the running job would be re-queued by the next start-up)
start_qdcd "$D" --workers 1 || { fail "start" "$(tail -3 "$D.log")"; exit 1; }
submit "$TMP/big.qmesh" $QM "max_iter=400&finish=0&tol_move=0&mode=literal" "$TMP/j1" > /dev/null
id1=$(jf "$TMP/j1" .id)
curl -s -m 60 "$URL/v1/jobs/$id1/progress?after=0&wait=50" > /dev/null
submit "$ROOT/tests/data/sample/cube.mesh" model/x-medit "max_iter=2" "$TMP/j2" > /dev/null
id2=$(jf "$TMP/j2" .id)
kill -9 "$QPID"
wait "$QPID" 2> /dev/null
QPID=
r1=$(row "$id1")
r2=$(row "$id2")
[ "$r1" = "1 1 set" ] && [ "$r2" = "0 0 unset" ] &&
    pass "killed with job 1 running (attempt 1) and job 2 queued" ||
    fail "setup" "job 1: $r1, job 2: $r2"

# another daemon holds a port; B is told to listen on it
start_qdcd "$TMP/other" --workers 1 || { fail "start the port holder" "$(tail -3 "$TMP/other.log")"; exit 1; }
HOLDER=$QPID
TAKEN=$PORT
"$QDCD" --listen 127.0.0.1:$TAKEN --data "$D" --workers 1 > "$TMP/b.log" 2>&1
rc=$?
if [ $rc != 0 ] && grep -q "cannot listen on 127.0.0.1:$TAKEN: Address already in use" "$TMP/b.log" &&
    ! grep -q "re-queued\|listening" "$TMP/b.log"; then
    pass "port $TAKEN taken: exit $rc, '$(head -1 "$TMP/b.log")'"
else
    fail "port taken" "exit $rc: $(cat "$TMP/b.log")"
fi
r1=$(row "$id1")
r2=$(row "$id2")
[ "$r1" = "1 1 set" ] && [ "$r2" = "0 0 unset" ] &&
    pass "the daemon that could not bind claimed nothing: job 2 queued, attempts 0, never started; job 1 not recovered" ||
    fail "claimed a job" "job 1: $r1, job 2: $r2 (want '1 1 set', '0 0 unset')"

# the lock comes first: a second daemon on the holder's --data stops there
"$QDCD" --listen 127.0.0.1:0 --data "$TMP/other" > "$TMP/c.log" 2>&1
rc=$?
[ $rc != 0 ] && grep -q "in use by another qdcd (pid $HOLDER)" "$TMP/c.log" &&
    pass "a second qdcd on the same --data: exit $rc, names the holder's pid" ||
    fail "lock" "exit $rc: $(cat "$TMP/c.log")"
stop_qdcd
QPID=$HOLDER
stop_qdcd

# B on a free port: job 1 re-queued and run again (attempt 2; cancelled
# then, it is long), job 2 runs after it (attempt 1)
start_qdcd "$D" --workers 1 || { fail "restart" "$(tail -3 "$D.log")"; exit 1; }
curl -s -m 60 "$URL/v1/jobs/$id1/progress?after=0&wait=50" > /dev/null
a1=$(curl -s "$URL/v1/jobs/$id1" | jq -r '"\(.state) \(.attempts)"')
curl -s -X POST "$URL/v1/jobs/$id1:cancel" > /dev/null
s2=$(wait_done "$id2")
r2=$(row "$id2")
[ "$a1" = "running 2" ] && [ "$s2" = succeeded ] && [ "${r2#* }" = "1 set" ] &&
    pass "started on a free port: job 1 ran again on attempt 2, job 2 succeeded on attempt 1" ||
    fail "after restart" "job 1: $a1, job 2: $s2 ($r2)"
stop_qdcd

exit $((NFAIL > 0))
