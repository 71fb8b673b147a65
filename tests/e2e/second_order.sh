#!/bin/sh
# second_order.sh - second-order (10-node) tetrahedra: a cylinder and a
# sphere meshed by gmsh with Mesh.ElementOrder = 2, written as MSH 4.1
# ASCII/binary, MSH 2.2, legacy VTK, Medit TetrahedraP2, Abaqus C3D10,
# Nastran 10-node CTETRA (large field) and I-DEAS FE 118 (and VTU through
# qdc convert), and Netgen's own second-order .vol: `qdc optimize` writes each back in its own
# format (spliced: only coordinates change), every element keeps its ten
# nodes and its Jacobian stays positive at every node (the report's
# run.second_order, and the output read again), boundary mid-edge nodes
# stay on the input's curved surface, and the corners' mean ratio ends
# within 0.01 of the same mesh's first-order run. Third and higher orders,
# tetgen -o2 and Medit binary TetrahedraP2 are refused with a message.
. "$(dirname "$0")/../lib.sh"
cd "$TMP" || exit 1
field() { # REPORT KEY: run.second_order.KEY
    "$PY" -c "import json,sys; print(json.load(open(sys.argv[1]))['run']['second_order'][sys.argv[2]])" "$1" "$2"
}
mean_after() {
    "$PY" -c "import json,sys; print(json.load(open(sys.argv[1]))['after']['mean_ratio_mean'])" "$1"
}
# round trip of IN: same format, ten nodes, positive Jacobians, on the surface
roundtrip() { # NAME IN OUT
    if ! "$BIN/qdc" optimize "$2" "$3" --report r.json 2> err; then
        fail "second order: $1" "exit $?: $(tail -2 err)"
        return
    fi
    if grep -q "written by qdc's" err; then
        fail "second order: $1" "not spliced: $(grep "written by" err)"
        return
    fi
    nt=$(field r.json tets)
    bad=$(field r.json jacobian_nonpositive_after)
    dist=$(field r.json boundary_mid_distance)
    if ! "$BIN/qdc" optimize "$3" again."${3##*.}" --max-iter 1 --report r2.json 2> err2; then
        fail "second order: $1" "output not read again: $(tail -2 err2)"
        return
    fi
    nt2=$(field r2.json tets)
    bad2=$(field r2.json jacobian_nonpositive_before)
    mids=$(field r.json mid_nodes)
    mids2=$(field r2.json mid_nodes)
    if [ "$bad" = 0 ] && [ "$bad2" = 0 ] && [ "$nt" = "$nt2" ] && [ "$mids" = "$mids2" ] &&
        [ "$nt" -gt 100 ] && "$PY" -c "import sys; sys.exit(not float(sys.argv[1]) < 1e-9)" "$dist"; then
        pass "second order: $1: $nt 10-node tets, $mids mid-edge nodes, Jacobian > 0, boundary mid-edge nodes $dist from the curved input"
    else
        fail "second order: $1" "tets $nt/$nt2 mids $mids/$mids2 bad $bad/$bad2 dist $dist"
    fi
}
if ! command -v gmsh > /dev/null; then
    pass "second order: gmsh-written files # SKIP gmsh missing"
    exit 0
fi
for shape in cylinder sphere; do
    for order in 1 2; do
        {
            echo 'SetFactory("OpenCASCADE");'
            if [ $shape = cylinder ]; then
                echo 'Cylinder(1) = {0, 0, 0, 0, 0, 1, 0.5};'
            else
                echo 'Sphere(1) = {0, 0, 0, 1};'
            fi
            echo 'Physical Volume("bulk") = {1};'
            echo 'Mesh.CharacteristicLengthMax = 0.3;'
            echo "Mesh.ElementOrder = $order;"
        } > "$shape$order.geo"
    done
    gmsh -3 "${shape}1.geo" -format msh41 -o "${shape}1.msh" > /dev/null 2>&1
    gmsh -3 "${shape}2.geo" -format msh41 -o "${shape}.msh" > /dev/null 2>&1
    gmsh -3 "${shape}2.geo" -format msh41 -bin -o "${shape}_b.msh" > /dev/null 2>&1
    gmsh -3 "${shape}2.geo" -format msh22 -o "${shape}_22.msh" > /dev/null 2>&1
    gmsh -3 "${shape}2.geo" -format vtk -o "${shape}.vtk" > /dev/null 2>&1
    gmsh -3 "${shape}2.geo" -format mesh -o "${shape}.mesh" > /dev/null 2>&1
    gmsh -3 "${shape}2.geo" -format inp -o "${shape}.inp" > /dev/null 2>&1
    gmsh -3 "${shape}2.geo" -string 'Mesh.BdfFieldFormat=2;' -format bdf -o "${shape}.bdf" \
        > /dev/null 2>&1
    gmsh -3 "${shape}2.geo" -format unv -o "${shape}.unv" > /dev/null 2>&1
    "$BIN/qdc" convert "$shape.msh" "$shape.vtu" -q 2> /dev/null
    for f in "$shape.msh" "${shape}_b.msh" "${shape}_22.msh" "$shape.vtk" "$shape.mesh" \
        "$shape.inp" "$shape.vtu" "$shape.bdf" "$shape.unv"; do
        roundtrip "$f" "$f" "out_$f"
    done
    # only coordinates change: the elements of a spliced MSH are the input's
    if cmp -s "$(sed -n '/^\$Elements/,$p' "$shape.msh" | tee a.txt > /dev/null; echo a.txt)" \
        "$(sed -n '/^\$Elements/,$p' "out_$shape.msh" > b.txt; echo b.txt)" && [ -s a.txt ]; then
        pass "second order: $shape.msh: \$Elements unchanged"
    else
        fail "second order: $shape.msh" "\$Elements changed"
    fi
    # the corners' gain against the same mesh's first-order run
    "$BIN/qdc" optimize "${shape}1.msh" o1.msh --report r1.json -q 2> /dev/null
    "$BIN/qdc" optimize "$shape.msh" o2.msh --report r2.json -q 2> /dev/null
    q1=$(mean_after r1.json)
    q2=$(mean_after r2.json)
    if "$PY" -c "import sys; sys.exit(not abs(float(sys.argv[1]) - float(sys.argv[2])) <= 0.01)" "$q1" "$q2"; then
        pass "second order: $shape: corner mean ratio $q2, first-order run $q1"
    else
        fail "second order: $shape" "corner mean ratio $q2, first-order run $q1"
    fi
done
# Netgen's own second-order sphere (tests/data/real), read back by Netgen
gzip -dc "$ROOT/tests/data/real/netgen_p2.vol.gz" > netgen_p2.vol
roundtrip netgen_p2.vol netgen_p2.vol out_netgen_p2.vol
if ! "$PY" -c 'import netgen.meshing' 2> /dev/null; then
    pass "second order: netgen reads out_netgen_p2.vol # SKIP python3-netgen missing"
elif n=$("$PY" -c 'import sys
from netgen.meshing import Mesh
m = Mesh()
m.Load(sys.argv[1])
print(len(m.Elements3D()), len(m.Elements3D()[0].points))' out_netgen_p2.vol 2> /dev/null | tail -1) &&
    [ "$n" = "191 10" ]; then
    pass "second order: netgen reads out_netgen_p2.vol back: 191 elements of 10 points"
else
    fail "second order: netgen reads out_netgen_p2.vol" "got '$n'"
fi
# a mesh with mid-edge nodes is not written by a writer of linear tets
if "$BIN/qdc" convert cylinder.vtk c.xml 2> err; then
    fail "second order: convert to DOLFIN XML" "accepted"
elif grep -q "second-order (10-node) tets are written only as the input" err; then
    pass "second order: convert to DOLFIN XML refused: $(grep -o "dolfin: second-order.*" err | cut -c1-100)"
else
    fail "second order: convert to DOLFIN XML" "$(head -2 err)"
fi
# and qdc optimize says so before the run, which would end with OUT unwritten
"$BIN/qdc" optimize cylinder.vtk o2.xml > /dev/null 2> err
rc=$?
if [ "$rc" = 1 ] && [ ! -e o2.xml ] && grep -q "linear tets).*nothing was done" err &&
    ! grep -q "^global" err; then
    pass "second order: optimize to DOLFIN XML refused before the run (exit 1)"
else
    fail "second order: optimize to DOLFIN XML" "exit $rc: $(tail -1 err)"
fi
# qdc's own Gmsh writer writes type 11: VTK -> MSH 2.2 -> optimized, the
# same corners' result as from the VTK file
"$BIN/qdc" convert cylinder.vtk c22.msh --out-format gmsh22 -q 2> /dev/null
roundtrip "cylinder.vtk -> qdc's MSH 2.2" c22.msh out_c22.msh
if "$BIN/qdc" optimize cylinder.msh t.msh --topology flips 2> err; then
    fail "second order: --topology flips" "accepted"
elif grep -q "use --topology none" err; then
    pass "second order: --topology flips refused"
else
    fail "second order: --topology flips" "$(head -2 err)"
fi
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
sed 's/ElementOrder = 2/ElementOrder = 3/' cylinder2.geo > o3.geo
gmsh -3 o3.geo -format msh41 -o o3.msh > /dev/null 2>&1
refused o3.msh ':[0-9]*:[0-9]*: \$Elements: third-order tetrahedra (Gmsh element type 29, 20 nodes) are not supported'
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
