/* test_gz.c - gzip-compressed mesh files (io/gz.h): round trips through the
 * writer and the reader, concatenated members, truncated and corrupt streams,
 * and meshio reading a gzip buffer of any format. */
#include "io/gz.h"
#include "qdc.h"
#include "testlib.h"
#include "testmesh.h"

#include <string.h>

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

TEST_MAIN("gz", T(round_trip_and_members), T(truncated_and_corrupt),
          T(meshio_reads_gzip_of_any_format))
