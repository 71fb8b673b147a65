#!/bin/sh
# server_bench.sh - the daemon's targets, measured on loopback:
#   1. upload + validate + enqueue of a 1M-tet binary mesh (target <= 0.5 s)
#   2. 1000 parked long-polls: extra RSS (target <= 20 MB) and extra threads (0),
#      on new connections and on the connections of clients that poll in a loop
#   3. p99 latency of GET /v1/jobs/{id} while two jobs run (target <= 5 ms)
#   4. the same latency while 1M-tet uploads are being parsed (no target)
# Usage: bench/server_bench.sh [N_UPLOADS] (default 5). Prints one line per figure.
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
QDCD=${QDCD:-$ROOT/build/rel/qdcd}
PY=/usr/bin/python3
MT="$PY $ROOT/tests/server/meshtool.py"
NUP=${1:-5}
TMP=$(mktemp -d "${TMPDIR:-/tmp}/qdcd-bench.XXXXXX")
QPID=
trap 'if [ -n "$QPID" ]; then kill -9 $QPID 2>/dev/null; fi; rm -rf "$TMP"' EXIT

start() { # DATADIR options...
    d=$1; shift
    "$QDCD" --listen 127.0.0.1:0 --port-file "$d.port" --data "$d" "$@" > "$d.log" 2>&1 &
    QPID=$!
    i=0
    until [ -s "$d.port" ] && curl -sf "http://127.0.0.1:$(cat "$d.port")/livez" > /dev/null; do
        i=$((i + 1)); [ $i -lt 100 ] || { echo "qdcd did not start" >&2; exit 1; }; sleep 0.1
    done
    URL=http://127.0.0.1:$(cat "$d.port")
}
stop() { kill -TERM "$QPID"; wait "$QPID" || true; QPID=; }
rss_kb() { awk '/^VmRSS/ { print $2 }' "/proc/$1/status"; }

# A 1M-tet structured grid (56^3 cells x 6 tets).
$PY "$ROOT/bench/grid_qmesh.py" 56 "$TMP/1m.qmesh"

# 1. upload + validate + enqueue (the 202 means committed and fsynced). A fresh
#    daemon for each upload, so no earlier 1M-tet job competes for the cores.
: > "$TMP/times"
for r in $(seq "$NUP"); do
    rm -rf "$TMP/u" "$TMP/u.port"
    start "$TMP/u" --workers 1
    curl -s -o "$TMP/sub" -w '%{time_total}\n' -X POST -H 'Content-Type: application/vnd.qdc.mesh' \
        --data-binary "@$TMP/1m.qmesh" "$URL/v1/jobs?max_iter=1" >> "$TMP/times"
    jq -e '.mesh.tets > 1000000' "$TMP/sub" > /dev/null || { echo "upload failed: $(head -c 300 "$TMP/sub")" >&2; exit 1; }
    kill -9 "$QPID"; wait "$QPID" 2> /dev/null || true; QPID=
done
sort -n "$TMP/times" | awk -v n="$NUP" '{ t[NR] = $1 } END {
    printf "1M-tet binary upload+validate+enqueue (202): median %.3f s, min %.3f s, max %.3f s over %d (target <= 0.5 s)\n",
        t[int((n + 1) / 2)], t[1], t[n], n }'

# 2. 1000 parked long-polls. One job runs (one worker; literal mode, so it
#    does not stop early however fast the machine), the polls wait on a
#    second, queued job, so besides the running job only the parked
#    connections change. Two kinds of clients, each on a fresh daemon:
#    "first poll": a new connection per long-poll; "next poll": a client that
#    polls in a loop (one poll answered at once, then the parked one, over its
#    keep-alive connection unless the daemon closed it, as HTTP clients do).
#    The line says so if a poll was answered before RSS was sampled.
gzip -dc "$ROOT/tests/data/dev/cube_h0.1_lowq.mesh.gz" > "$TMP/cube.mesh"
parked_polls() { # KIND: first | next
    rm -rf "$TMP/p" "$TMP/p.port"
    start "$TMP/p" --workers 1
    curl -s -X POST -H 'Content-Type: model/x-medit' --data-binary "@$TMP/cube.mesh" \
        "$URL/v1/jobs?max_iter=10000&tol_move=0&finish=0&mode=literal" > "$TMP/a"
    curl -s -X POST -H 'Content-Type: model/x-medit' --data-binary "@$TMP/cube.mesh" "$URL/v1/jobs" > "$TMP/b"
    curl -s "$URL/v1/jobs/$(jq -r .id "$TMP/a")/progress?after=1&wait=30" > /dev/null
    $PY "$ROOT/tests/server/parkmem.py" "$URL" "$(jq -r .id "$TMP/a")" "$(jq -r .id "$TMP/b")" \
        "$QPID" 1000 "$1" > "$TMP/park.json"
    jq -r --arg kind "$1" '(if $kind == "first" then "first poll of each connection"
        else "next poll of looping clients (\(.reconnected) of 1000 reconnected)" end) as $what |
        "\(.parked) parked long-polls, \($what): RSS \(.rss_kb_before / 102.4 | round / 10) MB -> \(.rss_kb_parked / 102.4 | round / 10) MB (+\((.rss_kb_parked - .rss_kb_before) / 102.4 | round / 10) MB, \(.kb_each) KB each), threads \(.threads_before) -> \(.threads_parked) (target <= 20 MB, no extra threads); all hung up: " +
        (if .parked_after_hangup == 0 then "dropped in \(.hangup_s) s" else "\(.parked_after_hangup) still parked after 5 s" end) +
        (if .answered > 0 then "; INVALID: \(.answered) polls were answered before the sample" else "" end)' "$TMP/park.json"
    stop
}
parked_polls first
parked_polls next

# 3. GET /v1/jobs/{id} latency while two jobs run (2 workers, 2 long jobs)
start "$TMP/l" --workers 2
for k in 1 2; do
    curl -s -X POST -H 'Content-Type: model/x-medit' --data-binary "@$TMP/cube.mesh" \
        "$URL/v1/jobs?max_iter=10000&tol_move=0&finish=0&mode=literal" > "$TMP/j$k"
done
J=$(jq -r .id "$TMP/j1")
curl -s "$URL/v1/jobs/$J/progress?after=0&wait=30" > /dev/null
curl -s "$URL/v1/jobs/$(jq -r .id "$TMP/j2")/progress?after=0&wait=30" > /dev/null
$PY - "$URL" "$J" 3000 <<'PYEOF'
import http.client, sys, time, json
from urllib.parse import urlparse
url, job, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
u = urlparse(url)
c = http.client.HTTPConnection(u.hostname, u.port)
lat = []
running = 0
for i in range(n):
    t = time.perf_counter()
    c.request("GET", "/v1/jobs/" + job)
    r = c.getresponse()
    body = r.read()
    lat.append(time.perf_counter() - t)
    running += json.loads(body)["state"] == "running"
lat.sort()
p = lambda q: lat[min(len(lat) - 1, int(q * len(lat)))] * 1e3
print("GET /v1/jobs/{id} while 2 jobs run: p50 %.2f ms, p99 %.2f ms, max %.2f ms over %d requests (%d saw 'running') (target p99 <= 5 ms)"
      % (p(0.5), p(0.99), lat[-1] * 1e3, n, running))
PYEOF
stop

# 4. the same GET while 1M-tet uploads are parsed and validated (intake thread)
start "$TMP/i" --workers 1 --max-queued 100
curl -s -X POST -H 'Content-Type: model/x-medit' --data-binary "@$ROOT/tests/data/sample/cube.mesh" \
    "$URL/v1/jobs?max_iter=1" > "$TMP/s"
$PY - "$URL" "$(jq -r .id "$TMP/s")" "$TMP/1m.qmesh" 3 <<'PYEOF'
import http.client, sys, threading, time
from urllib.parse import urlparse
url, job, path, nup = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
u = urlparse(url)
body = open(path, "rb").read()
done = threading.Event()
up = []
def uploader():
    c = http.client.HTTPConnection(u.hostname, u.port, timeout=60)
    for i in range(nup):
        t = time.perf_counter()
        c.request("POST", "/v1/jobs?max_iter=1", body, {"Content-Type": "application/vnd.qdc.mesh"})
        r = c.getresponse(); r.read()
        up.append((r.status, time.perf_counter() - t))

    done.set()
th = threading.Thread(target=uploader); th.start()
c = http.client.HTTPConnection(u.hostname, u.port)
lat = []
while not done.is_set():
    t = time.perf_counter()
    c.request("GET", "/v1/jobs/" + job); c.getresponse().read()
    lat.append(time.perf_counter() - t)
th.join()
lat.sort()
p = lambda q: lat[min(len(lat) - 1, int(q * len(lat)))] * 1e3
print("GET /v1/jobs/{id} during %d 1M-tet uploads (%s): p50 %.2f ms, p99 %.2f ms, max %.2f ms over %d requests"
      % (nup, ", ".join("%d in %.2f s" % x for x in up), p(0.5), p(0.99), lat[-1] * 1e3, len(lat)))
PYEOF
stop
