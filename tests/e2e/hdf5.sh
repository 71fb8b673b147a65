#!/bin/sh
# hdf5.sh - MED files (HDF5) through the qdc-h5 child: meshio's MED file from
# tests/data/real read with its families as regions, converted to the same
# bytes, optimized and written back with only the coordinate dataset changed
# (h5py compares every other dataset and attribute; meshio reads the same
# cells and tags and the coordinates of qdc's own Medit output of the run);
# another format's mesh written as MED (qdc's own writer, medwrite.sh);
# refusals: an HDF5 file that is no MED, qdc-h5 missing. A .med.gz file and
# MED on standard input are read through a
# private temporary file that no path leaves behind. XDMF whose heavy data is
# in HDF5 (meshio's default): read from the .h5 beside it, written back as
# the .xdmf (only the .h5 name changed) and a copy of the .h5 (only the
# geometry dataset changed); refusals: .h5 missing, a path out of the
# folder, a dataset of another shape than the XDMF says. dolfinx 0.5's own
# XDMF+HDF5 (tests/data/real/dolfinx.*): cell and facet tags read, only the
# geometry dataset changed.
. "$(dirname "$0")/../lib.sh"
REAL=$ROOT/tests/data/real
cd "$TMP" || exit 1
if [ ! -x "$BIN/qdc-h5" ]; then
    pass "hdf5: all # SKIP qdc-h5 not built (libhdf5-dev missing)"
    exit 0
fi
tally() { # FILE NAME: FILE's ok/FAIL lines shown and counted
    cat "$1"
    grep -q '^FAIL' "$1" && NFAIL=$((NFAIL + 1))
    grep -q '^ok' "$1" || fail "$2" "$(tail -2 "$1")"
}
for f in meshio.med meshio_tri.med meshio_h5.h5 meshio_h5.xdmf dolfinx.xdmf dolfinx.h5 \
    dolfin_h5.xdmf dolfin_h5.h5; do
    gzip -dc "$REAL/$f.gz" > "$f"
done

if "$BIN/qdc" convert meshio.med same.med --quiet 2> err && cmp -s meshio.med same.med; then
    pass "hdf5: meshio.med: qdc convert to .med gives the same bytes"
else
    fail "hdf5: convert" "$(head -2 err) $(cmp meshio.med same.med 2>&1)"
fi

if "$BIN/qdc" convert meshio.med regions.json --quiet 2> err &&
    "$PY" -c 'import json, sys
d = json.load(open("regions.json"))
r = sorted(set(d["regions"]))
sys.exit(0 if r == [-2, -1] and len(d["tets"]) == 1228 else 1)' 2>> err; then
    pass "hdf5: meshio.med: 1228 tets, families -1 and -2 as regions"
else
    fail "hdf5: regions" "$(head -2 err)"
fi

if "$BIN/qdc" optimize meshio.med out.med --quiet --max-iter 5 2> err &&
    "$BIN/qdc" optimize meshio.med ref.mesh --quiet --max-iter 5 --no-keep-source 2>> err; then
    pass "hdf5: meshio.med optimized into out.med"
else
    fail "hdf5: optimize" "$(head -3 err)"
fi
if "$PY" -c 'import h5py, meshio' 2> /dev/null; then
    "$PY" "$ROOT/tests/tools/medcoo.py" meshio.med out.med "hdf5: out.med" > chk 2>&1
    "$PY" - meshio.med out.med ref.mesh >> chk 2>&1 << 'EOF'
import sys
import meshio, numpy as np
ma, mb, r = meshio.read(sys.argv[1]), meshio.read(sys.argv[2]), meshio.read(sys.argv[3])
same = all(np.array_equal(x.data, y.data) for x, y in zip(ma.cells, mb.cells)) and \
    all(np.array_equal(x, y) for x, y in zip(ma.cell_data["cell_tags"], mb.cell_data["cell_tags"]))
print(("ok" if same else "FAIL") + " - hdf5: out.med: meshio reads the same cells and tags")
print(("ok" if np.array_equal(mb.points, r.points) else "FAIL")
      + " - hdf5: out.med: coordinates equal to qdc's own ref.mesh")
EOF
    tally chk "hdf5: h5py check"
else
    pass "hdf5: h5py comparison # SKIP python3-h5py or meshio missing"
fi

# MED with boundary triangles (TR3, families -11 and -12) and node families
# (NOE/FAM): the triangles read with their families as refs, the node
# families as vertex refs; the copy written back differs only in NOE/COO
if "$BIN/qdc" convert meshio_tri.med tri.mesh --quiet 2> err &&
    [ "$(awk '/^Triangles/{getline; print; exit}' tri.mesh)" = 270 ] &&
    [ "$(awk '/^Triangles/{f=1; getline; next} f && NF == 4 {print $4} /^End/{f=0}' tri.mesh |
        sort | uniq -c | awk '{printf "%s:%s ", $2, $1}')" = "-11:90 -12:180 " ] &&
    [ "$(awk '/^Vertices/{f=1; getline; next} f && NF == 4 {print $4} /^Tetra/{f=0}' tri.mesh |
        sort | uniq -c | awk '{printf "%s:%s ", $2, $1}')" = "0:196 1:58 2:102 " ]; then
    pass "hdf5: meshio_tri.med: 270 boundary triangles, families -11 and -12 as refs; node families 0/1/2 as vertex refs"
else
    fail "hdf5: MED triangles and node families" "$(head -2 err) $(grep -A1 -E '^(Vertices|Triangles)' tri.mesh)"
fi
if "$BIN/qdc" convert meshio_tri.med same_tri.med --quiet 2> err && cmp -s meshio_tri.med same_tri.med &&
    "$BIN/qdc" optimize meshio_tri.med out_tri.med --quiet --max-iter 5 2>> err; then
    pass "hdf5: meshio_tri.med: converted to the same bytes, optimized into out_tri.med"
else
    fail "hdf5: meshio_tri.med round trip" "$(head -3 err)"
fi
if "$PY" -c 'import h5py' 2> /dev/null; then
    "$PY" "$ROOT/tests/tools/medcoo.py" meshio_tri.med out_tri.med "hdf5: out_tri.med" > chk 2>&1
    tally chk "hdf5: h5py check of out_tri.med"
else
    pass "hdf5: h5py comparison of out_tri.med # SKIP python3-h5py missing"
fi

# dolfinx's form (made here with h5py from meshio_h5.h5): the mesh's
# Geometry and Topology in HDF5 and no cell attribute; a MeshTags grid after
# it (an xi:include of the Geometry) lists every tet, corners rolled and rows
# reversed, with a 2-D (N x 1) dataset of values 100 + the physical tag: read
# as the regions; a facet tags grid before it (the boundary triangles, values
# 1000 + k % 3): the boundary triangles with those refs (as Medit); written
# back, only the geometry dataset changes
if "$PY" - meshio_h5.h5 2> err << 'EOF'; then
import sys
import h5py, numpy as np
src = h5py.File(sys.argv[1], "r")
pts, tets, phys = src["data0"][()], src["data1"][()], src["data4"][()]
n = len(tets)
with h5py.File("dx.h5", "w") as f:
    f["Mesh/mesh/geometry"] = pts
    f["Mesh/mesh/topology"] = tets.astype(np.int64)
    f["MeshTags/cells/topology"] = np.roll(tets, 1, axis=1)[::-1].astype(np.int64)
    f["MeshTags/cells/Values"] = (100 + phys[::-1]).astype(np.int32).reshape(-1, 1)
    faces = np.sort(tets[:, [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]].reshape(-1, 3), axis=1)
    u, cnt = np.unique(faces, axis=0, return_counts=True)
    tris = u[cnt == 1]
    f["MeshTags/facets/topology"] = tris.astype(np.int64)
    f["MeshTags/facets/Values"] = (1000 + np.arange(len(tris)) % 3).astype(np.int32)
np.save("dx_tris.npy", np.c_[tris + 1, 1000 + np.arange(len(tris)) % 3])
item = '<DataItem Dimensions="%s" NumberType="%s" Format="HDF">dx.h5:/%s</DataItem>'
topo = '<Topology TopologyType="Tetrahedron" NumberOfElements="%d" NodesPerElement="4">' % n
open("dx.xdmf", "w").write(
    '<?xml version="1.0"?>\n<Xdmf Version="3.0" xmlns:xi="http://www.w3.org/2001/XInclude">'
    '<Domain><Grid Name="mesh" GridType="Uniform">' + topo
    + item % ("%d 4" % n, "Int", "Mesh/mesh/topology") + '</Topology>'
    '<Geometry GeometryType="XYZ">' + item % ("%d 3" % len(pts), "Float", "Mesh/mesh/geometry")
    + '</Geometry></Grid><Grid Name="facets" GridType="Uniform">'
    '<xi:include xpointer="xpointer(/Xdmf/Domain/Grid[@GridType=\'Uniform\'][1]/Geometry)" />'
    '<Topology TopologyType="Triangle" NumberOfElements="%d" NodesPerElement="3">' % len(tris)
    + item % ("%d 3" % len(tris), "Int", "MeshTags/facets/topology") + '</Topology>'
    '<Attribute Name="facets" AttributeType="Scalar" Center="Cell">'
    + item % ("%d" % len(tris), "Int", "MeshTags/facets/Values") + '</Attribute></Grid>'
    '<Grid Name="cells" GridType="Uniform">'
    '<xi:include xpointer="xpointer(/Xdmf/Domain/Grid[@GridType=\'Uniform\'][1]/Geometry)" />'
    + topo + item % ("%d 4" % n, "Int", "MeshTags/cells/topology") + '</Topology>'
    '<Attribute Name="cells" AttributeType="Scalar" Center="Cell">'
    + item % ("%d 1" % n, "Int", "MeshTags/cells/Values") + '</Attribute></Grid></Domain></Xdmf>\n')
np.save("dx_want.npy", 100 + phys)
EOF
    if "$BIN/qdc" convert dx.xdmf dx.json --quiet 2> err && "$PY" -c 'import json, sys, numpy as np
r = np.array(json.load(open("dx.json"))["regions"])
sys.exit(0 if np.array_equal(r, np.load("dx_want.npy")) else 1)' 2>> err; then
        pass "hdf5: dolfinx MeshTags in HDF5 (tets reordered, N x 1 values): read as the regions"
    else
        fail "hdf5: dolfinx MeshTags in HDF5" "$(head -3 err)"
    fi
    if "$BIN/qdc" convert dx.xdmf dx.mesh --quiet 2> err && "$PY" -c 'import sys, numpy as np
w = open("dx.mesh").read().split()
i = w.index("Triangles")
n = int(w[i + 1])
got = np.array(w[i + 2:i + 2 + 4 * n], dtype=int).reshape(-1, 4)
want = np.load("dx_tris.npy")
print(n, "triangles, refs", sorted(set(got[:, 3])))
sys.exit(0 if np.array_equal(got, want) and n > 0 else 1)' > tris.out 2>> err; then
        pass "hdf5: dolfinx facet tags in HDF5 (before the cell tags): $(cat tris.out) as Medit's Triangles"
    else
        fail "hdf5: dolfinx facet tags in HDF5" "$(cat tris.out) $(head -3 err)"
    fi
    if "$BIN/qdc" optimize dx.xdmf dxout.xdmf --quiet --max-iter 3 2> err &&
        sed 's/dx\.h5:/dxout.h5:/g' dx.xdmf | cmp -s - dxout.xdmf; then
        "$PY" "$ROOT/tests/tools/medcoo.py" dx.h5 dxout.h5 "hdf5: dxout.h5" Mesh/mesh/geometry > chk 2>&1
        tally chk "hdf5: h5py check of dxout.h5"
    else
        fail "hdf5: dolfinx XDMF optimized" "$(head -3 err)"
    fi
else
    pass "hdf5: dolfinx MeshTags in HDF5 # SKIP python3-h5py missing ($(tail -1 err))"
fi

# dolfinx 0.5's own file (tests/data/real/dolfinx.xdmf and .h5: write_mesh,
# then write_meshtags of cell tags and of facet tags, whose values carry no
# NumberType): cell tags 1 and 2 as the regions, the 432 facet tags (10, 11,
# 12) as boundary triangles; optimized, the XML changes only in the .h5
# name and the .h5 only in Mesh/mesh/geometry
if "$BIN/qdc" convert dolfinx.xdmf dfx.mesh --quiet 2> err &&
    [ "$(awk '/^Tetrahedra/{f=1; getline; next} f && NF == 5 {print $5} /^End/{f=0}' dfx.mesh |
        sort | uniq -c | awk '{printf "%s:%s ", $2, $1}')" = "1:1147 2:149 " ] &&
    [ "$(awk '/^Triangles/{f=1; getline; next} f && NF == 4 {print $4} /^Tetra/{f=0}' dfx.mesh |
        sort | uniq -c | awk '{printf "%s:%s ", $2, $1}')" = "10:72 11:72 12:288 " ]; then
    pass "hdf5: dolfinx.xdmf (dolfinx 0.5): cell tags 1/2 as regions, 432 facet tags 10/11/12 as refs"
else
    fail "hdf5: dolfinx.xdmf tags" "$(head -2 err) $(grep -A1 -E '^(Tetrahedra|Triangles)' dfx.mesh)"
fi
# pair_roundtrip BASE OUT WHO: BASE.xdmf converted to OUT's name gives the
# same .h5; optimized into OUT.xdmf, the XML changes only in the .h5 name
# and the .h5 only in Mesh/mesh/geometry
pair_roundtrip() {
    if "$BIN/qdc" convert "$1.xdmf" "$2s.xdmf" --quiet 2> err && cmp -s "$1.h5" "$2s.h5" &&
        "$BIN/qdc" optimize "$1.xdmf" "$2.xdmf" --quiet --max-iter 5 2>> err &&
        sed "s/$1\\.h5:/$2.h5:/g" "$1.xdmf" | cmp -s - "$2.xdmf"; then
        if "$PY" -c 'import h5py' 2> /dev/null; then
            "$PY" "$ROOT/tests/tools/medcoo.py" "$1.h5" "$2.h5" "hdf5: $2.h5 ($3)" \
                Mesh/mesh/geometry > chk 2>&1
            tally chk "hdf5: h5py check of $2.h5"
        else
            pass "hdf5: $2.h5 compared # SKIP python3-h5py missing"
        fi
    else
        fail "hdf5: $1.xdmf round trip" "$(head -3 err)"
    fi
}
pair_roundtrip dolfinx dfxout dolfinx
# DOLFIN's own XDMF+HDF5 (tests/data/real/dolfin_h5.*: the mesh and a
# MeshFunction)
pair_roundtrip dolfin_h5 dfo DOLFIN
# Its MeshFunction (uint64, no NumberType: qdc-h5 reports the dataset's
# class) is the region: 148 tets of 2, 1148 of 1; the same values as float64
# (a DG0 Function's look the same in the XML) are no region, the file read
tetrefs() { awk '/^Tetrahedra/{f=1; getline; next} f && NF == 5 {print $5} /^End/{f=0}' "$1" |
    sort | uniq -c | awk '{printf "%s:%s ", $2, $1}'; }
if "$BIN/qdc" convert dolfin_h5.xdmf dfr.mesh --quiet 2> err &&
    [ "$(tetrefs dfr.mesh)" = "1:1148 2:148 " ]; then
    pass "hdf5: dolfin_h5.xdmf (DOLFIN 2019): its uint64 MeshFunction with no NumberType as the regions"
else
    fail "hdf5: DOLFIN MeshFunction as regions" "$(head -2 err) $(tetrefs dfr.mesh)"
fi
if "$PY" -c 'import h5py' 2> /dev/null; then
    mkdir -p dff && sed 's/dolfin_h5\.h5:/f.h5:/g' dolfin_h5.xdmf > dff/f.xdmf &&
        "$PY" -c 'import h5py, numpy as np, shutil, sys
shutil.copy("dolfin_h5.h5", "dff/f.h5")
with h5py.File("dff/f.h5", "r+") as f:
    v = f["MeshFunction/0/values"][...].astype(np.float64) + 0.5
    del f["MeshFunction/0/values"]
    f["MeshFunction/0/values"] = v'
    if "$BIN/qdc" convert dff/f.xdmf dff.mesh --quiet 2> err && [ "$(tetrefs dff.mesh)" = "0:1296 " ]; then
        pass "hdf5: the same MeshFunction as float64: no region, the file read"
    else
        fail "hdf5: float MeshFunction" "$(head -2 err) $(tetrefs dff.mesh)"
    fi
else
    pass "hdf5: float MeshFunction # SKIP python3-h5py missing"
fi

want_rc= # the exit status a refusal must have, if set
check_refused() { # name, expected text in the message, command...
    name=$1
    want=$2
    shift 2
    "$@" > out 2> err
    rc=$?
    if [ $rc = 0 ]; then
        fail "hdf5: $name" "accepted"
    elif grep -q "$want" err && [ "${want_rc:-$rc}" = $rc ]; then
        pass "hdf5: $name: refused, exit $rc ($(grep -m1 "$want" err | cut -c1-100))"
    else
        fail "hdf5: $name" "exit $rc: $(head -2 err)"
    fi
}
check_refused "an HDF5 file that is no MED" "not a MED file" \
    "$BIN/qdc" convert meshio_h5.h5 x.mesh
check_refused "qdc-h5 missing" "cannot run" env QDC_H5=/nonexistent/qdc-h5 \
    "$BIN/qdc" convert meshio.med x.mesh
# another format's mesh is written as a MED file of qdc's own (qdc-h5
# med-new; tests/e2e/medwrite.sh): read back the same
if "$BIN/qdc" convert ref.mesh x.med --quiet 2> err && "$BIN/qdc" convert x.med x.mesh --quiet 2>> err &&
    "$BIN/qdc" convert ref.mesh y.mesh --quiet --no-keep-source 2>> err && cmp -s x.mesh y.mesh; then
    pass "hdf5: MED written from another format by qdc's MED writer, read back the same"
else
    fail "hdf5: MED from another format" "$(head -2 err)"
fi

# --- .med.gz and standard input ------------------------------------------
mkdir t
gzip -c meshio.med > meshio.med.gz
cp meshio.med.gz blob
gzip -c meshio.med.gz > twice.med.gz
head -c $(($(wc -c < meshio.med.gz) / 2)) meshio.med.gz > cut.med.gz
for how in named sniffed stdin stdin-gz; do
    case $how in
    named) set -- "$BIN/qdc" convert meshio.med.gz gz_$how.med --quiet ;;
    sniffed) set -- "$BIN/qdc" convert blob gz_$how.med --quiet ;;
    stdin) set -- sh -c '"$0" convert - gz_stdin.med --quiet < meshio.med' "$BIN/qdc" ;;
    stdin-gz) set -- sh -c '"$0" convert - gz_stdin-gz.med --quiet < meshio.med.gz' "$BIN/qdc" ;;
    esac
    if TMPDIR=$TMP/t "$@" 2> err && cmp -s meshio.med gz_$how.med &&
        [ -z "$(ls -A t)" ]; then
        pass "hdf5: meshio.med.gz ($how): read, written back as the same bytes, no temporary file left"
    else
        fail "hdf5: .med.gz $how" "$(head -2 err) $(cmp meshio.med gz_$how.med 2>&1) $(ls t)"
    fi
done
if TMPDIR=$TMP/t "$BIN/qdc" optimize meshio.med.gz gz_opt.med --quiet --max-iter 5 2> err &&
    cmp -s gz_opt.med out.med && [ -z "$(ls -A t)" ]; then
    pass "hdf5: meshio.med.gz optimized: the same file as from meshio.med"
else
    fail "hdf5: .med.gz optimize" "$(head -2 err) $(cmp gz_opt.med out.med 2>&1)"
fi
for f in twice cut; do
    TMPDIR=$TMP/t "$BIN/qdc" convert $f.med.gz x.med > out 2> err
    rc=$?
    if [ $rc = 2 ] && [ -z "$(ls -A t)" ] && grep -q "gzip" err; then
        pass "hdf5: $f.med.gz refused, exit 2, no temporary file left ($(head -1 err | cut -c1-70))"
    else
        fail "hdf5: $f.med.gz" "exit $rc: $(head -2 err) $(ls t)"
    fi
done
check_refused "MED written gzip-compressed" "uncompressed" \
    "$BIN/qdc" convert meshio.med x.med.gz

# --- XDMF with HDF5 heavy data --------------------------------------------
if "$BIN/qdc" convert meshio_h5.xdmf h5regions.json --quiet 2> err &&
    "$PY" -c 'import json, sys
d = json.load(open("h5regions.json"))
sys.exit(0 if len(d["tets"]) == 1228 and d.get("regions") else 1)' 2>> err; then
    pass "hdf5: meshio_h5.xdmf read from its .h5: 1228 tets, gmsh:physical as regions"
else
    fail "hdf5: xdmf+h5 read" "$(head -3 err)"
fi
if "$BIN/qdc" optimize meshio_h5.xdmf xout.xdmf --quiet --max-iter 5 2> err &&
    "$BIN/qdc" optimize meshio_h5.xdmf xref.mesh --quiet --max-iter 5 --no-keep-source 2>> err &&
    [ -f xout.h5 ]; then
    pass "hdf5: meshio_h5.xdmf optimized into xout.xdmf and xout.h5"
else
    fail "hdf5: xdmf+h5 optimize" "$(head -3 err)"
fi
if sed 's/meshio_h5\.h5:/xout.h5:/g' meshio_h5.xdmf | cmp -s - xout.xdmf; then
    pass "hdf5: xout.xdmf: the input's XML with only the .h5 name changed"
else
    fail "hdf5: xout.xdmf" "$(sed 's/meshio_h5\.h5:/xout.h5:/g' meshio_h5.xdmf | cmp - xout.xdmf 2>&1)"
fi
if "$PY" -c 'import h5py, meshio' 2> /dev/null; then
    "$PY" - meshio_h5.h5 xout.h5 meshio_h5.xdmf xout.xdmf xref.mesh > chk 2>&1 << 'EOF'
import sys
import h5py, meshio, numpy as np
a, b = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
same, diff = [], []
for n in a:
    x, y = a[n][()], b[n][()]
    (same if x.dtype == y.dtype and x.shape == y.shape and np.array_equal(x, y) else diff).append(n)
ok = sorted(b) == sorted(a) and diff == ["data0"]
print(("ok" if ok else "FAIL") + " - hdf5: xout.h5: only the coordinates (data0) changed "
      "(%d datasets the same, changed: %s)" % (len(same), diff))
c = a["data0"][()] - b["data0"][()]
print(("ok" if b["data0"].dtype == a["data0"].dtype and np.any(c != 0) else "FAIL")
      + " - hdf5: xout.h5: data0 rewritten, %d of %d values moved" % (int(np.sum(c != 0)), c.size))
ma, mb, r = meshio.read(sys.argv[3]), meshio.read(sys.argv[4]), meshio.read(sys.argv[5])
tags = all(np.array_equal(ma.cell_data[k][0], mb.cell_data[k][0]) for k in ma.cell_data)
print(("ok" if np.array_equal(ma.cells[0].data, mb.cells[0].data) and tags else "FAIL")
      + " - hdf5: meshio reads xout.xdmf with the same cells and cell data")
print(("ok" if np.array_equal(mb.points, r.points) else "FAIL")
      + " - hdf5: xout.xdmf: coordinates equal to qdc's own xref.mesh")
EOF
    tally chk "hdf5: h5py check of xout.h5"
else
    pass "hdf5: h5py comparison of xout.h5 # SKIP python3-h5py or meshio missing"
fi
if "$BIN/qdc" convert meshio_h5.xdmf xsame.xdmf --quiet 2> err && cmp -s meshio_h5.h5 xsame.h5; then
    pass "hdf5: meshio_h5.xdmf converted to .xdmf: the .h5 copy has the same bytes"
else
    fail "hdf5: xdmf+h5 convert" "$(head -2 err) $(cmp meshio_h5.h5 xsame.h5 2>&1)"
fi

want_rc=2
mkdir lone sub
cp meshio_h5.xdmf lone/
check_refused "XDMF whose .h5 is missing" "No such file" "$BIN/qdc" convert lone/meshio_h5.xdmf x.mesh
sed 's#meshio_h5\.h5:#../meshio_h5.h5:#g' meshio_h5.xdmf > sub/up.xdmf
check_refused "XDMF naming ../x.h5" "outside the .xdmf file's folder" \
    "$BIN/qdc" convert sub/up.xdmf x.mesh
sed "s#meshio_h5\.h5:#$TMP/meshio_h5.h5:#g" meshio_h5.xdmf > abs.xdmf
check_refused "XDMF naming an absolute path" "absolute path" "$BIN/qdc" convert abs.xdmf x.mesh
sed 's#Dimensions="356 3"#Dimensions="355 3"#' meshio_h5.xdmf > shape.xdmf
check_refused "XDMF with a dataset of another shape" "shape 356 x 3, where the XDMF says 355 x 3" \
    "$BIN/qdc" convert shape.xdmf x.mesh
check_refused "XDMF with HDF5 data on standard input" "beside the .xdmf" \
    sh -c '"$0" convert - x.mesh --in-format xdmf < meshio_h5.xdmf' "$BIN/qdc"
exit $NFAIL
