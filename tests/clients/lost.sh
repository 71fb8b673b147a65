#!/bin/sh
# lost.sh - a submit whose answer is lost (a 503 from a proxy after the job was
# made upstream, or a connection closed without an answer) is retried with the
# same Idempotency-Key and gets the same job: one job per submit, for `qdc
# submit` and for the Python client.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
PPID_=
trap 'if [ -n "$QPID" ]; then kill -9 $QPID 2>/dev/null; fi; if [ -n "$PPID_" ]; then kill $PPID_ 2>/dev/null; fi; rm -rf "$TMP"' EXIT
MESH=$(devmesh bunny_low_10k)

start_qdcd "$TMP/d" --workers 1 || { fail "start" "qdcd did not come up: $(tail -3 "$TMP/d.log")"; exit 1; }

# proxy MODE: start a fresh flaky proxy; sets PURL
proxy() {
    [ -n "$PPID_" ] && kill "$PPID_" 2> /dev/null && wait "$PPID_" 2> /dev/null
    rm -f "$TMP/pport" "$TMP/plog"
    $PY "$ROOT/tests/clients/flaky_proxy.py" "$PORT" "$TMP/pport" "$TMP/plog" "$1" &
    PPID_=$!
    i=0
    # (up to 30 s: Python starts slowly on a busy machine)
    while [ $i -lt 300 ] && [ ! -s "$TMP/pport" ]; do sleep 0.1; i=$((i + 1)); done
    PURL=http://127.0.0.1:$(cat "$TMP/pport")
}
njobs() { curl -s "$URL/v1/jobs" | jq '.jobs | length'; }

for mode in 503 drop; do
    proxy $mode
    before=$(njobs)
    id=$("$BIN/qdc" submit "$MESH" --server "$PURL" --max-iter 1 --wait -q 2> "$TMP/err")
    rc=$?
    posts=$(grep -c '^POST /v1/jobs' "$TMP/plog")
    keys=$(grep '^POST /v1/jobs' "$TMP/plog" | awk '{ print $3 }' | sort -u | wc -l)
    after=$(njobs)
    if [ $rc = 0 ] && [ "$posts" = 2 ] && [ "$keys" = 1 ] && [ $((after - before)) = 1 ] && [ -n "$id" ]; then
        pass "qdc submit, first answer lost ($mode): retried with the same Idempotency-Key, one job ($id)"
    else
        fail "qdc lost $mode" "rc $rc posts $posts keys $keys jobs $before -> $after: $(tail -2 "$TMP/err")"
    fi

    proxy $mode
    before=$(njobs)
    out=$(cd "$ROOT/clients/python" && $PY -c "
import qdc_client
c = qdc_client.Client('$PURL')
c.on_retry = None
j = c.submit('$MESH', {'max_iter': 1})
print(c.wait(j)['state'])" 2>&1)
    posts=$(grep -c '^POST /v1/jobs' "$TMP/plog")
    keys=$(grep '^POST /v1/jobs' "$TMP/plog" | awk '{ print $3 }' | sort -u | wc -l)
    after=$(njobs)
    if [ "$out" = succeeded ] && [ "$posts" = 2 ] && [ "$keys" = 1 ] && [ $((after - before)) = 1 ]; then
        pass "python submit, first answer lost ($mode): same Idempotency-Key, one job"
    else
        fail "python lost $mode" "'$out' posts $posts keys $keys jobs $before -> $after"
    fi
done
stop_qdcd
exit 0
