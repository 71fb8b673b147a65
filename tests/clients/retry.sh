#!/bin/sh
# retry.sh - `qdc submit` against a daemon with a one-job queue: the submit
# that finds the queue full gets 429, waits what Retry-After says, retries
# with the same Idempotency-Key and succeeds; exactly one job is made for it.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
QDC=$BIN/qdc

MESH=$(devmesh bunny_low_10k)
BIG=$(devmesh bunny_low_100k)

start_qdcd "$TMP/d" --workers 1 --max-queued 1 --shutdown-grace 1 || { fail "start" "qdcd did not come up: $(tail -3 "$TMP/d.log")"; exit 1; }
export QDC_SERVER=$URL

# A runs for ~4 s on the only worker, B waits in the queue: the queue is full.
A=$("$QDC" submit "$BIG" --max-iter 1000 --time-limit 4 --finish off -q)
i=0
while [ $i -lt 600 ] && ! "$QDC" status "$A" | grep -q ' running '; do
    sleep 0.1
    i=$((i + 1))
done
B=$("$QDC" submit "$MESH" --max-iter 1 -q)
code=$(submit "$MESH" model/x-medit "max_iter=1" "$TMP/full")
if [ "$code" = 429 ] && [ -n "$(hdr "$TMP/full" Retry-After)" ]; then
    pass "queue full: the daemon answers 429 with Retry-After $(hdr "$TMP/full" Retry-After)"
else
    fail "queue full" "status $code (A $A, B $B): $(head -c 200 "$TMP/full")"
fi

t0=$(date +%s)
C=$("$QDC" submit "$MESH" --max-iter 1 -o "$TMP/out.mesh" 2> "$TMP/c.err")
rc=$?
dt=$(( $(date +%s) - t0 ))
n429=$(grep -c 'HTTP 429 (server busy); retrying in' "$TMP/c.err")
if [ $rc = 0 ] && [ "$n429" -ge 1 ] && [ -s "$TMP/out.mesh" ] && "$QDC" quality "$TMP/out.mesh" > /dev/null; then
    pass "submit on a full queue: $n429 x 429, waited as told, then accepted and done in $dt s"
else
    fail "submit retry" "rc $rc, 429 seen $n429 times: $(tail -3 "$TMP/c.err")"
fi
if grep -q 'retrying in 5.0 s' "$TMP/c.err"; then
    pass "the wait is the server's Retry-After (5 s), not the client's backoff"
else
    fail "Retry-After" "$(grep retrying "$TMP/c.err" | head -2)"
fi

"$QDC" jobs > "$TMP/jobs"
n=$(wc -l < "$TMP/jobs")
others=$(grep -cv -e "^$A " -e "^$B " -e "^$C " "$TMP/jobs")
if [ "$n" = 3 ] && [ "$others" = 0 ] && [ "$C" != "$A" ] && [ "$C" != "$B" ]; then
    pass "one job per submit: 3 jobs (A, B and the retried C)"
else
    fail "one job only" "$n jobs: $(cat "$TMP/jobs")"
fi

# --retries 0: the 429 is final, exit 12 (the server could not take it)
"$QDC" submit "$BIG" --max-iter 1000 --time-limit 3 --finish off -q > /dev/null
"$QDC" submit "$MESH" --max-iter 1 -q > /dev/null
"$QDC" submit "$MESH" --max-iter 1 --retries 0 -q 2> "$TMP/e.err"
rc=$?
if [ $rc = 12 ] && grep -q 429 "$TMP/e.err"; then
    pass "--retries 0 on a full queue: exit 12 at once"
else
    fail "retries 0" "rc $rc: $(cat "$TMP/e.err")"
fi
stop_qdcd
exit 0
