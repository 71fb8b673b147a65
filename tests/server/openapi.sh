#!/bin/sh
# tests/server/openapi.sh - proto/openapi.yaml against the route table: every
# method and path qdcd routes (`qdcd --print-routes`, server/route.h) is
# documented, and nothing is documented that is not routed. HEAD is implied by
# GET (routed, not documented).
. "$(dirname "$0")/../lib.sh"
QDCD=${QDCD:-$BIN/qdcd}
if [ ! -x "$QDCD" ]; then
    fail "openapi" "no $QDCD (make all first)"
    exit 1
fi
if ! "$QDCD" --print-routes > "$TMP/routes"; then
    fail "openapi" "qdcd --print-routes failed"
    exit 1
fi
"$PY" - "$ROOT/proto/openapi.yaml" "$TMP/routes" <<'PYEOF'
import sys, yaml
spec = yaml.safe_load(open(sys.argv[1]))
methods = ("get", "put", "post", "delete", "options", "head", "patch", "trace")
documented = {(m.upper(), p) for p, item in spec["paths"].items() for m in item
              if m in methods}
routed = set()
for line in open(sys.argv[2]):
    m, p = line.split()
    if m != "HEAD":
        routed.add((m, p))
bad = 0
if len(routed) < 15:
    print("FAIL - openapi: only %d routes printed (the table is broken)" % len(routed))
    bad = 1
for m, p in sorted(routed - documented):
    print("FAIL - openapi: %s %s is routed but not in proto/openapi.yaml" % (m, p))
    bad = 1
for m, p in sorted(documented - routed):
    print("FAIL - openapi: %s %s is in proto/openapi.yaml but not routed" % (m, p))
    bad = 1
if not bad:
    print("ok - openapi: the %d routes of the table are the %d operations documented"
          % (len(routed), len(documented)))
sys.exit(bad)
PYEOF
