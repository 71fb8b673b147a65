#!/bin/sh
# second_order.sh - second-order tetrahedra are refused with an error naming
# the element type, never read as an empty or a linear mesh: moving their
# corners alone would leave the mid-edge nodes behind. A unit box meshed with
# Mesh.ElementOrder = 2 by gmsh (MSH 4.1 ASCII/binary, 2.2, legacy VTK,
# Medit TetrahedraP2), meshio (VTU with VTK type 24), tetgen -o2 (.ele with
# 10 nodes per tet) and a Medit binary file with a TetrahedraP2 keyword
# built here: `qdc optimize` exits 2 with file:line (or byte) and the message.
. "$(dirname "$0")/../lib.sh"
cd "$TMP" || exit 1
refused() { # FILE PATTERN
    "$BIN/qdc" optimize "$1" out.mesh --max-iter 1 2> err
    rc=$?
    if [ $rc = 2 ] && grep -q "^qdc: $1$2" err && [ ! -e out.mesh ]; then
        pass "second order: $1 refused: $(sed -n 's/^qdc: //p' err | head -1 | cut -c1-150)"
    else
        fail "second order: $1" "exit $rc: $(head -2 err)"
    fi
    rm -f out.mesh
}
if command -v gmsh > /dev/null; then
    cat > o2.geo << 'GEO'
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Physical Volume("bulk") = {1};
Mesh.CharacteristicLengthMax = 0.5;
Mesh.ElementOrder = 2;
GEO
    gmsh -3 o2.geo -format msh41 -o o2_41.msh > /dev/null 2>&1
    gmsh -3 o2.geo -format msh41 -bin -o o2_41b.msh > /dev/null 2>&1
    gmsh -3 o2.geo -format msh22 -o o2_22.msh > /dev/null 2>&1
    gmsh -3 o2.geo -format vtk -o o2.vtk > /dev/null 2>&1
    gmsh -3 o2.geo -format mesh -o o2.mesh > /dev/null 2>&1
    msg='second-order tetrahedra (Gmsh element type 11, 10 nodes) are not supported'
    refused o2_41.msh ":[0-9]*:[0-9]*: \$Elements: $msg"
    refused o2_41b.msh ": byte [0-9]*: \$Elements: $msg"
    refused o2_22.msh ":[0-9]*:[0-9]*: \$Elements: $msg"
    refused o2.vtk ': vtk: cell 0 is a second-order tetrahedron (VTK cell type 24, 10 points): not supported'
    refused o2.mesh ':[0-9]*:[0-9]*: TetrahedraP2: second-order tetrahedra (10 vertices) are not supported'
    if "$PY" -c 'import meshio' 2> /dev/null; then
        "$PY" -c "
import meshio
m = meshio.read('o2_41.msh')
meshio.Mesh(m.points, [('tetra10', m.cells_dict['tetra10'])]).write('o2.vtu')
" > /dev/null 2>&1
        refused o2.vtu ': vtu: cell 0 is a second-order tetrahedron (VTK cell type 24, 10 points)'
    else
        pass "second order: VTU # SKIP python3-meshio missing"
    fi
else
    pass "second order: gmsh-written files # SKIP gmsh missing"
fi
if command -v tetgen > /dev/null; then
    printf '8 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 1 1 0\n5 0 0 1\n6 1 0 1\n7 0 1 1\n8 1 1 1\n6 0\n1\n4 1 2 4 3\n1\n4 5 6 8 7\n1\n4 1 2 6 5\n1\n4 3 4 8 7\n1\n4 1 3 7 5\n1\n4 2 4 8 6\n0\n0\n' > cube.poly
    tetgen -pq -o2 -Q cube.poly > /dev/null 2>&1
    head -1 cube.1.ele | grep -q '^[0-9]* *10 ' &&
        refused cube.1.node ':1:[0-9]*: .ele: second-order tetrahedra (10 nodes per tet) are not supported' ||
        fail "second order: tetgen -o2" "no 10-node .ele: $(head -1 cube.1.ele 2>&1)"
else
    pass "second order: tetgen -o2 # SKIP tetgen missing"
fi
# Medit binary (libMeshb version 2): Dimension, 10 Vertices, one TetrahedraP2
"$PY" - << 'PYEOF'
import struct
v = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (.5, 0, 0), (.5, .5, 0), (0, .5, 0),
     (0, 0, .5), (.5, 0, .5), (0, .5, .5)]
b = struct.pack("<2i", 1, 2)
b += struct.pack("<3i", 3, len(b) + 12, 3)
body = b"".join(struct.pack("<3di", *p, 0) for p in v)
b += struct.pack("<3i", 4, len(b) + 12 + len(body), len(v)) + body
body = struct.pack("<11i", *range(1, 11), 0)
b += struct.pack("<3i", 30, len(b) + 12 + len(body), 1) + body
b += struct.pack("<2i", 54, 0)
open("p2.meshb", "wb").write(b)
PYEOF
refused p2.meshb ': byte [0-9]*: meshb: TetrahedraP2: second-order tetrahedra (10 vertices) are not supported'
exit 0
