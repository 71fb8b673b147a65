#!/bin/sh
# hausd.sh - --hausd bounds the Hausdorff distance between the input and the
# output boundary surfaces, under lsq and slide, at 1e-3 and 1e-4 of the
# bounding-box diagonal and as an absolute value, on a CAD-like part (sharp
# features, curved patches: Gmsh OCC) and a curved surface-heavy ball
# (scripts/corpus.py). Checked three ways: the report's boundary error, the
# report's bound, and every boundary vertex within the bound of the input
# surface (boundary_error.vertex_max: vertices of planar patches and straight
# edges slide freely on them in slide mode and in lsq's angle pass); with
# slide, numpy checks that planar-patch vertices stay on their input plane to
# 1e-12 of the diagonal. The default is the same kind of bound, at 3e-3.
. "$(dirname "$0")/../lib.sh"
if ! "$PY" -c 'import numpy, scipy, gmsh' 2> /dev/null; then
    echo "ok - hausd # SKIP python3-numpy/scipy/gmsh missing"
    exit 0
fi
"$PY" "$ROOT/scripts/corpus.py" "$TMP/c" --tets 60000 --only part-cad,ball-lowq > "$TMP/list" 2>&1 ||
    { fail "hausd: corpus" "$(tail -3 "$TMP/list")"; exit 1; }

moved() { # IN OUT: largest move of a boundary vertex (not checked), and the largest
    # distance of a planar-patch vertex from its input plane, relative to IN's diagonal
    "$PY" - "$1" "$2" "$ROOT/tests/tools" << 'PYEOF'
import sys
sys.path.insert(0, sys.argv[3])
import numpy as np
import evaluate as ev
xi, t = ev.read_mesh(sys.argv[1])
xo, _ = ev.read_mesh(sys.argv[2])
f = ev.boundary_faces(t)
b = np.unique(f)
diag = np.linalg.norm(xi.max(0) - xi.min(0))
n = np.cross(xi[f[:, 1]] - xi[f[:, 0]], xi[f[:, 2]] - xi[f[:, 0]])
n /= np.linalg.norm(n, axis=1)[:, None]
# a vertex is on a planar patch when all its faces have the same normal (1e-10 in cos)
lo = np.full((len(xi), 3), np.inf); hi = np.full((len(xi), 3), -np.inf)
for k in range(3):
    np.minimum.at(lo, f[:, k], n)
    np.maximum.at(hi, f[:, k], n)
flat = np.zeros(len(xi), bool)
flat[b] = (hi[b] - lo[b]).max(1) < 1e-6
nv = np.zeros((len(xi), 3)); nv[b] = lo[b]
off = np.abs(((xo - xi) * nv).sum(1))[flat].max() / diag if flat.any() else 0.0
mv = np.linalg.norm(xo[b] - xi[b], axis=1).max() / diag
print("%.17g %.17g" % (mv, off))
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
      r["after"]["mean_ratio_mean"], r["before"]["mean_ratio_mean"], r["after"]["n_inverted"],
      r["boundary_error"]["vertex_max_rel"])' "$TMP/r.json")
            hrel=$1 brel=$2 am=$3 bm=$4 inv=$5 mv=$6
            # the planes are checked under slide only (lsq's angle pass may
            # move planar-patch vertices off them): no mesh read for lsq
            off=0
            if [ $b = slide ]; then
                set -- $(moved "$in" "$TMP/o.mesh")
                off=$2
            fi
            if awk -v h="$hrel" -v m="$mv" -v off="$off" -v r="$r" -v b="$brel" -v am="$am" -v bm="$bm" -v inv="$inv" 'BEGIN {
                    tol = 1e-9 * r
                    exit !(m != "" && h <= r + tol && m <= r + tol && off <= 1e-12 && (b - r) < tol && (r - b) < tol && am >= bm && inv == 0) }'; then
                pass "hausd: $name $b --hausd $h: Hausdorff $hrel of the diagonal, vertices <= $mv from the input (slide: from its surface), planar patches kept to $off, mean ratio $bm -> $am"
            else
                fail "hausd: $name $b --hausd $h" "Hausdorff $hrel, vertices up to $mv from the input (slide: its surface), off planes $off, bound $brel (want $r), mean $bm -> $am, inverted $inv"
            fi
        done
    done
done
# the default (--hausd auto under slide) is the same kind of bound: the
# report's Hausdorff distance within the default 3e-3 of the diagonal, on the
# generated meshes and on every file other tools wrote (tests/data/real)
gzip -dc "$ROOT/tests/data/real/tetgen.node.gz" > "$TMP/tetgen.node"
gzip -dc "$ROOT/tests/data/real/tetgen.ele.gz" > "$TMP/tetgen.ele"
# MED goes through qdc-h5, which reads HDF5 from a plain file
gzip -dc "$ROOT/tests/data/real/meshio.med.gz" > "$TMP/meshio.med"
# XDMF whose data is in HDF5 (meshio, DOLFIN, dolfinx): the .h5 is read only
# from a plain file beside the .xdmf, so both are unpacked
pairs=
for h5 in "$ROOT"/tests/data/real/*.h5.gz; do
    b=$(basename "$h5" .h5.gz)
    gzip -dc "$h5" > "$TMP/$b.h5"
    gzip -dc "$ROOT/tests/data/real/$b.xdmf.gz" > "$TMP/$b.xdmf"
    pairs="$pairs $TMP/$b.xdmf"
done
for in in "$TMP/c/part-cad.mesh" "$TMP/c/ball-lowq.mesh" "$ROOT"/tests/data/real/*.gz "$TMP/tetgen.ele" \
    "$TMP/meshio.med" $pairs; do
    # tetgen, MED and the XDMF+HDF5 pairs: above
    case $in in *tetgen.*.gz | *.med.gz | *.h5.gz) continue ;; esac
    case $in in *.xdmf.gz) [ -e "${in%.xdmf.gz}.h5.gz" ] && continue ;; esac
    name=$(basename "$in")
    if ! "$BIN/qdc" optimize "$in" "$TMP/d.${name%.gz}" --report "$TMP/d.json" --quiet 2> "$TMP/err"; then
        fail "hausd: default on $name" "exit: $(tail -2 "$TMP/err")"
        continue
    fi
    set -- $("$PY" -c 'import json, sys
r = json.load(open(sys.argv[1])); be = r["boundary_error"]
print(be["hausdorff_rel"], r["run"]["hausd_bound"] / be["bbox_diagonal"])' "$TMP/d.json")
    if awk -v h="$1" -v b="$2" 'BEGIN { exit !(b > 3e-3 * (1 - 1e-6) && b < 3e-3 * (1 + 1e-6) && h <= b * (1 + 1e-9)) }'; then
        pass "hausd: default on $name: Hausdorff $1 of the diagonal, bound $2"
    else
        fail "hausd: default on $name" "Hausdorff $1 of the diagonal, bound $2 (want 3e-3)"
    fi
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
