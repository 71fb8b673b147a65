/* test_med.c - the MED reader on the frames qdc-h5 writes (lib/io/meshio_med.c),
 * built here by hand: two tets with their families, boundary triangles (TR3,
 * TR6) with theirs and node families, a second-order tet, the
 * coordinate frame alone rewritten by a spliced write, and refusals (an HDF5
 * file given as it is, frames cut short, nodes out of range, NaN, mixed
 * orders) with their byte offset. */
#include "testio.h"
#include "testlib.h"

/* a = 0, b = x, c = y, d = z, e = (1,1,1); tets a b c d (family -1), e b c d
 * (family -2), 1-based; an unknown frame between. */
static void two_tets(sink *s, int64_t bad_node, double bad_x)
{
    const double xyz[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, bad_x};
    const int64_t te4[8] = {1, 2, 3, 4, 5, 2, 3, bad_node}, fam[2] = {-1, -2},
                  other[1] = {7};

    sink_write(s, "QDCH5v1\n", 8);
    put_frame(s, "coords", 'f', xyz, 15);
    put_frame(s, "te4", 'i', te4, 8);
    put_frame(s, "tr3_later", 'i', other, 1);
    put_frame(s, "te4_fam", 'i', fam, 2);
}

TEST(two_tets_with_families)
{
    sink s = {0};
    mesh_t *m;
    qdc_error err;
    meshio_options o = {.source = 1};
    static const int32_t tets[8] = {0, 1, 2, 3, 4, 1, 2, 3};

    two_tets(&s, 4, 1);
    ASSERT_EQ_INT(meshio_sniff(s.b, s.n), MESHIO_MED);
    ASSERT_OK(meshio_read_ex(s.b, s.n, MESHIO_AUTO, &o, &m, &err));
    ASSERT_EQ_INT(m->nv, 5);
    ASSERT_EQ_INT(m->nt, 2);
    ASSERT_TRUE(memcmp(m->tets, tets, sizeof tets) == 0);
    ASSERT_NEAR(m->xyz[12], 1, 0);
    ASSERT_TRUE(m->region && m->region[0] == -1 && m->region[1] == -2);
    ASSERT_EQ_INT(meshio_format_from_name("x.med"), MESHIO_MED);
    ASSERT_TRUE(!meshio_has_writer(MESHIO_MED));
    {
        sink w = {0};
        m->xyz[3] = 0.25; /* b.x: bytes 8 + 32 + 24 .. + 8 */
        ASSERT_OK(meshio_write(m, MESHIO_MED, sink_write, &w, &err));
        ASSERT_EQ_INT((int)w.n, (int)s.n);
        ASSERT_TRUE(memcmp(w.b, s.b, 64) == 0);
        ASSERT_TRUE(memcmp(w.b + 72, s.b + 72, s.n - 72) == 0);
        ASSERT_TRUE(memcmp(w.b + 64, &m->xyz[3], 8) == 0);
        free(w.b);
    }
    mesh_free(m);
    free(s.b);
}

/* two_tets with a TR3 triangle (b c d, family -11), a TR6 one (a b c and
 * three mid-side nodes, family -12) and node families (1 0 0 2 0); tr3's
 * first node bad_node. */
static void with_triangles(sink *s, int64_t bad_node, int nfam)
{
    const int64_t tr3[3] = {bad_node, 3, 4}, tr6[6] = {1, 2, 3, 2, 3, 4};
    const int64_t f3[1] = {-11}, f6[1] = {-12}, noe[5] = {1, 0, 0, 2, 0};

    two_tets(s, 4, 1);
    put_frame(s, "tr3", 'i', tr3, 3);
    put_frame(s, "tr3_fam", 'i', f3, 1);
    put_frame(s, "tr6", 'i', tr6, 6);
    put_frame(s, "tr6_fam", 'i', f6, 1);
    put_frame(s, "noe_fam", 'i', noe, nfam);
}

TEST(boundary_triangles_and_node_families)
{
    sink s = {0};
    mesh_t *m;
    qdc_error err;
    static const int32_t tris[6] = {1, 2, 3, 0, 1, 2}, vref[5] = {1, 0, 0, 2, 0};

    with_triangles(&s, 2, 5);
    ASSERT_OK(meshio_read(s.b, s.n, MESHIO_MED, &m, &err));
    ASSERT_EQ_INT(m->nt, 2);
    ASSERT_EQ_INT(m->ntri, 2);
    ASSERT_TRUE(memcmp(m->tris, tris, sizeof tris) == 0);
    ASSERT_TRUE(m->tri_ref && m->tri_ref[0] == -11 && m->tri_ref[1] == -12);
    ASSERT_TRUE(m->vref && memcmp(m->vref, vref, sizeof vref) == 0);
    ASSERT_TRUE(m->region && m->region[0] == -1 && m->region[1] == -2);
    mesh_free(m);
    free(s.b);
    /* a triangle's node out of range, node families not one a node */
    memset(&s, 0, sizeof s);
    with_triangles(&s, 9, 5);
    ASSERT_EQ_INT(meshio_read(s.b, s.n, MESHIO_MED, &m, &err), QDC_EPARSE);
    ASSERT_TRUE(strstr(err.msg, "triangle 1: node 9 out of range [1, 5]") != NULL);
    free(s.b);
    memset(&s, 0, sizeof s);
    with_triangles(&s, 2, 4);
    ASSERT_EQ_INT(meshio_read(s.b, s.n, MESHIO_MED, &m, &err), QDC_EPARSE);
    ASSERT_TRUE(strstr(err.msg, "4 node families for 5 nodes") != NULL);
    free(s.b);
}

/* A TR3 that is no face of a tet (a c e: a shell element of its own, which
 * MED holds beside the volume) and one between the two tets (b c d) are kept
 * as they are, with their families, and written back unchanged: unlike
 * XDMF's facet tags (the mesh's own facets, test_xdmf), MED's triangles are
 * elements of their own, as Medit's are. */
TEST(triangles_off_the_boundary_kept)
{
    sink s = {0}, w = {0};
    mesh_t *m;
    qdc_error err;
    meshio_options o = {.source = 1};
    const int64_t tr3[6] = {1, 3, 5, 2, 3, 4}, f3[2] = {-21, -22};
    static const int32_t tris[6] = {0, 2, 4, 1, 2, 3};

    two_tets(&s, 4, 1);
    put_frame(&s, "tr3", 'i', tr3, 6);
    put_frame(&s, "tr3_fam", 'i', f3, 2);
    ASSERT_OK(meshio_read_ex(s.b, s.n, MESHIO_MED, &o, &m, &err));
    ASSERT_EQ_INT(m->ntri, 2);
    ASSERT_TRUE(memcmp(m->tris, tris, sizeof tris) == 0);
    ASSERT_TRUE(m->tri_ref && m->tri_ref[0] == -21 && m->tri_ref[1] == -22);
    ASSERT_OK(meshio_write(m, MESHIO_MED, sink_write, &w, &err));
    ASSERT_EQ_INT((int)w.n, (int)s.n);
    ASSERT_TRUE(memcmp(w.b, s.b, s.n) == 0);
    free(w.b);
    mesh_free(m);
    free(s.b);
}

TEST(second_order)
{
    const double xyz[30] = {0,   0, 0, 1,   0, 0, 0, 1,   0,   0, 0,   1, 0.5, 0,  0, 0.5,
                            0.5, 0, 0, 0.5, 0, 0, 0, 0.5, 0.5, 0, 0.5, 0, 0.5, 0.5};
    const int64_t t10[10] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
    sink s = {0};
    mesh_t *m;
    qdc_error err;

    sink_write(&s, "QDCH5v1\n", 8);
    put_frame(&s, "coords", 'f', xyz, 30);
    put_frame(&s, "t10", 'i', t10, 10);
    ASSERT_OK(meshio_read(s.b, s.n, MESHIO_MED, &m, &err));
    ASSERT_TRUE(m->mid != NULL);
    for (int e = 0; e < 6; e++)
        for (int k = 0; k < 3; k++)
            ASSERT_NEAR(m->xyz[3 * m->mid[e] + k],
                        0.5 * (m->xyz[3 * mesh_p2_edges[e][0] + k] +
                               m->xyz[3 * mesh_p2_edges[e][1] + k]),
                        0);
    mesh_free(m);
    free(s.b);
}

static void refused(const sink *s, size_t n, qdc_status st, int64_t off, const char *text)
{
    mesh_t *m = NULL;
    qdc_error err;

    ASSERT_EQ_INT(meshio_read(s->b, n, MESHIO_MED, &m, &err), st);
    if (!strstr(err.msg, text) || err.offset != off)
        printf("  got offset %lld: %s\n", (long long)err.offset, err.msg);
    ASSERT_TRUE(strstr(err.msg, text) != NULL);
    ASSERT_EQ_INT(err.offset, off);
    ASSERT_TRUE(m == NULL);
}

TEST(refusals)
{
    sink s = {0}, h = {0};
    static const unsigned char hdf5[16] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
    const int64_t t10[10] = {1, 2, 3, 4, 5, 1, 2, 3, 4, 5};

    two_tets(&s, 6, 1);
    refused(&s, s.n, QDC_EPARSE, 8 + 32 + 120 + 32 + 56, "node 6 out of range [1, 5]");
    refused(&s, s.n - 1, QDC_EPARSE, 8 + 32 + 120 + 32 + 64 + 40, "runs past the end");
    refused(&s, 8 + 32 + 120 + 10, QDC_EPARSE, 8 + 32 + 120, "cut short");
    refused(&s, 8 + 32 + 120, QDC_EFORMAT, 160, "no tetrahedra");
    s.b[0] = 'X';
    refused(&s, s.n, QDC_EPARSE, 0, "not what qdc-h5 writes");
    s.n = 0;
    two_tets(&s, 4, NAN);
    refused(&s, s.n, QDC_EPARSE, 8 + 32 + 14 * 8, "not finite");
    put_frame(&s, "t10", 'i', t10, 10);
    refused(&s, s.n, QDC_EFORMAT, (int64_t)s.n - 80, "linear (TE4) and second-order");
    sink_write(&h, hdf5, sizeof hdf5);
    refused(&h, h.n, QDC_EFORMAT, 0, "through qdc-h5");
    free(s.b);
    free(h.b);
}

TEST_MAIN("med", T(two_tets_with_families), T(boundary_triangles_and_node_families),
          T(triangles_off_the_boundary_kept), T(second_order), T(refusals))
