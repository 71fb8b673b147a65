#!/bin/sh
# pgmed.sh - a MED job on two nodes of one PostgreSQL store (pg.inc): node a
# runs the job (qdc-h5 reads the upload in its child), node b, which never
# saw it (started after the job ended), serves the result as MED: it fetches the upload and qdc-h5's frames
# from the store, and the file it gives is the upload with only NOE/COO
# changed (medcoo.py, h5py). Also as VTU, and the input mesh, from node b.
# XDMF with its .h5 file (multipart): both files stored with the job; node a
# takes the upload while its one worker is busy, node c (its own --data)
# runs it; node d, started after the job ended, serves the XDMF, the .h5
# (only the geometry changed), the VTU result and the input mesh.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/pg.inc"
QDCD=${QDCD:-$BIN/qdcd}
QM='application/octet-stream'
PIDS=
trap 'for p in $PIDS; do kill -9 $p 2>/dev/null; done; pg_cleanup; rm -rf "$TMP"' EXIT

CHECKS="job on node a|MED result from node b|VTU result from node b|input from node b|XDMF+HDF5 job run by another node|XDMF+HDF5 job record|XDMF result from node d|h5 result from node d|VTU of XDMF+HDF5 from node d|XDMF+HDF5 input from node d"
if [ ! -x "$BIN/qdc-h5" ]; then
    echo "$CHECKS" | tr '|' '\n' | while read -r n; do
        echo "ok - pgmed: $n # SKIP qdc-h5 not built (libhdf5-dev missing)"
    done
    exit 0
fi
if ! pg_available; then
    pg_skip pgmed "$CHECKS"
    exit 0
fi
pg_started pgmed || exit 1
gzip -dc "$ROOT/tests/data/real/meshio.med.gz" > "$TMP/m.med"
node a "$TMP/da" --workers 1 || { fail "pgmed: node a starts" "$(tail -3 "$TMP/a.log")"; exit 1; }

code=$(post "$URL_a" "$TMP/m.med" "max_iter=5" "$TMP/sub")
ID=$(jf "$TMP/sub" .id)
st=$(wait_done "$URL_a" "$ID")
if [ "$code" = 202 ] && [ "$st" = succeeded ]; then
    pass "pgmed: job on node a: MED upload succeeded"
else
    fail "pgmed: job on node a" "$code $st $(head -c 300 "$TMP/sub")"
fi
# node b starts once the job is done: no job for it to run, nothing cached
node b "$TMP/db" --workers 1 || { fail "pgmed: node b starts" "$(tail -3 "$TMP/b.log")"; exit 1; }
# h5_result URL DATA ID FORMAT ORIG OUT WHAT [DATASET]: GET the job's result
# in FORMAT from the node at URL as OUT, which h5py finds the same as ORIG but
# for the coordinates; the node (--data DATA) kept no frames of it
h5_result() {
    code=$(curl -s -m 60 -o "$6" -w '%{http_code}' "$1/v1/jobs/$3/result?format=$4")
    if [ "$code" = 200 ] && [ ! -e "$2/jobs/$3/result.$4.frames" ]; then
        "$PY" "$ROOT/tests/tools/medcoo.py" "$5" "$6" "$7" ${8:-} > "$TMP/chk" 2>&1
        cat "$TMP/chk"
        grep -q '^ok' "$TMP/chk" || NFAIL=$((NFAIL + 1))
    else
        fail "$7" "$code $(head -c 300 "$6")"
    fi
}
h5_result "$URL_b" "$TMP/db" "$ID" med "$TMP/m.med" "$TMP/b.med" "pgmed: MED result from node b"
code=$(curl -s -m 60 -o "$TMP/b.vtu" -w '%{http_code}' "$URL_b/v1/jobs/$ID/result?format=vtu")
[ "$code" = 200 ] && grep -q "<VTKFile" "$TMP/b.vtu" &&
    pass "pgmed: VTU result from node b" ||
    fail "pgmed: VTU result from node b" "$code $(head -c 300 "$TMP/b.vtu")"
code=$(curl -s -m 60 -o "$TMP/b.in" -w '%{http_code}' "$URL_b/v1/jobs/$ID/input?format=medit")
[ "$code" = 200 ] && grep -q "^Tetrahedra" "$TMP/b.in" &&
    pass "pgmed: input from node b: the MED job's input mesh as Medit" ||
    fail "pgmed: input from node b" "$code $(head -c 300 "$TMP/b.in")"
gzip -dc "$ROOT/tests/data/real/meshio_h5.xdmf.gz" > "$TMP/m.xdmf"
gzip -dc "$ROOT/tests/data/real/meshio_h5.h5.gz" > "$TMP/m.h5"
# node a's one worker busy (node b stopped: it would take the jobs), the
# pair uploaded to node a, run by node c
stop "$PID_b"
# (a job that runs until it is cancelled below: 10000 iterations)
code=$(curl -s -m 60 -o "$TMP/blk" -X POST --data-binary "@$(devmesh cube_h0.1_lowq)" \
    -H "Content-Type: text/plain" "$URL_a/v1/jobs?max_iter=10000&finish=0&tol_move=0&mode=literal")
BLK=$(jf "$TMP/blk" .id)
wait_running "$URL_a" "$BLK"
code=$(curl -s -m 60 -o "$TMP/x.json" -w '%{http_code}' -F "xdmf=@$TMP/m.xdmf" \
    -F "h5=@$TMP/m.h5" "$URL_a/v1/jobs?max_iter=5")
XID=$(jf "$TMP/x.json" .id)
node c "$TMP/dc" --workers 1 || { fail "pgmed: node c starts" "$(tail -3 "$TMP/c.log")"; exit 1; }
st=$(wait_done "$URL_c" "$XID")
curl -s -m 10 -o /dev/null -X POST "$URL_a/v1/jobs/$BLK:cancel"
if [ "$code" = 202 ] && [ "$st" = succeeded ] && [ -e "$TMP/dc/jobs/$XID/input.frames" ] &&
    [ ! -e "$TMP/da/jobs/$XID/input.frames" ]; then
    pass "pgmed: XDMF+HDF5 job run by another node: uploaded to node a, run by node c"
else
    fail "pgmed: XDMF+HDF5 job run by another node" "$code $st $(head -c 300 "$TMP/x.json")"
fi
stop "$PID_c"
node d "$TMP/dd" --workers 1 || { fail "pgmed: node d starts" "$(tail -3 "$TMP/d.log")"; exit 1; }
curl -s -m 10 -o "$TMP/xj.json" "$URL_d/v1/jobs/$XID"
jq -e '.mesh.h5 == true and .mesh.format == "xdmf" and .mesh.tets == 1228' "$TMP/xj.json" > /dev/null &&
    pass "pgmed: XDMF+HDF5 job record from node d: mesh.h5 true, 1228 tets" ||
    fail "pgmed: XDMF+HDF5 job record" "$(head -c 300 "$TMP/xj.json")"
code=$(curl -s -m 60 -o "$TMP/d.xdmf" -w '%{http_code}' "$URL_d/v1/jobs/$XID/result?format=xdmf")
if [ "$code" = 200 ] && sed 's/meshio_h5\.h5:/result.h5:/g' "$TMP/m.xdmf" | cmp -s - "$TMP/d.xdmf"; then
    pass "pgmed: XDMF result from node d: the uploaded XML naming result.h5"
else
    fail "pgmed: XDMF result from node d" "$code $(head -c 300 "$TMP/d.xdmf")"
fi
h5_result "$URL_d" "$TMP/dd" "$XID" h5 "$TMP/m.h5" "$TMP/d.h5" "pgmed: h5 result from node d" data0
code=$(curl -s -m 60 -o "$TMP/d.vtu" -w '%{http_code}' "$URL_d/v1/jobs/$XID/result?format=vtu")
[ "$code" = 200 ] && grep -q "<VTKFile" "$TMP/d.vtu" &&
    pass "pgmed: VTU of XDMF+HDF5 from node d" ||
    fail "pgmed: VTU of XDMF+HDF5 from node d" "$code $(head -c 300 "$TMP/d.vtu")"
code=$(curl -s -m 60 -o "$TMP/d.in" -w '%{http_code}' "$URL_d/v1/jobs/$XID/input?format=medit")
[ "$code" = 200 ] && [ "$(awk '/^Tetrahedra/{getline; print; exit}' "$TMP/d.in")" = 1228 ] &&
    pass "pgmed: XDMF+HDF5 input from node d: 1228 tets as Medit" ||
    fail "pgmed: XDMF+HDF5 input from node d" "$code $(head -c 300 "$TMP/d.in")"
exit $NFAIL
