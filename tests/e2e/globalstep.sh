#!/bin/sh
# globalstep.sh - the global step never folds a valid tet: on valid
# low-quality, surface-heavy meshes (scripts/corpus.py: random interior points
# Delaunay-tetrahedralized inside a ball, a thin bent bone and a torus) the
# report's run.max_inverted_global and run.folded_global are 0 and no progress
# record of the global phase has an inverted tet; on their tangled copies the
# inverted count of every global iterate stays at or below the input's, and
# the result never has more inverted tets than the input. Graded Gmsh meshes
# (refined toward a corner, along a face) come out valid with a mean ratio
# above the input's. No rerun for tets left inverted runs when none is.
. "$(dirname "$0")/../lib.sh"

if ! "$PY" -c 'import numpy, scipy' 2> /dev/null; then
    echo "ok - globalstep: corpus # SKIP python3-numpy/python3-scipy missing"
    exit 0
fi
"$PY" "$ROOT/scripts/corpus.py" "$TMP/c" --tets 20000 --only ball-lowq,bone-lowq,torus-lowq > "$TMP/list" 2>&1 ||
    { fail "globalstep: corpus" "$(tail -3 "$TMP/list")"; exit 1; }

names="ball-lowq bone-lowq torus-lowq ball-lowq-tangled bone-lowq-tangled torus-lowq-tangled"
if "$PY" -c 'import gmsh' 2> /dev/null; then
    "$PY" "$ROOT/scripts/corpus.py" "$TMP/c" --tets 15000 --only graded-box,graded-layer > "$TMP/list" 2>&1 ||
        { fail "globalstep: graded corpus" "$(tail -3 "$TMP/list")"; exit 1; }
    names="$names graded-box graded-layer graded-box-tangled"
else
    echo "ok - globalstep: graded meshes # SKIP python3-gmsh missing"
fi
for name in $names; do
    in=$TMP/c/$name.mesh
    if ! "$BIN/qdc" optimize "$in" "$TMP/o.mesh" --report "$TMP/r.json" 2> "$TMP/err"; then
        fail "globalstep: $name" "exit $?: $(tail -2 "$TMP/err")"
        continue
    fi
    out=$("$PY" - "$TMP/r.json" << 'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
run = r["run"]
b, a = r["before"], r["after"]
print(b["n_inverted"], a["n_inverted"], run["max_inverted_global"], run["folded_global"],
      "%.4f" % b["mean_ratio_mean"], "%.4f" % a["mean_ratio_mean"])
EOF
)
    set -- $out
    bi=$1 ai=$2 mx=$3 folded=$4 bm=$5 am=$6
    why=
    if [ "$bi" = 0 ]; then
        [ "$mx" = 0 ] && [ "$folded" = 0 ] || why="valid input, but global iterates had up to $mx inverted ($folded folds)"
    else
        [ "$mx" -le "$bi" ] || why="a global iterate had $mx inverted, more than the input's $bi"
    fi
    [ "$ai" -le "$bi" ] || why="$why; output has $ai inverted, input $bi"
    ! grep -q "^qdc: 0 tets left inverted" "$TMP/err" || why="$why; a rerun for 0 tets left inverted"
    awk -v a="$am" -v b="$bm" 'BEGIN { exit !(a > b) }' || why="$why; mean ratio $bm -> $am"
    case $name in
    graded-*-tangled) ;;
    graded-*) # and at least Gmsh Relocate3D's on the same mesh, both read by qdc quality
        if "$PY" "$ROOT/bench/gmsh_opt.py" "$in" "$TMP/g.mesh" Relocate3D "$TMP/g.json" > "$TMP/err" 2>&1 &&
            "$BIN/qdc" quality "$TMP/g.mesh" --json > "$TMP/gq.json" 2>> "$TMP/err"; then
            gm=$("$PY" -c 'import json, sys; print("%.4f" % json.load(open(sys.argv[1]))["after"]["mean_ratio_mean"])' "$TMP/gq.json")
            awk -v a="$am" -v g="$gm" 'BEGIN { exit !(a >= g) }' || why="$why; Gmsh Relocate3D $gm > ours $am"
            am="$am (Gmsh Relocate3D $gm)"
        else
            why="$why; Gmsh Relocate3D failed: $(tail -1 "$TMP/err")"
        fi
        ;;
    esac
    if [ -z "$why" ]; then
        pass "globalstep: $name: inverted $bi -> $ai, largest over the global phase $mx, mean ratio $bm -> $am"
    else
        fail "globalstep: $name" "$why"
    fi
done
exit 0
