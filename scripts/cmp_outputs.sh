#!/bin/sh
# cmp_outputs.sh - check that two builds of qdc optimize give bit-identical
# results: for each mesh, `qdc optimize` with the default options, with
# --boundary fixed, and with --report; the meshes compared with cmp, the
# reports with their timing fields ("seconds", "elapsed") left out.
# Usage: scripts/cmp_outputs.sh OLD_QDC NEW_QDC WORKDIR MESH...
#   e.g. git worktree add /tmp/base HEAD~3 && make -C /tmp/base build/rel/qdc &&
#        cp build/rel/qdc /tmp/qdc.new &&
#        scripts/cmp_outputs.sh /tmp/base/build/rel/qdc /tmp/qdc.new /tmp/cmp \
#            tests/data/dev/*.mesh.gz
#   (copy the new binary first: a rebuild during the run would change it).
# Prints `ok - NAME` or `FAIL - NAME`, then a count; exits 1 if any differ.
set -u
[ $# -ge 4 ] || { echo "usage: $0 OLD_QDC NEW_QDC WORKDIR MESH..." >&2; exit 2; }
old=$1 new=$2 dir=$3
shift 3
mkdir -p "$dir/old" "$dir/new" || exit 2
strip_times() {
    python3 -c 'import json, sys
def s(o):
    if isinstance(o, dict):
        return {k: s(v) for k, v in o.items() if k not in ("seconds", "elapsed")}
    return [s(v) for v in o] if isinstance(o, list) else o
json.dump(s(json.load(open(sys.argv[1]))), sys.stdout, sort_keys=True)' "$1"
}
n=0 bad=0
for m in "$@"; do
    name=$(basename "$m" | sed 's/\.gz$//; s/\.[^.]*$//')
    for side in old new; do
        bin=$old
        [ $side = new ] && bin=$new
        o=$dir/$side/$name
        "$bin" optimize "$m" "$o.def.mesh" >/dev/null 2>&1 || echo "# $side failed: $name default"
        "$bin" optimize "$m" "$o.fix.mesh" --boundary fixed >/dev/null 2>&1 ||
            echo "# $side failed: $name fixed"
        "$bin" optimize "$m" "$o.rep.mesh" --report "$o.json" >/dev/null 2>&1 ||
            echo "# $side failed: $name report"
        strip_times "$o.json" >"$o.json.strip" 2>/dev/null || : >"$o.json.strip"
    done
    for f in def.mesh fix.mesh rep.mesh json.strip; do
        n=$((n + 1))
        if [ -s "$dir/old/$name.$f" ] && cmp -s "$dir/old/$name.$f" "$dir/new/$name.$f"; then
            echo "ok - $name.$f"
        else
            echo "FAIL - $name.$f"
            bad=$((bad + 1))
        fi
    done
done
echo "# compared $n files, $bad differ"
[ $bad -eq 0 ]
