#!/bin/sh
# tests/container/replicas.sh - docker/compose.yaml's topology run by a real
# container engine: PostgreSQL (docker/postgres.Dockerfile), three qdcd
# replicas on it (docker/Dockerfile, --store postgresql://, each its own cache
# volume) and HAProxy (docker/haproxy.Dockerfile) as the one port, all built
# here from debian:bookworm-slim.
# No compose tool runs it: Podman 4.3 has no `podman compose`, podman-compose
# is not installed, and compose's bridge networks would carry the test's
# traffic on private-range addresses, which tests here must not use. So
# compose_run.py turns compose.yaml itself into plain `podman run` commands
# (same images, commands, environment, volumes, stop signals, start order)
# on the host network, each service on its own loopback port; the test adds
# a shorter lease (3 s), one worker per replica and fsync=off.
# Checks:
#  - the three images build (the qdcd image's layers are shared with image.sh);
#  - PostgreSQL becomes ready, the replicas start on it, the balancer answers;
#  - six jobs submitted through the one port all succeed, more than one
#    replica ran them, each result fetched through the port is a valid mesh;
#  - kill -9 of the replica running a long job: the job still succeeds (run
#    again by another replica after the lease), and every request sent
#    through the port meanwhile is answered (the balancer sends around the
#    dead replica);
#  - PostgreSQL stopped: the balancer soon has no ready replica and answers 503
#    with Retry-After and a problem+json itself; PostgreSQL started again:
#    the replicas reconnect, the port is ready again and takes a job;
#  - `podman stop` ends the replicas (SIGTERM), the balancer (SIGUSR1) and
#    PostgreSQL (SIGINT), compose.yaml's stop signals, cleanly (exit 0).
# Without a working engine, or not as root, every check is reported as a skip.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/engine.inc"

CHECKS="replicas: images|replicas: start|replicas: jobs through one port|replicas: database restart|replicas: replica killed mid-job|replicas: SIGTERM stop"
engine_or_skip "$CHECKS"
$PY -c 'import yaml' 2> /dev/null || skip_checks "$CHECKS" "no PyYAML (apt-get install python3-yaml)"

P=qdc-rep-$$
SERVICES="postgres qdcd1 qdcd2 qdcd3 lb"
cleanup() {
    for s in $SERVICES; do "$ENGINE" rm -f "$P-$s" > /dev/null 2>&1; done
    for v in qdc-pg qdc-cache1 qdc-cache2 qdc-cache3; do "$ENGINE" volume rm -f "$P-$v" > /dev/null 2>&1; done
    rm -rf "$TMP"
}
trap cleanup EXIT
trap 'exit 1' INT TERM HUP PIPE # so that cleanup runs then too

# 1. images: the qdcd image from the repository, the others from docker/
base_image || { fail "replicas: base image" "$(tail -3 "$TMP/base.log" | tr '\n' ' ')"; exit 1; }
repo_context "$TMP/ctx"
took=
for spec in "$IMG_QDC Dockerfile $TMP/ctx" "$IMG_PG postgres.Dockerfile $TMP/ctx/docker" \
    "$IMG_LB haproxy.Dockerfile $TMP/ctx/docker"; do
    set -- $spec
    if ! build_image "$1" "$TMP/ctx/docker/$2" "$3"; then
        fail "replicas: images" "$2: $(tail -5 "$TMP/build.log" | tr '\n' ' ')"
        exit 1
    fi
    took="$took $2 ${BUILD_S} s ${BUILD_MB} MB,"
done
pass "replicas: images built ($ENGINE; layers cached between runs):${took%,}"

# 2. the topology of compose.yaml, each service on a loopback port
free_port() {
    /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'
}
ports=
for s in $SERVICES; do
    p=$(free_port)
    ports="$ports$s=$p,"
    eval "PORT_$s=$p"
done
QDC_PG_PASSWORD=$(od -An -N12 -tx1 /dev/urandom | tr -d ' \n')
export QDC_PG_PASSWORD
EXTRA="postgres=-c listen_addresses=127.0.0.1 -c fsync=off"
for s in qdcd1 qdcd2 qdcd3; do
    EXTRA="$EXTRA;$s=--lease 3 --workers 1 --shutdown-grace 1 --max-attempts 3"
done
if ! $PY "$ROOT/tests/container/compose_run.py" "$ROOT/docker/compose.yaml" "$ENGINE" "$P" "$ports" \
    "Dockerfile=$IMG_QDC,postgres.Dockerfile=$IMG_PG,haproxy.Dockerfile=$IMG_LB" "$EXTRA" > "$TMP/run.txt" 2> "$TMP/run.err"; then
    fail "replicas: start" "compose_run.py: $(cat "$TMP/run.err")"
    exit 1
fi
[ "$(cut -f1 "$TMP/run.txt" | tr '\n' ' ')" = "postgres qdcd1 qdcd2 qdcd3 lb " ] ||
    { fail "replicas: start" "compose.yaml's services in start order: $(cut -f1 "$TMP/run.txt" | tr '\n' ' ')"; exit 1; }
URL=http://127.0.0.1:$PORT_lb
url_of() { eval "echo http://127.0.0.1:\$PORT_$1"; }
logs() { "$ENGINE" logs "$P-$1" 2>&1 | tail -3 | tr '\n' ' '; }
up() { # SERVICE: its run command from compose_run.py
    eval "$(awk -F'\t' -v s="$1" '$1 == s { print $2 }' "$TMP/run.txt")" > /dev/null
}
t0=$(date +%s)
bad=
up postgres || bad="postgres run"
i=0 # depends_on: service_healthy, as the image's HEALTHCHECK decides it
until "$ENGINE" exec "$P-postgres" pg_isready -q -h /run/postgresql -p "$PORT_postgres" 2> /dev/null; do
    i=$((i + 1))
    [ $i -ge 150 ] && { bad="postgres not ready: $(logs postgres)"; break; }
    sleep 0.2
done
for s in qdcd1 qdcd2 qdcd3; do
    [ -z "$bad" ] && { up $s || bad="$s run"; }
done
for s in qdcd1 qdcd2 qdcd3; do
    i=0
    while [ -z "$bad" ] && [ "$(curl -s -m 2 -o /dev/null -w '%{http_code}' "$(url_of $s)/livez")" != 200 ]; do
        i=$((i + 1))
        [ $i -ge 150 ] && bad="$s not live: $(logs $s)"
        sleep 0.2
    done
done
[ -z "$bad" ] && { up lb || bad="lb run"; }
i=0
while [ -z "$bad" ] && [ "$(curl -s -m 2 -o /dev/null -w '%{http_code}' "$URL/readyz")" != 200 ]; do
    i=$((i + 1))
    [ $i -ge 100 ] && bad="no ready replica behind the balancer: $(logs lb)"
    sleep 0.2
done
if [ -z "$bad" ]; then
    pass "replicas: start: postgres ready, qdcd1-3 live on it, the balancer's port answers /readyz 200 ($(($(date +%s) - t0)) s)"
else
    fail "replicas: start" "$bad"
    exit 1
fi

# 3. six jobs through the one port
QM='application/vnd.qdc.mesh'
MT="$PY $ROOT/tests/server/meshtool.py"
$MT qmesh "$ROOT/tests/data/sample/cube.mesh" "$TMP/cube.qmesh" || { fail "replicas: sample" "meshtool"; exit 1; }
post() { # FILE QUERY OUT: status code
    curl -s -m 60 -o "$3" -w '%{http_code}' -X POST --data-binary "@$1" -H "Content-Type: $QM" "$URL/v1/jobs?$2"
}
wait_done() { # ID: the final state through the port (max 60 s); counts other answers than 200 in NON200
    _i=0
    while [ $_i -lt 300 ]; do
        _c=$(curl -s -m 10 -o "$TMP/st" -w '%{http_code}' "$URL/v1/jobs/$1")
        if [ "$_c" != 200 ]; then
            NON200="$NON200 $_c"
        elif [ "$(jq -r .done "$TMP/st")" = true ]; then
            jq -r .state "$TMP/st"
            return 0
        fi
        sleep 0.2
        _i=$((_i + 1))
    done
    echo timeout
}
succeeded_on() { # SERVICE: qdcd_jobs_finished_total{state="succeeded"} of that replica
    curl -s -m 5 "$(url_of "$1")/metrics" | awk '/^qdcd_jobs_finished_total\{state="succeeded"\}/ { print $2 }'
}
ids=
codes=
for i in 1 2 3 4 5 6; do
    codes="$codes$(post "$TMP/cube.qmesh" "max_iter=8" "$TMP/j$i")"
    ids="$ids $(jq -r .id "$TMP/j$i")"
done
NON200=
bad=
for id in $ids; do
    st=$(wait_done "$id")
    [ "$st" = succeeded ] || bad="$bad $id:$st"
    c=$(curl -s -m 30 -o "$TMP/r.mesh" -w '%{http_code}' "$URL/v1/jobs/$id/result?format=medit")
    [ "$c" = 200 ] && "$BIN/qdc" quality "$TMP/r.mesh" > /dev/null 2>&1 || bad="$bad $id:result-$c"
done
spread=
nrep=0
total=0
for s in qdcd1 qdcd2 qdcd3; do
    n=$(succeeded_on $s)
    spread="$spread $s=${n:-?}"
    [ "${n:-0}" -gt 0 ] && nrep=$((nrep + 1))
    total=$((total + ${n:-0}))
done
if [ "$codes" = 202202202202202202 ] && [ -z "$bad" ] && [ -z "$NON200" ] && [ $total = 6 ] && [ $nrep -ge 2 ]; then
    pass "replicas: jobs through one port: 6 submitted (202), all succeeded, results valid meshes; run by$spread"
else
    fail "replicas: jobs through one port" "codes $codes,$bad; other answers:$NON200; runs:$spread"
fi

# 4. the database away and back, behind the balancer
"$ENGINE" stop -t 30 "$P-postgres" > /dev/null 2>&1
t0=$(date +%s%N)
i=0
c=
while [ $i -lt 100 ]; do
    c=$(curl -s -m 5 -D "$TMP/h503" -o "$TMP/b503" -w '%{http_code}' "$URL/v1/jobs/$(echo $ids | cut -d' ' -f1)")
    # first the replicas' own 503 (store-unavailable), then, once the checks
    # have taken every replica out, the balancer's
    [ "$c" = 503 ] && grep -qi '^retry-after: 5' "$TMP/h503" && [ "$(jq -r .status "$TMP/b503" 2> /dev/null)" = 503 ] &&
        jq -r .detail "$TMP/b503" | grep -q 'no qdcd node is ready' && break
    sleep 0.2
    i=$((i + 1))
done
gone=$((($(date +%s%N) - t0) / 1000000))
t0=$(date +%s%N)
"$ENGINE" start "$P-postgres" > /dev/null 2>&1
i=0
while [ $i -lt 150 ] && [ "$(curl -s -m 2 -o /dev/null -w '%{http_code}' "$URL/readyz")" != 200 ]; do
    sleep 0.2
    i=$((i + 1))
done
back=$((($(date +%s%N) - t0) / 1000000))
code=$(post "$TMP/cube.qmesh" "max_iter=5" "$TMP/jdb")
NON200=
st=$(wait_done "$(jq -r .id "$TMP/jdb")")
alive=
for s in qdcd1 qdcd2 qdcd3; do
    [ "$("$ENGINE" inspect "$P-$s" --format '{{.State.Running}}')" = true ] && alive="$alive $s"
done
if [ "$c" = 503 ] && [ "$code" = 202 ] && [ "$st" = succeeded ] && [ "$alive" = " qdcd1 qdcd2 qdcd3" ]; then
    pass "replicas: database restart: PostgreSQL stopped -> within $gone ms the balancer answers 503 itself, Retry-After: 5, problem+json ($(jq -c .type "$TMP/b503")); started again -> ready through the port in $back ms (podman start included), a new job succeeded; no replica died"
else
    fail "replicas: database restart" "while down: $c $(head -c 200 "$TMP/b503"); after: ready in $back ms, POST $code, job $st, running:$alive"
fi

# 5. kill -9 of the replica running a long job
gzip -dc "$DEV/bunny_low_10k.mesh.gz" > "$TMP/bunny.mesh"
$MT qmesh "$TMP/bunny.mesh" "$TMP/bunny.qmesh" || { fail "replicas: bunny" "meshtool"; exit 1; }
post "$TMP/bunny.qmesh" "max_iter=300&finish=0&tol_move=0&mode=literal" "$TMP/jl" > /dev/null
idl=$(jq -r .id "$TMP/jl")
owner=
i=0
while [ $i -lt 200 ] && [ -z "$owner" ]; do
    owner=$("$ENGINE" exec -e PGPASSWORD="$QDC_PG_PASSWORD" "$P-postgres" psql -h 127.0.0.1 -p "$PORT_postgres" -U qdc -d qdc -Atc \
        "SELECT lease_owner FROM jobs WHERE id = '$idl' AND state = 1" 2> "$TMP/psql.err")
    [ -z "$owner" ] && sleep 0.05
    i=$((i + 1))
done
victim=${owner%%:*}
NON200=
case $victim in
qdcd1 | qdcd2 | qdcd3)
    sleep 0.3
    before=$(curl -s -m 5 "$URL/v1/jobs/$idl" | jq -r '"\(.state), \(.iterations) iterations"')
    "$ENGINE" kill -s KILL "$P-$victim" > /dev/null
    st=$(wait_done "$idl")
    att=$(jq -r .attempts "$TMP/st")
    c=$(curl -s -m 30 -o "$TMP/rl.mesh" -w '%{http_code}' "$URL/v1/jobs/$idl/result?format=medit")
    q=$("$BIN/qdc" quality "$TMP/rl.mesh" 2>&1 | head -1 | sed "s/^[^:]*: //")
    krc=$("$ENGINE" inspect "$P-$victim" --format '{{.State.ExitCode}}')
    if [ "$st" = succeeded ] && [ "$att" = 2 ] && [ "$c" = 200 ] && "$BIN/qdc" quality "$TMP/rl.mesh" > /dev/null 2>&1 &&
        [ -z "$NON200" ]; then
        pass "replicas: replica killed mid-job: $victim (exit $krc) was running it ($before); the job succeeded on attempt 2, its result through the port is a valid mesh ($q); every request through the port answered 200"
    else
        fail "replicas: replica killed mid-job" "killed $victim ($before): state $st, attempts $att, result $c, other answers:$NON200"
    fi
    ;;
*)
    fail "replicas: replica killed mid-job" "no replica holds the job's lease (owner '$owner'; $(cat "$TMP/psql.err"); job $(curl -s "$URL/v1/jobs/$idl" | head -c 300))"
    victim=
    ;;
esac

# 6. SIGTERM: replicas, then the balancer, then the database (compose down's order)
res=
ok=1
for s in qdcd1 qdcd2 qdcd3 lb postgres; do
    [ "$s" = "$victim" ] && continue
    t0=$(date +%s%N)
    "$ENGINE" stop -t 30 "$P-$s" > /dev/null 2>&1
    ms=$((($(date +%s%N) - t0) / 1000000))
    rc=$("$ENGINE" inspect "$P-$s" --format '{{.State.ExitCode}}')
    res="$res $s=$rc/${ms}ms"
    [ "$rc" = 0 ] && [ $ms -lt 15000 ] || ok=
done
if [ -n "$ok" ]; then
    pass "replicas: SIGTERM stop: every container exited 0 on its stop signal (replicas SIGTERM, lb SIGUSR1, postgres SIGINT; exit/time:$res)"
else
    fail "replicas: SIGTERM stop" "exit/time:$res; $(logs qdcd1)"
fi
exit 0
