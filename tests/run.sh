#!/bin/sh
# tests/run.sh - run every suite and print "N passed, N failed" last.
# Suites: unit tests (release and sanitizer builds), end-to-end (tests/e2e/*.sh),
# daemon (tests/server/*.sh), clients (tests/clients/*.sh), house rules (tests/house/*.sh).
# A suite prints "ok - ..." per passed check, "FAIL - ..." per failed one and
# "ok - ... # SKIP reason" (or "# SKIP ...") for a check it could not run:
# skips are counted apart, never as passes.
# QDC_QUICK=1: release unit tests only.
ROOT=$(cd "$(dirname "$0")/.." && pwd)
export ROOT
cd "$ROOT" || exit 1
LOG=$(mktemp)
trap 'rm -f "$LOG"' EXIT
crashed=0

run_one() { # label command...
    label=$1; shift
    echo "# $label"
    start=$(date +%s)
    "$@" > "$LOG.one" 2>&1
    rc=$?
    cat "$LOG.one"
    cat "$LOG.one" >> "$LOG"
    # a suite that exits non-zero without reporting a failure counts as one
    if [ $rc -ne 0 ] && ! grep -q '^FAIL - ' "$LOG.one"; then
        echo "FAIL - $label: exited with status $rc" | tee -a "$LOG"
    fi
    echo "# $label: $(( $(date +%s) - start )) s"
    rm -f "$LOG.one"
}

for t in build/rel/tests/test_*; do
    [ -x "$t" ] && run_one "unit $(basename "$t")" "$t"
done
if [ -z "${QDC_QUICK:-}" ]; then
    for t in build/san/tests/test_*; do
        [ -x "$t" ] && run_one "asan+ubsan $(basename "$t")" env ASAN_OPTIONS=detect_leaks=1 \
            UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 "$t"
    done
    for t in tests/house/*.sh tests/e2e/*.sh tests/server/*.sh tests/faults/*.sh tests/clients/*.sh tests/container/*.sh; do
        [ -f "$t" ] && run_one "$t" sh "$t"
    done
fi
skipped=$(grep -Ec '^(ok - .*)?# SKIP' "$LOG")
passed=$(grep '^ok - ' "$LOG" | grep -vc '# SKIP')
failed=$(grep -c '^FAIL - ' "$LOG")
echo
grep '^FAIL - ' "$LOG" | sed 's/^/  /'
grep -E '^(ok - .*)?# SKIP' "$LOG" | sed 's/^/  /'
echo "$passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
