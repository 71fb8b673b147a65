#!/bin/sh
# format_table.sh - one format table: what `qdc formats` prints (the library's
# table, lib/io/formats.h) is what proto/openapi.yaml names (every enum of
# format names holds exactly the formats qdcd takes as uploads, by name or
# alias, and the surfaces; GET /v1/formats documented), what `qdc optimize
# --help` lists, and each format is one line of formats.h.
. "$(dirname "$0")/../lib.sh"
"$BIN/qdc" formats > "$TMP/f.json" || { fail "format table: qdc formats" "exit $?"; exit 1; }
"$BIN/qdc" optimize --help > "$TMP/help.txt" 2>&1
out=$("$PY" - "$TMP/f.json" "$ROOT/proto/openapi.yaml" "$TMP/help.txt" "$ROOT/lib/io/formats.h" << 'PYEOF'
import json, re, sys
t = json.load(open(sys.argv[1]))
doc = open(sys.argv[2]).read()
helptext = open(sys.argv[3]).read()
lines = [l for l in open(sys.argv[4]) if l.startswith("MESHIO_FORMAT(")]
bad = []
canon = {}
for f in t["formats"]:
    for n in [f["name"]] + f["aliases"]:
        canon[n] = f["name"]
surfaces = {s["name"] for s in t["surfaces"]}
uploads = {f["name"] for f in t["formats"] if f["upload"]}
enums = [m for m in re.findall(r"enum: \[([^\]]*)\]", doc) if "gmsh" in m.split(", ")]
if not enums:
    bad.append("no enum of format names in openapi.yaml")
for e in enums:
    words = [w.strip() for w in e.split(",")]
    unknown = [w for w in words if w not in canon and w not in surfaces]
    named = {canon[w] for w in words if w in canon}
    if unknown:
        bad.append("openapi names %s, not in the table" % unknown)
    if named != uploads:
        bad.append("an openapi enum lacks %s / has %s" % (sorted(uploads - named), sorted(named - uploads)))
if "  /v1/formats:" not in doc:
    bad.append("GET /v1/formats is not documented")
for f in t["formats"]:
    if not re.search(r"(^|[ |])%s([|,\n]|$)" % re.escape(f["name"]), helptext, re.M):
        bad.append("qdc optimize --help does not list " + f["name"])
if len(lines) != len(t["formats"]):
    bad.append("formats.h has %d lines, the table %d formats" % (len(lines), len(t["formats"])))
print("\n".join(bad))
PYEOF
)
if [ -z "$out" ]; then
    pass "format table: openapi.yaml, qdc optimize --help and formats.h name exactly the table's $(grep -c '"name"' "$TMP/f.json") entries"
else
    fail "format table" "$(printf '%s' "$out" | tr '\n' ';')"
fi
exit $NFAIL
