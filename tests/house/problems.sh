#!/bin/sh
# tests/house/problems.sh - one problem+json table: every problem type the
# daemon names (http_problem(...), a job's problem(...), the slugs of
# status_slug) is an entry of server/problem.c, and no other file writes a
# "/problems/" type by hand.
ROOT=${ROOT:-$(cd "$(dirname "$0")/../.." && pwd)}
cd "$ROOT" || exit 1
fail=0
table=$(sed -n 's/^[[:space:]]*{"\([a-z-]*\)", [0-9][0-9][0-9],.*/\1/p' server/problem.c)
if [ -z "$table" ]; then
    echo "FAIL - problems: no table in server/problem.c"
    exit 1
fi
# The first string literal after http_problem( or problem(j, across line breaks,
# and the literals status_slug returns.
used=$(for f in server/*.c; do tr '\n' ' ' <"$f" |
    grep -o '\(http_problem\|problem\)([^";]*"[a-z-]*"' | sed 's/.*"\([a-z-]*\)"$/\1/'
done
sed -n '/^static const char \*status_slug/,/^}/s/.*return "\([a-z-]*\)";.*/\1/p' server/api.c)
n=0
for s in $(echo "$used" | sort -u); do
    n=$((n + 1))
    if ! echo "$table" | grep -qx "$s"; then
        echo "FAIL - problems: type '$s' is used but not in server/problem.c"
        fail=1
    fi
done
if [ "$n" -lt 20 ]; then
    echo "FAIL - problems: only $n problem types found in use (the scan is broken)"
    fail=1
fi
hand=$(grep -l '\\"/problems/' server/*.c | grep -v '^server/problem.c$')
if [ -n "$hand" ]; then
    echo "FAIL - problems: problem bodies built by hand in: $hand"
    fail=1
fi
[ $fail = 0 ] && echo "ok - problems: the $n problem types in use are all in the one table"
exit $fail
