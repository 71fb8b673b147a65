#!/bin/sh
# fewrite.sh - qdc's own Abaqus and Netgen writers: `qdc optimize IN OUT
# --topology flips` of a CalculiX-style .inp (two ELSET regions, S3 boundary
# triangles) and of meshio's .vol (materials, bc numbers) from tests/data/real
# exits 0 and writes OUT in IN's format with the new tets: read by qdc (qdc
# convert to Medit), the vertices are the input's, the boundary triangles with
# their refs and the set of region tags the input's, every triangle a face of
# a tet, the tets not the input's; meshio reads OUT with the same tets,
# triangles and tags (Abaqus: one ELSET REGION_<n> per region, SURFACE_<n> per
# ref; Netgen: netgen:index); Netgen loads the .vol with the same elements and
# materials; `qdc quality` finds 0 inverted. `qdc convert x.mesh y.inp` and
# `y.vol` give the same mesh back. Netgen's own second-order .vol written by
# qdc's writer (through Medit) has Netgen's surface and volume element rows
# (domin/domout, 6- and 10-point node order) exactly.
. "$(dirname "$0")/../lib.sh"
REAL=$ROOT/tests/data/real
if ! "$PY" -c 'import meshio, numpy' 2> /dev/null; then
    echo "ok - fewrite # SKIP python3-meshio/python3-numpy missing"
    exit 0
fi
have_netgen=0
"$PY" -c 'import netgen.meshing' 2> /dev/null && have_netgen=1
cd "$TMP" || exit 1
gzip -dc "$REAL/calculix.inp.gz" > calculix.inp
gzip -dc "$REAL/meshio.vol.gz" > meshio.vol
gzip -dc "$REAL/netgen_p2.vol.gz" > netgen_p2.vol

cat > check.py << 'EOF'
import os, sys
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio, meshio
import numpy as np

inm, outm, out = sys.argv[1:4]
a, b = meditio.read(inm), meditio.read(outm)
key = lambda rows: {tuple(sorted(r)) for r in rows.tolist()}
tri_a = {tuple(sorted(t)) + (r,) for t, r in zip(a.triangles.tolist(), a.triangle_refs.tolist())}
tri_b = {tuple(sorted(t)) + (r,) for t, r in zip(b.triangles.tolist(), b.triangle_refs.tolist())}
faces = set()
for t in b.tets.tolist():
    for k in range(4):
        faces.add(tuple(sorted(t[:k] + t[k + 1:])))
if not np.array_equal(a.vertices.shape, b.vertices.shape):
    sys.exit("vertex count %d, input %d" % (len(b.vertices), len(a.vertices)))
if tri_a != tri_b or len(b.triangles) != len(a.triangles):
    sys.exit("boundary triangles: %d of %d the input's" % (len(tri_a & tri_b), len(tri_a)))
if set(a.tet_refs.tolist()) != set(b.tet_refs.tolist()):
    sys.exit("region tags %s, input %s" % (set(b.tet_refs.tolist()), set(a.tet_refs.tolist())))
if not all(t[:3] in faces for t in tri_b):
    sys.exit("a triangle is no face of a tet")
if key(a.tets) == key(b.tets):
    sys.exit("the tets are the input's: no flip")
# meshio: the same tets, triangles and tags, in qdc's order
m = meshio.read(out)
tets = np.concatenate([c.data for c in m.cells if c.type == "tetra"])
tris = np.concatenate([c.data for c in m.cells if c.type == "triangle"])
if out.endswith(".vol"):  # meshio swaps Netgen's points 1 and 2 of a tet
    tets = tets[:, [0, 2, 1, 3]]
if not (np.array_equal(tets, b.tets) and np.array_equal(tris, b.triangles)):
    sys.exit("meshio: other tets or triangles than qdc reads")
if out.endswith(".vol"):
    idx = m.cell_data["netgen:index"]
    kinds = [c.type for c in m.cells]
    reg = np.concatenate([i for i, k in zip(idx, kinds) if k == "tetra"])
    ref = np.concatenate([i for i, k in zip(idx, kinds) if k == "triangle"])
else:
    reg, ref = np.zeros(len(tets), int), np.zeros(len(tris), int)
    base = {"tetra": 0, "triangle": 0}
    offs = []
    for c in m.cells:
        offs.append(base[c.type] if c.type in base else -1)
        if c.type in base:
            base[c.type] += len(c.data)
    for name, blocks in m.cell_sets.items():
        kind, n = name.split("_")
        for blk, sel in enumerate(blocks):
            if len(sel):
                want = m.cells[blk].type
                dest = reg if want == "tetra" else ref
                if (want == "tetra") != (kind == "REGION"):
                    sys.exit("meshio: set %s holds %s" % (name, want))
                dest[offs[blk] + np.asarray(sel)] = int(n.replace("M", "-"))
if not (np.array_equal(reg, b.tet_refs) and np.array_equal(ref, b.triangle_refs)):
    sys.exit("meshio: other region tags or refs than qdc reads")
print("ok %d tets (input %d), %d triangles, regions %s, refs %s" % (
    len(b.tets), len(a.tets), len(tri_b), sorted(set(b.tet_refs.tolist())),
    sorted(set(b.triangle_refs.tolist()))))
EOF

cat > ngcheck.py << 'EOF'
import os, sys
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio
from netgen.meshing import Mesh
b = meditio.read(sys.argv[2])
m = Mesh()
m.Load(sys.argv[1])
e3, e2 = m.Elements3D(), m.Elements2D()
if len(e3) != len(b.tets) or len(e2) != len(b.triangles):
    sys.exit("netgen: %d and %d elements" % (len(e3), len(e2)))
if [el.index for el in e3] != b.tet_refs.tolist():
    sys.exit("netgen: other materials")
if [[p.nr - 1 for p in el.vertices] for el in e3] != b.tets.tolist():
    sys.exit("netgen: other tets")
print("ok netgen loads %d tets, %d surface elements, the materials" % (len(e3), len(e2)))
EOF

for f in calculix.inp meshio.vol; do
    ext=${f#*.}
    n="fewrite: $f --topology flips"
    if ! "$BIN/qdc" optimize "$f" "out.$ext" --topology flips -q 2> err; then
        fail "$n" "exit $?: $(tail -1 err)"
        continue
    fi
    pass "$n: exit 0"
    "$BIN/qdc" convert "$f" in.mesh -q 2> /dev/null
    "$BIN/qdc" convert "out.$ext" out.mesh -q 2> /dev/null
    verdict "$n: qdc and meshio read it back" "$("$PY" check.py in.mesh out.mesh "out.$ext" 2>&1 | tail -1)"
    q=$("$BIN/qdc" quality "out.$ext" 2>&1 | head -1)
    case $q in
    *" 0 inverted"*) pass "$n: qdc quality: 0 inverted" ;;
    *) fail "$n: qdc quality" "$q" ;;
    esac
    if [ "$ext" = vol ] && [ $have_netgen = 1 ]; then
        verdict "$n: Netgen" "$("$PY" ngcheck.py "out.$ext" out.mesh 2>&1 | tail -1)"
    elif [ "$ext" = vol ]; then
        pass "$n: Netgen # SKIP python3-netgen missing"
    fi
    # qdc convert x.mesh y.EXT, read back: the same mesh
    if "$BIN/qdc" convert out.mesh "y.$ext" -q 2> err && "$BIN/qdc" convert "y.$ext" y.mesh -q 2> err &&
        cmp -s out.mesh y.mesh; then
        pass "fewrite: qdc convert out.mesh y.$ext: the same mesh back"
    else
        fail "fewrite: qdc convert out.mesh y.$ext" "$(tail -1 err)"
    fi
done

# Netgen's own second-order file through Medit and back: its element rows
"$BIN/qdc" convert netgen_p2.vol p2.mesh -q 2> /dev/null
"$BIN/qdc" convert p2.mesh p2.vol -q 2> /dev/null
r=$("$PY" - << 'EOF'
def rows(path, name):
    L = open(path).read().split("\n")
    i = L.index(name)
    return [l.split() for l in L[i + 2:i + 2 + int(L[i + 1])]]
for s in ("surfaceelements", "volumeelements"):
    a, b = rows("netgen_p2.vol", s), rows("p2.vol", s)
    if a != b:
        print("%s: %d of %d rows Netgen's" % (s, sum(x == y for x, y in zip(a, b)), len(a)))
        raise SystemExit
print("ok %d surface and %d volume element rows" % (len(rows("p2.vol", "surfaceelements")),
      len(rows("p2.vol", "volumeelements"))))
EOF
)
verdict "fewrite: netgen_p2.vol written by qdc's writer: Netgen's own element rows" "$r"

[ $NFAIL = 0 ]
