#!/bin/sh
# ompwait.sh - the OpenMP threads of qdc and qdcd sleep while they wait
# (OMP_WAIT_POLICY=PASSIVE) unless the user chose a policy: the running
# process's environment is read from /proc (qdc while it optimizes a 100k-tet
# mesh, qdcd once it answers).
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"

if [ ! -r /proc/self/environ ]; then
    echo "ok - ompwait: passive by default # SKIP no /proc"
    echo "ok - ompwait: the user's policy kept # SKIP no /proc"
    echo "ok - ompwait: qdcd passive by default # SKIP no /proc"
    exit 0
fi
M=$(devmesh bunny_low_100k)

# policy_of [ENV...]: the OMP_WAIT_POLICY the running qdc sees ("unset" if none)
policy_of() {
    env "$@" "$BIN/qdc" optimize "$M" "$TMP/o.mesh" --quiet --max-iter 10 --stall 0 &
    pid=$!
    seen=
    i=0
    while [ $i -lt 100 ] && kill -0 $pid 2> /dev/null; do
        # after the re-exec the process image is qdc again with the variable set
        seen=$(tr '\0' '\n' < /proc/$pid/environ 2> /dev/null | sed -n 's/^OMP_WAIT_POLICY=//p')
        [ -n "$seen" ] && break
        sleep 0.02
        i=$((i + 1))
    done
    wait $pid
    echo "${seen:-unset} rc=$?"
}

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
