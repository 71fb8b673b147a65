#!/bin/sh
# tests/run.sh - run every suite and print "N passed, N failed" last.
# Suites: unit tests (release and sanitizer builds), end-to-end (tests/e2e/*.sh),
# daemon (tests/server/*.sh), clients (tests/clients/*.sh), house rules (tests/house/*.sh).
# A suite prints "ok - ..." per passed check, "FAIL - ..." per failed one and
# "ok - ... # SKIP reason" (or "# SKIP ...") for a check it could not run:
# skips are counted apart, never as passes.
# QDC_QUICK=1: release unit tests only.
#
# Suites run QDC_TEST_JOBS at a time (default 2); each suite's output is
# printed whole, with its time, once it and those started before it have
# ended. Every suite has its own temporary directory and free ports. A free
# place goes to a computing suite (unit tests, house rules, end-to-end: the
# optimizer, Python checks; the client suites that build) when the other
# runs a waiting one (daemon, fault and client suites: timers, leases,
# databases, browsers) and the other way round, so that two at a time use
# the machine rather than fight over it. The container suites share one
# engine and the same image tags: they run one after the other, in one
# place. tests/faults/load.sh runs last with nothing beside it: its latency
# limit (100 ms at least) is judged against an idle phase of its own.
ROOT=$(cd "$(dirname "$0")/.." && pwd)
export ROOT
cd "$ROOT" || exit 1
JOBS=${QDC_TEST_JOBS:-2}
ALONE=tests/faults/load.sh
# client suites that compute: each builds the project (make run in a fresh
# clone, the Dockerfile's build stage)
BUILDS="tests/clients/make_run.sh tests/clients/docker.sh"
OUT=$(mktemp -d "${TMPDIR:-/tmp}/qdc-run.XXXXXX")
trap 'rm -rf "$OUT"' EXIT
LOG=$OUT/log
: > "$LOG"

# The suites, one per line: "LABEL<tab>COMMAND..." ("unit NAME" and the
# sanitizer's run their binary; a script's label is its path)
{
    for t in build/rel/tests/test_*; do
        [ -x "$t" ] && printf 'unit %s\t%s\n' "$(basename "$t")" "$t"
    done
    if [ -z "${QDC_QUICK:-}" ]; then
        for t in build/san/tests/test_*; do
            [ -x "$t" ] && printf 'asan+ubsan %s\tenv ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 %s\n' \
                "$(basename "$t")" "$t"
        done
        for t in tests/house/*.sh tests/e2e/*.sh $BUILDS; do
            [ -f "$t" ] && printf '%s\tsh %s\n' "$t" "$t"
        done
    fi
} > "$OUT/compute"
: > "$OUT/wait"
: > "$OUT/containers"
if [ -z "${QDC_QUICK:-}" ]; then
    for t in tests/server/*.sh tests/faults/*.sh tests/clients/*.sh; do
        case " $ALONE $BUILDS " in *" $t "*) continue ;; esac
        [ -f "$t" ] && printf '%s\tsh %s\n' "$t" "$t"
    done > "$OUT/wait"
    for t in tests/container/*.sh; do
        [ -f "$t" ] && printf '%s\tsh %s\n' "$t" "$t"
    done > "$OUT/containers"
fi

# run_one N LINE: the suite's output, its failure if it exited non-zero
# without reporting one, and its time, into $OUT/N.out
run_one() {
    n=$1
    label=$(printf '%s' "$2" | cut -f1)
    cmd=$(printf '%s' "$2" | cut -f2-)
    start=$(date +%s)
    {
        echo "# $label"
        # (paths and options without blanks: the command is split on them)
        $cmd > "$OUT/$n.raw" 2>&1 3>&-
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

# The pool: each suite that ends writes "N" to the FIFO on fd 3, and
# "N free" when its place is free for the next one.
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
# reap: wait for a suite to end
reap() {
    read -r d free <&3
    : > "$OUT/$d.end"
    if [ -n "$free" ]; then
        running=$((running - 1))
        case $(cat "$OUT/kind.$d") in
        compute) ncomp=$((ncomp - 1)) ;;
        *) nwait=$((nwait - 1)) ;;
        esac
    fi
    flush
}
# place FILE KIND: run FILE's suites one after the other in the next free
# place; KIND (compute or wait) counts for the choice of the next suite
place() {
    [ -s "$1" ] || return 0
    while [ $running -ge "$JOBS" ]; do reap; done
    first=$((started + 1))
    started=$((started + $(wc -l < "$1")))
    running=$((running + 1))
    echo "$2" > "$OUT/kind.$started"
    case $2 in compute) ncomp=$((ncomp + 1)) ;; *) nwait=$((nwait + 1)) ;; esac
    cp "$1" "$OUT/place.$first"
    (
        n=$first
        while IFS= read -r line; do
            run_one $n "$line"
            [ $n = $started ] && echo "$n free" >&3 || echo "$n" >&3
            n=$((n + 1))
        done < "$OUT/place.$first"
    ) &
}

ncomp=0 nwait=0
place "$OUT/containers" compute
# a free place takes a computing suite when fewer of those run than
# waiting ones, else a waiting one (while both lists last)
nc=$(wc -l < "$OUT/compute") nw=$(wc -l < "$OUT/wait")
ic=1 iw=1
while [ $ic -le "$nc" ] || [ $iw -le "$nw" ]; do
    while [ $running -ge "$JOBS" ]; do reap; done
    if [ $iw -gt "$nw" ] || { [ $ic -le "$nc" ] && [ $ncomp -le $nwait ]; }; then
        sed -n "${ic}p" "$OUT/compute" > "$OUT/one"
        place "$OUT/one" compute
        ic=$((ic + 1))
    else
        sed -n "${iw}p" "$OUT/wait" > "$OUT/one"
        place "$OUT/one" wait
        iw=$((iw + 1))
    fi
done
while [ $running -gt 0 ]; do reap; done
if [ -z "${QDC_QUICK:-}" ] && [ -f "$ALONE" ]; then
    printf '%s\tsh %s\n' "$ALONE" "$ALONE" > "$OUT/one"
    place "$OUT/one" wait
    while [ $running -gt 0 ]; do reap; done
fi
exec 3>&-
skipped=$(grep -Ec '^(ok - .*)?# SKIP' "$LOG")
passed=$(grep '^ok - ' "$LOG" | grep -vc '# SKIP')
failed=$(grep -c '^FAIL - ' "$LOG")
echo
grep '^FAIL - ' "$LOG" | sed 's/^/  /'
grep -E '^(ok - .*)?# SKIP' "$LOG" | sed 's/^/  /'
echo "$passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
