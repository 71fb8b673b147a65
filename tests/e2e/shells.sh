#!/bin/sh
# shells.sh - the angle polish opens flat tets whose four corners lie on a
# curved surface. A thin bone of scripts/corpus.py (bone-scan: surface points
# spaced like a scanned surface's vertices, random interior points,
# Delaunay) has hundreds of such "shells" under 1 degree after the global step
# and the finishing pass; in clusters their smallest sines balance each other
# so that no steepest-ascent direction of one vertex lifts them, and only the
# pattern moves of the angle sweep do (without them the run ends at 0.38
# degrees on this mesh, with them near 0.7 under the 1e-3 off-surface
# allowance of the default until 2026-11-27, 0.49 within the 3e-3 bound of
# the default since: docs/defaults.md). Checked by the independent
# evaluator (tests/tools/evaluate.py): the smallest dihedral at least 0.45
# degrees and above the input's, no tet inverted, the worst mean ratio not
# below the input's, the boundary surface's Hausdorff distance within the
# default bound (3e-3 of the bounding-box diagonal).
. "$(dirname "$0")/../lib.sh"

if ! "$PY" -c 'import numpy, scipy' 2> /dev/null; then
    echo "ok - shells: corpus # SKIP python3-numpy/python3-scipy missing"
    exit 0
fi
"$PY" "$ROOT/scripts/corpus.py" "$TMP/c" --tets 20000 --only bone-scan > "$TMP/list" 2>&1 ||
    { fail "shells: corpus" "$(tail -3 "$TMP/list")"; exit 1; }
in=$TMP/c/bone-scan.mesh
if ! "$BIN/qdc" optimize "$in" "$TMP/o.mesh" --report "$TMP/r.json" 2> "$TMP/err"; then
    fail "shells: bone-scan" "exit $?: $(tail -2 "$TMP/err")"
    exit 0
fi
if ! "$PY" "$QUALITY" "$in" > "$TMP/qi.json" 2> "$TMP/err" ||
    ! "$PY" "$QUALITY" "$TMP/o.mesh" > "$TMP/qo.json" 2>> "$TMP/err"; then
    fail "shells: evaluator" "$(tail -2 "$TMP/err")"
    exit 0
fi
why=$("$PY" - "$TMP/qi.json" "$TMP/qo.json" "$TMP/r.json" << 'EOF'
import json, sys
qi, qo, r = (json.load(open(f)) for f in sys.argv[1:4])
why = []
if not qo["dihedral_min"] >= 0.45:
    why.append("smallest dihedral %.2f < 0.45 degrees" % qo["dihedral_min"])
if not qo["dihedral_min"] > qi["dihedral_min"]:
    why.append("smallest dihedral %.2f -> %.2f" % (qi["dihedral_min"], qo["dihedral_min"]))
if qo["n_inverted"] != 0:
    why.append("%d inverted" % qo["n_inverted"])
if not qo["eta_min"] >= qi["eta_min"]:
    why.append("worst mean ratio %.4f -> %.4f" % (qi["eta_min"], qo["eta_min"]))
hb = r["run"]["hausd_bound"]
if not 0 < r["boundary_error"]["hausdorff"] <= hb * (1 + 1e-9):
    why.append("Hausdorff distance %.3g, bound %.3g"
               % (r["boundary_error"]["hausdorff"], hb))
print("; ".join(why) if why else "ok smallest dihedral %.2f -> %.2f, worst mean ratio %.4f -> %.4f"
      % (qi["dihedral_min"], qo["dihedral_min"], qi["eta_min"], qo["eta_min"]))
EOF
)
verdict "shells: bone-scan (20k tets)" "$why"
exit 0
