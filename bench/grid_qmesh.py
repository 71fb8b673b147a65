#!/usr/bin/env python3
"""grid_qmesh.py N OUT - the unit cube as N^3 cells of 6 positive tets
(6 N^3 tets; N = 56 gives 1.05M), written as a binary QMESH (numpy)."""
import sys, numpy as np
n = int(sys.argv[1])
i, j, k = np.meshgrid(np.arange(n + 1), np.arange(n + 1), np.arange(n + 1), indexing="ij")
xyz = np.stack([i, j, k], -1).reshape(-1, 3).astype("<f8") / n
idx = lambda a, b, c: (a * (n + 1) + b) * (n + 1) + c
ci, cj, ck = [x.ravel() for x in np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")]
tets = []
for p in [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]:
    cur = [ci.copy(), cj.copy(), ck.copy()]
    path = [idx(*cur)]
    for ax in p:
        cur[ax] = cur[ax] + 1
        path.append(idx(*cur))
    t = np.stack(path, -1)
    e = xyz[t[:, 1:]] - xyz[t[:, :1]]
    neg = np.linalg.det(e) < 0
    t[neg, 1], t[neg, 2] = t[neg, 2].copy(), t[neg, 1].copy()
    tets.append(t)
tets = np.concatenate(tets).astype("<i4")
with open(sys.argv[2], "wb") as f:
    f.write(b"QDCMESH\0" + np.array([1, 0], "<u4").tobytes() + np.array([len(xyz), len(tets)], "<u8").tobytes())
    f.write(xyz.tobytes()); f.write(tets.tobytes())
print("mesh: %d vertices, %d tets, %.1f MB" % (len(xyz), len(tets), (32 + xyz.nbytes + tets.nbytes) / 1e6))
