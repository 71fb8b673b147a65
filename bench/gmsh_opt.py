#!/usr/bin/python3
"""Optimize a tet mesh with Gmsh's Python API (Debian python3-gmsh).

Usage: gmsh_opt.py IN.mesh OUT.mesh METHOD INFO.json

METHOD is passed to gmsh.model.mesh.optimize(METHOD, force=True):
"Relocate3D" moves vertices only; "" is Gmsh's default tetrahedral
optimizer, which also swaps/collapses (connectivity may change).
INFO.json gets the Gmsh version and the wall time of read / optimize /
write as measured inside this process (the whole-process wall time, CPU
and peak RSS are measured outside by measure.py).
"""
import json
import sys
import time

import gmsh


def main():
    src, dst, method, info = sys.argv[1:5]
    t = {}
    t0 = time.perf_counter()
    gmsh.initialize()
    gmsh.option.setNumber('General.Terminal', 1)
    t['init'] = time.perf_counter() - t0
    t0 = time.perf_counter()
    gmsh.open(src)
    t['read'] = time.perf_counter() - t0
    t0 = time.perf_counter()
    gmsh.model.mesh.optimize(method, force=True)
    t['optimize'] = time.perf_counter() - t0
    t0 = time.perf_counter()
    gmsh.write(dst)
    t['write'] = time.perf_counter() - t0
    res = {'gmsh_version': gmsh.__version__, 'method': method,
           'threads': gmsh.option.getNumber('General.NumThreads'), 'seconds': t}
    gmsh.finalize()
    with open(info, 'w') as f:
        json.dump(res, f, indent=1)
        f.write('\n')


if __name__ == '__main__':
    main()
