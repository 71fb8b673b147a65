#!/bin/sh
# delete.sh - DELETE answers without unlinking the job's files on the request
# thread (server/trash.c): the job's directory is renamed into DATA/trash at
# once and a thread of its own removes it. A job directory padded with 3000
# files stands for a big job (one whose files took ~3 s to unlink): its DELETE
# must take under half the time the test itself needs to remove a twin of
# that directory (measured in the same run, so a busy machine slows both),
# the directory is gone from jobs/ at the 204 and the trash is empty soon
# after. Nothing is lost on a crash: what a killed daemon left in DATA/trash
# is removed at start-up, before it serves.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"
SAMPLE=$ROOT/tests/data/sample/cube.mesh
D=$TMP/d
NPAD=3000

# a leftover of a crash, there before the daemon starts
mkdir -p "$D/trash/0123456789abcdef0123456789abcdef.3"
echo x > "$D/trash/0123456789abcdef0123456789abcdef.3/result.mesh"
echo x > "$D/trash/stray"
start_qdcd "$D" --workers 1 || { fail "delete: start" "$(tail -3 "$D.log")"; exit 1; }
if [ -d "$D/trash" ] && [ -z "$(ls -A "$D/trash")" ]; then
    pass "delete: what a crash left in DATA/trash is removed at start-up"
else
    fail "delete: trash at start-up" "$(ls -A "$D/trash" 2>&1 | head -3 | tr '\n' ' ')"
fi

# pad DIR N: N empty files in DIR
pad() {
    "$PY" -c 'import os, sys
for i in range(int(sys.argv[2])):
    open(os.path.join(sys.argv[1], "pad%05d" % i), "w").close()' "$1" "$2"
}
code=$(submit "$SAMPLE" model/x-medit "max_iter=3" "$TMP/a")
A=$(jf "$TMP/a" .id)
code2=$(submit "$SAMPLE" model/x-medit "max_iter=3" "$TMP/b")
B=$(jf "$TMP/b" .id)
st=$(wait_done "$A") st2=$(wait_done "$B")
[ "$code $code2 $st $st2" = "202 202 succeeded succeeded" ] ||
    { fail "delete: jobs" "$code $code2 $st $st2"; exit 1; }
pad "$D/jobs/$A" $NPAD
mkdir "$TMP/twin"
pad "$TMP/twin" $NPAD
t0=$(date +%s.%N)
rm -rf "$TMP/twin"
t_rm=$(echo "$(date +%s.%N) $t0" | awk '{ printf "%.4f", $1 - $2 }')
small=$(curl -s -m 60 -o /dev/null -w '%{http_code} %{time_total}' -X DELETE "$URL/v1/jobs/$B")
big=$(curl -s -m 60 -o /dev/null -w '%{http_code} %{time_total}' -X DELETE "$URL/v1/jobs/$A")
gone=no
[ ! -e "$D/jobs/$A" ] && gone=yes
set -- $small $big
if [ "$1 $3 $gone" = "204 204 yes" ] && awk -v b="$4" -v r="$t_rm" 'BEGIN { exit !(b < r / 2) }'; then
    pass "delete: a job directory of $NPAD files: 204 in $4 s (a small job's: $2 s), under half of removing its twin here ($t_rm s); gone from jobs/ at the 204"
else
    fail "delete: off the request thread" "DELETE $1 in $2 s (small), $3 in $4 s ($NPAD files; removing its twin: $t_rm s), gone from jobs/ at once: $gone"
fi
i=0
while [ $i -lt 300 ] && [ -n "$(ls -A "$D/trash")" ]; do
    sleep 0.1
    i=$((i + 1))
done
g1=$(req GET "/v1/jobs/$A" "$TMP/ga")
g2=$(req GET "/v1/jobs/$B" "$TMP/gb")
if [ -z "$(ls -A "$D/trash")" ] && [ "$g1 $g2" = "404 404" ]; then
    pass "delete: the trash thread removed both directories ($(echo "$i" | awk '{ print $1 / 10 }') s after the 204s); both jobs 404"
else
    fail "delete: trash emptied" "GET $g1 $g2, left: $(ls -A "$D/trash" | head -3 | tr '\n' ' ')"
fi

# kill -9 with a deleted job's files still in the trash (put there by hand:
# the thread is quicker than any test): the next start removes them
code=$(submit "$SAMPLE" model/x-medit "max_iter=3" "$TMP/c")
C=$(jf "$TMP/c" .id)
st=$(wait_done "$C")
del=$(req DELETE "/v1/jobs/$C" "$TMP/dc")
kill -9 "$QPID"
wait "$QPID" 2> /dev/null
QPID=
mkdir -p "$D/trash/$C.0"
pad "$D/trash/$C.0" 10
start_qdcd "$D" --workers 1 || { fail "delete: restart" "$(tail -3 "$D.log")"; exit 1; }
g=$(req GET "/v1/jobs/$C" "$TMP/gc")
if [ "$code $st $del $g" = "202 succeeded 204 404" ] && [ -z "$(ls -A "$D/trash")" ] && [ ! -e "$D/jobs/$C" ]; then
    pass "delete: after kill -9 the restarted daemon emptied DATA/trash before serving; the job stays deleted (404)"
else
    fail "delete: after kill -9" "$code $st $del $g, trash: $(ls -A "$D/trash" | head -3 | tr '\n' ' ')"
fi
stop_qdcd || fail "delete: SIGTERM" "exit status $?"
[ "$NFAIL" -eq 0 ]
