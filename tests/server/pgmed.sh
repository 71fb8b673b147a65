#!/bin/sh
# pgmed.sh - a MED job on two nodes of one PostgreSQL store (pg.inc): node a
# runs the job (qdc-h5 reads the upload in its child), node b, which never
# saw it (started after the job ended), serves the result as MED: it fetches the upload and qdc-h5's frames
# from the store, and the file it gives is the upload with only NOE/COO
# changed (medcoo.py, h5py). Also as VTU, and the input mesh, from node b.
# XDMF with its .h5 file (multipart) is not taken with a shared store: 415.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/pg.inc"
QDCD=${QDCD:-$BIN/qdcd}
QM='application/octet-stream'
PIDS=
trap 'for p in $PIDS; do kill -9 $p 2>/dev/null; done; pg_cleanup; rm -rf "$TMP"' EXIT

CHECKS="job on node a|MED result from node b|VTU result from node b|input from node b|XDMF+HDF5 upload 415"
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
code=$(curl -s -m 60 -o "$TMP/b.med" -w '%{http_code}' "$URL_b/v1/jobs/$ID/result?format=med")
if [ "$code" = 200 ] && [ ! -e "$TMP/db/jobs/$ID/result.med.frames" ]; then
    "$PY" "$ROOT/tests/tools/medcoo.py" "$TMP/m.med" "$TMP/b.med" \
        "pgmed: MED result from node b" > "$TMP/chk" 2>&1
    cat "$TMP/chk"
    grep -q '^ok' "$TMP/chk" || NFAIL=$((NFAIL + 1))
else
    fail "pgmed: MED result from node b" "$code $(head -c 300 "$TMP/b.med")"
fi
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
code=$(curl -s -m 60 -o "$TMP/x.json" -w '%{http_code}' -F "xdmf=@$TMP/m.xdmf" \
    -F "h5=@$TMP/m.h5" "$URL_b/v1/jobs")
[ "$code" = 415 ] && grep -q "PostgreSQL" "$TMP/x.json" &&
    pass "pgmed: XDMF+HDF5 upload 415 with a shared store (one input file a job)" ||
    fail "pgmed: XDMF+HDF5 upload 415" "$code $(head -c 300 "$TMP/x.json")"
exit $NFAIL
