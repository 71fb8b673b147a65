#!/bin/sh
# pg3.sh - three qdcd nodes on one PostgreSQL database (pg.inc starts a real
# server), each with its OWN --data directory: the nodes share nothing but
# the database. Checks:
#  - jobs submitted round-robin all succeed, each run exactly once;
#  - a node other than the worker's answers long-polls (woken through
#    LISTEN/NOTIFY: median wake-up measured, <= 100 ms), follows /events,
#    shows live progress, serves /progress, /report and /result in every
#    format with the worker's ETags, also after its cache was emptied;
#  - DELETE on one node removes the job's files from the database and from
#    the other nodes' caches;
#  - kill -9 of the node running a job: another node finishes it; a job
#    whose run killed a node on each of its --max-attempts fails, with a
#    clear problem;
#  - one Idempotency-Key sent to the three nodes at once: one job;
#  - PostgreSQL stopped and restarted mid-run: no job lost, no node dies;
#  - rolling SIGTERM restart of every node while jobs run: no job fails.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/pg.inc"
QDCD=${QDCD:-$BIN/qdcd}
QM='application/vnd.qdc.mesh'
MT="$PY $ROOT/tests/server/meshtool.py"
XN="$PY $ROOT/tests/server/xnode.py"
PIDS=
trap 'for p in $PIDS; do kill -9 $p 2>/dev/null; done; pg_cleanup; rm -rf "$TMP"' EXIT

CHECKS="round-robin|wake-up|events|live progress|progress|report|results|cache emptied|delete|node killed|attempts exhausted|idempotency|database restart|rolling restart"
if ! pg_available; then
    pg_skip pg3 "$CHECKS"
    exit 0
fi
pg_started pg3 || exit 1

NODEOPTS="--workers 1 --lease 3 --shutdown-grace 1 --max-attempts 2"
for n in a b c; do
    node $n "$TMP/d$n" $NODEOPTS || { fail "pg3: node $n starts" "$(tail -3 "$TMP/$n.log")"; exit 1; }
done
url_of() { eval "echo \$URL_$1"; }
pid_of() { eval "echo \$PID_$1"; }
# runner ID: the name of the node whose worker holds the job's lease ("" if none)
runner() {
    _o=$(pg_sql "SELECT lease_owner FROM jobs WHERE id = '$1'")
    for _n in a b c; do
        case $_o in *:"$(pid_of $_n)":*) echo $_n; return ;; esac
    done
}
succeeded_total() { # sum over the nodes of qdcd_jobs_finished_total{state="succeeded"}
    _t=0
    for _n in a b c; do
        _v=$(curl -s "$(url_of $_n)/metrics" | awk '/^qdcd_jobs_finished_total\{state="succeeded"\}/ { print $2 }')
        _t=$((_t + ${_v:-0}))
    done
    echo $_t
}

$MT qmesh "$ROOT/tests/data/sample/cube.mesh" "$TMP/cube.qmesh" || { fail "pg3: sample" "meshtool"; exit 1; }
gzip -dc "$DEV/bunny_low_10k.mesh.gz" > "$TMP/bunny.mesh"
$MT qmesh "$TMP/bunny.mesh" "$TMP/bunny.qmesh" || { fail "pg3: bunny" "meshtool"; exit 1; }
# about 40 ms per iteration here: a run of LONG takes a few seconds
LONG="max_iter=60&finish=0&tol_move=0&mode=literal"

# 1. round-robin: 9 jobs, 3 per node; each succeeds once
ids=
i=0
for n in a b c a b c a b c; do
    i=$((i + 1))
    post "$(url_of $n)" "$TMP/cube.qmesh" "max_iter=3" "$TMP/rr$i" > /dev/null
    ids="$ids $(jf "$TMP/rr$i" .id)"
done
bad=
[ "$(echo $ids | wc -w)" = 9 ] || bad="submitted: '$ids'"
for id in $ids; do
    st=$(wait_done "$URL_c" "$id")
    att=$(curl -s "$URL_a/v1/jobs/$id" | jq -r .attempts)
    [ "$st" = succeeded ] && [ "$att" = 1 ] || bad="$bad $id:$st:$att"
done
runs=$(succeeded_total)
if [ -z "$bad" ] && [ "$runs" = 9 ]; then
    pass "pg3: round-robin: 9 jobs on 3 nodes, each succeeded with 1 attempt, 9 runs in all"
else
    fail "pg3: round-robin" "$bad (runs ended: $runs)"
fi

# 2. a long job; reads through the nodes that do not run it
post "$URL_a" "$TMP/bunny.qmesh" "$LONG" "$TMP/jl" > /dev/null
idl=$(jf "$TMP/jl" .id)
wait_running "$URL_a" "$idl"
w=$(runner "$idl")
case $w in a) o1=b o2=c ;; b) o1=c o2=a ;; *) o1=a o2=b ;; esac
$XN events "$(url_of $o2)" "$idl" > "$TMP/ev.json" &
evp=$!
# node o1 hears of a record past the first (a long-poll), then shows the job
curl -s -m 60 "$(url_of $o1)/v1/jobs/$idl/progress?after=0&wait=50" > /dev/null
live=$(curl -s "$(url_of $o1)/v1/jobs/$idl" | jq -r '"\(.state) \(.iterations) \(.progress.seq)"')
$XN wake "$(url_of $w)" "$(url_of $o1)" "$idl" > "$TMP/wake.json"
wait $evp
med=$(jq -r '.median_ms // empty' "$TMP/wake.json")
ns=$(jq -r .samples "$TMP/wake.json")
if [ -n "$med" ] && [ "$ns" -ge 5 ] && awk "BEGIN { exit !($med <= 100) }"; then
    pass "pg3: wake-up: a long-poll on node $o1 for a job on node $w: median $med ms after the worker's own ($(jq -c 'del(.records)' "$TMP/wake.json"))"
else
    fail "pg3: wake-up" "$(cat "$TMP/wake.json")"
fi
st=$(wait_done "$URL_b" "$idl")
nrec=$(curl -s "$(url_of $w)/v1/jobs/$idl/progress" | jq -r .count)
if [ "$(jq -r .end "$TMP/ev.json")" = succeeded ] && [ "$(jq -r .in_order "$TMP/ev.json")" = true ] &&
    [ "$(jq -r .progress "$TMP/ev.json")" = "$nrec" ] && [ "$nrec" -gt 10 ]; then
    pass "pg3: events: node $o2 streamed all $nrec records in order and the end (succeeded)"
else
    fail "pg3: events" "$(cat "$TMP/ev.json"), worker has $nrec records"
fi
set -- $live
if [ "$1" = running ] && [ "$2" -gt 0 ] && [ "$3" -ge 0 ]; then
    pass "pg3: live progress: node $o1 showed the job running with $2 iterations"
else
    fail "pg3: live progress" "'$live'"
fi
bad=
for n in a b c; do
    curl -s "$(url_of $n)/v1/jobs/$idl/progress?after=-1" | jq -c .records > "$TMP/p.$n"
    curl -s -o "$TMP/rep.$n" -w '%{http_code}' "$(url_of $n)/v1/jobs/$idl/report" > "$TMP/rep.$n.code"
done
cmp -s "$TMP/p.a" "$TMP/p.b" && cmp -s "$TMP/p.a" "$TMP/p.c" && [ "$(jq length "$TMP/p.a")" = "$nrec" ] ||
    bad="records differ"
[ "$st" = succeeded ] && pass "pg3: progress: the same $nrec records from each node" ||
    fail "pg3: progress" "$st $bad"
if [ "$(cat "$TMP/rep.a.code" "$TMP/rep.b.code" "$TMP/rep.c.code" | tr -d '\n')" = 200200200 ] &&
    cmp -s "$TMP/rep.a" "$TMP/rep.b" && cmp -s "$TMP/rep.a" "$TMP/rep.c" && jq -e .after "$TMP/rep.a" > /dev/null; then
    pass "pg3: report: the same report.json from each node"
else
    fail "pg3: report" "codes $(cat "$TMP/rep.a.code" "$TMP/rep.b.code" "$TMP/rep.c.code" | tr '\n' ' ')"
fi
# every format from every node: same bytes, same ETag (vtk is converted on
# the first request, by one node, and stored)
results() { # TAG: fetches every format from every node; prints the problems
    for f in qmesh json medit vtk; do
        for n in a b c; do
            curl -s -D "$TMP/h.$1.$f.$n" -o "$TMP/r.$1.$f.$n" "$(url_of $n)/v1/jobs/$idl/result?format=$f"
            tr -d '\r' < "$TMP/h.$1.$f.$n" | awk -F': ' 'tolower($1) == "etag" { print $2 }' > "$TMP/e.$1.$f.$n"
        done
        [ -s "$TMP/e.$1.$f.a" ] || echo "$f: no etag"
        for n in b c; do
            cmp -s "$TMP/r.$1.$f.a" "$TMP/r.$1.$f.$n" || echo "$f: bytes differ on $n"
            cmp -s "$TMP/e.$1.$f.a" "$TMP/e.$1.$f.$n" || echo "$f: etag differs on $n"
        done
    done
}
bad=$(results first)
etq=$(cat "$TMP/e.first.qmesh.a")
"$BIN/qdc" quality "$TMP/r.first.medit.a" > /dev/null 2>&1 || bad="$bad medit result not a valid mesh"
[ -z "$bad" ] && pass "pg3: results: qmesh, json, medit and vtk from each node, same bytes and ETags (qmesh $etq)" ||
    fail "pg3: results" "$bad"
# a node whose cache is emptied serves them from the database
rm -rf "$TMP/d$o2/jobs/$idl"
bad=$(results again)
for f in qmesh json medit vtk; do
    cmp -s "$TMP/e.first.$f.a" "$TMP/e.again.$f.$o2" || bad="$bad $f: etag changed"
done
[ -f "$TMP/d$o2/jobs/$idl/result.vtk" ] || bad="$bad not cached again"
[ -z "$bad" ] && pass "pg3: cache emptied: node $o2 fetched the results again from the database, same ETags" ||
    fail "pg3: cache emptied" "$bad"

# 3. DELETE on one node: the blobs and records leave the database, the other
# nodes' cached files go (their listeners hear it)
code=$(curl -s -o /dev/null -w '%{http_code}' -X DELETE "$(url_of $o1)/v1/jobs/$idl")
i=0
while :; do # until every node's listener removed its copy (at most 30 s)
    left=
    for n in a b c; do
        [ -e "$TMP/d$n/jobs/$idl" ] && left="$left $n"
    done
    [ -z "$left" ] || [ $i -ge 600 ] && break
    sleep 0.05
    i=$((i + 1))
done
nb=$(pg_sql "SELECT (SELECT COUNT(*) FROM blobs WHERE job_id = '$idl') + (SELECT COUNT(*) FROM blob_chunks WHERE job_id = '$idl') + (SELECT COUNT(*) FROM progress WHERE job_id = '$idl')")
if [ "$code" = 204 ] && [ -z "$left" ] && [ "$nb" = 0 ]; then
    pass "pg3: delete: 204 on node $o1; no file left on any node, no blob or record rows"
else
    fail "pg3: delete" "code $code, files left on:$left, rows $nb"
fi

# 4. kill -9 of the node running a job: another node finishes it after the
# lease (3 s) expires. The run ends by its time limit (4 s of its own), so it
# cannot end before the kill however slow the machine; the kill waits for a
# progress record past the first (the run is under way).
post "$URL_b" "$TMP/bunny.qmesh" "max_iter=10000&finish=0&tol_move=0&mode=literal&time_limit=4" "$TMP/jk" > /dev/null
idk=$(jf "$TMP/jk" .id)
curl -s -m 60 "$URL_b/v1/jobs/$idk/progress?after=0&wait=50" > /dev/null
k=$(runner "$idk")
kill -9 "$(pid_of "$k")"
wait "$(pid_of "$k")" 2> /dev/null
case $k in a) s=b ;; *) s=a ;; esac
st=$(wait_done "$(url_of $s)" "$idk")
att=$(curl -s "$(url_of $s)/v1/jobs/$idk" | jq -r .attempts)
curl -s -o "$TMP/k.mesh" "$(url_of $s)/v1/jobs/$idk/result?format=medit"
if [ -n "$k" ] && [ "$st" = succeeded ] && [ "$att" = 2 ] && "$BIN/qdc" quality "$TMP/k.mesh" > /dev/null 2>&1; then
    pass "pg3: node killed: kill -9 of node $k mid-job; another node finished it (attempts 2, valid result)"
else
    fail "pg3: node killed" "runner '$k' state $st attempts $att"
fi
node "$k" "$TMP/d$k" $NODEOPTS || { fail "pg3: node $k restarts" "$(tail -3 "$TMP/$k.log")"; exit 1; }

# 4b. a job during which its node dies on each of its 2 attempts fails
# (attempts exhausted), whichever nodes ran it
# (a run of up to 60 s: neither attempt can end before its kill)
post "$URL_c" "$TMP/bunny.qmesh" "max_iter=10000&finish=0&tol_move=0&mode=literal&time_limit=60" "$TMP/jp" > /dev/null
idp=$(jf "$TMP/jp" .id)
killed=
for attempt in 1 2; do
    i=0
    while [ $i -lt 300 ] && [ "$(pg_sql "SELECT state || ' ' || attempts FROM jobs WHERE id = '$idp'")" != "1 $attempt" ]; do
        sleep 0.05
        i=$((i + 1))
    done
    sleep 0.2
    k=$(runner "$idp")
    [ -n "$k" ] || break
    kill -9 "$(pid_of "$k")"
    wait "$(pid_of "$k")" 2> /dev/null
    killed="$killed $k"
    node "$k" "$TMP/d$k" $NODEOPTS || { fail "pg3: node $k restarts" "$(tail -3 "$TMP/$k.log")"; exit 1; }
done
st=$(wait_done "$URL_a" "$idp")
typ=$(curl -s "$URL_b/v1/jobs/$idp" | jq -r '"\(.attempts) \(.error.type)"')
if [ "$st" = failed ] && [ "$typ" = "2 /problems/attempts-exhausted" ] && [ "$(echo $killed | wc -w)" = 2 ]; then
    pass "pg3: attempts exhausted: nodes$killed killed during the job's 2 attempts; it failed with /problems/attempts-exhausted"
else
    fail "pg3: attempts exhausted" "killed '$killed', state $st, '$typ'"
fi

# 5. one Idempotency-Key sent to the three nodes at the same moment: one job
K='Idempotency-Key: pg3-same-key'
for n in a b c; do
    post "$(url_of $n)" "$TMP/cube.qmesh" "max_iter=2" "$TMP/k$n" -H "$K" > "$TMP/k$n.code" &
    eval "kp_$n=\$!"
done
wait $kp_a $kp_b $kp_c
n=$(pg_sql "SELECT COUNT(*) FROM jobs WHERE idem_key = 'pg3-same-key'")
ka=$(jf "$TMP/ka" .id)
if [ -n "$ka" ] && [ "$ka" = "$(jf "$TMP/kb" .id)" ] && [ "$ka" = "$(jf "$TMP/kc" .id)" ] && [ "$n" = 1 ]; then
    pass "pg3: idempotency: one key to three nodes at once: one job ($(cat "$TMP/ka.code")/$(cat "$TMP/kb.code")/$(cat "$TMP/kc.code"))"
else
    fail "pg3: idempotency" "ids $(jf "$TMP/ka" .id) $(jf "$TMP/kb" .id) $(jf "$TMP/kc" .id), rows $n"
fi
wait_done "$URL_a" "$ka" > /dev/null

# 6. PostgreSQL stopped for 3 s while 6 jobs run or wait: every node lives,
# every job succeeds (their ends and records are written once it is back)
before=$(pg_sql "SELECT COUNT(*) FROM jobs")
ids=
i=0
for n in a b c a b c; do
    i=$((i + 1))
    post "$(url_of $n)" "$TMP/bunny.qmesh" "max_iter=30&finish=0&tol_move=0&mode=literal" "$TMP/db$i" > /dev/null
    ids="$ids $(jf "$TMP/db$i" .id)"
done
wait_running "$URL_a" "$(jf "$TMP/db1" .id)"
pg_stop
sleep 3
down=$(curl -s -o /dev/null -w '%{http_code}' -m 10 "$URL_c/v1/jobs")
pg_up
bad=
for id in $ids; do
    st=$(wait_done "$URL_a" "$id")
    [ "$st" = succeeded ] || bad="$bad $id:$st"
done
for n in a b c; do
    kill -0 "$(pid_of $n)" 2> /dev/null || bad="$bad node $n died"
done
after=$(pg_sql "SELECT COUNT(*) FROM jobs")
if [ -z "$bad" ] && [ "$(echo $ids | wc -w)" = 6 ] && [ "$after" = $((before + 6)) ] && [ "$down" = 503 ]; then
    pass "pg3: database restart: PostgreSQL down 3 s mid-run (503 meanwhile); 6 jobs succeeded, 3 nodes alive"
else
    fail "pg3: database restart" "$bad; jobs $before -> $after, GET while down $down"
fi

# 7. rolling restart: SIGTERM each node in turn (grace 1 s: running jobs go
# back to the queue and another node takes them) while 9 jobs run
ids=
i=0
for n in a b c a b c a b c; do
    i=$((i + 1))
    post "$(url_of $n)" "$TMP/bunny.qmesh" "max_iter=40&finish=0&tol_move=0&mode=literal" "$TMP/rs$i" > /dev/null
    ids="$ids $(jf "$TMP/rs$i" .id)"
done
bad=
for n in a b c; do
    sleep 1
    stop "$(pid_of $n)" || bad="$bad $n exited $?"
    node "$n" "$TMP/d$n" $NODEOPTS || bad="$bad $n did not restart"
done
for id in $ids; do
    st=$(wait_done "$URL_c" "$id")
    [ "$st" = succeeded ] || bad="$bad $id:$st"
done
inlist=$(echo $ids | sed "s/\([0-9a-f]*\)/'\1'/g; s/ /,/g")
failed=$(pg_sql "SELECT COUNT(*) FROM jobs WHERE state = 3 AND id IN ($inlist)")
if [ -z "$bad" ] && [ "$(echo $ids | wc -w)" = 9 ] && [ "$failed" = 0 ]; then
    pass "pg3: rolling restart: each node SIGTERMed and restarted in turn; 9 jobs succeeded, none failed (database)"
else
    fail "pg3: rolling restart" "$bad; failed jobs $failed"
fi
for n in a b c; do
    stop "$(pid_of $n)"
done
exit 0
