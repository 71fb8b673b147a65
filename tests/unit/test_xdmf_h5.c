/* test_xdmf_h5.c - XDMF whose heavy data is in HDF5 (meshio_xdmf.c): the
 * datasets the reader asks for (meshio_xdmf_h5_refs), the framed input
 * read into the mesh and written back spliced with only the geometry
 * frame's values changed (the form also made in place, after the frames),
 * dolfinx MeshTags grids in HDF5 (cell tags as regions, facet tags as
 * boundary triangles with refs, in either order; a facet off the mesh
 * refused), DOLFIN's MeshFunction with no NumberType a region when its
 * dataset holds integers, the
 * XML renamed to another .h5 file, and the references refused (absolute,
 * "..", two files, a plain read). */
#include "testio.h"
#include "testlib.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* One tet in HDF5: geometry, topology, a region, and a node attribute. */
static const char xml[] =
    "<Xdmf Version=\"3.0\"><Domain><Grid Name=\"g\">"
    "<Geometry GeometryType=\"XYZ\"><DataItem DataType=\"Float\" Dimensions=\"4 3\" "
    "Format=\"HDF\" Precision=\"8\">m.h5:/g</DataItem></Geometry>"
    "<Topology TopologyType=\"Tetrahedron\" NumberOfElements=\"1\"><DataItem "
    "DataType=\"Int\" Dimensions=\"1 4\" Format=\"HDF\">\n  "
    "m.h5:/t\n</DataItem></Topology>"
    "<Attribute Name=\"x\" Center=\"Node\"><DataItem Dimensions=\"4\" Format=\"HDF\">"
    "m.h5:/x</DataItem></Attribute>"
    "<Attribute Name=\"region\" Center=\"Cell\"><DataItem DataType=\"Int\" "
    "Dimensions=\"1\" Format=\"HDF\">m.h5:/r</DataItem></Attribute>"
    "</Grid></Domain></Xdmf>\n";

/* What qdc-h5 prints for the datasets of xml (little-endian host). */
static void frames(sink *o, uint64_t ngeom)
{
    static const double g[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    static const int64_t t[4] = {0, 1, 2, 3}, r[1] = {7};
    o->n = 0;
    sink_write(o, "QDCH5v1\n", 8);
    put_frame(o, "geometry", 'f', g, ngeom);
    put_frame(o, "topology", 'i', t, 4);
    put_frame(o, "region", 'i', r, 1);
}

TEST(refs_list_the_mesh_datasets)
{
    meshio_xdmf_h5 h;
    ASSERT_OK(meshio_xdmf_h5_refs(xml, strlen(xml), &h, NULL));
    ASSERT_TRUE(!strcmp(h.file, "m.h5"));
    ASSERT_EQ_INT(h.n, 3);
    ASSERT_TRUE(!strcmp(h.set[0].name, "geometry") && h.set[0].type == 'f');
    ASSERT_TRUE(!strcmp(h.set[0].path, "/g"));
    ASSERT_EQ_INT(h.set[0].ndims, 2);
    ASSERT_EQ_INT(h.set[0].dims[0], 4);
    ASSERT_EQ_INT(h.set[0].dims[1], 3);
    ASSERT_TRUE(!strcmp(h.set[1].name, "topology") && !strcmp(h.set[1].path, "/t"));
    ASSERT_TRUE(!strcmp(h.set[2].name, "region") && !strcmp(h.set[2].path, "/r"));
    ASSERT_EQ_INT(h.set[2].dims[0], 1);
}

TEST(framed_read_and_spliced_write)
{
    static sink fr, out;
    char *in = NULL;
    size_t in_len = 0;
    mesh_t *m = NULL;
    meshio_options mo = {.source = 1};
    size_t geom;

    frames(&fr, 12);
    ASSERT_OK(meshio_xdmf_h5_input(xml, strlen(xml), fr.b, fr.n, &in, &in_len, NULL));
    ASSERT_OK(meshio_read_ex(in, in_len, MESHIO_XDMF, &mo, &m, NULL));
    ASSERT_EQ_INT(m->nv, 4);
    ASSERT_EQ_INT(m->nt, 1);
    ASSERT_TRUE(m->region != NULL);
    ASSERT_EQ_INT(m->region[0], 7);
    ASSERT_NEAR(m->xyz[3], 1.0, 0);
    ASSERT_TRUE(meshio_splices(m, MESHIO_XDMF, NULL));
    m->xyz[3] = 0.5;
    out.n = 0;
    ASSERT_OK(meshio_write(m, MESHIO_XDMF, sink_write, &out, NULL));
    ASSERT_EQ_INT((long long)out.n, (long long)in_len);
    /* the second node's x: after the magic, the XML frame, a frame header */
    geom = 8 + 32 + (strlen(xml) + 7) / 8 * 8 + 32 + 3 * 8;
    {
        double x;
        memcpy(&x, out.b + geom, 8);
        ASSERT_NEAR(x, 0.5, 0);
    }
    ASSERT_TRUE(memcmp(out.b, in, geom) == 0);
    ASSERT_TRUE(memcmp(out.b + geom + 8, in + geom + 8, in_len - geom - 8) == 0);
    mesh_free(m);
    qdc_free(in);
}

/* The form made in place after the frames were read into room left for it
 * is the one meshio_xdmf_h5_input copies together; frames without their
 * magic, or cut before it, are refused. */
TEST(the_form_is_made_in_place)
{
    static sink fr;
    static char buf[4096];
    char *in = NULL;
    size_t in_len = 0, room = meshio_xdmf_h5_room(strlen(xml));
    qdc_error e;

    frames(&fr, 12);
    ASSERT_EQ_INT((long long)room, (long long)(32 + (strlen(xml) + 7) / 8 * 8));
    ASSERT_TRUE(room + fr.n <= sizeof buf);
    memcpy(buf + room, fr.b, fr.n);
    ASSERT_OK(meshio_xdmf_h5_fill(buf, room + fr.n, xml, strlen(xml), NULL));
    ASSERT_OK(meshio_xdmf_h5_input(xml, strlen(xml), fr.b, fr.n, &in, &in_len, NULL));
    ASSERT_EQ_INT((long long)in_len, (long long)(room + fr.n));
    ASSERT_TRUE(memcmp(buf, in, in_len) == 0);
    qdc_free(in);
    ASSERT_EQ_INT(meshio_xdmf_h5_fill(buf, room + 7, xml, strlen(xml), &e), QDC_EPARSE);
    memcpy(buf + room, "QDCH5v0\n", 8);
    ASSERT_EQ_INT(meshio_xdmf_h5_fill(buf, room + fr.n, xml, strlen(xml), &e),
                  QDC_EPARSE);
    ASSERT_TRUE(strstr(e.msg, "no frames") != NULL);
}

/* Two tets in HDF5 and no region in the mesh's grid; a dolfinx MeshTags
 * grid of cell tags (sharing its Geometry) lists them (corners in another
 * order, the second first) with values 5 and 6, one of facet tags lists two
 * triangles with values 9 and 8: DX_CELLS before DX_FACETS in dx, after
 * them in dx2. */
#define DX_HEAD                                                                          \
    "<Xdmf Version=\"3.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\"><Domain>"        \
    "<Grid Name=\"mesh\" GridType=\"Uniform\">"                                          \
    "<Topology TopologyType=\"Tetrahedron\" NumberOfElements=\"2\" "                     \
    "NodesPerElement=\"4\"><DataItem Dimensions=\"2 4\" NumberType=\"Int\" "             \
    "Format=\"HDF\">d.h5:/Mesh/topology</DataItem></Topology>"                           \
    "<Geometry GeometryType=\"XYZ\"><DataItem Dimensions=\"5 3\" Format=\"HDF\">"        \
    "d.h5:/Mesh/geometry</DataItem></Geometry></Grid>"
#define DX_SHARED_AT(grid)                                                               \
    "<xi:include xpointer=\"xpointer(/Xdmf/Domain/" grid "/Geometry)\" />"
#define DX_SHARED DX_SHARED_AT("Grid[@GridType='Uniform'][1]")
#define DX_INT "NumberType=\"Int\" "
/* shared as sh, the values' DataItem attributes vt before Format */
#define DX_CELLS_AS(sh, vt)                                                              \
    "<Grid Name=\"cells\" GridType=\"Uniform\">" sh                                      \
    "<Topology TopologyType=\"Tetrahedron\" NumberOfElements=\"2\" "                     \
    "NodesPerElement=\"4\"><DataItem Dimensions=\"2 4\" NumberType=\"Int\" "             \
    "Format=\"HDF\">d.h5:/Tags/cells/topology</DataItem></Topology>"                     \
    "<Attribute Name=\"cells\" AttributeType=\"Scalar\" Center=\"Cell\"><DataItem "      \
    "Dimensions=\"2 1\" " vt "Format=\"HDF\">d.h5:/Tags/cells/Values"                    \
    "</DataItem></Attribute></Grid>"
#define DX_FACETS_AS(sh, vt)                                                             \
    "<Grid Name=\"facets\" GridType=\"Uniform\">" sh                                     \
    "<Topology TopologyType=\"Triangle\" NumberOfElements=\"2\" "                        \
    "NodesPerElement=\"3\"><DataItem Dimensions=\"2 3\" NumberType=\"Int\" "             \
    "Format=\"HDF\">d.h5:/Tags/facets/topology</DataItem></Topology>"                    \
    "<Attribute Name=\"facets\" AttributeType=\"Scalar\" Center=\"Cell\"><DataItem "     \
    "Dimensions=\"2 1\" " vt "Format=\"HDF\">d.h5:/Tags/facets/Values"                   \
    "</DataItem></Attribute></Grid>"
#define DX_CELLS DX_CELLS_AS(DX_SHARED, DX_INT)
#define DX_FACETS DX_FACETS_AS(DX_SHARED, DX_INT)
static const char dx[] = DX_HEAD DX_CELLS DX_FACETS "</Domain></Xdmf>\n";
static const char dx2[] = DX_HEAD DX_FACETS DX_CELLS "</Domain></Xdmf>\n";

/* What qdc-h5 prints for the datasets of dx: the facet tags' triangles ft
 * (the second's last corner: last). */
static void dx_frames(sink *fr, int64_t last)
{
    static const double g[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    static const int64_t t[8] = {0, 1, 2, 3, 4, 1, 3, 2};
    static const int64_t tt[8] = {3, 1, 4, 2, 2, 1, 3, 0}, tv[2] = {6, 5};
    static const int64_t fv[2] = {9, 8};
    const int64_t ft[6] = {0, 2, 1, 1, 2, last};

    fr->n = 0;
    sink_write(fr, "QDCH5v1\n", 8);
    put_frame(fr, "geometry", 'f', g, 15);
    put_frame(fr, "topology", 'i', t, 8);
    put_frame(fr, "tagtopo", 'i', tt, 8);
    put_frame(fr, "tagvals", 'i', tv, 2);
    put_frame(fr, "tritopo", 'i', ft, 6);
    put_frame(fr, "trivals", 'i', fv, 2);
}

/* Read dxml (dx or dx2) from frames as qdc-h5 gives them: the cell tags
 * the regions, the facet tags the boundary triangles with their refs. */
static void check_meshtags(const char *dxml)
{
    static const int32_t ft[6] = {0, 2, 1, 1, 2, 4};
    static sink fr;
    meshio_xdmf_h5 h;
    char *in = NULL;
    size_t in_len = 0;
    mesh_t *m = NULL;

    ASSERT_OK(meshio_xdmf_h5_refs(dxml, strlen(dxml), &h, NULL));
    ASSERT_EQ_INT(h.n, 6); /* listed in the frames' order, not the grids' */
    ASSERT_TRUE(!strcmp(h.set[2].name, "tagtopo") &&
                !strcmp(h.set[2].path, "/Tags/cells/topology"));
    ASSERT_TRUE(!strcmp(h.set[3].name, "tagvals") &&
                !strcmp(h.set[3].path, "/Tags/cells/Values") && h.set[3].type == 'i');
    ASSERT_EQ_INT(h.set[3].ndims, 2);
    ASSERT_TRUE(!strcmp(h.set[4].name, "tritopo") &&
                !strcmp(h.set[4].path, "/Tags/facets/topology"));
    ASSERT_EQ_INT(h.set[4].dims[1], 3);
    ASSERT_TRUE(!strcmp(h.set[5].name, "trivals") &&
                !strcmp(h.set[5].path, "/Tags/facets/Values"));
    dx_frames(&fr, 4);
    ASSERT_OK(meshio_xdmf_h5_input(dxml, strlen(dxml), fr.b, fr.n, &in, &in_len, NULL));
    ASSERT_OK(meshio_read(in, in_len, MESHIO_XDMF, &m, NULL));
    ASSERT_EQ_INT(m->nt, 2);
    ASSERT_TRUE(m->region != NULL);
    ASSERT_EQ_INT(m->region[0], 5);
    ASSERT_EQ_INT(m->region[1], 6);
    ASSERT_EQ_INT(m->ntri, 2);
    ASSERT_TRUE(m->tri_ref != NULL);
    ASSERT_TRUE(memcmp(m->tris, ft, sizeof ft) == 0);
    ASSERT_EQ_INT(m->tri_ref[0], 9);
    ASSERT_EQ_INT(m->tri_ref[1], 8);
    mesh_free(m);
    qdc_free(in);
}

TEST(dolfinx_meshtags_in_hdf5_as_regions)
{
    check_meshtags(dx);
}

/* dolfinx writes facet tags and cell tags as two grids, in either order:
 * the facet grid first (its values as many as the cells) used to give the
 * cell tags' topology its values. */
TEST(facet_tags_first_and_cell_tags_after_them)
{
    check_meshtags(dx2);
}

/* As dolfinx 0.5's XDMFFile.write_meshtags writes them: the geometry
 * shared as /Xdmf/Domain/Grid/Geometry, the values with no NumberType
 * (XDMF's default is Float; the dataset is int32): read as integers. */
static const char dx05[] = DX_HEAD DX_CELLS_AS(DX_SHARED_AT("Grid"), "")
    DX_FACETS_AS(DX_SHARED_AT("Grid"), "") "</Domain></Xdmf>\n";

TEST(dolfinx_05_meshtags_with_untyped_values)
{
    check_meshtags(dx05);
}

/* A facet tag grid whose triangle names a vertex the mesh lacks: refused. */
TEST(a_facet_tag_off_the_mesh_is_refused)
{
    static sink fr;
    char *in = NULL;
    size_t in_len = 0;
    mesh_t *m = NULL;
    qdc_error e;

    dx_frames(&fr, 5);
    ASSERT_OK(meshio_xdmf_h5_input(dx, strlen(dx), fr.b, fr.n, &in, &in_len, NULL));
    ASSERT_EQ_INT(meshio_read(in, in_len, MESHIO_XDMF, &m, &e), QDC_EPARSE);
    ASSERT_TRUE(strstr(e.msg, "facet tag triangle 1: vertex 5") != NULL);
    qdc_free(in);
}

TEST(a_geometry_frame_of_another_size_is_refused)
{
    static sink fr;
    char *in = NULL;
    size_t in_len = 0;
    mesh_t *m = NULL;
    qdc_error e;

    frames(&fr, 9);
    ASSERT_OK(meshio_xdmf_h5_input(xml, strlen(xml), fr.b, fr.n, &in, &in_len, NULL));
    ASSERT_EQ_INT(meshio_read_ex(in, in_len, MESHIO_XDMF, NULL, &m, &e), QDC_EPARSE);
    ASSERT_TRUE(strstr(e.msg, "9 values") != NULL);
    qdc_free(in);
}

TEST(rename_changes_only_the_file_names)
{
    static sink out;
    static char want[sizeof xml + 64];
    const char *p = xml;
    size_t n = 0;

    ASSERT_OK(meshio_xdmf_h5_rename(xml, strlen(xml), "out.h5", sink_write, &out, NULL));
    while (*p) { /* "m.h5:" -> "out.h5:" */
        if (!strncmp(p, "m.h5:", 5)) {
            memcpy(want + n, "out.h5:", 7);
            n += 7;
            p += 5;
        } else {
            want[n++] = *p++;
        }
    }
    ASSERT_EQ_INT((long long)out.n, (long long)n);
    ASSERT_TRUE(memcmp(out.b, want, n) == 0);
    out.n = 0;
    ASSERT_EQ_INT(
        meshio_xdmf_h5_rename(xml, strlen(xml), "a&b.h5", sink_write, &out, NULL),
        QDC_EINVAL);
}

/* xml with its first "m.h5" replaced by file */
static qdc_status refs_with(const char *file, qdc_error *e)
{
    static char x[sizeof xml + 64];
    const char *at = strstr(xml, "m.h5");
    meshio_xdmf_h5 h;

    snprintf(x, sizeof x, "%.*s%s%s", (int)(at - xml), xml, file, at + 4);
    return meshio_xdmf_h5_refs(x, strlen(x), &h, e);
}

TEST(references_out_of_the_folder_are_refused)
{
    qdc_error e;
    mesh_t *m = NULL;

    ASSERT_EQ_INT(refs_with("../m.h5", &e), QDC_EFORMAT);
    ASSERT_TRUE(strstr(e.msg, "outside") != NULL);
    ASSERT_EQ_INT(refs_with("a/../../m.h5", &e), QDC_EFORMAT);
    ASSERT_EQ_INT(refs_with("/tmp/m.h5", &e), QDC_EFORMAT);
    ASSERT_TRUE(strstr(e.msg, "absolute") != NULL);
    ASSERT_EQ_INT(refs_with("n.h5", &e), QDC_EFORMAT);
    ASSERT_TRUE(strstr(e.msg, "two HDF5 files") != NULL);
    {
        static sink x;
        meshio_xdmf_h5 h;
        ASSERT_OK(
            meshio_xdmf_h5_rename(xml, strlen(xml), "sub/..m.h5", sink_write, &x, NULL));
        ASSERT_OK(meshio_xdmf_h5_refs(x.b, x.n, &h, NULL)); /* a name, not a parent */
        ASSERT_TRUE(!strcmp(h.file, "sub/..m.h5"));
    }
    ASSERT_EQ_INT(meshio_read(xml, strlen(xml), MESHIO_XDMF, &m, &e), QDC_EFORMAT);
    ASSERT_TRUE(strstr(e.msg, "qdc command") != NULL);
}

/* DOLFIN's MeshFunction in the mesh's own grid: HDF5 values with no
 * NumberType (XDMF's default is Float). qdc-h5 is asked for either class
 * ('a') and frames integers as 'i', floats as 'f': integers are the region,
 * floats (a DG0 Function's values) are not, and the file is read either way;
 * a typed integer attribute is preferred to it. */
TEST(dolfin_meshfunction_by_the_dataset_class)
{
    static const char dolfin[] =
        "<Xdmf Version=\"3.0\"><Domain><Grid Name=\"mesh\">"
        "<Topology NumberOfElements=\"1\" TopologyType=\"Tetrahedron\"><DataItem "
        "Dimensions=\"1 4\" NumberType=\"UInt\" Format=\"HDF\">m.h5:/t</DataItem>"
        "</Topology><Geometry GeometryType=\"XYZ\"><DataItem Dimensions=\"4 3\" "
        "Format=\"HDF\">m.h5:/g</DataItem></Geometry>"
        "<Attribute Name=\"f\" AttributeType=\"Scalar\" Center=\"Cell\"><DataItem "
        "Dimensions=\"1 1\" Format=\"HDF\">m.h5:/f</DataItem></Attribute>"
        "%s</Grid></Domain></Xdmf>\n";
    static const char typed[] =
        "<Attribute Name=\"other\" AttributeType=\"Scalar\" Center=\"Cell\"><DataItem "
        "Dimensions=\"1\" DataType=\"Int\" Format=\"HDF\">m.h5:/o</DataItem>"
        "</Attribute>";
    static const double g[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, rf[1] = {7.5};
    static const int64_t t[4] = {0, 1, 2, 3}, ri[1] = {7};
    char doc[1400];
    meshio_xdmf_h5 h;

    snprintf(doc, sizeof doc, dolfin, typed);
    ASSERT_OK(meshio_xdmf_h5_refs(doc, strlen(doc), &h, NULL));
    ASSERT_EQ_INT(h.n, 3);
    ASSERT_TRUE(!strcmp(h.set[2].name, "region") && !strcmp(h.set[2].path, "/o"));
    ASSERT_EQ_INT(h.set[2].type, 'i');
    snprintf(doc, sizeof doc, dolfin, "");
    ASSERT_OK(meshio_xdmf_h5_refs(doc, strlen(doc), &h, NULL));
    ASSERT_EQ_INT(h.n, 3);
    ASSERT_TRUE(!strcmp(h.set[2].name, "region") && !strcmp(h.set[2].path, "/f"));
    ASSERT_EQ_INT(h.set[2].type, 'a');
    for (int k = 0; k < 2; k++) {
        static sink fr, out;
        char *in = NULL;
        size_t in_len = 0;
        mesh_t *m = NULL;
        meshio_options mo = {.source = 1};
        fr.n = 0;
        sink_write(&fr, "QDCH5v1\n", 8);
        put_frame(&fr, "topology", 'i', t, 4);
        put_frame(&fr, "geometry", 'f', g, 12);
        if (k == 0)
            put_frame(&fr, "region", 'i', ri, 1);
        else
            put_frame(&fr, "region", 'f', rf, 1);
        ASSERT_OK(meshio_xdmf_h5_input(doc, strlen(doc), fr.b, fr.n, &in, &in_len, NULL));
        ASSERT_OK(meshio_read_ex(in, in_len, MESHIO_XDMF, &mo, &m, NULL));
        ASSERT_EQ_INT(m->nt, 1);
        if (k == 0) {
            ASSERT_TRUE(m->region != NULL);
            ASSERT_EQ_INT(m->region[0], 7);
        } else {
            ASSERT_TRUE(m->region == NULL);
        }
        out.n = 0;
        ASSERT_OK(meshio_write(m, MESHIO_XDMF, sink_write, &out, NULL));
        ASSERT_TRUE(out.n == in_len && memcmp(out.b, in, in_len) == 0);
        mesh_free(m);
        qdc_free(in);
    }
}

TEST_MAIN("xdmf_h5", T(refs_list_the_mesh_datasets),
          T(dolfin_meshfunction_by_the_dataset_class), T(framed_read_and_spliced_write),
          T(the_form_is_made_in_place), T(dolfinx_meshtags_in_hdf5_as_regions),
          T(facet_tags_first_and_cell_tags_after_them),
          T(dolfinx_05_meshtags_with_untyped_values),
          T(a_facet_tag_off_the_mesh_is_refused),
          T(a_geometry_frame_of_another_size_is_refused),
          T(rename_changes_only_the_file_names),
          T(references_out_of_the_folder_are_refused))
