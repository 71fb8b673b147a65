#!/bin/sh
# tests/house/problems.sh - one problem+json table: every problem type the
# daemon names (http_problem(...), a job's problem(...), the slugs of
# status_slug) is an entry of server/problem.c, no other file writes a
# "/problems/" type by hand, and each title is written once: no two types
# share a title, and a reply gives its own title only when it says more than
# the table's (else NULL, the table's).
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
sed -n '/^static const char \*status_slug/,/^}/s/.*return "\([a-z-]*\)";.*/\1/p' server/*.c)
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
if ! grep -q '^static const char \*status_slug' server/*.c; then
    echo "FAIL - problems: status_slug not found in server/*.c (the scan is broken)"
    fail=1
fi
# Titles: "slug<TAB>title" of the table, then of every call with a literal title.
titles=$(tr '\n' ' ' < server/problem.c | grep -o '{"[a-z-]*", [0-9][0-9][0-9], *"[^"]*"' |
    sed 's/{"\([a-z-]*\)", [0-9]*, *"\([^"]*\)"/\1\t\2/')
same=$(echo "$titles" | cut -f2 | sort | uniq -d)
if [ -n "$same" ]; then
    echo "FAIL - problems: types of server/problem.c share a title: $same"
    fail=1
fi
twice=$(for f in server/*.c; do tr '\n' ' ' < "$f" |
    grep -o '\(http_problem\|problem\)([^";]*"[a-z-]*", *"[^"]*"' |
    sed 's/.*"\([a-z-]*\)", *"\([^"]*\)"$/\1\t\2/' | sed "s|^|$f\t|"
done | while IFS="$(printf '\t')" read -r f slug title; do
    echo "$titles" | grep -qxF "$slug	$title" && echo "$f: $slug '$title'"
done)
if [ -n "$twice" ]; then
    echo "FAIL - problems: the table's title written again (pass NULL): $twice"
    fail=1
fi
[ $fail = 0 ] && echo "ok - problems: the $n problem types in use are all in the one table, each title written once ($(echo "$titles" | wc -l) types)"
exit $fail
