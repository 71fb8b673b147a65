#!/bin/sh
# topology.sh - qdcd runs topology=flips: a low-quality 20k-tet mesh of
# scripts/corpus.py (the thin bone), uploaded as Medit and as Gmsh 4.1, comes
# back with other tets, the same vertices, none inverted and a higher mean
# ratio than a topology=none job on the same upload; in the upload's own
# format (normally spliced) it is written by qdc's own writer with a Qdc-Note
# saying so, the boundary triangles kept; Abaqus is not offered; the report
# counts the tets in and out and the flips, and the progress stream has the
# "topology" records.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

if ! "$PY" -c 'import numpy, scipy' 2> /dev/null; then
    echo "ok - server topology # SKIP python3-numpy/python3-scipy missing"
    exit 0
fi
if ! "$PY" "$ROOT/scripts/corpus.py" "$TMP/c" --tets 20000 --seed 3 \
    --only bone-lowq > "$TMP/list" 2>&1; then
    fail "server topology: corpus" "scripts/corpus.py failed: $(tail -1 "$TMP/list")"
    exit 1
fi
# the upload: the bone with its boundary triangles (refs 1-3) added, which
# the result must keep
IN=$TMP/bone.mesh
"$PY" - "$TMP/c/bone-lowq.mesh" "$IN" << 'PY'
import os, sys
from collections import Counter
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio
m = meditio.read(sys.argv[1])
t = [tuple(x) for x in m.tets.tolist()]
faces = Counter()
for a, b, c, d in t:
    for f in ((b, c, d), (a, d, c), (a, b, d), (a, c, b)):
        faces[tuple(sorted(f))] += 1
once = [f for f in (tuple(x) for a, b, c, d in t
        for x in ((b, c, d), (a, d, c), (a, b, d), (a, c, b))) if faces[tuple(sorted(f))] == 1]
m.triangles, m.triangle_refs = once, [1 + k % 3 for k in range(len(once))]
m.write(sys.argv[2])
PY
"$BIN/qdc" convert --quiet "$IN" "$TMP/in.msh" ||
    { fail "server topology: convert" "qdc convert failed"; exit 1; }
start_qdcd "$TMP/d" --workers 1 ||
    { fail "server topology: start qdcd" "$(tail -3 "$TMP/d.log")"; exit 1; }

# counts FILE: "vertices tets triangles TRIANGLES" of a Medit file, the last
# a hash of the set of triangles with their refs
counts() {
    "$PY" - "$1" << 'PY'
import hashlib, os, sys
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio
m = meditio.read(sys.argv[1])
# each triangle as its sorted 1-based indices and its ref, all as text
s = sorted(tuple(sorted(str(v + 1) for v in f)) + (str(r),)
           for f, r in zip(m.triangles.tolist(), m.triangle_refs.tolist()))
print(len(m.vertices), len(m.tets), len(m.triangles),
      hashlib.sha256(repr(s).encode()).hexdigest()[:16])
PY
}
# quality FILE: "inverted mean_ratio"
quality() {
    "$BIN/qdc" quality "$1" --json | jq -r '"\(.after.n_inverted) \(.after.mean_ratio_mean)"'
}

# run NAME FILE TYPE TOPOLOGY: submit, wait; the job's id in $TMP/NAME.id
run() {
    code=$(submit "$2" "$3" "topology=$4" "$TMP/$1.sub")
    id=$(jf "$TMP/$1.sub" .id)
    st=$(poll_all "$id")
    cp "$TMP/poll.$id" "$TMP/$1.poll"
    echo "$id" > "$TMP/$1.id"
    if [ "$code" = 202 ] && [ "$st" = succeeded ]; then
        pass "server topology: $1: topology=$4 -> 202, succeeded"
    else
        fail "server topology: $1" "$code $st $(head -c 300 "$TMP/$1.sub") $(tail -3 "$TMP/d.log")"
        return 1
    fi
}

run none "$IN" model/x-medit none || exit 1
run flips "$IN" model/x-medit flips || exit 1
run gflips "$TMP/in.msh" model/vnd.gmsh flips || exit 1
idn=$(cat "$TMP/none.id")
idf=$(cat "$TMP/flips.id")
idg=$(cat "$TMP/gflips.id")

set -- $(counts "$IN")
nv=$1 nt=$2 ntri=$3 trih=$4
req GET "/v1/jobs/$idn/result?format=medit" "$TMP/none.mesh" > /dev/null
set -- $(quality "$TMP/none.mesh")
qn=$2

# NAME:ID:FORMAT: the result in FORMAT, checked read back as Medit
for c in "flips:$idf:medit:medit" "gflips:$idg:gmsh:gmsh" "gflips-mesh:$idg:medit:medit"; do
    name=${c%%:*} rest=${c#*:}
    id=${rest%%:*} rest=${rest#*:}
    fmt=${rest%%:*}
    code=$(req GET "/v1/jobs/$id/result?format=$fmt" "$TMP/$name.out")
    note=$(hdr "$TMP/$name.out" Qdc-Note)
    if [ "$fmt" = medit ]; then
        cp "$TMP/$name.out" "$TMP/$name.mesh"
    else
        mv "$TMP/$name.out" "$TMP/$name.msh"
        "$BIN/qdc" convert --quiet "$TMP/$name.msh" "$TMP/$name.mesh" 2> "$TMP/$name.err" ||
            fail "server topology: $name: read back" "$(cat "$TMP/$name.err")"
    fi
    set -- $(counts "$TMP/$name.mesh")
    v=$1 t=$2 tri=$3 h=$4
    set -- $(quality "$TMP/$name.mesh")
    inv=$1 q=$2
    if [ "$code" = 200 ] && [ "$v" = "$nv" ] && [ "$t" != "$nt" ] && [ "$ntri" -gt 0 ] && [ "$h" = "$trih" ] &&
        [ "$inv" = 0 ] && awk -v a="$q" -v b="$qn" 'BEGIN { exit !(a > b) }'; then
        pass "server topology: $name: $fmt: $nv vertices kept, tets $nt -> $t, the $tri boundary triangles and refs, 0 inverted, mean ratio $qn (none) -> $q"
    else
        fail "server topology: $name: $fmt" "$code: vertices $nv -> $v, tets $nt -> $t, triangles $ntri -> $tri, $inv inverted, mean ratio none $qn flips $q"
    fi
    # the upload's own format is not spliced: the note says so
    case $name:$note in
    gflips-mesh:*) ;;
    *:*topology*) pass "server topology: $name: Qdc-Note: $note" ;;
    *) fail "server topology: $name: Qdc-Note" "'$note'" ;;
    esac
done

# Abaqus and MED come from qdc's own writers (the tets of the flips job,
# read back by qdc; MED through qdc-h5 med-new in the worker's child)
code=$(req GET "/v1/jobs/$idf/result?format=abaqus" "$TMP/abq.inp")
"$BIN/qdc" convert "$TMP/abq.inp" "$TMP/abq.mesh" 2> /dev/null
a=$(counts "$TMP/abq.mesh" 2> /dev/null)
b=$(counts "$TMP/flips.mesh")
if [ "$code" = 200 ] && [ "$a" = "$b" ] && [ "$(quality "$TMP/abq.inp" | cut -d' ' -f1)" = 0 ]; then
    pass "server topology: ?format=abaqus: qdc's Abaqus writer, the flips job's vertices, tets and triangles ($a)"
else
    fail "server topology: abaqus" "$code: '$a' against '$b'"
fi
if [ -x "$BIN/qdc-h5" ]; then
    code=$(req GET "/v1/jobs/$idf/result?format=med" "$TMP/flips.med")
    "$BIN/qdc" convert "$TMP/flips.med" "$TMP/med.mesh" 2> /dev/null
    a=$(counts "$TMP/med.mesh" 2> /dev/null)
    if [ "$code" = 200 ] && [ "$a" = "$b" ] && [ "$(quality "$TMP/flips.med" | cut -d' ' -f1)" = 0 ] &&
        cmp -s "$TMP/med.mesh" "$TMP/flips.mesh"; then
        pass "server topology: ?format=med: qdc's MED writer, read back as the flips job's Medit result ($a)"
    else
        fail "server topology: med" "$code: '$a' against '$b' $(head -c 200 "$TMP/flips.med")"
    fi
else
    pass "server topology: ?format=med # SKIP qdc-h5 not built (libhdf5-dev missing)"
fi

# the report counts the tets in and out and the operations; progress has
# the topology records
req GET "/v1/jobs/$idf/report" "$TMP/rep" > /dev/null
t=$(jf "$TMP/rep" '.run.topology.tets_out')
set -- $(counts "$TMP/flips.mesh")
jcheck "$TMP/rep" ".options.topology == \"flips\" and .run.topology.tets_in == $nt and .run.topology.tets_out == $2 and .run.topology.edge_removals + .run.topology.flips23 + .run.topology.multiface_removals > 0" \
    "server topology: report" "server topology: report: topology flips, tets $nt -> $t, flips counted"
curl -s "$URL/v1/jobs/$idf/progress?after=-1" > "$TMP/prog"
jcheck "$TMP/prog" "[.records[] | select(.phase == \"topology\")] as \$t | (\$t | length > 0) and (\$t | all(.operations > 0 and .n_tets > 0)) and \$t[-1].n_tets == $2" \
    "server topology: progress" "server topology: progress: records of phase topology with the tets after each round and its flips"

stop_qdcd || fail "server topology: stop" "exit $?"
exit $((NFAIL > 0))
