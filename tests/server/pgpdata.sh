#!/bin/sh
# pgpdata.sh - a topology=full job's point data across two nodes of one
# PostgreSQL store (pg.inc): node a runs a .vtu of the dev bunny with two
# arrays (a linear field f and an integer id); node b, started after the job
# ended (nothing of it cached), serves the result as VTU and as Gmsh: it
# fetches the upload, result.qmesh, result.mesh and the worker's arrays from
# the store, and both files carry f and id with the values node a's own VTU
# result has, at every vertex (the run inserted some).
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/pg.inc"
QDCD=${QDCD:-$BIN/qdcd}
QM='application/vnd.vtk.vtu+xml'
PIDS=
trap 'for p in $PIDS; do kill -9 $p 2>/dev/null; done; pg_cleanup; rm -rf "$TMP"' EXIT

CHECKS="job on node a|VTU result from node b|Gmsh result from node b"
if ! "$PY" -c 'import meshio, numpy' 2> /dev/null; then
    echo "$CHECKS" | tr '|' '\n' | while read -r n; do
        echo "ok - pgpdata: $n # SKIP python3 meshio/numpy missing"
    done
    exit 0
fi
if ! pg_available; then
    pg_skip pgpdata "$CHECKS"
    exit 0
fi
pg_started pgpdata || exit 1
"$PY" - "$(devmesh bunny_low_10k)" "$TMP/in.vtu" << 'PY' || { fail "pgpdata: input" "meshio failed"; exit 1; }
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
p = m.points
tets = [c.data for c in m.cells if c.type == "tetra"][0]
meshio.Mesh(p, [("tetra", tets)], point_data={
    "f": p[:, 0] + 2 * p[:, 1] + 3 * p[:, 2],
    "id": np.arange(len(p), dtype=np.int32)}).write(sys.argv[2])
PY
node a "$TMP/da" --workers 1 || { fail "pgpdata: node a starts" "$(tail -3 "$TMP/a.log")"; exit 1; }
code=$(post "$URL_a" "$TMP/in.vtu" "topology=full" "$TMP/sub")
ID=$(jf "$TMP/sub" .id)
st=$(wait_done "$URL_a" "$ID")
ca=$(curl -s -m 60 -o "$TMP/a.vtu" -w '%{http_code}' "$URL_a/v1/jobs/$ID/result?format=vtu")
if [ "$code" = 202 ] && [ "$st" = succeeded ] && [ "$ca" = 200 ]; then
    pass "pgpdata: job on node a: topology=full succeeded, its VTU served"
else
    fail "pgpdata: job on node a" "$code $st $ca $(head -c 300 "$TMP/sub")"
fi
stop "$PID_a"
node b "$TMP/db" --workers 1 || { fail "pgpdata: node b starts" "$(tail -3 "$TMP/b.log")"; exit 1; }
for f in vtu msh; do
    code=$(curl -s -m 60 -o "$TMP/b.$f" -w '%{http_code}' "$URL_b/v1/jobs/$ID/result?format=$([ $f = msh ] && echo gmsh || echo vtu)")
    why=$("$PY" - "$TMP/in.vtu" "$TMP/a.vtu" "$TMP/b.$f" "$code" 2> /dev/null << 'PY' | tail -1
import sys, meshio, numpy as np
if sys.argv[4] != "200":
    print("HTTP %s" % sys.argv[4]); sys.exit()
i, a, b = (meshio.read(x) for x in sys.argv[1:4])
bad = []
if len(a.points) == len(i.points): bad.append("no vertex inserted or contracted")
if len(b.points) != len(a.points): bad.append("%d vertices, node a's %d" % (len(b.points), len(a.points)))
for k in ("f", "id"):
    if k not in b.point_data: bad.append(k + " missing")
    elif not np.array_equal(np.ravel(b.point_data[k]).astype(float), np.ravel(a.point_data[k]).astype(float)):
        bad.append(k + " differs")
print("differ: %s" % bad if bad else "ok %d -> %d vertices, f and id as node a's"
      % (len(i.points), len(b.points)))
PY
)
    verdict "pgpdata: $([ $f = msh ] && echo Gmsh || echo VTU) result from node b" "$why"
done
exit $NFAIL
