#!/bin/sh
# signals.sh - a stop signal always ends in the graceful shutdown (drain, exit
# 0), whichever thread the kernel hands it to. qdcd blocks SIGTERM and SIGINT
# in its threads and takes them in the main loop; threads a library starts
# before main() (OpenBLAS's pool) do not block them. By default qdcd runs with
# one BLAS thread, so no such thread exists; where the operator asks for more,
# a stop signal that lands on one is forwarded to the main thread. Both are
# checked here through /proc (the threads' blocked masks, a signal sent to one
# thread with tgkill).
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

if [ ! -r /proc/self/task/$$/status ]; then
    echo "ok - signals # SKIP no /proc"
    exit 0
fi

# the threads of pid $1, other than the main one, that do not block SIGTERM
# (bit 15 of SigBlk, 0x4000)
unblocked() {
    for _t in /proc/"$1"/task/*; do
        _n=${_t##*/}
        [ "$_n" = "$1" ] && continue
        _m=$(sed -n 's/^SigBlk:[[:space:]]*//p' "$_t/status")
        [ $((0x$_m & 0x4000)) -eq 0 ] && echo "$_n"
    done
}

unset OPENBLAS_NUM_THREADS
start_qdcd "$TMP/d" --workers 2 || { fail "start" "$(tail -3 "$TMP/d.log")"; exit 1; }
n=$(ls /proc/"$QPID"/task | wc -l)
u=$(unblocked "$QPID")
if [ -z "$u" ] && [ "$n" -gt 2 ]; then
    pass "default: every thread but the main one blocks SIGTERM ($n threads)"
else
    fail "default threads" "$n threads, not blocking SIGTERM: $u"
fi
if stop_qdcd && grep -q "^qdcd: stopped" "$TMP/d.log"; then
    pass "default: SIGTERM -> drained, exit 0"
else
    fail "default stop" "$(tail -3 "$TMP/d.log")"
fi

OPENBLAS_NUM_THREADS=2
export OPENBLAS_NUM_THREADS
start_qdcd "$TMP/b" --workers 2 || { fail "start (2 BLAS threads)" "$(tail -3 "$TMP/b.log")"; exit 1; }
t=$(unblocked "$QPID" | head -1)
if [ -z "$t" ]; then
    # an OpenBLAS built without threads, or one that blocks signals itself
    echo "ok - signals: SIGTERM on a stray thread # SKIP no thread without SIGTERM blocked"
    stop_qdcd
    exit 0
fi
# tgkill (syscall 234 on x86-64) with SIGTERM (15)
"$PY" -c 'import ctypes, sys; sys.exit(ctypes.CDLL(None).syscall(234, int(sys.argv[1]), int(sys.argv[2]), 15) != 0)' \
    "$QPID" "$t" || fail "tgkill" "could not signal thread $t"
# the daemon must stop by itself (drain, exit 0), not die of the signal
i=0
while kill -0 "$QPID" 2> /dev/null && [ $i -lt 100 ]; do
    sleep 0.1
    i=$((i + 1))
done
wait "$QPID"
rc=$?
QPID=
if [ "$rc" = 0 ] && grep -q "^qdcd: stopped" "$TMP/b.log"; then
    pass "SIGTERM sent to a thread that does not block it (OpenBLAS's, OPENBLAS_NUM_THREADS=2): forwarded, drained, exit 0"
else
    fail "SIGTERM on a stray thread" "exit status $rc: $(tail -2 "$TMP/b.log")"
fi
exit $((NFAIL > 0))
