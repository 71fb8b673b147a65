#!/bin/sh
# cancel.sh - a job cancelled while the optimizer runs keeps the best mesh so
# far, as `qdc optimize` does on Ctrl-C: state cancelled, with a result in
# every format and a report whose after is the result's quality; one
# cancelled before it started has none (409 no-result).
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"
MESH=$(devmesh bunny_low_10k)
LONG="mode=literal&max_iter=10000&finish=off&tol_move=0&stall=0&time_limit=120"

start_qdcd "$TMP/d" --workers 1 || { fail "start" "$(tail -3 "$TMP/d.log")"; exit 1; }
code=$(submit "$MESH" model/x-medit "$LONG" "$TMP/a")
A=$(jf "$TMP/a" .id)
code2=$(submit "$MESH" model/x-medit "max_iter=2" "$TMP/b")
B=$(jf "$TMP/b" .id)
# a few records, then cancel both (B is still queued behind A)
i=0
while [ $i -lt 600 ] && [ "$(curl -s "$URL/v1/jobs/$A" | jq -r '.iterations // 0')" -lt 4 ]; do
    sleep 0.1
    i=$((i + 1))
done
cb=$(req POST "/v1/jobs/$B:cancel" "$TMP/cb")
ca=$(req POST "/v1/jobs/$A:cancel" "$TMP/ca")
sa=$(wait_done "$A")
sb=$(wait_done "$B")
curl -s "$URL/v1/jobs/$A" > "$TMP/ja"
ra=$(req GET "/v1/jobs/$A/result?format=medit" "$TMP/ra.mesh")
rr=$(req GET "/v1/jobs/$A/report" "$TMP/rep.json")
rq=$(req GET "/v1/jobs/$A/result?format=qmesh" "$TMP/ra.qmesh")
"$BIN/qdc" quality "$TMP/ra.mesh" > "$TMP/q" 2>&1
nt=$(jq -r .after.n_tets "$TMP/rep.json")
mr=$(jq -r '.after.mean_ratio_mean' "$TMP/rep.json")
if [ "$code $code2 $ca $cb" = "202 202 200 200" ] && [ "$sa $sb" = "cancelled cancelled" ] &&
    jq -e '.links.result and .links.report and .stop_reason == "cancelled" and .iterations >= 4' "$TMP/ja" > /dev/null &&
    [ "$ra $rr $rq" = "200 200 200" ] && grep -q " $nt tets, 0 inverted" "$TMP/q" &&
    grep -q "mean ratio: mean $(printf %.4f "$mr")" "$TMP/q" &&
    jq -e '.after.mean_ratio_mean > .before.mean_ratio_mean' "$TMP/rep.json" > /dev/null; then
    pass "cancelled after $(jf "$TMP/ja" .iterations) records: state cancelled with links to a result and a report; the result ($nt tets, 0 inverted, mean ratio $(printf %.4f "$mr")) is the report's after, better than the input"
else
    fail "cancel keeps the best mesh" "submit $code $code2, cancel $ca $cb, states $sa $sb, result $ra report $rr qmesh $rq; $(head -c 300 "$TMP/ja") $(head -2 "$TMP/q")"
fi
curl -s "$URL/v1/jobs/$B" > "$TMP/jb"
rb=$(req GET "/v1/jobs/$B/result" "$TMP/rb")
if [ "$rb" = 409 ] && jq -e '.type | endswith("no-result")' "$TMP/rb" > /dev/null && jq -e '.links | has("result") | not' "$TMP/jb" > /dev/null; then
    pass "cancelled before it started: no result (409 no-result, no result link)"
else
    fail "cancel queued" "$rb $(head -c 200 "$TMP/rb")"
fi
# the qdc client fetches the cancelled job's result, says so, exits 11
"$BIN/qdc" fetch "$A" --server "$URL" -o "$TMP/f.mesh" > "$TMP/f.out" 2>&1
rc=$?
if [ $rc = 11 ] && cmp -s "$TMP/f.mesh" "$TMP/ra.mesh" && grep -q "cancelled: what was written is its best mesh so far" "$TMP/f.out"; then
    pass "qdc fetch of the cancelled job writes its result, says it is the best mesh so far, exit 11"
else
    fail "qdc fetch cancelled" "exit $rc: $(tail -2 "$TMP/f.out")"
fi
stop_qdcd
exit $((NFAIL > 0))
