#!/bin/sh
# local.sh - tets the finishing pass leaves inverted are repaired where they
# are (lib/opt/local.c): the tets within a few rings of them optimized again
# as a mesh of their own, the rest of the mesh as it was, instead of the whole
# run again from the input. The tangled dev torus (8727 tets inverted) kept 8
# after untangling; the rerun that freed the boundary around them took the
# whole mesh again and widened the bound to 1e-2 of the diagonal. Now one
# local round at the default bound repairs them: 0 inverted (independent
# evaluator), no rerun, the surface within the default bound (3e-3 of the
# diagonal of all the vertices, some pushed outside: 3.03e-3 of the surface's), the
# angle polish run on the whole mesh after it (smallest dihedral over 10°),
# and the mean ratio up from the input's.
. "$(dirname "$0")/../lib.sh"

in=$TMP/torus.mesh
gzip -dc "$DEV/torus_h0.1_tangled.mesh.gz" > "$in"
if ! "$BIN/qdc" optimize "$in" "$TMP/o.mesh" --report "$TMP/r.json" 2> "$TMP/err"; then
    fail "local: torus" "exit $?: $(tail -2 "$TMP/err")"
    exit 0
fi
set -- $("$PY" - "$in" "$TMP/o.mesh" "$TMP/r.json" "$QUALITY" <<'PYEOF'
import json, subprocess, sys
src, out, rep, quality = sys.argv[1:5]
q = lambda p: json.loads(subprocess.run([sys.executable, quality, p], capture_output=True,
                                        text=True, check=True).stdout)
qi, qo, r = q(src), q(out), json.load(open(rep))
be = r["boundary_error"]
print(qi["n_inverted"], qo["n_inverted"], "%.4f" % qi["eta_mean"], "%.4f" % qo["eta_mean"],
      "%.2f" % qo["dihedral_min"], "%.3e" % be["hausdorff_rel"],
      "%.3e" % (r["run"]["hausd_bound"] / be["bbox_diagonal"]))
PYEOF
)
bi=$1 ai=$2 bm=$3 am=$4 dmin=$5 hd=$6 bound=$7
if grep -q 'local repair: .*: kept' "$TMP/err" && ! grep -q ' again ' "$TMP/err"; then
    pass "local: torus: repaired locally, no rerun of the whole mesh"
else
    fail "local: torus: repaired locally" "$(grep -E 'local|again' "$TMP/err" | head -3)"
fi
if [ "$bi" -gt 0 ] && [ "$ai" = 0 ] && awk -v a="$am" -v b="$bm" -v d="$dmin" \
    -v h="$hd" -v B="$bound" 'BEGIN { exit !(a > b && d > 10 && h <= B * 1.0001 && B < 3.1e-3) }'; then
    pass "local: torus: inverted $bi -> 0, mean ratio $bm -> $am, smallest dihedral $dmin, Hausdorff $hd (bound $bound)"
else
    fail "local: torus" "inverted $bi -> $ai, mean $bm -> $am, dihedral $dmin, Hausdorff $hd, bound $bound"
fi
exit 0
