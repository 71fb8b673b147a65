#!/bin/sh
# pdata.sh - point data (VTK POINT_DATA, VTU <PointData>, Gmsh $NodeData)
# through --topology flips and full and qdc convert: a .vtu, a .vtk and a
# binary MSH 2.2 of
# the dev bunny (low quality, 10k tets: full inserts vertices on it) with a
# linear field f = x + 2y + 3z, a 3-component field and an integer array
# (each vertex's input index). flips keeps every vertex in its order: every
# array equal, value for value. full: the vertices kept (each named by its
# index in the integer array, the prefix of the output that increases)
# have their input values bit for bit; a new vertex's f lies within the
# input's range (its exactness is test_pdata's: the interpolation of a
# linear field is exact) and the note says at how many vertices it was
# interpolated. Converting to Gmsh and back keeps the arrays; to Medit the
# note says they are dropped.
. "$(dirname "$0")/../lib.sh"

if ! "$PY" -c 'import meshio, numpy' 2> /dev/null; then
    echo "ok - pdata # SKIP python3 meshio/numpy missing"
    exit 0
fi
BUN=$(devmesh bunny_low_10k)
"$PY" - "$BUN" "$TMP" << 'PY' 2> "$TMP/mk.err" || { fail "pdata: inputs" "$(tail -1 "$TMP/mk.err")"; exit 1; }
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
p = m.points
tets = [c.data for c in m.cells if c.type == "tetra"][0]
pd = {"f": p[:, 0] + 2 * p[:, 1] + 3 * p[:, 2], "vec": p * 0.5 - 1.0,
      "id": np.arange(len(p), dtype=np.int32)}
out = meshio.Mesh(p, [("tetra", tets)], point_data=pd)
out.write(sys.argv[2] + "/in.vtu")
out.write(sys.argv[2] + "/in.vtk")
out.write(sys.argv[2] + "/in.msh", file_format="gmsh22", binary=True)
PY

# cmp IN OUT MODE: "ok ..." or why not
cmp_pd() {
    "$PY" - "$1" "$2" "$3" << 'PY'
import sys, meshio, numpy as np
a, b, mode = meshio.read(sys.argv[1]), meshio.read(sys.argv[2]), sys.argv[3]
pa, pb = a.point_data, b.point_data
missing = [k for k in ("f", "vec", "id") if k not in pb]
if missing:
    print("arrays missing:", missing, "have", sorted(pb)); sys.exit()
idb = np.asarray(pb["id"]).astype(np.int64)
if mode == "flips":
    bad = [k for k in ("f", "vec", "id") if not np.array_equal(np.asarray(pa[k]), np.asarray(pb[k]))]
    print("differ:", bad) if bad or len(b.points) != len(a.points) else \
        print("ok %d vertices, f, vec and id equal value for value" % len(b.points))
    sys.exit()
d = np.diff(idb)
kept = int(np.argmax(d <= 0)) + 1 if (d <= 0).any() else len(idb)
new = len(idb) - kept
ok = all(np.array_equal(np.asarray(pb[k])[:kept], np.asarray(pa[k])[idb[:kept]])
         for k in ("f", "vec"))
f = np.asarray(pa["f"]); fn = np.asarray(pb["f"])[kept:]
inr = bool(np.all((fn >= f.min()) & (fn <= f.max())))
vid = bool(np.all((idb >= 0) & (idb < len(a.points))))
if ok and inr and vid and new > 0:
    print("ok %d kept vertices equal bit for bit, %d new with f in [%.4g, %.4g]" %
          (kept, new, f.min(), f.max()))
else:
    print("kept equal %s, new %d in range %s, ids valid %s" % (ok, new, inr, vid))
PY
}

for in in in.vtu in.vtk in.msh; do
    ext=${in#in.}
    for mode in flips full; do
        out=$TMP/$mode.$ext
        if ! "$BIN/qdc" optimize "$TMP/$in" "$out" --topology $mode > "$TMP/$mode.log" 2>&1; then
            fail "pdata: $in --topology $mode" "$(tail -2 "$TMP/$mode.log")"
            continue
        fi
        verdict "pdata: $in --topology $mode" "$(cmp_pd "$TMP/$in" "$out" $mode 2> /dev/null | tail -1)"
        case $mode:$(grep 'note:.*point data' "$TMP/$mode.log") in
        flips:*"the point data are kept (3 arrays)"*) pass "pdata: $in flips: the note says point data kept" ;;
        full:*"point data are kept (3 arrays, interpolated at "[1-9]*) pass "pdata: $in full: the note says where it was interpolated" ;;
        *) fail "pdata: $in $mode: note" "$(grep note: "$TMP/$mode.log")" ;;
        esac
    done
done

# qdc convert: through Gmsh (2.2 binary, 4.1 ASCII) back to VTU, to Medit
for f in gmsh22-bin gmsh; do
    if "$BIN/qdc" convert -q "$TMP/in.vtu" "$TMP/c-$f.msh" --out-format $f &&
        "$BIN/qdc" convert -q "$TMP/c-$f.msh" "$TMP/c-$f.vtu"; then
        verdict "pdata: convert vtu -> $f -> vtu" "$(cmp_pd "$TMP/in.vtu" "$TMP/c-$f.vtu" flips)"
    else
        fail "pdata: convert vtu -> $f -> vtu" "qdc convert failed"
    fi
done
"$BIN/qdc" convert "$TMP/in.vtk" "$TMP/c.mesh" 2> "$TMP/c.log"
case $(cat "$TMP/c.log") in
*"point data dropped (3 arrays"*) pass "pdata: convert vtk -> medit: the note says point data dropped" ;;
*) fail "pdata: convert vtk -> medit: note" "$(cat "$TMP/c.log")" ;;
esac
[ $NFAIL = 0 ]
