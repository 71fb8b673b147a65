#!/bin/sh
# pdata.sh - qdcd and point data: a .vtu of the dev bunny (low quality, 10k
# tets) with a linear field f, a 3-component and an integer array, run with
# topology=flips and topology=full and fetched as VTU. flips: the same
# vertices, every array equal value for value, the Qdc-Note (qdc's own
# writer: the tets changed) drops nothing of them. full inserts vertices: the
# result (result.qmesh with result.mesh's surface and the worker's arrays)
# has the vertices and the arrays, value for value, of `qdc optimize IN OUT
# --topology full` on the same file (the run is deterministic), the input's
# values at the vertices it kept, and its Qdc-Note says they were
# interpolated. The same for a full job of a binary MSH 2.2 upload, whose
# result in Gmsh has the CLI's arrays.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

if ! "$PY" -c 'import meshio, numpy' 2> /dev/null; then
    echo "ok - server pdata # SKIP python3 meshio/numpy missing"
    exit 0
fi
BUN=$(devmesh bunny_low_10k)
"$PY" - "$BUN" "$TMP/in.vtu" << 'PY' || { fail "server pdata: input" "meshio failed"; exit 1; }
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
p = m.points
tets = [c.data for c in m.cells if c.type == "tetra"][0]
meshio.Mesh(p, [("tetra", tets)], point_data={
    "f": p[:, 0] + 2 * p[:, 1] + 3 * p[:, 2], "vec": p * 0.5 - 1.0,
    "id": np.arange(len(p), dtype=np.int32)}).write(sys.argv[2])
PY
start_qdcd "$TMP/d" --workers 1 ||
    { fail "server pdata: start qdcd" "$(tail -3 "$TMP/d.log")"; exit 1; }
VTU=application/vnd.vtk.vtu+xml
"$BIN/qdc" optimize "$TMP/in.vtu" "$TMP/cli-full.vtu" --topology full -q ||
    fail "server pdata: qdc optimize --topology full" "exit $?"
for mode in flips full; do
    code=$(submit "$TMP/in.vtu" $VTU "topology=$mode" "$TMP/$mode.sub")
    id=$(jf "$TMP/$mode.sub" .id)
    st=$(poll_all "$id")
    if [ "$code" != 202 ] || [ "$st" != succeeded ]; then
        fail "server pdata: $mode" "$code $st $(head -c 300 "$TMP/$mode.sub")"
        continue
    fi
    code=$(req GET "/v1/jobs/$id/result?format=vtu" "$TMP/$mode.vtu")
    note=$(hdr "$TMP/$mode.vtu" Qdc-Note)
    if [ "$code" != 200 ]; then
        fail "server pdata: $mode: result as vtu" "$code $(head -c 300 "$TMP/$mode.vtu")"
        continue
    fi
    why=$("$PY" - "$TMP/in.vtu" "$TMP/$mode.vtu" $mode "$TMP/cli-full.vtu" << 'PY'
import sys, meshio, numpy as np
a, b = meshio.read(sys.argv[1]), meshio.read(sys.argv[2])
if sys.argv[3] == "full":
    c = meshio.read(sys.argv[4])
    bad = [k for k in ("f", "vec", "id") if k not in b.point_data or k not in c.point_data
           or not np.array_equal(np.asarray(b.point_data[k]), np.asarray(c.point_data[k]))]
    if len(b.points) == len(a.points): bad.append("no vertex inserted or contracted")
    if not np.array_equal(b.points, c.points): bad.append("vertices differ from the CLI's")
    if not bad:
        ids = np.asarray(b.point_data["id"]).astype(np.int64)
        # the kept vertices: the prefix whose ids increase
        n = 1
        while n < len(ids) and ids[n] > ids[n - 1]: n += 1
        kept = ids[:n]
        for k in ("f", "vec"):
            if not np.array_equal(np.asarray(b.point_data[k])[:n], np.asarray(a.point_data[k])[kept]):
                bad.append(k + " at kept vertices")
    print("differ: %s" % bad if bad else
          "ok %d -> %d vertices, f, vec and id equal to the CLI's, the input's at %d kept"
          % (len(a.points), len(b.points), n))
    sys.exit()
bad = [k for k in ("f", "vec", "id") if k not in b.point_data or
       not np.array_equal(np.asarray(a.point_data[k]), np.asarray(b.point_data[k]))]
print("differ: %s" % bad if bad or len(a.points) != len(b.points)
      else "ok %d vertices, f, vec and id equal" % len(b.points))
PY
)
    verdict "server pdata: $mode: result as vtu" "$why"
    case $mode:$note in
    flips:*dropped*) fail "server pdata: flips: Qdc-Note" "'$note'" ;;
    flips:*topology*) pass "server pdata: flips: Qdc-Note: $note" ;;
    full:*"point data are kept"*interpolated*) pass "server pdata: full: Qdc-Note: $note" ;;
    *) fail "server pdata: $mode: Qdc-Note" "'$note'" ;;
    esac
done
# topology=full on a Gmsh upload (binary MSH 2.2 with $NodeData): its result in
# its own format has the arrays of `qdc optimize IN OUT --topology full`
"$PY" - "$TMP/in.vtu" "$TMP/in.msh" 2> /dev/null << 'PY' || fail "server pdata: gmsh input" "meshio failed"
import sys, meshio
meshio.read(sys.argv[1]).write(sys.argv[2], file_format="gmsh22", binary=True)
PY
"$BIN/qdc" optimize "$TMP/in.msh" "$TMP/cli-full.msh" --topology full -q ||
    fail "server pdata: qdc optimize in.msh --topology full" "exit $?"
code=$(submit "$TMP/in.msh" model/vnd.gmsh "topology=full" "$TMP/g.sub")
id=$(jf "$TMP/g.sub" .id)
st=$(poll_all "$id")
c1=$(req GET "/v1/jobs/$id/result?format=gmsh" "$TMP/g.msh")
why=$("$PY" - "$TMP/in.msh" "$TMP/g.msh" "$TMP/cli-full.msh" "$code $st $c1" 2> /dev/null << 'PY' | tail -1
import sys, meshio, numpy as np
if sys.argv[4] != "202 succeeded 200":
    print("HTTP/state %s" % sys.argv[4]); sys.exit()
a, b, c = (meshio.read(x) for x in sys.argv[1:4])
bad = [k for k in ("f", "vec", "id") if k not in b.point_data or k not in c.point_data
       or not np.array_equal(np.asarray(b.point_data[k]), np.asarray(c.point_data[k]))]
if len(b.points) == len(a.points): bad.append("no vertex inserted or contracted")
if not np.array_equal(b.points, c.points): bad.append("vertices differ from the CLI's")
print("differ: %s" % bad if bad else "ok %d -> %d vertices, f, vec and id equal to the CLI's"
      % (len(a.points), len(b.points)))
PY
)
verdict "server pdata: gmsh full: result as gmsh" "$why"
# topology=full on a Medit upload with boundary triangles and refs: the vertices
# change, so its VTU is written from the run's own surface (result.mesh), not
# the upload's numbering: the same triangles as the Medit result, each a face
# of exactly one tet, the input's refs as a multiset.
# The same for topology=flips under a bound (hausd=0.01): boundary edge flips
# change the triangles, so the upload's no longer hold either.
for q in full flips:hausd=0.01; do
mode=${q%%:*} extra=${q#*:}
[ "$extra" = "$q" ] && extra= || extra="&$extra"
code=$(submit "$BUN" model/x-medit "topology=$mode$extra" "$TMP/mf.sub")
id=$(jf "$TMP/mf.sub" .id)
st=$(poll_all "$id")
if [ "$code" != 202 ] || [ "$st" != succeeded ]; then
    fail "server pdata: medit $q" "$code $st $(head -c 300 "$TMP/mf.sub")"
else
    c1=$(req GET "/v1/jobs/$id/result?format=vtu" "$TMP/mf.vtu")
    c2=$(req GET "/v1/jobs/$id/result?format=medit" "$TMP/mf.mesh")
    why=$("$PY" - "$BUN" "$TMP/mf.mesh" "$TMP/mf.vtu" "$c1" "$c2" "$mode" << 'PY'
import sys, collections, meshio, numpy as np
if sys.argv[4] != "200" or sys.argv[5] != "200":
    print("HTTP %s %s" % (sys.argv[4], sys.argv[5])); sys.exit()
def tri_refs(m):
    tris, refs = [], []
    for k, c in enumerate(m.cells):
        if c.type == "triangle":
            tris.append(c.data)
            r = [v[k] for n, v in m.cell_data.items() if n in ("medit:ref", "gmsh:physical", "CellEntityIds", "region")]
            refs.append(np.asarray(r[0]) if r else np.zeros(len(c.data), int))
    return np.vstack(tris), np.concatenate(refs)
a, md, vt = meshio.read(sys.argv[1]), meshio.read(sys.argv[2]), meshio.read(sys.argv[3])
ta, ra = tri_refs(a)
tm, rm = tri_refs(md)
tv, rv = tri_refs(vt)
tets = [c.data for c in vt.cells if c.type == "tetra"][0]
faces = collections.Counter()
for t in tets:
    for f in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)):
        faces[tuple(sorted(t[list(f)]))] += 1
once = sum(faces[tuple(sorted(t))] == 1 for t in tv)
key = lambda T: sorted(tuple(sorted(x)) for x in T.tolist())
bad = []
full = sys.argv[6] == "full"
if full and len(vt.points) == len(a.points): bad.append("no vertex inserted or contracted")
if not full and key(tv) == key(ta): bad.append("no boundary triangle changed")
if key(tv) != key(tm): bad.append("vtu and medit triangles differ")
if once != len(tv): bad.append("%d of %d triangles not boundary faces" % (len(tv) - once, len(tv)))
if sorted(rv.tolist()) != sorted(ra.tolist()): bad.append("refs differ from the input's: %s, input %s" % (collections.Counter(rv.tolist()).most_common(3), collections.Counter(ra.tolist()).most_common(3)))
print("differ: %s" % bad if bad else
      "ok %d -> %d vertices, %d triangles with the input's refs, each a boundary face"
      % (len(a.points), len(vt.points), len(tv)))
PY
)
    verdict "server pdata: medit $q: result as vtu" "$why"
fi
done
stop_qdcd
[ $NFAIL = 0 ]
