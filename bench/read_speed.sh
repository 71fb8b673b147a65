#!/bin/sh
# read_speed.sh - reading speed of every mesh format on a ~1M-tet mesh.
# Generates the unit-cube mesh of scripts/corpus.py (cube-lowq, --tets 1000000,
# seed 1), writes it in each format with `qdc convert` (Abaqus and Netgen,
# which qdc writes only spliced, with meshio), builds bench/read_speed.c
# against build/rel/libqdc.a and prints one line per format: size, tets, best
# of three parses (file already in memory, no source kept) and MB/s. Then MED
# (HDF5, written by meshio, families -1/-2): `qdc-h5 med-read`, the whole
# process, best of three; and XDMF with its heavy data in HDF5 (meshio,
# uncompressed and gzip): `qdc-h5 h5-read` of its two datasets and `qdc
# convert` of the .xdmf, each the whole process, best of three (MB/s of the
# .h5 file). Targets: ASCII >= 100 MB/s, binary and HDF5
# >= 500 MB/s. Files go to bench/out/read_speed
# (gitignored); run `make` first.
#   sh bench/read_speed.sh [TETS]
set -e
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BIN=$ROOT/build/rel
PY=/usr/bin/python3
OUT=$ROOT/bench/out/read_speed
TETS=${1:-1000000}
mkdir -p "$OUT"
cd "$OUT"
if [ ! -s cube.mesh ] || [ "$(cat tets 2> /dev/null)" != "$TETS" ]; then
    rm -rf corpus
    "$PY" "$ROOT/scripts/corpus.py" corpus --only cube-lowq --tets "$TETS" --seed 1 > /dev/null
    mv corpus/cube-lowq.mesh cube.mesh
    echo "$TETS" > tets
fi
for spec in gmsh41.msh:gmsh gmsh41b.msh:gmsh-bin gmsh22.msh:gmsh22 gmsh22b.msh:gmsh22-bin \
    gmsh40.msh:gmsh40 ascii.vtk:vtk-ascii bin.vtk:vtk ascii.vtu:vtu-ascii appended.vtu:vtu \
    medit.meshb:meshb dolfin.xml:dolfin; do
    f=${spec%%:*}
    [ -s "$f" ] && [ "$f" -nt cube.mesh ] ||
        "$BIN/qdc" convert cube.mesh "$f" --out-format "${spec#*:}" --quiet
done
if [ ! -s abaqus.inp ] || [ cube.mesh -nt abaqus.inp ]; then
    "$PY" - << 'PYEOF'
import meshio
m = meshio.read("cube.mesh")
m = meshio.Mesh(m.points, [("tetra", m.cells_dict["tetra"])])
m.write("abaqus.inp")
m.write("netgen.vol")
PYEOF
fi
cc -D_POSIX_C_SOURCE=200809L -I"$ROOT/lib" -std=c11 -O2 -o read_speed \
    "$ROOT/bench/read_speed.c" "$BIN/libqdc.a" -lcholmod -lz -lm -ltet -lstdc++ -fopenmp
./read_speed cube.mesh gmsh41.msh gmsh41b.msh gmsh22.msh gmsh22b.msh gmsh40.msh ascii.vtk \
    bin.vtk ascii.vtu appended.vtu medit.meshb dolfin.xml abaqus.inp netgen.vol
if [ ! -s cube.med ] || [ cube.mesh -nt cube.med ]; then
    "$PY" - << 'PYEOF'
import meshio, numpy as np
m = meshio.read("cube.mesh")
t = m.cells_dict["tetra"]
med = meshio.Mesh(m.points, [("tetra", t)], cell_data={"cell_tags": [-1 - np.arange(len(t)) % 2]})
med.cell_tags = {-1: ["material_0"], -2: ["material_1"]}
med.write("cube.med")
PYEOF
fi
if [ -x "$BIN/qdc-h5" ]; then
    "$PY" - "$BIN/qdc-h5" cube.med << 'PYEOF'
import os, subprocess, sys, time
best = None
for _ in range(3):
    t0 = time.perf_counter()
    subprocess.run([sys.argv[1], "med-read", sys.argv[2]], stdout=subprocess.DEVNULL, check=True)
    dt = time.perf_counter() - t0
    best = dt if best is None or dt < best else best
mb = os.path.getsize(sys.argv[2]) / 1e6
print("%-14s %8.1f MB  qdc-h5 med-read, whole process, best of 3: %.3f s = %.0f MB/s"
      % (sys.argv[2], mb, best, mb / best))
PYEOF
fi
if [ ! -s cube_h5.xdmf ] || [ cube.mesh -nt cube_h5.xdmf ]; then
    "$PY" - << 'PYEOF'
import meshio
m = meshio.read("cube.mesh")
m = meshio.Mesh(m.points, [("tetra", m.cells_dict["tetra"])])
meshio.xdmf.write("cube_h5.xdmf", m, data_format="HDF", compression=None)
meshio.xdmf.write("cube_h5z.xdmf", m, data_format="HDF", compression="gzip")
PYEOF
fi
if [ -x "$BIN/qdc-h5" ]; then
    "$PY" - "$BIN" << 'PYEOF'
import os, re, subprocess, sys, time
def best(cmd):
    b = None
    for _ in range(3):
        t0 = time.perf_counter()
        subprocess.run(cmd, stdout=subprocess.DEVNULL, check=True)
        dt = time.perf_counter() - t0
        b = dt if b is None or dt < b else b
    return b
for x in ("cube_h5.xdmf", "cube_h5z.xdmf"):
    xml = open(x).read()
    h5 = x[:-5] + ".h5"
    items = re.findall(r'Dimensions="(\d+) (\d+)"[^>]*>[^:<]*:(/\w+)<', xml)
    spec = ["%s:%s:%sx%s:%s" % (n, t, a, b, p)
            for (n, t), (a, b, p) in zip((("geometry", "f"), ("topology", "i")), items)]
    mb = os.path.getsize(h5) / 1e6
    for what, cmd in (("qdc-h5 h5-read", [sys.argv[1] + "/qdc-h5", "h5-read", h5] + spec),
                      ("qdc convert", [sys.argv[1] + "/qdc", "convert", x, "xdmf_h5.qmesh",
                                       "--quiet"])):
        dt = best(cmd)
        print("%-14s %8.1f MB  %s, whole process, best of 3: %.3f s = %.0f MB/s"
              % (h5, mb, what, dt, mb / dt))
PYEOF
fi
