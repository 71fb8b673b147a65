#!/bin/sh
# longpoll.sh - 200 concurrent long-polls held while a job runs: every client
# receives every record after its starting point, in order; they park as
# suspended connections, so the daemon's thread count does not move.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

MESH=$(devmesh cube_h0.1_lowq)
$MT qmesh "$MESH" "$TMP/in.qmesh"
start_qdcd "$TMP/d" --workers 2 || { fail "start" "$(tail -3 "$TMP/d.log")"; exit 1; }
code=$(submit "$TMP/in.qmesh" application/vnd.qdc.mesh "max_iter=10" "$TMP/sub")
id=$(jf "$TMP/sub" .id)
# start once the run is under way (its first record is out)
curl -s -m 30 "$URL/v1/jobs/$id/progress?after=-1&wait=20" > /dev/null
$PY "$ROOT/tests/server/pollers.py" "$URL" "$id" 200 "$QPID" > "$TMP/res.json" 2> "$TMP/res.err"
if [ "$code" = 202 ] && jq -e '.complete == 200 and .errors == 0 and .last > .start + 3' "$TMP/res.json" > /dev/null; then
    pass "200 long-polls: all got every record $(jf "$TMP/res.json" '"\(.start + 1)..\(.last)"') in order ($(jf "$TMP/res.json" .requests) round trips)"
else
    fail "200 long-polls" "$(cat "$TMP/res.json") $(head -3 "$TMP/res.err")"
fi
if jq -e '.parked_max >= 150' "$TMP/res.json" > /dev/null; then
    pass "they were parked together: up to $(jf "$TMP/res.json" .parked_max) suspended connections at once"
else
    fail "parked" "$(cat "$TMP/res.json")"
fi
if jq -e '.threads_max <= .threads_before' "$TMP/res.json" > /dev/null; then
    pass "thread count flat: $(jf "$TMP/res.json" .threads_before) before, at most $(jf "$TMP/res.json" .threads_max) with 200 waiting"
else
    fail "thread count" "$(cat "$TMP/res.json")"
fi
# wait=N returns after N seconds with the state unchanged when nothing happens
curl -s -m 10 "$URL/v1/jobs/$id/progress?after=100000&wait=1" > "$TMP/p"
if [ "$(jf "$TMP/p" .count)" = 0 ] && [ "$(jf "$TMP/p" .done)" = true ]; then
    pass "a finished job answers at once (done, nothing after the last record)"
else
    fail "finished job poll" "$(cat "$TMP/p")"
fi
stop_qdcd || fail "SIGTERM" "exit status $?"
exit $((NFAIL > 0))
