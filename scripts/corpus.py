#!/usr/bin/python3
"""corpus.py - a harder development corpus, made by the project (nothing is
downloaded; the same seed gives the same files).

Classes (each as a Medit .mesh, valid unless named tangled):
  ball-lowq, bone-lowq, torus-lowq   surface-heavy, low quality: points on an
        analytic surface plus random interior points, Delaunay-tetrahedralized
        (scipy), tets outside the shape dropped; 40-55% boundary vertices.
        bone: a thin bent capsule, aspect ratio about 12.
  ball-scan, bone-scan   the same, but the surface points spaced like the
        vertices of a scanned surface mesh (Poisson-disk thinned, no two closer
        than about 0.6 of their mean spacing): the surface itself is fair,
        the tets Delaunay makes across it are not
  cube-lowq        the same in the unit cube (only when asked for with --only):
                   the benchmark's scale series
  graded-box       Gmsh, a box refined toward one corner (size field), so
                   sizes vary 10x across the mesh
  graded-layer     Gmsh, a box refined along one face (the sizes of a
                   boundary layer, 9x)
  part-cad         Gmsh OCC: a box minus a cylinder, with a fillet-like
                   curved patch: sharp features and curved patches
  two-region       Gmsh: a box with an embedded ball (two physical volumes)
  *-tangled        a copy with random interior vertices pushed far enough to
                   invert some of their tets

usage: scripts/corpus.py OUTDIR [--tets N] [--only NAME,...] [--seed S]
                         [--surface-share F]
   N: rough tet count of each mesh (default 20000; 1e6 for the large set)
   F: the share of the *-lowq and *-scan vertices placed on the surface
      (default 0.5). With F fixed, the surface spacing shrinks as N^(-1/2)
      and the interior spacing as N^(-1/3): at 10x the tets the surface is
      about 1.5x finer against the interior, so the tets that touch it are
      worse before and after any smoothing. Lower F at the larger size keeps
      that ratio (the ball at 1.1M tets with F 0.32 has the 100k ball's)
"""
import argparse
import os
import sys

# numpy and scipy are imported by main() after the arguments are parsed, so
# that --help prints on a machine without them
np = None
Delaunay = None


def write_medit(path, x, tets, region=None):
    """Medit ASCII, 1-based, tets with their region ref."""
    if region is None:
        region = np.ones(len(tets), dtype=int)
    with open(path, "w") as f:
        f.write("MeshVersionFormatted 2\nDimension 3\nVertices\n%d\n" % len(x))
        np.savetxt(f, np.column_stack([x, np.zeros(len(x))]), fmt="%.17g %.17g %.17g %d")
        f.write("Tetrahedra\n%d\n" % len(tets))
        np.savetxt(f, np.column_stack([tets + 1, region]), fmt="%d")
        f.write("End\n")


def positive(x, t):
    a, b, c, d = (x[t[:, k]] for k in range(4))
    v = np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))
    t = t.copy()
    neg = v < 0
    t[neg, 0], t[neg, 1] = t[neg, 1].copy(), t[neg, 0].copy()
    return t, np.abs(v)


# ---- analytic shapes: inside(p) and points on the surface -------------------
def ball_surface(n, rng):
    p = rng.normal(size=(n, 3))
    return p / np.linalg.norm(p, axis=1)[:, None]


def ball_inside(p):
    return np.linalg.norm(p, axis=1) < 1.0


def bone_axis(s):
    """A bent axis of length ~12: s in [0, 1]."""
    return np.column_stack([12.0 * s, 1.5 * np.sin(np.pi * s), 0.0 * s])


def bone_dist(p, m=4000):
    s = np.linspace(0.0, 1.0, m)
    ax = bone_axis(s)
    # distance to the polyline through its samples (fine enough at m = 4000)
    from scipy.spatial import cKDTree

    d, i = cKDTree(ax).query(p)
    # a radius that swells at the ends like a bone
    r = 0.5 + 0.35 * (np.exp(-((s[i] - 0.0) / 0.08) ** 2) + np.exp(-((s[i] - 1.0) / 0.08) ** 2))
    return d - r


def bone_surface(n, rng):
    pts = []
    need = n
    while need > 0:
        # sample near the surface: points around the axis, pushed onto it
        s = rng.uniform(0, 1, 4 * need)
        ax = bone_axis(s)
        dirs = rng.normal(size=(4 * need, 3))
        dirs /= np.linalg.norm(dirs, axis=1)[:, None]
        p = ax + dirs * 0.6
        # Newton-like projection on the distance field
        for _ in range(6):
            d = bone_dist(p)
            h = 1e-4
            g = np.column_stack([(bone_dist(p + h * e) - d) / h for e in np.eye(3)])
            g /= np.maximum(np.linalg.norm(g, axis=1), 1e-12)[:, None]
            p = p - d[:, None] * g
        ok = np.abs(bone_dist(p)) < 1e-3
        pts.append(p[ok][:need])
        need -= min(need, int(ok.sum()))
    return np.vstack(pts)


def bone_inside(p):
    return bone_dist(p) < 0.0


def torus_dist(p, R=1.0, r=0.35):
    q = np.sqrt(p[:, 0] ** 2 + p[:, 1] ** 2) - R
    return np.sqrt(q**2 + p[:, 2] ** 2) - r


def torus_surface(n, rng, R=1.0, r=0.35):
    u, v = rng.uniform(0, 2 * np.pi, (2, n))
    return np.column_stack([(R + r * np.cos(v)) * np.cos(u), (R + r * np.cos(v)) * np.sin(u), r * np.sin(v)])


def torus_inside(p):
    return torus_dist(p) < 0.0


def cube_surface(n, rng):
    corners = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], float)
    p = rng.uniform(0, 1, (n, 3))
    axis = rng.integers(0, 3, n)
    p[np.arange(n), axis] = rng.integers(0, 2, n)
    return np.vstack([corners, p])


def cube_inside(p):
    return np.all((p > 0) & (p < 1), axis=1)


SHAPES = {
    "cube": (cube_surface, cube_inside, ((0, 0, 0), (1, 1, 1))),
    "ball": (ball_surface, ball_inside, ((-1, -1, -1), (1, 1, 1))),
    "bone": (bone_surface, bone_inside, ((-1, -1, -1), (13, 3, 1))),
    "torus": (torus_surface, torus_inside, ((-1.4, -1.4, -0.4), (1.4, 1.4, 0.4))),
}


def spaced(p, n, rng):
    """About n of the points p, no two closer than ~0.6 of their mean spacing
    (greedy Poisson-disk thinning in random order)."""
    from scipy.spatial import cKDTree

    p = p[rng.permutation(len(p))]
    tree = cKDTree(p)
    d, _ = tree.query(p, k=2)
    # Poisson points: mean nearest distance 0.5/sqrt(density), so the spacing
    # of n points over the same area is 2 * mean * sqrt(len(p) / n)
    r = 0.6 * 2.0 * d[:, 1].mean() * np.sqrt(len(p) / n)
    keep = np.zeros(len(p), bool)
    taken = np.zeros(len(p), bool)
    for i in range(len(p)):
        if taken[i]:
            continue
        keep[i] = True
        taken[tree.query_ball_point(p[i], r)] = True
    return p[keep]


def lowq(shape, ntets, rng, scan=False, share=0.5):
    """Surface points and random interior points, Delaunay; tets inside kept."""
    surf, inside, (lo, hi) = SHAPES[shape]
    nv = max(200, ntets // 6)
    nsurf = int(share * nv)
    ps = spaced(surf(4 * nsurf, rng), nsurf, rng) if scan else surf(nsurf, rng)
    lo, hi = np.array(lo, float), np.array(hi, float)
    pi = []
    need = nv - nsurf
    while need > 0:
        p = rng.uniform(lo, hi, (4 * need, 3))
        p = p[inside(p)]
        pi.append(p[:need])
        need -= min(need, len(p))
    x = np.vstack([ps, np.vstack(pi)])
    # the cube's faces hold thousands of coplanar points, on which Qhull's exact
    # merging takes minutes at 1M tets; joggled input (QJ) takes seconds, and the
    # flat tets it leaves on the faces are dropped below. The ball's surface
    # points are all cospherical, which Qhull merges too: at 5M tets that ran
    # for more than 15 minutes. Qhull's own joggle triangulates points that are
    # not the ones returned, and some tets come out inverted against their
    # neighbours in the returned ones (575 at 5M); so above 2M tets the ball's
    # points are moved by 1e-7 of the box first and the mesh keeps them (smaller
    # meshes stay as they were generated before)
    if shape == "ball" and ntets > 2000000:
        x = x + rng.uniform(-1e-7, 1e-7, x.shape) * (hi - lo)
    t = Delaunay(x, qhull_options="QJ Qbb" if shape == "cube" else None).simplices
    c = x[t].mean(axis=1)
    t = t[inside(c)]
    t, vol = positive(x, t)
    t = t[vol > 1e-14 * np.max(vol)]
    used = np.unique(t)
    remap = -np.ones(len(x), int)
    remap[used] = np.arange(len(used))
    return x[used], remap[t]


def gmsh_mesh(kind, ntets, k=1.0):
    """k scales every mesh size; gmsh_sized() calibrates it to ntets."""
    import gmsh

    gmsh.initialize(["-noenv"])
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)  # 2 threads: not the same mesh twice
    gmsh.model.add(kind)
    occ = gmsh.model.occ
    h = k * (6.0 * 1.2 / ntets) ** (1 / 3) * 1.6  # uniform size for ntets in a unit cube
    if kind in ("graded-box", "graded-layer"):
        occ.addBox(0, 0, 0, 1, 1, 1)
        occ.synchronize()
        f = gmsh.model.mesh.field
        f.add("Distance", 1)
        if kind == "graded-box":  # refined toward one corner, sizes vary 10x
            f.setNumbers(1, "PointsList", [1])
            lo, hi, d0, d1 = h / 4, h * 2.5, 0.05, 1.2
        else:  # a layer of refinement along the face z = 0 (a boundary layer's sizes)
            zf = [tag for dim, tag in gmsh.model.getEntities(2)
                  if abs(gmsh.model.occ.getCenterOfMass(2, tag)[2]) < 1e-9]
            f.setNumbers(1, "SurfacesList", zf)
            lo, hi, d0, d1 = h / 5, h * 1.8, 0.02, 0.5
        f.add("Threshold", 2)
        f.setNumber(2, "InField", 1)
        f.setNumber(2, "SizeMin", lo)
        f.setNumber(2, "SizeMax", hi)
        f.setNumber(2, "DistMin", d0)
        f.setNumber(2, "DistMax", d1)
        f.setAsBackgroundMesh(2)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    elif kind == "part-cad":
        b = occ.addBox(0, 0, 0, 2, 1, 0.6)
        c = occ.addCylinder(1.0, 0.5, -0.1, 0, 0, 0.8, 0.3)
        s = occ.addSphere(2.0, 1.0, 0.6, 0.35)
        occ.cut([(3, b)], [(3, c), (3, s)])
        occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", h * (2 * 1 * 0.6) ** (1 / 3))
    elif kind == "two-region":
        b = occ.addBox(0, 0, 0, 1, 1, 1)
        s = occ.addSphere(0.5, 0.5, 0.5, 0.3)
        occ.fragment([(3, b)], [(3, s)])
        occ.synchronize()
        for i, (dim, tag) in enumerate(gmsh.model.getEntities(3)):
            gmsh.model.addPhysicalGroup(3, [tag], i + 1)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.option.setNumber("Mesh.Optimize", 0)
    gmsh.model.mesh.generate(3)
    nodes, xyz, _ = gmsh.model.mesh.getNodes()
    idx = {int(n): i for i, n in enumerate(nodes)}
    x = np.asarray(xyz).reshape(-1, 3)
    tets, regs = [], []
    for dim, tag in gmsh.model.getEntities(3):
        types, _, conn = gmsh.model.mesh.getElements(dim, tag)
        for ty, cn in zip(types, conn):
            if ty == 4:
                t = np.array([idx[int(n)] for n in cn]).reshape(-1, 4)
                tets.append(t)
                regs.append(np.full(len(t), tag))
    gmsh.finalize()
    t = np.vstack(tets)
    used = np.unique(t)
    remap = -np.ones(len(x), int)
    remap[used] = np.arange(len(used))
    t, _ = positive(x[used], remap[t])
    return x[used], t, np.concatenate(regs)


def gmsh_sized(kind, ntets):
    """Gmsh's count for a size is not known beforehand: mesh once, rescale the
    sizes by the cube root of the count ratio, mesh again."""
    x, t, reg = gmsh_mesh(kind, ntets)
    k = (len(t) / ntets) ** (1 / 3)
    if abs(k - 1) > 0.1:
        x, t, reg = gmsh_mesh(kind, ntets, k)
    return x, t, reg


def tangle(x, t, rng, frac=0.01):
    """Push a fraction of the interior vertices across their neighbours."""
    faces = np.sort(np.vstack([t[:, [1, 2, 3]], t[:, [0, 2, 3]], t[:, [0, 1, 3]], t[:, [0, 1, 2]]]), axis=1)
    _, inv, cnt = np.unique(faces, axis=0, return_inverse=True, return_counts=True)
    bnd = np.unique(faces[cnt[inv.ravel()] == 1])
    interior = np.setdiff1d(np.unique(t), bnd)
    pick = rng.choice(interior, max(1, int(frac * len(interior))), replace=False)
    e = np.linalg.norm(x[t[:, 0]] - x[t[:, 1]], axis=1).mean()
    y = x.copy()
    y[pick] += rng.normal(size=(len(pick), 3)) * 0.8 * e
    return y


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("outdir")
    ap.add_argument("--tets", type=float, default=20000)
    ap.add_argument("--only", default="")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--surface-share", type=float, default=0.5)
    a = ap.parse_args()
    global np, Delaunay
    try:
        import numpy as np
    except ImportError:
        sys.exit("corpus.py: numpy is missing (apt-get install python3-numpy)")
    try:
        from scipy.spatial import Delaunay
    except ImportError:  # pragma: no cover
        Delaunay = None
    if not 0.05 <= a.surface_share <= 0.95:
        sys.exit("corpus.py: --surface-share must be in [0.05, 0.95]")
    os.makedirs(a.outdir, exist_ok=True)
    only = set(a.only.split(",")) - {""}
    n = int(a.tets)
    made = []
    for shape, cls in (("ball", "lowq"), ("bone", "lowq"), ("torus", "lowq"), ("cube", "lowq"),
                       ("ball", "scan"), ("bone", "scan")):
        name = shape + "-" + cls
        if (only or shape == "cube" or cls == "scan") and name not in only and name + "-tangled" not in only:
            continue
        if Delaunay is None:
            sys.exit("corpus.py: scipy is missing (apt-get install python3-scipy)")
        rng = np.random.default_rng(a.seed)
        x, t = lowq(shape, n, rng, scan=cls == "scan", share=a.surface_share)
        write_medit(os.path.join(a.outdir, name + ".mesh"), x, t)
        write_medit(os.path.join(a.outdir, name + "-tangled.mesh"), tangle(x, t, rng), t)
        made += [name, name + "-tangled"]
    for kind in ("graded-box", "graded-layer", "part-cad", "two-region"):
        if only and kind not in only and kind + "-tangled" not in only:
            continue
        rng = np.random.default_rng(a.seed)
        x, t, reg = gmsh_sized(kind, n)
        write_medit(os.path.join(a.outdir, kind + ".mesh"), x, t, reg)
        write_medit(os.path.join(a.outdir, kind + "-tangled.mesh"), tangle(x, t, rng), t, reg)
        made += [kind, kind + "-tangled"]
    for m in made:
        print(os.path.join(a.outdir, m + ".mesh"))


if __name__ == "__main__":
    main()
