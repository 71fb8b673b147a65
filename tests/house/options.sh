#!/bin/sh
# options.sh - one option table: what `qdc options` prints (the library's
# table) is what proto/openapi.yaml documents for POST /v1/jobs (every option,
# same type, range and default, nothing more) and what `qdc optimize --help`
# lists.
. "$(dirname "$0")/../lib.sh"
"$BIN/qdc" options > "$TMP/t.json" || { fail "options: qdc options" "exit $?"; exit 1; }
out=$("$PY" - "$TMP/t.json" "$ROOT/proto/openapi.yaml" << 'PYEOF'
import json, re, sys
table = json.load(open(sys.argv[1]))
doc = open(sys.argv[2]).read()
post = doc[doc.index("  /v1/jobs:"):]
post = post[:post.index("\n  /v1/jobs/")]
bad = []
def num(x):
    return float(x)
for o in table:
    m = re.search(r"- \{name: %s, in: query.*\}\}?\s*$" % o["name"], post, re.M)
    block = m.group(0) if m else None
    if not block:
        m = re.search(r"- name: %s\n(?:          .*\n)+" % o["name"], post)
        block = m.group(0) if m else None
    if not block:
        bad.append(o["name"] + ": not documented")
        continue
    sch = block[block.index("schema:"):]
    t = re.search(r"type: (\w+)", sch).group(1)
    want = {"word": "string", "hausd": "string", "bool": "boolean", "integer": "integer", "number": "number"}[o["type"]]
    if t != want:
        bad.append("%s: type %s, table %s" % (o["name"], t, want))
    d = re.search(r"default: \"?([^,}\"]+)\"?", sch)
    dv = d.group(1).strip() if d else None
    if o["type"] == "bool":
        ok = dv == {"on": "true", "off": "false"}[o["default"]]
    elif o["type"] in ("integer", "number"):
        ok = dv is not None and num(dv) == num(o["default"])
    else:
        ok = dv == o["default"]
    if not ok:
        bad.append("%s: default %s, table %s" % (o["name"], dv, o["default"]))
    if o["type"] in ("integer", "number"):
        lo = re.search(r"(exclusiveMinimum|minimum): ([-0-9.e+]+)", sch)
        hi = re.search(r"maximum: ([-0-9.e+]+)", sch)
        if not lo or num(lo.group(2)) != o["min"] or (lo.group(1) == "exclusiveMinimum") != o["min_excluded"]:
            bad.append("%s: minimum %s, table %s%s" % (o["name"], lo and lo.group(0), "(" if o["min_excluded"] else "[", o["min"]))
        if not hi or num(hi.group(1)) != o["max"]:
            bad.append("%s: maximum %s, table %s" % (o["name"], hi and hi.group(1), o["max"]))
    if o["type"] == "word":
        e = re.search(r"enum: \[([^\]]*)\]", sch)
        if not e or [w.strip() for w in e.group(1).split(",")] != o["values"]:
            bad.append("%s: enum %s, table %s" % (o["name"], e and e.group(1), o["values"]))
print("; ".join(bad) if bad else "ok %d" % len(table))
PYEOF
)
case $out in
"ok "*) pass "options: proto/openapi.yaml documents the ${out#ok } options of the table with the same types, ranges and defaults" ;;
*) fail "options: openapi vs table" "$out" ;;
esac
"$BIN/qdc" optimize --help > "$TMP/help" 2>&1
missing=$("$PY" -c 'import json, sys
t = json.load(open(sys.argv[1])); h = open(sys.argv[2]).read()
print(" ".join(o["name"] for o in t if "--" + o["name"].replace("_", "-") not in h))' "$TMP/t.json" "$TMP/help")
[ -z "$missing" ] && pass "options: qdc optimize --help lists every option of the table" ||
    fail "options: --help" "missing: $missing"
exit 0
