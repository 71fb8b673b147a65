/* test_meshio.c - mesh formats: exact round trips, the dev meshes, the
 * malformed-input corpus (tests/data/meshio/<case>/input.* + expect) and a
 * replay of the fuzz seeds and crashes through every reader. */
#include "meshio.h"
#include "testlib.h"

#include <dirent.h>
#include <stdint.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- helpers ---- */

typedef struct {
    char *b;
    size_t n, cap;
    size_t fail_after; /* fail once more than this many bytes were written; 0 = never */
} sink;

static int sink_write(void *ctx, const void *d, size_t len)
{
    sink *s = ctx;

    if (s->fail_after && s->n + len > s->fail_after)
        return -1;
    if (s->n + len > s->cap) {
        size_t cap = s->cap ? s->cap : 4096;
        while (cap < s->n + len)
            cap *= 2;
        s->b = realloc(s->b, cap);
        if (!s->b)
            return -1;
        s->cap = cap;
    }
    memcpy(s->b + s->n, d, len);
    s->n += len;
    return 0;
}

static uint64_t rng_state = 88172645463325252ULL;

static uint64_t rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}

/* Doubles that stress exact printing: random bits, subnormals, signed zero,
 * extremes, short decimals. */
static double nasty_double(int i)
{
    static const double fixed[] = {0.0,
                                   -0.0,
                                   0.1,
                                   -0.3,
                                   1e308,
                                   -1.7976931348623157e308,
                                   4.9406564584124654e-324,
                                   2.2250738585072014e-308,
                                   1.0 / 3.0,
                                   123456789012345678.0,
                                   5e-1,
                                   9007199254740993.0};
    uint64_t u;
    double x;

    if (i < (int)(sizeof fixed / sizeof fixed[0]))
        return fixed[i];
    if (i % 3 == 0)
        return (double)(int64_t)(rnd() % 2001) / 1000.0 - 1.0;
    do {
        u = rnd();
        memcpy(&x, &u, 8);
    } while (!isfinite(x));
    return x;
}

/* A mesh with every optional array filled (not a valid tet mesh: the formats
 * don't care). */
static mesh_t *make_mesh(int32_t nv, int32_t nt, int32_t ntri)
{
    mesh_t *m = mesh_new(nv, nt, MESH_WITH_REGION | MESH_WITH_FIXED | MESH_WITH_VREF);

    if (!m)
        return NULL;
    for (int32_t i = 0; i < 3 * nv; i++)
        m->xyz[i] = nasty_double(i);
    for (int32_t i = 0; i < nv; i++) {
        m->vref[i] = (int32_t)(rnd() % 7) - 3;
        m->fixed[i] = rnd() % 3 == 0;
    }
    for (int32_t i = 0; i < 4 * nt; i++)
        m->tets[i] = (int32_t)(rnd() % (uint64_t)nv);
    for (int32_t t = 0; t < nt; t++)
        m->region[t] = t % 5 == 0 ? INT32_MIN + t : (int32_t)(rnd() % 1000) - 100;
    if (ntri && mesh_set_tris(m, ntri, 1) != QDC_OK) {
        mesh_free(m);
        return NULL;
    }
    for (int32_t i = 0; i < 3 * ntri; i++)
        m->tris[i] = (int32_t)(rnd() % (uint64_t)nv);
    for (int32_t t = 0; t < ntri; t++)
        m->tri_ref[t] = (int32_t)(rnd() % 100);
    return m;
}

static int same_bytes(const void *a, const void *b, size_t n)
{
    if (!a || !b)
        return a == b || n == 0;
    return memcmp(a, b, n) == 0;
}

/* What survives a format: 1 xyz+tets, 2 region, 4 fixed, 8 vref, 16 tris. */
enum { K_REGION = 2, K_FIXED = 4, K_VREF = 8, K_TRIS = 16 };

static int same_mesh(const mesh_t *a, const mesh_t *b, unsigned keep)
{
    if (a->nv != b->nv || a->nt != b->nt)
        return 0;
    if (!same_bytes(a->xyz, b->xyz, 24 * (size_t)a->nv) ||
        !same_bytes(a->tets, b->tets, 16 * (size_t)a->nt))
        return 0;
    if ((keep & K_REGION) && !same_bytes(a->region, b->region, 4 * (size_t)a->nt))
        return 0;
    if ((keep & K_FIXED) && !same_bytes(a->fixed, b->fixed, (size_t)a->nv))
        return 0;
    if ((keep & K_VREF) && !same_bytes(a->vref, b->vref, 4 * (size_t)a->nv))
        return 0;
    if ((keep & K_TRIS) &&
        (a->ntri != b->ntri || !same_bytes(a->tris, b->tris, 12 * (size_t)a->ntri) ||
         !same_bytes(a->tri_ref, b->tri_ref, 4 * (size_t)a->ntri)))
        return 0;
    return 1;
}

static qdc_status roundtrip(const mesh_t *m, meshio_format f, mesh_t **back)
{
    sink s = {0};
    qdc_error err;
    qdc_status st = meshio_write(m, f, sink_write, &s, &err);

    *back = NULL;
    if (st == QDC_OK)
        st = meshio_read(s.b, s.n, f, back, &err);
    if (st != QDC_OK)
        printf("  %s: %s\n", meshio_format_name(f), err.msg);
    free(s.b);
    return st;
}

static const char *root_path(const char *rel, char *buf, size_t n)
{
    const char *root = getenv("ROOT");

    snprintf(buf, n, "%s%s%s", root ? root : "", root ? "/" : "", rel);
    return buf;
}

/* gunzip a dev mesh into /tmp; returns its path or NULL if the mesh is missing. */
static const char *dev_mesh(const char *name, char *out, size_t n)
{
    char src[512], cmd[1200];
    struct stat sb;

    root_path("../shared/meshes/dev/", src, sizeof src);
    strncat(src, name, sizeof src - strlen(src) - 1);
    strncat(src, ".mesh.gz", sizeof src - strlen(src) - 1);
    if (stat(src, &sb) != 0)
        return NULL;
    snprintf(out, n, "/tmp/qdc_test_meshio_%d_%s.mesh", (int)getpid(), name);
    snprintf(cmd, sizeof cmd, "gzip -dc '%s' > '%s'", src, out);
    return system(cmd) == 0 ? out : NULL;
}

static double now(void)
{
    return qdc_now();
}

/* ---- round trips ---- */

TEST(roundtrip_medit)
{
    mesh_t *m = make_mesh(200, 300, 50), *b;

    ASSERT_TRUE(m);
    ASSERT_OK(roundtrip(m, MESHIO_MEDIT, &b));
    ASSERT_TRUE(b->region && b->vref && b->fixed && b->tri_ref);
    ASSERT_TRUE(same_mesh(m, b, K_REGION | K_FIXED | K_VREF | K_TRIS));
    mesh_free(b);
    mesh_free(m);
}

TEST(roundtrip_qmesh)
{
    mesh_t *m = make_mesh(200, 300, 0), *b;

    ASSERT_TRUE(m);
    m->fixed[3] = 7; /* binary keeps the byte as is */
    ASSERT_OK(roundtrip(m, MESHIO_QMESH, &b));
    ASSERT_TRUE(same_mesh(m, b, K_REGION | K_FIXED));
    mesh_free(b);
    qdc_free(m->region);
    qdc_free(m->fixed);
    m->region = NULL;
    m->fixed = NULL;
    ASSERT_OK(roundtrip(m, MESHIO_QMESH, &b));
    ASSERT_TRUE(!b->region && !b->fixed && same_mesh(m, b, 0));
    mesh_free(b);
    mesh_free(m);
}

TEST(roundtrip_json)
{
    mesh_t *m = make_mesh(200, 300, 0), *b;

    ASSERT_TRUE(m);
    ASSERT_OK(roundtrip(m, MESHIO_JSON, &b));
    ASSERT_TRUE(same_mesh(m, b, K_REGION | K_FIXED));
    mesh_free(b);
    mesh_free(m);
}

TEST(roundtrip_empty)
{
    mesh_t *m = mesh_new(0, 0, 0), *b;

    ASSERT_TRUE(m);
    for (int f = MESHIO_MEDIT; f < MESHIO_FORMAT_COUNT; f++) {
        if (f == MESHIO_TETGEN)
            continue;
        ASSERT_OK(roundtrip(m, (meshio_format)f, &b));
        ASSERT_TRUE(b->nv == 0 && b->nt == 0);
        mesh_free(b);
    }
    mesh_free(m);
}

TEST(roundtrip_files)
{
    static const char *const ext[] = {"mesh", "qmesh", "json", "node"};
    static const unsigned keep[] = {K_REGION | K_FIXED | K_VREF | K_TRIS,
                                    K_REGION | K_FIXED, K_REGION | K_FIXED,
                                    K_REGION | K_VREF};
    char dir[] = "/tmp/qdc_test_meshio_XXXXXX", path[256], cmd[300];
    mesh_t *m = make_mesh(100, 150, 20), *b = NULL;
    qdc_error err;

    ASSERT_TRUE(m && mkdtemp(dir));
    for (int i = 0; i < 4; i++) {
        snprintf(path, sizeof path, "%s/out.%s", dir, ext[i]);
        ASSERT_OK(meshio_save(path, MESHIO_AUTO, m, &err));
        if (meshio_load(path, MESHIO_AUTO, &b, &err) != QDC_OK)
            printf("  %s: %s\n", path, err.msg);
        ASSERT_OK(err.status);
        ASSERT_TRUE(same_mesh(m, b, keep[i]));
        mesh_free(b);
    }
    /* TetGen by base name; no temporary file left behind */
    snprintf(path, sizeof path, "%s/out", dir);
    ASSERT_OK(meshio_load(path, MESHIO_TETGEN, &b, &err));
    ASSERT_TRUE(same_mesh(m, b, K_REGION | K_VREF));
    mesh_free(b);
    snprintf(cmd, sizeof cmd, "test $(ls '%s' | wc -l) -eq 5 && rm -rf '%s'", dir, dir);
    ASSERT_EQ_INT(system(cmd), 0);
    mesh_free(m);
}

TEST(save_bad_dir)
{
    mesh_t *m = make_mesh(10, 10, 0);
    qdc_error err;

    ASSERT_TRUE(m);
    ASSERT_EQ_INT(meshio_save("/nonexistent-dir/x.mesh", MESHIO_AUTO, m, &err), QDC_EIO);
    ASSERT_EQ_INT(meshio_save("/tmp/x.unknown", MESHIO_AUTO, m, &err), QDC_EFORMAT);
    mesh_free(m);
}

TEST(write_failure_is_eio)
{
    mesh_t *m = make_mesh(5000, 5000, 0);
    sink s = {0};
    qdc_error err;

    ASSERT_TRUE(m);
    s.fail_after = 100000;
    for (int f = MESHIO_MEDIT; f < MESHIO_FORMAT_COUNT; f++) {
        if (f == MESHIO_TETGEN)
            continue;
        s.n = 0;
        ASSERT_EQ_INT(meshio_write(m, (meshio_format)f, sink_write, &s, &err), QDC_EIO);
    }
    m->xyz[7] = NAN;
    ASSERT_EQ_INT(meshio_write(m, MESHIO_MEDIT, sink_write, &s, &err), QDC_EINVAL);
    ASSERT_EQ_INT(err.index, 2);
    free(s.b);
    mesh_free(m);
}

/* ---- reading details ---- */

static qdc_status read_str(const char *text, meshio_format f, mesh_t **m, qdc_error *err)
{
    return meshio_read(text, strlen(text), f, m, err);
}

TEST(medit_features)
{
    /* comments, unknown sections, keywords split over lines, tets before vertices */
    const char *text = "# a comment\nMeshVersionFormatted 2 # trailing\nDimension\n3\n"
                       "Tetrahedra\n1\n1 2 3 4 9\n"
                       "Edges 2\n1 2 0\n3 4 0\nCorners 1 1\nRidges\n1\n1\n"
                       "Vertices 4\n0 0 0 1\n1 0 0 2\n0 1 0 3\n0 0 1 4\n"
                       "RequiredVertices 2 1 3\nSolAtVertices 1 1 1 0.5\n"
                       "Triangles 1 1 2 3 7\nEnd\n# done\n";
    mesh_t *m;
    qdc_error err;

    ASSERT_OK(read_str(text, MESHIO_AUTO, &m, &err));
    ASSERT_EQ_INT(m->nv, 4);
    ASSERT_EQ_INT(m->nt, 1);
    ASSERT_EQ_INT(m->tets[3], 3);
    ASSERT_EQ_INT(m->region[0], 9);
    ASSERT_EQ_INT(m->vref[3], 4);
    ASSERT_EQ_INT(m->ntri, 1);
    ASSERT_EQ_INT(m->tri_ref[0], 7);
    ASSERT_TRUE(m->fixed && m->fixed[0] && !m->fixed[1] && m->fixed[2]);
    ASSERT_NEAR(m->xyz[11], 1.0, 0);
    mesh_free(m);
}

TEST(medit_error_position)
{
    const char *text = "MeshVersionFormatted 2\nDimension 3\nVertices\n2\n0 0 0 0\n"
                       "1 0 0 0\nTetrahedra\n1\n1 2 7 1 0\nEnd\n";
    mesh_t *m = (mesh_t *)1;
    qdc_error err;

    ASSERT_EQ_INT(read_str(text, MESHIO_MEDIT, &m, &err), QDC_EPARSE);
    ASSERT_TRUE(m == NULL);
    ASSERT_EQ_INT(err.line, 9);
    ASSERT_EQ_INT(err.col, 5);
    ASSERT_EQ_INT(err.index, 0);
    ASSERT_TRUE(strcmp(err.kind, "tet") == 0);
    ASSERT_TRUE(strstr(err.msg, "Tetrahedra: vertex index 7 out of range [1, 2]"));
}

TEST(medit_deferred_error_position)
{
    const char *text = "Tetrahedra\n2\n1 2 3 4 0\n1 2 3\n 5 0\nVertices\n4\n"
                       "0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n";
    mesh_t *m;
    qdc_error err;

    ASSERT_EQ_INT(read_str(text, MESHIO_MEDIT, &m, &err), QDC_EPARSE);
    ASSERT_EQ_INT(err.line, 5);
    ASSERT_EQ_INT(err.col, 2);
    ASSERT_EQ_INT(err.index, 1);
    ASSERT_TRUE(strstr(err.msg, "out of range [1, 4]"));
}

TEST(json_features)
{
    const char *text = " {\"name\": {\"a\": [1, \"x\\\"y\", true, null, -2.5e3]},\n"
                       "  \"tets\": [[0, 1, 2, 3]], \"regions\": [5], \"fixed\": null,\n"
                       "  \"\\u0076ertices\": [[0,0,0],[1,0,0],[0,1,0],[0,0,1e0]]}\n";
    mesh_t *m;
    qdc_error err;

    ASSERT_OK(read_str(text, MESHIO_AUTO, &m, &err));
    ASSERT_EQ_INT(m->nv, 4);
    ASSERT_EQ_INT(m->nt, 1);
    ASSERT_EQ_INT(m->region[0], 5);
    ASSERT_TRUE(m->fixed == NULL);
    mesh_free(m);
    ASSERT_EQ_INT(read_str("{\"tets\": [[0,1,2,4]], \"vertices\": [[0,0,0],[1,0,0],\n"
                           "[0,1,0],[0,0,1]]}",
                           MESHIO_JSON, &m, &err),
                  QDC_EPARSE);
    ASSERT_EQ_INT(err.line, 1);
    ASSERT_EQ_INT(err.col, 18);
}

TEST(json_not_nul_terminated)
{
    /* the number runs to the end of the buffer: nothing may read past it */
    const char full[] = "{\"vertices\": [[0,0,0]], \"tets\": [], \"x\": 12345";
    size_t len = sizeof full - 1;
    char *buf = malloc(len);
    mesh_t *m;
    qdc_error err;

    ASSERT_TRUE(buf);
    memcpy(buf, full, len);
    for (size_t n = 0; n <= len; n++) {
        ASSERT_EQ_INT(meshio_read(buf + len - n, n, MESHIO_JSON, &m, &err), QDC_EPARSE);
        ASSERT_EQ_INT(meshio_read(buf, n, MESHIO_MEDIT, &m, &err), QDC_EPARSE);
    }
    free(buf);
}

TEST(tetgen_read)
{
    const char *node = "# nodes\n4 3 1 1\n0 0 0 0 0.5 7\n1 1 0 0 0.5 8\n"
                       "2 0 1 0 0.5 9\n3 0 0 1 0.5 10\n";
    const char *ele = "1 4 2\n0 0 1 2 3 -4 0.25\n";
    mesh_t *m;
    qdc_error err;

    ASSERT_OK(meshio_read_tetgen(node, strlen(node), ele, strlen(ele), &m, &err));
    ASSERT_EQ_INT(m->nv, 4);
    ASSERT_EQ_INT(m->tets[1], 1);
    ASSERT_EQ_INT(m->region[0], -4);
    ASSERT_EQ_INT(m->vref[3], 10);
    mesh_free(m);
    ASSERT_EQ_INT(meshio_read(node, strlen(node), MESHIO_TETGEN, &m, &err), QDC_EINVAL);
}

TEST(huge_counts_fail_fast)
{
    const char medit[] = "Vertices 1000000000\n";
    unsigned char q[32] = "QDCMESH";
    mesh_t *m;
    qdc_error err;
    double t0 = now();

    ASSERT_EQ_INT(read_str(medit, MESHIO_MEDIT, &m, &err), QDC_EPARSE);
    ASSERT_TRUE(strstr(err.msg, "truncated"));
    q[8] = 1;
    q[19] = 0x40; /* nv = 2^30 */
    ASSERT_EQ_INT(meshio_read((const char *)q, 32, MESHIO_QMESH, &m, &err), QDC_EPARSE);
    ASSERT_TRUE(strstr(err.msg, "size mismatch"));
    q[23] = 0xff; /* nv near 2^64 */
    ASSERT_EQ_INT(meshio_read((const char *)q, 32, MESHIO_AUTO, &m, &err), QDC_EPARSE);
    ASSERT_TRUE(now() - t0 < 0.1);
}

TEST(formats_and_sniffing)
{
    ASSERT_EQ_INT(meshio_format_from_name("x/y.MESH"), MESHIO_MEDIT);
    ASSERT_EQ_INT(meshio_format_from_name("binary"), MESHIO_QMESH);
    ASSERT_EQ_INT(meshio_format_from_name("application/vnd.qdc.mesh"), MESHIO_QMESH);
    ASSERT_EQ_INT(meshio_format_from_name(".json"), MESHIO_JSON);
    ASSERT_EQ_INT(meshio_format_from_name("a.node"), MESHIO_TETGEN);
    ASSERT_EQ_INT(meshio_format_from_name("a.mesh.gz"), MESHIO_AUTO);
    ASSERT_EQ_INT(meshio_format_from_name("dir.mesh/file"), MESHIO_AUTO);
    ASSERT_TRUE(strcmp(meshio_format_name(MESHIO_QMESH), "qmesh") == 0);
    ASSERT_TRUE(meshio_format_name(MESHIO_FORMAT_COUNT) == NULL);
    ASSERT_EQ_INT(meshio_sniff("# c\n MeshVersionFormatted 2", 25), MESHIO_MEDIT);
    ASSERT_EQ_INT(meshio_sniff("\n {", 3), MESHIO_JSON);
    ASSERT_EQ_INT(meshio_sniff("QDCMESH", 8), MESHIO_QMESH);
    ASSERT_EQ_INT(meshio_sniff("4 3 0 0", 7), MESHIO_AUTO);
    ASSERT_EQ_INT(meshio_sniff("Mesh", 4), MESHIO_AUTO);
}

/* ---- dev meshes and speed ---- */

TEST(dev_cube)
{
    char path[256];
    mesh_t *m = NULL;
    qdc_error err;

    if (!dev_mesh("cube_h0.1_good", path, sizeof path)) {
        printf("  # dev meshes not found, skipped\n");
        return;
    }
    ASSERT_OK(meshio_load(path, MESHIO_AUTO, &m, &err));
    unlink(path);
    ASSERT_EQ_INT(m->nv, 5415);
    ASSERT_EQ_INT(m->nt, 24118);
    ASSERT_TRUE(m->region && m->vref);
    ASSERT_NEAR(m->xyz[0], -0.5, 0);
    ASSERT_EQ_INT(mesh_validate(m, NULL, &err), QDC_OK);
    mesh_free(m);
}

TEST(dev_speed)
{
    char path[256];
    char *buf;
    size_t len;
    mesh_t *m = NULL, *b = NULL;
    qdc_error err;
    sink s = {0};
    double t0, best = 1e9;

    if (!dev_mesh("bunny_low_100k", path, sizeof path)) {
        printf("  # dev meshes not found, skipped\n");
        return;
    }
    ASSERT_OK(meshio_slurp(path, &buf, &len, &err));
    unlink(path);
    for (int rep = 0; rep < 3; rep++) {
        t0 = now();
        ASSERT_OK(meshio_read(buf, len, MESHIO_MEDIT, &m, &err));
        best = fmin(best, now() - t0);
        if (rep < 2)
            mesh_free(m);
    }
    printf("  # medit read: %.1f MB in %.3f s = %.0f MB/s (%d tets)\n", len / 1e6, best,
           len / 1e6 / best, m->nt);
    t0 = now();
    ASSERT_OK(meshio_write(m, MESHIO_MEDIT, sink_write, &s, &err));
    printf("  # medit write: %.3f s\n", now() - t0);
    ASSERT_OK(meshio_read(s.b, s.n, MESHIO_MEDIT, &b, &err));
    ASSERT_TRUE(same_mesh(m, b, K_REGION | K_VREF | K_TRIS));
    mesh_free(b);
    s.n = 0;
    t0 = now();
    ASSERT_OK(meshio_write(m, MESHIO_JSON, sink_write, &s, &err));
    printf("  # json write %.3f s,", now() - t0);
    t0 = now();
    ASSERT_OK(meshio_read(s.b, s.n, MESHIO_JSON, &b, &err));
    printf(" read %.0f MB/s\n", s.n / 1e6 / (now() - t0));
    ASSERT_TRUE(same_mesh(m, b, K_REGION));
    mesh_free(b);
    free(s.b);
    qdc_free(buf);
    mesh_free(m);
}

TEST(qmesh_1m_tets_speed)
{
    const int32_t nv = 200000, nt = 1000000;
    mesh_t *m = mesh_new(nv, nt, MESH_WITH_REGION), *b;
    sink s = {0};
    qdc_error err;
    double t0, t;

    ASSERT_TRUE(m);
    for (int32_t i = 0; i < 3 * nv; i++)
        m->xyz[i] = (double)(rnd() >> 11) * 0x1.0p-53;
    for (int32_t i = 0; i < 4 * nt; i++)
        m->tets[i] = (int32_t)(rnd() % (uint64_t)nv);
    ASSERT_OK(meshio_write(m, MESHIO_QMESH, sink_write, &s, &err));
    t0 = now();
    ASSERT_OK(meshio_read(s.b, s.n, MESHIO_QMESH, &b, &err));
    t = now() - t0;
    printf("  # qmesh read of 1M tets (%.1f MB): %.3f s\n", s.n / 1e6, t);
    ASSERT_TRUE(same_mesh(m, b, K_REGION));
#if defined(__SANITIZE_ADDRESS__)
    ASSERT_TRUE(t < 5);
#else
    ASSERT_TRUE(t < 0.5);
#endif
    mesh_free(b);
    free(s.b);
    mesh_free(m);
}

/* Every allocation failing in turn: ENOMEM, never a crash or a leak (run
 * under ASan in a build with -DQDC_FAULT_INJECTION). */
TEST(allocation_failures)
{
#ifdef QDC_FAULT_INJECTION
    mesh_t *m = make_mesh(50, 60, 10), *b;
    qdc_error err;

    ASSERT_TRUE(m);
    for (int f = MESHIO_MEDIT; f < MESHIO_FORMAT_COUNT; f++) {
        sink s = {0};
        qdc_status st;
        if (f == MESHIO_TETGEN)
            continue;
        qdc_fault_set(1);
        ASSERT_EQ_INT(meshio_write(m, (meshio_format)f, sink_write, &s, &err),
                      QDC_ENOMEM);
        qdc_fault_set(0);
        ASSERT_OK(meshio_write(m, (meshio_format)f, sink_write, &s, &err));
        for (long n = 1;; n++) {
            qdc_fault_set(n);
            st = meshio_read(s.b, s.n, (meshio_format)f, &b, &err);
            qdc_fault_set(0);
            if (st == QDC_OK)
                break;
            ASSERT_EQ_INT(st, QDC_ENOMEM);
            ASSERT_TRUE(b == NULL);
        }
        ASSERT_TRUE(same_mesh(m, b, 0));
        mesh_free(b);
        free(s.b);
    }
    mesh_free(m);
#else
    printf("  # built without QDC_FAULT_INJECTION, skipped\n");
#endif
}

/* ---- corpus and fuzz replay ---- */

static char *read_file(const char *path, size_t *len)
{
    char *buf;
    qdc_error err;

    if (meshio_slurp(path, &buf, len, &err) != QDC_OK)
        return NULL;
    return buf;
}

/* One case dir: input.<ext> (input.node + input.ele for TetGen) and expect:
 * "STATUS [LINE:COL | @OFFSET] message substring". Returns 0 if it passes. */
static int run_case(const char *dir)
{
    static const char *const exts[] = {"mesh", "qmesh", "json", "node"};
    char path[1024], want_status[32], where[32] = "", want_msg[256] = "";
    char *in = NULL, *ele = NULL, *exp;
    size_t len = 0, elen = 0, elen2;
    mesh_t *m = NULL;
    qdc_error err;
    qdc_status st;
    int i, ok = 1;
    long long l = -1, c = -1, off = -1;

    for (i = 0; i < 4 && !in; i++) {
        snprintf(path, sizeof path, "%s/input.%s", dir, exts[i]);
        in = read_file(path, &len);
    }
    snprintf(path, sizeof path, "%s/expect", dir);
    exp = read_file(path, &elen2);
    if (!in || !exp) {
        printf("  %s: missing input.* or expect\n", dir);
        return 1;
    }
    exp = realloc(exp, elen2 + 1);
    exp[elen2] = '\0';
    exp[strcspn(exp, "\n")] = '\0';
    sscanf(exp, "%31s %31s", want_status, where);
    if (sscanf(where, "%lld:%lld", &l, &c) == 2 || sscanf(where, "@%lld", &off) == 1)
        snprintf(want_msg, sizeof want_msg, "%s", strstr(exp, where) + strlen(where) + 1);
    else
        snprintf(want_msg, sizeof want_msg, "%s", exp + strlen(want_status) + 1);
    if (i == 4) {
        snprintf(path, sizeof path, "%s/input.ele", dir);
        ele = read_file(path, &elen);
        st = meshio_read_tetgen(in, len, ele, elen, &m, &err);
    } else {
        st = meshio_read(in, len,
                         (meshio_format)(i == 1   ? MESHIO_MEDIT
                                         : i == 2 ? MESHIO_QMESH
                                                  : MESHIO_JSON),
                         &m, &err);
    }
    if (strcmp(qdc_status_name(st), want_status) != 0 || !strstr(err.msg, want_msg) ||
        (l >= 0 && (err.line != l || err.col != c)) || (off >= 0 && err.offset != off) ||
        (m != NULL) != (st == QDC_OK)) {
        printf("  %s: got %s %lld:%lld @%lld \"%s\", expected \"%s\"\n", dir,
               qdc_status_name(st), (long long)err.line, (long long)err.col,
               (long long)err.offset, err.msg, exp);
        ok = 0;
    }
    mesh_free(m);
    qdc_free(in);
    qdc_free(ele);
    free(exp);
    return ok ? 0 : 1;
}

TEST(malformed_corpus)
{
    char dir[512], sub[800];
    DIR *d = opendir(root_path("tests/data/meshio", dir, sizeof dir));
    struct dirent *e;
    int n = 0, bad = 0;

    ASSERT_TRUE(d);
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        snprintf(sub, sizeof sub, "%s/%s", dir, e->d_name);
        bad += run_case(sub);
        n++;
    }
    closedir(d);
    printf("  # %d corpus cases\n", n);
    ASSERT_TRUE(n >= 20);
    ASSERT_EQ_INT(bad, 0);
}

/* Every reader on buf: a valid status, a mesh exactly on success. */
static int replay(const char *buf, size_t len)
{
    for (int f = 0; f < MESHIO_FORMAT_COUNT; f++) {
        mesh_t *m = NULL;
        qdc_error err;
        qdc_status st;
        if (f == MESHIO_TETGEN)
            st = meshio_read_tetgen(buf, len / 2, buf + len / 2, len - len / 2, &m, &err);
        else
            st = meshio_read(buf, len, (meshio_format)f, &m, &err);
        if ((unsigned)st >= QDC_STATUS_COUNT || (st == QDC_OK) != (m != NULL) ||
            (st != QDC_OK && err.status != st))
            return 1;
        mesh_free(m);
    }
    return 0;
}

TEST(fuzz_replay)
{
    static const char *const dirs[] = {"tests/fuzz/seeds/meshio",
                                       "tests/fuzz/crashes/meshio"};
    int n = 0, bad = 0;

    for (int k = 0; k < 2; k++) {
        char dir[512], path[800];
        DIR *d = opendir(root_path(dirs[k], dir, sizeof dir));
        struct dirent *e;
        if (!d) {
            ASSERT_TRUE(k == 1); /* crashes/ exists only when there were some */
            continue;
        }
        while ((e = readdir(d))) {
            size_t len;
            char *buf;
            if (e->d_name[0] == '.')
                continue;
            snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
            buf = read_file(path, &len);
            if (!buf)
                continue;
            if (replay(buf, len)) {
                printf("  %s: bad status\n", path);
                bad++;
            }
            /* and every prefix of the small ones: truncation anywhere */
            for (size_t p = 0; len < 4096 && p < len; p++)
                bad += replay(buf, p);
            qdc_free(buf);
            n++;
        }
        closedir(d);
    }
    printf("  # %d fuzz inputs replayed\n", n);
    ASSERT_TRUE(n > 0);
    ASSERT_EQ_INT(bad, 0);
}

TEST_MAIN("meshio", T(roundtrip_medit), T(roundtrip_qmesh), T(roundtrip_json),
          T(roundtrip_empty), T(roundtrip_files), T(save_bad_dir),
          T(write_failure_is_eio), T(medit_features), T(medit_error_position),
          T(medit_deferred_error_position), T(json_features), T(json_not_nul_terminated),
          T(tetgen_read), T(huge_counts_fail_fast), T(formats_and_sniffing), T(dev_cube),
          T(dev_speed), T(qmesh_1m_tets_speed), T(allocation_failures),
          T(malformed_corpus), T(fuzz_replay))
