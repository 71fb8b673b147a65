#!/bin/sh
# evaluate.sh - the independent evaluator (tests/tools/evaluate.py) on meshes
# whose answers are known in closed form, so that the checks that compare qdc
# with it compare with something right.
. "$(dirname "$0")/../lib.sh"
if ! "$PY" -c 'import numpy, scipy' 2> /dev/null; then
    echo "ok - evaluate # SKIP python3-numpy/python3-scipy missing"
    exit 0
fi
out=$("$PY" - "$ROOT/tests/tools" "$TMP" << 'PYEOF' 2>&1
import math, sys
sys.path.insert(0, sys.argv[1])
import numpy as np
import evaluate as ev
from meditio import write
tmp = sys.argv[2]
bad = []
def check(name, got, want, tol=1e-12):
    if not abs(got - want) <= tol:
        bad.append("%s: %r, expected %r" % (name, got, want))
# a regular tet: mean ratio 1, volume-length 1, every dihedral acos(1/3)
reg = np.array([[0, 0, 0], [1, 0, 0], [0.5, math.sqrt(3) / 2, 0],
                [0.5, math.sqrt(3) / 6, math.sqrt(2.0 / 3.0)]])
write(tmp + "/reg.mesh", reg, [[0, 1, 2, 3]])
r = ev.evaluate(tmp + "/reg.mesh")
check("regular eta", r["eta_min"], 1.0)
check("regular vlq", r["vlq_mean"], 1.0)
check("regular dihedral min", r["dihedral_min"], math.degrees(math.acos(1 / 3)), 1e-9)
check("regular dihedral max", r["dihedral_max"], math.degrees(math.acos(1 / 3)), 1e-9)
check("regular inverted", r["n_inverted"], 0)
# written the other way round it is the same valid tet (orientation from the mesh)
write(tmp + "/reg2.mesh", reg, [[1, 0, 2, 3]])
check("regular reversed inverted", ev.evaluate(tmp + "/reg2.mesh")["n_inverted"], 0)
# the corner tet: 90 degrees at the axis edges, acos(1/sqrt3) at the others;
# mean ratio 12 (3 V)^(2/3) / sum l^2 with V = 1/6, sum l^2 = 3 + 3 * 2
cor = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
write(tmp + "/cor.mesh", cor, [[0, 1, 2, 3]])
r = ev.evaluate(tmp + "/cor.mesh")
check("corner eta", r["eta_min"], 12 * 0.5 ** (2 / 3) / 9)
check("corner dihedral min", r["dihedral_min"], math.degrees(math.acos(1 / math.sqrt(3))), 1e-9)
check("corner dihedral max", r["dihedral_max"], 90.0, 1e-9)
# two tets on a face; the second's apex pushed through it: inverted, and its
# mean ratio negative, whichever vertex order it is written in
two = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 1], [0.3, 0.3, 0.5]])
for t2 in ([1, 0, 2, 4], [0, 1, 2, 4]):
    write(tmp + "/two.mesh", two, [[0, 1, 2, 3], t2])
    r = ev.evaluate(tmp + "/two.mesh")
    check("folded inverted %s" % t2, r["n_inverted"], 1)
    if not r["eta_min"] < 0:
        bad.append("folded eta_min %r not negative" % r["eta_min"])
# flat: the second tet's apex at height h over the first's base plane is
# degenerate when 6V = h <= 1e-9 l_rms^3 (lib/core/tet.h), l_rms^3 about 0.66
# here, whatever the units (scaled by 1e6)
for h, flat in ((0.0, 1), (1e-10, 1), (1e-8, 0)):
    for s in (1.0, 1e6):
        p = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 1], [0.4, 0.4, -h]]) * s
        write(tmp + "/flat.mesh", p, [[0, 1, 2, 3], [1, 0, 2, 4]])
        r = ev.evaluate(tmp + "/flat.mesh")
        check("flat h=%g x%g degenerate" % (h, s), r["n_degenerate"], flat)
        check("flat h=%g x%g inverted" % (h, s), r["n_inverted"], 0)
# boundary distance: the regular tet against itself moved by 0.25 along z
write(tmp + "/up.mesh", reg + [0, 0, 0.25], [[0, 1, 2, 3]])
r = ev.evaluate(tmp + "/up.mesh", tmp + "/reg.mesh", samples=20000)
check("hausdorff", r["boundary_hausdorff"], 0.25, 1e-9)
check("same connectivity", r["same_connectivity"], True)
# a surface against itself is at distance 0, also where long thin triangles
# (a fan from one corner of the unit square to its diagonal) meet small ones
# (a fine grid over the other half): the nearest centroids of a point near the
# diagonal are then all the grid's, not its fan triangle's
n = 40
pts = [(i / n, j / n, 0.0) for j in range(n + 1) for i in range(n + 1)]
vid = lambda i, j: j * (n + 1) + i
tri = [(vid(0, 0), vid(k, n - k), vid(k + 1, n - k - 1)) for k in range(n)]
for j in range(n):
    for i in range(n):
        if i + j >= n:
            tri.append((vid(i, j), vid(i + 1, j), vid(i, j + 1)))
        if i + j + 1 >= n:
            tri.append((vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)))
pts, tri = np.array(pts), np.array(tri)
h, m = ev.one_sided(pts, tri, pts, tri, 20000, np.random.default_rng(3))
check("graded surface against itself", h, 0.0, 1e-12)
print("; ".join(bad) if bad else "all")
PYEOF
)
[ "$out" = all ] && pass "evaluate: regular, corner and folded tets, orientation from the mesh, Hausdorff of a shift and of a graded surface against itself" ||
    fail "evaluate" "$out"
exit 0
