#!/bin/sh
# outcome.sh - the outcome in words (docs/defaults.md): `qdc optimize` ends with
# an "outcome:" line, then a warning and a suggestion when much is left bad; the
# report's "outcome" holds the same texts. A tangled cube after one global
# iteration and no finishing pass leaves tets inverted and slivers (warned, with
# --topology suggested); the sample cube optimized as usual gets no warning.
. "$(dirname "$0")/../lib.sh"

"$BIN/qdc" optimize "$DEV/cube_h0.1_tangled.mesh.gz" "$TMP/bad.mesh" --max-iter 1 \
    --finish off --report "$TMP/bad.json" 2> "$TMP/bad.err"
rc=$?
tail -6 "$TMP/bad.err" > "$TMP/bad.tail"
summary=$(jq -r .outcome.summary "$TMP/bad.json")
if [ $rc = 0 ] && grep -qxF "qdc: outcome: $summary" "$TMP/bad.tail" &&
    grep -q "^qdc: warning: [0-9]* tets are left inverted$" "$TMP/bad.tail" &&
    grep -q "^qdc: suggestion: try --topology flips" "$TMP/bad.tail" &&
    jq -e '.outcome as $o | ($o.warnings | length) >= 2 and ($o.suggestions[0] | startswith("try --topology flips"))
        and $o.left_bad.n_inverted == .after.n_inverted and $o.left_bad.n_inverted > 0
        and $o.left_bad.n_dihedral_lt_5 == .after.n_dmin_lt_5
        and $o.left_bad.worst_mean_ratio == .after.mean_ratio_min
        and ($o.summary | contains("under 5°"))' "$TMP/bad.json" > /dev/null; then
    pass "outcome: a bad result ends with its outcome, warnings and --topology suggested, the same in the report ($(jq -r .outcome.left_bad.n_inverted "$TMP/bad.json") inverted)"
else
    fail "outcome: bad" "rc $rc $(cat "$TMP/bad.tail") $(jq -c .outcome "$TMP/bad.json" 2>&1 | head -c 600)"
fi
# every printed warning and suggestion is the report's, in its order
jq -r '.outcome | (.warnings[] | "qdc: warning: " + .), (.suggestions[] | "qdc: suggestion: " + .)' \
    "$TMP/bad.json" > "$TMP/bad.want"
grep "^qdc: \(warning\|suggestion\): " "$TMP/bad.err" > "$TMP/bad.got"
cmp -s "$TMP/bad.want" "$TMP/bad.got" && pass "outcome: the CLI prints the report's warnings and suggestions word for word" ||
    fail "outcome: words" "$(diff "$TMP/bad.want" "$TMP/bad.got" | head -5)"

# a good mesh: no warning, and the outcome is the last line
"$BIN/qdc" optimize "$ROOT/tests/data/sample/cube.mesh" "$TMP/good.mesh" --report "$TMP/good.json" 2> "$TMP/good.err"
rc=$?
if [ $rc = 0 ] && tail -1 "$TMP/good.err" | grep -q "^qdc: outcome: mean ratio .* -> .*, worst tet .*; left: 0 of [0-9]* tets under 5° and 0 over 175° dihedral, 0 inverted; worst tet [0-9]* (from 0) at (.*), mean ratio +0\.[0-9]*; boundary moved" &&
    ! grep -q "^qdc: \(warning\|suggestion\):" "$TMP/good.err" &&
    jq -e '.outcome.warnings == [] and .outcome.suggestions == [] and .outcome.left_bad.n_inverted == 0' "$TMP/good.json" > /dev/null; then
    pass "outcome: a good result's last line is its outcome, no warning"
else
    fail "outcome: good" "rc $rc $(tail -3 "$TMP/good.err")"
fi
# without --report: the same lines from a scan of the result (the boundary distance not measured)
"$BIN/qdc" optimize "$DEV/cube_h0.1_tangled.mesh.gz" "$TMP/bad2.mesh" --max-iter 1 --finish off 2> "$TMP/bad2.err"
grep "^qdc: \(warning\|suggestion\): " "$TMP/bad2.err" | grep -v "looser --hausd" > "$TMP/bad2.got"
grep -v "looser --hausd" "$TMP/bad.got" > "$TMP/bad.nobound"
cmp -s "$TMP/bad.nobound" "$TMP/bad2.got" && grep -q "^qdc: outcome: .*boundary bound .* (distance not measured)$" "$TMP/bad2.err" &&
    pass "outcome: without --report the same warnings and suggestions (the boundary's distance not measured)" ||
    fail "outcome: no report" "$(diff "$TMP/bad.nobound" "$TMP/bad2.got" | head -5) $(grep outcome "$TMP/bad2.err")"
# -q: nothing printed
"$BIN/qdc" optimize "$DEV/cube_h0.1_tangled.mesh.gz" "$TMP/bad3.mesh" --max-iter 1 --finish off -q 2> "$TMP/bad3.err"
[ ! -s "$TMP/bad3.err" ] && pass "outcome: -q prints no outcome" || fail "outcome: quiet" "$(head -2 "$TMP/bad3.err")"

# one iteration count (docs/defaults.md): a tangled bunny without the finishing
# pass runs again from the input (its records go on, "rerun"); the summary's N
# iterations, the report's run.iterations and the last progress line's number
# agree, the lines are numbered 0..N, and the record run.best_iteration names is
# the result (its printed mean ratio and worst are the report's after)
"$BIN/qdc" optimize "$DEV/bunny_tangled-low_10k.mesh.gz" "$TMP/rr.mesh" --finish off \
    --report "$TMP/rr.json" 2> "$TMP/rr.err"
grep '^[a-z]* *[0-9]* *q mean' "$TMP/rr.err" | awk '{ print $1, $2, $5, $7 }' > "$TMP/rr.recs"
n=$(jq .run.iterations "$TMP/rr.json")
best=$(jq .run.best_iteration "$TMP/rr.json")
want=$(jq -r '"\(.after.mean_ratio_mean * 10000 | round / 10000) \(.after.mean_ratio_min * 10000 | round / 10000)"' "$TMP/rr.json")
got=$(awk -v b="$best" '$2 == b { printf "%g %g", $3, $4 }' "$TMP/rr.recs")
if [ "$(awk '{ print $2 }' "$TMP/rr.recs" | tr '\n' ' ')" = "$(seq 0 "$n" | tr '\n' ' ')" ] &&
    grep -q "^rerun " "$TMP/rr.recs" && grep -q "(converged, $n iterations, " "$TMP/rr.err" &&
    [ "$best" -le "$n" ] && [ "$got" = "$(echo "$want" | awk '{ printf "%g %g", $1, $2 }')" ]; then
    pass "iterations: a run with reruns numbers its records 0..$n, the summary and the report say $n, the best record ($best) is the result"
else
    fail "iterations" "n $n best $best got '$got' want '$want' $(grep -c . "$TMP/rr.recs") records, $(grep -o '([a-z-]*, [0-9]* iterations' "$TMP/rr.err")"
fi
exit $((NFAIL > 0))
