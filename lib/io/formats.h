/* formats.h - the format table: one line per mesh format, MESHIO_FORMAT(ID,
 * descriptor). The line makes the constant MESHIO_<ID> of meshio_format (its
 * value is the line's position, from 1), declares the descriptor and
 * registers it for meshio.c, which finds a format's names, extensions, media
 * types, sniffing, reader and writer only there. The descriptor itself is in
 * the format's own file (format.h says what it holds). A new format is a new
 * line at the end: the values of the others never change (qdcd stores the
 * names, not the values, but tests and clients name the constants).
 * Included with MESHIO_FORMAT defined; no include guard. */
MESHIO_FORMAT(MEDIT, fmt_medit)           /* Medit .mesh ASCII */
MESHIO_FORMAT(TETGEN, fmt_tetgen)         /* TetGen .node + .ele */
MESHIO_FORMAT(QMESH, fmt_qmesh)           /* qdc binary, proto/mesh-binary.md */
MESHIO_FORMAT(JSON, fmt_json)             /* JSON vertices/tets/regions, 0-based */
MESHIO_FORMAT(GMSH41, fmt_gmsh41)         /* Gmsh MSH 4.1 ASCII */
MESHIO_FORMAT(GMSH41_BIN, fmt_gmsh41_bin) /* Gmsh MSH 4.1 binary */
MESHIO_FORMAT(GMSH22, fmt_gmsh22)         /* Gmsh MSH 2.2 ASCII */
MESHIO_FORMAT(VTK, fmt_vtk)               /* legacy VTK, binary */
MESHIO_FORMAT(VTK_ASCII, fmt_vtk_ascii)   /* legacy VTK, ASCII */
MESHIO_FORMAT(VTU, fmt_vtu)               /* VTK XML, appended raw */
MESHIO_FORMAT(VTU_ASCII, fmt_vtu_ascii)   /* VTK XML, ascii */
MESHIO_FORMAT(GMSH22_BIN, fmt_gmsh22_bin) /* Gmsh MSH 2.2 binary */
MESHIO_FORMAT(GMSH40, fmt_gmsh40)         /* Gmsh MSH 4.0 ASCII */
MESHIO_FORMAT(DOLFIN, fmt_dolfin)         /* DOLFIN legacy XML */
MESHIO_FORMAT(MESHB, fmt_meshb)           /* Medit binary .meshb */
MESHIO_FORMAT(ABAQUS, fmt_abaqus)         /* Abaqus/CalculiX .inp */
MESHIO_FORMAT(NETGEN, fmt_netgen)         /* Netgen .vol */
MESHIO_FORMAT(MSH1, fmt_msh1)             /* Gmsh MSH 1 */
MESHIO_FORMAT(BDF, fmt_bdf)               /* Nastran bulk data */
MESHIO_FORMAT(UNV, fmt_unv)               /* I-DEAS universal */
MESHIO_FORMAT(XDMF, fmt_xdmf)             /* XDMF 2/3, inline XML data */
MESHIO_FORMAT(MED, fmt_med)               /* MED, HDF5 via qdc-h5 */
