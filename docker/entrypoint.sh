#!/bin/sh
# qdcd-entrypoint - start qdcd in the container (PID 1 after exec, so it gets
# SIGTERM directly). With /run/secrets/qdc_tokens (hashed tokens, one per line:
# qdcd --hash-token T), the API needs a bearer token; without it qdcd listens
# on all the container's interfaces with --insecure, and the port must only be
# published on a loopback address of the host (compose.yaml does).
set -eu
QDCD=${QDCD:-/usr/local/bin/qdcd}
TOKENS=${QDC_TOKENS_FILE:-/run/secrets/qdc_tokens}
if [ -r "$TOKENS" ]; then
    exec "$QDCD" --tokens "$TOKENS" "$@"
fi
echo "qdcd-entrypoint: no $TOKENS: API open to whoever reaches the port" >&2
exec "$QDCD" --insecure "$@"
