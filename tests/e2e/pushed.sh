#!/bin/sh
# pushed.sh - a tangle whose pushed vertices went through the surface is
# untangled in every mode. scripts/corpus.py's thin torus at 20k tets with 5%
# of its interior vertices pushed (seed 7: 507 tets inverted) kept 3 tets
# inverted (5 with the boundary fixed, 2-3 with --topology) around one vertex
# left 1.8 edges outside, its neighbours dragged along: no move of one vertex
# opened its star, and the reruns of slide mode did not either. Checked by the
# independent evaluator (tests/tools/evaluate.py): no tet inverted, none flat,
# the worst usable tet no worse than the input's.
. "$(dirname "$0")/../lib.sh"

corpus_mesh "pushed: torus-lowq-tangled" torus-lowq-tangled 20000 --seed 7 --tangle-frac 0.05
in=$CORPUS_MESH
if ! "$PY" "$QUALITY" "$in" > "$TMP/qi.json" 2> "$TMP/e"; then
    fail "pushed: evaluator on the input" "$(tail -2 "$TMP/e")"
    exit 0
fi
for mode in default "--boundary fixed" "--topology flips" "--topology full --boundary fixed"; do
    case $mode in default) opts= ;; *) opts=$mode ;; esac
    # shellcheck disable=SC2086 # the options split into words
    if ! "$BIN/qdc" optimize "$in" "$TMP/o.mesh" $opts --quiet 2> "$TMP/err"; then
        fail "pushed: $mode" "exit $?: $(tail -2 "$TMP/err")"
        continue
    fi
    if ! "$PY" "$QUALITY" "$TMP/o.mesh" > "$TMP/qo.json" 2> "$TMP/e"; then
        fail "pushed: $mode: evaluator" "$(tail -2 "$TMP/e")"
        continue
    fi
    why=$("$PY" - "$TMP/qi.json" "$TMP/qo.json" << 'EOF'
import json, sys
qi, qo = (json.load(open(f)) for f in sys.argv[1:3])
why = []
if qi["n_inverted"] < 400:
    why.append("input: %d inverted (want the harsh tangle)" % qi["n_inverted"])
if qo["n_inverted"] != 0:
    why.append("%d tets left inverted" % qo["n_inverted"])
if qo["n_degenerate"] > qi["n_degenerate"]:
    why.append("%d tets flat (input %d)" % (qo["n_degenerate"], qi["n_degenerate"]))
if qo["eta_min_valid"] < qi["eta_min_valid"]:
    why.append("worst usable tet %.3g < the input's %.3g"
               % (qo["eta_min_valid"], qi["eta_min_valid"]))
print("; ".join(why) if why else "ok inverted %d -> 0, mean ratio %.4f -> %.4f"
      % (qi["n_inverted"], qi["eta_mean"], qo["eta_mean"]))
EOF
)
    case $why in
    ok*) pass "pushed: $mode: ${why#ok }" ;;
    *) fail "pushed: $mode" "$why" ;;
    esac
done
exit 0
