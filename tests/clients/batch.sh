#!/bin/sh
# batch.sh - clients/batch/qdc-batch.sh over a folder of 5 dev meshes (gzipped
# and plain), 3 at a time: every result valid, every report present, the
# summary CSV complete; the same with sed instead of jq; a bad mesh gives a
# "rejected" row and exit 1; nine files of other tools come back in their own
# format byte for byte as qdc optimize writes them; two meshes of one name are
# refused.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
BATCH=$ROOT/clients/batch/qdc-batch.sh

mkdir -p "$TMP/in" "$TMP/bad"
for m in bunny_low_10k bunny_tangled-low_10k bunny_good_10k bracket_h0.1_good; do
    cp "$DEV/$m.mesh.gz" "$TMP/in/"
done
gzip -dc "$DEV/cube_h0.1_good.mesh.gz" > "$TMP/in/cube_h0.1_good.mesh"
printf 'MeshVersionFormatted 1\nDimension 3\nVertices\n1\n0 0 nan 0\nEnd\n' > "$TMP/bad/broken.mesh"

start_qdcd "$TMP/d" --workers 2 || { fail "start" "qdcd did not come up: $(tail -3 "$TMP/d.log")"; exit 1; }

# check_run OUTDIR LABEL: results, reports and CSV of one run
check_run() {
    o=$1
    csv=$o/summary.csv
    rows=$(($(wc -l < "$csv") - 1))
    cols=$(awk -F, '{ print NF }' "$csv" | sort -u | tr '\n' ' ')
    nok=$(grep -c ',succeeded,' "$csv")
    empty=$(awk -F, 'NR > 1 { for (i = 4; i <= 12; i++) if ($i == "") n++ } END { print n + 0 }' "$csv")
    bad=
    for f in bunny_low_10k bunny_tangled-low_10k bunny_good_10k bracket_h0.1_good cube_h0.1_good; do
        want=$(gzip -dc "$DEV/$f.mesh.gz" | awk '/^Tetrahedra/ { getline; print; exit }')
        "$BIN/qdc" quality "$o/$f.mesh" > "$TMP/q" 2>&1 && grep -q " $want tets" "$TMP/q" || bad="$bad $f.mesh"
        [ "$(jq -r .after.n_tets "$o/$f.report.json" 2> /dev/null)" = "$want" ] || bad="$bad $f.report.json"
        grep -q "^$f.mesh[^,]*,[0-9a-f]\{32\},succeeded,$want," "$csv" || bad="$bad csv:$f"
    done
    if [ "$rows" = 5 ] && [ "$cols" = "16 " ] && [ "$nok" = 5 ] && [ "$empty" = 0 ] && [ -z "$bad" ]; then
        pass "$2: 5 results valid, 5 reports, summary.csv 5 rows x 16 columns, all filled"
    else
        fail "$2" "rows $rows cols '$cols' ok $nok empty $empty bad:$bad $(head -3 "$csv")"
    fi
}

t0=$(date +%s)
sh "$BATCH" -s "$URL" -j 3 -q 'max_iter=2' -o "$TMP/out" "$TMP/in" 2> "$TMP/batch.err"
rc=$?
dt=$(($(date +%s) - t0))
[ $rc = 0 ] && pass "batch (jq): exit 0 in $dt s" || fail "batch rc" "rc $rc $(tail -3 "$TMP/batch.err")"
check_run "$TMP/out" "batch (jq)"
n=$(grep -c ': \(global\|finish\|input\) .*q mean' "$TMP/batch.err")
[ "$n" -ge 5 ] && pass "batch: $n progress lines followed by long-poll" || fail "batch progress" "$(head -5 "$TMP/batch.err")"
njobs=$(curl -s "$URL/v1/jobs" | jq '.jobs | length')
[ "$njobs" = 5 ] && pass "batch: 5 jobs made, one per mesh" || fail "batch jobs" "$njobs jobs"

# each job carries its file's name (GET /v1/jobs/ID), no label unless -l
ls "$TMP/in" | sort > "$TMP/names.want"
curl -s "$URL/v1/jobs?page_size=100" | jq -r '.jobs[].id' | while read -r id; do
    curl -s "$URL/v1/jobs/$id" | jq -r 'if has("label") then "label!" else .file_name end'
done | sort > "$TMP/names.got"
cmp -s "$TMP/names.want" "$TMP/names.got" && pass "batch: every job has its file's name (GET /v1/jobs/ID), no label" ||
    fail "batch names" "$(diff "$TMP/names.want" "$TMP/names.got" | head -4)"

QDC_BATCH_JQ=0 sh "$BATCH" -s "$URL" -j 2 -Q -l "second run é&=" -q 'max_iter=1&finish=off' -o "$TMP/out2" "$TMP/in" 2> "$TMP/batch2.err"
rc=$?
[ $rc = 0 ] && [ "$(wc -l < "$TMP/batch2.err")" = 1 ] && pass "batch (sed, -Q): exit 0, one summary line" ||
    fail "batch sed rc" "rc $rc $(tail -3 "$TMP/batch2.err")"
check_run "$TMP/out2" "batch (sed)"
curl -s "$URL/v1/jobs?page_size=100" | jq -r '.jobs[].id' | while read -r id; do
    curl -s "$URL/v1/jobs/$id" | jq -r 'select(.label == "second run é&=") | .file_name'
done | sort > "$TMP/names2.got"
cmp -s "$TMP/names.want" "$TMP/names2.got" && pass "batch -l: the label (UTF-8, & and =) and the file's name on every job of the run" ||
    fail "batch label" "$(diff "$TMP/names.want" "$TMP/names2.got" | head -4)"
# input-derived columns agree between the jq and the sed runs
c1=$(cut -d, -f1,4,6,8,10 "$TMP/out/summary.csv" | sort)
c2=$(cut -d, -f1,4,6,8,10 "$TMP/out2/summary.csv" | sort)
[ "$c1" = "$c2" ] && pass "batch: jq and sed read the same input quality" || fail "batch jq/sed" "$c1 / $c2"

sh "$BATCH" -s "$URL" -Q -o "$TMP/out3" "$TMP/bad" 2> /dev/null
rc=$?
if [ $rc = 1 ] && grep -q '^broken.mesh,,rejected:400,' "$TMP/out3/summary.csv" &&
    [ "$(awk -F, 'NR == 2 { print NF }' "$TMP/out3/summary.csv")" = 16 ]; then
    pass "batch: a malformed mesh gives a rejected:400 row with the reason, exit 1"
else
    fail "batch bad" "rc $rc $(cat "$TMP/out3/summary.csv")"
fi
sh "$BATCH" -s "$URL" -o "$TMP/in" "$TMP/in" 2> /dev/null
[ $? = 2 ] && pass "batch: OUTDIR = DIR refused (exit 2)" || fail "batch outdir" "not refused"

# files of other tools, each sent as it is (by media type, or named in the
# query): with the default -f same, each result is the file written back
# with only its coordinates replaced, byte for byte what qdc optimize writes
mkdir -p "$TMP/real"
bad=
n=0
REALS="gmsh41.msh gmsh22_bin.msh gmsh40.msh gmsh.vtk meshio_zlib.vtu meshio.meshb dolfin.xml calculix.inp netgen.vol"
for f in $REALS; do
    cp "$ROOT/tests/data/real/$(echo "$f" | sed 's/^netgen.vol$/meshio.vol/').gz" "$TMP/real/$f.gz"
    gzip -dc "$TMP/real/$f.gz" > "$TMP/src.$f"
    "$BIN/qdc" optimize "$TMP/src.$f" "$TMP/local.$f" --max-iter 2 --quiet || bad="$bad $f:local"
    n=$((n + 1))
done
sh "$BATCH" -s "$URL" -Q -q 'max_iter=2' -o "$TMP/out4" "$TMP/real" 2> "$TMP/batch4.err"
rc=$?
for f in $REALS; do
    cmp -s "$TMP/out4/$f" "$TMP/local.$f" || bad="$bad $f"
done
[ $rc = 0 ] && [ -z "$bad" ] && pass "batch: $n files of other tools (Gmsh 4.1, 2.2 binary, 4.0, VTK, VTU, Medit binary, DOLFIN, Abaqus, Netgen; gzipped) come back in their own format, byte for byte as qdc optimize writes them" ||
    fail "batch other tools" "rc $rc, differ:$bad $(tail -2 "$TMP/batch4.err")"
cp "$ROOT/tests/data/real/gmsh.mesh.gz" "$TMP/real/gmsh41.mesh.gz"
sh "$BATCH" -s "$URL" -Q -o "$TMP/out5" "$TMP/real" 2> "$TMP/batch5.err"
rc=$?
[ $rc = 2 ] && grep -q 'named gmsh41' "$TMP/batch5.err" && [ ! -e "$TMP/out5/summary.csv" ] &&
    pass "batch: two meshes of one name (gmsh41.msh.gz, gmsh41.mesh.gz) refused before any job (exit 2): $(cat "$TMP/batch5.err")" ||
    fail "batch name clash" "rc $rc $(cat "$TMP/batch5.err")"
stop_qdcd
exit 0
