#!/bin/sh
# faults/datadir.sh - one daemon per data directory, and no orphaned job
# directories. A second qdcd on the same --data refuses to start with a clear
# message (before, it started, re-queued the first one's running job and ran
# it too); the lock goes with the process, kill -9 included; job directories
# without a row (a crash between the input's rename and its INSERT) are
# removed at start-up, jobs with a row are kept.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
start_qdcd "$TMP/d" --workers 1 || { fail "datadir: start" "$(tail -3 "$TMP/d.log")"; exit 1; }
first=$QPID
c=$(submit "$ROOT/tests/data/sample/cube.mesh" model/x-medit "max_iter=2" "$TMP/j")
id=$(jf "$TMP/j" .id)
poll_all "$id" > /dev/null
"$QDCD" --listen 127.0.0.1:0 --data "$TMP/d" > "$TMP/second.log" 2>&1 &
second=$!
i=0
while [ $i -lt 50 ] && kill -0 $second 2> /dev/null; do sleep 0.1; i=$((i + 1)); done
if kill -0 $second 2> /dev/null; then
    kill -9 $second
    fail "datadir: second daemon" "still running after 5 s: $(tail -2 "$TMP/second.log")"
else
    wait $second
    rc=$?
    if [ $rc != 0 ] && grep -q "in use by another qdcd (pid $first)" "$TMP/second.log"; then
        pass "datadir: a second qdcd on the same --data exits $rc: $(head -c 120 "$TMP/second.log")"
    else
        fail "datadir: second daemon" "exit $rc: $(cat "$TMP/second.log")"
    fi
fi
# an orphan: a job directory with no row (as a crash before the INSERT leaves it)
orphan=0123456789abcdef0123456789abcdef
mkdir -p "$TMP/d/jobs/$orphan"
echo x > "$TMP/d/jobs/$orphan/input"
kill -9 $first
wait $first 2> /dev/null
QPID=
start_qdcd "$TMP/d" --workers 1 || { fail "datadir: restart after kill -9" "$(tail -3 "$TMP/d.log")"; exit 1; }
st=$(curl -s "$URL/v1/jobs/$id" | jq -r .state)
if [ ! -e "$TMP/d/jobs/$orphan" ] && [ -d "$TMP/d/jobs/$id" ] && [ "$st" = succeeded ] &&
    grep -q 'removed 1 job directory without a job' "$TMP/d.log"; then
    pass "datadir: after kill -9 the lock is free again; the orphan directory is removed, the job kept ($st)"
else
    fail "datadir: orphans" "orphan $(ls -d "$TMP/d/jobs/$orphan" 2>&1) job $st $(tail -2 "$TMP/d.log")"
fi
stop_qdcd || fail "datadir: stop" "exit $?"
exit 0
