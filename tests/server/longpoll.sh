#!/bin/sh
# longpoll.sh - 200 concurrent long-polls held while a job runs: every client
# receives every record after its starting point, in order; they park as
# suspended connections, so the daemon's thread count does not move. Then what
# parked polls cost (RSS), clients hanging up while parked, SSE keep-alive.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

MESH=$(devmesh cube_h0.1_lowq)
$MT qmesh "$MESH" "$TMP/in.qmesh"
start_qdcd "$TMP/d" --workers 2 || { fail "start" "$(tail -3 "$TMP/d.log")"; exit 1; }
# every one of the 40 iterations (no stall or move rule ends the run early), so
# that records keep coming after the 200 pollers have started: with the stall
# rule the run had 7 records (0-6), and on a loaded machine the pollers once
# started after the 4th (a fresh-clone CI: start 3, last 6)
code=$(submit "$TMP/in.qmesh" application/vnd.qdc.mesh "max_iter=40&stall=0&tol_move=0" "$TMP/sub")
id=$(jf "$TMP/sub" .id)
# start once the run is under way (its first record is out)
curl -s -m 30 "$URL/v1/jobs/$id/progress?after=-1&wait=20" > /dev/null
$PY "$ROOT/tests/server/pollers.py" "$URL" "$id" 200 "$QPID" > "$TMP/res.json" 2> "$TMP/res.json.err"
[ "$code" = 202 ] || fail "submit" "status $code"
R=$TMP/res.json
jcheck "$R" '.complete == 200 and .errors == 0 and .last > .start + 3' "200 long-polls" \
    "200 long-polls: all got every record $(jf "$R" '"\(.start + 1)..\(.last)"') in order ($(jf "$R" .requests) round trips)"
# most of them at once (how many exactly depends on how fast the other 199
# come back between two records: 114-200 seen on a loaded 2-core machine);
# that none needs a thread is the next check
jcheck "$R" '.parked_max >= 100' "parked" \
    "they were parked together: up to $(jf "$R" .parked_max) suspended connections at once"
jcheck "$R" '.threads_max <= .threads_before' "thread count" \
    "thread count flat: $(jf "$R" .threads_before) before, at most $(jf "$R" .threads_max) with 200 waiting"
# wait=N returns after N seconds with the state unchanged when nothing happens
curl -s -m 10 "$URL/v1/jobs/$id/progress?after=100000&wait=1" > "$TMP/p"
if [ "$(jf "$TMP/p" .count)" = 0 ] && [ "$(jf "$TMP/p" .done)" = true ]; then
    pass "a finished job answers at once (done, nothing after the last record)"
else
    fail "finished job poll" "$(cat "$TMP/p")"
fi
stop_qdcd || fail "SIGTERM" "exit status $?"

# Memory of parked long-polls (1000 of them <= 20 MB) from clients
# that poll in a loop over keep-alive connections. libmicrohttpd 0.9.75 zeroes
# a reused connection's whole 128 KiB pool, so a poll parked on a reused
# connection costs ~135 KB against ~14 KB on a fresh one; progress replies
# close the connection to keep it at the latter. One long job runs (literal
# mode: no early stop), the polls wait on a queued one.
start_qdcd "$TMP/d2" --workers 1 --sse-keepalive 1 || { fail "start (2)" "$(tail -3 "$TMP/d2.log")"; exit 1; }
submit "$TMP/in.qmesh" application/vnd.qdc.mesh \
    "max_iter=10000&tol_move=0&finish=0&mode=literal&time_limit=120" "$TMP/x" > /dev/null
submit "$TMP/in.qmesh" application/vnd.qdc.mesh "max_iter=10" "$TMP/y" > /dev/null
x=$(jf "$TMP/x" .id)
y=$(jf "$TMP/y" .id)
curl -s -m 30 "$URL/v1/jobs/$x/progress?after=1&wait=20" > /dev/null
M=$TMP/mem.json
$PY "$ROOT/tests/server/parkmem.py" "$URL" "$x" "$y" "$QPID" 200 > "$M" 2> "$M.err"
jcheck "$M" '.parked == 200 and .answered == 0 and .reconnected == 200 and .kb_each <= 40' "RSS of parked polls" \
    "200 parked polls of looping clients: $(jf "$M" .kb_each) KB of RSS each (<= 40; on reused connections ~135)"
jcheck "$M" '.threads_parked <= .threads_before' "threads of parked polls" \
    "no thread for them: $(jf "$M" .threads_before) before, $(jf "$M" .threads_parked) parked"
# A client that hangs up while parked is dropped at the next sweep (1 s), not
# when its wait (60 s) runs out: nothing else would resume a queued job's polls.
jcheck "$M" '.parked_after_hangup == 0 and .hangups >= 200 and .hangup_s <= 3' "hang-ups while parked" \
    "200 clients hung up while parked: dropped in $(jf "$M" .hangup_s) s (qdcd_parked_hangups_total $(jf "$M" .hangups))"
# SSE on the queued job: nothing happens, so a comment every --sse-keepalive s
curl -s -N -m 3.5 -D "$TMP/sse.h" "$URL/v1/jobs/$y/events" > "$TMP/sse"
nk=$(grep -c '^: keep-alive$' "$TMP/sse")
if [ "$nk" -ge 2 ] && ! grep -q '^event:' "$TMP/sse" && [ "$(hdr "$TMP/sse" content-type)" = text/event-stream ]; then
    pass "SSE keep-alive: $nk comments in 3.5 s on an idle stream (--sse-keepalive 1), no events"
else
    fail "SSE keep-alive" "$nk comments: $(head -c 300 "$TMP/sse" | tr '\n' '|')"
fi
req POST "/v1/jobs/$y:cancel" "$TMP/c" > /dev/null
req POST "/v1/jobs/$x:cancel" "$TMP/c" > /dev/null
stop_qdcd || fail "SIGTERM (2)" "exit status $?"
exit $((NFAIL > 0))
