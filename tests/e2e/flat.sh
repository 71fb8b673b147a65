#!/bin/sh
# flat.sh - no pass flattens a tet: a harshly tangled thin scanned shape
# (scripts/corpus.py bone-scan at 100k tets, 5% of the interior vertices
# pushed 0.8 of the mean edge, seed 1: 2589 tets inverted, none flat) came
# back with 2 tets slid flat (signed volume ~1e-24, counted neither inverted
# nor degenerate) before flat tets counted as unusable (lib/core/tet.h,
# 6V <= 1e-9 l_rms^3). Checked by the independent evaluator
# (tests/tools/evaluate.py): no tet degenerate, no more inverted than the
# input, the worst usable tet's mean ratio above the floor's (1.26e-6), and
# the summary line names no degenerate tet either.
. "$(dirname "$0")/../lib.sh"

corpus_mesh "flat: bone-scan-tangled" bone-scan-tangled 100000 --seed 1 --tangle-frac 0.05
in=$CORPUS_MESH
if ! "$BIN/qdc" optimize "$in" "$TMP/o.mesh" 2> "$TMP/err"; then
    fail "flat: bone-scan-tangled" "exit $?: $(tail -2 "$TMP/err")"
    exit 0
fi
if ! "$PY" "$QUALITY" "$in" > "$TMP/qi.json" 2> "$TMP/e" ||
    ! "$PY" "$QUALITY" "$TMP/o.mesh" > "$TMP/qo.json" 2>> "$TMP/e"; then
    fail "flat: evaluator" "$(tail -2 "$TMP/e")"
    exit 0
fi
why=$("$PY" - "$TMP/qi.json" "$TMP/qo.json" << 'EOF'
import json, sys
qi, qo = (json.load(open(f)) for f in sys.argv[1:3])
why = []
if qi["n_inverted"] < 1000 or qi["n_degenerate"] != 0:
    why.append("input: %d inverted, %d degenerate (want a harsh tangle, none flat)"
               % (qi["n_inverted"], qi["n_degenerate"]))
if qo["n_degenerate"] != 0:
    why.append("%d tets flat" % qo["n_degenerate"])
if qo["n_inverted"] > qi["n_inverted"]:
    why.append("inverted %d -> %d" % (qi["n_inverted"], qo["n_inverted"]))
if not qo["eta_min_valid"] > 2 * (1e-9 / 2) ** (2 / 3):
    why.append("worst usable tet's mean ratio %.3g at the flat floor" % qo["eta_min_valid"])
print("; ".join(why) if why else "ok inverted %d -> %d, none flat, worst usable tet %.3g (input %.3g)"
      % (qi["n_inverted"], qo["n_inverted"], qo["eta_min_valid"], qi["eta_min_valid"]))
EOF
)
verdict "flat: bone-scan-tangled 100k" "$why"
# (progress records of candidates a pass did not keep may count flat tets)
if grep '^qdc: .*mean ratio' "$TMP/err" | grep -q "degenerate"; then
    fail "flat: summary line" "$(grep '^qdc: .*mean ratio' "$TMP/err" | tail -1)"
else
    pass "flat: the summary line reports no degenerate tet"
fi
exit 0
