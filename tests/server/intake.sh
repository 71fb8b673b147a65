#!/bin/sh
# intake.sh - the intake keeps the mesh it parsed (DATA/jobs/ID/intake.qmesh)
# and the worker reads that instead of parsing the upload again; the result
# is the same either way:
#  - Gmsh 4.1 ASCII, VTU and JSON uploads (the JSON with fixed vertices: a
#    Gmsh periodic mesh's held pairs) get intake.qmesh, the worker says it read
#    it, and result.qmesh is byte for byte `qdc optimize` of the same file;
#    intake.qmesh is removed when the job ends;
#  - a Medit upload gets none (its result.mesh is spliced from the file);
#  - the same uploads with intake.qmesh deleted, or overwritten with garbage,
#    while queued behind a long job: the worker parses the input and the three
#    results (binary, JSON, Medit) are byte for byte those of the first jobs;
#  - a VTU upload with topology=full gets none (the worker parses it: the run
#    interpolates its point data, which the binary mesh would not hold).
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

BUNNY=$ROOT/tests/data/dev/bunny_low_10k.mesh.gz
PERIODIC=$ROOT/tests/data/real/periodic41.msh.gz
for f in "$BUNNY" "$PERIODIC"; do
    if [ ! -f "$f" ]; then
        echo "ok - intake: the parsed upload kept for the worker # SKIP ${f#$ROOT/} is missing"
        exit 0
    fi
done

gzip -dc "$BUNNY" > "$TMP/b.mesh"
gzip -dc "$PERIODIC" > "$TMP/p.msh"
# b.qmesh drops the Medit file's vertex refs, so b.msh and b.vtu have neither
# vertex refs nor boundary triangles; p.json keeps the periodic pairs' fixed flags
for conv in "b.mesh b.qmesh" "b.qmesh b.msh" "b.qmesh b.vtu" "p.msh p.json"; do
    set -- $conv
    "$BIN/qdc" convert "$TMP/$1" "$TMP/$2" 2> "$TMP/conv.err" ||
        { fail "intake: qdc convert $1 $2" "$(cat "$TMP/conv.err")"; exit 1; }
done
if grep -q '"fixed"' "$TMP/p.json"; then
    pass "intake: the JSON input holds fixed vertices ($(grep -c . "$TMP/p.json") lines)"
else
    fail "intake: the JSON input holds fixed vertices" "no \"fixed\" in p.json"
fi

# name  file  Content-Type
CASES="msh:b.msh:model/vnd.gmsh
vtu:b.vtu:application/vnd.vtk.vtu+xml
json:p.json:application/json"

for c in $CASES; do
    n=${c%%:*}
    f=$(echo "$c" | cut -d: -f2)
    "$BIN/qdc" optimize "$TMP/$f" "$TMP/$n.cli.qmesh" --quiet 2> "$TMP/$n.cli.err" ||
        fail "intake: $n: qdc optimize" "$(cat "$TMP/$n.cli.err")"
done

D=$TMP/d
start_qdcd "$D" --workers 1 --verbose || { fail "intake: qdcd starts" "$(tail -3 "$D.log")"; exit 1; }

# hold_worker: a long job (cancelled later) that holds the one worker; its id
# in HOLD once it runs (wait_running)
hold_worker() {
    submit "$TMP/b.qmesh" application/vnd.qdc.mesh \
        "max_iter=10000&mode=literal&finish=off&tol_move=0&time_limit=60" "$TMP/hold" > /dev/null
    HOLD=$(jf "$TMP/hold" .id)
    wait_running "$HOLD"
}

# 1. the worker reads the intake's mesh
for c in $CASES; do
    n=${c%%:*}
    f=$(echo "$c" | cut -d: -f2)
    t=$(echo "$c" | cut -d: -f3)
    code=$(submit "$TMP/$f" "$t" "" "$TMP/$n.job")
    id=$(jf "$TMP/$n.job" .id)
    st=$(wait_done "$id")
    echo "$id" > "$TMP/$n.id"
    if [ "$code" != 202 ] || [ "$st" != succeeded ]; then
        fail "intake: $n: job" "submit $code, state $st: $(head -c 300 "$TMP/$n.job")"
        continue
    fi
    c1=$(req GET "/v1/jobs/$id/result?format=qmesh" "$TMP/$n.d.qmesh")
    if [ ! -e "$D/jobs/$id/intake.qmesh" ] &&
        grep -q "job $id: input read from intake.qmesh" "$D.log" &&
        [ "$c1" = 200 ] && cmp -s "$TMP/$n.d.qmesh" "$TMP/$n.cli.qmesh"; then
        pass "intake: $n: the worker read intake.qmesh (removed when the job ended); result.qmesh is qdc optimize's, byte for byte"
    else
        fail "intake: $n: worker read intake.qmesh, result as the CLI's" "file $(ls "$D/jobs/$id" | tr '\n' ' '); GET $c1; log: $(grep "job $id" "$D.log" | tail -3)"
    fi
done

# 2. a Medit upload: no intake.qmesh (its result.mesh is spliced from its source)
code=$(submit "$TMP/b.mesh" model/x-medit "" "$TMP/medit.job")
id=$(jf "$TMP/medit.job" .id)
st=$(wait_done "$id")
if [ "$code" = 202 ] && [ "$st" = succeeded ] && [ ! -e "$D/jobs/$id/intake.qmesh" ] &&
    grep -q "job $id: input parsed from input.mesh" "$D.log"; then
    pass "intake: medit: no intake.qmesh, the worker parsed input.mesh"
else
    fail "intake: medit: parsed by the worker" "submit $code, state $st, files $(ls "$D/jobs/$id" | tr '\n' ' ')"
fi

# 3. without it: a long job holds the one worker while the same uploads wait
hold_worker
for c in $CASES; do
    n=${c%%:*}
    f=$(echo "$c" | cut -d: -f2)
    t=$(echo "$c" | cut -d: -f3)
    code=$(submit "$TMP/$f" "$t" "" "$TMP/$n.job2")
    id=$(jf "$TMP/$n.job2" .id)
    echo "$id" > "$TMP/$n.id2"
    q=$D/jobs/$id/intake.qmesh
    st=$(curl -s "$URL/v1/jobs/$id" | jq -r .state)
    if [ "$code" = 202 ] && [ "$st" = queued ] && [ -s "$q" ]; then
        pass "intake: $n: queued with intake.qmesh ($(wc -c < "$q") bytes)"
    else
        fail "intake: $n: queued with intake.qmesh" "submit $code, state $st, files $(ls "$D/jobs/$id" | tr '\n' ' ')"
    fi
    # the JSON one corrupted (a torn or foreign file), the others removed
    if [ "$n" = json ]; then
        head -c 100 "$TMP/b.qmesh" > "$q"
    else
        rm -f "$q"
    fi
done
code=$(req POST "/v1/jobs/$HOLD:cancel" "$TMP/cancel")
[ "$code" = 200 ] || [ "$code" = 202 ] || fail "intake: cancel the long job" "$code $(cat "$TMP/cancel")"
for c in $CASES; do
    n=${c%%:*}
    a=$(cat "$TMP/$n.id")
    b=$(cat "$TMP/$n.id2")
    st=$(wait_done "$b")
    same=1
    for r in result.qmesh result.json result.mesh; do
        cmp -s "$D/jobs/$a/$r" "$D/jobs/$b/$r" || same=0
    done
    if [ "$n" = json ]; then
        how="job $b: intake.qmesh unusable"
    else
        how="job $b: input parsed from input"
    fi
    if [ "$st" = succeeded ] && [ "$same" = 1 ] && grep -q "$how" "$D.log" &&
        ! grep -q "job $b: input read from intake.qmesh" "$D.log"; then
        pass "intake: $n: $(echo "$how" | cut -d' ' -f3-): result.qmesh, .json, .mesh byte for byte those read from intake.qmesh"
    else
        fail "intake: $n: fallback result identical" "state $st, same $same; log: $(grep "job $b" "$D.log" | tail -3)"
    fi
done

# 4. topology=full of a VTU upload: no intake.qmesh (the binary mesh has no
# point data, which the run interpolates); the worker parses input.vtu
hold_worker
code=$(submit "$TMP/b.vtu" application/vnd.vtk.vtu+xml "topology=full" "$TMP/full.job")
id=$(jf "$TMP/full.job" .id)
st=$(curl -s "$URL/v1/jobs/$id" | jq -r .state)
files=$(ls "$D/jobs/$id" | tr '\n' ' ')
req POST "/v1/jobs/$HOLD:cancel" "$TMP/cancel2" > /dev/null
st2=$(wait_done "$id")
if [ "$code" = 202 ] && [ "$st" = queued ] && [ ! -e "$D/jobs/$id/intake.qmesh" ] &&
    case $files in *intake.qmesh*) false ;; *) true ;; esac &&
    [ "$st2" = succeeded ] && grep -q "job $id: input parsed from input.vtu" "$D.log"; then
    pass "intake: vtu topology=full: queued without intake.qmesh, the worker parsed input.vtu"
else
    fail "intake: vtu topology=full: parsed by the worker" "submit $code, $st then $st2, files $files; log: $(grep "job $id" "$D.log" | tail -2)"
fi

stop_qdcd || fail "intake: qdcd stops" "exit status $?"
exit $((NFAIL > 0))
