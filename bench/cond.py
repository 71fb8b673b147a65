#!/usr/bin/python3
"""Condition number of a mesh's P1 Laplacian stiffness matrix (bench/run.sh --topology).

Usage: cond.py MESH [-o OUT.json]

Assembles K_ij = sum over tets of |V| grad(phi_i) . grad(phi_j) (linear
elements, volume taken unsigned so that an inverted tet adds a positive
semi-definite block like the others), keeps the rows and columns of the
interior vertices (those on no boundary face; faces between regions are
interior), and prints {"cond", "lambda_max", "lambda_min", "n_interior",
"n_degenerate"}: cond = lambda_max / lambda_min, both from scipy's ARPACK
(eigsh: the largest directly, the smallest by shift-invert about 0 with a
sparse LU), relative tolerance 1e-8. The number does not depend on the
mesh's scale. Tets with zero volume (no gradient) are left out and counted
in n_degenerate. Vertices used by no tet are dropped.
"""
import argparse
import json
import os
import sys

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'tests',
                                'tools'))
import evaluate  # noqa: E402  (the bench's one mesh reader)


def stiffness(x, t):
    """P1 Laplacian stiffness matrix (n x n, CSR) and the degenerate tet count."""
    e = x[t[:, 1:]] - x[t[:, :1]]               # (m, 3, 3) edge vectors from vertex 0
    det = np.linalg.det(e)
    ok = np.abs(det) > 1e-300
    e, det, t = e[ok], det[ok], t[ok]
    # gradients of the barycentric coordinates 1..3 are the rows of inv(E)^T ...
    g123 = np.linalg.inv(e).transpose(0, 2, 1)   # (m, 3, 3): row k = grad phi_{k+1}
    g = np.concatenate([-g123.sum(axis=1, keepdims=True), g123], axis=1)  # (m, 4, 3)
    vol = np.abs(det) / 6.0
    ke = np.einsum('mid,mjd->mij', g, g) * vol[:, None, None]
    rows = np.repeat(t, 4, axis=1).ravel()
    cols = np.tile(t, (1, 4)).ravel()
    k = sp.coo_matrix((ke.ravel(), (rows, cols)), shape=(len(x), len(x))).tocsr()
    return k, int((~ok).sum())


def condition(path):
    x, t = evaluate.compact(*evaluate.read_mesh(path))
    k, ndeg = stiffness(x, t)
    bnd = np.unique(evaluate.boundary_faces(t, len(x)))
    interior = np.setdiff1d(np.arange(len(x)), bnd)
    ki = k[interior][:, interior].tocsc()
    if ki.shape[0] < 2:
        return {'cond': None, 'n_interior': int(ki.shape[0]), 'n_degenerate': ndeg}
    lmax = eigsh(ki, k=1, which='LA', tol=1e-8, return_eigenvectors=False)[0]
    lmin = eigsh(ki, k=1, sigma=0, which='LM', tol=1e-8, return_eigenvectors=False)[0]
    return {'cond': float(lmax / lmin), 'lambda_max': float(lmax), 'lambda_min': float(lmin),
            'n_interior': int(ki.shape[0]), 'n_degenerate': ndeg}


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('mesh')
    ap.add_argument('-o', metavar='OUT.json')
    a = ap.parse_args()
    res = condition(a.mesh)
    text = json.dumps(res, indent=1) + '\n'
    if a.o:
        with open(a.o, 'w') as f:
            f.write(text)
    else:
        sys.stdout.write(text)


if __name__ == '__main__':
    main()
