# tests/e2e/modes.sh - boundary modes on dev meshes (issue targets):
#   fixed: boundary bit for bit (Hausdorff <= 1e-12 of the diagonal);
#   slide: Hausdorff <= 1e-4 of the diagonal on flat-faced shapes and <= 0.5% on curved
#          ones, with better mean and worst tet than fixed;
#   every mode: tags kept, no inverted tets, never worse than the input.
. "$(dirname "$0")/../lib.sh"

run() { # run NAME MODE -> $TMP/NAME.MODE.json
    "$BIN/qdc" optimize "$(devmesh "$1")" "$TMP/$1.$2.mesh" --boundary "$2" --quiet \
        --report "$TMP/$1.$2.json"
}

for spec in cube_h0.1_good:1e-4 bracket_h0.1_good:1e-4 sphere_h0.1_good:5e-3 torus_h0.1_good:5e-3; do
    name=${spec%%:*}
    hmax=${spec#*:}
    if ! run "$name" fixed || ! run "$name" slide; then
        fail "modes.$name" "qdc failed"
        continue
    fi
    why=$($PY - "$TMP/$name.fixed.json" "$TMP/$name.slide.json" "$hmax" \
        "$TMP/$name.fixed.mesh" "$TMP/$name.slide.mesh" <<'PYEOF'
import json, os, sys
import numpy as np
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio
f, s, hmax = json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), float(sys.argv[3])

def boundary_tet_quality(path):
    """Mean of the mean ratio over tets with a vertex on the boundary."""
    m = meditio.read(path)
    X, T, n = m.vertices, m.tets, len(m.vertices)
    F = np.sort(np.concatenate([T[:, [1, 2, 3]], T[:, [0, 2, 3]], T[:, [0, 1, 3]], T[:, [0, 1, 2]]]), 1)
    _, inv, cnt = np.unique(F, axis=0, return_inverse=True, return_counts=True)
    onb = np.zeros(n, bool); onb[F[cnt[inv] == 1].ravel()] = True
    P = X[T]; a, b, c, d = P[:, 0], P[:, 1], P[:, 2], P[:, 3]
    v = np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6
    l2 = sum(((P[:, p] - P[:, q]) ** 2).sum(1) for p, q in ((0,1),(0,2),(0,3),(1,2),(1,3),(2,3)))
    eta = np.sign(v) * 12 * np.cbrt(3 * np.abs(v)) ** 2 / l2
    return float(eta[onb[T].any(1)].mean())

bf, bs = boundary_tet_quality(sys.argv[4]), boundary_tet_quality(sys.argv[5])
why = []
if f["boundary_error"]["hausdorff_rel"] > 1e-12:
    why.append(f"fixed moved the boundary ({f['boundary_error']['hausdorff_rel']:.2e})")
h = s["boundary_error"]["hausdorff_rel"]
if h > hmax:
    why.append(f"slide Hausdorff {h:.2e} > {hmax:.0e}")
for tag, r in (("fixed", f), ("slide", s)):
    a, b = r["after"], r["before"]
    if a["n_inverted"] > 0 or a["mean_ratio_min"] < b["mean_ratio_min"]:
        why.append(f"{tag} worse than input")
if not s["after"]["mean_ratio_mean"] > f["after"]["mean_ratio_mean"]:
    why.append("slide mean not above fixed")
if not bs > bf:
    why.append(f"boundary tets: slide {bs:.4f} not above fixed {bf:.4f}")
if not s["after"]["mean_ratio_min"] >= f["after"]["mean_ratio_min"] - 0.005:
    why.append("slide worst tet below fixed")
print("; ".join(why) if why else
      f"ok: slide {s['after']['mean_ratio_mean']:.4f}/{s['after']['mean_ratio_min']:.3f} "
      f"boundary tets {bs:.4f} H {h:.1e} vs fixed {f['after']['mean_ratio_mean']:.4f}/"
      f"{f['after']['mean_ratio_min']:.3f} boundary tets {bf:.4f}")
PYEOF
)
    case "$why" in
    ok:*) pass "modes.$name: ${why#ok: }" ;;
    *) fail "modes.$name" "$why" ;;
    esac
done

# Slide must not squash the ears of a smooth surface (tets with two boundary
# faces): on the tangled bunny one ended flat (mean ratio 1e-10) before the
# rerun with their corners held; measured 0.051 since (lsq reaches 0.18).
if run bunny_tangled-low_10k slide; then
    r=$($PY -c "import json,sys; a=json.load(open(sys.argv[1]))['after']; print(a['n_inverted'], a['mean_ratio_min'])" "$TMP/bunny_tangled-low_10k.slide.json")
    set -- $r
    if [ "$1" -eq 0 ] && $PY -c "import sys; sys.exit(0 if float(sys.argv[1]) >= 0.02 else 1)" "$2"; then
        pass "modes.slide_ears: bunny_tangled-low_10k untangled, worst tet $2"
    else
        fail "modes.slide_ears" "$1 inverted, worst tet $2 (want 0 and >= 0.02)"
    fi
else
    fail "modes.slide_ears" "qdc failed"
fi

# Region tags survive every mode: a two-region mesh made from a dev mesh by tagging
# tets by the sign of their centroid's x.
in=$(devmesh cube_h0.1_lowq)
$PY - "$in" "$TMP/regions.mesh" <<'PYEOF'
import os, sys
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio
m = meditio.read(sys.argv[1])
x = m.vertices[:, 0].tolist()
m.tet_refs = [1 if sum(x[v] for v in t) / 4 < 0 else 2 for t in m.tets.tolist()]
m.write(sys.argv[2])
PYEOF
for mode in lsq fixed slide; do
    if "$BIN/qdc" optimize "$TMP/regions.mesh" "$TMP/regions.$mode.mesh" --boundary "$mode" --quiet; then
        same=$($PY - "$TMP/regions.mesh" "$TMP/regions.$mode.mesh" <<'PYEOF'
import os, sys
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio
def tets(p):
    m = meditio.read(p)
    return m.tets.tolist(), m.tet_refs.tolist()
print(tets(sys.argv[1]) == tets(sys.argv[2]))
PYEOF
)
        [ "$same" = True ] && pass "modes.regions.$mode: tets and tags unchanged" ||
            fail "modes.regions.$mode" "connectivity or tags changed"
    else
        fail "modes.regions.$mode" "qdc failed"
    fi
done
exit 0
