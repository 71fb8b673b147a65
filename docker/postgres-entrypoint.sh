#!/bin/sh
# qdc-postgres-entrypoint - PostgreSQL for the qdcd replicas (PID 1 after exec).
# On an empty $PGDATA: initdb with the superuser qdc, a database qdc, and
# password (scram-sha-256) authentication for connections over the network;
# the password comes from POSTGRES_PASSWORD or the file POSTGRES_PASSWORD_FILE.
# Then postgres listens on every interface of the container on $PGPORT (5432);
# arguments are passed on to postgres (-c name=value ...).
set -eu
PGDATA=${PGDATA:-/var/lib/postgresql/data}
PGPORT=${PGPORT:-5432}
if [ ! -s "$PGDATA/PG_VERSION" ]; then
    pw=${POSTGRES_PASSWORD:-}
    if [ -z "$pw" ] && [ -n "${POSTGRES_PASSWORD_FILE:-}" ]; then
        pw=$(cat "$POSTGRES_PASSWORD_FILE")
    fi
    if [ -z "$pw" ]; then
        echo "qdc-postgres: set POSTGRES_PASSWORD (or POSTGRES_PASSWORD_FILE) for the first start" >&2
        exit 2
    fi
    pwfile=$(mktemp)
    printf '%s\n' "$pw" > "$pwfile"
    initdb -D "$PGDATA" -U qdc --pwfile="$pwfile" -A scram-sha-256 --auth-local=peer \
        -E UTF8 --locale=C.UTF-8 > /dev/null
    rm -f "$pwfile"
    # the replicas connect over the container network
    echo 'host all all all scram-sha-256' >> "$PGDATA/pg_hba.conf"
    echo 'CREATE DATABASE qdc OWNER qdc' | postgres --single -D "$PGDATA" -c exit_on_error=on postgres > /dev/null
    echo "qdc-postgres: initialized $PGDATA (user qdc, database qdc)" >&2
fi
exec postgres -D "$PGDATA" -c listen_addresses='*' -p "$PGPORT" \
    -c unix_socket_directories=/run/postgresql "$@"
