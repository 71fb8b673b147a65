/* test_bdf_unv.c - the Nastran bulk data and I-DEAS universal readers and
 * their spliced writes, on hand-made two-tet files with known values: the
 * three field formats read as one mesh, Nastran's short reals, tags as
 * regions, refusals with their line, fixed-width fields written back in
 * their width. */
#include "testio.h"
#include "testlib.h"

/* Five points a = 0, b = x, c = y, d = z, e = (1,1,1), numbered 10..50; tets
 * a b c d (PID 1) and e b c d (PID 2), triangle b c d (PID 7), a PSOLID and
 * a beam kept, in each field format. */
static const char small[] = "$ two tets, small field\n"
                            "SOL 101\nCEND\nBEGIN BULK\n"
                            "GRID    10      0       0.      0.      0.\n"
                            "GRID    20              1.      0.      0.\n"
                            "GRID    30      0       0.      1.      0.      0\n"
                            "GRID    40      0       0.      0.      1.\n"
                            "GRID    50      0       1.      1.      1.\n"
                            "CTETRA  1       1       10      20      30      40\n"
                            "CTETRA  2       2       50      20      30      40\n"
                            "CTRIA3  3       7       20      30      40\n"
                            "CBAR    4       9       10      20      0.      0.      1.\n"
                            "PSOLID  1       1\n"
                            "ENDDATA\n";
static const char freef[] = "$ free field\nBEGIN BULK\n"
                            "GRID,10,,0.,0.,0.\nGRID, 20, , 1., 0., 0.\n"
                            "GRID,30,0,0.,1.,0.\nGRID,40,,0.,0.,1.\nGRID,50,,1.,1.,1.\n"
                            "CTETRA,1,1,10,20,30,40\nCTETRA,2,2,50,20,30,40\n"
                            "CTRIA3,3,7,20,30,40\nENDDATA\n";
static const char large[] =
    "$ large field\nBEGIN BULK\n"
    "GRID*   10              0               0.              0.              *G10\n"
    "*G10    0.\n"
    "GRID*   20                              1.              0.\n*       0.\n"
    "GRID*   30              0               0.              1.\n*       0.\n"
    "GRID*   40              0               0.              0.\n*       1.\n"
    "GRID*   50              0               1.              1.\n*       1.\n"
    "CTETRA* 1               1               10              20              *\n"
    "*       30              40\n"
    "CTETRA  2       2       50      20      30      40\n"
    "CTRIA3  3       7       20      30      40\n";

static qdc_status rd(const char *s, meshio_format f, mesh_t **m, qdc_error *err)
{
    meshio_options o = {.log = NULL, .log_ctx = NULL, .source = 1};

    return meshio_read_ex(s, strlen(s), f, &o, m, err);
}

static void check_mesh(const mesh_t *m)
{
    ASSERT_TRUE(is_two_tets(m, 1, 2));
    ASSERT_EQ_INT(m->ntri, 1);
    ASSERT_EQ_INT(m->tris[0], 1);
    ASSERT_EQ_INT(m->tris[2], 3);
    ASSERT_EQ_INT(m->tri_ref[0], 7);
}

/* doc read with its source, vertex v's coordinate a set to x and written
 * back: the output is doc with `from` replaced by `to`. */
static void moved(const char *doc, meshio_format f, int v, int a, double x,
                  const char *from, const char *to)
{
    mesh_t *m;
    qdc_error err;
    sink s = {0};
    char *want = replaced(doc, from, to);

    ASSERT_TRUE(want != NULL);
    ASSERT_OK(rd(doc, f, &m, &err));
    /* unmoved: the same bytes */
    ASSERT_OK(meshio_write(m, MESHIO_AUTO, sink_write, &s, &err));
    ASSERT_TRUE(s.n == strlen(doc) && memcmp(s.b, doc, s.n) == 0);
    s.n = 0;
    m->xyz[3 * v + a] = x;
    ASSERT_OK(meshio_write(m, MESHIO_AUTO, sink_write, &s, &err));
    if (s.n != strlen(want) || memcmp(s.b, want, s.n) != 0)
        printf("  got:\n%.*s\n  want:\n%s\n", (int)s.n, s.b, want);
    ASSERT_TRUE(s.n == strlen(want) && memcmp(s.b, want, s.n) == 0);
    mesh_free(m);
    free(s.b);
    free(want);
}

/* doc with `from` replaced by `to` is refused with status, on line ln,
 * with text in the message. */
static void refused(const char *doc, meshio_format f, const char *from, const char *to,
                    qdc_status status, int64_t ln, const char *text)
{
    char *d = replaced(doc, from, to);
    mesh_t *m = NULL;
    qdc_error err;

    ASSERT_TRUE(d != NULL);
    ASSERT_EQ_INT(meshio_read(d, strlen(d), f, &m, &err), status);
    if (!strstr(err.msg, text) || err.line != ln)
        printf("  got line %d: %s\n", (int)err.line, err.msg);
    ASSERT_TRUE(strstr(err.msg, text) != NULL);
    ASSERT_EQ_INT(err.line, ln);
    ASSERT_TRUE(m == NULL);
    free(d);
}

TEST(bdf_three_field_formats)
{
    const char *docs[3] = {small, freef, large};
    mesh_t *m;
    qdc_error err;

    for (int k = 0; k < 3; k++) {
        ASSERT_EQ_INT(meshio_sniff(docs[k], strlen(docs[k])), MESHIO_BDF);
        ASSERT_OK(rd(docs[k], MESHIO_AUTO, &m, &err));
        check_mesh(m);
        ASSERT_EQ_INT(meshio_source_format(m), MESHIO_BDF);
        ASSERT_TRUE(meshio_splices(m, MESHIO_BDF, NULL));
        mesh_free(m);
    }
    ASSERT_EQ_INT(meshio_format_from_name("a.nas"), MESHIO_BDF);
    ASSERT_EQ_INT(meshio_format_from_name("a.bdf"), MESHIO_BDF);
    ASSERT_EQ_INT(meshio_format_from_name("nastran"), MESHIO_BDF);
    ASSERT_TRUE(meshio_has_writer(MESHIO_BDF)); /* test_fewrite2 */
}

/* 1.-3 = 1e-3, -.5+2 = -50, 2.5D1 = 25, .125E+1 = 1.25, 7 (an integer where
 * a real belongs, read as 7), blank = 0 */
TEST(bdf_short_reals)
{
    static const char doc[] =
        "GRID,1,,1.-3,-.5+2,2.5D1\nGRID    2               .125E+1 7\n"
        "GRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\n"
        "CTETRA,1,,1,2,3,4\n";
    mesh_t *m;
    qdc_error err;

    ASSERT_OK(rd(doc, MESHIO_BDF, &m, &err));
    ASSERT_TRUE(m->xyz[0] == 1e-3 && m->xyz[1] == -50 && m->xyz[2] == 25);
    ASSERT_TRUE(m->xyz[3] == 1.25 && m->xyz[4] == 7 && m->xyz[5] == 0);
    ASSERT_TRUE(m->region == NULL); /* PID blank in every CTETRA: no regions */
    /* the z of GRID 2 is left out of its line: read as 0, not spliced */
    ASSERT_TRUE(!meshio_splices(m, MESHIO_BDF, NULL));
    mesh_free(m);
}

/* Moved coordinates go into their own field: right-aligned in its 8 or 16
 * characters, in place of the token in a free field; the rest unchanged. */
TEST(bdf_splice_widths)
{
    moved(small, MESHIO_BDF, 3, 2, 0.5, "GRID    40      0       0.      0.      1.\n",
          "GRID    40      0       0.      0.           0.5\n");
    /* 8 characters hold 7 digits of 1/3, Nastran's exponent form what would not fit */
    moved(small, MESHIO_BDF, 3, 2, 1.0 / 3, "0.      0.      1.\n",
          "0.      0.      .3333333\n");
    moved(small, MESHIO_BDF, 3, 0, -1.25e-7, "GRID    40      0       0.      ",
          "GRID    40      0       -1.25E-7");
    moved(small, MESHIO_BDF, 3, 0, 1.0 / 3e-7, "GRID    40      0       0.      ",
          "GRID    40      0       3333333.");
    moved(small, MESHIO_BDF, 3, 0, -1.0 / 3e-9, "GRID    40      0       0.      ",
          "GRID    40      0       -3.333+8");
    moved(freef, MESHIO_BDF, 3, 2, 0.5, "GRID,40,,0.,0.,1.", "GRID,40,,0.,0.,0.5");
    moved(freef, MESHIO_BDF, 1, 0, 0.1, "GRID, 20, , 1.,", "GRID, 20, , 0.1,");
    moved(large, MESHIO_BDF, 3, 2, 1.0 / 3, "*       1.\nGRID*   50",
          "*       .333333333333333\nGRID*   50");
    moved(large, MESHIO_BDF, 0, 2, -0.5, "*G10    0.", "*G10                -0.5");
}

TEST(bdf_refusals)
{
    refused(small, MESHIO_BDF, "GRID    30      0 ", "GRID    30      3 ", QDC_EFORMAT, 7,
            "coordinate system 3 (CP) is not supported");
    refused(small, MESHIO_BDF, "50      20      30      40\n",
            "50      20      30      41\n", QDC_EPARSE, 11, "CTETRA: unknown GRID 41");
    refused(small, MESHIO_BDF, "1.      1.      1.", "1.      nan     1.", QDC_EPARSE, 9,
            "not finite");
    refused(small, MESHIO_BDF, "1.      1.      1.", "1.      1.+999  1.", QDC_EPARSE, 9,
            "not finite");
    refused(small, MESHIO_BDF, "1.      1.      1.", "1.      1.x     1.", QDC_EPARSE, 9,
            "expected a number, got '1.x'");
    /* two exponents, and a free field long enough that each would have
     * overrun the buffer the reader rewrites the number in */
    refused(freef, MESHIO_BDF, "GRID,40,,0.,0.,1.", "GRID,40,,0.,0.,1.-3-4", QDC_EPARSE,
            6, "expected a number, got '1.-3-4'");
    refused(freef, MESHIO_BDF, "GRID,40,,0.,0.,1.",
            "GRID,40,,0.,0.,1.-1-2-3-4-5-6-7-8-9-1-2-3-4-5-6-7-8-9-1-2-3-4-5-6-7-8",
            QDC_EPARSE, 6, "expected a number");
    refused(small, MESHIO_BDF, "GRID    30", "GRID    10", QDC_EPARSE, 7,
            "GRID 10 appears twice");
    refused(small, MESHIO_BDF, "30      40\nCTRIA3", "30      40      60\nCTRIA3",
            QDC_EFORMAT, 11, "CTETRA 2: the mid-side nodes G5-G10 must be all given");
    refused(large, MESHIO_BDF, "*       30              40\n",
            "*       30              40              60\n", QDC_EFORMAT, 14,
            "CTETRA 1: the mid-side nodes G5-G10 must be all given");
    refused(small, MESHIO_BDF, "30      40\nCTRIA3",
            "30      40      1       2       +\n+       3       4       5       6       "
            "7\nCTRIA3",
            QDC_EFORMAT, 12, "CTETRA 2: more than 10 nodes");
    refused(freef, MESHIO_BDF, "CTETRA,2,2,50", "CTETRA,2,2,-5", QDC_EPARSE, 9,
            "CTETRA: node '-5' out of range");
    refused(small, MESHIO_BDF, "GRID    50      0 ", "GRID    50\t     0 ", QDC_EFORMAT,
            9, "a tab in a fixed-field card");
    refused(freef, MESHIO_BDF, "GRID,10", "GRIX,10", QDC_EPARSE, 8,
            "CTETRA: unknown GRID 10");
    refused(small, MESHIO_BDF, "BEGIN BULK", "BEGIN BULK\nENDDATA", QDC_EPARSE, -1,
            "no GRID card");
}

/* I-DEAS: the same two tets, a triangle and a beam (with its orientation
 * record), units and a group kept. */
static const char unv[] =
    "    -1\n   164\n         1  SI - mks (Kg m s)\n"
    "    1.0000000000000000D+00    1.0000000000000000D+00    1.0000000000000000D+00\n"
    "    2.7314999999999998D+02\n    -1\n"
    "    -1\n  2411\n"
    "        10         1         1        11\n"
    "   0.0000000000000000D+00   0.0000000000000000D+00   0.0000000000000000D+00\n"
    "        20         1         1        11\n"
    "   1.0000000000000000D+00   0.0000000000000000D+00   0.0000000000000000D+00\n"
    "        30         1         1        11\n"
    "   0.0000000000000000D+00   1.0000000000000000D+00   0.0000000000000000D+00\n"
    "        40         1         1        11\n"
    "   0.0000000000000000D+00   0.0000000000000000D+00   1.0000000000000000D+00\n"
    "        50         1         1        11\n"
    "   1.0000000000000000D+00   1.0000000000000000D+00   1.0000000000000000D+00\n"
    "    -1\n    -1\n  2412\n"
    "         4        21         9         0         7         2\n"
    "         0         0         0\n"
    "        10        20\n"
    "         1       111         3         1         7         4\n"
    "        10        20        30        40\n"
    "         2       111         3         2         7         4\n"
    "        50        20        30        40\n"
    "         3        91         5         7         7         3\n"
    "        20        30        40\n"
    "    -1\n    -1\n  2477\n"
    "         1         0         0         0         0         0         0         2\n"
    "solid\n"
    "         8         1         0         0         8         2         0         0\n"
    "    -1\n";

TEST(unv_read_and_splice)
{
    mesh_t *m;
    qdc_error err;

    ASSERT_EQ_INT(meshio_sniff(unv, strlen(unv)), MESHIO_UNV);
    ASSERT_EQ_INT(meshio_format_from_name("a.unv"), MESHIO_UNV);
    ASSERT_OK(rd(unv, MESHIO_AUTO, &m, &err));
    check_mesh(m); /* material 1, 2 as regions (physical 3 for both) */
    ASSERT_TRUE(meshio_splices(m, MESHIO_UNV, NULL));
    mesh_free(m);
    moved(unv, MESHIO_UNV, 3, 2, 0.5,
          "0.0000000000000000D+00   1.0000000000000000D+00\n        50",
          "0.0000000000000000D+00   5.0000000000000000D-01\n        50");
    moved(unv, MESHIO_UNV, 4, 0, -1.0 / 3,
          "   1.0000000000000000D+00   1.0000000000000000D+00   1.0000000000000000D+00\n"
          "    -1\n    -1\n  2412",
          "  -3.3333333333333331D-01   1.0000000000000000D+00   1.0000000000000000D+00\n"
          "    -1\n    -1\n  2412");
}

/* One 10-node tet: corners 1-4 at 0, x, y, z, mid-edge nodes 5-10 at their
 * edges' midpoints, listed in each format's order (Nastran: 12 23 31 14 24
 * 34 after the corners; I-DEAS FE 118: around the base, then to the apex),
 * a 6-node triangle on its face 1 2 3. */
static const char bdf10[] =
    "$ one 10-node tet, large field\nBEGIN BULK\n"
    "GRID*   1                               0.              0.\n*       0.\n"
    "GRID*   2                               1.              0.\n*       0.\n"
    "GRID*   3                               0.              1.\n*       0.\n"
    "GRID*   4                               0.              0.\n*       1.\n"
    "GRID,5,,.5,0.,0.\nGRID,6,,.5,.5,0.\nGRID,7,,0.,.5,0.\n"
    "GRID,8,,0.,0.,.5\nGRID,9,,.5,0.,.5\nGRID,10,,0.,.5,.5\n"
    "CTETRA  1       3       1       2       3       4       5       6\n"
    "        7       8       9       10\n"
    "CTRIA6  2       4       1       3       2       7       6       5\n"
    "ENDDATA\n";
static const char unv10[] =
    "    -1\n  2411\n"
    "         1         1         1        11\n"
    "   0.0000000000000000D+00   0.0000000000000000D+00   0.0000000000000000D+00\n"
    "         2         1         1        11\n"
    "   1.0000000000000000D+00   0.0000000000000000D+00   0.0000000000000000D+00\n"
    "         3         1         1        11\n"
    "   0.0000000000000000D+00   1.0000000000000000D+00   0.0000000000000000D+00\n"
    "         4         1         1        11\n"
    "   0.0000000000000000D+00   0.0000000000000000D+00   1.0000000000000000D+00\n"
    "         5         1         1        11\n"
    "   5.0000000000000000D-01   0.0000000000000000D+00   0.0000000000000000D+00\n"
    "         6         1         1        11\n"
    "   5.0000000000000000D-01   5.0000000000000000D-01   0.0000000000000000D+00\n"
    "         7         1         1        11\n"
    "   0.0000000000000000D+00   5.0000000000000000D-01   0.0000000000000000D+00\n"
    "         8         1         1        11\n"
    "   0.0000000000000000D+00   0.0000000000000000D+00   5.0000000000000000D-01\n"
    "         9         1         1        11\n"
    "   5.0000000000000000D-01   0.0000000000000000D+00   5.0000000000000000D-01\n"
    "        10         1         1        11\n"
    "   0.0000000000000000D+00   5.0000000000000000D-01   5.0000000000000000D-01\n"
    "    -1\n    -1\n  2412\n"
    "         1       118         1         3         7        10\n"
    "         1         5         2         6         3         7         8         9\n"
    "        10         4\n"
    "         2        92         1         4         7         6\n"
    "         1         7         3         6         2         5\n"
    "    -1\n";

/* The tet of bdf10 or unv10: corners 0-3 (reoriented: 1 and 2 exchanged by
 * the reader's orientation fix, their edges' nodes with them), every
 * mid-edge node at its edge's midpoint, region 3, the triangle's corners
 * with ref 4. */
static void check_tet10(const mesh_t *m)
{
    ASSERT_EQ_INT(m->nv, 10);
    ASSERT_EQ_INT(m->nt, 1);
    ASSERT_TRUE(m->mid != NULL);
    for (int e = 0; e < 6; e++) {
        const double *a = m->xyz + 3 * m->tets[mesh_p2_edges[e][0]],
                     *b = m->xyz + 3 * m->tets[mesh_p2_edges[e][1]],
                     *p = m->xyz + 3 * m->mid[e];
        for (int i = 0; i < 3; i++)
            ASSERT_TRUE(p[i] == 0.5 * (a[i] + b[i]));
    }
    ASSERT_EQ_INT(m->region[0], 3);
    ASSERT_EQ_INT(m->ntri, 1);
    ASSERT_EQ_INT(m->tri_ref[0], 4);
    ASSERT_EQ_INT(m->tris[0] + m->tris[1] + m->tris[2], 0 + 1 + 2);
}

TEST(ten_node_tets)
{
    mesh_t *m;
    qdc_error err;
    char *d;

    ASSERT_OK(rd(bdf10, MESHIO_AUTO, &m, &err));
    check_tet10(m);
    ASSERT_TRUE(meshio_splices(m, MESHIO_BDF, NULL));
    mesh_free(m);
    ASSERT_OK(rd(unv10, MESHIO_AUTO, &m, &err));
    check_tet10(m);
    ASSERT_TRUE(meshio_splices(m, MESHIO_UNV, NULL));
    mesh_free(m);
    /* a mid-edge node moved: its own field rewritten, nothing else */
    moved(bdf10, MESHIO_BDF, 5, 2, 0.25, "GRID,6,,.5,.5,0.", "GRID,6,,.5,.5,0.25");
    moved(unv10, MESHIO_UNV, 9, 0, 0.25,
          "   0.0000000000000000D+00   5.0000000000000000D-01   5.0000000000000000D-01\n"
          "    -1",
          "   2.5000000000000000D-01   5.0000000000000000D-01   5.0000000000000000D-01\n"
          "    -1");
    /* meshio 5.0 names the 10-node CTETRA "CTETRA_" */
    d = replaced(bdf10, "CTETRA  1 ", "CTETRA_ 1 ");
    ASSERT_TRUE(d != NULL);
    ASSERT_OK(rd(d, MESHIO_BDF, &m, &err));
    check_tet10(m);
    mesh_free(m);
    free(d);
}

TEST(ten_node_refusals)
{
    refused(bdf10, MESHIO_BDF, "ENDDATA",
            "CTETRA  3       3       1       2       3       9", QDC_EFORMAT, 20,
            "CTETRA 3: 4-node and 10-node CTETRA in one file");
    refused(bdf10, MESHIO_BDF, "        7       8       9       10\n",
            "        7       8       9       11\n", QDC_EPARSE, 17,
            "CTETRA: unknown GRID 11");
    refused(unv10, MESHIO_UNV, "        10         4\n", "        10        40\n",
            QDC_EPARSE, 26, "unknown node 40");
    refused(unv10, MESHIO_UNV, "       118         1         3         7        10",
            "       118         1         3         7         4", QDC_EPARSE, 26,
            "element 1 (FE descriptor 118) has 4 nodes");
    refused(unv10, MESHIO_UNV, "    -1\n    -1\n  2412\n",
            "    -1\n    -1\n  2412\n         9       111         1         3         7  "
            "       4\n         1         2         3         4\n",
            QDC_EFORMAT, 28, "linear (FE descriptor 111) and parabolic (118) tetrahedra");
}

TEST(unv_refusals)
{
    refused(unv, MESHIO_UNV, "        50        20        30        40",
            "        50        20        30        41", QDC_EPARSE, 27,
            "unknown node 41");
    refused(unv, MESHIO_UNV, "   1.0000000000000000D+00   1.0000000000000000D+00\n    -1",
            "   1.0000000000000000D+00                  nan\n    -1", QDC_EPARSE, 18,
            "not finite");
    refused(unv, MESHIO_UNV, "   1.0000000000000000D+00   1.0000000000000000D+00\n    -1",
            "   1.0000000000000000D+00   1.0000000000000000D+999\n   -1", QDC_EPARSE, 18,
            "not finite");
    refused(unv, MESHIO_UNV, "        30         1", "        10         1", QDC_EPARSE,
            14, "node 10 appears twice");
    refused(unv, MESHIO_UNV, "         3        91         5",
            "         3        91        x5", QDC_EPARSE, 29,
            "2412: physical property: expected an integer");
    refused(unv, MESHIO_UNV, "0         0\n    -1\n", "0         0\n", QDC_EPARSE, 37,
            "dataset 2477: no closing -1");
    refused(unv, MESHIO_UNV, "  2411\n", "  2419\n", QDC_EPARSE, -1, "no dataset 2411");
}

TEST_MAIN("bdf_unv", T(bdf_three_field_formats), T(bdf_short_reals), T(bdf_splice_widths),
          T(bdf_refusals), T(unv_read_and_splice), T(unv_refusals), T(ten_node_tets),
          T(ten_node_refusals))
