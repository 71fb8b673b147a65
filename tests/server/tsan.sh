#!/bin/sh
# tsan.sh - qdcd built with ThreadSanitizer (make TSAN=1 build/tsan/qdcd, which
# make test does) under concurrent traffic: jobs submitted at once on two
# workers, long-polls and event streams on them, a cancel, a DELETE right
# after the 202, metrics, a surface job (TetGen child), then SIGTERM while a
# job runs. Passes when no data race, lock-order inversion or other report
# appears and the daemon exits 0.
. "$(dirname "$0")/../lib.sh"
QDCD=$ROOT/build/tsan/qdcd
. "$ROOT/tests/server/daemon.inc"
if [ ! -x "$QDCD" ]; then
    echo "ok - tsan # SKIP build/tsan/qdcd not built (make TSAN=1 build/tsan/qdcd)"
    exit 0
fi
# OpenBLAS's and libgomp's own thread pools are not instrumented: TSan cannot
# see their synchronization, so it reports races inside them (false ones).
# One BLAS thread, one OpenMP thread per job; anything inside those
# libraries suppressed. Everything of qdcd's own is checked.
printf 'called_from_lib:libopenblas.so.0\ncalled_from_lib:libgomp.so.1\nrace:libopenblas.so.0\nrace:libgomp.so.1\n' > "$TMP/supp"
export TSAN_OPTIONS="halt_on_error=0 log_path=$TMP/tsan second_deadlock_stack=1 suppressions=$TMP/supp"
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
gzip -dc "$DEV/cube_h0.1_lowq.mesh.gz" > "$TMP/a.mesh"
gzip -dc "$DEV/bunny_low_10k.mesh.gz" > "$TMP/b.mesh"
start_qdcd "$TMP/d" --workers 2 --qdc "$BIN/qdc" ||
    { fail "tsan: start" "$(tail -3 "$TMP/d.log")"; exit 1; }
pass "tsan: qdcd (ThreadSanitizer build) answers /livez"

ids=
for i in 1 2 3 4 5 6; do
    f=$TMP/a.mesh
    [ $((i % 2)) -eq 0 ] && f=$TMP/b.mesh
    submit "$f" model/x-medit "max_iter=2&finish=off" "$TMP/s$i" > "$TMP/c$i" &
    pids="${pids:-} $!"
done
# (a bare `wait` would wait for the daemon too)
wait $pids
pids=
for i in 1 2 3 4 5 6; do
    [ "$(cat "$TMP/c$i")" = 202 ] && ids="$ids $(jf "$TMP/s$i" .id)"
done
set -- $ids
[ $# -eq 6 ] && pass "tsan: 6 jobs submitted at once" || fail "tsan: submit" "$# accepted"
# watchers on every job: a long-poll and an event stream each
for id in $ids; do
    curl -s -m 30 "$URL/v1/jobs/$id/progress?after=-1&wait=10" > /dev/null &
    pids="$pids $!"
    curl -s -m 30 -N "$URL/v1/jobs/$id/events" > "$TMP/ev.$id" &
    pids="$pids $!"
done
req POST "/v1/jobs/$2:cancel" "$TMP/cancel" > /dev/null
# a DELETE right after a 202
submit "$TMP/a.mesh" model/x-medit "" "$TMP/s7" > /dev/null
req DELETE "/v1/jobs/$(jf "$TMP/s7" .id)" "$TMP/del" > /dev/null
req GET /metrics "$TMP/m" > /dev/null
# a surface job: the TetGen child
printf 'solid c\n' > "$TMP/cube.stl"
"$PY" - "$TMP/cube.stl" << 'PYEOF'
import sys, itertools
v = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
q = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
with open(sys.argv[1], 'w') as f:
    f.write('solid c\n')
    for a, b, c, d in q:
        for t in ((a, b, c), (a, c, d)):
            f.write(' facet normal 0 0 0\n  outer loop\n')
            for k in t:
                f.write('   vertex %g %g %g\n' % v[k])
            f.write('  endloop\n endfacet\n')
    f.write('endsolid c\n')
PYEOF
submit "$TMP/cube.stl" model/stl "max_volume=0.01" "$TMP/s8" > "$TMP/c8"
wait $pids
states=
for id in $ids $(jf "$TMP/s8" .id); do
    states="$states $(poll_all "$id")"
done
case $states in
*failed* | *queued* | *running*) fail "tsan: job states" "$states" ;;
*) pass "tsan: every job ended (states:$states)" ;;
esac
# one more job, then SIGTERM while it runs
submit "$TMP/b.mesh" model/x-medit "max_iter=50" "$TMP/s9" > /dev/null
wait_running "$(jf "$TMP/s9" .id)"
stop_qdcd && pass "tsan: SIGTERM with a job running: exit 0" || fail "tsan: stop" "exit status $?"
reports=$(cat "$TMP"/tsan.* 2> /dev/null | grep -c '^WARNING: ThreadSanitizer' || true)
if [ "$reports" -eq 0 ]; then
    pass "tsan: no ThreadSanitizer report"
else
    fail "tsan: $reports ThreadSanitizer reports" "$(cat "$TMP"/tsan.* | grep -A12 '^WARNING' | head -40 | tr '\n' ' ')"
fi
[ "$NFAIL" -eq 0 ]
