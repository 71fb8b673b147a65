#!/bin/sh
# names.sh - a job keeps the upload's file name (?name=, its last path part)
# and a label (?label=): in the job, in the list, after a restart, on SQLite
# and on PostgreSQL (pg.inc; skipped without a server); a name with a control
# character or too long is refused with 400 before the body; a job submitted
# without them has neither member; `qdc submit` sends the file's name and
# --label, and `qdc jobs` / `qdc status` show them.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"
SAMPLE=$ROOT/tests/data/sample/cube.mesh
MT=model/x-medit

start_qdcd "$TMP/d" --workers 1 || { fail "start" "$(tail -3 "$TMP/d.log")"; exit 1; }
code=$(submit "$SAMPLE" $MT "max_iter=2&name=some%2Fdir%2Fbunny_low_10k.mesh.gz&label=first%20try%20%C3%A9" "$TMP/a")
A=$(jf "$TMP/a" .id)
code2=$(submit "$SAMPLE" $MT "max_iter=2" "$TMP/b")
B=$(jf "$TMP/b" .id)
wait_done "$A" > /dev/null
wait_done "$B" > /dev/null
if [ "$code $code2" = "202 202" ] && jq -e '.file_name == "bunny_low_10k.mesh.gz" and .label == "first try é"' "$TMP/a" > /dev/null &&
    jq -e 'has("file_name") or has("label") | not' "$TMP/b" > /dev/null; then
    pass "names: ?name= keeps the file's last path part (bunny_low_10k.mesh.gz), ?label= its UTF-8 text; a job without them has neither member"
else
    fail "names: submit" "$code $code2 $(head -c 300 "$TMP/a")"
fi
curl -s "$URL/v1/jobs/$A" > "$TMP/ga"
curl -s "$URL/v1/jobs?page_size=100" > "$TMP/list"
jq -e '.file_name == "bunny_low_10k.mesh.gz" and .label == "first try é" and .state == "succeeded"' "$TMP/ga" > /dev/null &&
    jq -e --arg a "$A" '.jobs[] | select(.id == $a) | .file_name == "bunny_low_10k.mesh.gz"' "$TMP/list" > /dev/null &&
    pass "names: GET /v1/jobs/{id} and the list carry them once the job has run" || fail "names: get/list" "$(head -c 300 "$TMP/ga")"
bad=
# a control character is refused in every query value before any handler
# (invalid-parameter); lengths by the upload's own checks (invalid-option)
for q in "name=a%01b:invalid-parameter" "label=x%0Ay:invalid-parameter" \
    "name=$(printf '%0300d' 0):invalid-option" "label=$(printf '%0130d' 0):invalid-option"; do
    c=$(submit "$SAMPLE" $MT "${q%:*}" "$TMP/bad")
    [ "$c" = 400 ] && jq -e --arg t "${q##*:}" '.type | endswith($t)' "$TMP/bad" > /dev/null ||
        bad="$bad ${q%%=*}:$c:$(jq -r .type "$TMP/bad" 2> /dev/null)"
done
[ -z "$bad" ] && pass "names: a control character (400 invalid-parameter) or a name over 255 / label over 127 bytes (400 invalid-option)" ||
    fail "names: bad" "$bad"

# qdc submit / jobs / status
out=$("$BIN/qdc" submit "$SAMPLE" --server "$URL" --label "cli run" --max-iter 2 --wait -q 2> "$TMP/sub.err")
C=$(echo "$out" | tail -1)
"$BIN/qdc" jobs --server "$URL" > "$TMP/jobs" 2>&1
"$BIN/qdc" status "$C" --server "$URL" > "$TMP/status" 2>&1
if [ "$(curl -s "$URL/v1/jobs/$C" | jq -r '.file_name + "|" + .label')" = "cube.mesh|cli run" ] &&
    grep -q "^$C .*  cli run (cube.mesh)$" "$TMP/jobs" && grep -q "cli run (cube.mesh)$" "$TMP/status" &&
    grep -q "^$A .*  first try é (bunny_low_10k.mesh.gz)$" "$TMP/jobs"; then
    pass "names: qdc submit sends the file's name and --label; qdc jobs and status end with \"cli run (cube.mesh)\""
else
    fail "names: qdc" "$(cat "$TMP/sub.err" "$TMP/jobs" "$TMP/status" | tail -4)"
fi
# a restart: read back from the store
stop_qdcd
start_qdcd "$TMP/d" --workers 1 || { fail "restart" "$(tail -3 "$TMP/d.log")"; exit 1; }
curl -s "$URL/v1/jobs/$A" > "$TMP/ra"
jq -e '.file_name == "bunny_low_10k.mesh.gz" and .label == "first try é"' "$TMP/ra" > /dev/null &&
    pass "names: kept in SQLite across a restart" || fail "names: restart" "$(head -c 200 "$TMP/ra")"
stop_qdcd

# a store made before the columns: they are added, old jobs have no name
rm -rf "$TMP/old"
mkdir -p "$TMP/old"
if command -v sqlite3 > /dev/null 2>&1; then
    start_qdcd "$TMP/old" --workers 1 && stop_qdcd
    sqlite3 "$TMP/old/qdcd.db" "ALTER TABLE jobs DROP COLUMN label; ALTER TABLE jobs DROP COLUMN file_name;" 2> "$TMP/sq.err"
    if start_qdcd "$TMP/old" --workers 1; then
        c=$(submit "$SAMPLE" $MT "max_iter=1&name=old.mesh" "$TMP/o")
        [ "$c" = 202 ] && jq -e '.file_name == "old.mesh"' "$TMP/o" > /dev/null &&
            pass "names: a SQLite store without the columns gets them at start" || fail "names: old store" "$c $(cat "$TMP/sq.err") $(head -c 200 "$TMP/o")"
        stop_qdcd
    else
        fail "names: old store" "$(tail -3 "$TMP/old.log")"
    fi
else
    echo "ok - names: a SQLite store without the columns # SKIP no sqlite3 command"
fi

# PostgreSQL: the same members through its rows (a migration adds the columns)
. "$(dirname "$0")/pg.inc"
QDCD=${QDCD:-$BIN/qdcd}
PIDS=
trap 'for p in $PIDS; do kill -9 $p 2>/dev/null; done; pg_cleanup; rm -rf "$TMP"' EXIT
if ! pg_available; then
    pg_skip names "PostgreSQL keeps file_name and label"
    exit $((NFAIL > 0))
fi
pg_started names || exit 1
QM=model/x-medit
node p "$TMP/dp" --workers 1 || { fail "names: pg node" "$(tail -3 "$TMP/p.log")"; exit 1; }
c=$(post "$URL_p" "$SAMPLE" "max_iter=2&name=x%2Fpart.msh&label=pg%20run" "$TMP/pj")
P=$(jf "$TMP/pj" .id)
st=$(wait_done "$URL_p" "$P")
row=$(pg_sql "SELECT file_name || '|' || label FROM jobs WHERE id = '$P'")
stop "$PID_p"
node p "$TMP/dp" --workers 1 || { fail "names: pg node restart" "$(tail -3 "$TMP/p.log")"; exit 1; }
again=$(curl -s "$URL_p/v1/jobs/$P" | jq -r '.file_name + "|" + .label')
if [ "$c $st" = "202 succeeded" ] && [ "$row" = "part.msh|pg run" ] && [ "$again" = "part.msh|pg run" ]; then
    pass "names: PostgreSQL keeps file_name and label (row '$row', read back after a restart)"
else
    fail "names: pg" "post $c state $st row '$row' again '$again'"
fi
stop "$PID_p"
exit $((NFAIL > 0))
