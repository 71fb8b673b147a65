#!/bin/sh
# graded.sh - graded meshes gain like uniform ones: on a box refined toward a
# corner and a box refined toward one face (sizes vary 9-10x; Gmsh meshes made
# by scripts/corpus.py), qdc's default run gives a mean ratio at least the
# input's and at least what Gmsh Relocate3D (vertex moves only, the peer) gives
# on the same file, a worst tet no worse than either, and no inverted tet. Every
# figure comes from the independent evaluator (tests/tools/evaluate.py).
. "$(dirname "$0")/../lib.sh"

names="graded-box graded-layer"
if ! "$PY" -c 'import numpy, scipy, gmsh' 2> /dev/null; then
    for n in $names; do echo "ok - graded: $n # SKIP python3-gmsh or scipy missing"; done
    exit 0
fi
if ! "$PY" "$ROOT/scripts/corpus.py" "$TMP/c" --tets 8000 --only graded-box,graded-layer \
    > "$TMP/list" 2>&1; then
    for n in $names; do fail "graded: $n" "scripts/corpus.py failed: $(tail -1 "$TMP/list")"; done
    exit 1
fi

# eval FILE: "mean worst inverted" by the evaluator
eval_mesh() {
    "$PY" "$QUALITY" "$1" | "$PY" -c 'import json, sys
d = json.load(sys.stdin)
print("%.6f %.6f %d" % (d["eta_mean"], d["eta_min"], d["n_inverted"]))'
}

cat > "$TMP/judge.py" << 'PYEOF'
import sys
im, iw, ii, gm, gw, gi, qm, qw, qi = (float(a) for a in sys.argv[1:])
bad = []
if qi > 0:
    bad.append("%d inverted" % qi)
if qm < im:
    bad.append("mean %.4f below the input's %.4f" % (qm, im))
if qm < gm:
    bad.append("mean %.4f below Gmsh Relocate3D %.4f" % (qm, gm))
if qw < iw or qw < gw:
    bad.append("worst %.4f below the input %.4f or Gmsh %.4f" % (qw, iw, gw))
print("; ".join(bad) if bad else
      "ok mean %.4f -> %.4f (Gmsh Relocate3D %.4f), worst %.4f -> %.4f (Gmsh %.4f)"
      % (im, qm, gm, iw, qw, gw))
PYEOF
for n in $names; do
    in=$TMP/c/$n.mesh
    if ! "$BIN/qdc" optimize "$in" "$TMP/$n.qdc.mesh" --quiet 2> "$TMP/err"; then
        fail "graded: $n" "qdc failed: $(tail -2 "$TMP/err")"
        continue
    fi
    if ! "$PY" "$ROOT/bench/gmsh_opt.py" "$in" "$TMP/$n.gmsh.mesh" Relocate3D "$TMP/g.json" \
        > "$TMP/gerr" 2>&1; then
        fail "graded: $n" "Gmsh Relocate3D failed: $(tail -2 "$TMP/gerr")"
        continue
    fi
    set -- $(eval_mesh "$in") $(eval_mesh "$TMP/$n.gmsh.mesh") $(eval_mesh "$TMP/$n.qdc.mesh")
    res=$("$PY" "$TMP/judge.py" "$@")
    case $res in
    ok*) pass "graded: $n ${res#ok }" ;;
    *) fail "graded: $n" "$res" ;;
    esac
done
[ "$NFAIL" = 0 ]
