#!/bin/sh
# untangle.sh - tangled thin, surface-heavy meshes come out with no tet
# inverted: scripts/corpus.py's bent bone (aspect about 12, half of the
# vertices on the surface) at 100k tets, as random surface points and as
# scan-like spaced ones, with 1% of the interior vertices pushed 0.8 of the
# mean edge (seed 8: 547 and 496 tets inverted). The finishing pass trades
# inverted tets for valid ones, and at the surface of these no later move
# undid some trades: a run that leaves tets inverted runs once more with no
# fold at the surface allowed (lib/opt/finish.c, folds_at_surface). Without
# that rerun these two kept 1 and 2 inverted tets. The count is the
# independent evaluator's (tests/tools/evaluate.py), and the mean ratio must
# rise.
. "$(dirname "$0")/../lib.sh"

names="bone-lowq-tangled bone-scan-tangled"
if ! "$PY" -c 'import numpy, scipy' 2> /dev/null; then
    for n in $names; do echo "ok - untangle: $n # SKIP python3-numpy/python3-scipy missing"; done
    exit 0
fi
if ! "$PY" "$ROOT/scripts/corpus.py" "$TMP/c" --tets 100000 --seed 8 \
    --only bone-lowq-tangled,bone-scan-tangled > "$TMP/list" 2>&1; then
    for n in $names; do fail "untangle: $n" "scripts/corpus.py failed: $(tail -1 "$TMP/list")"; done
    exit 1
fi
for n in $names; do
    in=$TMP/c/$n.mesh
    if ! "$BIN/qdc" optimize "$in" "$TMP/o.mesh" 2> "$TMP/err"; then
        fail "untangle: $n" "exit $?: $(tail -2 "$TMP/err")"
        continue
    fi
    out=$("$PY" "$QUALITY" "$in" | "$PY" -c 'import json, sys
d = json.load(sys.stdin); print(d["n_inverted"], "%.4f" % d["eta_mean"])')
    set -- $out
    bi=$1 bm=$2
    out=$("$PY" "$QUALITY" "$TMP/o.mesh" | "$PY" -c 'import json, sys
d = json.load(sys.stdin); print(d["n_inverted"], "%.4f" % d["eta_mean"])')
    set -- $out
    ai=$1 am=$2
    if [ "$bi" -gt 0 ] && [ "$ai" = 0 ] && awk -v a="$am" -v b="$bm" 'BEGIN { exit !(a > b) }'; then
        pass "untangle: $n"
    else
        fail "untangle: $n" "inverted $bi -> $ai, mean ratio $bm -> $am"
    fi
done
exit $((NFAIL > 0))
