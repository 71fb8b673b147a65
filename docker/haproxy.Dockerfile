# The one port in front of the qdcd replicas of docker/compose.yaml: HAProxy
# from Debian's package (no registry image needed, only the local debian:bookworm-slim).
#   docker build -f docker/haproxy.Dockerfile -t qdc-haproxy docker
# QDC_BACKENDS: the replicas' HOST:PORT, space-separated; QDC_LISTEN: the
# address HAProxy binds (default 0.0.0.0:8080). See haproxy-entrypoint.sh.
FROM debian:bookworm-slim
RUN apt-get update \
    && apt-get install -y --no-install-recommends haproxy \
    && rm -rf /var/lib/apt/lists/*
COPY haproxy-entrypoint.sh /usr/local/bin/qdc-haproxy-entrypoint
COPY haproxy-503.http /etc/haproxy/qdc-503.http
USER haproxy
EXPOSE 8080
# SIGUSR1: HAProxy's soft stop (lets running requests and long-polls finish)
STOPSIGNAL SIGUSR1
ENTRYPOINT ["/usr/local/bin/qdc-haproxy-entrypoint"]
