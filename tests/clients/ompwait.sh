#!/bin/sh
# ompwait.sh - qdc's OpenMP threads sleep while they wait (OMP_WAIT_POLICY=PASSIVE)
# unless the user chose a policy: the running process's environment is read
# from /proc while it optimizes a 100k-tet mesh.
. "$(dirname "$0")/../lib.sh"

if [ ! -r /proc/self/environ ]; then
    echo "ok - ompwait: passive by default # SKIP no /proc"
    echo "ok - ompwait: the user's policy kept # SKIP no /proc"
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
[ "$NFAIL" = 0 ]
