#!/bin/sh
# local.sh - tets the finishing pass leaves inverted are repaired where they
# are (lib/opt/local.c): the tets within a few rings of them optimized again
# as a mesh of their own, the rest of the mesh as it was, instead of the
# whole run again from the input with the boundary around them freed to 1e-2
# of the diagonal. A harshly tangled thin bone (scripts/corpus.py bone-lowq
# at 30k tets, 5% of the interior vertices pushed, seed 1: 737 tets inverted)
# kept 1 inverted after untangling the interior vertices: local repairs took
# it to 0; untangling that slides the boundary vertices too now does (either
# counts as repaired where it is). 0 left (independent evaluator), with no
# rerun that frees the boundary, the surface within the default bound (3e-3
# of the diagonal) and the mean ratio up; the same bytes at 1, 2 and 4
# threads.
. "$(dirname "$0")/../lib.sh"

corpus_mesh "local: bone-lowq-tangled" bone-lowq-tangled 30000 --seed 1 --tangle-frac 0.05
in=$CORPUS_MESH
if ! "$BIN/qdc" optimize "$in" "$TMP/o.mesh" --report "$TMP/r.json" 2> "$TMP/err"; then
    fail "local: bone-lowq-tangled" "exit $?: $(tail -2 "$TMP/err")"
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
      "%.3e" % be["hausdorff_rel"], "%.3e" % (r["run"]["hausd_bound"] / be["bbox_diagonal"]))
PYEOF
)
bi=$1 ai=$2 bm=$3 am=$4 hd=$5 bound=$6
if grep -Eq 'local repair: .*: kept|^untangle .* inverted 0 ' "$TMP/err" &&
    ! grep -q 'boundary vertices around them free' "$TMP/err" &&
    ! grep -q 'with the boundary within' "$TMP/err"; then
    pass "local: bone-lowq-tangled: repaired locally, no rerun that frees the boundary"
else
    fail "local: bone-lowq-tangled: repaired locally" "$(grep -E 'local|again' "$TMP/err" | head -3)"
fi
if [ "$bi" -gt 0 ] && [ "$ai" = 0 ] && awk -v a="$am" -v b="$bm" -v h="$hd" -v B="$bound" \
    'BEGIN { exit !(a > b && h <= B * 1.0001 && B < 3.0001e-3) }'; then
    pass "local: bone-lowq-tangled: inverted $bi -> 0, mean ratio $bm -> $am, Hausdorff $hd (bound $bound)"
else
    fail "local: bone-lowq-tangled" "inverted $bi -> $ai, mean $bm -> $am, Hausdorff $hd, bound $bound"
fi
# The untangling moves colour classes in parallel, as the sweeps do: the same
# run gives the same bytes at 1, 2 and 4 threads.
same=yes
for n in 1 2 4; do
    OMP_NUM_THREADS=$n "$BIN/qdc" optimize "$in" "$TMP/t$n.mesh" 2> /dev/null || same="exit $? at $n"
    [ "$same" = yes ] && ! cmp -s "$TMP/t1.mesh" "$TMP/t$n.mesh" && same="differs at $n threads"
done
if [ "$same" = yes ] && grep -q '^untangle' "$TMP/err"; then
    pass "local: bone-lowq-tangled: untangled, the same bytes at 1, 2 and 4 threads"
else
    fail "local: bone-lowq-tangled: the same bytes at 1, 2 and 4 threads" "$same"
fi
exit 0
