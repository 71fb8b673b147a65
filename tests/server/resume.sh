#!/bin/sh
# resume.sh - readers that follow a job across its restart are told the job
# runs again: qdc watch and the Python client's wait() follow a running job,
# the daemon is killed (kill -9) and started again on the same port; both
# retry, resume with after= and the attempt their records came from, and
# report that the job runs again from the start (attempt 2) instead of
# appending the new run's records to the old ones.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

MESH=$(devmesh cube_h0.1_lowq)
$MT qmesh "$MESH" "$TMP/big.qmesh"
D=$TMP/d

start_qdcd "$D" --workers 1 || { fail "start" "$(tail -3 "$D.log")"; exit 1; }
P=$PORT
submit "$TMP/big.qmesh" application/vnd.qdc.mesh "max_iter=400&finish=0&tol_move=0&mode=literal" "$TMP/j" > /dev/null
id=$(jf "$TMP/j" .id)
curl -s -m 60 "$URL/v1/jobs/$id/progress?after=2&wait=50" > /dev/null

"$BIN/qdc" watch --server "$URL" "$id" > "$TMP/watch.out" 2> "$TMP/watch.err" &
WPID=$!
PYTHONPATH=$ROOT/clients/python $PY - "$URL" "$id" > "$TMP/py.out" 2>&1 << 'EOF' &
import sys
from qdc_client import Client
c = Client(sys.argv[1], retries=30)
seen = []
def rec(r):
    seen.append((r["attempt"], r["seq"]))
    print("record", r["attempt"], r["seq"], flush=True)
def restart(r):
    print("restart", r["from_attempt"], r["attempt"], flush=True)
final = c.wait(sys.argv[2], on_progress=rec, on_restart=restart, poll_wait=5,
               raise_on_failure=False)
print("final", final["state"], final["attempts"], flush=True)
EOF
PYPID=$!
# both have printed records of the first run
i=0
while [ $i -lt 600 ] && ! { grep -q "^record 1 " "$TMP/py.out" && grep -q "global" "$TMP/watch.out"; }; do
    sleep 0.1
    i=$((i + 1))
done
kill -9 "$QPID"
wait "$QPID" 2> /dev/null
QPID=
# the same port again (the clients retry it)
"$QDCD" --listen 127.0.0.1:$P --data "$D" --workers 1 >> "$D.log" 2>&1 &
QPID=$!
i=0
while [ $i -lt 300 ] && ! grep -q "^restart" "$TMP/py.out"; do
    sleep 0.1
    i=$((i + 1))
done
i=0
while [ $i -lt 300 ] && ! grep -q "runs again" "$TMP/watch.out"; do
    sleep 0.1
    i=$((i + 1))
done
curl -s -X POST "$URL/v1/jobs/$id:cancel" > /dev/null
i=0
while [ $i -lt 600 ] && { kill -0 $WPID 2> /dev/null || kill -0 $PYPID 2> /dev/null; }; do
    sleep 0.1
    i=$((i + 1))
done
kill $WPID $PYPID 2> /dev/null

# Python: records of attempt 1, the restart, records of attempt 2 from seq 0
if grep -q "^restart 1 2$" "$TMP/py.out" &&
    awk '/^restart/ { r = NR } /^record 2 / && !f { f = NR; s = $3 } END { exit !(r && f > r && s == 0) }' "$TMP/py.out" &&
    ! awk '/^restart/ { r = 1 } r && /^record 1 / { bad = 1 } END { exit !bad }' "$TMP/py.out" &&
    grep -q "^final cancelled 2$" "$TMP/py.out"; then
    pass "Python wait(): on_restart(1 -> 2), then the new run's records from seq 0; cancelled on attempt 2 ($(grep -c '^record 1 ' "$TMP/py.out") + $(grep -c '^record 2 ' "$TMP/py.out") records)"
else
    fail "Python client across the restart" "$(grep -v '^record' "$TMP/py.out" | head -5 | tr '\n' ' ') $(grep '^record' "$TMP/py.out" | head -3 | tr '\n' ' ')"
fi
if grep -q "job $id runs again from the start: attempt 2 (attempt 1 stopped)" "$TMP/watch.out" &&
    grep -q "job $id cancelled" "$TMP/watch.out"; then
    pass "qdc watch: 'job ... runs again from the start: attempt 2 (attempt 1 stopped)', then cancelled"
else
    fail "qdc watch across the restart" "$(tail -5 "$TMP/watch.out" | tr '\n' ' ') $(tail -3 "$TMP/watch.err" | tr '\n' ' ')"
fi
stop_qdcd

exit $((NFAIL > 0))
