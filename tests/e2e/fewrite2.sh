#!/bin/sh
# fewrite2.sh - Gmsh MSH 1, Nastran bulk data and I-DEAS universal files
# optimized with --topology flips are written back in their own format by
# qdc's writers (the tets changed: not spliced). For each file of another
# tool (tests/data/real) the run exits 0, qdc reads the output (0 inverted),
# and Gmsh (python3-gmsh) reads it with the input's boundary triangles (as
# node-tag triples, each a face of a tet) and their tags, and the input's
# region tags: Gmsh's physical groups for MSH 1 and I-DEAS, its entity tags
# (the PIDs) for Nastran. meshio reads the Nastran output with the same PIDs.
# Gmsh 4.8 does not read its own .unv file whole (1098 of 1148 tets of an
# entity, then a crash): the I-DEAS input is compared as qdc read it, written
# by qdc as MSH 2.2 (physical tags the regions and refs).
. "$(dirname "$0")/../lib.sh"

if ! $PY -c 'import gmsh, meshio' 2> /dev/null; then
    echo "ok - fewrite2 # SKIP python3-gmsh/meshio missing"
    exit 0
fi
cat > "$TMP/look.py" <<'EOF'
# look.py IN OUT FIRST: "ok figures" if OUT holds IN's boundary triangles
# (node tags) with their tags, each a face of one of OUT's tets, the same
# region tags, fewer or other tets, and starts with FIRST; else what differs.
import sys, gmsh

def look(path, by_entity):
    gmsh.open(path)
    tags, _, _ = gmsh.model.mesh.getNodes()
    tris, regions, tets = set(), set(), []
    for dim in (2, 3):
        for d, t in gmsh.model.getEntities(dim):
            types, _, nodes = gmsh.model.mesh.getElements(d, t)
            marks = [t] if by_entity else gmsh.model.getPhysicalGroupsForEntity(d, t)
            for ty, nd in zip(types, nodes):
                k = {2: 3, 4: 4}.get(ty)
                if not k or not len(marks):
                    continue
                cells = [tuple(int(x) for x in nd[i:i + k]) for i in range(0, len(nd), k)]
                if k == 3:
                    tris.update((tuple(sorted(c)), int(marks[0])) for c in cells)
                else:
                    tets.extend(cells)
                    regions.update(int(m) for m in marks)
    return sorted(int(x) for x in tags), tris, regions, tets

inp, out, first = sys.argv[1:4]
with open(out) as f:
    head = f.readline().rstrip("\n")
if head.strip() != first.strip():
    print("output starts with %r, not %r" % (head, first))
    sys.exit(0)
nas = out.endswith(".bdf")
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
a = look(inp, nas)
b = look(out, nas)
gmsh.finalize()
faces = set()
for t in b[3]:
    for s in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)):
        faces.add(tuple(sorted(t[i] for i in s)))
if a[0] != b[0]:
    print("node tags differ: %d in, %d out" % (len(a[0]), len(b[0])))
elif a[1] != b[1]:
    print("triangles differ: %d in, %d out, %d in common" % (len(a[1]), len(b[1]), len(a[1] & b[1])))
elif a[2] != b[2]:
    print("region tags differ: %s in, %s out" % (sorted(a[2]), sorted(b[2])))
elif any(t not in faces for t, _ in b[1]):
    print("a triangle is no face of a tet")
elif sorted(map(sorted, a[3])) == sorted(map(sorted, b[3])):
    print("the tets did not change")
else:
    print("ok %d -> %d tets, %d triangles (tags %s), regions %s" % (len(a[3]), len(b[3]),
          len(b[1]), sorted(set(m for _, m in b[1])), sorted(b[2])))
EOF
cat > "$TMP/pid.py" <<'EOF'
# pid.py IN OUT: "ok" if meshio reads the same PID sets per cell type.
import sys, meshio
def pids(path):
    m = meshio.read(path, file_format="nastran")
    r = {}
    for c, p in zip(m.cells, m.cell_data.get("nastran:ref", [])):
        r.setdefault(c.type, set()).update(int(x) for x in p)
    return r
a, b = pids(sys.argv[1]), pids(sys.argv[2])
a.pop("line", None)
print("ok %s" % {k: sorted(v) for k, v in b.items()} if a == b else "meshio: %s in, %s out" % (a, b))
EOF

# IN (tests/data/real, gzipped), OUT's extension, the output's first line
while read -r f ext first; do
    n="fewrite2: $f --topology flips into .$ext"
    gzip -dc "$ROOT/tests/data/real/$f.gz" > "$TMP/$f"
    out="$TMP/out_$f.$ext"
    if ! "$BIN/qdc" optimize "$TMP/$f" "$out" --topology flips -q 2> "$TMP/err"; then
        fail "$n" "exit $?: $(tail -1 "$TMP/err")"
        continue
    fi
    if ! "$BIN/qdc" quality "$out" > "$TMP/q" 2>&1 || ! grep -q ", 0 inverted" "$TMP/q"; then
        fail "$n" "qdc quality: $(head -1 "$TMP/q")"
        continue
    fi
    ref=$TMP/$f
    if [ "$ext" = unv ]; then
        ref=$TMP/ref_$f.msh
        "$BIN/qdc" convert "$TMP/$f" "$ref" --out-format gmsh22 2> "$TMP/err" ||
            { fail "$n" "convert: $(tail -1 "$TMP/err")"; continue; }
    fi
    verdict "$n" "$("$PY" "$TMP/look.py" "$ref" "$out" "$first" 2>&1 | tail -1)"
    if [ "$ext" = bdf ] && grep -q "^BEGIN BULK" "$TMP/$f"; then
        verdict "$n: meshio" "$("$PY" "$TMP/pid.py" "$TMP/$f" "$out" 2>&1 | tail -1)"
    fi
done <<'EOF'
gmsh_msh1.msh msh $NOD
gmsh.bdf bdf $ Nastran bulk data written by qdc
meshio_free.bdf bdf $ Nastran bulk data written by qdc
gmsh.unv unv     -1
EOF
exit $((NFAIL > 0))
