#!/bin/sh
# hdf5.sh - qdcd takes no MED upload (HDF5 is read by the qdc command's
# qdc-h5 child, never in the daemon): a .med body sniffed, named by
# ?format=med, or given as the frames qdc-h5 prints, is a 415 naming the way
# (qdc convert), and no job is made. XDMF with the data inline is taken.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

gzip -dc "$ROOT/tests/data/real/meshio.med.gz" > "$TMP/in.med"
gzip -dc "$ROOT/tests/data/real/meshio.xdmf.gz" > "$TMP/in.xdmf"
printf 'QDCH5v1\n' > "$TMP/frames.bin"
start_qdcd "$TMP/d" --workers 1 || { fail "hdf5: qdcd starts" "$(tail -3 "$TMP/d.log")"; exit 1; }
for how in sniffed format=med frames; do
    f=$TMP/in.med q=
    [ $how = format=med ] && q=format=med
    [ $how = frames ] && f=$TMP/frames.bin q=format=med
    code=$(submit "$f" application/octet-stream "$q" "$TMP/out")
    if [ "$code" = 415 ] && grep -q "qdc convert" "$TMP/out"; then
        pass "hdf5: MED upload ($how): 415 naming qdc convert"
    else
        fail "hdf5: MED upload ($how)" "$code $(head -c 300 "$TMP/out")"
    fi
done
n=$(curl -s "$URL/v1/jobs" | jq '.jobs | length')
[ "$n" = 0 ] && pass "hdf5: no job made of them" || fail "hdf5: jobs" "$n"
code=$(submit "$TMP/in.xdmf" application/octet-stream "" "$TMP/out")
if [ "$code" = 202 ]; then
    pass "hdf5: an inline XDMF upload is taken (202)"
else
    fail "hdf5: XDMF upload" "$code $(head -c 300 "$TMP/out")"
fi
stop_qdcd
exit $NFAIL
