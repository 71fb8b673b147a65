#!/bin/sh
# read_speed.sh - reading speed of every mesh format on a ~1M-tet mesh.
# Generates the unit-cube mesh of scripts/corpus.py (cube-lowq, --tets 1000000,
# seed 1), writes it in each format with `qdc convert` (Abaqus and Netgen,
# which qdc writes only spliced, with meshio), builds bench/read_speed.c
# against build/rel/libqdc.a and prints one line per format: size, tets, best
# of three parses (file already in memory, no source kept) and MB/s. Targets:
# ASCII >= 100 MB/s, binary >= 500 MB/s. Files go to bench/out/read_speed
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
