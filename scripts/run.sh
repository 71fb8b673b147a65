#!/bin/sh
# run.sh - what `make run` starts: qdcd on 127.0.0.1:8080 with its data in ./var,
# in the foreground (Ctrl-C stops it gracefully). QDCD_LISTEN / QDCD_DATA override.
set -eu
cd "$(dirname "$0")/.."
LISTEN=${QDCD_LISTEN:-127.0.0.1:8080}
DATA=${QDCD_DATA:-./var}
BIN=build/rel/qdcd
[ -x "$BIN" ] || { echo "run.sh: $BIN is missing: run make all" >&2; exit 1; }
URL=http://$LISTEN
cat <<MSG
qdcd listens on $URL (data in $DATA; API: proto/openapi.yaml)
Web console: $URL/

Submit the sample mesh (750 tets, Medit) and follow it:
  curl -s -i -X POST -H 'Content-Type: model/x-medit' --data-binary @tests/data/sample/cube.mesh '$URL/v1/jobs?max_iter=10'
  curl -s '$URL/v1/jobs/JOB_ID/progress?after=-1&wait=30'
  curl -s '$URL/v1/jobs/JOB_ID/report'
  curl -s -o out.mesh '$URL/v1/jobs/JOB_ID/result?format=medit'

MSG
exec "$BIN" --listen "$LISTEN" --data "$DATA"
