#!/bin/sh
# make.sh - regenerate the files of tests/data/real (see README.md) with the
# tools that write them: gmsh (the gmsh Debian package, 4.8), meshio (python3-meshio,
# 5.0), netgen (python3-netgen), tetgen (the tetgen package, 1.6), dolfinx
# (python3-dolfinx 0.5), DOLFIN (python3-dolfin 2019.2), VTK (python3-vtk9 9.1)
# FreeFEM (freefem++ 4.11), GetFEM (python3-getfem 5.4), CGAL (libcgal-dev
# 5.5, with g++) and mmg (mmg3d_O3 5.8 built from source; skipped if absent).
# Run from anywhere:
#   sh tests/data/real/make.sh
# Each file is stored gzip-compressed (gzip -n: no name or time, so a rerun with the
# same tool versions gives the same bytes).
set -e
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/qdc-real.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
# need MODULE PACKAGE: stop, naming the Debian package, when python3 lacks MODULE
need() {
    /usr/bin/python3 -c "import $1" 2> /dev/null && return
    echo "make.sh: the Python module $1 is missing: install the Debian package $2" >&2
    exit 1
}

# A unit box holding a sphere: two volumes, 7 surfaces, physical names for both
# volumes, two boundary groups, a curve and a point (line and point elements).
cat > box_sphere.geo <<'EOF'
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Sphere(2) = {0.5, 0.5, 0.5, 0.25};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
e = 1e-6;
inner() = Volume In BoundingBox{0.25 - e, 0.25 - e, 0.25 - e, 0.75 + e, 0.75 + e, 0.75 + e};
outer() = Volume{:};
outer() -= inner();
Physical Volume("material_0") = {outer()};
Physical Volume("material_1") = {inner()};
Physical Surface("inlet") = Surface In BoundingBox{-e, -e, -e, e, 1 + e, 1 + e};
w1() = Surface In BoundingBox{1 - e, -e, -e, 1 + e, 1 + e, 1 + e};
w2() = Surface In BoundingBox{-e, -e, -e, 1 + e, 1 + e, e};
Physical Surface("wall") = {w1(), w2()};
Physical Curve("edge") = Curve In BoundingBox{-e, -e, -e, e, e, 1 + e};
Physical Point("origin") = Point In BoundingBox{-e, -e, -e, e, e, e};
Mesh.CharacteristicLengthMax = 0.2;
Mesh.MaxNumThreads3D = 1;
Mesh.RandomSeed = 1;
EOF
gmsh -3 -nt 1 box_sphere.geo -format msh41 -o gmsh41.msh > /dev/null
gmsh -3 -nt 1 box_sphere.geo -format msh41 -bin -o gmsh41_bin.msh > /dev/null
gmsh -3 -nt 1 box_sphere.geo -format msh22 -o gmsh22.msh > /dev/null
gmsh -3 -nt 1 box_sphere.geo -format msh22 -bin -o gmsh22_bin.msh > /dev/null
sed 's/CharacteristicLengthMax = 0.2/CharacteristicLengthMax = 0.35/' box_sphere.geo > coarse.geo
gmsh -3 -nt 1 coarse.geo -format msh1 -o gmsh_msh1.msh > /dev/null
# Nastran bulk data in Gmsh's three field formats (Mesh.BdfFieldFormat: 0 free,
# 1 small, the default, 2 large) and the I-DEAS universal file
gmsh -3 -nt 1 box_sphere.geo -format bdf -o gmsh.bdf > /dev/null
gmsh -3 -nt 1 box_sphere.geo -string 'Mesh.BdfFieldFormat=0;' -format bdf -o gmsh_free.bdf > /dev/null
gmsh -3 -nt 1 box_sphere.geo -string 'Mesh.BdfFieldFormat=2;' -format bdf -o gmsh_large.bdf > /dev/null
gmsh -3 -nt 1 box_sphere.geo -format unv -o gmsh.unv > /dev/null
gmsh -3 -nt 1 box_sphere.geo -format msh40 -o gmsh40.msh > /dev/null
gmsh -3 -nt 1 box_sphere.geo -format vtk -o gmsh.vtk > /dev/null
gmsh -3 -nt 1 box_sphere.geo -format mesh -o gmsh.mesh > /dev/null

# Periodic: a unit box whose faces x = 1 and y = 1 are translated copies of
# x = 0 and y = 0 ($Periodic: the surfaces, their curves and points, with
# node pairs and the affine transform), in every MSH version Gmsh writes
# (4.0 binary it does not write).
cat > periodic.geo <<'EOF'
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Periodic Surface{2} = {1} Translate{1, 0, 0};
Periodic Surface{4} = {3} Translate{0, 1, 0};
Physical Volume("bulk") = {1};
Physical Surface("left") = {1};
Physical Surface("right") = {2};
Mesh.CharacteristicLengthMax = 0.3;
Mesh.MaxNumThreads3D = 1;
Mesh.RandomSeed = 1;
EOF
for v in msh41 msh40 msh22; do
    gmsh -3 -nt 1 periodic.geo -format $v -o "periodic${v#msh}.msh" 2>&1 | grep -v ANN > /dev/null
done
gmsh -3 -nt 1 periodic.geo -format msh41 -bin -o periodic41_bin.msh 2>&1 | grep -v ANN > /dev/null
gmsh -3 -nt 1 periodic.geo -format msh22 -bin -o periodic22_bin.msh 2>&1 | grep -v ANN > /dev/null

# Second-order (10-node) tets on a curved boundary: a unit sphere, physical
# volume and surface, Mesh.ElementOrder = 2 (MSH 4.1 and Gmsh's Abaqus .inp).
cat > sphere_p2.geo <<'EOF'
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 1};
Physical Volume("ball") = {1};
Physical Surface("skin") = {1};
Mesh.CharacteristicLengthMax = 0.6;
Mesh.ElementOrder = 2;
Mesh.MaxNumThreads3D = 1;
Mesh.RandomSeed = 1;
EOF
gmsh -3 -nt 1 sphere_p2.geo -format msh41 -o gmsh41_p2.msh > /dev/null
gmsh -3 -nt 1 sphere_p2.geo -format inp -o gmsh_p2.inp > /dev/null
# ... as Nastran 10-node CTETRA (small field: "+E" continuations; large: GRID*
# cards, CTETRA continued on a line whose first field is blank) and I-DEAS
# FE 118 (parabolic tetrahedron) with FE 92 parabolic triangles
gmsh -3 -nt 1 sphere_p2.geo -format bdf -o gmsh_p2.bdf > /dev/null
gmsh -3 -nt 1 sphere_p2.geo -string 'Mesh.BdfFieldFormat=2;' -format bdf -o gmsh_large_p2.bdf > /dev/null
gmsh -3 -nt 1 sphere_p2.geo -format unv -o gmsh_p2.unv > /dev/null

# meshio: the Gmsh mesh with a point array and cell arrays of several types.
/usr/bin/python3 - <<'EOF'
import zlib, struct
import numpy as np
import meshio

m = meshio.read("gmsh41.msh")
tets = m.cells_dict["tetra"]
tris = m.cells_dict["triangle"]
pts = m.points
cells = [("tetra", tets), ("triangle", tris)]
temperature = 300 + 10 * pts[:, 0] + pts[:, 1] * pts[:, 2]
material = [np.arange(len(tets), dtype=np.int32) % 3, np.full(len(tris), 7, dtype=np.int32)]
stress = [np.linspace(0, 1, len(tets)), np.linspace(1, 2, len(tris))]
velocity = np.stack([pts[:, 1], -pts[:, 0], 0 * pts[:, 2]], axis=1)
out = meshio.Mesh(pts, cells, point_data={"temperature": temperature, "velocity": velocity},
                  cell_data={"material": material, "stress": stress})
out.write("meshio_zlib.vtu")  # meshio's default: base64, vtkZLibDataCompressor
out.write("meshio_ascii.vtu", binary=False)
out.write("meshio_bin.vtk")  # legacy 5.1 binary
out.write("meshio_ascii.vtk", binary=False)

# DOLFIN XML (a plain tet mesh: meshio writes cell data to separate files),
# Abaqus (tets and boundary triangles, element sets per material, a node
# set), Netgen (materials and boundary conditions as netgen:index) and Medit
# binary (refs).
phys = m.cell_data_dict["gmsh:physical"]
tp, sp = phys["tetra"], phys["triangle"]
meshio.Mesh(pts, [("tetra", tets)]).write("dolfin.xml")
sets = {"material_%d" % i: [np.nonzero(tp == p)[0], np.zeros(0, dtype=int)]
        for i, p in enumerate(sorted(set(tp)))}
sets["boundary"] = [np.zeros(0, dtype=int), np.arange(len(tris))]
meshio.Mesh(pts, cells, cell_sets=sets, point_sets={"origin": np.array([0])}).write("meshio.inp")
meshio.Mesh(pts, cells, cell_data={"netgen:index": [tp, sp]}).write("meshio.vol")
# Medit binary (meshio writes GMF version 3: float64, int32, 64-bit positions)
meshio.Mesh(pts, cells, point_data={"medit:ref": np.arange(len(pts), dtype=np.int32) % 4},
            cell_data={"medit:ref": [tp, sp]}).write("meshio.meshb")
# Nastran (physical tags as property ids), GRID cards in free, small and
# large field (meshio 5.0 fails on free-field cells: those are small field)
nas = meshio.Mesh(pts, cells, cell_data={"nastran:ref": [tp, sp]})
meshio.nastran.write("meshio_free.bdf", nas, point_format="free", cell_format="fixed-small")
meshio.nastran.write("meshio_small.nas", nas, point_format="fixed-small",
                     cell_format="fixed-small")
meshio.nastran.write("meshio_large.bdf", nas, point_format="fixed-large",
                     cell_format="fixed-large")
# meshio's Nastran of Gmsh's second-order sphere: 10-node tets as "CTETRA_"
# (meshio 5.0's own name for them) and CTRIA6, GRID in free field; moved by
# (2, 2, 2), as meshio 5.0 cannot write a negative real in 16 characters
p2 = meshio.read("gmsh41_p2.msh")
p2c = [(k, v) for k, v in p2.cells_dict.items() if k in ("tetra10", "triangle6")]
p2p = p2.cell_data_dict["gmsh:physical"]
meshio.nastran.write("meshio_p2.bdf", meshio.Mesh(p2.points + 2.0, p2c, cell_data={
    "nastran:ref": [p2p[k] for k, _ in p2c]}), point_format="free", cell_format="fixed-small")

# XDMF (XDMF 3, one topology: the tets alone) with the data inline
# (data_format="XML"), the physical tag as Int cell data, a scalar and a vector
# point array and a float cell array; the second-order sphere as Tetrahedron_10.
# With the data in HDF5 (meshio's default: meshio_h5.xdmf beside meshio_h5.h5,
# named in the XML) and as MED (Code_Aster/Salome: families from cell_tags,
# as meshio writes them when it has them).
xd = meshio.Mesh(pts, [("tetra", tets)],
                 point_data={"temperature": temperature, "velocity": velocity},
                 cell_data={"gmsh:physical": [tp.astype(np.int32)],
                            "stress": [stress[0]]})
meshio.write("meshio.xdmf", xd, data_format="XML")
meshio.write("meshio_h5.xdmf", xd)
p2 = meshio.read("gmsh41_p2.msh")
meshio.write("meshio_p2.xdmf", meshio.Mesh(p2.points, [("tetra10", p2.cells_dict["tetra10"])]),
             data_format="XML")
med = meshio.Mesh(pts, [("tetra", tets)], point_data={"temperature": temperature},
                  cell_data={"cell_tags": [-np.searchsorted(sorted(set(tp)), tp) - 1]})
med.cell_tags = {-1 - i: ["material_%d" % i] for i in range(len(set(tp)))}
meshio.write("meshio.med", med)
# MED with its boundary triangles (TR3: families -11, -12 by physical surface,
# after the tets' -1, -2) and node families (NOE/FAM: 1 on the first surface's
# nodes, 2 on the rest of the boundary, 0 inside)
tfam = -np.searchsorted(sorted(set(tp)), tp) - 1
sfam = -np.searchsorted(sorted(set(sp)), sp) - 11
nfam = np.zeros(len(pts), dtype=np.int64)
nfam[np.unique(tris)] = 2
nfam[np.unique(tris[sp == sorted(set(sp))[0]])] = 1
medt = meshio.Mesh(pts, [("tetra", tets), ("triangle", tris)],
                   point_data={"temperature": temperature, "point_tags": nfam},
                   cell_data={"cell_tags": [tfam, sfam]})
medt.cell_tags = {**{-1 - i: ["material_%d" % i] for i in range(len(set(tp)))},
                  **{-11 - i: ["surface_%d" % s] for i, s in enumerate(sorted(set(sp)))}}
medt.point_tags = {1: ["inlet_nodes"], 2: ["boundary_nodes"]}
meshio.write("meshio_tri.med", medt)

# CalculiX's layout (as cgx writes it): one *ELEMENT block per material with
# its ELSET, S3 boundary triangles, a material, a section and a step.
with open("calculix.inp", "w") as f:
    f.write("** box with a sphere, two materials\n*NODE, NSET=Nall\n")
    for i, p in enumerate(pts):
        f.write("%d, %.12e, %.12e, %.12e\n" % (i + 1, p[0], p[1], p[2]))
    e = 1
    for k, p in enumerate(sorted(set(tp))):
        f.write("*ELEMENT, TYPE=C3D4, ELSET=material_%d\n" % k)
        for t in tets[tp == p]:
            f.write("%d, %d, %d, %d, %d\n" % (e, t[0] + 1, t[1] + 1, t[2] + 1, t[3] + 1))
            e += 1
    f.write("*ELEMENT, TYPE=S3, ELSET=skin\n")
    for t in tris:
        f.write("%d,%d,%d,%d\n" % (e, t[0] + 1, t[1] + 1, t[2] + 1))
        e += 1
    f.write("*MATERIAL, NAME=steel\n*ELASTIC\n210000, 0.3\n"
            "*SOLID SECTION, ELSET=material_0, MATERIAL=steel\n"
            "*SOLID SECTION, ELSET=material_1, MATERIAL=steel\n"
            "*BOUNDARY\nNall, 1, 3, 0.\n*STEP\n*STATIC\n*NODE FILE\nU\n*END STEP\n")

# The layout VTK's own writer (vtkXMLUnstructuredGridWriter) uses by default:
# appended raw data, UInt64 headers, zlib blocks (4 kB here, 32 kB in VTK: the
# Points take several), RangeMin/RangeMax.
BS = 4096
def zblock(raw):
    blocks = [raw[i:i + BS] for i in range(0, len(raw), BS)] or [b""]
    comp = [zlib.compress(b, 6) for b in blocks]
    last = len(blocks[-1]) if len(raw) % BS else BS
    hdr = struct.pack("<%dQ" % (3 + len(comp)), len(comp), BS, last, *[len(c) for c in comp])
    return hdr + b"".join(comp)
conn = np.concatenate([tets.ravel(), tris.ravel()]).astype(np.int64)
offs = np.concatenate([4 * np.arange(1, len(tets) + 1),
                       4 * len(tets) + 3 * np.arange(1, len(tris) + 1)]).astype(np.int64)
types = np.concatenate([np.full(len(tets), 10), np.full(len(tris), 5)]).astype(np.uint8)
arrays = [("PointData", 'type="Float64" Name="temperature"', temperature.astype("<f8")),
          ("CellData", 'type="Int32" Name="material"', np.concatenate(material).astype("<i4")),
          ("Points", 'type="Float64" Name="Points" NumberOfComponents="3" RangeMin="0" RangeMax="1.7320508076"', pts.astype("<f8")),
          ("Cells", 'type="Int64" Name="connectivity"', conn),
          ("Cells", 'type="Int64" Name="offsets"', offs),
          ("Cells", 'type="UInt8" Name="types"', types)]
blobs, off, heads = [], 0, {}
for sec, attrs, a in arrays:
    b = zblock(np.ascontiguousarray(a).tobytes())
    heads.setdefault(sec, []).append('        <DataArray %s format="appended" offset="%d"/>\n' % (attrs, off))
    blobs.append(b)
    off += len(b)
with open("vtk_appended_zlib.vtu", "wb") as f:
    f.write(b'<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" '
            b'byte_order="LittleEndian" header_type="UInt64" compressor="vtkZLibDataCompressor">\n'
            b'  <UnstructuredGrid>\n    <Piece NumberOfPoints="%d" NumberOfCells="%d">\n'
            % (len(pts), len(tets) + len(tris)))
    for sec in ("PointData", "CellData", "Points", "Cells"):
        f.write(("      <%s>\n%s      </%s>\n" % (sec, "".join(heads[sec]), sec)).encode())
    f.write(b'    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding="raw">\n   _')
    f.write(b"".join(blobs))
    f.write(b"\n  </AppendedData>\n</VTKFile>\n")
EOF

# TetGen: a box with a region attribute, boundary markers, 0-based numbering.
cat > box.poly <<'EOF'
# a unit box, two facets marked
8 3 0 1
0 0.0 0.0 0.0 1
1 0.0 0.0 1.0 1
2 0.0 1.0 0.0 1
3 0.0 1.0 1.0 1
4 1.0 0.0 0.0 2
5 1.0 0.0 1.0 2
6 1.0 1.0 0.0 2
7 1.0 1.0 1.0 2
6 1
1 0 1
4 0 1 3 2
1 0 2
4 4 6 7 5
1 0 3
4 0 4 5 1
1 0 3
4 2 3 7 6
1 0 3
4 0 2 6 4
1 0 3
4 1 5 7 3
0
1
0 0.5 0.5 0.5 7 0.002
EOF
tetgen -pq1.4aAzQ box.poly
mv box.1.node tetgen.node
mv box.1.ele tetgen.ele

# Netgen's own second-order mesh (python3-netgen): a CSG unit sphere, maxh
# 0.5, mesh.SecondOrder() (10-point volume elements, 6-point surface elements
# with the new points on the sphere) and Save.
/usr/bin/python3 - <<'EOF' > /dev/null
from netgen.csg import CSGeometry, Pnt, Sphere
geo = CSGeometry()
geo.Add(Sphere(Pnt(0, 0, 0), 1).bc("skin"))
mesh = geo.GenerateMesh(maxh=0.5)
mesh.SecondOrder()
mesh.Save("netgen_p2.vol")
EOF

# VTK's own writers (python3-vtk9): the Gmsh mesh's tets and boundary
# triangles with a point array (temperature, Float64) and a cell array
# (material, Int32), written by vtkXMLUnstructuredGridWriter with its
# defaults (appended data, zlib) and by vtkUnstructuredGridWriter (legacy,
# binary).
need vtk python3-vtk9
/usr/bin/python3 - <<'EOF'
import meshio
import numpy as np
import vtk
from vtk.util.numpy_support import numpy_to_vtk
m = meshio.read("gmsh41.msh")
tets, tris, pts = m.cells_dict["tetra"], m.cells_dict["triangle"], m.points
grid = vtk.vtkUnstructuredGrid()
vp = vtk.vtkPoints()
vp.SetData(numpy_to_vtk(np.ascontiguousarray(pts, dtype=np.float64), deep=True))
grid.SetPoints(vp)
for kind, cs in ((vtk.VTK_TETRA, tets), (vtk.VTK_TRIANGLE, tris)):
    for c in cs:
        grid.InsertNextCell(kind, len(c), [int(i) for i in c])
t = numpy_to_vtk(300 + 10 * pts[:, 0] + pts[:, 1] * pts[:, 2], deep=True)
t.SetName("temperature")
grid.GetPointData().AddArray(t)
mat = np.concatenate([m.cell_data_dict["gmsh:physical"]["tetra"],
                      m.cell_data_dict["gmsh:physical"]["triangle"]]).astype(np.int32)
a = numpy_to_vtk(mat, deep=True, array_type=vtk.VTK_INT)
a.SetName("material")
grid.GetCellData().AddArray(a)
w = vtk.vtkXMLUnstructuredGridWriter()
w.SetFileName("vtk_xml.vtu")
w.SetInputData(grid)
w.Write()
w = vtk.vtkUnstructuredGridWriter()
w.SetFileName("vtk_legacy_bin.vtk")
w.SetFileTypeToBinary()
w.SetInputData(grid)
w.Write()
EOF

# FreeFEM (the freefem++ and libfreefem++ packages; Debian 12's FreeFem++
# looks for its plugins elsewhere than libfreefem++ puts them: FF_LOADPATH):
# cube(6, 6, 6) with face labels 1-6 and region 7, its inside moved by
# movemesh, saved by savemesh as Medit ASCII and binary (FreeFEM writes no 3D
# mesh in its own .msh format: "PB Write error").
command -v FreeFem++ > /dev/null ||
    { echo "make.sh: FreeFem++ is missing: install the Debian packages freefem++ and libfreefem++" >&2; exit 1; }
cat > box.edp <<'EOF'
load "msh3"
int[int] lab = [1, 2, 3, 4, 5, 6];
mesh3 Th = cube(6, 6, 6, label = lab, region = 7);
func b = sin(pi * x) * sin(pi * y) * sin(pi * z);
Th = movemesh(Th, [x + 0.06 * b * cos(3 * y), y + 0.06 * b * sin(2 * z), z - 0.05 * b * cos(2 * x)]);
savemesh(Th, "freefem.mesh");
savemesh(Th, "freefem.meshb");
EOF
FF_LOADPATH=${FF_LOADPATH:-/usr/lib/freefem++} FreeFem++ -nw -ns box.edp > /dev/null

# DOLFIN (legacy FEniCS, python3-dolfin 2019.2): BoxMesh 6 x 6 x 6, its
# inner vertices moved at random (seeded), a MeshFunction "region" (2 within
# 0.3 of the centre, else 1); XDMFFile.write of the mesh and of the
# MeshFunction (HDF5: dolfin_h5.h5) and File("dolfin2019.xml") << mesh.
need dolfin python3-dolfin
/usr/bin/python3 - <<'EOF'
import numpy as np
import dolfin
mesh = dolfin.BoxMesh(dolfin.Point(0, 0, 0), dolfin.Point(1, 1, 1), 6, 6, 6)
x = mesh.coordinates()
inside = np.all((x > 1e-9) & (x < 1 - 1e-9), axis=1)
x[inside] += np.random.default_rng(1).uniform(-0.04, 0.04, (int(inside.sum()), 3))
mf = dolfin.MeshFunction("size_t", mesh, 3, 1)
for c in dolfin.cells(mesh):
    if (c.midpoint() - dolfin.Point(0.5, 0.5, 0.5)).norm() < 0.3:
        mf[c] = 2
mf.rename("region", "region")
with dolfin.XDMFFile(mesh.mpi_comm(), "dolfin_h5.xdmf") as f:
    f.write(mesh)
    f.write(mf)
dolfin.File("dolfin2019.xml") << mesh
EOF

# dolfinx 0.5 (python3-dolfinx; one MPI process): a unit box cut into 6 x 6 x 6
# x 6 tets (create_box), its inner vertices moved at random (seeded), cell tags
# (2 within 0.3 of the centre, else 1) and facet tags (10 at x = 0, 11 at
# x = 1, 12 elsewhere on the boundary), written by XDMFFile: write_mesh, then
# write_meshtags of each (HDF5 heavy data: dolfinx.h5 beside dolfinx.xdmf).
need dolfinx python3-dolfinx
/usr/bin/python3 - <<'EOF'
from mpi4py import MPI
import numpy as np
import dolfinx, dolfinx.io, dolfinx.mesh
comm = MPI.COMM_WORLD
mesh = dolfinx.mesh.create_box(comm, [np.array([0.0, 0.0, 0.0]), np.array([1.0, 1.0, 1.0])],
                               [6, 6, 6], dolfinx.mesh.CellType.tetrahedron)
mesh.name = "mesh"
x = mesh.geometry.x
inside = np.all((x > 1e-9) & (x < 1 - 1e-9), axis=1)
x[inside] += np.random.default_rng(1).uniform(-0.04, 0.04, (int(inside.sum()), 3))
tdim = mesh.topology.dim
cells = np.arange(mesh.topology.index_map(tdim).size_local, dtype=np.int32)
mid = dolfinx.mesh.compute_midpoints(mesh, tdim, cells)
inner = np.linalg.norm(mid - 0.5, axis=1) < 0.3
ct = dolfinx.mesh.meshtags(mesh, tdim, cells, np.where(inner, 2, 1).astype(np.int32))
ct.name = "cell_tags"
mesh.topology.create_connectivity(tdim - 1, tdim)
mesh.topology.create_connectivity(tdim - 1, 0)
bf = np.sort(dolfinx.mesh.exterior_facet_indices(mesh.topology)).astype(np.int32)
fx = dolfinx.mesh.compute_midpoints(mesh, tdim - 1, bf)[:, 0]
fv = np.where(np.isclose(fx, 0.0), 10, np.where(np.isclose(fx, 1.0), 11, 12)).astype(np.int32)
ft = dolfinx.mesh.meshtags(mesh, tdim - 1, bf, fv)
ft.name = "facet_tags"
with dolfinx.io.XDMFFile(comm, "dolfinx.xdmf", "w") as f:
    f.write_mesh(mesh)
    f.write_meshtags(ct)
    f.write_meshtags(ft)
EOF

# GetFEM's own writers (python3-getfem): its regular simplex mesh of the unit
# cube (5 x 5 x 5 cells, 750 tets), the inner vertices moved at random, with a
# P1 field; Mesh.export_to_vtu (VTU, ascii) and MeshFem.export_to_vtk (legacy
# VTK 2.0 ASCII, `float` coordinates with 6 digits, the field as POINT_DATA).
need getfem python3-getfem
/usr/bin/python3 - <<'EOF'
import getfem as gf
import numpy as np
s = np.linspace(0.0, 1.0, 6)
m = gf.Mesh("regular simplices", s, s, s)
p = m.pts()
inner = np.all((p > 1e-9) & (p < 1 - 1e-9), axis=0)
p[:, inner] += np.random.default_rng(1).uniform(-0.06, 0.06, (3, int(inner.sum())))
m.set_pts(p)
mf = gf.MeshFem(m, 1)
mf.set_classical_fem(1)
x = mf.basic_dof_nodes()
m.export_to_vtu("getfem.vtu", "ascii")
mf.export_to_vtk("getfem_field.vtk", "ascii", np.sin(x[0]) + x[1] * x[2], "u")
EOF

# CGAL (the libcgal-dev package, 5.5, header-only, and g++): cgal_mesh.cpp meshes
# a ball of radius 0.5 holding a smaller ball off its centre (two regions,
# labels 2 and 1) with Mesh_3 (make_mesh_3 of a Labeled_mesh_domain_3, its
# defaults: perturbation and exudation) and writes it with CGAL's own writers:
# output_to_medit without and with rebinding and patches, output_to_vtu binary
# and ascii. Mesh_3 orders by addresses: a rerun gives another mesh of the same
# size (about 640 vertices, 2300 tets), not the same bytes.
command -v g++ > /dev/null && [ -f /usr/include/CGAL/make_mesh_3.h ] ||
    { echo "make.sh: CGAL or g++ is missing: install the Debian packages libcgal-dev and g++" >&2; exit 1; }
g++ -O1 -std=c++17 -DCGAL_NDEBUG -o cgal_mesh "$here/cgal_mesh.cpp" -lgmp -lmpfr
./cgal_mesh

# mmg (mmg3d_O3 5.8, no Debian package: built from source, github.com/MmgTools/mmg,
# with cmake; MMG3D names the program, else mmg3d_O3 on PATH): gmsh.mesh
# remeshed (-hmax 0.25 -hausd 0.03) and written by mmg itself as Medit ASCII
# and binary, with its own keywords (Corners, RequiredVertices, Ridges,
# Normals, NormalAtVertices, Tangents, TangentAtVertices). Skipped, saying so,
# when mmg3d_O3 is absent (the files already here are kept).
mmg=${MMG3D:-mmg3d_O3}
have_mmg=0
if command -v "$mmg" > /dev/null; then
    "$mmg" -v -1 -in gmsh.mesh -out mmg.mesh -hmax 0.25 -hausd 0.03 > /dev/null
    "$mmg" -v -1 -in gmsh.mesh -out mmg.meshb -hmax 0.25 -hausd 0.03 > /dev/null
    have_mmg=1
else
    echo "make.sh: $mmg not found: mmg.mesh and mmg.meshb not remade (build mmg from github.com/MmgTools/mmg, set MMG3D)" >&2
fi

[ $have_mmg = 1 ] && mmgfiles="mmg.mesh mmg.meshb" || mmgfiles=
for f in gmsh41.msh gmsh41_bin.msh gmsh22.msh gmsh22_bin.msh gmsh40.msh gmsh.vtk gmsh.mesh meshio_zlib.vtu \
    meshio_ascii.vtu meshio_bin.vtk meshio_ascii.vtk vtk_appended_zlib.vtu tetgen.node \
    tetgen.ele dolfin.xml meshio.inp calculix.inp meshio.vol meshio.meshb periodic41.msh \
    periodic41_bin.msh periodic40.msh periodic22.msh periodic22_bin.msh gmsh41_p2.msh gmsh_p2.inp \
    gmsh_msh1.msh gmsh.bdf gmsh_free.bdf gmsh_large.bdf gmsh.unv meshio_free.bdf meshio_small.nas \
    meshio_large.bdf meshio.xdmf meshio_p2.xdmf meshio_h5.xdmf meshio_h5.h5 meshio.med meshio_tri.med \
    gmsh_p2.bdf gmsh_large_p2.bdf gmsh_p2.unv meshio_p2.bdf netgen_p2.vol \
    dolfinx.xdmf dolfinx.h5 vtk_xml.vtu vtk_legacy_bin.vtk freefem.mesh freefem.meshb \
    dolfin2019.xml dolfin_h5.xdmf dolfin_h5.h5 getfem.vtu getfem_field.vtk \
    cgal.mesh cgal_patches.mesh cgal.vtu cgal_ascii.vtu $mmgfiles; do
    gzip -n -9 -c "$f" > "$here/$f.gz"
done
ls -l "$here"
