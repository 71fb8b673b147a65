#!/bin/sh
# pg.sh - qdcd with its job rows in PostgreSQL (--store postgresql://...):
# a real server started for the test (pg.inc), real qdcd processes.
# One node: the whole job life cycle, a restart keeps the jobs, the schema is
# created once and found again. Two nodes on one database, each with its own
# --data directory (the job files are in the database too): jobs submitted to
# either node run exactly once and are read from the other; one Idempotency-Key sent to both nodes at the same
# moment makes one job; a node killed mid-job leaves the job to the other;
# a node given another's --data stops at its lock;
# the database stopped and restarted mid-run: no node dies, no job is lost.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/pg.inc"
QDCD=${QDCD:-$BIN/qdcd}
QM='application/vnd.qdc.mesh'
MT="$PY $ROOT/tests/server/meshtool.py"
PIDS=
trap 'for p in $PIDS; do kill -9 $p 2>/dev/null; done; pg_cleanup; rm -rf "$TMP"' EXIT

if ! pg_available; then
    pg_skip pg "one node|restart|schema|data directory lock|two nodes|idempotency|node killed|takeover with the default lease|database restart"
    exit 0
fi
pg_started pg || exit 1

$MT qmesh "$ROOT/tests/data/sample/cube.mesh" "$TMP/cube.qmesh" || { fail "pg: sample" "meshtool"; exit 1; }

# 1. one node: submit, run, result and report, through PostgreSQL rows
node a "$TMP/da" --workers 1 || { fail "pg: node a starts" "$(tail -3 "$TMP/a.log")"; exit 1; }
c=$(post "$URL_a" "$TMP/cube.qmesh" "max_iter=5" "$TMP/j1")
id1=$(jf "$TMP/j1" .id)
st=$(wait_done "$URL_a" "$id1")
curl -s -o "$TMP/r1.mesh" "$URL_a/v1/jobs/$id1/result?format=medit"
rows=$(pg_sql "SELECT state FROM jobs WHERE id = '$id1'")
if [ "$c" = 202 ] && [ "$st" = succeeded ] && [ "$rows" = 2 ] && "$BIN/qdc" quality "$TMP/r1.mesh" > /dev/null 2>&1; then
    pass "pg: one node: 202, succeeded, the row is in PostgreSQL (state 2), result is a valid mesh"
else
    fail "pg: one node" "post $c state $st row '$rows'"
fi

# 2. restart: the job is still there; 3. the schema is version 1, recorded once
stop "$PID_a"
node a "$TMP/da" --workers 1 || { fail "pg: node a restarts" "$(tail -3 "$TMP/a.log")"; exit 1; }
st=$(curl -s "$URL_a/v1/jobs/$id1" | jq -r .state)
[ "$st" = succeeded ] && pass "pg: restart: the job is still there (succeeded)" || fail "pg: restart" "state '$st'"
v=$(pg_sql "SELECT string_agg(version::text, ',' ORDER BY version) FROM qdc_schema")
once=$(pg_sql "SELECT COUNT(*) = COUNT(DISTINCT version) AND MIN(version) = 1 AND MAX(version) = COUNT(*) FROM qdc_schema")
[ "$once" = t ] && pass "pg: schema created once and found again on restart (versions: $v, each once)" ||
    fail "pg: schema" "versions '$v'"

# a node given node a's data directory stops at its lock: nodes share the
# database, not --data (its cache and scratch space)
"$QDCD" --listen 127.0.0.1:0 --data "$TMP/da" --store "$PGURI" > "$TMP/dup.log" 2>&1
rc=$?
[ $rc != 0 ] && grep -q "in use by another qdcd (pid $PID_a)" "$TMP/dup.log" &&
    pass "pg: a second node on node a's --data exits $rc, naming node a's pid" ||
    fail "pg: --data lock" "exit $rc: $(cat "$TMP/dup.log")"

# 4. a second node on the same database, its own data directory: 6 jobs, round-robin
node b "$TMP/db" --workers 1 || { fail "pg: node b starts" "$(tail -3 "$TMP/b.log")"; exit 1; }
ids=
for i in 1 2 3 4 5 6; do
    if [ $((i % 2)) = 0 ]; then u=$URL_a; else u=$URL_b; fi
    post "$u" "$TMP/cube.qmesh" "max_iter=3" "$TMP/rr$i" > /dev/null
    ids="$ids $(jf "$TMP/rr$i" .id)"
done
bad=
[ "$(echo $ids | wc -w)" = 6 ] || bad="submitted: '$ids'"
for id in $ids; do
    st=$(wait_done "$URL_a" "$id")
    att=$(curl -s "$URL_b/v1/jobs/$id" | jq -r .attempts)
    [ "$st" = succeeded ] && [ "$att" = 1 ] || bad="$bad $id:$st:$att"
    curl -s -o "$TMP/ra.mesh" "$URL_a/v1/jobs/$id/result?format=medit"
    curl -s -o "$TMP/rb.mesh" "$URL_b/v1/jobs/$id/result?format=medit"
    cmp -s "$TMP/ra.mesh" "$TMP/rb.mesh" || bad="$bad $id:results-differ"
done
[ -z "$bad" ] && pass "pg: two nodes: 6 jobs round-robin, each succeeded once (attempts 1), same result from both nodes" ||
    fail "pg: two nodes" "$bad"

# 5. one Idempotency-Key sent to both nodes at the same moment: one job
K='Idempotency-Key: pg-same-key'
post "$URL_a" "$TMP/cube.qmesh" "max_iter=2" "$TMP/ka" -H "$K" > "$TMP/ka.code" &
p1=$!
post "$URL_b" "$TMP/cube.qmesh" "max_iter=2" "$TMP/kb" -H "$K" > "$TMP/kb.code" &
p2=$!
wait $p1 $p2
ka=$(jf "$TMP/ka" .id)
kb=$(jf "$TMP/kb" .id)
n=$(pg_sql "SELECT COUNT(*) FROM jobs WHERE idem_key = 'pg-same-key'")
if [ -n "$ka" ] && [ "$ka" = "$kb" ] && [ "$n" = 1 ]; then
    pass "pg: one Idempotency-Key on two nodes at once: one job ($(cat "$TMP/ka.code")/$(cat "$TMP/kb.code"))"
else
    fail "pg: idempotency" "ids '$ka' '$kb', rows $n"
fi
wait_done "$URL_a" "$ka" > /dev/null

# 5b. a cancel sent to the node that does not run the job reaches its worker,
# in at most 5 times what a cancel sent to the runner itself takes (the same
# job, measured just before: a busy machine slows both), or 3 s
cancel_ms() { # self|other: submit a long job, cancel it through that node; prints "STATE MS RUNNER"
    post "$URL_a" "$TMP/cube.qmesh" "max_iter=10000&finish=0&tol_move=0&mode=literal&ls_halvings=0" "$TMP/jc" > /dev/null
    _id=$(jf "$TMP/jc" .id)
    curl -s -m 60 "$URL_a/v1/jobs/$_id/progress?after=0&wait=50" > /dev/null
    _r=$(pg_sql "SELECT lease_owner FROM jobs WHERE id = '$_id'")
    case $1:$_r in
    self:*:"$PID_a":* | other:*) _u=$URL_a ;;
    *) _u=$URL_b ;;
    esac
    case $1:$_r in other:*:"$PID_a":*) _u=$URL_b ;; esac
    _t0=$(date +%s%N)
    curl -s -o /dev/null -X POST "$_u/v1/jobs/$_id:cancel"
    _st=$(wait_done "$_u" "$_id")
    echo "$_st $((($(date +%s%N) - _t0) / 1000000)) $_r"
}
set -- $(cancel_ms self)
st0=$1 ms0=$2
set -- $(cancel_ms other)
st=$1 ms=$2 runner=$3
lim=$((5 * ms0))
[ $lim -lt 3000 ] && lim=3000
if [ "$st0" = cancelled ] && [ "$st" = cancelled ] && [ $ms -le $lim ]; then
    pass "pg: cancel sent to the other node stopped the running job in $ms ms (sent to its runner: $ms0 ms; limit $lim ms)"
else
    fail "pg: cross-node cancel" "state $st after $ms ms, limit $lim (runner $runner; to the runner: $st0 in $ms0 ms)"
fi

# 6. kill -9 of the node running a job: the other node takes it over after
# the lease expires and finishes it
stop "$PID_a"
stop "$PID_b"
node a "$TMP/da" --workers 1 --lease 2 || { fail "pg: node a" "$(tail -3 "$TMP/a.log")"; exit 1; }
# a run that ends by its time limit (4 s of its own), not by iterations: it
# cannot end before the kill however slow the machine; the kill waits for a
# progress record past the first (the run is under way)
post "$URL_a" "$TMP/cube.qmesh" "max_iter=10000&finish=0&tol_move=0&mode=literal&time_limit=4" "$TMP/jk" > /dev/null
idk=$(jf "$TMP/jk" .id)
curl -s -m 60 "$URL_a/v1/jobs/$idk/progress?after=0&wait=50" > /dev/null
kill -9 "$PID_a"
wait "$PID_a" 2> /dev/null
node b "$TMP/db" --workers 1 --lease 2 || { fail "pg: node b" "$(tail -3 "$TMP/b.log")"; exit 1; }
st=$(wait_done "$URL_b" "$idk")
att=$(curl -s "$URL_b/v1/jobs/$idk" | jq -r .attempts)
if [ "$st" = succeeded ] && [ "$att" = 2 ]; then
    pass "pg: kill -9 of the running node: the other node finished the job (attempts 2)"
else
    fail "pg: node killed" "state $st attempts $att"
fi

# 6b. the same with the default --lease: the lease is renewed by a heartbeat
# every lease/4, so the job runs again on the other node within 15 s
stop "$PID_b"
gzip -dc "$DEV/cube_h0.1_lowq.mesh.gz" > "$TMP/big.mesh"
$MT qmesh "$TMP/big.mesh" "$TMP/big.qmesh"
node a "$TMP/da" --workers 1 || { fail "pg: node a" "$(tail -3 "$TMP/a.log")"; exit 1; }
post "$URL_a" "$TMP/big.qmesh" "max_iter=400&finish=0&tol_move=0&mode=literal" "$TMP/jt" > /dev/null
idt=$(jf "$TMP/jt" .id)
curl -s -m 60 "$URL_a/v1/jobs/$idt/progress?after=0&wait=50" > /dev/null
node b "$TMP/db" --workers 1 || { fail "pg: node b" "$(tail -3 "$TMP/b.log")"; exit 1; }
kill -9 "$PID_a"
wait "$PID_a" 2> /dev/null
t0=$(date +%s.%N)
i=0
while [ $i -lt 600 ] && [ "$(pg_sql "SELECT attempts FROM jobs WHERE id = '$idt'")" != 2 ]; do
    sleep 0.1
    i=$((i + 1))
done
dt=$(echo "$(date +%s.%N) $t0" | awk '{ printf "%.1f", $1 - $2 }')
curl -s -X POST "$URL_b/v1/jobs/$idt:cancel" > /dev/null
if [ "$(pg_sql "SELECT attempts FROM jobs WHERE id = '$idt'")" = 2 ] &&
    [ "$(echo "$dt" | awk '{ print ($1 <= 15) }')" = 1 ]; then
    pass "pg: default --lease (10 s, heartbeat every 2.5 s): node killed, its job running again on the other node after $dt s (<= 15)"
else
    fail "pg: takeover with the default lease" "after $dt s: attempts $(pg_sql "SELECT attempts FROM jobs WHERE id = '$idt'")"
fi
stop "$PID_b"
node b "$TMP/db" --workers 1 --lease 2 || { fail "pg: node b" "$(tail -3 "$TMP/b.log")"; exit 1; }

# 7. the database stops and comes back while a job runs: the node survives,
# the job's end (written while the database is away) is retried until it is
# recorded, nothing is lost
n0=$(pg_sql "SELECT COUNT(*) FROM jobs")
post "$URL_b" "$TMP/cube.qmesh" "max_iter=40&finish=0&tol_move=0&mode=literal" "$TMP/jd" > /dev/null
idd=$(jf "$TMP/jd" .id)
wait_running "$URL_b" "$idd"
pg_stop
# the job ends while the database is away: its end is written when it is back
sleep 3
down=$(curl -s -o /dev/null -D "$TMP/down.h" -w '%{http_code}' -m 10 "$URL_b/v1/jobs/$idd")
grep -qi '^retry-after: ' "$TMP/down.h" || down="$down without Retry-After"
pg_up
st=$(wait_done "$URL_b" "$idd")
alive=no
kill -0 "$PID_b" 2> /dev/null && alive=yes
n=$(pg_sql "SELECT COUNT(*) FROM jobs")
if [ "$alive" = yes ] && [ "$st" = succeeded ] && [ "$n" = $((n0 + 1)) ] && [ "$down" = 503 ]; then
    pass "pg: database restarted mid-run: node alive, GET while down 503 (+ Retry-After), job succeeded, all $n jobs kept"
else
    fail "pg: database restart" "alive $alive state $st jobs $n (GET while down: $down) $(tail -2 "$TMP/b.log" | tr '\n' ' ')"
fi
stop "$PID_b"
exit 0
