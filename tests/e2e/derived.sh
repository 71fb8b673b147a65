#!/bin/sh
# derived.sh - values a file derives from its coordinates follow them in a
# spliced write: Gmsh 4.x $Entities bounding boxes and VTU Points
# RangeMin/RangeMax. `qdc optimize --boundary lsq` moves boundary vertices
# and corners of files from tests/data/real; tests/tools/splicecheck.py
# recomputes the values with its own parsers (boxes: each bound shifted as
# far as the bound of the entity's nodes, closure included, moved; ranges:
# the range of the point norms), requires some to have changed, and checks
# that everything else but the coordinates is byte-identical. Gmsh reads the
# outputs back. With the default (slide) boundary the corners stay: the VTU
# range keeps its original text.
. "$(dirname "$0")/../lib.sh"
REAL=$ROOT/tests/data/real
CHECK=$ROOT/tests/tools/splicecheck.py
cd "$TMP" || exit 1
if ! "$PY" -c 'import meshio, numpy' 2> /dev/null; then
    pass "derived: recomputed values # SKIP python3-meshio or numpy missing"
    exit 0
fi
for f in gmsh41.msh gmsh41_bin.msh gmsh40.msh vtk_appended_zlib.vtu periodic41_bin.msh; do
    gzip -dc "$REAL/$f.gz" > "$f"
    base=${f%%.*}
    if ! "$BIN/qdc" optimize "$f" "lsq_$f" --boundary lsq --quiet --max-iter 5 2> err ||
        ! "$BIN/qdc" optimize "$f" "ref_$base.mesh" --boundary lsq --quiet --max-iter 5 \
            --no-keep-source 2>> err; then
        fail "derived: $f --boundary lsq" "$(head -2 err)"
        continue
    fi
    "$PY" "$CHECK" "$f" "lsq_$f" "ref_$base.mesh" > chk 2>&1
    if grep -q 'recomputed ([1-9][0-9]* changed' chk && ! grep -q '^FAIL' chk; then
        pass "derived: $f --boundary lsq: $(sed -n 's/^ok - lsq_[^:]*: \(.*recomputed.*\)/\1/p' chk), the rest spliced"
    else
        fail "derived: $f --boundary lsq" "$(grep -h 'FAIL\|recomputed' chk | head -2)"
    fi
done
# slide keeps the corners: the range keeps its text
"$BIN/qdc" optimize vtk_appended_zlib.vtu slide.vtu --quiet --max-iter 5 2> err
if grep -a -q 'Name="Points" NumberOfComponents="3" RangeMin="0" RangeMax="1.7320508076"' slide.vtu &&
    ! cmp -s vtk_appended_zlib.vtu slide.vtu; then
    pass "derived: vtk_appended_zlib.vtu, corners held (slide): RangeMin/RangeMax keep their text"
else
    fail "derived: slide range" "$(grep -a -o 'Name="Points"[^/]*' slide.vtu) $(head -2 err)"
fi
if command -v gmsh > /dev/null; then
    for f in lsq_gmsh41.msh lsq_gmsh41_bin.msh lsq_gmsh40.msh; do
        if gmsh -0 "$f" -o back.msh > log 2>&1 && ! grep -q '^Error' log &&
            grep -q 'material_1' back.msh; then
            pass "derived: gmsh reads $f back (physical names kept)"
        else
            fail "derived: gmsh reads $f" "$(grep Error log | head -2)"
        fi
    done
else
    pass "derived: gmsh reads the outputs # SKIP gmsh missing"
fi
exit 0
