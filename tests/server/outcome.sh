#!/bin/sh
# outcome.sh - the outcome in words through qdcd (docs/defaults.md): a job's
# report holds the "outcome" qdc optimize prints; a bad result (a tangled cube
# after one global iteration, no finishing pass) is warned with --topology
# suggested, a good one (the sample cube) is not; `qdc status` prints the
# outcome under the job's line and `qdc fetch` ends with it, word for word.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"
MT=model/x-medit

start_qdcd "$TMP/d" --workers 1 || { fail "start" "$(tail -3 "$TMP/d.log")"; exit 1; }
submit "$(devmesh cube_h0.1_tangled)" $MT "max_iter=1&finish=off" "$TMP/a" > /dev/null
A=$(jf "$TMP/a" .id)
submit "$ROOT/tests/data/sample/cube.mesh" $MT "" "$TMP/b" > /dev/null
B=$(jf "$TMP/b" .id)
sa=$(wait_done "$A")
sb=$(wait_done "$B")
curl -s "$URL/v1/jobs/$A/report" > "$TMP/ra"
curl -s "$URL/v1/jobs/$B/report" > "$TMP/rb"
if [ "$sa $sb" = "succeeded succeeded" ] &&
    jq -e '.outcome as $o | ($o.warnings | length) >= 2 and ($o.suggestions[0] | startswith("try --topology flips"))
        and $o.left_bad.n_inverted == .after.n_inverted and $o.left_bad.n_inverted > 0
        and ($o.summary | contains("boundary moved"))' "$TMP/ra" > /dev/null &&
    jq -e '.outcome.warnings == [] and .outcome.suggestions == [] and (.outcome.summary | length) > 50' "$TMP/rb" > /dev/null; then
    pass "outcome: the report through qdcd warns on a bad result ($(jf "$TMP/ra" .outcome.left_bad.n_inverted) inverted, --topology suggested), not on a good one"
else
    fail "outcome: report" "$sa $sb $(jq -c .outcome "$TMP/ra" | head -c 400) $(jq -c .outcome.warnings "$TMP/rb")"
fi

# the CLI: status lists the outcome under the job's line, fetch ends with it
jq -r '.outcome | "outcome: " + .summary, (.warnings[] | "warning: " + .), (.suggestions[] | "suggestion: " + .)' "$TMP/ra" > "$TMP/want"
"$BIN/qdc" status "$A" --server "$URL" > "$TMP/status" 2>&1
"$BIN/qdc" fetch "$A" --server "$URL" -o "$TMP/a.mesh" 2> "$TMP/fetch.err"
sed -n '2,$s/^  //p' "$TMP/status" > "$TMP/got.status"
sed -n 's/^qdc: \(outcome\|warning\|suggestion\): /\1: /p' "$TMP/fetch.err" > "$TMP/got.fetch"
if cmp -s "$TMP/want" "$TMP/got.status" && cmp -s "$TMP/want" "$TMP/got.fetch" && [ -s "$TMP/a.mesh" ]; then
    pass "outcome: qdc status and qdc fetch print the report's outcome, warnings and suggestions word for word ($(wc -l < "$TMP/want") lines)"
else
    fail "outcome: cli" "$(diff "$TMP/want" "$TMP/got.status" | head -3) / $(diff "$TMP/want" "$TMP/got.fetch" | head -3)"
fi
"$BIN/qdc" status "$B" --server "$URL" > "$TMP/statusb" 2>&1
[ "$(grep -c '^  outcome: ' "$TMP/statusb")" = 1 ] && ! grep -q "^  \(warning\|suggestion\):" "$TMP/statusb" &&
    pass "outcome: qdc status of a good result: its outcome, no warning" || fail "outcome: status good" "$(cat "$TMP/statusb")"
# one iteration count (docs/defaults.md): the job's, the report's and the last
# record's number agree; the record kept is one of them
bad=
for id in "$A" "$B"; do
    curl -s "$URL/v1/jobs/$id" > "$TMP/j.$id"
    curl -s "$URL/v1/jobs/$id/report" > "$TMP/r.$id"
    curl -s "$URL/v1/jobs/$id/progress?after=-1" > "$TMP/p.$id"
    it=$(jf "$TMP/j.$id" .iterations)
    [ "$it" = "$(jf "$TMP/r.$id" .run.iterations)" ] && [ "$it" = "$(jq '.records[-1].iteration' "$TMP/p.$id")" ] &&
        [ "$it" = "$(jq '.records | length - 1' "$TMP/p.$id")" ] &&
        jq -e --argjson n "$it" '.run.best_iteration <= $n and .run.global_iterations <= $n' "$TMP/r.$id" > /dev/null ||
        bad="$bad $id: job $it, report $(jq -c '.run | [.iterations, .best_iteration, .global_iterations]' "$TMP/r.$id"), records $(jq '.records | length' "$TMP/p.$id")"
done
"$BIN/qdc" status "$A" --server "$URL" | head -1 | grep -q " $(jf "$TMP/j.$A" .iterations) it " || bad="$bad status: $("$BIN/qdc" status "$A" --server "$URL" | head -1)"
[ -z "$bad" ] && pass "iterations: the job's, the report's, qdc status's and the last record's number agree ($(jf "$TMP/j.$A" .iterations) and $(jf "$TMP/j.$B" .iterations))" ||
    fail "iterations" "$bad"
stop_qdcd
exit $((NFAIL > 0))
