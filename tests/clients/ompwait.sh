#!/bin/sh
# ompwait.sh - the OpenMP threads of qdc and qdcd sleep while they wait
# (OMP_WAIT_POLICY=PASSIVE) unless the user chose a policy, and qdc caps
# OpenMP at the threads it runs (OMP_THREAD_LIMIT: --threads, else
# OMP_NUM_THREADS, else the cores online) unless the user set a cap: the
# running process's environment is read from /proc (qdc while it optimizes a
# 100k-tet mesh, qdcd once it answers). Both also run with malloc kept from
# handing memory back at each free, in transparent huge pages (GLIBC_TUNABLES,
# glibc.malloc.*), unless the user tuned malloc.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"

if [ ! -r /proc/self/environ ]; then
    echo "ok - ompwait: passive by default # SKIP no /proc"
    echo "ok - ompwait: the user's policy kept # SKIP no /proc"
    echo "ok - ompwait: qdcd passive by default # SKIP no /proc"
    echo "ok - ompwait: OpenMP capped at --threads # SKIP no /proc"
    echo "ok - ompwait: OpenMP capped at OMP_NUM_THREADS, else the cores # SKIP no /proc"
    echo "ok - ompwait: the user's cap kept # SKIP no /proc"
    echo "ok - ompwait: malloc tuned by default # SKIP no /proc"
    echo "ok - ompwait: the user's malloc tunables kept # SKIP no /proc"
    echo "ok - ompwait: the user's other tunables kept # SKIP no /proc"
    echo "ok - ompwait: qdcd's malloc tuned by default # SKIP no /proc"
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
# tunables_of [ENV...]: "TUNABLES HUGE rc=N": GLIBC_TUNABLES as the running qdc
# saw it at its re-exec (OMP_WAIT_POLICY unset before it: the re-exec sets it;
# /proc shows the first tunable only, as glibc leaves the string it parsed),
# "unset" if none, and "huge" once its memory is seen in transparent huge pages
# (AnonHugePages), else "small"
tunables_of() {
    env -u OMP_WAIT_POLICY "$@" "$BIN/qdc" optimize "$M" "$TMP/o.mesh" --quiet --max-iter 10 \
        --stall 0 &
    pid=$!
    seen=
    huge=small
    i=0
    while [ $i -lt 1500 ] && kill -0 $pid 2> /dev/null; do
        env=$( (tr '\0' '\n' < "/proc/$pid/environ") 2> /dev/null)
        if printf '%s\n' "$env" | grep -q '^OMP_WAIT_POLICY='; then
            [ -n "$seen" ] || seen=$(printf '%s\n' "$env" | sed -n 's/^GLIBC_TUNABLES=//p')
            [ -n "$seen" ] || seen="unset"
            kb=$(sed -n 's/^AnonHugePages: *\([0-9]*\) kB/\1/p' /proc/$pid/smaps_rollup \
                2> /dev/null)
            if [ "${kb:-0}" -gt 0 ]; then
                huge=huge
                break
            fi
        fi
        sleep 0.02
        i=$((i + 1))
    done
    wait $pid
    echo "$seen $huge rc=$?"
}
# "huge" is asserted only where the kernel gives huge pages on request
# (H), "small" only where it gives them on request alone (S)
THP=$(sed -n 's/.*\[\(.*\)\].*/\1/p' /sys/kernel/mm/transparent_hugepage/enabled 2> /dev/null)
H='*'
S='*'
case $THP in
always) H=huge ;;
madvise) H=huge S=small ;;
esac
res=$(tunables_of -u GLIBC_TUNABLES)
# shellcheck disable=SC2254,SC2027
case $res in
"glibc.malloc.hugetlb=1 "$H" rc=0") pass "ompwait: malloc tuned by default" ;;
*) fail "ompwait: malloc tuned by default" "saw $res (THP $THP)" ;;
esac
a=$(tunables_of GLIBC_TUNABLES=glibc.malloc.hugetlb=0)
b=$(tunables_of -u GLIBC_TUNABLES MALLOC_TRIM_THRESHOLD_=131072)
# shellcheck disable=SC2254,SC2027
case "$a/$b" in
"glibc.malloc.hugetlb=0 "$S" rc=0/unset "$S" rc=0")
    pass "ompwait: the user's malloc tunables kept" ;;
*) fail "ompwait: the user's malloc tunables kept" "saw '$a', '$b' (THP $THP)" ;;
esac
res=$(tunables_of GLIBC_TUNABLES=glibc.pthread.rseq=1)
# shellcheck disable=SC2254,SC2027
case $res in
"glibc.pthread.rseq=1 "$H" rc=0") pass "ompwait: the user's other tunables kept" ;;
*) fail "ompwait: the user's other tunables kept" "saw $res (THP $THP)" ;;
esac
unset OMP_WAIT_POLICY GLIBC_TUNABLES
if start_qdcd "$TMP/d" --workers 1; then
    seen=$(tr '\0' '\n' < /proc/$QPID/environ | sed -n 's/^OMP_WAIT_POLICY=//p')
    comm=$(cat /proc/$QPID/comm)
    if [ "$seen" = PASSIVE ] && [ "$comm" = qdcd ]; then
        pass "ompwait: qdcd passive by default"
    else
        fail "ompwait: qdcd passive by default" "saw '${seen:-unset}', comm '$comm'"
    fi
    seen=$(tr '\0' '\n' < /proc/$QPID/environ | sed -n 's/^GLIBC_TUNABLES=//p')
    case $seen in
    glibc.malloc.hugetlb=1) pass "ompwait: qdcd's malloc tuned by default" ;;
    *) fail "ompwait: qdcd's malloc tuned by default" "saw '${seen:-unset}'" ;;
    esac
    stop_qdcd
else
    fail "ompwait: qdcd passive by default" "qdcd did not start: $(tail -2 "$TMP/d.log")"
    fail "ompwait: qdcd's malloc tuned by default" "qdcd did not start"
fi
[ "$NFAIL" = 0 ]
