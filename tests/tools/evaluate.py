#!/usr/bin/python3
"""evaluate.py - an independent check of qdc's quality numbers.

It shares no code with the C library: numpy for the measures, meshio for
every format but Medit (read by tests/tools/meditio.py, so that a Medit
file is checked without meshio's Medit reader either), scipy's k-d tree to
find candidate triangles for the boundary distance.

usage: evaluate.py MESH [--orig ORIG] [--samples N]
prints one JSON object:
  n_verts, n_tets, n_inverted, n_degenerate (not inverted, but 6V <= 1e-9
  l_rms^3, as lib/core/tet.h defines it), eta_min_valid and
  dihedral_min_valid (over the tets neither inverted nor degenerate),
  n_zero_volume, eta_mean, eta_std, eta_min
  (signed mean ratio 12 (3|V|)^(2/3) / sum of squared edges, negative when
  inverted), vlq_mean (volume-length 6 sqrt2 V / l_rms^3), dihedral_min,
  dihedral_max (degrees), n_dmin_lt_5/15/30/40, n_dmax_gt_175/165/150/140;
  eta_p01 (1st percentile); with --orig: same_counts, same_connectivity,
  boundary_hausdorff (symmetric, absolute, from N random samples per surface
  and every vertex, with exact point-triangle distances), boundary_hausdorff_rel
  and boundary_dist_mean_rel (over the bounding-box diagonal of ORIG),
  boundary_vertex_max_move (relative), interior_vertices_moved,
  n_inverted_input_order (inverted under the input's orientation).

A tet is inverted when its signed volume disagrees with the orientation of
its face-connected component, taken from the connectivity and the sign most
of the component's tets have (as qdc does), so meshes written with their tets
in any vertex order are judged by their geometry.
"""
import argparse
import itertools
import json
import sys

import numpy as np

import meditio


def read_medit(path):
    m = meditio.read(path)
    return m.vertices, m.tets


def read_any(path):
    if path.endswith(".mesh"):
        return read_medit(path)
    import meshio

    m = meshio.read(path)
    tets = [c.data for c in m.cells if c.type == "tetra"]
    return np.asarray(m.points, float)[:, :3], np.vstack(tets).astype(np.int64)


def read_mesh(path):
    """(points, tets) of any mesh file this reads (0-based tets)."""
    return read_any(path)


def compact(pts, tets):
    """Drop vertices no tet uses; tets renumbered."""
    used = np.unique(tets)
    remap = -np.ones(len(pts), np.int64)
    remap[used] = np.arange(len(used))
    return pts[used], remap[tets]


def boundary_faces(tets, nverts=None):
    """Faces of exactly one tet (0-based, in the tet's outward order)."""
    return boundary_tris(tets)


def _tet_hash(tets):
    """The set of tets as a sorted array of sorted rows (for comparing)."""
    s = np.sort(np.asarray(tets), axis=1)
    return s[np.lexsort(s.T[::-1])]


FLAT_EPS = 1e-9


def signed_vol6(x, t):
    a, b, c, d = (x[t[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))


FACES = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])


def orientation(t, vol):
    """+1/-1 per tet: the sign under which the tet is positive when it agrees
    with its component; components walked across shared faces."""
    nt = len(t)
    f = t[:, FACES].reshape(-1, 3)  # face 4*i+k, in the tet's own order
    key = np.sort(f, axis=1)
    order = np.lexsort((key[:, 2], key[:, 1], key[:, 0]))
    ks = key[order]
    same = np.all(ks[1:] == ks[:-1], axis=1)
    pairs = np.column_stack([order[:-1][same], order[1:][same]])
    # relative parity of the two listings of one face: same cyclic order means
    # the two tets are written in opposite orientations
    def cyc(r):
        m = np.argmin(r, axis=1)
        return np.take_along_axis(r, (m[:, None] + np.arange(3)) % 3, axis=1)

    fa, fb = cyc(f[pairs[:, 0]]), cyc(f[pairs[:, 1]])
    flip_rel = np.all(fa == fb, axis=1)  # True: the tets disagree
    ta, tb = pairs[:, 0] // 4, pairs[:, 1] // 4
    adj = [[] for _ in range(nt)]
    for a, b, r in zip(ta.tolist(), tb.tolist(), flip_rel.tolist()):
        adj[a].append((b, r))
        adj[b].append((a, r))
    sign = np.zeros(nt, int)
    for s in range(nt):
        if sign[s]:
            continue
        comp = [s]
        sign[s] = 1
        stack = [s]
        while stack:
            u = stack.pop()
            for v, r in adj[u]:
                want = -sign[u] if r else sign[u]
                if not sign[v]:
                    sign[v] = want
                    comp.append(v)
                    stack.append(v)
        comp = np.array(comp)
        sv = sign[comp] * vol[comp]
        if (sv < 0).sum() > (sv > 0).sum():
            sign[comp] *= -1
    return sign


def dihedrals(x, t):
    """6 dihedral angles per tet (degrees), from the face normals."""
    p = x[t]
    # faces opposite each vertex, outward for a positive tet
    n = []
    for a in range(4):
        i, j, k = FACES[a]
        n.append(np.cross(p[:, j] - p[:, i], p[:, k] - p[:, i]))
    n = np.stack(n, 1)
    nn = np.linalg.norm(n, axis=2)
    nn[nn == 0] = 1.0
    n = n / nn[..., None]
    ang = []
    for a in range(4):
        for b in range(a + 1, 4):
            c = np.clip(-np.einsum("ij,ij->i", n[:, a], n[:, b]), -1.0, 1.0)
            ang.append(np.degrees(np.arccos(c)))
    return np.stack(ang, 1)


def boundary_tris(t):
    f = t[:, FACES].reshape(-1, 3)
    key = np.sort(f, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return f[cnt[inv.ravel()] == 1]


def sample_tris(x, tri, n, rng):
    a, b, c = x[tri[:, 0]], x[tri[:, 1]], x[tri[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    pick = rng.choice(len(tri), n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    return (1 - s)[:, None] * a[pick] + (s * (1 - r2))[:, None] * b[pick] + (s * r2)[:, None] * c[pick]


def point_tri_dist(p, a, b, c):
    """Exact distance from points p to triangles (a, b, c), row by row
    (Ericson's closest-point regions)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    denom = va + vb + vc
    denom[denom == 0] = 1e-300
    v = vb / denom
    w = vc / denom
    q = a + ab * v[:, None] + ac * w[:, None]  # interior
    # edge and vertex regions override
    m = (d1 <= 0) & (d2 <= 0)
    q[m] = a[m]
    m = (d3 >= 0) & (d4 <= d3)
    q[m] = b[m]
    m = (d6 >= 0) & (d5 <= d6)
    q[m] = c[m]
    with np.errstate(invalid="ignore", divide="ignore"):
        m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        q[m] = a[m] + ab[m] * (d1[m] / (d1[m] - d3[m]))[:, None]
        m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        q[m] = a[m] + ac[m] * (d2[m] / (d2[m] - d6[m]))[:, None]
        m = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
        e = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        q[m] = b[m] + (c[m] - b[m]) * e[m][:, None]
    return np.linalg.norm(p - q, axis=1)


def one_sided(x_from, tri_from, x_to, tri_to, n, rng, k=8, chunk=40000):
    """Largest and mean distance from points of the first surface (n random
    samples and every vertex) to the second surface, exact: an upper bound
    from the k triangles with the nearest centroids first; then every triangle
    that could be closer, since a triangle at distance d from p has its
    centroid within d + r of p (r: the triangle's largest centroid-to-corner
    distance). The triangles are taken in groups of like r (powers of 2), so
    that a few long thin triangles do not widen every search; the nearest
    centroids alone miss the triangle under a point when long thin triangles
    surround it (a low-quality surface: up to 1% of the diagonal too much)."""
    from scipy.spatial import cKDTree

    p = sample_tris(x_from, tri_from, n, rng)
    p = np.vstack([p, x_from[np.unique(tri_from)]])
    corners = x_to[tri_to]
    cen = corners.mean(axis=1)
    rad = np.linalg.norm(corners - cen[:, None, :], axis=2).max(axis=1)
    k = min(k, len(tri_to))

    def dist(pi, ti):
        tt = tri_to[ti]
        return point_tri_dist(p[pi], x_to[tt[:, 0]], x_to[tt[:, 1]], x_to[tt[:, 2]])

    _, idx = cKDTree(cen).query(p, k=k)
    idx = idx.reshape(len(p), k)
    best = np.full(len(p), np.inf)
    for j in range(k):
        best = np.minimum(best, dist(np.arange(len(p)), idx[:, j]))
    group = np.floor(np.log2(np.maximum(rad, 1e-300) / max(rad.max(), 1e-300))).astype(int)
    for g in np.unique(group):
        sel = np.where(group == g)[0]
        tree = cKDTree(cen[sel])
        rmax = rad[sel].max()
        for lo in range(0, len(p), chunk):
            q = np.arange(lo, min(lo + chunk, len(p)))
            lists = tree.query_ball_point(p[q], best[q] + rmax)
            lens = np.fromiter(map(len, lists), int, len(q))
            if not lens.sum():
                continue
            pi = np.repeat(q, lens)
            ti = sel[np.fromiter(itertools.chain.from_iterable(lists), int, lens.sum())]
            np.minimum.at(best, pi, dist(pi, ti))
    return best.max(), best.mean()


def evaluate(path, orig=None, samples=300000, seed=1):
    x, t = read_any(path)
    vol = signed_vol6(x, t)
    sign = orientation(t, vol)
    v = sign * vol
    tp = t.copy()
    neg = sign < 0
    tp[neg, 0], tp[neg, 1] = t[neg, 1], t[neg, 0]
    p = x[tp]
    l2 = sum(((p[:, i] - p[:, j]) ** 2).sum(1) for i in range(4) for j in range(i + 1, 4))
    vabs = np.abs(v) / 6.0
    eta = np.sign(v) * 12.0 * (3.0 * vabs) ** (2.0 / 3.0) / l2
    vlq = np.sign(v) * 6.0 * np.sqrt(2.0) * vabs / (l2 / 6.0) ** 1.5
    ang = dihedrals(x, tp)
    amin, amax = ang.min(1), ang.max(1)
    # degenerate (flat): not inverted, 6V <= 1e-9 l_rms^3 (lib/core/tet.h)
    flat = (v >= 0) & (v * v <= FLAT_EPS * FLAT_EPS * (l2 / 6.0) ** 3)
    ok = (v > 0) & ~flat
    r = {
        "n_verts": int(len(x)),
        "n_tets": int(len(t)),
        "n_inverted": int((v < 0).sum()),
        "n_degenerate": int(flat.sum()),
        # over the usable tets (neither inverted nor degenerate)
        "eta_min_valid": float(eta[ok].min()) if ok.any() else 0.0,
        "dihedral_min_valid": float(amin[ok].min()) if ok.any() else 0.0,
        "eta_mean": float(eta.mean()),
        "eta_std": float(eta.std()),
        "eta_min": float(eta.min()),
        "vlq_mean": float(vlq.mean()),
        "dihedral_min": float(amin.min()),
        "dihedral_max": float(amax.max()),
    }
    for th in (5, 15, 30, 40):
        r["n_dmin_lt_%d" % th] = int((amin < th).sum())
    for th in (175, 165, 150, 140):
        r["n_dmax_gt_%d" % th] = int((amax > th).sum())
    r["eta_p01"] = float(np.percentile(eta, 1))
    r["n_zero_volume"] = int((v == 0).sum())
    if orig:
        xo, to = read_any(orig)
        r["same_counts"] = bool(len(xo) == len(x) and len(to) == len(t))
        r["same_connectivity"] = bool(to.shape == t.shape and (to == t).all())
        rng = np.random.default_rng(seed)
        ta, tb = boundary_tris(t), boundary_tris(to)
        ha, ma = one_sided(x, ta, xo, tb, samples, rng)
        hb, mb = one_sided(xo, tb, x, ta, samples, rng)
        diag = float(np.linalg.norm(xo.max(0) - xo.min(0)))
        r["boundary_hausdorff"] = float(max(ha, hb))
        r["boundary_hausdorff_rel"] = float(max(ha, hb) / diag) if diag > 0 else 0.0
        r["boundary_dist_mean_rel"] = float(0.5 * (ma + mb) / diag) if diag > 0 else 0.0
        if r["same_counts"]:
            bv = np.unique(tb)
            iv = np.setdiff1d(np.unique(to), bv)
            d = np.linalg.norm(x - xo, axis=1)
            r["boundary_vertex_max_move"] = float(d[bv].max() / diag) if len(bv) and diag > 0 else 0.0
            r["interior_vertices_moved"] = int((d[iv] > 0).sum())
            if r["same_connectivity"]:
                # inverted as the input's vertex order and orientation say
                so = orientation(to, signed_vol6(xo, to))
                r["n_inverted_input_order"] = int((so * signed_vol6(x, t) <= 0).sum())
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh")
    ap.add_argument("--orig")
    ap.add_argument("--samples", type=int, default=300000)
    ap.add_argument("-o", "--out", help="write the JSON here instead of stdout")
    a = ap.parse_args()
    try:
        r = evaluate(a.mesh, a.orig, a.samples)
    except (OSError, ValueError, KeyError, IndexError) as e:
        print("evaluate.py: %s: %s" % (a.mesh, e), file=sys.stderr)
        return 2
    s = json.dumps(r, indent=1)
    if a.out:
        with open(a.out, "w") as f:
            f.write(s + "\n")
    else:
        print(s)
    return 0


if __name__ == "__main__":
    sys.exit(main())
