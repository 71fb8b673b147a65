#!/bin/sh
# periodic.sh - Gmsh $Periodic: the section comes back unchanged (spliced) and
# the periodic node pairs never move apart. Files from tests/data/real (a box
# periodic in x and y, written by gmsh in MSH 4.1 ASCII/binary, 4.0 and 2.2
# ASCII/binary): `qdc optimize` with each boundary mode, then
# tests/tools/periodiccheck.py checks every pair's residual
# x_slave - A x_master to 1e-12 against the input, and splicecheck.py that
# only coordinates changed. A control run on the file with $Periodic renamed
# (so qdc does not see it) must move pairs apart: the check can fail.
. "$(dirname "$0")/../lib.sh"
REAL=$ROOT/tests/data/real
PCHECK=$ROOT/tests/tools/periodiccheck.py
CHECK=$ROOT/tests/tools/splicecheck.py
cd "$TMP" || exit 1
if ! "$PY" -c 'import numpy' 2> /dev/null; then
    pass "periodic: pairs keep their transform # SKIP python3-numpy missing"
    exit 0
fi
have_meshio=0
"$PY" -c 'import meshio' 2> /dev/null && have_meshio=1
for v in 41 41_bin 40 22 22_bin; do
    f=periodic$v.msh
    gzip -dc "$REAL/$f.gz" > "$f"
    for b in slide lsq; do
        if ! "$BIN/qdc" optimize "$f" "out_$b$f" --boundary $b --max-iter 5 2> err; then
            fail "periodic: $f --boundary $b: optimize" "$(head -3 err)"
            continue
        fi
        grep -q "^qdc: gmsh: \$Periodic: [0-9]* links, [0-9]* node pairs: their [0-9]* vertices are held fixed (a pair never moves apart)$" err &&
            pass "periodic: $f --boundary $b: one note line says the periodic vertices are held" ||
            fail "periodic: $f: note" "$(grep -i periodic err | head -2)"
        "$PY" "$PCHECK" "$f" "out_$b$f" > chk 2>&1 || grep -q '^FAIL - ' chk ||
            fail "periodic: $f: periodiccheck" "$(tail -2 chk)"
        sed -n "s/^\(ok\|FAIL\) - periodic: /\1 - periodic: --boundary $b: /p" chk
    done
    if [ $have_meshio = 1 ] && [ $v != 40 ]; then
        "$BIN/qdc" optimize "$f" "ref_$v.mesh" --max-iter 5 --quiet --no-keep-source
        if "$PY" "$CHECK" "$f" "out_slide$f" "ref_$v.mesh" > chk 2>&1; then
            pass "periodic: $f: spliced, \$Periodic and everything but the coordinates unchanged"
        else
            fail "periodic: $f: splicecheck" "$(grep FAIL chk | head -2)"
        fi
    fi
done
# The converted Medit file holds the periodic vertices as RequiredVertices
"$BIN/qdc" convert periodic41.msh conv.mesh --quiet 2> err
n=$(awk '/^RequiredVertices/ { getline; print $1 }' conv.mesh)
[ "$n" = 204 ] && pass "periodic: converted to Medit, the 204 periodic vertices are RequiredVertices" ||
    fail "periodic: RequiredVertices" "'$n' $(head -2 err)"
# Control: $Periodic renamed, qdc does not hold the pairs and they move apart
sed 's/^\$Periodic/$PeriodicX/; s/^\$EndPeriodic/$EndPeriodicX/' periodic41.msh > hidden.msh
"$BIN/qdc" optimize hidden.msh out_hidden.msh --max-iter 5 --quiet 2> err
sed 's/^\$PeriodicX/$Periodic/; s/^\$EndPeriodicX/$EndPeriodic/' out_hidden.msh > out_back.msh
if "$PY" "$PCHECK" periodic41.msh out_back.msh > chk 2>&1; then
    fail "periodic: control" "pairs did not move apart without \$Periodic: the check proves nothing"
elif grep -q 'FAIL - periodic: out_back.msh: every pair keeps its transform' chk; then
    pass "periodic: control: without \$Periodic the pairs move apart and the check says so"
else
    fail "periodic: control" "$(head -3 chk) $(head -2 err)"
fi
exit 0
