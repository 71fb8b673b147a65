#!/bin/sh
# tests/run.sh - run every suite and print "N passed, N failed" last.
# Suites: unit tests (release and sanitizer builds), end-to-end (tests/e2e/*.sh),
# daemon (tests/server/*.sh), clients (tests/clients/*.sh), house rules (tests/house/*.sh).
# A suite prints "ok - ..." per passed check, "FAIL - ..." per failed one and
# "ok - ... # SKIP reason" (or "# SKIP ...") for a check it could not run:
# skips are counted apart, never as passes.
# QDC_QUICK=1: release unit tests only.
# Suites run QDC_TEST_JOBS at a time (default 2: many of them wait on
# daemons, databases, browsers and timers more than they compute); each
# suite's output is printed whole, in the order below, once it has ended.
# Every suite has its own temporary directory and free ports. The suites in
# ALONE run with nothing beside them: the container suites (one engine, the
# same image tags) and the load test (its latency limit is judged against an
# idle phase of its own).
ROOT=$(cd "$(dirname "$0")/.." && pwd)
export ROOT
cd "$ROOT" || exit 1
JOBS=${QDC_TEST_JOBS:-2}
ALONE="tests/container/*.sh tests/faults/load.sh"
OUT=$(mktemp -d "${TMPDIR:-/tmp}/qdc-run.XXXXXX")
trap 'rm -rf "$OUT"' EXIT
LOG=$OUT/log
: > "$LOG"

# run_one N LABEL COMMAND...: the suite's output, its failure if it exited
# non-zero without reporting one, and its time, into $OUT/N.out
run_one() {
    n=$1 label=$2
    shift 2
    start=$(date +%s)
    {
        echo "# $label"
        "$@" > "$OUT/$n.raw" 2>&1 3>&-
        rc=$?
        cat "$OUT/$n.raw"
        # a suite that exits non-zero without reporting a failure counts as one
        if [ $rc -ne 0 ] && ! grep -q '^FAIL - ' "$OUT/$n.raw"; then
            echo "FAIL - $label: exited with status $rc"
        fi
        echo "# $label: $(($(date +%s) - start)) s"
    } > "$OUT/$n.out"
    rm -f "$OUT/$n.raw"
}

# The pool: a suite that ends writes its number to the FIFO on fd 3.
mkfifo "$OUT/done" || exit 1
exec 3<> "$OUT/done"
started=0 running=0 printed=0
# flush: print the suites that have ended, in the order they were started
flush() {
    while [ $printed -lt $started ] && [ -e "$OUT/$((printed + 1)).end" ]; do
        printed=$((printed + 1))
        cat "$OUT/$printed.out"
        cat "$OUT/$printed.out" >> "$LOG"
    done
}
# reap: wait for one suite to end
reap() {
    read -r d <&3
    : > "$OUT/$d.end"
    running=$((running - 1))
    flush
}
# suite LABEL COMMAND...: run it when a place is free (alone: when all are)
suite() {
    limit=$JOBS
    for a in $ALONE; do
        case "$2 $3" in "sh $a") limit=1 ;; esac
    done
    while [ $running -gt 0 ] && [ $running -ge "$limit" ]; do reap; done
    started=$((started + 1))
    running=$((running + 1))
    (
        run_one $started "$@"
        echo $started >&3
    ) &
    # nothing starts beside a suite that runs alone
    [ "$limit" = 1 ] && while [ $running -gt 0 ]; do reap; done
}

for t in build/rel/tests/test_*; do
    [ -x "$t" ] && suite "unit $(basename "$t")" "$t"
done
if [ -z "${QDC_QUICK:-}" ]; then
    for t in build/san/tests/test_*; do
        [ -x "$t" ] && suite "asan+ubsan $(basename "$t")" env ASAN_OPTIONS=detect_leaks=1 \
            UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 "$t"
    done
    for t in tests/house/*.sh tests/e2e/*.sh tests/server/*.sh tests/faults/*.sh tests/clients/*.sh tests/container/*.sh; do
        [ -f "$t" ] && suite "$t" sh "$t"
    done
fi
while [ $running -gt 0 ]; do reap; done
exec 3>&-
skipped=$(grep -Ec '^(ok - .*)?# SKIP' "$LOG")
passed=$(grep '^ok - ' "$LOG" | grep -vc '# SKIP')
failed=$(grep -c '^FAIL - ' "$LOG")
echo
grep '^FAIL - ' "$LOG" | sed 's/^/  /'
grep -E '^(ok - .*)?# SKIP' "$LOG" | sed 's/^/  /'
echo "$passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
