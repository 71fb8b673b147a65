#!/bin/sh
# hausd.sh - --hausd bounds the Hausdorff distance between the input and the
# output boundary surfaces, under lsq and slide, at 1e-3 and 1e-4 of the
# bounding-box diagonal and as an absolute value, on a CAD-like part (sharp
# features, curved patches: Gmsh OCC) and a curved surface-heavy ball
# (scripts/corpus.py). Checked three ways: the report's boundary error, the
# report's bound, and numpy (every boundary vertex within the bound of where it
# was, which bounds the surface distance point for point).
. "$(dirname "$0")/../lib.sh"
if ! "$PY" -c 'import numpy, scipy, gmsh' 2> /dev/null; then
    echo "ok - hausd # SKIP python3-numpy/scipy/gmsh missing"
    exit 0
fi
"$PY" "$ROOT/scripts/corpus.py" "$TMP/c" --tets 60000 --only part-cad,ball-lowq > "$TMP/list" 2>&1 ||
    { fail "hausd: corpus" "$(tail -3 "$TMP/list")"; exit 1; }

moved() { # IN OUT: largest move of a boundary vertex, relative to IN's diagonal
    "$PY" - "$1" "$2" "$ROOT/tests/tools" << 'PYEOF'
import sys
sys.path.insert(0, sys.argv[3])
import numpy as np
import evaluate as ev
xi, t = ev.read_mesh(sys.argv[1])
xo, _ = ev.read_mesh(sys.argv[2])
b = np.unique(ev.boundary_faces(t))
diag = np.linalg.norm(xi.max(0) - xi.min(0))
print("%.17g" % (np.linalg.norm(xo[b] - xi[b], axis=1).max() / diag))
PYEOF
}

for name in part-cad ball-lowq; do
    in=$TMP/c/$name.mesh
    for b in lsq slide; do
        for h in rel:1e-3 0.1% rel:1e-4; do
            case $h in rel:*) r=${h#rel:} ;; *%) r=$(awk -v p="${h%\%}" 'BEGIN { print p / 100 }') ;; esac
            if ! "$BIN/qdc" optimize "$in" "$TMP/o.mesh" --boundary $b --hausd $h --report "$TMP/r.json" --quiet 2> "$TMP/err"; then
                fail "hausd: $name $b $h" "exit: $(tail -2 "$TMP/err")"
                continue
            fi
            set -- $("$PY" -c 'import json, sys
r = json.load(open(sys.argv[1]))
print(r["boundary_error"]["hausdorff_rel"], r["run"]["hausd_bound"] / r["boundary_error"]["bbox_diagonal"],
      r["after"]["mean_ratio_mean"], r["before"]["mean_ratio_mean"], r["after"]["n_inverted"])' "$TMP/r.json")
            hrel=$1 brel=$2 am=$3 bm=$4 inv=$5
            mv=$(moved "$in" "$TMP/o.mesh")
            if awk -v h="$hrel" -v m="$mv" -v r="$r" -v b="$brel" -v am="$am" -v bm="$bm" -v inv="$inv" 'BEGIN {
                    tol = 1e-9 * r
                    exit !(m != "" && h <= r + tol && m <= r + tol && (b - r) < tol && (r - b) < tol && am >= bm && inv == 0) }'; then
                pass "hausd: $name $b --hausd $h: Hausdorff $hrel of the diagonal, vertex moves <= $mv, mean ratio $bm -> $am"
            else
                fail "hausd: $name $b --hausd $h" "Hausdorff $hrel, largest boundary move $mv, bound $brel (want $r), mean $bm -> $am, inverted $inv"
            fi
        done
    done
done
# an absolute bound is the same thing in the mesh's units
in=$TMP/c/part-cad.mesh
"$BIN/qdc" optimize "$in" "$TMP/a.mesh" --hausd 0.002 --report "$TMP/a.json" --quiet
set -- $("$PY" -c 'import json, sys; r = json.load(open(sys.argv[1])); print(r["boundary_error"]["hausdorff"], r["run"]["hausd_bound"])' "$TMP/a.json")
awk -v h="$1" -v b="$2" 'BEGIN { exit !(b == 0.002 && h <= 0.002 * (1 + 1e-9)) }' &&
    pass "hausd: absolute --hausd 0.002: Hausdorff $1" || fail "hausd: absolute" "Hausdorff $1 bound $2"
for bad in -1 nan inf 1e-3x "" rel: 5%%; do
    "$BIN/qdc" optimize "$in" "$TMP/x.mesh" --hausd "$bad" --quiet > /dev/null 2>&1
    rc=$?
    [ $rc = 1 ] || fail "hausd: bad value '$bad'" "exit $rc"
done
pass "hausd: -1, nan, inf, 1e-3x, empty, rel:, 5%% refused (exit 1)"
exit 0
