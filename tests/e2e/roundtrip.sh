#!/bin/sh
# roundtrip.sh - files come back whole: `qdc optimize IN OUT` with OUT in IN's
# format gives IN with only the coordinates changed, for files written by Gmsh
# (MSH 4.1 ASCII/binary, 4.0, 2.2 ASCII/binary, VTK, Medit), meshio (VTU zlib and ascii, legacy
# VTK binary and ascii, DOLFIN XML, Abaqus, Netgen, Medit binary), a VTK-style appended zlib
# VTU, a CalculiX-style .inp, TetGen (0-based), Gmsh's second-order (10-node) tets in
# MSH 4.1 and Abaqus .inp, Nastran bulk data (Gmsh's and meshio's, free, small and large
# field; 10-node CTETRA), I-DEAS universal (Gmsh; FE 118), Netgen's own second-order .vol
# XDMF with the data inline (meshio: linear and second-order tets) and VTK's
# own writers (XML appended base64 zlib, legacy 5.1 binary), FreeFEM's savemesh
# (Medit ASCII and binary GMF version 2), DOLFIN's own XML and CGAL's Mesh_3
# writers (Medit version 1, each surface facet twice or with patches; VTU raw
# appended and ascii) and mmg3d's own Medit output (ASCII and binary) from
# tests/data/real. tests/tools/splicecheck.py masks the coordinate
# fields with its own parsers and compares the rest byte for byte, then reads
# both files with meshio (same cells, cell/point/field data) and compares the
# coordinates with qdc's own Medit output of the same run.
. "$(dirname "$0")/../lib.sh"
REAL=$ROOT/tests/data/real
CHECK=$ROOT/tests/tools/splicecheck.py
have_meshio=0
"$PY" -c 'import meshio, numpy' 2> /dev/null && have_meshio=1
cd "$TMP" || exit 1
for gz in "$REAL"/*.gz; do
    gzip -dc "$gz" > "$(basename "$gz" .gz)"
done
files="gmsh41.msh gmsh41_bin.msh gmsh22.msh gmsh22_bin.msh gmsh40.msh gmsh.vtk gmsh.mesh meshio_zlib.vtu meshio_ascii.vtu
meshio_bin.vtk meshio_ascii.vtk vtk_appended_zlib.vtu tetgen.node dolfin.xml meshio.inp calculix.inp
meshio.vol meshio.meshb gmsh_msh1.msh gmsh41_p2.msh gmsh_p2.inp gmsh.bdf gmsh_free.bdf gmsh_large.bdf
gmsh.unv meshio_free.bdf meshio_small.nas meshio_large.bdf meshio.xdmf meshio_p2.xdmf gmsh_p2.bdf
gmsh_large_p2.bdf gmsh_p2.unv meshio_p2.bdf netgen_p2.vol vtk_xml.vtu vtk_legacy_bin.vtk
freefem.mesh freefem.meshb dolfin2019.xml getfem.vtu getfem_field.vtk cgal.mesh cgal_patches.mesh
cgal.vtu cgal_ascii.vtu mmg.mesh mmg.meshb"
for f in $files; do
    base=${f%%.*}
    ext=${f#*.}
    # read and written unchanged: the very same bytes
    if "$BIN/qdc" convert "$f" "same.$ext" --quiet 2> err && cmp -s "$f" "same.$ext" &&
        { [ "$ext" != node ] || cmp -s tetgen.ele same.ele; }; then
        pass "roundtrip: $f: qdc convert to .$ext gives the same bytes"
    else
        fail "roundtrip: $f: convert" "$(cmp "$f" "same.$ext" 2>&1) $(head -2 err)"
    fi
    # the reference as qdc writes it: Medit (meshio reads no Medit
    # TetrahedraP2: VTU for second-order tets)
    ref=ref_$base.mesh
    case $f in *_p2.*) ref=ref_$base.vtu ;; esac
    if ! "$BIN/qdc" optimize "$f" "out_$f" --quiet --max-iter 5 2> err ||
        ! "$BIN/qdc" optimize "$f" "$ref" --quiet --max-iter 5 --no-keep-source \
            2>> err; then
        fail "roundtrip: $f: optimize" "$(head -3 err)"
        continue
    fi
    [ -s err ] && fail "roundtrip: $f: no note when the output is spliced" "$(head -2 err)"
    if [ "$ext" = node ]; then
        cmp -s tetgen.ele out_tetgen.ele && pass "roundtrip: $f: the .ele comes back unchanged" ||
            fail "roundtrip: $f: .ele" "$(cmp tetgen.ele out_tetgen.ele 2>&1)"
    fi
    if [ "$f" = gmsh_msh1.msh ]; then # meshio reads no MSH 1: node numbers, all else
        mask() { awk '/^\$NOD/ { n = 1 } /^\$ENDNOD/ { n = 0 } n && NF == 4 { print $1; next } { print }' "$1"; }
        mask "$f" > a.mask
        mask "out_$f" > b.mask
        if cmp -s a.mask b.mask && ! cmp -s "$f" "out_$f"; then
            pass "roundtrip: $f: only the coordinates changed"
        else
            fail "roundtrip: $f: only the coordinates changed" "$(diff a.mask b.mask | head -3)"
        fi
    elif [ $have_meshio = 1 ]; then
        "$PY" "$CHECK" "$f" "out_$f" "$ref" > chk 2>&1 ||
            grep -q '^FAIL - ' chk || fail "roundtrip: $f: splicecheck" "$(tail -2 chk)"
        sed -n 's/^\(ok\|FAIL\) - /\1 - roundtrip: /p' chk
    else
        pass "roundtrip: $f: masked comparison # SKIP python3-meshio or numpy missing"
    fi
done
# meshio 7.0 reads no legacy file of VTK's own writer (METADATA blocks):
# qdc reads the spliced file back, its vertices those of qdc's own Medit output
verts() { awk '/^Vertices/ { f = 1; getline; next } /^[A-Z]/ { f = 0 } f' "$1"; }
if [ -s out_vtk_legacy_bin.vtk ] && "$BIN/qdc" convert out_vtk_legacy_bin.vtk back_vtk.mesh --quiet 2> err &&
    verts ref_vtk_legacy_bin.mesh > rv && [ "$(wc -l < rv)" -gt 356 ] &&
    verts back_vtk.mesh | cmp -s - rv; then
    pass "roundtrip: out_vtk_legacy_bin.vtk read back: vertices equal to qdc's own Medit output"
else
    fail "roundtrip: out_vtk_legacy_bin.vtk read back" "$(head -2 err)"
fi
# Gmsh reads the spliced files back
if command -v gmsh > /dev/null; then
    for f in out_gmsh41.msh out_gmsh41_bin.msh out_gmsh22.msh out_gmsh22_bin.msh \
        out_gmsh40.msh; do
        if gmsh -0 "$f" -o back.msh > log 2>&1 && ! grep -q '^Error' log &&
            grep -q 'material_1' back.msh; then
            pass "roundtrip: gmsh reads $f back (physical names kept)"
        else
            fail "roundtrip: gmsh reads $f" "$(grep Error log | head -2)"
        fi
    done
else
    pass "roundtrip: gmsh reads the outputs # SKIP gmsh missing"
fi

# DOLFIN writes each tet's vertices in increasing order (orientations mixed):
# the same optimization as with the tets as meshio wrote them, and spliced
"$PY" - 2> /dev/null << 'EOF' && have_sorted=1 || have_sorted=0
import meshio, numpy as np
m = meshio.read("dolfin.xml")
meshio.Mesh(m.points, [("tetra", np.sort(m.cells_dict["tetra"], axis=1))]).write("sorted.xml")
EOF
if [ $have_sorted = 1 ]; then
    a=$("$BIN/qdc" optimize dolfin.xml o1.xml --max-iter 5 2>&1 | sed -n 's/.* -> o1.xml: \(.*\) (.*/\1/p')
    b=$("$BIN/qdc" optimize sorted.xml o2.xml --max-iter 5 2>&1 | sed -n 's/.* -> o2.xml: \(.*\) (.*/\1/p')
    if [ -n "$a" ] && [ "$a" = "$b" ] && "$PY" "$CHECK" sorted.xml o2.xml > chk 2>&1; then
        pass "roundtrip: DOLFIN's sorted tets (mixed orientation): same result ($b), spliced"
    else
        fail "roundtrip: DOLFIN sorted tets" "'$a' vs '$b' $(grep FAIL chk | head -2)"
    fi
else
    pass "roundtrip: DOLFIN sorted tets # SKIP python3-meshio missing"
fi

# gzip in, gzip out, the same bytes inside
gzip -c gmsh41_bin.msh > in.msh.gz
if "$BIN/qdc" optimize in.msh.gz out.msh.gz --quiet --max-iter 5 2> err &&
    gzip -t out.msh.gz && gzip -dc out.msh.gz | cmp -s - out_gmsh41_bin.msh; then
    pass "roundtrip: .msh.gz in, .msh.gz out: the spliced binary file, compressed"
else
    fail "roundtrip: gzip" "$(head -2 err)"
fi

# the same for the formats added later: .vol.gz, .xml.gz, .inp.gz, .meshb.gz
for f in meshio.vol dolfin.xml calculix.inp meshio.meshb gmsh22_bin.msh gmsh40.msh; do
    gzip -c "$f" > "in_$f.gz"
    if "$BIN/qdc" optimize "in_$f.gz" "o_$f.gz" --quiet --max-iter 5 2> err && gzip -t "o_$f.gz" &&
        gzip -dc "o_$f.gz" | cmp -s - "out_$f"; then
        pass "roundtrip: $f.gz in, $f.gz out: the spliced file, compressed"
    else
        fail "roundtrip: gzip $f" "$(head -2 err)"
    fi
done

# float32 points stay float32, and the CLI says so
"$PY" - 2> /dev/null << 'EOF' && have_f32=1 || have_f32=0
import meshio, numpy as np
m = meshio.read("meshio_bin.vtk")
meshio.Mesh(m.points.astype(np.float32), m.cells, point_data=m.point_data,
            cell_data=m.cell_data).write("f32.vtk")
EOF
if [ $have_f32 = 1 ]; then
    if "$BIN/qdc" optimize f32.vtk out_f32.vtk --max-iter 5 2> err &&
        grep -q 'out_f32.vtk: coordinates written as float32, as in the input' err &&
        "$BIN/qdc" optimize f32.vtk ref_f32.mesh --quiet --max-iter 5 --no-keep-source &&
        "$PY" "$CHECK" f32.vtk out_f32.vtk ref_f32.mesh > chk 2>&1; then
        pass "roundtrip: float32 VTK points: spliced as float32 (a note says so), equal to qdc's coordinates rounded"
    else
        fail "roundtrip: float32" "$(grep -h 'FAIL\|note\|rror' err chk | head -3)"
    fi
else
    pass "roundtrip: float32 VTK points # SKIP python3-meshio missing"
fi

# Another format, or no source kept: qdc's own writer, and a note says what is kept
"$BIN/qdc" optimize gmsh41.msh conv.vtu --max-iter 5 2> err
grep -q 'conv.vtu: written by qdc.s vtu writer (another format, version or encoding than the input.s): only vertices, tets, triangles and their region tags are kept' err &&
    pass "roundtrip: .msh to .vtu: one note line says what is kept" ||
    fail "roundtrip: conversion note" "$(grep note err | head -2)"
"$BIN/qdc" optimize gmsh41.msh conv22.msh --out-format gmsh22 --max-iter 5 2> err
grep -q 'conv22.msh: written by qdc.s gmsh22 writer' err && ! grep -q PhysicalNames conv22.msh &&
    pass "roundtrip: MSH 4.1 asked as 2.2 (--out-format): converted, with the note" ||
    fail "roundtrip: 4.1 -> 2.2" "$(grep note err | head -2)"
# --reorient rewrites tets: the file cannot be spliced any more, and a note says so
awk '/Tetrahedra/ { t = 1; print; next } t == 1 && NF == 1 { print; t = 2; next }
     t == 2 && NF == 5 { print $2, $1, $3, $4, $5; next } { print }' gmsh.mesh > flip.mesh
"$BIN/qdc" optimize flip.mesh flip_on.mesh --reorient on --max-iter 3 2> err
"$BIN/qdc" optimize flip.mesh flip_off.mesh --max-iter 3 2> err2
grep -q 'flip_on.mesh: written by qdc.s medit writer (the connectivity, regions or tags changed since reading)' err &&
    ! grep -q 'written by' err2 && ! grep -q '^Edges' flip_on.mesh && grep -q 'Edges' flip_off.mesh &&
    pass "roundtrip: --reorient on: qdc's writer with a note (Edges dropped); off: spliced" ||
    fail "roundtrip: --reorient" "$(grep note err err2 | head -2)"
"$BIN/qdc" optimize gmsh41.msh nokeep.msh --no-keep-source --max-iter 5 2> err
! grep -q note err && ! grep -q PhysicalNames nokeep.msh &&
    pass "roundtrip: --no-keep-source: qdc's own MSH writer, no note" ||
    fail "roundtrip: --no-keep-source" "$(head -2 err)"
exit 0
