#!/bin/sh
# pg_bench.sh - qdcd on PostgreSQL (issue 13's targets), measured on loopback
# with a PostgreSQL server started for the run (tests/server/pg.inc: initdb
# into a temporary directory, as the postgres user; needs root):
#   1. cross-node long-poll wake-up: a long-poll parked on one node for a job
#      running on another, median delay after the worker node's own long-poll
#      (target <= 100 ms)
#   2. throughput of many small jobs (10k-tet bunny, --workers 1 per node)
#      with 1, 2 and 3 nodes, jobs per minute (and one SQLite node)
#   3. per-job overhead of the PostgreSQL store against SQLite: jobs one after
#      the other (submit, long-poll to the end, fetch the result) less each
#      job's own run, medians (target: difference <= 20 ms)
#   4. upload of a 1M-tet binary mesh to a PostgreSQL-backed node until the
#      202 (target <= 1.0 s), and the same on SQLite
# PostgreSQL runs with fsync on (PG_DURABLE=1), as a production server would.
# Usage: bench/pg_bench.sh [JOBS] (default 30 jobs per throughput run and 20
# per overhead run). Prints one line per figure.
ROOT=$(cd "$(dirname "$0")/.." && pwd)
export ROOT
. "$ROOT/tests/lib.sh"
. "$ROOT/tests/server/pg.inc"
PG_DURABLE=1 # fsync on, as SQLite's store
QDCD=${QDCD:-$BIN/qdcd}
QM='application/vnd.qdc.mesh'
NJ=${1:-30}
NS=$((NJ * 2 / 3))
LOAD="$PY $ROOT/bench/pg_load.py"
PIDS=
trap 'for p in $PIDS; do kill -9 $p 2>/dev/null; done; pg_cleanup; rm -rf "$TMP"' EXIT

pg_available || { echo "pg_bench: needs PostgreSQL's server binaries and root" >&2; exit 1; }
pg_start || { echo "pg_bench: PostgreSQL did not start" >&2; exit 1; }
gzip -dc "$ROOT/tests/data/dev/bunny_low_10k.mesh.gz" > "$TMP/bunny.mesh"
$PY "$ROOT/tests/server/meshtool.py" qmesh "$TMP/bunny.mesh" "$TMP/bunny.qmesh"
$PY "$ROOT/tests/server/meshtool.py" qmesh "$ROOT/tests/data/sample/cube.mesh" "$TMP/cube.qmesh"
$PY "$ROOT/bench/grid_qmesh.py" 56 "$TMP/1m.qmesh" > /dev/null
OPTS="--workers 1 --max-queued 10000"
url_of() { eval "echo \$URL_$1"; }
pid_of() { eval "echo \$PID_$1"; }
stop_all() { for _n in "$@"; do stop "$(pid_of "$_n")"; done; }
# sqlite NAME DIR: a node on the SQLite store (same helpers)
sqlite_node() {
    rm -f "$TMP/$1.port"
    "$QDCD" --listen 127.0.0.1:0 --port-file "$TMP/$1.port" --data "$2" $OPTS >> "$TMP/$1.log" 2>&1 &
    eval "PID_$1=$!"
    PIDS="$PIDS $!"
    until [ -s "$TMP/$1.port" ] && curl -sf "http://127.0.0.1:$(cat "$TMP/$1.port")/livez" > /dev/null; do sleep 0.1; done
    eval "URL_$1=http://127.0.0.1:$(cat "$TMP/$1.port")"
}

# 1. wake-up
node a "$TMP/da" $OPTS && node b "$TMP/db" $OPTS || { echo "pg_bench: nodes did not start" >&2; exit 1; }
post "$URL_a" "$TMP/bunny.qmesh" "max_iter=150&finish=0&tol_move=0&mode=literal" "$TMP/jw" > /dev/null
id=$(jf "$TMP/jw" .id)
until [ "$(curl -s "$URL_a/v1/jobs/$id" | jq -r .state)" = running ]; do sleep 0.05; done
case $(pg_sql "SELECT lease_owner FROM jobs WHERE id = '$id'") in
*:"$PID_a":*) w=$URL_a o=$URL_b ;;
*) w=$URL_b o=$URL_a ;;
esac
$PY "$ROOT/tests/server/xnode.py" wake "$w" "$o" "$id" > "$TMP/wake.json"
jq -r '"cross-node long-poll wake-up: median \(.median_ms) ms, p90 \(.p90_ms) ms, max \(.max_ms) ms after the worker node'"'"'s own long-poll, \(.samples) records (target <= 100 ms)"' "$TMP/wake.json"
stop_all a b

# 2. throughput, 1 to 3 nodes (a fresh set of data directories each time)
for k in 1 2 3; do
    urls=
    names=$(echo a b c | cut -d' ' -f1-$k)
    for n in $names; do
        rm -rf "$TMP/t$k$n"
        node "$n" "$TMP/t$k$n" $OPTS || { echo "pg_bench: node $n did not start" >&2; exit 1; }
        urls="$urls $(url_of "$n")"
    done
    $LOAD throughput "$NJ" "$TMP/bunny.qmesh" "" $urls > "$TMP/tp$k.json"
    jq -r --arg k "$k" '"throughput, \($k) PostgreSQL node(s), --workers 1 each: \(.jobs_per_min) jobs/min (\(.succeeded)/\(.jobs) 10k-tet jobs succeeded in \(.seconds) s)"' "$TMP/tp$k.json"
    stop_all $names
done
sqlite_node s "$TMP/ts"
$LOAD throughput "$NJ" "$TMP/bunny.qmesh" "" "$URL_s" > "$TMP/tps.json"
jq -r '"throughput, 1 SQLite node, --workers 1: \(.jobs_per_min) jobs/min (\(.succeeded)/\(.jobs) jobs succeeded in \(.seconds) s)"' "$TMP/tps.json"

# 3. per-job overhead: jobs one after the other, alternating between a
#    SQLite node and a PostgreSQL node; overhead = wall time less the run
for what in "cube max_iter=3" "bunny "; do
    set -- $what
    node p "$TMP/sp$1" $OPTS || exit 1
    $LOAD overhead "$NS" "$TMP/$1.qmesh" "${2:-}" "$URL_s" "$URL_p" > "$TMP/ov.json"
    stop_all p
    jq -r --arg m "$1" '"per-job overhead (\($m) jobs, \(.[0].jobs) per store, alternating; submit, long-poll to the end, result, less the run): PostgreSQL \(.[1].overhead_ms) ms, SQLite \(.[0].overhead_ms) ms: \((.[1].overhead_ms - .[0].overhead_ms) * 10 | round / 10) ms more (target <= 20 ms); median wall per job \(.[1].median_ms) vs \(.[0].median_ms) ms"' "$TMP/ov.json"
done
stop_all s

# 4. 1M-tet upload until the 202 (each job deleted at once, so no run
#    competes with the next upload)
upload() { # URL: prints seconds
    curl -s -o "$TMP/up" -w '%{time_total}\n' -X POST -H "Content-Type: $QM" --data-binary "@$TMP/1m.qmesh" "$1/v1/jobs?max_iter=1"
    curl -s -o /dev/null -X DELETE "$1/v1/jobs/$(jq -r .id "$TMP/up")"
    sleep 1
}
node p "$TMP/up" $OPTS || exit 1
: > "$TMP/tpg"
for r in 1 2 3 4 5; do upload "$URL_p" >> "$TMP/tpg"; done
stop_all p
sqlite_node s "$TMP/us"
: > "$TMP/tsq"
for r in 1 2 3 4 5; do upload "$URL_s" >> "$TMP/tsq"; done
stop_all s
med() { sort -n "$1" | awk '{ t[NR] = $1 } END { printf "median %.3f s, min %.3f s, max %.3f s", t[int((NR + 1) / 2)], t[1], t[NR] }'; }
echo "1M-tet binary upload to a PostgreSQL node until the 202: $(med "$TMP/tpg") over 5 (target <= 1.0 s); SQLite: $(med "$TMP/tsq")"
