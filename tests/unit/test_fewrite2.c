/* test_fewrite2.c - qdc's own writers of Gmsh MSH 1, Nastran bulk data and
 * I-DEAS universal files, on hand-made meshes with known values: written,
 * read back, the same coordinates bit for bit, the same tets, regions,
 * triangles and refs; the text each writes; a mesh without regions or
 * triangles; negative, zero and extreme tags (held as they are, an I10 field
 * too narrow for one widened); second-order tets (Nastran and I-DEAS write
 * them, MSH 1 refuses); an empty mesh. */
#include "testio.h"
#include "testlib.h"

static const meshio_format fmts[3] = {MESHIO_MSH1, MESHIO_BDF, MESHIO_UNV};

/* Doubles that stress exact printing: signed zero, a subnormal, the
 * extremes, thirds, integers, a power of ten with no '.' in %.17g. */
static const double xyz[15] = {0.0,
                               -0.0,
                               1.0 / 3.0,
                               1.0,
                               -2.0,
                               1e21,
                               4.9406564584124654e-324,
                               -1.7976931348623157e308,
                               0.1,
                               1e-5,
                               123456789012345678.0,
                               2.2250738585072014e-308,
                               -1.0 / 3.0,
                               5.0,
                               9007199254740993.0};

TEST(writers_declared)
{
    meshio_format_info fi;

    for (int k = 0; k < 3; k++) {
        ASSERT_TRUE(meshio_has_writer(fmts[k]));
        ASSERT_TRUE(meshio_format_info_of(fmts[k], &fi));
        ASSERT_TRUE(fi.writes && fi.splices);
        ASSERT_TRUE(strstr(fi.about, "spliced") == NULL);
    }
}

TEST(roundtrip_exact)
{
    mesh_t *m = five_mesh(xyz, 1, 3, 7, 2, 11, 12), *b;

    ASSERT_TRUE(m);
    for (int k = 0; k < 3; k++) {
        ASSERT_OK(roundtrip(m, fmts[k], &b));
        ASSERT_TRUE(same_mesh(m, b, K_REGION | K_TRIS));
        ASSERT_EQ_INT(b->region[1], 7);
        ASSERT_EQ_INT(b->tri_ref[1], 12);
        ASSERT_TRUE(signbit(b->xyz[1]) && b->xyz[1] == 0); /* -0 stays -0 */
        ASSERT_TRUE(b->mid == NULL);
        mesh_free(b);
    }
    mesh_free(m);
}

/* The text: nodes numbered from 1, tets then triangles, tags where each
 * reader takes them. */
TEST(written_text)
{
    mesh_t *m = five_mesh(xyz, 1, 3, 7, 2, 11, 12);
    sink s = {0};
    qdc_error err;

    ASSERT_TRUE(m);
    ASSERT_OK(write_to(m, MESHIO_MSH1, &s, &err));
    ASSERT_TRUE(strncmp(s.b, "$NOD\n5\n1 0 -0 0.33333333333333331\n", 33) == 0);
    ASSERT_TRUE(strstr(s.b, "\n$ELM\n4\n1 4 3 1 4 1 2 3 4\n2 4 7 2 4 5 2 3 4\n"
                            "3 2 11 1 3 2 3 4\n4 2 12 2 3 1 2 3\n$ENDELM\n"));
    ASSERT_OK(write_to(m, MESHIO_BDF, &s, &err));
    ASSERT_TRUE(strstr(s.b, "\nBEGIN BULK\nGRID,1,,0.,-0.,0.33333333333333331\n"
                            "GRID,2,,1.,-2.,1.e+21\n"));
    ASSERT_TRUE(strstr(s.b, "\nGRID,4,,1.0000000000000001e-05,1.2345678901234568e+17,"));
    ASSERT_TRUE(strstr(s.b, "\nCTETRA,1,3,1,2,3,4\nCTETRA,2,7,5,2,3,4\n"
                            "CTRIA3,3,11,2,3,4\nCTRIA3,4,12,1,2,3\nENDDATA\n"));
    ASSERT_OK(write_to(m, MESHIO_UNV, &s, &err));
    ASSERT_TRUE(strncmp(s.b,
                        "    -1\n  2411\n         1         1         1        11\n"
                        "   0.0000000000000000D+00  -0.0000000000000000D+00"
                        "   3.3333333333333331D-01\n",
                        128) == 0);
    ASSERT_TRUE(strstr(s.b,
                       "    -1\n    -1\n  2412\n"
                       "         1       111         3         3         7         4\n"
                       "         1         2         3         4\n"));
    ASSERT_TRUE(strstr(s.b,
                       "         4        91        12        12         7         3\n"
                       "         1         2         3\n    -1\n"));
    free(s.b);
    mesh_free(m);
}

/* No regions, no triangles: read back as none (blank PIDs, physical tags 0). */
TEST(no_regions_no_triangles)
{
    mesh_t *m = five_mesh(xyz, 0, 0, 0, 0, 0, 0), *b;
    sink s = {0};
    qdc_error err;

    ASSERT_TRUE(m);
    for (int k = 0; k < 3; k++) {
        ASSERT_OK(roundtrip(m, fmts[k], &b));
        ASSERT_TRUE(same_mesh(m, b, K_REGION | K_TRIS));
        ASSERT_TRUE(b->region == NULL && b->ntri == 0 && b->tri_ref == NULL);
        mesh_free(b);
    }
    ASSERT_OK(write_to(m, MESHIO_BDF, &s, &err));
    ASSERT_TRUE(strstr(s.b, "\nCTETRA,1,,1,2,3,4\nCTETRA,2,,5,2,3,4\nENDDATA\n"));
    ASSERT_OK(write_to(m, MESHIO_MSH1, &s, &err));
    ASSERT_TRUE(strstr(s.b, "\n1 4 0 1 4 1 2 3 4\n2 4 0 1 4 5 2 3 4\n$ENDELM\n"));
    /* regions all 0 are no regions, as in every Gmsh file */
    mesh_free(m);
    m = five_mesh(xyz, 1, 0, 0, 0, 0, 0);
    ASSERT_TRUE(m);
    for (int k = 0; k < 3; k++) {
        ASSERT_OK(roundtrip(m, fmts[k], &b));
        ASSERT_TRUE(b->region == NULL);
        mesh_free(b);
    }
    free(s.b);
    mesh_free(m);
}

/* Negative, zero and extreme tags are held as they are; in I-DEAS a value
 * that fills its 10 columns is written after a blank. */
TEST(negative_and_zero_tags)
{
    mesh_t *m = five_mesh(xyz, 1, INT32_MIN, 0, 2, -1, INT32_MAX), *b;
    sink s = {0};
    qdc_error err;

    ASSERT_TRUE(m);
    for (int k = 0; k < 3; k++) {
        ASSERT_OK(roundtrip(m, fmts[k], &b));
        ASSERT_TRUE(same_mesh(m, b, K_REGION | K_TRIS));
        ASSERT_EQ_INT(b->region[0], INT32_MIN);
        ASSERT_EQ_INT(b->tri_ref[0], -1);
        ASSERT_EQ_INT(b->tri_ref[1], INT32_MAX);
        mesh_free(b);
    }
    ASSERT_OK(write_to(m, MESHIO_UNV, &s, &err));
    ASSERT_TRUE(strstr(s.b, "\n         1       111 -2147483648 -2147483648         7"
                            "         4\n"));
    ASSERT_TRUE(strstr(s.b, "\n         4        91 2147483647 2147483647         7"
                            "         3\n"));
    ASSERT_TRUE(strstr(s.b, "\n         3        91        -1        -1         7"));
    ASSERT_OK(write_to(m, MESHIO_BDF, &s, &err));
    ASSERT_TRUE(strstr(s.b, "\nCTETRA,1,-2147483648,1,2,3,4\nCTETRA,2,0,5,2,3,4\n"));
    free(s.b);
    mesh_free(m);
}

/* Ten-node tets: Nastran (G5-G10 continued on a '+' line, after a '+'
 * field that Gmsh needs) and I-DEAS (FE
 * 118) keep the mid-edge nodes; MSH 1 (type 11 not read) refuses them. */
TEST(second_order)
{
    mesh_t *m = mesh_new(10, 1, MESH_WITH_REGION), *b;
    sink s = {0};
    qdc_error err;

    ASSERT_TRUE(m && mesh_set_mid(m) == QDC_OK);
    for (int i = 0; i < 30; i++)
        m->xyz[i] = xyz[i % 15] + i;
    for (int k = 0; k < 4; k++)
        m->tets[k] = 9 - k; /* 9 8 7 6 */
    for (int e = 0; e < 6; e++)
        m->mid[e] = e; /* edges 01 12 02 03 13 23: 0..5 */
    m->region[0] = 4;
    for (int k = 1; k < 3; k++) {
        ASSERT_OK(roundtrip(m, fmts[k], &b));
        ASSERT_TRUE(same_mesh(m, b, K_REGION));
        ASSERT_TRUE(b->mid && memcmp(b->mid, m->mid, 6 * sizeof(int32_t)) == 0);
        mesh_free(b);
    }
    ASSERT_OK(write_to(m, MESHIO_BDF, &s, &err));
    ASSERT_TRUE(strstr(s.b, "\nCTETRA,1,4,10,9,8,7,1,2,+\n+,3,4,5,6\nENDDATA\n"));
    ASSERT_OK(
        write_to(m, MESHIO_UNV, &s, &err)); /* c0 m01 c1 m12 c2 m02 m03 m13 m23 c3 */
    ASSERT_TRUE(strstr(s.b,
                       "\n         1       118         4         4         7        10\n"
                       "        10         1         9         2         8         3"
                       "         4         5\n         6         7\n    -1\n"));
    ASSERT_EQ_INT(write_to(m, MESHIO_MSH1, &s, &err), QDC_EINVAL);
    ASSERT_TRUE(strstr(err.msg, "second-order"));
    free(s.b);
    mesh_free(m);
}

/* An empty mesh reads back empty (Nastran: an empty bulk section), while a
 * file whose GRIDs come after ENDDATA is still refused. */
TEST(empty_mesh)
{
    static const char after[] = "BEGIN BULK\nENDDATA\nGRID,1,,0.,0.,0.\n";
    mesh_t *m = mesh_new(0, 0, 0), *b;
    sink s = {0};
    qdc_error err;

    ASSERT_TRUE(m);
    for (int k = 0; k < 3; k++) {
        ASSERT_OK(roundtrip(m, fmts[k], &b));
        ASSERT_TRUE(b->nv == 0 && b->nt == 0 && b->ntri == 0);
        mesh_free(b);
    }
    ASSERT_OK(write_to(m, MESHIO_BDF, &s, &err));
    ASSERT_TRUE(
        strcmp(s.b, "$ Nastran bulk data written by qdc\nBEGIN BULK\nENDDATA\n") == 0);
    ASSERT_EQ_INT(meshio_read(after, strlen(after), MESHIO_BDF, &b, &err), QDC_EPARSE);
    ASSERT_TRUE(strstr(err.msg, "no GRID card"));
    free(s.b);
    mesh_free(m);
}

/* A mesh read from a file and given new tets is written by the writer, not
 * spliced: the file's other cards are gone, the new tets there. */
TEST(new_tets_not_spliced)
{
    static const char doc[] = "BEGIN BULK\nGRID,10,,0.,0.,0.\nGRID,20,,1.,0.,0.\n"
                              "GRID,30,,0.,1.,0.\nGRID,40,,0.,0.,1.\nGRID,50,,1.,1.,1.\n"
                              "CTETRA,1,1,10,20,30,40\nPSOLID,1,1\nENDDATA\n";
    meshio_options o = {.log = NULL, .log_ctx = NULL, .source = 1};
    mesh_t *m;
    sink s = {0};
    qdc_error err;

    ASSERT_OK(meshio_read_ex(doc, strlen(doc), MESHIO_BDF, &o, &m, &err));
    ASSERT_TRUE(meshio_splices(m, MESHIO_BDF, NULL));
    m->tets[0] = 4; /* vertex 50 for 10 */
    ASSERT_TRUE(!meshio_splices(m, MESHIO_BDF, NULL));
    ASSERT_OK(write_to(m, MESHIO_BDF, &s, &err));
    ASSERT_TRUE(strstr(s.b, "PSOLID") == NULL);
    ASSERT_TRUE(strstr(s.b, "\nGRID,5,,1.,1.,1.\nCTETRA,1,1,5,2,3,4\nENDDATA\n"));
    free(s.b);
    mesh_free(m);
}

TEST_MAIN("fewrite2", T(writers_declared), T(roundtrip_exact), T(written_text),
          T(no_regions_no_triangles), T(negative_and_zero_tags), T(second_order),
          T(empty_mesh), T(new_tets_not_spliced))
