#!/bin/sh
# bombs.sh - compressed uploads are held to the limits of what they inflate
# to: a 1 MB gzip of zeros (1 GiB inflated), a small gzip of JSON twice
# --max-json, gzip inside gzip and a VTU whose zlib arrays inflate ~1000x get
# 413/400 naming the limit, inflating stops at it (qdcd's peak memory stays
# under the limit plus 64 MB), and a small upload sent while a bomb is being
# inflated is answered about as fast as one sent alone (measured in this run).
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

CUBE=$ROOT/tests/data/sample/cube.mesh
MB=1048576

# The zero bomb: 16 gzip members of 64 MiB of zeros each (members one after
# the other are one gzip file): 1 MB that inflates to 1 GiB.
head -c $((64 * MB)) /dev/zero | gzip -9 > "$TMP/z64.gz"
for i in 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16; do cat "$TMP/z64.gz"; done > "$TMP/zeros.gz"
zsize=$(stat -c %s "$TMP/zeros.gz")
# JSON twice --max-json (1 MiB below), and under it; gzip inside gzip
$MT bigjson $((2 * MB)) "$TMP/two.json"
gzip -9 -c "$TMP/two.json" > "$TMP/two.json.gz"
$MT bigjson $((MB / 2)) "$TMP/half.json"
gzip -9 -c "$TMP/half.json" > "$TMP/half.json.gz"
gzip -9 -c "$CUBE" > "$TMP/cube.mesh.gz"
gzip -9 -c "$TMP/cube.mesh.gz" > "$TMP/cube.mesh.gz.gz"
# a VTU of 4M points whose appended zlib blocks (1 MiB of zeros each) inflate
# to 96 MiB from ~100 kB
$PY - "$TMP/bomb.vtu" << 'EOF'
import struct, sys, zlib
np = 1 << 22
blk = zlib.compress(bytes(1 << 20), 9)
nb = np * 24 // (1 << 20)
head = ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" '
        'byte_order="LittleEndian" header_type="UInt64" compressor="vtkZLibDataCompressor">\n'
        '<UnstructuredGrid>\n<Piece NumberOfPoints="%d" NumberOfCells="1">\n<Points>\n'
        '<DataArray type="Float64" NumberOfComponents="3" format="appended" offset="0"/>\n'
        '</Points>\n<Cells>\n<DataArray type="Int64" Name="connectivity" format="ascii">0 1 2 3'
        '</DataArray>\n<DataArray type="Int64" Name="offsets" format="ascii">4</DataArray>\n'
        '<DataArray type="UInt8" Name="types" format="ascii">10</DataArray>\n</Cells>\n'
        '</Piece>\n</UnstructuredGrid>\n<AppendedData encoding="raw">\n_' % np).encode()
body = struct.pack("<3Q", nb, 1 << 20, 0) + struct.pack("<Q", len(blk)) * nb + blk * nb
open(sys.argv[1], "wb").write(head + body + b"\n</AppendedData>\n</VTKFile>\n")
EOF

# expect413 NAME LIMIT STATUS: the problem in $TMP/out says 413 too-big and
# names LIMIT
expect413() {
    if [ "$3" = 413 ] && [ "$(hdr "$TMP/out" Content-Type)" = application/problem+json ] &&
        [ "$(jf "$TMP/out" .limit)" = "$2" ] && [ "$(jf "$TMP/out" .type)" = /problems/too-big ]; then
        pass "$1: 413 naming --$2 ($(jf "$TMP/out" .detail))"
    else
        fail "$1" "status $3, body $(head -c 300 "$TMP/out")"
    fi
}
hwm_mb() { awk '/^VmHWM/ { print int($2 / 1024) }' "/proc/$QPID/status"; }

# --- the default ratio cap (100): a 1 MB bomb stops at 100 MB -------------
start_qdcd "$TMP/d" --workers 1 --max-body $((256 * MB)) --max-json $MB ||
    { fail "start" "$(tail -3 "$TMP/d.log")"; exit 1; }
for t in text/plain model/x-medit; do
    code=$(submit "$TMP/zeros.gz" $t "" "$TMP/out")
    expect413 "1 MB gzip of zeros ($zsize bytes, 1 GiB inflated) as $t" max-ratio "$code"
done
hwm=$(hwm_mb)
[ "$hwm" -le $((100 + 64)) ] && pass "peak RSS $hwm MB <= 100 MB (--max-ratio x 1 MB) + 64 MB" ||
    fail "peak RSS with the ratio cap" "$hwm MB"
code=$(submit "$TMP/bomb.vtu" text/plain "" "$TMP/out")
if [ "$code" = 413 ] && jf "$TMP/out" .detail | grep -q "zlib arrays inflate to more than"; then
    pass "VTU with zlib arrays inflating ~1000x ($(stat -c %s "$TMP/bomb.vtu") bytes, 96 MiB): 413"
else
    fail "VTU zlib bomb" "$code $(head -c 300 "$TMP/out")"
fi
code=$(submit "$TMP/cube.mesh.gz.gz" text/plain "" "$TMP/out")
[ "$code" = 400 ] && jf "$TMP/out" .detail | grep -q "compressed twice" &&
    pass "gzip inside gzip: 400 ($(jf "$TMP/out" .detail))" ||
    fail "nested gzip" "$code $(head -c 300 "$TMP/out")"
code=$(submit "$TMP/cube.mesh.gz" text/plain "max_iter=1" "$TMP/out")
[ "$code" = 202 ] && [ "$(jf "$TMP/out" .mesh.format)" = medit ] &&
    pass "a gzip Medit mesh within the limits: 202" || fail "gzip mesh" "$code $(head -c 300 "$TMP/out")"
stop_qdcd

# --- no ratio cap: --max-body and --max-json hold on the inflated bytes ----
start_qdcd "$TMP/e" --workers 1 --max-body $((256 * MB)) --max-json $MB --max-ratio 1000000 ||
    { fail "start" "$(tail -3 "$TMP/e.log")"; exit 1; }
for t in text/plain application/json; do
    code=$(submit "$TMP/two.json.gz" $t "" "$TMP/out")
    expect413 "gzip of $(stat -c %s "$TMP/two.json.gz") bytes inflating to 2x --max-json as $t" max-json "$code"
done
code=$(submit "$TMP/half.json.gz" application/json "max_iter=1" "$TMP/out")
[ "$code" = 202 ] && pass "gzip JSON of half --max-json: 202" || fail "gzip JSON" "$code $(head -c 300 "$TMP/out")"

# A small upload alone, three times: the baseline of this run.
base=0
for i in 1 2 3; do
    t=$(curl -s -m 60 -o /dev/null -w '%{time_total}' --data-binary @"$CUBE" \
        -H "Content-Type: model/x-medit" "$URL/v1/jobs?max_iter=1")
    base=$(echo "$t $base" | awk '{ print ($1 > $2) ? $1 : $2 }')
done
rss0=$(awk '/^VmRSS/ { print int($2 / 1024) }' "/proc/$QPID/status")
curl -s -m 120 -o "$TMP/bomb.out" -D "$TMP/bomb.out.h" -w '%{http_code} %{time_total}\n' --data-binary @"$TMP/zeros.gz" \
    -H "Content-Type: model/x-medit" "$URL/v1/jobs" > "$TMP/bomb.code" &
BPID=$!
# wait until the bomb is being inflated: qdcd's memory grows 32 MB
i=0
while [ $i -lt 1000 ] && kill -0 $BPID 2> /dev/null &&
    [ "$(awk '/^VmRSS/ { print int($2 / 1024) }' "/proc/$QPID/status")" -lt $((rss0 + 32)) ]; do
    sleep 0.01
    i=$((i + 1))
done
small=$(curl -s -m 60 -o "$TMP/small.out" -w '%{http_code} %{time_total}' --data-binary @"$CUBE" \
    -H "Content-Type: model/x-medit" "$URL/v1/jobs?max_iter=1")
kill -0 $BPID 2> /dev/null && during=1 || during=0
wait $BPID
bomb=$(cat "$TMP/bomb.code")
st=${small% *}
ts=${small#* }
# generous: five times the slowest lone upload, or 0.25 s more (a loaded
# machine); before the limits the bomb held the small upload for ~10 s
ok=$(echo "$ts $base" | awk '{ print ($1 <= 5 * $2 || $1 <= $2 + 0.25) ? 1 : 0 }')
if [ "$during" = 0 ]; then
    echo "ok - small upload during a bomb # SKIP the bomb ($bomb) ended before the small upload was answered (${ts} s)"
elif [ "$st" = 202 ] && [ "$ok" = 1 ]; then
    pass "small upload while a bomb inflates: 202 in ${ts} s (alone: ${base} s at most; bomb: $bomb)"
else
    fail "small upload during a bomb" "$small (alone: ${base} s; bomb $bomb)"
fi
cp "$TMP/bomb.out" "$TMP/out"
cp "$TMP/bomb.out.h" "$TMP/out.h"
expect413 "the bomb, without a ratio cap" max-body "${bomb% *}"
hwm=$(hwm_mb)
[ "$hwm" -le $((256 + 64)) ] && pass "peak RSS $hwm MB <= 256 MB (--max-body) + 64 MB" ||
    fail "peak RSS with --max-body" "$hwm MB"
stop_qdcd

exit $((NFAIL > 0))
