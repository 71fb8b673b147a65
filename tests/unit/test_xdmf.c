/* test_xdmf.c - the XDMF reader (data inline), its writer and its spliced
 * write, on hand-made two-tet documents in the forms meshio, DOLFIN (XDMF 2,
 * MeshFunction) and dolfinx (MeshTags) write: known coordinates, tets and
 * regions, dolfinx facet tags as boundary triangles with refs,
 * second-order tets, the Geometry's numbers alone rewritten, and
 * refusals (entities, heavy data, bad counts and indices) with their line. */
#include "testio.h"
#include "testlib.h"

/* Five points a = 0, b = x, c = y, d = z, e = (1,1,1); tets a b c d (region
 * 1) and e b c d (region 2). meshio's XDMF 3 form: Geometry first, a point
 * attribute, then the cell data. */
static const char meshio3[] =
    "<Xdmf Version=\"3.0\"><Domain><Grid Name=\"Grid\"><Geometry GeometryType=\"XYZ\">"
    "<DataItem DataType=\"Float\" Dimensions=\"5 3\" Format=\"XML\" Precision=\"8\">\n"
    "0.0 0.0 0.0\n1.0 0.0 0.0\n0.0 1.0 0.0\n0.0 0.0 1.0\n1.0 1.0 1.0\n"
    "</DataItem></Geometry><Topology TopologyType=\"Tetrahedron\" "
    "NumberOfElements=\"2\" NodesPerElement=\"4\"><DataItem DataType=\"Int\" "
    "Dimensions=\"2 4\" Format=\"XML\" Precision=\"4\">\n0 1 2 3\n4 1 2 3\n"
    "</DataItem></Topology><Attribute Name=\"temp\" AttributeType=\"Scalar\" "
    "Center=\"Node\"><DataItem DataType=\"Float\" Dimensions=\"5\" Format=\"XML\" "
    "Precision=\"8\">\n1.5 2.5 3.5 4.5 5.5\n</DataItem></Attribute>"
    "<Attribute Name=\"gmsh:geometrical\" AttributeType=\"Scalar\" Center=\"Cell\">"
    "<DataItem DataType=\"Int\" Dimensions=\"2\" Format=\"XML\" Precision=\"4\">\n"
    "7 7\n</DataItem></Attribute>"
    "<Attribute Name=\"gmsh:physical\" AttributeType=\"Scalar\" Center=\"Cell\">"
    "<DataItem DataType=\"Int\" Dimensions=\"2\" Format=\"XML\" Precision=\"4\">\n"
    "1 2\n</DataItem></Attribute></Grid></Domain></Xdmf>\n";

/* DOLFIN's XDMFFile (XDMF 2 names: Type, NumberType), a DOCTYPE with an empty
 * internal subset, Topology first, a MeshFunction as a cell attribute. */
static const char dolfin2[] =
    "<?xml version=\"1.0\"?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    "<Xdmf Version=\"2.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n"
    "  <Domain>\n"
    "    <Grid Name=\"mesh\" GridType=\"Uniform\">\n"
    "      <Topology NumberOfElements=\"2\" Type=\"Tetrahedron\">\n"
    "        <DataItem Dimensions=\"2 4\" NumberType=\"UInt\" Format=\"XML\">0 1 2 3 4 1 "
    "2 3</DataItem>\n"
    "      </Topology>\n"
    "      <!-- coordinates -->\n"
    "      <Geometry Type=\"XYZ\">\n"
    "        <DataItem Dimensions=\"5 3\" Format=\"XML\">0 0 0 1 0 0 0 1 0 0 0 1 1 1 "
    "1</DataItem>\n"
    "      </Geometry>\n"
    "      <Attribute Name=\"f\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
    "        <DataItem Dimensions=\"2 1\" NumberType=\"UInt\" Format=\"XML\">1 "
    "2</DataItem>\n"
    "      </Attribute>\n"
    "    </Grid>\n"
    "  </Domain>\n"
    "</Xdmf>\n";

/* dolfinx: the mesh grid, then a MeshTags grid sharing its geometry that
 * lists the tets (corners in another order) with their tags. */
static const char dolfinx[] =
    "<?xml version=\"1.0\"?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    "<Xdmf Version=\"3.0\" xmlns:xi=\"https://www.w3.org/2001/XInclude\">\n"
    "  <Domain>\n"
    "    <Grid Name=\"mesh\" GridType=\"Uniform\">\n"
    "      <Topology TopologyType=\"Tetrahedron\" NumberOfElements=\"2\" "
    "NodesPerElement=\"4\">\n"
    "        <DataItem Dimensions=\"2 4\" NumberType=\"Int\" Format=\"XML\">\n"
    "          0 1 2 3\n          4 1 2 3\n        </DataItem>\n"
    "      </Topology>\n"
    "      <Geometry GeometryType=\"XYZ\">\n"
    "        <DataItem Dimensions=\"5 3\" Format=\"XML\">\n"
    "          0 0 0\n          1 0 0\n          0 1 0\n          0 0 1\n"
    "          1 1 1\n        </DataItem>\n"
    "      </Geometry>\n"
    "    </Grid>\n"
    "    <Grid Name=\"cells\" GridType=\"Uniform\">\n"
    "      <xi:include xpointer=\"xpointer(/Xdmf/Domain/Grid[@GridType='Uniform'][1]/"
    "Geometry)\" />\n"
    "      <Topology TopologyType=\"Tetrahedron\" NumberOfElements=\"2\" "
    "NodesPerElement=\"4\">\n"
    "        <DataItem Dimensions=\"2 4\" NumberType=\"Int\" Format=\"XML\">\n"
    "          3 2 1 4\n          0 3 2 1\n        </DataItem>\n"
    "      </Topology>\n"
    "      <Attribute Name=\"cells\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
    "        <DataItem Dimensions=\"2\" NumberType=\"Int\" Format=\"XML\">\n"
    "          20\n          10\n        </DataItem>\n"
    "      </Attribute>\n"
    "    </Grid>\n"
    "  </Domain>\n"
    "</Xdmf>\n";

static qdc_status rd(const char *s, mesh_t **m, qdc_error *err)
{
    meshio_options o = {.log = NULL, .log_ctx = NULL, .source = 1};

    return meshio_read_ex(s, strlen(s), MESHIO_AUTO, &o, m, err);
}

TEST(three_forms_read)
{
    const char *docs[3] = {meshio3, dolfin2, dolfinx};
    const int reg[3][2] = {{1, 2}, {1, 2}, {10, 20}};
    mesh_t *m;
    qdc_error err;

    for (int k = 0; k < 3; k++) {
        ASSERT_EQ_INT(meshio_sniff(docs[k], strlen(docs[k])), MESHIO_XDMF);
        ASSERT_OK(rd(docs[k], &m, &err));
        ASSERT_TRUE(is_two_tets(m, reg[k][0], reg[k][1]));
        ASSERT_TRUE(m->mid == NULL);
        ASSERT_EQ_INT(meshio_source_format(m), MESHIO_XDMF);
        ASSERT_TRUE(meshio_splices(m, MESHIO_XDMF, NULL));
        mesh_free(m);
    }
    ASSERT_EQ_INT(meshio_format_from_name("a.xdmf"), MESHIO_XDMF);
    ASSERT_EQ_INT(meshio_format_from_name("a.xmf"), MESHIO_XDMF);
    ASSERT_TRUE(meshio_has_writer(MESHIO_XDMF));
}

/* Vertex e moved: the numbers of the Geometry alone change, unmoved ones
 * keep their text; unmoved, the same bytes. */
TEST(spliced_geometry_only)
{
    const char *docs[2] = {meshio3, dolfin2};
    const char *from[2] = {"0.0 0.0 1.0\n1.0 1.0 1.0\n", "0 0 1 1 1 1<"};
    const char *to[2] = {"0.0 0.0 1.0\n0.75 1.0 -2.5\n", "0 0 1 0.75 1 -2.5<"};

    for (int k = 0; k < 2; k++) {
        mesh_t *m;
        qdc_error err;
        sink s = {0};
        char *want = replaced(docs[k], from[k], to[k]);
        ASSERT_TRUE(want != NULL);
        ASSERT_OK(rd(docs[k], &m, &err));
        ASSERT_OK(meshio_write(m, MESHIO_AUTO, sink_write, &s, &err));
        ASSERT_TRUE(s.n == strlen(docs[k]) && memcmp(s.b, docs[k], s.n) == 0);
        s.n = 0;
        m->xyz[12] = 0.75;
        m->xyz[14] = -2.5;
        ASSERT_OK(meshio_write(m, MESHIO_XDMF, sink_write, &s, &err));
        if (s.n != strlen(want) || memcmp(s.b, want, s.n) != 0)
            printf("  got:\n%.*s\n", (int)s.n, s.b);
        ASSERT_TRUE(s.n == strlen(want) && memcmp(s.b, want, s.n) == 0);
        mesh_free(m);
        free(s.b);
        free(want);
    }
}

/* Tetrahedron_10: corners, then the six mid-edge nodes in VTK's order
 * (mesh_p2_edges); written back with ten nodes a tet. */
TEST(second_order)
{
    static const char doc[] =
        "<Xdmf Version=\"3.0\"><Domain><Grid Name=\"p2\">"
        "<Geometry GeometryType=\"XYZ\"><DataItem Dimensions=\"10 3\" Format=\"XML\">"
        "0 0 0 1 0 0 0 1 0 0 0 1 0.5 0 0 0.5 0.5 0 0 0.5 0 0 0 0.5 0.5 0 0.5 0 0.5 0.5"
        "</DataItem></Geometry><Topology TopologyType=\"Tetrahedron_10\" "
        "NumberOfElements=\"1\"><DataItem Dimensions=\"1 10\" NumberType=\"Int\" "
        "Format=\"XML\">0 1 2 3 4 5 6 7 8 9</DataItem></Topology></Grid></Domain></Xdmf>";
    mesh_t *m, *b;
    qdc_error err;
    sink s = {0};

    ASSERT_OK(rd(doc, &m, &err));
    ASSERT_EQ_INT(m->nv, 10);
    ASSERT_EQ_INT(m->nt, 1);
    ASSERT_TRUE(m->mid != NULL);
    for (int e = 0; e < 6; e++) {
        const double *p = m->xyz + 3 * m->mid[e], *a = m->xyz + 3 * mesh_p2_edges[e][0],
                     *c = m->xyz + 3 * mesh_p2_edges[e][1];
        for (int k = 0; k < 3; k++)
            ASSERT_NEAR(p[k], 0.5 * (a[k] + c[k]), 0);
    }
    meshio_drop_source(m);
    ASSERT_OK(meshio_write(m, MESHIO_XDMF, sink_write, &s, &err));
    ASSERT_TRUE(strstr(s.b, "Tetrahedron_10") != NULL);
    ASSERT_OK(meshio_read(s.b, s.n, MESHIO_XDMF, &b, &err));
    ASSERT_TRUE(b->mid && memcmp(b->mid, m->mid, 6 * sizeof(int32_t)) == 0);
    mesh_free(b);
    mesh_free(m);
    free(s.b);
}

/* qdc's writer: read back the same mesh, regions included. */
TEST(writer_roundtrip)
{
    mesh_t *m = make_mesh(300, 900, 0), *b = NULL;

    ASSERT_TRUE(m != NULL);
    ASSERT_OK(roundtrip(m, MESHIO_XDMF, &b));
    ASSERT_TRUE(same_mesh(m, b, K_REGION));
    mesh_free(b);
    mesh_free(m);
}

TEST(refusals_say_where)
{
    static const struct {
        const char *from, *to;
        qdc_status st;
        int line;
        const char *text;
    } cases[] = {
        {"[]>", "[<!ENTITY x \"y\">]>", QDC_EPARSE, 2, "DOCTYPE with declarations"},
        {"<!-- coordinates -->", "<!ENTITY a \"b\">", QDC_EPARSE, 9, "no entity"},
        {"<!-- coordinates -->", "<![CDATA[x]]>", QDC_EPARSE, 9, "CDATA"},
        {"0 0 0 1 0 0", "0 0 nan 1 0 0", QDC_EPARSE, 11, "not finite"},
        {"0 0 0 1 0 0", "0 0 1e999 1 0 0", QDC_EPARSE, 11, "not finite"},
        {"3 4 1 2", "3 5 1 2", QDC_EPARSE, 7, "vertex 5 out of range"},
        {"3 4 1 2", "3 4 -1 2", QDC_EPARSE, 7, "out of range"},
        {"Dimensions=\"5 3\" Format=\"XML\"", "Dimensions=\"5 3\" Format=\"HDF\"",
         QDC_EFORMAT, 11, "HDF5"},
        {"Dimensions=\"5 3\" Format=\"XML\"", "Dimensions=\"5 3\" Format=\"Binary\"",
         QDC_EFORMAT, 11, "Format Binary"},
        {"Dimensions=\"5 3\" Format", "Dimensions=\"6 3\" Format", QDC_EPARSE, 11,
         "15 values, expected 18"},
        {"Dimensions=\"5 3\" Format", "Dimensions=\"99999999 3\" Format", QDC_EPARSE, 11,
         "does not fit"},
        {"Dimensions=\"5 3\" Format", "Dimensions=\"5 2\" Format", QDC_EFORMAT, 11,
         "\"N 3\""},
        {"1 1 1</DataItem>", "1 1 1 7</DataItem>", QDC_EPARSE, 11, "more than its 15"},
        {"Type=\"Tetrahedron\"", "Type=\"Mixed\"", QDC_EFORMAT, 6, "Mixed"},
        {"Type=\"Tetrahedron\"", "Type=\"Hexahedron\"", QDC_EFORMAT, 6, "Hexahedron"},
        {"Geometry Type=\"XYZ\"", "Geometry Type=\"X_Y_Z\"", QDC_EFORMAT, 10, "X_Y_Z"},
        {"Name=\"mesh\"", "Name=\"&amp;\"", QDC_OK, 0, ""},
        {"Format=\"XML\">1 2", "Format=\"&XML;\">1 2", QDC_EPARSE, 14, "reference"},
        {"Format=\"XML\">1 2", "Format=\"XML\">1 2 3", QDC_EPARSE, 14, "more than"},
        {"Format=\"XML\">1 2", "Format=\"XML\">1 2.5", QDC_EPARSE, 14, "integer"},
        {"</Grid>", "</Grid><Grid>", QDC_EPARSE, 17, "expected </Grid>"},
        {"</Xdmf>", "", QDC_EPARSE, 19, "ends inside"},
        {"</Grid>", "</Grid></Grid>", QDC_EPARSE, 16, "expected </Domain>"},
        {"</Xdmf>", "</Xdmf><x/>", QDC_EPARSE, 18, "after </Xdmf>"},
        {"<Xdmf", "<Xdmx", QDC_EPARSE, 3, "not an XDMF"},
    };

    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        char *d = replaced(dolfin2, cases[k].from, cases[k].to);
        mesh_t *m = NULL;
        qdc_error err;
        qdc_status st;
        ASSERT_TRUE(d != NULL);
        st = meshio_read(d, strlen(d), MESHIO_XDMF, &m, &err);
        if (st != cases[k].st || (st != QDC_OK && (!strstr(err.msg, cases[k].text) ||
                                                   err.line != cases[k].line)))
            printf("  case %zu: status %d, line %d: %s\n", k, (int)st, (int)err.line,
                   st == QDC_OK ? "" : err.msg);
        ASSERT_EQ_INT(st, cases[k].st);
        if (st != QDC_OK) {
            ASSERT_TRUE(strstr(err.msg, cases[k].text) != NULL);
            ASSERT_EQ_INT(err.line, cases[k].line);
            ASSERT_TRUE(m == NULL);
        }
        mesh_free(m);
        free(d);
    }
}

/* Every prefix of a document is refused or read, never more. */
TEST(truncated)
{
    for (size_t n = 0; n < sizeof dolfin2 - 1; n++) {
        mesh_t *m = NULL;
        qdc_error err;
        qdc_status st = meshio_read(dolfin2, n, MESHIO_XDMF, &m, &err);
        ASSERT_TRUE(st != QDC_OK || n + 1 >= sizeof dolfin2 - 1);
        ASSERT_TRUE((st == QDC_OK) == (m != NULL));
        mesh_free(m);
    }
}

/* dolfinx with a facet tags grid before the cell tags grid: the triangles
 * tris (two lines of corners) with the values 7 and 8 (a new string, free). */
static char *with_facets(const char *tris)
{
    char facets[1200];

    snprintf(
        facets, sizeof facets,
        "    <Grid Name=\"facets\" GridType=\"Uniform\">\n"
        "      <xi:include xpointer=\"xpointer(/Xdmf/Domain/"
        "Grid[@GridType='Uniform'][1]/Geometry)\" />\n"
        "      <Topology TopologyType=\"Triangle\" NumberOfElements=\"2\" "
        "NodesPerElement=\"3\">\n"
        "        <DataItem Dimensions=\"2 3\" NumberType=\"Int\" Format=\"XML\">\n"
        "%s        </DataItem>\n"
        "      </Topology>\n"
        "      <Attribute Name=\"facets\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
        "        <DataItem Dimensions=\"2\" NumberType=\"Int\" Format=\"XML\">\n"
        "          7\n          8\n        </DataItem>\n"
        "      </Attribute>\n"
        "    </Grid>\n"
        "    <Grid Name=\"cells\"",
        tris);
    return replaced(dolfinx, "    <Grid Name=\"cells\"", facets);
}

/* 1 when m, unmoved, is written back as doc's very bytes. */
static int written_back_same(const mesh_t *m, const char *doc)
{
    sink s = {0};
    qdc_error err;
    int same = meshio_write(m, MESHIO_AUTO, sink_write, &s, &err) == QDC_OK &&
               s.n == strlen(doc) && memcmp(s.b, doc, s.n) == 0;

    free(s.b);
    return same;
}

/* dolfinx's facet tags grid (triangles, before the cell tags grid here):
 * the boundary triangles, its values their refs; the cell tags still the
 * regions; written back unmoved, the same bytes. */
TEST(facet_tags_as_boundary_triangles)
{
    static const int32_t tris[6] = {0, 2, 1, 1, 2, 4};
    char *doc = with_facets("          0 2 1\n          1 2 4\n");
    mesh_t *m;
    qdc_error err;

    ASSERT_TRUE(doc != NULL);
    ASSERT_OK(rd(doc, &m, &err));
    ASSERT_TRUE(is_two_tets(m, 10, 20));
    ASSERT_EQ_INT(m->ntri, 2);
    ASSERT_TRUE(m->tri_ref != NULL);
    ASSERT_TRUE(memcmp(m->tris, tris, sizeof tris) == 0);
    ASSERT_EQ_INT(m->tri_ref[0], 7);
    ASSERT_EQ_INT(m->tri_ref[1], 8);
    ASSERT_TRUE(written_back_same(m, doc));
    mesh_free(m);
    free(doc);
}

/* Facet tags are the mesh's own faces: one between the two tets (the
 * interface of regions 10 and 20) is kept with its value, unchanged, as Medit's
 * and Gmsh's triangles are; a triangle that is no face of a tet is refused,
 * named (it was taken silently). */
TEST(facet_tags_off_the_boundary)
{
    char *doc = with_facets("          0 2 1\n          3 1 2\n");
    mesh_t *m = NULL;
    qdc_error err;

    ASSERT_TRUE(doc != NULL);
    ASSERT_OK(rd(doc, &m, &err));
    ASSERT_TRUE(is_two_tets(m, 10, 20));
    ASSERT_EQ_INT(m->ntri, 2);
    ASSERT_EQ_INT(m->tris[3], 3);
    ASSERT_EQ_INT(m->tri_ref[1], 8);
    ASSERT_TRUE(written_back_same(m, doc));
    mesh_free(m);
    free(doc);
    /* 0 1 4: no tet has these corners */
    doc = with_facets("          0 2 1\n          0 1 4\n");
    ASSERT_TRUE(doc != NULL);
    m = NULL;
    ASSERT_EQ_INT(rd(doc, &m, &err), QDC_EPARSE);
    ASSERT_TRUE(m == NULL);
    ASSERT_TRUE(strstr(err.msg, "facet tag triangle 1 (vertices 0 1 4) is no face of a "
                                "tetrahedron") != NULL);
    ASSERT_EQ_INT(err.index, 1);
    free(doc);
}

TEST_MAIN("xdmf", T(three_forms_read), T(spliced_geometry_only), T(second_order),
          T(writer_roundtrip), T(refusals_say_where), T(truncated),
          T(facet_tags_as_boundary_triangles), T(facet_tags_off_the_boundary))
