#!/usr/bin/python3
"""Netgen's volume optimizer on a Medit mesh, boundary kept (bench/run.sh --topology).

Usage: netgen_opt.py IN.mesh OUT.mesh [INFO.json]

Reads IN (Vertices, Tetrahedra with their region refs; a Triangles section is
ignored: the faces are taken from the tets; the tets turned all together if
their volumes sum to less than zero), builds a Netgen mesh of it with
Debian's python3-netgen (one Element3D per tet, its region as the element
index; one Element2D per boundary face and per face between two regions, with
a FaceDescriptor per (region, region-or-outside) pair, so that Netgen keeps
those faces, their edges and their vertices), runs Mesh.OptimizeVolumeMesh()
with Netgen's defaults (3 steps of its volume optimization: edge and face
swaps, combining (edge collapse) and smoothing of the interior vertices), and
writes the result as Medit: the vertices in use, the tets with their region
refs, the boundary and interface triangles with the face descriptor's number.
INFO gets the seconds inside OptimizeVolumeMesh and the counts in and out.
"""
import json
import sys
import time

import numpy as np


def read_medit(path):
    """Vertices and Tetrahedra (with refs) of an ASCII Medit file."""
    tok = open(path).read().split()
    out, i = {}, 0
    while i < len(tok):
        w = tok[i]
        if w in ('Vertices', 'Tetrahedra', 'Triangles', 'Edges', 'Corners', 'RequiredVertices',
                 'Ridges', 'RequiredEdges', 'RequiredTriangles', 'Normals', 'NormalAtVertices',
                 'Tangents', 'TangentAtVertices', 'Quadrilaterals', 'Hexahedra', 'Prisms'):
            n = int(tok[i + 1])
            k = {'Vertices': 4, 'Tetrahedra': 5, 'Triangles': 4, 'Edges': 3, 'Normals': 3,
                 'NormalAtVertices': 2, 'Tangents': 3, 'TangentAtVertices': 2,
                 'Quadrilaterals': 5, 'Hexahedra': 9, 'Prisms': 7}.get(w, 1)
            out[w] = np.array(tok[i + 2:i + 2 + k * n], float).reshape(n, k)
            i += 2 + k * n
        else:
            i += 1
    x = out['Vertices'][:, :3]
    t = out['Tetrahedra'][:, :4].astype(np.int64) - 1
    ref = out['Tetrahedra'][:, 4].astype(np.int64)
    return x, t, ref


def faces_to_keep(t, ref):
    """Boundary faces and faces between tets of different refs: (faces, (domin,
    domout) per face), each face oriented outward of its domin tet."""
    # the faces of a positively oriented tet (0,1,2,3), each seen from outside
    loc = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])
    f = t[:, loc].reshape(-1, 3)
    owner = np.repeat(np.arange(len(t)), 4)
    key = np.sort(f, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    order = np.argsort(inv, kind='stable')
    first = np.ones(len(order), bool)
    first[1:] = inv[order][1:] != inv[order][:-1]
    faces, doms = [], []
    for j in np.nonzero(first)[0]:
        a = order[j]
        if cnt[inv[a]] == 1:
            faces.append(f[a])
            doms.append((ref[owner[a]], 0))
        else:
            b = order[j + 1]
            if ref[owner[a]] != ref[owner[b]]:
                faces.append(f[a])
                doms.append((ref[owner[a]], ref[owner[b]]))
    return np.array(faces, np.int64).reshape(-1, 3), doms


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    import netgen.meshing as ng
    ng.SetMessageImportance(0)
    x, t, ref = read_medit(sys.argv[1])
    # positive orientation as a whole (the corpus writes it; files of other tools
    # may not): all tets turned when their volumes sum to less than zero, never one
    # by one, so that the inverted tets of a tangled mesh stay inverted
    a, b, c, d = (x[t[:, k]] for k in range(4))
    if np.einsum('ij,ij->i', b - a, np.cross(c - a, d - a)).sum() < 0:
        t[:, [0, 1]] = t[:, [1, 0]]
    regions = sorted(set(ref.tolist()))
    rix = {r: i + 1 for i, r in enumerate(regions)}  # Netgen domains are 1..k
    faces, doms = faces_to_keep(t, ref)

    m = ng.Mesh(dim=3)
    pid = [m.Add(ng.MeshPoint(ng.Pnt(*p))) for p in x.tolist()]
    fd = {}
    for din, dout in sorted(set(doms)):
        fd[(din, dout)] = m.Add(ng.FaceDescriptor(surfnr=len(fd) + 1, domin=rix[din],
                                                  domout=rix.get(dout, 0), bc=len(fd) + 1))
    # Netgen numbers a tet's vertices the other way round (its positive volume is
    # our negative one): swap two; its surface elements' normals point out of domin
    # the same way, so a face seen from outside its domin tet is reversed too
    for (p, q, r_), dd in zip(faces.tolist(), doms):
        m.Add(ng.Element2D(fd[dd], [pid[p], pid[r_], pid[q]]))
    for (p, q, r_, s), g in zip(t.tolist(), ref.tolist()):
        m.Add(ng.Element3D(rix[g], [pid[q], pid[p], pid[r_], pid[s]]))

    t0 = time.perf_counter()
    m.OptimizeVolumeMesh()
    sec = time.perf_counter() - t0
    m.Compress()

    pts = np.array([[p[0], p[1], p[2]] for p in m.Points()])
    tet = np.array([[v.nr for v in e.vertices] for e in m.Elements3D()], np.int64)
    tix = np.array([e.index for e in m.Elements3D()], np.int64)
    tri = np.array([[v.nr for v in e.vertices] for e in m.Elements2D()], np.int64)
    fix = np.array([e.index for e in m.Elements2D()], np.int64)
    tet[:, [0, 1]] = tet[:, [1, 0]]
    tri = tri[:, [0, 2, 1]] if len(tri) else tri.reshape(0, 3)
    with open(sys.argv[2], 'w') as f:
        f.write('MeshVersionFormatted 2\nDimension 3\nVertices\n%d\n' % len(pts))
        np.savetxt(f, np.column_stack([pts, np.zeros(len(pts))]), fmt='%.17g %.17g %.17g %d')
        f.write('Triangles\n%d\n' % len(tri))
        np.savetxt(f, np.column_stack([tri, fix]), fmt='%d')
        f.write('Tetrahedra\n%d\n' % len(tet))
        np.savetxt(f, np.column_stack([tet, np.array(regions)[tix - 1]]), fmt='%d')
        f.write('End\n')
    if len(sys.argv) == 4:
        with open(sys.argv[3], 'w') as f:
            json.dump({'seconds': {'optimize': sec}, 'tets_in': len(t), 'tets_out': len(tet),
                       'verts_in': len(x), 'verts_out': len(pts)}, f, indent=1)
            f.write('\n')


if __name__ == '__main__':
    main()
