/* test_gz.c - gzip-compressed mesh files (io/gz.h): round trips through the
 * writer and the reader, concatenated members, truncated and corrupt streams,
 * meshio reading a gzip buffer of any format, and the limits on what
 * compressed input inflates to (gzip and VTU zlib bombs). */
#include "io/gz.h"
#include "qdc.h"
#include "testlib.h"
#include "testmesh.h"

#include <stdio.h>
#include <string.h>
#include <zlib.h>

typedef struct {
    char *b;
    size_t n, cap;
} membuf;

static int mem_sink(void *ctx, const void *data, size_t len)
{
    membuf *m = ctx;
    if (m->n + len > m->cap) {
        size_t cap = (m->n + len) * 2;
        char *t = realloc(m->b, cap);
        if (!t)
            return -1;
        m->b = t;
        m->cap = cap;
    }
    memcpy(m->b + m->n, data, len);
    m->n += len;
    return 0;
}

static void deflate_to(membuf *m, const char *text, size_t len)
{
    gz_writer *w = gz_writer_new(mem_sink, m);
    /* in pieces, as the mesh writers call it */
    for (size_t i = 0; w && i < len; i += 1000)
        gz_write(w, text + i, len - i < 1000 ? len - i : 1000);
    gz_writer_finish(w);
}

TEST(round_trip_and_members)
{
    char text[20000];
    membuf m = {0};
    char *out = NULL;
    size_t n = 0;
    for (size_t i = 0; i < sizeof text; i++)
        text[i] = (char)('a' + (i * 7 + i / 13) % 26);
    deflate_to(&m, text, sizeof text);
    ASSERT_TRUE(gz_is_gzip(m.b, m.n));
    ASSERT_TRUE(m.n < sizeof text);
    ASSERT_OK(gz_inflate(m.b, m.n, &out, &n, NULL));
    ASSERT_EQ_INT(n, sizeof text);
    ASSERT_TRUE(memcmp(out, text, n) == 0 && out[n] == 0);
    qdc_free(out);
    /* two members one after the other are one file (gzip -c a b) */
    deflate_to(&m, text, 500);
    ASSERT_OK(gz_inflate(m.b, m.n, &out, &n, NULL));
    ASSERT_EQ_INT(n, sizeof text + 500);
    ASSERT_TRUE(memcmp(out + sizeof text, text, 500) == 0);
    qdc_free(out);
    free(m.b);
}

TEST(truncated_and_corrupt)
{
    char text[5000];
    membuf m = {0};
    char *out = NULL;
    size_t n = 0;
    qdc_error e;
    memset(text, 'x', sizeof text);
    deflate_to(&m, text, sizeof text);
    ASSERT_EQ_INT(gz_inflate(m.b, m.n / 2, &out, &n, &e), QDC_EPARSE);
    ASSERT_TRUE(strstr(e.msg, "too early") != NULL && out == NULL);
    m.b[12] ^= 0x55;
    m.b[13] ^= 0x55;
    ASSERT_EQ_INT(gz_inflate(m.b, m.n, &out, &n, &e), QDC_EPARSE);
    ASSERT_EQ_INT(gz_inflate("\x1f\x8b", 2, &out, &n, &e), QDC_EPARSE);
    free(m.b);
}

TEST(meshio_reads_gzip_of_any_format)
{
    mesh_t *g = tm_grid(2, 0), *back = NULL;
    static const meshio_format fmts[] = {MESHIO_MEDIT, MESHIO_GMSH41, MESHIO_VTU,
                                         MESHIO_QMESH};
    for (size_t f = 0; f < sizeof fmts / sizeof fmts[0]; f++) {
        membuf plain = {0}, z = {0};
        ASSERT_OK(meshio_write(g, fmts[f], mem_sink, &plain, NULL));
        deflate_to(&z, plain.b, plain.n);
        ASSERT_OK(meshio_read(z.b, z.n, MESHIO_AUTO, &back, NULL));
        ASSERT_EQ_INT(back->nv, g->nv);
        ASSERT_EQ_INT(back->nt, g->nt);
        ASSERT_TRUE(memcmp(back->tets, g->tets, 16 * (size_t)g->nt) == 0);
        for (int32_t i = 0; i < 3 * g->nv; i++)
            ASSERT_NEAR(back->xyz[i], g->xyz[i], 1e-15);
        mesh_free(back);
        free(plain.b);
        free(z.b);
    }
    mesh_free(g);
}

TEST(budget)
{
    /* no ratio: the cap, never past GZ_MAX_OUT */
    ASSERT_EQ_INT(gz_budget(1000, 0, 0), GZ_MAX_OUT);
    ASSERT_EQ_INT(gz_budget(1000, 5000, 0), 5000);
    ASSERT_EQ_INT(gz_budget(1000, GZ_MAX_OUT * 2, 0), GZ_MAX_OUT);
    /* a ratio: max_ratio * len, the floor below it, the cap above it */
    ASSERT_EQ_INT(gz_budget(1000, 0, 100), GZ_RATIO_FLOOR);
    ASSERT_EQ_INT(gz_budget(1 << 20, 0, 100), (size_t)100 << 20);
    ASSERT_EQ_INT(gz_budget(1 << 20, (size_t)50 << 20, 100), (size_t)50 << 20);
    ASSERT_EQ_INT(gz_budget((size_t)1 << 40, 0, 100), GZ_MAX_OUT);
}

/* A gzip stream of n zeros (deflated in pieces of 1 MiB). */
static void zeros_gz(membuf *m, size_t n)
{
    static char z[1 << 20];
    gz_writer *w = gz_writer_new(mem_sink, m);
    for (size_t i = 0; w && i < n; i += sizeof z)
        gz_write(w, z, n - i < sizeof z ? n - i : sizeof z);
    gz_writer_finish(w);
}

TEST(bomb_stops_at_the_limit)
{
    membuf m = {0};
    char *out = NULL, head[16];
    size_t n = 0;
    qdc_error e;
    zeros_gz(&m, (size_t)64 << 20);
    /* 64 MiB of zeros deflate about 1000 to 1 */
    ASSERT_TRUE(m.n < ((size_t)64 << 20) / 500);
    ASSERT_EQ_INT(gz_inflate_max(m.b, m.n, (size_t)1 << 20, &out, &n, &e), QDC_ETOOBIG);
    ASSERT_TRUE(out == NULL && n == 0 && strstr(e.msg, "1048576") != NULL);
    ASSERT_EQ_INT(gz_inflate_max(m.b, m.n, ((size_t)64 << 20) - 1, &out, &n, &e),
                  QDC_ETOOBIG);
    ASSERT_OK(gz_inflate_max(m.b, m.n, (size_t)64 << 20, &out, &n, &e));
    ASSERT_EQ_INT(n, (size_t)64 << 20);
    qdc_free(out);
    /* the ratio cap stops it too: 100 times a stream of ~65 kB */
    ASSERT_EQ_INT(gz_inflate_max(m.b, m.n, gz_budget(m.n, 0, 100), &out, &n, &e),
                  QDC_ETOOBIG);
    /* the head, to sniff a format before choosing a limit */
    ASSERT_EQ_INT(gz_head(m.b, m.n, head, sizeof head), sizeof head);
    ASSERT_TRUE(head[0] == 0 && head[15] == 0);
    ASSERT_EQ_INT(gz_head("plain", 5, head, sizeof head), 0);
    free(m.b);
}

TEST(meshio_limits_and_nested_gzip)
{
    mesh_t *g = tm_grid(3, 0), *back = NULL;
    membuf plain = {0}, z = {0}, zz = {0};
    meshio_options o = {0};
    qdc_error e;
    ASSERT_OK(meshio_write(g, MESHIO_MEDIT, mem_sink, &plain, NULL));
    deflate_to(&z, plain.b, plain.n);
    o.max_bytes = plain.n;
    ASSERT_OK(meshio_read_ex(z.b, z.n, MESHIO_AUTO, &o, &back, &e));
    mesh_free(back);
    o.max_bytes = plain.n - 1;
    ASSERT_EQ_INT(meshio_read_ex(z.b, z.n, MESHIO_AUTO, &o, &back, &e), QDC_ETOOBIG);
    ASSERT_TRUE(back == NULL);
    /* gzip inside gzip is refused, not inflated twice */
    deflate_to(&zz, z.b, z.n);
    ASSERT_EQ_INT(meshio_read_ex(zz.b, zz.n, MESHIO_AUTO, NULL, &back, &e), QDC_EPARSE);
    ASSERT_TRUE(strstr(e.msg, "twice") != NULL);
    free(plain.b);
    free(z.b);
    free(zz.b);
    mesh_free(g);
}

/* A VTU file of np points at the origin (zlib blocks of 1 MiB of zeros, one
 * compressed block repeated) and one tet: a zlib bomb of appended data. */
static char *vtu_zlib_bomb(size_t np, size_t *len)
{
    static unsigned char zero[1 << 20];
    unsigned char blk[4096];
    uLongf bl = sizeof blk;
    size_t want = np * 24, nb = (want + sizeof zero - 1) / sizeof zero;
    size_t last = want - (nb - 1) * sizeof zero, cap = 4096 + nb * (8 + sizeof blk);
    char *b = malloc(cap), *p;
    uint64_t w;
    if (!b || compress2(blk, &bl, zero, sizeof zero, 9) != Z_OK || last != sizeof zero) {
        free(b);
        return NULL;
    }
    p = b + snprintf(b, cap,
                     "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" "
                     "version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\" "
                     "compressor=\"vtkZLibDataCompressor\">\n<UnstructuredGrid>\n"
                     "<Piece NumberOfPoints=\"%zu\" NumberOfCells=\"1\">\n<Points>\n"
                     "<DataArray type=\"Float64\" NumberOfComponents=\"3\" "
                     "format=\"appended\" offset=\"0\"/>\n</Points>\n<Cells>\n"
                     "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
                     "0 1 2 3</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" "
                     "format=\"ascii\">4</DataArray>\n<DataArray type=\"UInt8\" "
                     "Name=\"types\" format=\"ascii\">10</DataArray>\n</Cells>\n"
                     "</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_",
                     np);
    uint64_t words[3] = {nb, sizeof zero, 0};
    for (int k = 0; k < 3; k++) {
        w = words[k];
        memcpy(p, &w, 8);
        p += 8;
    }
    for (size_t k = 0; k < nb; k++) {
        w = bl;
        memcpy(p, &w, 8);
        p += 8;
    }
    for (size_t k = 0; k < nb; k++) {
        memcpy(p, blk, bl);
        p += bl;
    }
    p += sprintf(p, "\n</AppendedData>\n</VTKFile>\n");
    *len = (size_t)(p - b);
    return b;
}

TEST(vtu_zlib_bomb_stops_at_the_limit)
{
    size_t len = 0;
    char *b = vtu_zlib_bomb((size_t)1 << 22, &len); /* 96 MiB of coordinates */
    meshio_options o = {0};
    mesh_t *m = NULL;
    qdc_error e;
    ASSERT_TRUE(b != NULL);
    ASSERT_TRUE(len < ((size_t)96 << 20) / 500);
    o.max_ratio = 100;
    ASSERT_EQ_INT(meshio_read_ex(b, len, MESHIO_VTU, &o, &m, &e), QDC_ETOOBIG);
    ASSERT_TRUE(m == NULL && strstr(e.msg, "zlib arrays") != NULL);
    o.max_ratio = 0;
    o.max_bytes = (size_t)8 << 20;
    ASSERT_EQ_INT(meshio_read_ex(b, len, MESHIO_VTU, &o, &m, &e), QDC_ETOOBIG);
    /* within the budget it is read: 4M points, one tet */
    o.max_bytes = (size_t)96 << 20;
    ASSERT_OK(meshio_read_ex(b, len, MESHIO_VTU, &o, &m, &e));
    ASSERT_EQ_INT(m->nv, 1 << 22);
    ASSERT_EQ_INT(m->nt, 1);
    mesh_free(m);
    free(b);
}

TEST_MAIN("gz", T(round_trip_and_members), T(truncated_and_corrupt),
          T(meshio_reads_gzip_of_any_format), T(budget), T(bomb_stops_at_the_limit),
          T(meshio_limits_and_nested_gzip), T(vtu_zlib_bomb_stops_at_the_limit))
