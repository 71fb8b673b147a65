#!/bin/sh
# batch.sh - clients/batch/qdc-batch.sh over a folder of 5 dev meshes (gzipped
# and plain), 3 at a time: every result valid, every report present, the
# summary CSV complete; the same with sed instead of jq; a bad mesh gives a
# "rejected" row and exit 1.
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

QDC_BATCH_JQ=0 sh "$BATCH" -s "$URL" -j 2 -Q -q 'max_iter=1&finish=off' -o "$TMP/out2" "$TMP/in" 2> "$TMP/batch2.err"
rc=$?
[ $rc = 0 ] && [ "$(wc -l < "$TMP/batch2.err")" = 1 ] && pass "batch (sed, -Q): exit 0, one summary line" ||
    fail "batch sed rc" "rc $rc $(tail -3 "$TMP/batch2.err")"
check_run "$TMP/out2" "batch (sed)"
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
stop_qdcd
exit 0
