#!/bin/sh
# tests/e2e/formats.sh - cross-format tests against Gmsh itself (python3-gmsh)
# and meshio (python3-meshio): Gmsh writes MSH 4.1/2.2 (ASCII, binary) and VTK
# from a dev mesh with physical groups, qdc reads them and must find the same
# tets with the same tags; qdc writes MSH/VTK/VTU and Gmsh/meshio must read
# them back with the tags. Then surface input through `qdc optimize`.
. "$(dirname "$0")/../lib.sh"

if ! $PY -c 'import gmsh, meshio' 2>/dev/null; then
    echo "ok - formats # SKIP python3-gmsh/meshio missing"
    exit 0
fi
[ -f "$DEV/cube_h0.1_good.mesh.gz" ] || { echo "FAIL - formats: dev meshes missing from $DEV"; exit 1; }

# A converter on the library: qdcconv IN OUT [OUTFORMAT] (meshio_load/meshio_save).
cat > "$TMP/conv.c" <<'EOF'
#include "io/meshio.h"
#include <stdio.h>
int main(int argc, char **argv)
{
    mesh_t *m;
    qdc_error e;

    if (argc < 3)
        return 1;
    if (meshio_load(argv[1], MESHIO_AUTO, &m, &e) != QDC_OK) {
        fprintf(stderr, "%s: %s (%s)\n", argv[1], e.msg, qdc_status_name(e.status));
        return 2;
    }
    if (meshio_save(argv[2], argc > 3 ? meshio_format_from_name(argv[3]) : MESHIO_AUTO, m,
                    &e) != QDC_OK) {
        fprintf(stderr, "%s: %s\n", argv[2], e.msg);
        return 3;
    }
    mesh_free(m);
    return 0;
}
EOF
if ! cc -O1 -I"$ROOT/lib" "$TMP/conv.c" "$BIN/libqdc.a" -lcholmod -lz -lm -fopenmp -ltet -lstdc++ \
        -o "$TMP/conv" 2> "$TMP/cc.log"; then
    fail "formats: build converter" "$(tail -3 "$TMP/cc.log")"
    exit 1
fi
CONV=$TMP/conv
IN=$(devmesh cube_h0.1_good)

# Gmsh writes its formats from the dev mesh, regions by octant as physical groups.
cat > "$TMP/gmsh_write.py" <<'EOF'
import os, sys, json, gmsh
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio
src, out = sys.argv[1], sys.argv[2]
m = meditio.read(src)
xyz = [tuple(p) for p in m.vertices.tolist()]
tets = [tuple(t) for t in (m.tets + 1).tolist()]
nv = len(xyz)
def region(t):
    c = [sum(xyz[v - 1][a] for v in t) / 4 for a in range(3)]
    return 11 + (c[0] > 0) + 2 * (c[1] > 0)
gmsh.initialize(); gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("m")
regs = sorted(set(region(t) for t in tets))
for r in regs:
    gmsh.model.addDiscreteEntity(3, r)
    gmsh.model.addPhysicalGroup(3, [r], 100 + r)
flat = [c for p in xyz for c in p]
gmsh.model.mesh.addNodes(3, regs[0], list(range(1, nv + 1)), flat)
eid = 1
for r in regs:
    sel = [t for t in tets if region(t) == r]
    gmsh.model.mesh.addElementsByType(r, 4, list(range(eid, eid + len(sel))), [v for t in sel for v in t])
    eid += len(sel)
for name, ver, binary in [("a41.msh", 4.1, 0), ("b41.msh", 4.1, 1), ("a22.msh", 2.2, 0), ("b22.msh", 2.2, 1),
                          ("a40.msh", 4.0, 0)]:
    gmsh.option.setNumber("Mesh.MshFileVersion", ver); gmsh.option.setNumber("Mesh.Binary", binary)
    gmsh.write(out + "/" + name)
gmsh.option.setNumber("Mesh.Binary", 0); gmsh.write(out + "/a.vtk")
gmsh.option.setNumber("Mesh.Binary", 1); gmsh.write(out + "/b.vtk")
gmsh.finalize()
json.dump({"tets": sorted([sorted(xyz[v - 1] for v in t), 100 + region(t)] for t in tets)},
          open(out + "/truth.json", "w"))
EOF
check "formats: gmsh writes msh 4.1/4.0/2.2 ascii+binary and vtk" $PY "$TMP/gmsh_write.py" "$IN" "$TMP"

# Same tets (as coordinate sets) and tags in qdc's JSON output as in the truth.
cat > "$TMP/same.py" <<'EOF'
import sys, json
truth = json.load(open(sys.argv[1]))["tets"]
m = json.load(open(sys.argv[2]))
with_tags = sys.argv[3] == "tags"
# Gmsh's ASCII files print 16 digits: coordinates agree to 1e-15 relative
r = lambda x: round(x, 12)
got = sorted([sorted(tuple(map(r, m["vertices"][v])) for v in t),
              m["regions"][k] if with_tags else 0] for k, t in enumerate(m["tets"]))
want = sorted([sorted(tuple(map(r, p)) for p in t[0]), t[1] if with_tags else 0] for t in truth)
if got != want:
    sys.exit("differ: %d vs %d tets, first %s vs %s" % (len(got), len(want), got[:1], want[:1]))
EOF
for f in a41.msh b41.msh a22.msh b22.msh a40.msh; do
    if $CONV "$TMP/$f" "$TMP/$f.json" 2> "$TMP/err"; then
        check "formats: gmsh-written $f read with physical tags" $PY "$TMP/same.py" "$TMP/truth.json" "$TMP/$f.json" tags
    else
        fail "formats: gmsh-written $f read" "$(cat "$TMP/err")"
    fi
done
for f in a.vtk b.vtk; do
    if $CONV "$TMP/$f" "$TMP/$f.json" 2> "$TMP/err"; then
        check "formats: gmsh-written $f read" $PY "$TMP/same.py" "$TMP/truth.json" "$TMP/$f.json" notags
    else
        fail "formats: gmsh-written $f read" "$(cat "$TMP/err")"
    fi
done
# Gmsh itself writes 4.0 in ASCII only; a 4.0 binary header is refused
printf '$MeshFormat\n4 1 8\n\001\000\000\000\n$EndMeshFormat\n' > "$TMP/b40.msh"
if $CONV "$TMP/b40.msh" "$TMP/b40.json" 2> "$TMP/err"; then
    fail "formats: msh 4.0 binary" "accepted, expected a clear refusal"
elif grep -q "b40.msh.*MSH 4.0 binary is not supported (4.0 ASCII, 4.1 ASCII or binary, 2.2 ASCII or binary)" "$TMP/err"; then
    pass "formats: msh 4.0 binary refused with a clear message naming the supported versions"
else
    fail "formats: msh 4.0 binary" "$(cat "$TMP/err")"
fi

# qdc writes; Gmsh and meshio read back, tags included.
$CONV "$TMP/a41.msh" "$TMP/tagged.mesh" 2> /dev/null
for spec in q41.msh:gmsh q41b.msh:gmsh-bin q22.msh:gmsh22 q.vtk:vtk qa.vtk:vtk-ascii q.vtu:vtu qa.vtu:vtu-ascii; do
    f=${spec%%:*}
    check "formats: qdc writes $f" $CONV "$TMP/tagged.mesh" "$TMP/$f" "${spec#*:}"
done
cat > "$TMP/gmsh_read.py" <<'EOF'
import sys, json, gmsh
truth = json.load(open(sys.argv[1]))["tets"]
r = lambda p: tuple(round(x, 12) for x in p)
want = sorted([sorted(r(p) for p in t[0]), t[1]] for t in truth)
gmsh.initialize(); gmsh.option.setNumber("General.Terminal", 0)
for f in sys.argv[2:]:
    gmsh.clear(); gmsh.open(f)
    n, xyz, _ = gmsh.model.mesh.getNodes()
    pos = {int(t): r(xyz[3 * i: 3 * i + 3]) for i, t in enumerate(n)}
    got = []
    for dim, ptag in gmsh.model.getPhysicalGroups(3):
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, ptag):
            types, _, nodes = gmsh.model.mesh.getElements(3, ent)
            for ty, nd in zip(types, nodes):
                assert ty == 4, (f, ty)
                got += [[sorted(pos[v] for v in nd[4 * k: 4 * k + 4].tolist()), ptag] for k in range(len(nd) // 4)]
    if sorted(got) != want:
        sys.exit("%s: gmsh sees %d tagged tets, expected %d" % (f, len(got), len(want)))
gmsh.finalize()
EOF
check "formats: gmsh reads qdc's msh 4.1/4.1-bin/2.2 with physical groups" \
    $PY "$TMP/gmsh_read.py" "$TMP/truth.json" "$TMP/q41.msh" "$TMP/q41b.msh" "$TMP/q22.msh"
cat > "$TMP/meshio_read.py" <<'EOF'
import sys, json, meshio
truth = json.load(open(sys.argv[1]))["tets"]
want = sorted(t[1] for t in truth)
for f in sys.argv[2:]:
    m = meshio.read(f)
    tets = [k for k, c in enumerate(m.cells) if c.type == "tetra"]
    assert len(tets) == 1, f
    reg = m.cell_data["region"][tets[0]]
    if sorted(int(r) for r in reg) != want or len(m.points) == 0:
        sys.exit("%s: regions differ" % f)
EOF
check "formats: meshio reads qdc's vtk/vtu with the region array" \
    $PY "$TMP/meshio_read.py" "$TMP/truth.json" "$TMP/q.vtk" "$TMP/qa.vtk" "$TMP/q.vtu" "$TMP/qa.vtu"
# meshio's own VTU (base64, no compression) and VTK 5.1 back into qdc
cat > "$TMP/meshio_write.py" <<'EOF'
import sys, meshio
m = meshio.read(sys.argv[1])
m.cell_data = {"gmsh:physical": m.cell_data["region"]}
meshio.write(sys.argv[2], m, binary=True, compression=None)
meshio.write(sys.argv[3], m, binary=False)
EOF
if $PY "$TMP/meshio_write.py" "$TMP/q.vtu" "$TMP/m.vtu" "$TMP/m.vtk" 2> /dev/null &&
   $CONV "$TMP/m.vtu" "$TMP/m.vtu.json" && $CONV "$TMP/m.vtk" "$TMP/m.vtk.json"; then
    check "formats: meshio-written vtu (base64) with gmsh:physical" $PY "$TMP/same.py" "$TMP/truth.json" "$TMP/m.vtu.json" tags
    check "formats: meshio-written vtk 5.1 with gmsh:physical" $PY "$TMP/same.py" "$TMP/truth.json" "$TMP/m.vtk.json" tags
else
    fail "formats: meshio-written vtu/vtk" "write or read failed"
fi

# The CLI: every format in and out, tags through optimization.
if "$BIN/qdc" optimize "$TMP/a41.msh" "$TMP/opt.vtu" --quiet --max-iter 2 &&
   $CONV "$TMP/opt.vtu" "$TMP/opt.json"; then
    check "formats: qdc optimize in.msh out.vtu keeps the physical tags" $PY -c '
import json, sys
a = json.load(open(sys.argv[1])); b = json.load(open(sys.argv[2]))
assert sorted(t[1] for t in a["tets"]) == sorted(b["regions"]), "regions differ"' "$TMP/truth.json" "$TMP/opt.json"
else
    fail "formats: qdc optimize in.msh out.vtu" "failed"
fi
"$BIN/qdc" optimize "$IN" "$TMP/o.msh" --quiet --max-iter 1 --format gmsh22 2> "$TMP/err"
[ $? -eq 2 ] && grep -q "expected a \$Section" "$TMP/err" && pass "formats: --format forces the reader" ||
    fail "formats: --format forces the reader" "$(cat "$TMP/err")"

# Surface input: Gmsh writes a sphere as STL, qdc tetrahedralizes and optimizes.
$PY - "$TMP" <<'EOF'
import sys, gmsh
out = sys.argv[1]
gmsh.initialize(); gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.occ.addSphere(0, 0, 0, 1); gmsh.model.occ.synchronize()
gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25); gmsh.model.mesh.generate(2)
gmsh.write(out + "/sphere.stl")
gmsh.option.setNumber("Mesh.Binary", 1); gmsh.write(out + "/sphere_bin.stl")
gmsh.finalize()
lines = open(out + "/sphere.stl").read().split("endfacet")
open(out + "/open.stl", "w").write("endfacet".join(lines[:5] + lines[6:]))
EOF
check "formats: qdc optimize surface.stl out.mesh --tetgen-quality 1.4" \
    "$BIN/qdc" optimize "$TMP/sphere.stl" "$TMP/sphere.mesh" --quiet --tetgen-quality 1.4
check "formats: binary STL with --max-volume, written as VTU" \
    "$BIN/qdc" optimize "$TMP/sphere_bin.stl" "$TMP/sphere.vtu" --quiet --max-volume 0.01
check "formats: the tetrahedralized sphere is a valid mesh" "$BIN/qdc" quality "$TMP/sphere.mesh"
"$BIN/qdc" optimize "$TMP/open.stl" "$TMP/x.mesh" --quiet 2> "$TMP/err"
[ $? -eq 2 ] && grep -q "not closed" "$TMP/err" && pass "formats: open surface: exit 2, clear message" ||
    fail "formats: open surface" "$(cat "$TMP/err")"
exit $((NFAIL > 0))
