#!/bin/sh
# pgcache.sh - the node-local cache cap of the PostgreSQL store (--cache-max):
# a real PostgreSQL (pg.inc), a real qdcd with --cache-max CAP. Checks:
#  - --cache-max without a PostgreSQL store is refused (exit 2);
#  - six small jobs and a long one fill the cache past CAP; once the files are
#    older than the 10 s minimum age, the least recently used are evicted
#    until it fits: the result read last survives, the one read before it
#    goes; qdcd_cache_bytes / qdcd_cache_evicted_total say so;
#  - the input of the job running on the node is never evicted, even when
#    evicting it is the only way under CAP (it is the oldest file);
#  - an evicted result is fetched again from the database: same bytes, same
#    ETag, back in the cache;
#  - once the long job has ended its input may go too: the cache ends <= CAP.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/pg.inc"
QDCD=${QDCD:-$BIN/qdcd}
QM='application/vnd.qdc.mesh'
MT="$PY $ROOT/tests/server/meshtool.py"
PIDS=
trap 'for p in $PIDS; do kill -9 $p 2>/dev/null; done; pg_cleanup; rm -rf "$TMP"' EXIT

CHECKS="sqlite refused|over the cap|lru eviction|running job kept|refetch|settles under the cap"
if ! pg_available; then
    pg_skip pgcache "$CHECKS"
    exit 0
fi

# 1. only with a PostgreSQL store
"$QDCD" --data "$TMP/sq" --cache-max 1000 --listen 127.0.0.1:0 > "$TMP/sq.log" 2>&1
rc=$?
if [ $rc = 2 ] && grep -q 'needs a PostgreSQL' "$TMP/sq.log"; then
    pass "pgcache: sqlite refused: --cache-max without --store postgresql:// exits 2 ($(head -1 "$TMP/sq.log"))"
else
    fail "pgcache: sqlite refused" "rc $rc: $(head -2 "$TMP/sq.log")"
fi

pg_started pgcache || exit 1
$MT qmesh "$ROOT/tests/data/sample/cube.mesh" "$TMP/cube.qmesh" || { fail "pgcache: sample" "meshtool"; exit 1; }
gzip -dc "$DEV/bunny_low_10k.mesh.gz" > "$TMP/bunny.mesh"
$MT qmesh "$TMP/bunny.mesh" "$TMP/bunny.qmesh" || { fail "pgcache: bunny" "meshtool"; exit 1; }
# CAP holds the long job's input and three small results, not more
big=$(wc -c < "$TMP/bunny.qmesh")
CAP=$((big + 80000))
node a "$TMP/da" --workers 1 --cache-max $CAP --lease 3 --shutdown-grace 1 ||
    { fail "pgcache: node starts" "$(tail -3 "$TMP/a.log")"; exit 1; }
cache_bytes() { find "$TMP/da/jobs" -type f -printf '%s\n' 2> /dev/null | awk '{ s += $1 } END { print s + 0 }'; }
metric() { curl -s "$URL_a/metrics" | awk -v m="$1" '$1 == m { print $2 }'; }
sha() { sha256sum "$1" | cut -d' ' -f1; }

# six small jobs, done
ids=
for i in 1 2 3 4 5 6; do
    post "$URL_a" "$TMP/cube.qmesh" "max_iter=5" "$TMP/j$i" > /dev/null
    ids="$ids $(jf "$TMP/j$i" .id)"
done
bad=
for id in $ids; do
    st=$(wait_done "$URL_a" "$id")
    [ "$st" = succeeded ] || bad="$bad $id:$st"
done
[ -z "$bad" ] || { fail "pgcache: small jobs" "$bad"; exit 1; }
set -- $ids
# a long job (cancelled at the end): its input is the oldest file while it runs
post "$URL_a" "$TMP/bunny.qmesh" "max_iter=10000&finish=0&tol_move=0&mode=literal" "$TMP/jl" > /dev/null
idl=$(jf "$TMP/jl" .id)
i=0
while [ $i -lt 200 ] && [ "$(curl -s "$URL_a/v1/jobs/$idl" | jq -r .state)" != running ]; do
    sleep 0.05
    i=$((i + 1))
done
# read the results of jobs 2..6, then job 1's: job 1 is the most recently used
for id in "$2" "$3" "$4" "$5" "$6" "$1"; do
    curl -s -D "$TMP/h.$id" -o "$TMP/r.$id" "$URL_a/v1/jobs/$id/result?format=qmesh"
    tr -d '\r' < "$TMP/h.$id" | awk -F': ' 'tolower($1) == "etag" { print $2 }' > "$TMP/e.$id"
    sleep 0.05
done
before=$(cache_bytes)
if [ "$before" -gt $CAP ]; then
    pass "pgcache: over the cap: $before bytes cached > --cache-max $CAP"
else
    fail "pgcache: over the cap" "only $before bytes cached (cap $CAP): nothing to evict"
fi

# 2. eviction, once the files are 10 s old (a scan every 2 s): until the cache fits
i=0
while [ $i -lt 120 ] && [ "$(cache_bytes)" -gt $CAP ]; do
    sleep 0.25
    i=$((i + 1))
done
sleep 2.5 # one more scan: nothing else goes
[ -n "${QDC_DEBUG:-}" ] && find "$TMP/da/jobs" -type f -printf '%A@ %s %p\n' | sort -n >&2
ev=$(metric qdcd_cache_evicted_total)
mb=$(metric qdcd_cache_bytes)
after=$(cache_bytes)
d=$TMP/da/jobs
lst=$(curl -s "$URL_a/v1/jobs/$idl" | jq -r .state)
if [ "${ev:-0}" -gt 0 ] && [ -f "$d/$1/result.qmesh" ] && ! [ -f "$d/$2/result.qmesh" ] &&
    ! [ -f "$d/$1/input.qmesh" ] && [ "$after" -le $CAP ] && [ "$mb" = "$after" ]; then
    pass "pgcache: lru eviction: $ev files evicted, $before -> $after bytes (<= $CAP; metric $mb); the result read last kept, the one read first and the unread inputs gone"
else
    fail "pgcache: lru eviction" "evicted ${ev:-?}, bytes $before -> $after (metric $mb, cap $CAP); job1 result $(ls "$d/$1" 2> /dev/null | tr '\n' ' ')/ job2 $(ls "$d/$2" 2> /dev/null | tr '\n' ' ')"
fi
if [ "$lst" = running ] && [ -f "$d/$idl/input.qmesh" ]; then
    pass "pgcache: running job kept: the running job's input ($big bytes, the oldest file) stays in the cache"
else
    fail "pgcache: running job kept" "long job $lst, its files: $(ls "$d/$idl" 2> /dev/null | tr '\n' ' ')"
fi

# 3. evicted results come back from the database: same bytes, same ETag
bad=
for id in "$2" "$3" "$4" "$5" "$6" "$1"; do
    curl -s -D "$TMP/h2.$id" -o "$TMP/r2.$id" "$URL_a/v1/jobs/$id/result?format=qmesh"
    tr -d '\r' < "$TMP/h2.$id" | awk -F': ' 'tolower($1) == "etag" { print $2 }' > "$TMP/e2.$id"
    cmp -s "$TMP/r.$id" "$TMP/r2.$id" || bad="$bad $id:bytes"
    cmp -s "$TMP/e.$id" "$TMP/e2.$id" && [ -s "$TMP/e.$id" ] || bad="$bad $id:etag"
    [ "$(sha "$TMP/r2.$id")" = "$(tr -d '"' < "$TMP/e2.$id")" ] || bad="$bad $id:etag-is-not-sha"
done
if [ -z "$bad" ] && [ -f "$d/$2/result.qmesh" ]; then
    pass "pgcache: refetch: the six results, evicted or not, served again with the same bytes and ETag; evicted ones are back in the cache"
else
    fail "pgcache: refetch" "$bad; job2 cache: $(ls "$d/$2" 2> /dev/null | tr '\n' ' ')"
fi

# 4. the long job ends: then its input may be evicted too, and the cache fits
code=$(curl -s -o /dev/null -w '%{http_code}' -X POST "$URL_a/v1/jobs/$idl:cancel")
st=$(wait_done "$URL_a" "$idl")
i=0
while [ $i -lt 80 ] && [ "$(cache_bytes)" -gt $CAP ]; do
    sleep 0.25
    i=$((i + 1))
done
final=$(cache_bytes)
if [ "$st" = cancelled ] && [ "$final" -le $CAP ]; then
    pass "pgcache: settles under the cap: long job cancelled ($code), cache $final bytes <= $CAP"
else
    fail "pgcache: settles under the cap" "cancel $code, state $st, cache $final bytes (cap $CAP)"
fi
stop "$PID_a"
rc=$?
[ $rc = 0 ] || fail "pgcache: SIGTERM" "node exited $rc: $(tail -3 "$TMP/a.log")"
exit 0
