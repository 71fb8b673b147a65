/* test_meshio.c - mesh formats: exact round trips, the dev meshes, the
 * malformed-input corpus (tests/data/meshio/<case>/input.* + expect) and a
 * replay of the fuzz seeds and crashes through every reader. */
#include "qdc.h"
#include "testio.h"
#include "testlib.h"

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
        if (f == MESHIO_TETGEN || !meshio_has_writer((meshio_format)f))
            continue; /* two files; spliced only (test_formats) */
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
        if (f == MESHIO_TETGEN || !meshio_has_writer((meshio_format)f))
            continue; /* two files; spliced only (refused before writing) */
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

/* A Medit text of nv vertices and nt tets, one entry per line, with values
 * known from the index; `odd` changes the layout at entry nv / 2 and nt / 2
 * (1: a comment line among the vertices and two tets on one line; 2: a bad
 * coordinate at vertex 40000). */
static char *big_medit(int32_t nv, int32_t nt, int odd)
{
    size_t cap = 64 + (size_t)nv * 64 + (size_t)nt * 64, n = 0;
    char *b = malloc(cap);

    if (!b)
        return NULL;
    n += (size_t)snprintf(b + n, cap - n,
                          "MeshVersionFormatted 2\nDimension 3\nVertices\n%d\n", (int)nv);
    for (int32_t i = 0; i < nv; i++) {
        if (odd == 1 && i == nv / 2)
            n += (size_t)snprintf(b + n, cap - n, "# a comment line\n");
        n += (size_t)snprintf(b + n, cap - n, "%.17g %d %.17g %d\n",
                              odd == 2 && i == 40000 ? 0.0 : i * 0.5 + 0.25, -(int)i,
                              i / 8.0, (int)(i % 7));
        if (odd == 2 && i == 40000)
            memcpy(b + n - 12, "1.0x", 4); /* the last coordinate becomes bad */
    }
    n += (size_t)snprintf(b + n, cap - n, "Tetrahedra\n%d\n", (int)nt);
    for (int32_t i = 0; i < nt; i++)
        n += (size_t)snprintf(b + n, cap - n, "%d %d %d %d %d%s", (int)(i % nv + 1),
                              (int)((i + 1) % nv + 1), (int)((i + 2) % nv + 1),
                              (int)((i + 3) % nv + 1), (int)(i % 5),
                              odd == 1 && i == nt / 2 ? " " : "\n");
    snprintf(b + n, cap - n, "End\n");
    return b;
}

/* Sections of 50,000 entries and more are read in parallel runs of lines
 * (meshio.c); every layout the serial reader accepts gives the same values,
 * and errors keep their line and entry. */
TEST(medit_large_sections)
{
    const int32_t nv = 60000, nt = 120001;
    for (int odd = 0; odd < 3; odd++) {
        char *text = big_medit(nv, nt, odd);
        mesh_t *m = NULL;
        qdc_error err;
        ASSERT_TRUE(text != NULL);
        if (odd == 2) {
            ASSERT_EQ_INT(read_str(text, MESHIO_MEDIT, &m, &err), QDC_EPARSE);
            ASSERT_TRUE(m == NULL);
            ASSERT_EQ_INT(err.line, 5 + 40000);
            ASSERT_EQ_INT(err.index, 40000);
            ASSERT_TRUE(strcmp(err.kind, "vertex") == 0);
            free(text);
            continue;
        }
        ASSERT_OK(read_str(text, MESHIO_MEDIT, &m, &err));
        ASSERT_EQ_INT(m->nv, nv);
        ASSERT_EQ_INT(m->nt, nt);
        for (int32_t i = 0; i < nv; i++) {
            ASSERT_TRUE(m->xyz[3 * i] == i * 0.5 + 0.25 && m->xyz[3 * i + 1] == -i &&
                        m->xyz[3 * i + 2] == i / 8.0);
            ASSERT_EQ_INT(m->vref[i], i % 7);
        }
        for (int32_t i = 0; i < nt; i++) {
            for (int j = 0; j < 4; j++)
                ASSERT_EQ_INT(m->tets[4 * i + j], (i + j) % nv);
            ASSERT_EQ_INT(m->region[i], i % 5);
        }
        mesh_free(m);
        free(text);
    }
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

/* Counts far beyond the bytes fail before anything of their size is allocated
 * or walked: the three reads take less than 20 reference passes (testio.h's
 * ref_pass) over 1 MB, timed beside them (microseconds against about 1.5 ms
 * when idle; a walk of 10^9 vertices would take seconds); the least ratio of
 * three tries, so that a busy machine's pause in one does not count. */
TEST(huge_counts_fail_fast)
{
    const char medit[] = "Vertices 1000000000\n";
    const size_t nref = (size_t)1 << 20;
    char *ref = calloc(nref, 1);
    uint64_t h = 0;
    mesh_t *m;
    qdc_error err;
    double best = 1e9;

    ASSERT_TRUE(ref);
    for (int rep = 0; rep < 3 && best >= 20; rep++) {
        unsigned char q[32] = "QDCMESH";
        double tr = ref_pass(ref, nref, &h), t0 = now();

        ASSERT_EQ_INT(read_str(medit, MESHIO_MEDIT, &m, &err), QDC_EPARSE);
        ASSERT_TRUE(strstr(err.msg, "truncated"));
        q[8] = 1;
        q[19] = 0x40; /* nv = 2^30 */
        ASSERT_EQ_INT(meshio_read((const char *)q, 32, MESHIO_QMESH, &m, &err),
                      QDC_EPARSE);
        ASSERT_TRUE(strstr(err.msg, "size mismatch"));
        q[23] = 0xff; /* nv near 2^64 */
        ASSERT_EQ_INT(meshio_read((const char *)q, 32, MESHIO_AUTO, &m, &err),
                      QDC_EPARSE);
        best = fmin(best, (now() - t0) / tr);
    }
    free(ref);
    printf("  # the three reads: %.3f reference passes over 1 MB (%llx)\n", best,
           (unsigned long long)(h & 0xf));
    ASSERT_TRUE(best < 20);
}

TEST(formats_and_sniffing)
{
    ASSERT_EQ_INT(meshio_format_from_name("x/y.MESH"), MESHIO_MEDIT);
    ASSERT_EQ_INT(meshio_format_from_name("binary"), MESHIO_QMESH);
    ASSERT_EQ_INT(meshio_format_from_name("application/vnd.qdc.mesh"), MESHIO_QMESH);
    ASSERT_EQ_INT(meshio_format_from_name(".json"), MESHIO_JSON);
    ASSERT_EQ_INT(meshio_format_from_name("a.node"), MESHIO_TETGEN);
    /* a gzip-compressed file is named after what it holds */
    ASSERT_EQ_INT(meshio_format_from_name("a.mesh.gz"), MESHIO_MEDIT);
    ASSERT_EQ_INT(meshio_format_from_name("a.gz"), MESHIO_AUTO);
    ASSERT_EQ_INT(meshio_format_from_name("dir.mesh/file"), MESHIO_AUTO);
    ASSERT_TRUE(strcmp(meshio_format_name(MESHIO_QMESH), "qmesh") == 0);
    ASSERT_TRUE(meshio_format_name(MESHIO_FORMAT_COUNT) == NULL);
    ASSERT_EQ_INT(meshio_sniff("# c\n MeshVersionFormatted 2", 25), MESHIO_MEDIT);
    ASSERT_EQ_INT(meshio_sniff("\n {", 3), MESHIO_JSON);
    ASSERT_EQ_INT(meshio_sniff("QDCMESH", 8), MESHIO_QMESH);
    ASSERT_EQ_INT(meshio_sniff("4 3 0 0", 7), MESHIO_AUTO);
    ASSERT_EQ_INT(meshio_sniff("Mesh", 4), MESHIO_AUTO);
}

/* The format table (lib/io/formats.h): every entry answers to its name and
 * aliases, its extension names its family, its media type comes back to it,
 * and the JSON of `qdc formats` / GET /v1/formats lists it once. */
TEST(format_table)
{
    sink s = {0};
    int nf = 0;
    qdc_error err;

    for (int f = 1; f < MESHIO_FORMAT_COUNT; f++) {
        meshio_format_info fi;
        char buf[64];
        ASSERT_TRUE(meshio_format_info_of((meshio_format)f, &fi));
        ASSERT_TRUE(fi.name && fi.about && fi.ext && fi.about[0]);
        ASSERT_TRUE(strcmp(fi.name, meshio_format_name((meshio_format)f)) == 0);
        ASSERT_EQ_INT(meshio_format_from_name(fi.name), f);
        for (const char *a = fi.aliases; a && *a;) {
            size_t k = strcspn(a, " ");
            snprintf(buf, sizeof buf, "%.*s", (int)k, a);
            ASSERT_EQ_INT(meshio_format_from_name(buf), f);
            a += k + (a[k] == ' ');
        }
        snprintf(buf, sizeof buf, "dir/x.%s.gz", fi.ext);
        ASSERT_EQ_INT(meshio_format_from_name(buf), fi.family);
        ASSERT_EQ_INT(
            meshio_format_variant(meshio_format_from_name(buf), (meshio_format)f), f);
        ASSERT_EQ_INT(meshio_has_writer((meshio_format)f), fi.writes);
        if (fi.media)
            ASSERT_EQ_INT(meshio_format_from_media_type(fi.media), f);
        ASSERT_TRUE(fi.media == meshio_media_type((meshio_format)f));
        ASSERT_TRUE(!fi.input || strncmp(fi.input, "input.", 6) == 0);
        nf++;
    }
    ASSERT_TRUE(!meshio_format_info_of(MESHIO_AUTO, NULL));
    ASSERT_TRUE(!meshio_format_info_of(MESHIO_FORMAT_COUNT, NULL));
    /* a variant's parameter picks it, others are ignored */
    ASSERT_EQ_INT(
        meshio_format_from_media_type(" Model/VND.gmsh ; charset=x; version=\"2.2\""),
        MESHIO_GMSH22);
    ASSERT_EQ_INT(meshio_format_from_media_type("application/x-vtk;encoding=ascii"),
                  MESHIO_VTK);
    ASSERT_EQ_INT(meshio_format_from_media_type("model/vnd.gmsh;version=4.1"),
                  MESHIO_GMSH41);
    ASSERT_EQ_INT(meshio_format_from_media_type("model/vnd.gmsh2"), MESHIO_AUTO);
    ASSERT_OK(meshio_formats_json(sink_write, &s, &err));
    ASSERT_TRUE(s.b && s.n > 2 && s.b[0] == '{' && s.b[s.n - 2] == '}' &&
                s.b[s.n - 1] == '\n');
    for (int f = 1; f < MESHIO_FORMAT_COUNT; f++) {
        char pat[80];
        size_t k = (size_t)snprintf(pat, sizeof pat, "{\"name\":\"%s\",",
                                    meshio_format_name((meshio_format)f));
        int hits = 0;
        for (size_t i = 0; i + k <= s.n; i++)
            hits += memcmp(s.b + i, pat, k) == 0;
        ASSERT_EQ_INT(hits, 1);
    }
    ASSERT_EQ_INT(nf, MESHIO_FORMAT_COUNT - 1);
    free(s.b);
}

/* ---- dev meshes and speed ---- */

TEST(dev_cube)
{
    char path[256];
    mesh_t *m = NULL;
    qdc_error err;

    if (!dev_mesh("cube_h0.1_good", path, sizeof path)) {
        ASSERT_TRUE(!"dev mesh missing from tests/data/dev");
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
        ASSERT_TRUE(!"dev mesh missing from tests/data/dev");
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

/* a read's time over a reference pass over the same bytes (read_ratio,
 * testio.h): 0.24-0.39 measured with two busy loops beside other work
 * (load 11-25 on 2 cores); the former bound was 0.5 s for 24.8 MB */
#define QMESH_RATIO 1

TEST(qmesh_1m_tets_speed)
{
    double r = read_1m_tets(MESHIO_QMESH, QMESH_RATIO);

    ASSERT_TRUE(r > 0);
#if !defined(__SANITIZE_ADDRESS__)
    ASSERT_TRUE(r <= QMESH_RATIO);
#endif
}

#ifdef QDC_FAULT_INJECTION
static int tet_rec_cmp(const void *x, const void *y)
{
    return memcmp(x, y, 5 * sizeof(int32_t));
}

/* The same tets with the same regions, in any order. */
static int same_tet_set(const mesh_t *a, const mesh_t *b)
{
    int32_t *ra, *rb;
    int same;

    if (a->nt != b->nt || !a->region || !b->region)
        return 0;
    ra = malloc(20 * (size_t)a->nt + 1);
    rb = malloc(20 * (size_t)a->nt + 1);
    same = ra && rb;
    for (int32_t t = 0; same && t < a->nt; t++) {
        memcpy(ra + 5 * t, a->tets + 4 * t, 16);
        memcpy(rb + 5 * t, b->tets + 4 * t, 16);
        ra[5 * t + 4] = a->region[t];
        rb[5 * t + 4] = b->region[t];
    }
    if (same) {
        qsort(ra, (size_t)a->nt, 20, tet_rec_cmp);
        qsort(rb, (size_t)a->nt, 20, tet_rec_cmp);
        same = memcmp(ra, rb, 20 * (size_t)a->nt) == 0;
    }
    free(ra);
    free(rb);
    return same;
}
#endif

/* Every allocation failing in turn: ENOMEM, never a crash or a leak (run
 * under ASan in a build with -DQDC_FAULT_INJECTION). */
TEST(allocation_failures)
{
#ifdef QDC_FAULT_INJECTION
    mesh_t *m = make_mesh(50, 60, 10), *b;
    qdc_error err;
    double *pv = malloc(3 * 50 * sizeof *pv), *pi = malloc(50 * sizeof *pi);

    ASSERT_TRUE(m && pv && pi);
    /* point data too: its readers and writers (VTK, VTU, Gmsh) under failures */
    for (int i = 0; i < 150; i++)
        pv[i] = i * 0.25 - 3;
    for (int i = 0; i < 50; i++)
        pi[i] = i;
    ASSERT_OK(mesh_pdata_add(m, "vec", 3, 3, 0, NULL, pv, &err));
    ASSERT_OK(mesh_pdata_add(m, "id", 2, 1, 1, NULL, pi, &err));
    for (int f = MESHIO_MEDIT; f < MESHIO_FORMAT_COUNT; f++) {
        sink s = {0};
        qdc_status st;
        int other = !meshio_has_writer((meshio_format)f); /* spliced only */
        if (f == MESHIO_TETGEN)
            continue;
        if (other) {
            write_other(m, (meshio_format)f, &s);
        } else {
            qdc_fault_set(1);
            ASSERT_EQ_INT(meshio_write(m, (meshio_format)f, sink_write, &s, &err),
                          QDC_ENOMEM);
            qdc_fault_set(0);
            ASSERT_OK(meshio_write(m, (meshio_format)f, sink_write, &s, &err));
        }
        for (long n = 1;; n++) {
            qdc_fault_set(n);
            st = meshio_read(s.b, s.n, (meshio_format)f, &b, &err);
            qdc_fault_set(0);
            if (st == QDC_OK)
                break;
            if (st != QDC_ENOMEM)
                printf("  # %s, allocation %ld failing: %s\n",
                       meshio_format_name((meshio_format)f), n, err.msg);
            ASSERT_EQ_INT(st, QDC_ENOMEM);
            ASSERT_TRUE(b == NULL);
        }
        if (other) /* a spliced write: the source's own numbers */
            ASSERT_TRUE(b->nv == m->nv && b->nt == m->nt &&
                        same_bytes(b->tets, m->tets, 16 * (size_t)m->nt));
        else if (f == MESHIO_ABAQUS) /* tets grouped by region */
            ASSERT_TRUE(b->nv == m->nv &&
                        same_bytes(b->xyz, m->xyz, 24 * (size_t)m->nv) &&
                        same_tet_set(m, b));
        else
            ASSERT_TRUE(same_mesh(m, b, 0));
        mesh_free(b);
        /* with the source kept, then a spliced write of moved coordinates */
        for (long n = 1;; n++) {
            meshio_options keep = {.log = NULL, .log_ctx = NULL, .source = 1};
            qdc_fault_set(n);
            st = meshio_read_ex(s.b, s.n, (meshio_format)f, &keep, &b, &err);
            qdc_fault_set(0);
            if (st == QDC_OK)
                break;
            if (st != QDC_ENOMEM)
                printf("  # %s, allocation %ld failing: %s\n",
                       meshio_format_name((meshio_format)f), n, err.msg);
            ASSERT_EQ_INT(st, QDC_ENOMEM);
            ASSERT_TRUE(b == NULL);
        }
        b->xyz[0] += 1;
        free(s.b);
        s = (sink){0};
        qdc_fault_set(1);
        ASSERT_EQ_INT(meshio_write(b, (meshio_format)f, sink_write, &s, &err),
                      QDC_ENOMEM);
        qdc_fault_set(0);
        mesh_free(b);
        free(s.b);
    }
    mesh_free(m);
#else
    SKIP("built without QDC_FAULT_INJECTION (make fault runs it)");
#endif
}

/* ---- spliced writing ---- */

/* A file written by qdc, read with its source kept and its vertices moved
 * (a permutation of the positions: Gmsh's entity boxes stay the same), is
 * written spliced exactly as qdc's own writer writes the moved mesh. */
TEST(splice_equals_writer)
{
    static const meshio_format fs[] = {MESHIO_MEDIT,  MESHIO_GMSH41,   MESHIO_GMSH41_BIN,
                                       MESHIO_GMSH22, MESHIO_VTK,      MESHIO_VTK_ASCII,
                                       MESHIO_VTU,    MESHIO_VTU_ASCII};
    meshio_options keep = {.log = NULL, .log_ctx = NULL, .source = 1};
    mesh_t *m = make_mesh(300, 500, 60);

    ASSERT_TRUE(m);
    for (size_t k = 0; k < sizeof fs / sizeof fs[0]; k++) {
        sink a = {0}, b = {0}, c = {0};
        mesh_t *r = NULL, *d;
        qdc_error err;
        const char *why = NULL;
        ASSERT_OK(meshio_write(m, fs[k], sink_write, &a, &err));
        ASSERT_OK(meshio_read_ex(a.b, a.n, fs[k], &keep, &r, &err));
        ASSERT_EQ_INT(meshio_source_format(r), fs[k]);
        ASSERT_TRUE(meshio_source_bytes(r, NULL) >= a.n + 8 * (size_t)r->nv);
        for (int32_t v = 0; v < r->nv; v++)
            memcpy(r->xyz + 3 * v, m->xyz + 3 * (m->nv - 1 - v), 24);
        ASSERT_TRUE(meshio_splices(r, fs[k], &why));
        ASSERT_OK(meshio_write(r, MESHIO_AUTO, sink_write, &b, &err)); /* the source's */
        d = mesh_dup(r);
        ASSERT_TRUE(d && !d->source);
        ASSERT_OK(meshio_write(d, fs[k], sink_write, &c, &err));
        if (b.n != c.n || memcmp(b.b, c.b, b.n) != 0)
            printf("  %s: spliced %zu bytes, written %zu\n", meshio_format_name(fs[k]),
                   b.n, c.n);
        ASSERT_TRUE(b.n == c.n && memcmp(b.b, c.b, b.n) == 0);
        /* another variant of the family is a conversion */
        ASSERT_TRUE(
            !meshio_splices(r, fs[k] == MESHIO_MEDIT ? MESHIO_VTK : MESHIO_MEDIT, &why));
        ASSERT_TRUE(strstr(why, "another format") != NULL);
        /* changed connectivity: not spliced, qdc's writer instead */
        r->tets[0] ^= r->tets[1];
        r->tets[1] ^= r->tets[0];
        r->tets[0] ^= r->tets[1];
        ASSERT_TRUE(!meshio_splices(r, fs[k], &why));
        ASSERT_TRUE(strstr(why, "connectivity") != NULL);
        free(b.b);
        b = (sink){0};
        mesh_free(d);
        d = mesh_dup(r);
        free(c.b);
        c = (sink){0};
        ASSERT_OK(meshio_write(r, fs[k], sink_write, &b, &err));
        ASSERT_OK(meshio_write(d, fs[k], sink_write, &c, &err));
        ASSERT_TRUE(b.n == c.n && memcmp(b.b, c.b, b.n) == 0);
        meshio_drop_source(r);
        ASSERT_EQ_INT(meshio_source_format(r), MESHIO_AUTO);
        mesh_free(d);
        mesh_free(r);
        free(a.b);
        free(b.b);
        free(c.b);
    }
    mesh_free(m);
}

/* The format a save picks: the source's variant for its family's extension. */
TEST(splice_save_format)
{
    meshio_options keep = {.log = NULL, .log_ctx = NULL, .source = 1};
    mesh_t *m = make_mesh(20, 30, 4), *r = NULL;
    sink a = {0};
    qdc_error err;

    ASSERT_TRUE(m);
    ASSERT_OK(meshio_write(m, MESHIO_GMSH41_BIN, sink_write, &a, &err));
    ASSERT_OK(meshio_read_ex(a.b, a.n, MESHIO_GMSH41, &keep, &r, &err));
    ASSERT_EQ_INT(meshio_source_format(r),
                  MESHIO_GMSH41_BIN); /* the file's, not the name */
    ASSERT_EQ_INT(meshio_save_format("o.msh", MESHIO_AUTO, r), MESHIO_GMSH41_BIN);
    ASSERT_EQ_INT(meshio_save_format("o.msh.gz", MESHIO_AUTO, r), MESHIO_GMSH41_BIN);
    ASSERT_EQ_INT(meshio_save_format("o.msh", MESHIO_GMSH22, r), MESHIO_GMSH22);
    ASSERT_EQ_INT(meshio_save_format("o.vtk", MESHIO_AUTO, r), MESHIO_VTK);
    ASSERT_EQ_INT(meshio_save_format("o.msh", MESHIO_AUTO, m), MESHIO_GMSH41);
    mesh_free(r);
    /* meshio_read keeps no source unless asked; a JSON or QMESH one never */
    ASSERT_OK(meshio_read(a.b, a.n, MESHIO_AUTO, &r, &err));
    ASSERT_TRUE(!r->source);
    mesh_free(r);
    free(a.b);
    a = (sink){0};
    ASSERT_OK(meshio_write(m, MESHIO_JSON, sink_write, &a, &err));
    ASSERT_OK(meshio_read_ex(a.b, a.n, MESHIO_AUTO, &keep, &r, &err));
    ASSERT_TRUE(!r->source);
    ASSERT_EQ_INT(meshio_write(r, MESHIO_AUTO, sink_write, &a, &err), QDC_EINVAL);
    mesh_free(r);
    free(a.b);
    mesh_free(m);
}

/* TetGen files (0-based, comments, attributes) saved back: the .node with the
 * moved coordinates only, the .ele unchanged; the same gzip-compressed. */
TEST(splice_tetgen_files)
{
    const char *node = "# nodes\n4 3 1 1\n0 0 0 0 0.5 7 # first\n1 1 0 0 0.5 8\n"
                       "2 0 1 0 0.5 9\n3 0 0 1 0.5 10\n";
    const char *ele = "1 4 2\n0 0 1 2 3 -4 0.25\n";
    const char *want = "# nodes\n4 3 1 1\n0 0 0 0 0.5 7 # first\n1 1 0 0 0.5 8\n"
                       "2 0 1 0 0.5 9\n3 0 0 0.25 0.5 10\n";
    char dir[] = "/tmp/qdc_test_splice_XXXXXX", path[256], *b;
    mesh_t *m = NULL;
    size_t n;
    qdc_error err;
    FILE *f;

    ASSERT_TRUE(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/in.node", dir);
    ASSERT_TRUE((f = fopen(path, "w")) && fputs(node, f) >= 0 && fclose(f) == 0);
    snprintf(path, sizeof path, "%s/in.ele", dir);
    ASSERT_TRUE((f = fopen(path, "w")) && fputs(ele, f) >= 0 && fclose(f) == 0);
    snprintf(path, sizeof path, "%s/in", dir);
    ASSERT_OK(meshio_load(path, MESHIO_TETGEN, &m, &err));
    ASSERT_EQ_INT(meshio_source_format(m), MESHIO_TETGEN);
    m->xyz[11] = 0.25;
    snprintf(path, sizeof path, "%s/out.node", dir);
    ASSERT_OK(meshio_save(path, MESHIO_AUTO, m, &err));
    b = read_file(path, &n);
    ASSERT_TRUE(b && n == strlen(want) && memcmp(b, want, n) == 0);
    qdc_free(b);
    snprintf(path, sizeof path, "%s/out.ele", dir);
    b = read_file(path, &n);
    ASSERT_TRUE(b && n == strlen(ele) && memcmp(b, ele, n) == 0);
    qdc_free(b);
    mesh_free(m);
    /* compressed, the two alike: either name finds the other, and a save as
     * .gz writes both so */
    snprintf(path, sizeof path, "gzip '%s/out.node' '%s/out.ele'", dir, dir);
    ASSERT_EQ_INT(system(path), 0);
    for (int k = 0; k < 2; k++) {
        mesh_t *r = NULL;
        snprintf(path, sizeof path, "%s/out.%s.gz", dir, k ? "node" : "ele");
        ASSERT_OK(meshio_load(path, MESHIO_AUTO, &r, &err));
        ASSERT_EQ_INT(meshio_source_format(r), MESHIO_TETGEN);
        ASSERT_EQ_INT(r->nt, 1);
        ASSERT_NEAR(r->xyz[11], 0.25, 0.0);
        if (k)
            mesh_free(r);
        else
            m = r;
    }
    snprintf(path, sizeof path, "%s/gz.ele.gz", dir);
    ASSERT_OK(meshio_save(path, MESHIO_AUTO, m, &err));
    mesh_free(m);
    snprintf(path, sizeof path, "gunzip '%s/gz.node.gz' '%s/gz.ele.gz'", dir, dir);
    ASSERT_EQ_INT(system(path), 0);
    snprintf(path, sizeof path, "%s/gz.node", dir);
    b = read_file(path, &n);
    ASSERT_TRUE(b && n == strlen(want) && memcmp(b, want, n) == 0);
    qdc_free(b);
    snprintf(path, sizeof path, "rm -rf '%s'", dir);
    ASSERT_EQ_INT(system(path), 0);
}

/* A parked source is freed during a run and read again for the write: the
 * same spliced file as without parking, gzip or not; a file that changed in
 * between is refused and the mesh then does not splice. */
TEST(splice_parked_source)
{
    const char *text =
        "MeshVersionFormatted 2\n# kept comment\nDimension 3\nVertices\n4\n"
        "0 0 0 7\n1 0 0 8\n0 1 0 9\n0 0 1 10\nTetrahedra\n1\n1 2 3 4 3\nEnd\n";
    char dir[] = "/tmp/qdc_test_park_XXXXXX", in[256], gz[300], a[256], b[256], cmd[600];
    meshio_options keep = {.log = NULL, .log_ctx = NULL, .source = 1};
    const char *why = NULL;
    mesh_t *m = NULL, *r = NULL;
    char *fa, *fb;
    size_t na, nb, held;
    qdc_error err;
    FILE *f;

    ASSERT_TRUE(mkdtemp(dir));
    snprintf(in, sizeof in, "%s/in.mesh", dir);
    snprintf(a, sizeof a, "%s/a.mesh", dir);
    snprintf(b, sizeof b, "%s/b.mesh", dir);
    ASSERT_TRUE((f = fopen(in, "w")) && fputs(text, f) >= 0 && fclose(f) == 0);
    for (int zipped = 0; zipped < 2; zipped++) {
        const char *src = zipped ? gz : in;
        if (zipped) {
            snprintf(gz, sizeof gz, "%s.gz", in);
            snprintf(cmd, sizeof cmd, "gzip -c '%s' > '%s'", in, gz);
            ASSERT_EQ_INT(system(cmd), 0);
        }
        /* the reference: the source kept all along */
        ASSERT_OK(meshio_load_ex(src, MESHIO_AUTO, &keep, &r, &err));
        r->xyz[3] = 0.5;
        ASSERT_OK(meshio_save(a, MESHIO_MEDIT, r, &err));
        mesh_free(r);
        ASSERT_OK(meshio_load_ex(src, MESHIO_AUTO, &keep, &m, &err));
        held = meshio_source_bytes(m, NULL);
        ASSERT_EQ_INT(meshio_park_source(m), 1);
        ASSERT_EQ_INT(meshio_park_source(m), 0);
        ASSERT_TRUE(meshio_source_bytes(m, NULL) + strlen(text) == held);
        ASSERT_EQ_INT(meshio_splices(m, MESHIO_MEDIT, &why), 0);
        ASSERT_TRUE(why && strstr(why, "not in memory"));
        m->xyz[3] = 0.5;
        ASSERT_OK(meshio_unpark_source(m, &err));
        ASSERT_EQ_INT(meshio_splices(m, MESHIO_MEDIT, NULL), 1);
        ASSERT_OK(meshio_save(b, MESHIO_MEDIT, m, &err));
        fa = read_file(a, &na);
        fb = read_file(b, &nb);
        ASSERT_TRUE(fa && fb && na == nb && memcmp(fa, fb, na) == 0);
        ASSERT_TRUE(strstr(fb, "# kept comment") && strstr(fb, "0.5 0 0 8"));
        qdc_free(fa);
        qdc_free(fb);
        mesh_free(m);
    }
    /* changed while parked: same length, one byte other */
    ASSERT_OK(meshio_load_ex(in, MESHIO_AUTO, &keep, &m, &err));
    ASSERT_EQ_INT(meshio_park_source(m), 1);
    ASSERT_TRUE((f = fopen(in, "r+")) && fseek(f, 25, SEEK_SET) == 0 &&
                fputc('K', f) == 'K' && fclose(f) == 0);
    ASSERT_EQ_INT(meshio_unpark_source(m, &err), QDC_EIO);
    ASSERT_TRUE(strstr(err.msg, "changed since it was read") != NULL);
    ASSERT_EQ_INT(meshio_splices(m, MESHIO_MEDIT, NULL), 0);
    mesh_free(m);
    /* gone while parked */
    ASSERT_OK(meshio_load_ex(in, MESHIO_AUTO, &keep, &m, &err));
    ASSERT_EQ_INT(meshio_park_source(m), 1);
    ASSERT_EQ_INT(remove(in), 0);
    ASSERT_EQ_INT(meshio_unpark_source(m, &err), QDC_EIO);
    mesh_free(m);
    /* a mesh read from a buffer has nothing to park */
    ASSERT_OK(meshio_read_ex(text, strlen(text), MESHIO_AUTO, &keep, &m, &err));
    ASSERT_EQ_INT(meshio_park_source(m), 0);
    ASSERT_OK(meshio_unpark_source(m, &err));
    ASSERT_EQ_INT(meshio_splices(m, MESHIO_MEDIT, NULL), 1);
    mesh_free(m);
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    ASSERT_EQ_INT(system(cmd), 0);
}

/* ---- corpus and fuzz replay ---- */

TEST(malformed_corpus)
{
    int n, bad = run_corpus(NULL, &n);

    printf("  # %d corpus cases\n", n);
    ASSERT_TRUE(bad >= 0);
    ASSERT_TRUE(n >= 20);
    ASSERT_EQ_INT(bad, 0);
}

TEST(fuzz_replay)
{
    int n, bad = replay_fuzz("meshio", replay_meshio, &n);

    printf("  # %d fuzz inputs replayed\n", n);
    ASSERT_TRUE(n > 0);
    ASSERT_EQ_INT(bad, 0);
}

TEST_MAIN("meshio", T(roundtrip_medit), T(medit_large_sections), T(roundtrip_qmesh),
          T(roundtrip_json), T(roundtrip_empty), T(roundtrip_files), T(save_bad_dir),
          T(write_failure_is_eio), T(medit_features), T(medit_error_position),
          T(medit_deferred_error_position), T(json_features), T(json_not_nul_terminated),
          T(tetgen_read), T(huge_counts_fail_fast), T(formats_and_sniffing),
          T(format_table), T(dev_cube), T(dev_speed), T(qmesh_1m_tets_speed),
          T(allocation_failures), T(splice_equals_writer), T(splice_save_format),
          T(splice_tetgen_files), T(splice_parked_source), T(malformed_corpus),
          T(fuzz_replay))
