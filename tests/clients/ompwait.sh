#!/bin/sh
# ompwait.sh - the OpenMP threads of qdc and qdcd sleep while they wait
# (OMP_WAIT_POLICY=PASSIVE) unless the user chose a policy, and qdc caps
# OpenMP at the threads it runs (OMP_THREAD_LIMIT: --threads, else
# OMP_NUM_THREADS, else the cores online) unless the user set a cap: the
# running process's environment is read from /proc (qdc while it optimizes a
# 100k-tet mesh, qdcd once it answers).
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"

if [ ! -r /proc/self/environ ]; then
    echo "ok - ompwait: passive by default # SKIP no /proc"
    echo "ok - ompwait: the user's policy kept # SKIP no /proc"
    echo "ok - ompwait: qdcd passive by default # SKIP no /proc"
    echo "ok - ompwait: OpenMP capped at --threads # SKIP no /proc"
    echo "ok - ompwait: OpenMP capped at OMP_NUM_THREADS, else the cores # SKIP no /proc"
    echo "ok - ompwait: the user's cap kept # SKIP no /proc"
    exit 0
fi
M=$(devmesh bunny_low_100k)

# seen_of VAR [ENV...]: VAR as the running qdc sees it ("unset" if none), with
# $QARGS on its command line
seen_of() {
    var=$1
    shift
    # shellcheck disable=SC2086
    env "$@" "$BIN/qdc" optimize "$M" "$TMP/o.mesh" --quiet --max-iter 10 --stall 0 $QARGS &
    pid=$!
    seen=
    i=0
    # polled until the re-exec shows (at most 30 s, for a busy machine) or qdc ends
    while [ $i -lt 1500 ] && kill -0 $pid 2> /dev/null; do
        # after the re-exec the process image is qdc again with the variable set
        seen=$(tr '\0' '\n' < /proc/$pid/environ 2> /dev/null | sed -n "s/^$var=//p")
        [ -n "$seen" ] && break
        sleep 0.02
        i=$((i + 1))
    done
    wait $pid
    echo "${seen:-unset} rc=$?"
}
policy_of() {
    seen_of OMP_WAIT_POLICY "$@"
}
QARGS=

res=$(policy_of -u OMP_WAIT_POLICY)
case $res in
"PASSIVE rc=0") pass "ompwait: passive by default" ;;
*) fail "ompwait: passive by default" "saw $res" ;;
esac
res=$(policy_of OMP_WAIT_POLICY=active)
case $res in
"active rc=0") pass "ompwait: the user's policy kept" ;;
*) fail "ompwait: the user's policy kept" "saw $res" ;;
esac
QARGS="--threads 1"
res=$(seen_of OMP_THREAD_LIMIT -u OMP_THREAD_LIMIT OMP_NUM_THREADS=2)
case $res in
"1 rc=0") pass "ompwait: OpenMP capped at --threads" ;;
*) fail "ompwait: OpenMP capped at --threads" "saw $res" ;;
esac
QARGS=
a=$(seen_of OMP_THREAD_LIMIT -u OMP_THREAD_LIMIT OMP_NUM_THREADS=3)
b=$(seen_of OMP_THREAD_LIMIT -u OMP_THREAD_LIMIT -u OMP_NUM_THREADS)
if [ "$a" = "3 rc=0" ] && [ "$b" = "$(getconf _NPROCESSORS_ONLN) rc=0" ]; then
    pass "ompwait: OpenMP capped at OMP_NUM_THREADS, else the cores"
else
    fail "ompwait: OpenMP capped at OMP_NUM_THREADS, else the cores" "saw '$a', '$b'"
fi
res=$(seen_of OMP_THREAD_LIMIT OMP_THREAD_LIMIT=7)
case $res in
"7 rc=0") pass "ompwait: the user's cap kept" ;;
*) fail "ompwait: the user's cap kept" "saw $res" ;;
esac
unset OMP_WAIT_POLICY
if start_qdcd "$TMP/d" --workers 1; then
    seen=$(tr '\0' '\n' < /proc/$QPID/environ | sed -n 's/^OMP_WAIT_POLICY=//p')
    comm=$(cat /proc/$QPID/comm)
    if [ "$seen" = PASSIVE ] && [ "$comm" = qdcd ]; then
        pass "ompwait: qdcd passive by default"
    else
        fail "ompwait: qdcd passive by default" "saw '${seen:-unset}', comm '$comm'"
    fi
    stop_qdcd
else
    fail "ompwait: qdcd passive by default" "qdcd did not start: $(tail -2 "$TMP/d.log")"
fi
[ "$NFAIL" = 0 ]
