/* test_med.c - the MED reader on the frames qdc-h5 writes (lib/io/meshio_med.c),
 * built here by hand: two tets with their families, boundary triangles (TR3,
 * TR6) with theirs and node families, a second-order tet, the
 * coordinate frame alone rewritten by a spliced write, and refusals (an HDF5
 * file given as it is, frames cut short, nodes out of range, NaN, mixed
 * orders) with their byte offset. The writer of a whole mesh (the frames of
 * qdc-h5 med-new): each frame decoded and checked (counts, 1-based nodes,
 * element families below zero and node families above, the group lines
 * naming the tags), read back to the same tags; T10 and TR6 for a
 * second-order mesh; and the families mapped back only as the reader says. */
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
    ASSERT_TRUE(meshio_has_writer(MESHIO_MED) && meshio_writes_p2(MESHIO_MED));
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

/* ---- writing a whole mesh (qdc-h5 med-new) ---- */

/* One frame of a framed buffer. */
typedef struct {
    char name[17];
    char type;
    uint64_t n;
    const unsigned char *v;
} frame;

/* The frames of s (after the magic) into f[], at most max; their count, or
 * -1 if s is not well framed. */
static int frames_of(const sink *s, frame *f, int max)
{
    size_t pos = 8;
    int n = 0;

    if (s->n < 8 || memcmp(s->b, "QDCH5v1\n", 8) != 0)
        return -1;
    while (pos < s->n && n < max) {
        const unsigned char *h = (const unsigned char *)s->b + pos;
        uint64_t words;
        if (s->n - pos < 32)
            return -1;
        memcpy(f[n].name, h, 16);
        f[n].name[16] = 0;
        f[n].type = (char)h[16];
        f[n].n = 0;
        for (int k = 7; k >= 0; k--)
            f[n].n = f[n].n << 8 | h[24 + k];
        f[n].v = h + 32;
        words = f[n].type == 'b' ? (f[n].n + 7) / 8 : f[n].n;
        if (words > (s->n - pos - 32) / 8)
            return -1;
        pos += 32 + 8 * words;
        n++;
    }
    return pos == s->n ? n : -1;
}

static const frame *frame_named(const frame *f, int n, const char *name)
{
    for (int k = 0; k < n; k++)
        if (!strcmp(f[k].name, name))
            return &f[k];
    return NULL;
}

static int64_t ival(const frame *f, uint64_t i)
{
    int64_t v;

    memcpy(&v, f->v + 8 * i, 8);
    return v;
}

static const double five_xyz[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};

TEST(whole_mesh_frames)
{
    mesh_t *m = five_mesh(five_xyz, 1, 7, -3, 2, 5, 0), *b = NULL;
    sink s = {0};
    frame f[16];
    const frame *x;
    qdc_error err;
    int n;
    static const char lines[] = "-1 REGION_M3\n-2 REGION_7\n-3 SURFACE_5\n"
                                "1 NODE_M2147483648\n2 NODE_4\n";

    ASSERT_TRUE(m && (m->vref = qdc_calloc(5, sizeof(int32_t))) != NULL);
    m->vref[1] = 4;
    m->vref[3] = INT32_MIN;
    ASSERT_OK(meshio_write(m, MESHIO_MED, sink_write, &s, &err));
    n = frames_of(&s, f, 16);
    ASSERT_EQ_INT(n, 7);
    x = frame_named(f, n, "coords");
    ASSERT_TRUE(x && x->type == 'f' && x->n == 15 && memcmp(x->v, five_xyz, 120) == 0);
    x = frame_named(f, n, "te4");
    ASSERT_TRUE(x && x->type == 'i' && x->n == 8);
    for (int k = 0; k < 8; k++)
        ASSERT_EQ_INT(ival(x, (uint64_t)k), m->tets[k] + 1);
    /* regions -3 and 7: families -1 and -2 (ascending tags) */
    x = frame_named(f, n, "te4_fam");
    ASSERT_TRUE(x && x->n == 2 && ival(x, 0) == -2 && ival(x, 1) == -1);
    x = frame_named(f, n, "tr3");
    ASSERT_TRUE(x && x->n == 6 && ival(x, 0) == 2 && ival(x, 5) == 3);
    /* ref 5 after the regions' families; ref 0: family 0 */
    x = frame_named(f, n, "tr3_fam");
    ASSERT_TRUE(x && x->n == 2 && ival(x, 0) == -3 && ival(x, 1) == 0);
    x = frame_named(f, n, "noe_fam");
    ASSERT_TRUE(x && x->n == 5 && ival(x, 0) == 0 && ival(x, 1) == 2 && ival(x, 3) == 1);
    x = frame_named(f, n, "families");
    ASSERT_TRUE(x && x->type == 'b' && x->n == strlen(lines) &&
                memcmp(x->v, lines, x->n) == 0);
    ASSERT_TRUE(!frame_named(f, n, "t10") && !frame_named(f, n, "tr6"));
    /* read back: the tags, not the family numbers */
    ASSERT_OK(meshio_read(s.b, s.n, MESHIO_MED, &b, &err));
    ASSERT_TRUE(same_mesh(m, b, K_REGION | K_VREF | K_TRIS));
    mesh_free(b);
    mesh_free(m);
    /* no tags at all: no family frame of any kind */
    m = five_mesh(five_xyz, 0, 0, 0, 2, 0, 0);
    ASSERT_TRUE(m);
    s.n = 0;
    ASSERT_OK(meshio_write(m, MESHIO_MED, sink_write, &s, &err));
    n = frames_of(&s, f, 16);
    ASSERT_EQ_INT(n, 4);
    ASSERT_TRUE(frame_named(f, n, "tr3_fam") && !frame_named(f, n, "te4_fam") &&
                !frame_named(f, n, "noe_fam") && !frame_named(f, n, "families"));
    ASSERT_OK(meshio_read(s.b, s.n, MESHIO_MED, &b, &err));
    ASSERT_TRUE(same_mesh(m, b, K_TRIS) && !b->region);
    mesh_free(b);
    mesh_free(m);
    free(s.b);
}

/* One second-order tet (the nodes of test second_order) with two of its
 * faces as triangles: T10 in MED's order (mesh_p2_edges'), TR6 with the
 * tet's mid-edge nodes of edges 01, 12, 20; a triangle that is no face:
 * TR3 for all. */
TEST(whole_mesh_second_order)
{
    mesh_t *m = mesh_new(10, 1, MESH_WITH_REGION), *b = NULL;
    sink s = {0};
    frame f[16];
    const frame *x;
    qdc_error err;
    int n;

    ASSERT_TRUE(m && mesh_set_mid(m) == QDC_OK && mesh_set_tris(m, 2, 1) == QDC_OK);
    for (int v = 0; v < 4; v++) {
        m->tets[v] = v;
        if (v)
            m->xyz[3 * v + v - 1] = 1;
    }
    for (int e = 0; e < 6; e++) {
        m->mid[e] = 4 + e;
        for (int k = 0; k < 3; k++)
            m->xyz[3 * (4 + e) + k] = 0.5 * (m->xyz[3 * mesh_p2_edges[e][0] + k] +
                                             m->xyz[3 * mesh_p2_edges[e][1] + k]);
    }
    m->region[0] = 2;
    m->tris[0] = 1, m->tris[1] = 2, m->tris[2] = 3;
    m->tris[3] = 0, m->tris[4] = 2, m->tris[5] = 1;
    m->tri_ref[0] = 8, m->tri_ref[1] = 9;
    ASSERT_OK(meshio_write(m, MESHIO_MED, sink_write, &s, &err));
    n = frames_of(&s, f, 16);
    x = frame_named(f, n, "t10");
    ASSERT_TRUE(x && x->n == 10 && !frame_named(f, n, "te4"));
    for (int k = 0; k < 10; k++)
        ASSERT_EQ_INT(ival(x, (uint64_t)k), k + 1);
    x = frame_named(f, n, "t10_fam");
    ASSERT_TRUE(x && x->n == 1 && ival(x, 0) == -1);
    x = frame_named(f, n, "tr6");
    ASSERT_TRUE(x && x->n == 12 && !frame_named(f, n, "tr3"));
    for (int t = 0; t < 2; t++)
        for (int e = 0; e < 3; e++) {
            /* node e + 3: the middle of corners e and e + 1 */
            int64_t mid = ival(x, 6 * (uint64_t)t + 3 + (uint64_t)e) - 1;
            int32_t a = m->tris[3 * t + e], c = m->tris[3 * t + (e + 1) % 3];
            for (int k = 0; k < 3; k++)
                ASSERT_NEAR(m->xyz[3 * mid + k],
                            0.5 * (m->xyz[3 * a + k] + m->xyz[3 * c + k]), 0);
        }
    x = frame_named(f, n, "tr6_fam");
    ASSERT_TRUE(x && x->n == 2 && ival(x, 0) == -2 && ival(x, 1) == -3);
    ASSERT_OK(meshio_read(s.b, s.n, MESHIO_MED, &b, &err));
    ASSERT_TRUE(same_mesh(m, b, K_REGION | K_TRIS) && b->mid &&
                memcmp(b->mid, m->mid, sizeof(int32_t) * 6) == 0);
    mesh_free(b);
    m->tris[5] = 4; /* 0 2 4: no face of the tet */
    s.n = 0;
    ASSERT_OK(meshio_write(m, MESHIO_MED, sink_write, &s, &err));
    n = frames_of(&s, f, 16);
    ASSERT_TRUE(frame_named(f, n, "tr3") && !frame_named(f, n, "tr6") &&
                frame_named(f, n, "tr3")->n == 6);
    mesh_free(m);
    free(s.b);
}

/* two_tets with triangles and node families, and the families frame given:
 * the tags read. */
static qdc_status read_families(const char *lines, mesh_t **m, qdc_error *err)
{
    sink s = {0};
    qdc_status st;
    size_t n = strlen(lines);
    static const char zero[8] = {0};

    with_triangles(&s, 2, 5);
    {
        unsigned char h[32] = {0};
        memcpy(h, "families", 8);
        h[16] = 'b';
        for (int k = 0; k < 8; k++)
            h[24 + k] = (unsigned char)((uint64_t)n >> (8 * k));
        sink_write(&s, h, sizeof h);
        sink_write(&s, lines, n);
        sink_write(&s, zero, (8 - n % 8) % 8);
    }
    st = meshio_read(s.b, s.n, MESHIO_MED, m, err);
    free(s.b);
    return st;
}

/* with_triangles' families: tets -1 -2, triangles -11 -12, nodes 1 0 0 2 0 */
TEST(families_to_tags)
{
    mesh_t *m;
    qdc_error err;

    /* every family of each kind named: all three mapped; other groups of a
     * family (a user's "inlet") ignored, a line that is no family skipped */
    ASSERT_OK(read_families("-1 REGION_4\n-2 REGION_M4\n-2 Solid\n-11 SURFACE_0\n"
                            "-12 SURFACE_2147483647\n-12 inlet\nx REGION_9\n1 NODE_3\n"
                            "2 NODE_M1",
                            &m, &err));
    ASSERT_TRUE(m->region[0] == 4 && m->region[1] == -4);
    ASSERT_TRUE(m->tri_ref[0] == 0 && m->tri_ref[1] == INT32_MAX);
    ASSERT_TRUE(m->vref[0] == 3 && m->vref[1] == 0 && m->vref[3] == -1);
    mesh_free(m);
    /* a family unnamed (the tets' -2), two tags for one family (-11), and
     * names not spelled as qdc's (meshio's "surface_3", a leading zero, a
     * node family named as a region): those kinds keep their numbers */
    ASSERT_OK(read_families("-1 REGION_4\n-11 SURFACE_1\n-11 SURFACE_2\n"
                            "-12 SURFACE_3\n1 NODE_07\n2 REGION_5\n",
                            &m, &err));
    ASSERT_TRUE(m->region[0] == -1 && m->region[1] == -2);
    ASSERT_TRUE(m->tri_ref[0] == -11 && m->tri_ref[1] == -12);
    ASSERT_TRUE(m->vref[0] == 1 && m->vref[3] == 2);
    mesh_free(m);
    ASSERT_OK(read_families("-1 region_4\n-2 REGION_m4\n-11 surface_3\n-12 SURFACE_4\n",
                            &m, &err));
    ASSERT_TRUE(m->region[0] == -1 && m->region[1] == -2);
    ASSERT_TRUE(m->tri_ref[0] == -11 && m->tri_ref[1] == -12);
    mesh_free(m);
    /* families of another type than bytes: refused */
    {
        sink s = {0};
        const int64_t one[1] = {1};
        two_tets(&s, 4, 1);
        put_frame(&s, "families", 'i', one, 1);
        ASSERT_EQ_INT(meshio_read(s.b, s.n, MESHIO_MED, &m, &err), QDC_EPARSE);
        ASSERT_TRUE(strstr(err.msg, "families twice or of the wrong type") != NULL);
        free(s.b);
    }
}

/* A MED mesh whose tets changed: not spliced, written whole by the writer
 * (its source's families and names dropped), read back to the same tags; a
 * sink that fails: QDC_EIO. */
TEST(changed_tets_written_whole)
{
    sink s = {0}, w = {0};
    mesh_t *m, *b;
    qdc_error err;
    meshio_options o = {.source = 1};
    frame f[16];
    const char *why = NULL;

    with_triangles(&s, 2, 5);
    ASSERT_OK(meshio_read_ex(s.b, s.n, MESHIO_MED, &o, &m, &err));
    ASSERT_TRUE(meshio_splices(m, MESHIO_MED, NULL));
    m->tets[7] = 0; /* e b c a */
    ASSERT_TRUE(!meshio_splices(m, MESHIO_MED, &why) && why);
    ASSERT_OK(meshio_write(m, MESHIO_MED, sink_write, &w, &err));
    ASSERT_TRUE(frame_named(f, frames_of(&w, f, 16), "families") != NULL);
    ASSERT_OK(meshio_read(w.b, w.n, MESHIO_MED, &b, &err));
    ASSERT_TRUE(same_mesh(m, b, K_REGION | K_VREF | K_TRIS));
    ASSERT_TRUE(b->region[0] == -1 && b->tri_ref[1] == -12 && b->vref[3] == 2);
    mesh_free(b);
    w.n = 0;
    w.fail_after = 64;
    ASSERT_EQ_INT(meshio_write(m, MESHIO_MED, sink_write, &w, &err), QDC_EIO);
    mesh_free(m);
    free(s.b);
    free(w.b);
}

TEST_MAIN("med", T(two_tets_with_families), T(boundary_triangles_and_node_families),
          T(triangles_off_the_boundary_kept), T(second_order), T(refusals),
          T(whole_mesh_frames), T(whole_mesh_second_order), T(families_to_tags),
          T(changed_tets_written_whole))
