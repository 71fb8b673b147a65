#!/bin/sh
# faults/tetgen_limits.sh - a 1.3 KB closed cube STL with ?max_volume=1e-9
# made the TetGen child grow ~70 MB/s until the job's time limit: now the
# volume bound is checked against the tet limit before TetGen runs (422 at
# once), and the child runs under an address-space limit (--child-memory):
# a run that needs more fails with a clear problem instead of eating memory.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
STL=$ROOT/tests/fuzz/seeds/surface/cube.stl
start_qdcd "$TMP/d" --workers 1 --max-tets 1000000 --child-memory 268435456 ||
    { fail "tetgen: start" "$(tail -3 "$TMP/d.log")"; exit 1; }
# baseline from the same run: a small job on the same cube, meshed and optimized
t0=$(date +%s%N)
submit "$STL" model/stl "max_volume=0.01" "$TMP/j0" > /dev/null
st0=$(poll_all "$(jf "$TMP/j0" .id)")
base=$((($(date +%s%N) - t0) / 1000000))
t0=$(date +%s%N)
code=$(submit "$STL" model/stl "max_volume=1e-9" "$TMP/j")
id=$(jf "$TMP/j" .id)
st=$(poll_all "$id")
ms=$((($(date +%s%N) - t0) / 1000000))
req GET "/v1/jobs/$id" "$TMP/job" > /dev/null
status=$(jf "$TMP/job" .error.status)
detail=$(jf "$TMP/job" .error.detail)
case $st:$status:$detail in
failed:422:*"would make at least"*)
    [ "$st0" = succeeded ] && [ $ms -lt $((2000 + 3 * base)) ] &&
        pass "tetgen: max_volume=1e-9 on a unit cube: failed 422 in $ms ms (a small job: $base ms): $detail" ||
        fail "tetgen: fast refusal" "took $ms ms; a small job $st0 in $base ms" ;;
*) fail "tetgen: volume bound" "code $code state $st status $status: $detail" ;;
esac
# within the tet limit but beyond the memory limit: 1e-6 -> ~1e6+ tets under 256 MB of address space
code=$(submit "$STL" model/stl "max_volume=2e-6" "$TMP/j2")
id=$(jf "$TMP/j2" .id)
st=$(poll_all "$id")
req GET "/v1/jobs/$id" "$TMP/job2" > /dev/null
detail=$(jf "$TMP/job2" .error.detail)
case $st:$detail in
failed:*memory*) pass "tetgen: past --child-memory the job fails: $detail" ;;
succeeded:*) pass "tetgen: max_volume=2e-6 fitted in 256 MB here (succeeded) # SKIP memory limit not reached" ;;
*) fail "tetgen: memory limit" "state $st: $detail $(tail -3 "$TMP/d.log")" ;;
esac
rss=$(ps -o rss= -p "$QPID" | tr -d ' ')
[ "${rss:-0}" -lt 400000 ] && pass "tetgen: the daemon itself stays small ($rss KB)" || fail "tetgen: daemon RSS" "$rss KB"
stop_qdcd || fail "tetgen: stop" "exit $?"
exit 0
