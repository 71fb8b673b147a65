#!/bin/sh
# medwrite.sh - MED files of qdc's own (qdc-h5 med-new), for a mesh that is
# no splice of a MED file read: its tets changed, or it was read from
# another format. meshio_tri.med (tests/data/real: regions and triangle
# families, node families) optimized with --topology flips into .med: exit
# 0, qdc's writer's note, 0 inverted, the tets changed, and the input's
# vertices (count and refs), boundary triangles with their refs and
# region tags come back (triangles as sets, regions as sets of tags);
# MED-fichier's own reader (mdump, libmed-tools) reads the file with its
# counts and the families named REGION_<n>, SURFACE_<n>, NODE_<n>. Every
# mesh of tests/data/real converted to .med and back is the mesh converted
# straight to Medit (the same text, its held vertices aside: MED has none;
# the MED files through --no-keep-source, so that med-new writes them).
# meshio reads qdc's MED files with the points and tets of qdc's VTK output,
# and its families' group names give qdc's tags. Gmsh reads MED only when
# built with it (the Debian 12 gmsh is not): said as a SKIP.
. "$(dirname "$0")/../lib.sh"
REAL=$ROOT/tests/data/real
if [ ! -x "$BIN/qdc-h5" ]; then
    pass "medwrite: all # SKIP qdc-h5 not built (libhdf5-dev missing)"
    exit 0
fi
cd "$TMP" || exit 1
gzip -dc "$REAL/meshio_tri.med.gz" > tri.med

# --- a MED mesh whose tets changed -----------------------------------------
"$BIN/qdc" optimize tri.med flips.med --topology flips > /dev/null 2> err
rc=$?
if [ "$rc" = 0 ] && grep -q "flips.med: written by qdc's med writer" err &&
    "$BIN/qdc" quality flips.med 2>&1 | grep -q " 0 inverted"; then
    pass "medwrite: meshio_tri.med --topology flips into .med: exit 0, qdc's MED writer, 0 inverted"
else
    fail "medwrite: flips into .med" "exit $rc: $(tail -2 err)"
fi
"$BIN/qdc" convert tri.med in.mesh --quiet 2> err && "$BIN/qdc" convert flips.med out.mesh --quiet 2>> err
verdict "medwrite: flips.med read back" "$("$PY" - in.mesh out.mesh 2>&1 << 'EOF'
import os, sys
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio, numpy as np
a, b = meditio.read(sys.argv[1]), meditio.read(sys.argv[2])
def tris(m):
    return sorted((tuple(sorted(t)), int(r)) for t, r in zip(m.triangles, m.triangle_refs))
why = []
if len(a.vertices) != len(b.vertices) or not np.array_equal(a.vertex_refs, b.vertex_refs):
    why.append("vertex count or refs differ")
if tris(a) != tris(b):
    why.append("boundary triangles differ")
if set(a.tet_refs.tolist()) != set(b.tet_refs.tolist()):
    why.append("region tags %s, not %s" % (sorted(set(b.tet_refs)), sorted(set(a.tet_refs))))
if len(a.tets) == len(b.tets):
    why.append("the tets did not change")
print("ok %d -> %d tets, %d triangles (refs %s), regions %s, vertex refs kept"
      % (len(a.tets), len(b.tets), len(b.triangles), sorted(set(b.triangle_refs.tolist())),
         sorted(set(b.tet_refs.tolist()))) if not why else "; ".join(why))
EOF
)"
if command -v mdump > /dev/null 2>&1; then
    mdump flips.med NODALE FULL_INTERLACE 1 > md 2>&1
    nt=$(awk '/^Tetrahedra/{getline; print; exit}' out.mesh)
    if grep -q "Nombre de noeuds : 356" md && grep -q "MED_TETRA4 : $nt " md &&
        grep -q "MED_TRIA3 : 270" md && grep -q "gro = REGION_M1 " md &&
        grep -q "gro = SURFACE_M12 " md && grep -q "gro = NODE_2 " md &&
        grep -q "FIN DU DUMP" md && ! grep -qi "erreur" md; then
        pass "medwrite: MED-fichier's mdump reads flips.med: 356 nodes, $nt TETRA4, 270 TRIA3, families REGION_M1, SURFACE_M12, NODE_2..."
    else
        fail "medwrite: mdump flips.med" "$(grep -i -m3 "erreur\|Nombre" md)"
    fi
else
    pass "medwrite: MED-fichier's mdump reads flips.med # SKIP mdump missing (libmed-tools)"
fi

# --- every real mesh through MED ----------------------------------------------
strip() { awk '/^RequiredVertices/{skip=1; next} skip && /^[A-Z]/{skip=0} !skip' "$1"; }
n=0
bad=
for f in "$REAL"/*.gz; do
    b=$(basename "${f%.gz}")
    case $b in *.h5 | *.ele | *.cpp | *.sh | *.md) continue ;; esac
    gzip -dc "$f" > "$b"
    case $b in # the .h5 beside an XDMF, the .ele beside a .node
    *.xdmf | *.node) for g in "$REAL/${b%.*}".h5.gz "$REAL/${b%.*}".ele.gz; do
        [ -f "$g" ] && gzip -dc "$g" > "$(basename "${g%.gz}")"
    done ;;
    esac
    keep=
    case $b in *.med) keep=--no-keep-source ;; esac
    if "$BIN/qdc" convert "$b" "m_$b.med" --quiet $keep 2> err &&
        "$BIN/qdc" convert "m_$b.med" "back_$b.mesh" --quiet 2>> err &&
        "$BIN/qdc" convert "$b" "ref_$b.mesh" --quiet --no-keep-source 2>> err &&
        strip "ref_$b.mesh" > a.txt && strip "back_$b.mesh" > b.txt && cmp -s a.txt b.txt; then
        n=$((n + 1))
    else
        bad="$bad $b($(head -1 err | cut -c1-80))"
    fi
done
if [ -z "$bad" ] && [ "$n" -gt 40 ]; then
    pass "medwrite: $n meshes of tests/data/real through .med and back: vertices, tets (10-node too), triangles and tags as written straight to Medit"
else
    fail "medwrite: real meshes through .med" "$n the same;$bad"
fi

# --- meshio reads qdc's MED files ---------------------------------------------
if "$PY" -c 'import meshio, h5py' 2> /dev/null; then
    for b in flips.med m_gmsh41_p2.msh.med m_cgal.mesh.med; do
        "$BIN/qdc" convert "$b" "$b.vtk" --quiet 2> err || fail "medwrite: $b to VTK" "$(head -1 err)"
        verdict "medwrite: meshio reads $b" "$("$PY" - "$b" "$b.vtk" 2>&1 << 'EOF'
import sys
import meshio, numpy as np
m, v = meshio.read(sys.argv[1]), meshio.read(sys.argv[2])
kind = [c.type for c in v.cells if c.type.startswith("tetra")][0]
tets = lambda x: np.concatenate([c.data for c in x.cells if c.type == kind])
why = []
if not np.array_equal(m.points, v.points):
    why.append("points differ")
if not np.array_equal(tets(m), tets(v)):
    why.append("%s cells differ" % kind)
# each tet's family, through its group's name, is qdc's region
fam = dict(zip([c.type for c in m.cells], m.cell_data["cell_tags"]))[kind]
def tag(f):
    if f == 0:
        return 0
    (g,) = [n for n in m.cell_tags[f] if n.startswith("REGION_")]
    n = g[len("REGION_"):]
    return -int(n[1:]) if n[0] == "M" else int(n)
region = np.concatenate([np.ravel(d) for c, d in zip(v.cells, v.cell_data["region"])
                         if c.type == kind]) if "region" in v.cell_data else np.zeros(len(fam), int)
if [tag(f) for f in fam] != region.tolist():
    why.append("families' groups are not the regions")
print("ok %d points, %d %s, regions %s by their families' groups"
      % (len(m.points), len(fam), kind, sorted(set(region.tolist()))) if not why else "; ".join(why))
EOF
)"
    done
else
    pass "medwrite: meshio reads qdc's MED files # SKIP python3-meshio/python3-h5py missing"
fi

# --- Gmsh ------------------------------------------------------------------
if ! command -v gmsh > /dev/null 2>&1; then
    pass "medwrite: Gmsh reads flips.med # SKIP gmsh missing"
elif ! gmsh -info 2>&1 | grep -q "Build options.*\bMed\b"; then
    pass "medwrite: Gmsh reads flips.med # SKIP gmsh built without MED ($(gmsh -info 2>&1 | awk '/^Version/{print $3}'))"
else
    gmsh flips.med -format msh22 -o g.msh -save > gerr 2>&1 || true
    if "$BIN/qdc" convert g.msh g.mesh --quiet 2>> gerr &&
        [ "$(awk '/^Tetrahedra/{getline; print; exit}' g.mesh)" = "$(awk '/^Tetrahedra/{getline; print; exit}' out.mesh)" ]; then
        pass "medwrite: Gmsh reads flips.med with its tets"
    else
        fail "medwrite: Gmsh reads flips.med" "$(tail -2 gerr)"
    fi
fi
exit $((NFAIL > 0))
