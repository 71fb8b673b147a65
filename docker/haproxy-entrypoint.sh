#!/bin/sh
# qdc-haproxy-entrypoint - write the HAProxy configuration for the qdcd
# replicas and exec HAProxy (PID 1). QDC_BACKENDS lists the replicas'
# HOST:PORT (space-separated; names are resolved again while running, so a
# replica may start after the balancer or come back with a new address);
# QDC_LISTEN is the address to bind (default 0.0.0.0:8080).
# - round robin; a replica is taken out while /readyz is not 200 (it is stopping
#   or has lost the database) and put back at its first 200;
# - a request whose connection fails is sent to another replica (retries 3,
#   redispatch: only connection failures, so an upload is never sent twice);
# - long-polls (qdcd's --max-wait, 60 s) and event streams are given time;
# - with no replica ready: 503, Retry-After: 5, problem+json.
set -eu
: "${QDC_BACKENDS:?set QDC_BACKENDS to the replicas HOST:PORT list}"
LISTEN=${QDC_LISTEN:-0.0.0.0:8080}
CFG=${QDC_HAPROXY_CFG:-/tmp/qdc-haproxy.cfg}
{
    cat << CFG
global
    maxconn 4096
    # soft stop (SIGUSR1): running requests may finish, for at most 65 s
    hard-stop-after 65s

resolvers dns
    parse-resolv-conf
    hold valid 5s
    hold nx 1s
    hold refused 1s
    hold timeout 1s
    hold other 1s

defaults
    mode http
    timeout connect 2s
    timeout client 120s
    timeout server 120s
    timeout http-request 120s
    timeout tunnel 1h
    timeout client-fin 5s
    retries 3
    option redispatch 1
    errorfile 503 /etc/haproxy/qdc-503.http

frontend qdc
    bind $LISTEN
    default_backend qdcd

backend qdcd
    balance roundrobin
    option httpchk GET /readyz
    http-check expect status 200
    default-server check inter 1s fall 2 rise 1 resolvers dns init-addr last,libc,none
CFG
    i=0
    for b in $QDC_BACKENDS; do
        i=$((i + 1))
        echo "    server qdcd$i $b"
    done
} > "$CFG"
exec haproxy -W -db -f "$CFG" "$@"
