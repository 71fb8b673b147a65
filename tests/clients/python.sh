#!/bin/sh
# python.sh - clients/python/qdc_client.py against a real qdcd: the module
# (tests/clients/python_client.py) and its command line. With qdc-h5 built,
# meshio_h5.xdmf + meshio_h5.h5 go as one multipart/form-data upload and the
# result comes back as pyx.xdmf + pyx.h5 (read by `qdc convert`; h5py, when
# installed, finds only the coordinates changed); an .xmf pair likewise, and
# the job's record ("h5": true) tells such a job from an inline one.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
PYC=$ROOT/clients/python/qdc_client.py

MESH=$(devmesh bunny_low_10k)
BIG=$(devmesh bunny_low_100k)
$MT qmesh "$MESH" "$TMP/in.qmesh"
start_qdcd "$TMP/d" --workers 2 || { fail "start" "qdcd did not come up: $(tail -3 "$TMP/d.log")"; exit 1; }

H5=0 H5PY=0
[ -x "$BIN/qdc-h5" ] && H5=1
"$PY" -c 'import h5py' 2> /dev/null && H5PY=1
export URL TMP MESH BIG ROOT H5 H5PY
MESHQ=$TMP/in.qmesh NT=9033 QDC=$BIN/qdc $PY "$ROOT/tests/clients/python_client.py" ||
    echo "# python_client.py exited $?"

# the command line: submit -o --report, then fetch and status by id
id=$($PY "$PYC" --server "$URL" submit "$MESH" --opt max_iter=2 -o "$TMP/cli.mesh" --report "$TMP/cli.json" 2> "$TMP/cli.err")
rc=$?
if [ $rc = 0 ] && "$BIN/qdc" quality "$TMP/cli.mesh" | grep -q ' 9033 tets, 0 inverted' &&
    [ "$(jq -r .after.n_tets "$TMP/cli.json")" = 9033 ] && grep -q 'q mean' "$TMP/cli.err"; then
    pass "python CLI: submit -o --report (progress on stderr, result valid)"
else
    fail "python CLI submit" "rc $rc $(tail -3 "$TMP/cli.err")"
fi
QDC_SERVER=$URL $PY "$PYC" fetch "$id" -o "$TMP/cli2.json" && QDC_SERVER=$URL $PY "$PYC" status "$id" > "$TMP/st.json" &&
    [ "$(jq -r .state "$TMP/st.json")" = succeeded ] && "$BIN/qdc" quality "$TMP/cli2.json" > /dev/null &&
    pass "python CLI: fetch (JSON) and status with QDC_SERVER" || fail "python CLI fetch" "$(cat "$TMP/st.json")"
# --label and --name; the outcome in words ends what it prints, the report's texts
id3=$($PY "$PYC" --server "$URL" submit "$MESH" --opt max_iter=1 --opt finish=off --label "cli label" --wait 2> "$TMP/cli3.err")
curl -s "$URL/v1/jobs/$id3" > "$TMP/j3"
curl -s "$URL/v1/jobs/$id3/report" | jq -r '.outcome | "qdc: outcome: " + .summary, (.warnings[] | "qdc: warning: " + .), (.suggestions[] | "qdc: suggestion: " + .)' > "$TMP/want3"
if jq -e --arg n "$(basename "$MESH")" '.label == "cli label" and .file_name == $n' "$TMP/j3" > /dev/null &&
    grep "^qdc: \(outcome\|warning\|suggestion\): " "$TMP/cli3.err" | cmp -s - "$TMP/want3" && [ -s "$TMP/want3" ]; then
    pass "python CLI: submit --label sends the label and the file's name; --wait ends with the report's outcome ($(wc -l < "$TMP/want3") lines)"
else
    fail "python CLI label" "$(jq -c '[.label, .file_name]' "$TMP/j3") $(tail -3 "$TMP/cli3.err")"
fi
$PY "$PYC" --server "$URL" jobs | grep -q "^$id3 succeeded cli label (" && pass "python CLI: jobs shows the label and file name" ||
    fail "python CLI jobs" "$($PY "$PYC" --server "$URL" jobs | grep "$id3")"
$PY "$PYC" --server "$URL" submit "$MESH" --opt metric=nope 2> /dev/null
[ $? = 10 ] && pass "python CLI: rejected request exits 10" || fail "python CLI exit" "not 10"
stop_qdcd
exit 0
