#!/bin/sh
# example.sh - examples/optimize.c, a program that uses the library through
# qdc.h alone, optimizes the bundled cube (1 inverted tet): it exits 0, what
# it reports of its output is what `qdc quality` reads in the file it wrote
# (a higher mean ratio than the input's, 0 inverted), and with the BLAS on
# one thread, as qdc runs it, the file is byte for byte `qdc optimize`'s.
. "$(dirname "$0")/../lib.sh"
EX=$BIN/examples/optimize
CUBE=$ROOT/tests/data/sample/cube.mesh
if [ ! -x "$EX" ]; then
    fail "example: built" "$EX missing (make all builds it)"
    exit 1
fi

if OPENBLAS_NUM_THREADS=1 "$EX" "$CUBE" "$TMP/ex.mesh" > "$TMP/ex.out" 2> "$TMP/ex.err"; then
    pass "example: optimize the cube through qdc.h"
else
    fail "example: optimize the cube through qdc.h" "$(cat "$TMP/ex.err")"
fi
# "before: ... mean ratio mean M min Q, ..., N inverted"
field() { sed -n "s/^$1:.* mean ratio mean \([-0-9.]*\) min .*, \([0-9]*\) inverted$/\\$2/p" "$TMP/ex.out"; }
b_mean=$(field before 1)
a_mean=$(field after 1)
a_inv=$(field after 2)
"$BIN/qdc" quality "$TMP/ex.mesh" > "$TMP/q.out" 2>&1
q_mean=$(sed -n 's/^mean ratio: mean \([-0-9.]*\) .*/\1/p' "$TMP/q.out")
q_inv=$(sed -n 's/.* tets, \([0-9]*\) inverted,.*/\1/p' "$TMP/q.out")
if [ -n "$b_mean" ] && [ -n "$q_mean" ] && [ "$a_mean" = "$q_mean" ] && [ "$a_inv" = 0 ] &&
    [ "$q_inv" = 0 ] && awk -v a="$q_mean" -v b="$b_mean" 'BEGIN { exit !(a > b + 0.1) }'; then
    pass "example: mean ratio $b_mean -> $q_mean, 0 inverted (qdc quality agrees)"
else
    fail "example: quality" "example said mean $b_mean -> $a_mean, $a_inv inverted; qdc quality: mean $q_mean, $q_inv inverted"
fi
"$BIN/qdc" optimize "$CUBE" "$TMP/cli.mesh" --quiet > /dev/null 2>&1
if cmp -s "$TMP/ex.mesh" "$TMP/cli.mesh"; then
    pass "example: the same bytes as qdc optimize"
else
    fail "example: the same bytes as qdc optimize" "$(cmp "$TMP/ex.mesh" "$TMP/cli.mesh" 2>&1)"
fi
[ "$NFAIL" = 0 ]
