#!/bin/sh
# load.sh - mixed traffic for QDC_LOAD_SECONDS (default 30; `make test-load`
# runs 600): job submissions, event streams opened and closed at once or
# later, long-polls, uploads cut half-way, refused uploads whose client hangs
# up without reading (tests/faults/load.py). Checks: /livez p99 under the
# traffic within 10 times its p99 in an idle phase just before (the same
# prober, the daemon alone; 100 ms is always allowed: an idle machine's
# baseline of a millisecond says nothing of scheduling), no accepted job lost or left queued/running, every one
# succeeded, fds and threads back to their baseline and RSS within 64 MB of it.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
secs=${QDC_LOAD_SECONDS:-30}
gzip -dc "$DEV/cube_h0.1_good.mesh.gz" > "$TMP/in.mesh"
start_qdcd "$TMP/d" --workers 2 --max-connections 100 --max-queued 50 ||
    { fail "load: start" "$(tail -3 "$TMP/d.log")"; exit 1; }
"$PY" "$ROOT/tests/faults/load.py" "$URL" "$QPID" "$secs" "$TMP/in.mesh" > "$TMP/load.json" 2> "$TMP/load.err" ||
    { fail "load: driver" "$(tail -3 "$TMP/load.err")"; exit 1; }
L=$TMP/load.json
summary=$(jq -c '{s: .seconds, accepted, states, counts, p99: .livez_p99_ms, idle_p99: .idle_p99_ms, max: .livez_max_ms, base, end: .end}' "$L")
lim=$(jq '[100, 10 * .idle_p99_ms] | max' "$L")
jq -e --argjson lim "$lim" '.livez_n > 0 and .idle_n > 0 and .livez_p99_ms <= $lim' "$L" > /dev/null &&
    pass "load: /livez p99 $(jq .livez_p99_ms "$L") ms over $(jq .livez_n "$L") probes in ${secs} s (max $(jq .livez_max_ms "$L") ms), limit $lim ms = 10 x idle p99 $(jq .idle_p99_ms "$L") ms (floor 100; target 100 ms on an idle machine)" ||
    fail "load: /livez p99 over $lim ms (10 x idle p99, floor 100)" "$summary"
jq -e '.accepted >= 10 * (.seconds / 30 | floor) and .stuck == 0 and (.states | keys) == ["succeeded"] and .n_errors == 0' "$L" > /dev/null &&
    pass "load: $(jq .accepted "$L") accepted jobs all succeeded, none stuck, no request errors ($(jq -c .counts "$L"))" ||
    fail "load: jobs lost, stuck or failed" "$summary $(jq -c .errors "$L")"
jq -e '.end.fds <= .base.fds + 2 and .end.threads <= .base.threads and .end.rss_kb <= .base.rss_kb + 65536' "$L" > /dev/null &&
    pass "load: fds $(jq .base.fds "$L") -> $(jq .end.fds "$L"), threads $(jq .base.threads "$L") -> $(jq .end.threads "$L"), RSS $(jq .base.rss_kb "$L") -> $(jq .end.rss_kb "$L") kB" ||
    fail "load: resources not back to baseline" "$summary"
stop_qdcd
[ "$NFAIL" -eq 0 ]
