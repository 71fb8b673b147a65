#!/bin/sh
# inner.sh - a surface the user gives inside one region (the input's triangles
# that are faces between two tets of one region: an embedded surface, facet
# tags) is kept as an interface is. A perturbed 8x8x8 Kuhn cube whose faces in
# the plane y = 1/2 are given as triangles of ref 5 (their vertices moved in
# the plane only): the default run leaves those vertices on the plane (they
# slide in it, as on an interface) and raises the mean ratio; --topology flips
# and full keep every one of those triangles a face between two tets, their
# vertices on the plane. Before, the default run moved them off the plane by
# 0.09 (of a unit cube).
. "$(dirname "$0")/../lib.sh"

cat > "$TMP/plane.py" << 'PY'
import os, sys
import numpy as np
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio
n = 8
rng = np.random.default_rng(3)
idx = lambda i, j, k: i + (n + 1) * (j + (n + 1) * k)
x = np.array([[i / n, j / n, k / n] for k in range(n + 1) for j in range(n + 1) for i in range(n + 1)])
for k in range(1, n):
    for j in range(1, n):
        for i in range(1, n):
            d = rng.uniform(-0.3, 0.3, 3) / n
            if j == n // 2:
                d[1] = 0.0  # on the plane y = 1/2: stays on it
            x[idx(i, j, k)] += d
perm = [(0, 1, 2), (1, 2, 0), (2, 0, 1), (0, 2, 1), (2, 1, 0), (1, 0, 2)]
tets = []
for k in range(n):
    for j in range(n):
        for i in range(n):
            for p, pp in enumerate(perm):
                c = [i, j, k]
                vs = []
                for s in range(4):
                    vs.append(idx(*c))
                    if s < 3:
                        c[pp[s]] += 1
                if p >= 3:
                    vs[1], vs[2] = vs[2], vs[1]
                tets.append(vs)
faces = {}
for t in tets:
    for o in range(4):
        f = t[:o] + t[o + 1:]
        faces.setdefault(tuple(sorted(f)), []).append(f)
yv = lambda v: (v // (n + 1)) % (n + 1)
plane = [fs[0] for k, fs in sorted(faces.items()) if len(fs) == 2 and all(yv(v) == n // 2 for v in k)]
bnd = [fs[0] for k, fs in sorted(faces.items()) if len(fs) == 1]
meditio.write(sys.argv[1], x, tets, bnd + plane, triangle_refs=[1] * len(bnd) + [5] * len(plane))
PY
cat > "$TMP/check.py" << 'PY'
import os, sys
import numpy as np
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio

m = meditio.read(sys.argv[1])
x, t = m.vertices, m.tets
mine = m.triangles[m.triangle_refs == 5]
faces = {}
for tt in t.tolist():
    for o in range(4):
        k = tuple(sorted(tt[:o] + tt[o + 1:]))
        faces[k] = faces.get(k, 0) + 1
off = sum(1 for f in mine.tolist() if faces.get(tuple(sorted(f))) != 2)
v = np.unique(mine)
print(len(mine), off, "%.3g" % np.abs(x[v, 1] - 0.5).max())
PY
"$PY" "$TMP/plane.py" "$TMP/in.mesh"
# mean IN: the evaluator's mean ratio
mean() { "$PY" "$QUALITY" "$1" | "$PY" -c 'import json, sys; print(json.load(sys.stdin)["eta_mean"])'; }
m0=$(mean "$TMP/in.mesh")
for mode in none flips full; do
    if ! "$BIN/qdc" optimize --quiet --topology $mode "$TMP/in.mesh" "$TMP/$mode.mesh" \
        2> "$TMP/err"; then
        fail "inner surface: $mode" "exit: $(tail -2 "$TMP/err")"
        continue
    fi
    set -- $("$PY" "$TMP/check.py" "$TMP/$mode.mesh")
    m1=$(mean "$TMP/$mode.mesh")
    if [ "$1" = 128 ] && [ "$2" = 0 ] && [ "$3" = 0 ] &&
        awk -v a="$m1" -v b="$m0" 'BEGIN { exit !(a > b) }'; then
        pass "inner surface: $mode: 128 triangles kept between two tets, on the plane, mean ratio $m0 -> $m1"
    else
        fail "inner surface: $mode" "$1 triangles, $2 not between two tets, off the plane by $3, mean ratio $m0 -> $m1"
    fi
done
exit $((NFAIL > 0))
