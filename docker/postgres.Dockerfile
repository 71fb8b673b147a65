# PostgreSQL for docker/compose.yaml (the database the qdcd replicas share),
# from Debian's postgresql package: no registry image needed, only the local
# debian:bookworm-slim (docker/base-image.sh makes it where no registry is reached).
#   docker build -f docker/postgres.Dockerfile -t qdc-postgres docker
# The first start on an empty volume runs initdb with the user and database
# qdc and the password in POSTGRES_PASSWORD (or the file POSTGRES_PASSWORD_FILE).
FROM debian:bookworm-slim
# No cluster made by the package's postinst: the entrypoint makes one in $PGDATA.
RUN mkdir -p /etc/postgresql-common \
    && echo 'create_main_cluster = false' > /etc/postgresql-common/createcluster.conf \
    && apt-get update \
    && apt-get install -y --no-install-recommends postgresql-15 \
    && rm -rf /var/lib/apt/lists/* \
    && mkdir -p /var/lib/postgresql/data /run/postgresql \
    && chown postgres:postgres /var/lib/postgresql/data /run/postgresql \
    && chmod 700 /var/lib/postgresql/data
COPY postgres-entrypoint.sh /usr/local/bin/qdc-postgres-entrypoint
ENV PGDATA=/var/lib/postgresql/data PATH=/usr/lib/postgresql/15/bin:$PATH
USER postgres
VOLUME ["/var/lib/postgresql/data"]
EXPOSE 5432
# SIGINT: PostgreSQL's fast shutdown (SIGTERM would wait for every client to leave)
STOPSIGNAL SIGINT
HEALTHCHECK --interval=10s --timeout=5s --start-period=30s --retries=3 \
    CMD ["pg_isready", "-q", "-h", "/run/postgresql"]
ENTRYPOINT ["/usr/local/bin/qdc-postgres-entrypoint"]
