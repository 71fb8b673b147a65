#!/bin/sh
# tests/e2e/tetra.sh - `qdc tetra SURFACE OUT`: the subcommand qdcd runs in a
# child process for surface uploads, so its exit codes are a contract:
# 0 (OUT written: a valid tet mesh), 1 usage, 2 bad surface, 3 TetGen failed,
# each failure with one "qdc: " line on stderr.
. "$(dirname "$0")/../lib.sh"

QDC=$BIN/qdc
for k in cube open selfx; do $PY "$ROOT/tests/server/surfaces.py" stl $k "$TMP/$k.stl"; done

"$QDC" tetra "$TMP/cube.stl" "$TMP/cube.mesh" 2> "$TMP/err"
rc=$?
"$QDC" quality "$TMP/cube.mesh" > "$TMP/q" 2>&1
[ $rc = 0 ] && grep -q ' 0 inverted' "$TMP/q" && grep -q 'qdc: .*cube.mesh: [0-9]* vertices, [0-9]* tets' "$TMP/err" &&
    pass "tetra: closed cube -> Medit, exit 0, $(head -1 "$TMP/q" | cut -d: -f2)" ||
    fail "tetra cube" "exit $rc $(cat "$TMP/err" "$TMP/q")"
"$QDC" tetra "$TMP/cube.stl" "$TMP/fine.qmesh" --tetgen-quality 1.2 --max-volume 0.001 2> "$TMP/err"
rc=$?
n0=$(awk '/^Tetrahedra/ { getline; print; exit }' "$TMP/cube.mesh")
"$QDC" optimize --max-iter 0 --finish off --quiet "$TMP/fine.qmesh" "$TMP/fine.mesh"
n1=$(awk '/^Tetrahedra/ { getline; print; exit }' "$TMP/fine.mesh")
[ $rc = 0 ] && [ "${n1:-0}" -gt $((n0 * 5)) ] &&
    pass "tetra: --max-volume 0.001 --tetgen-quality 1.2 -> QMESH with $n1 tets (default: $n0)" ||
    fail "tetra options" "exit $rc, $n0 -> $n1 tets $(cat "$TMP/err")"
"$QDC" tetra "$TMP/open.stl" "$TMP/x.qmesh" 2> "$TMP/err"
rc=$?
[ $rc = 2 ] && [ "$(wc -l < "$TMP/err")" = 1 ] && grep -q '^qdc: .*open.stl: .*not closed' "$TMP/err" && [ ! -e "$TMP/x.qmesh" ] &&
    pass "tetra: open surface: exit 2, $(cat "$TMP/err")" || fail "tetra open" "exit $rc $(cat "$TMP/err")"
"$QDC" tetra "$TMP/selfx.stl" "$TMP/x.qmesh" > "$TMP/out" 2> "$TMP/err"
rc=$?
[ $rc = 3 ] && grep -q '^qdc: .*intersects itself' "$TMP/err" && [ ! -e "$TMP/x.qmesh" ] &&
    pass "tetra: self-intersecting surface: exit 3, $(grep '^qdc: ' "$TMP/err" | tail -1)" ||
    fail "tetra selfx" "exit $rc $(cat "$TMP/err")"
printf 'solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 zz\n' > "$TMP/bad.stl"
"$QDC" tetra "$TMP/bad.stl" "$TMP/x.qmesh" 2> "$TMP/err"
rc=$?
[ $rc = 2 ] && grep -q '^qdc: .*bad.stl:4' "$TMP/err" && pass "tetra: malformed STL: exit 2 with the line: $(cat "$TMP/err")" ||
    fail "tetra malformed" "exit $rc $(cat "$TMP/err")"
"$QDC" tetra "$TMP/cube.stl" 2> /dev/null
rc1=$?
"$QDC" tetra "$TMP/cube.stl" "$TMP/x.qmesh" --tetgen-quality 0.5 2> /dev/null
rc2=$?
"$QDC" tetra "$TMP/cube.stl" "$TMP/x.qmesh" --bogus 1 2> /dev/null
rc3=$?
[ $rc1 = 1 ] && [ $rc2 = 1 ] && [ $rc3 = 1 ] && pass "tetra: usage errors exit 1" || fail "tetra usage" "$rc1 $rc2 $rc3"
exit $((NFAIL > 0))
