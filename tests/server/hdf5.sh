#!/bin/sh
# hdf5.sh - MED uploads: qdcd never reads HDF5 itself; the worker runs qdc-h5
# in a child process (the job's time limit, --child-memory, no network,
# killed with the daemon) to read the upload, and again to write the result
# as a copy of it with only NOE/COO changed (h5py compares every other
# dataset and attribute), or, for a topology=flips job, as a MED file of
# qdc's own (read back as the job's VTU result). A body named MED that is no HDF5 file is a 400 at
# once; an HDF5 file that is no MED, or a MED file cut short, fails its job
# with a 400 problem saying why; qdc-h5 killed at the job's deadline fails
# it with a 422 that says so; the daemon lives on. XDMF whose heavy data is
# HDF5 comes as two files in one multipart/form-data request (curl -F, and
# `qdc submit m.xdmf`): the job reads the .h5 through qdc-h5 too, its
# result?format=h5 is the upload's .h5 with only the coordinates changed
# (h5py) and result?format=xdmf its XML naming result.h5; a missing part,
# two .h5 names, a part that is no HDF5 file are 400s at once, a cut .h5
# fails its job with a 400; the .xdmf alone is a 415 saying how to send
# both. Inline XDMF is taken. qdc-h5 over --child-memory (a 96 MB chunk to
# inflate, 64 MiB allowed) fails its job with a 422 naming the limit.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

if [ ! -x "$BIN/qdc-h5" ]; then
    pass "hdf5: all # SKIP qdc-h5 not built (libhdf5-dev missing)"
    exit 0
fi
for f in meshio.med meshio.xdmf meshio_h5.h5 meshio_h5.xdmf; do
    gzip -dc "$ROOT/tests/data/real/$f.gz" > "$TMP/$f"
done
head -c 40000 "$TMP/meshio.med" > "$TMP/cut.med"
printf 'QDCH5v1\n' > "$TMP/frames.bin"
start_qdcd "$TMP/d" --workers 1 || { fail "hdf5: qdcd starts" "$(tail -3 "$TMP/d.log")"; exit 1; }

# job NAME FILE QUERY: submit FILE (octet-stream); its id in $ID, its end state in $ST
job() {
    code=$(submit "$2" application/octet-stream "$3" "$TMP/sub.$1")
    ID=$(jf "$TMP/sub.$1" .id)
    ST=
    if [ "$code" != 202 ]; then
        fail "hdf5: $1: upload" "$code $(head -c 300 "$TMP/sub.$1")"
        return 1
    fi
    ST=$(wait_done "$ID")
}

# coo_check A B WHAT [DATASET]: h5py finds B the same file as A but for
# NOE/COO, or DATASET (one "ok - " or "FAIL - " line; a failure counted)
coo_check() {
    "$PY" "$ROOT/tests/tools/medcoo.py" "$@" > "$TMP/chk" 2>&1
    cat "$TMP/chk"
    grep -q '^ok' "$TMP/chk" || NFAIL=$((NFAIL + 1))
}

# h5_result ID FORMAT ORIG WHAT [DATASET]: GET job ID's result in FORMAT (med,
# h5) and coo_check it against ORIG
h5_result() {
    code=$(req GET "/v1/jobs/$1/result?format=$2" "$TMP/result.$2")
    if [ "$code" = 200 ] && "$PY" -c 'import h5py' 2> /dev/null; then
        coo_check "$3" "$TMP/result.$2" "$4" ${5:-}
    elif [ "$code" = 200 ]; then
        pass "$4: h5py check # SKIP python3-h5py missing"
    else
        fail "$4" "$code $(head -c 300 "$TMP/result.$2")"
    fi
}

if job med "$TMP/meshio.med" "max_iter=5" && [ "$ST" = succeeded ] &&
    [ "$(jf "$TMP/job.$ID" .mesh.tets)" = 1228 ]; then
    pass "hdf5: meshio.med upload (sniffed): job succeeded, $(jf "$TMP/job.$ID" .mesh.tets) tets"
else
    fail "hdf5: meshio.med job" "$ST $(cat "$TMP/job.$ID" 2> /dev/null | head -c 400)"
fi
MEDID=$ID
h5_result "$ID" med "$TMP/meshio.med" "hdf5: result.med"
code=$(req GET "/v1/jobs/$ID/result?format=vtu" "$TMP/result.vtu")
[ "$code" = 200 ] && pass "hdf5: the MED job's result as VTU too" ||
    fail "hdf5: result vtu" "$code $(head -c 300 "$TMP/result.vtu")"

# qdc submit sends the MED file as it is and writes the result as a MED file
if "$BIN/qdc" submit "$TMP/meshio.med" --server "$URL" --max-iter 5 -o "$TMP/sub.med" -q \
    > "$TMP/sub.out" 2>&1 && "$PY" -c 'import h5py' 2> /dev/null; then
    coo_check "$TMP/meshio.med" "$TMP/sub.med" "hdf5: qdc submit meshio.med -o sub.med"
else
    fail "hdf5: qdc submit meshio.med" "$(tail -3 "$TMP/sub.out")"
fi

# a run that changed the tets: its MED result is a MED file of qdc's own
# (qdc-h5 med-new in the worker's child), with a note saying so; read back
# by qdc it is the job's VTU result: the same vertices, tets and regions,
# 0 inverted
if job flips "$TMP/meshio.med" "max_iter=5&topology=flips" && [ "$ST" = succeeded ]; then
    code=$(req GET "/v1/jobs/$ID/result?format=med" "$TMP/flips.med")
    code2=$(req GET "/v1/jobs/$ID/result?format=vtu" "$TMP/flips.vtu")
    "$BIN/qdc" convert "$TMP/flips.med" "$TMP/flips_med.json" --quiet 2> "$TMP/err"
    "$BIN/qdc" convert "$TMP/flips.vtu" "$TMP/flips_vtu.json" --quiet 2>> "$TMP/err"
    if [ "$code" = 200 ] && [ "$code2" = 200 ] &&
        hdr "$TMP/flips.med" Qdc-Note | grep -q "qdc's med writer" &&
        jq -e --slurpfile v "$TMP/flips_vtu.json" \
            '.vertices == $v[0].vertices and .tets == $v[0].tets and .regions == $v[0].regions and (.tets | length) != 1228' \
            "$TMP/flips_med.json" > /dev/null &&
        "$BIN/qdc" quality "$TMP/flips.med" 2>&1 | grep -q " 0 inverted"; then
        pass "hdf5: topology=flips on a MED upload: result?format=med by qdc's MED writer ($(jq '.tets | length' "$TMP/flips_med.json") tets), read back as the VTU result, 0 inverted"
    else
        fail "hdf5: MED result after flips" "$code $(head -c 300 "$TMP/flips.med") vtu $code2 $(head -2 "$TMP/err")"
    fi
else
    fail "hdf5: topology=flips MED job" "$ST $(head -c 400 "$TMP/job.$ID" 2> /dev/null)"
fi

code=$(submit "$TMP/frames.bin" application/octet-stream format=med "$TMP/out")
if [ "$code" = 400 ] && grep -q "not an HDF5 file" "$TMP/out"; then
    pass "hdf5: a body named MED that is no HDF5 file: 400 at once"
else
    fail "hdf5: non-HDF5 MED body" "$code $(head -c 300 "$TMP/out")"
fi
for c in "nomed meshio_h5.h5 not a MED file" "cut cut.med MED"; do
    set -- $c
    if job "$1" "$TMP/$2" "format=med" && [ "$ST" = failed ] &&
        jq -e '.error.status == 400' "$TMP/job.$ID" > /dev/null; then
        pass "hdf5: $2 as MED: job failed with a 400 ($(jf "$TMP/job.$ID" .error.detail | cut -c1-80))"
    else
        fail "hdf5: $2 as MED" "$ST $(head -c 400 "$TMP/job.$ID")"
    fi
done
if job slow "$TMP/meshio.med" "time_limit=0.000001" && [ "$ST" = failed ] &&
    jq -e '.error.status == 422 and (.error.detail | test("qdc-h5.*killed"))' "$TMP/job.$ID" > /dev/null; then
    pass "hdf5: qdc-h5 killed at the job's deadline: $(jf "$TMP/job.$ID" .error.detail | cut -c1-90)"
else
    fail "hdf5: qdc-h5 killed" "$ST $(head -c 400 "$TMP/job.$ID")"
fi
curl -sf "$URL/livez" > /dev/null && pass "hdf5: qdcd still answers" || fail "hdf5: livez" "no answer"

code=$(submit "$TMP/meshio_h5.xdmf" application/octet-stream "" "$TMP/out")
if [ "$code" = 415 ] && grep -q "multipart/form-data" "$TMP/out"; then
    pass "hdf5: the .xdmf alone of an XDMF with HDF5 heavy data: 415 saying to send both"
else
    fail "hdf5: XDMF+HDF5 upload alone" "$code $(head -c 300 "$TMP/out")"
fi

# form NAME QUERY CURL-ARGS...: POST the -F parts; the answer in $TMP/form.NAME
form() {
    _n=$1 _q=$2
    shift 2
    req POST "/v1/jobs?$_q" "$TMP/form.$_n" "$@"
}
code=$(form ok "max_iter=5" -F "xdmf=@$TMP/meshio_h5.xdmf" -F "h5=@$TMP/meshio_h5.h5")
ID=$(jf "$TMP/form.ok" .id 2> /dev/null)
if [ "$code" = 202 ] && [ "$(wait_done "$ID")" = succeeded ] &&
    [ "$(jf "$TMP/job.$ID" .mesh.tets)" = 1228 ]; then
    pass "hdf5: meshio_h5.xdmf + meshio_h5.h5 as multipart/form-data: job succeeded, 1228 tets"
else
    fail "hdf5: XDMF+HDF5 multipart job" "$code $(head -c 300 "$TMP/form.ok") $(head -c 300 "$TMP/job.$ID" 2> /dev/null)"
fi
h5_result "$ID" h5 "$TMP/meshio_h5.h5" "hdf5: result?format=h5 of the XDMF+HDF5 job" data0
code=$(req GET "/v1/jobs/$ID/result?format=xdmf" "$TMP/result.xdmf")
if [ "$code" = 200 ] && sed 's/meshio_h5\.h5:/result.h5:/g' "$TMP/meshio_h5.xdmf" | cmp -s - "$TMP/result.xdmf"; then
    pass "hdf5: result?format=xdmf: the uploaded XML with only the .h5 name changed (result.h5)"
else
    fail "hdf5: result?format=xdmf" "$code $(head -c 300 "$TMP/result.xdmf")"
fi
code=$(req GET "/v1/jobs/$ID/result?format=vtu" "$TMP/resultx.vtu")
[ "$code" = 200 ] && pass "hdf5: the XDMF+HDF5 job's result as VTU too" ||
    fail "hdf5: XDMF+HDF5 result vtu" "$code $(head -c 300 "$TMP/resultx.vtu")"
# ?format=h5 is an XDMF+HDF5 job's only
if [ "$(req GET "/v1/jobs/$MEDID/result?format=h5" "$TMP/out")" = 400 ]; then
    pass "hdf5: result?format=h5 of a MED job: 400"
else
    fail "hdf5: format=h5 of a MED job" "$(head -c 300 "$TMP/out")"
fi

# qdc submit sends both files and writes -o as qdc optimize does (.xdmf + .h5)
if "$BIN/qdc" submit "$TMP/meshio_h5.xdmf" --server "$URL" --max-iter 5 -o "$TMP/subx.xdmf" -q \
    > "$TMP/subx.out" 2>&1 && "$PY" -c 'import h5py' 2> /dev/null; then
    coo_check "$TMP/meshio_h5.h5" "$TMP/subx.h5" "hdf5: qdc submit meshio_h5.xdmf -o subx.xdmf" data0
else
    fail "hdf5: qdc submit meshio_h5.xdmf" "$(tail -3 "$TMP/subx.out")"
fi

# refused at once (400): a missing part, two .h5 names in the XML, a part
# that is no HDF5 file, a third part, a body cut short
sed 's|meshio_h5.h5:/data1|other.h5:/data1|' "$TMP/meshio_h5.xdmf" > "$TMP/two.xdmf"
head -c 3000 "$TMP/meshio_h5.h5" > "$TMP/cut.h5"
printf -- '--b\r\nContent-Disposition: form-data; name="xdmf"\r\n\r\n<Xdmf' > "$TMP/cutbody"
for c in "nopart no_.h5_part -F xdmf=@$TMP/meshio_h5.xdmf" \
    "noxdmf no_XDMF_part -F h5=@$TMP/meshio_h5.h5" \
    "two two_HDF5_files -F xdmf=@$TMP/two.xdmf -F h5=@$TMP/meshio_h5.h5" \
    "nohdf not_an_HDF5_file -F xdmf=@$TMP/meshio_h5.xdmf -F h5=@$TMP/meshio_h5.xdmf" \
    "third two_.h5_parts -F xdmf=@$TMP/meshio_h5.xdmf -F h5=@$TMP/meshio_h5.h5 -F x=@$TMP/cut.h5" \
    "cutbody not_ended -H Content-Type:multipart/form-data;boundary=b --data-binary @$TMP/cutbody"; do
    set -- $c
    n=$1 want=$(echo "$2" | tr _ ' ')
    shift 2
    code=$(form "$n" "" "$@")
    if [ "$code" = 400 ] && jq -e --arg w "$want" '.detail | contains($w)' "$TMP/form.$n" > /dev/null; then
        pass "hdf5: multipart $n: 400 ($(jf "$TMP/form.$n" .detail | cut -c1-70))"
    else
        fail "hdf5: multipart $n" "$code $(head -c 300 "$TMP/form.$n")"
    fi
done
code=$(form cut "" -F "xdmf=@$TMP/meshio_h5.xdmf" -F "h5=@$TMP/cut.h5")
ID=$(jf "$TMP/form.cut" .id 2> /dev/null)
if [ "$code" = 202 ] && [ "$(wait_done "$ID")" = failed ] &&
    jq -e '.error.status == 400' "$TMP/job.$ID" > /dev/null; then
    pass "hdf5: a cut .h5: job failed with a 400 ($(jf "$TMP/job.$ID" .error.detail | cut -c1-70))"
else
    fail "hdf5: cut .h5" "$code $(head -c 300 "$TMP/job.$ID" 2> /dev/null)"
fi
code=$(submit "$TMP/meshio.xdmf" application/octet-stream "" "$TMP/out")
if [ "$code" = 202 ]; then
    pass "hdf5: an inline XDMF upload is taken (202)"
else
    fail "hdf5: XDMF upload" "$code $(head -c 300 "$TMP/out")"
fi
stop_qdcd

# qdc-h5 over its memory limit: a MED file whose NOE/COO is one gzip chunk
# of 96 MB (zeros: 238 kB on disk) that HDF5 must inflate whole, read under
# the smallest --child-memory (64 MiB): the job fails with a 422 that names
# the limit, and the daemon lives on
if "$PY" - "$TMP/meshio.med" "$TMP/bigchunk.med" 2> "$TMP/bigchunk.err" << 'EOF'; then
import shutil, sys
import h5py
shutil.copy(sys.argv[1], sys.argv[2])
f = h5py.File(sys.argv[2], "r+")
base = "ENS_MAA/" + list(f["ENS_MAA"])[0]
base += "/" + list(f[base])[0]
n = 3 * (1 << 22)
del f[base + "/NOE/COO"]
f.create_dataset(base + "/NOE/COO", shape=(n,), dtype="<f8", chunks=(n,), compression="gzip")
f[base + "/NOE/COO"][0:8] = 0.25  # the chunk written (a chunk never written is not read)
f.close()
EOF
    start_qdcd "$TMP/d2" --workers 1 --child-memory 67108864 ||
        { fail "hdf5: qdcd --child-memory 64 MiB starts" "$(tail -3 "$TMP/d2.log")"; exit 1; }
    if job oom "$TMP/bigchunk.med" "format=med" && [ "$ST" = failed ] &&
        jq -e '.error.status == 422 and (.error.detail | test("qdc-h5.*memory limit \\(67108864 bytes\\)"))' \
            "$TMP/job.$ID" > /dev/null; then
        pass "hdf5: qdc-h5 over --child-memory: job failed with a 422 ($(jf "$TMP/job.$ID" .error.detail | cut -c1-100))"
    else
        fail "hdf5: qdc-h5 memory limit" "$ST $(jq -c .error "$TMP/job.$ID")"
    fi
    curl -sf "$URL/livez" > /dev/null && pass "hdf5: qdcd still answers after the memory kill" ||
        fail "hdf5: livez after the memory kill" "no answer"
    stop_qdcd
else
    pass "hdf5: qdc-h5 memory limit # SKIP python3-h5py missing ($(tail -1 "$TMP/bigchunk.err"))"
fi
exit $NFAIL
