#!/bin/sh
# hdf5.sh - MED files (HDF5) through the qdc-h5 child: meshio's MED file from
# tests/data/real read with its families as regions, converted to the same
# bytes, optimized and written back with only the coordinate dataset changed
# (h5py compares every other dataset and attribute; meshio reads the same
# cells and tags and the coordinates of qdc's own Medit output of the run);
# refusals: an HDF5 file that is no MED, qdc-h5 missing, XDMF with HDF5 heavy
# data (not read yet), MED through qdcd's library reader.
. "$(dirname "$0")/../lib.sh"
REAL=$ROOT/tests/data/real
cd "$TMP" || exit 1
if [ ! -x "$BIN/qdc-h5" ]; then
    pass "hdf5: all # SKIP qdc-h5 not built (libhdf5-dev missing)"
    exit 0
fi
for f in meshio.med meshio_h5.h5 meshio_h5.xdmf; do
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
    "$PY" - meshio.med out.med ref.mesh > chk 2>&1 << 'EOF'
import sys
import h5py, meshio, numpy as np
a, b = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
bad = []
def walk(name, obj):
    o = b.get(name)
    if o is None or type(o) != type(obj):
        bad.append("missing " + name)
        return
    if dict(obj.attrs).keys() != dict(o.attrs).keys() or any(
            not np.array_equal(obj.attrs[k], o.attrs[k]) for k in obj.attrs):
        bad.append("attributes of " + name)
    if isinstance(obj, h5py.Dataset) and not name.endswith("/NOE/COO"):
        if obj.dtype != o.dtype or not np.array_equal(obj[()], o[()]):
            bad.append("dataset " + name)
a.visititems(walk)
b.visititems(lambda n, o: None if n in a else bad.append("added " + n))
names = []
a.visit(lambda n: names.append(n) if n.endswith("/NOE/COO") else None)
ca, cb = a[names[0]][()], b[names[0]][()]
print(("ok" if not bad else "FAIL") + " - hdf5: out.med: every dataset and attribute but "
      "NOE/COO as in the input %s" % bad[:3])
print(("ok" if ca.dtype == cb.dtype and ca.shape == cb.shape and np.any(ca != cb) else "FAIL")
      + " - hdf5: out.med: NOE/COO rewritten in place, %d of %d values changed"
      % (int(np.sum(ca != cb)), ca.size))
ma, mb, r = meshio.read(sys.argv[1]), meshio.read(sys.argv[2]), meshio.read(sys.argv[3])
same = all(np.array_equal(x.data, y.data) for x, y in zip(ma.cells, mb.cells)) and \
    all(np.array_equal(x, y) for x, y in zip(ma.cell_data["cell_tags"], mb.cell_data["cell_tags"]))
print(("ok" if same else "FAIL") + " - hdf5: out.med: meshio reads the same cells and tags")
print(("ok" if np.array_equal(mb.points, r.points) else "FAIL")
      + " - hdf5: out.med: coordinates equal to qdc's own ref.mesh")
EOF
    cat chk
    grep -q '^FAIL' chk && NFAIL=$((NFAIL + 1))
    grep -q '^ok' chk || fail "hdf5: h5py check" "$(tail -2 chk)"
else
    pass "hdf5: h5py comparison # SKIP python3-h5py or meshio missing"
fi

check_refused() { # name, command..., expected text in the message
    name=$1
    want=$2
    shift 2
    if "$@" > out 2> err; then
        fail "hdf5: $name" "accepted"
    elif grep -q "$want" err; then
        pass "hdf5: $name: refused ($(head -1 err | cut -c1-90))"
    else
        fail "hdf5: $name" "$(head -2 err)"
    fi
}
check_refused "an HDF5 file that is no MED" "not a MED file" \
    "$BIN/qdc" convert meshio_h5.h5 x.mesh
check_refused "qdc-h5 missing" "cannot run" env QDC_H5=/nonexistent/qdc-h5 \
    "$BIN/qdc" convert meshio.med x.mesh
check_refused "XDMF with HDF5 heavy data" "HDF5" "$BIN/qdc" convert meshio_h5.xdmf x.mesh
check_refused "MED written from another format" "only over the MED file" \
    "$BIN/qdc" convert ref.mesh x.med
exit $NFAIL
