/* fuzz_meshio.c - libFuzzer target: every reader on the input, and for what
 * parses, write-then-read must give the same mesh back.
 *
 *   clang -g -O1 -fsanitize=fuzzer,address,undefined -Ilib tests/fuzz/fuzz_meshio.c \
 *       lib/base.c lib/mesh.c lib/meshio.c -lm -o build/fuzz_meshio
 *   build/fuzz_meshio -max_len=4096 build/corpus tests/fuzz/seeds/meshio
 *
 * TetGen takes the first half of the input as .node and the second as .ele.
 * Crashes go to tests/fuzz/crashes/meshio/, which test_meshio replays. */
#include "meshio.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    char *b;
    size_t n, cap;
} sink;

static int sink_write(void *ctx, const void *d, size_t len)
{
    sink *s = ctx;

    if (s->n + len > s->cap) {
        size_t cap = s->cap ? 2 * s->cap : 4096;
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

static int same(const void *a, const void *b, size_t n)
{
    return n == 0 || (!a && !b) || (a && b && memcmp(a, b, n) == 0);
}

/* What each format carries: QMESH and JSON drop vref and triangles. */
static void check_roundtrip(const mesh_t *m, meshio_format f)
{
    sink s = {0};
    mesh_t *b = NULL;
    int text = f == MESHIO_MEDIT;

    if (meshio_write(m, f, sink_write, &s, NULL) != QDC_OK ||
        meshio_read(s.b, s.n, f, &b, NULL) != QDC_OK)
        __builtin_trap();
    if (b->nv != m->nv || b->nt != m->nt || !same(b->xyz, m->xyz, 24 * (size_t)m->nv) ||
        !same(b->tets, m->tets, 16 * (size_t)m->nt) ||
        !same(b->region, m->region, 4 * (size_t)m->nt) ||
        !same(b->fixed, m->fixed, (size_t)m->nv) ||
        (text && (!same(b->vref, m->vref, 4 * (size_t)m->nv) || b->ntri != m->ntri ||
                  !same(b->tris, m->tris, 12 * (size_t)m->ntri))))
        __builtin_trap();
    mesh_free(b);
    free(s.b);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *buf = (const char *)data;
    mesh_t *m = NULL;
    qdc_error err;

    for (int f = MESHIO_AUTO; f < MESHIO_FORMAT_COUNT; f++) {
        qdc_status st;
        if (f == MESHIO_TETGEN)
            st = meshio_read_tetgen(buf, size / 2, buf + size / 2, size - size / 2, &m,
                                    &err);
        else
            st = meshio_read(buf, size, (meshio_format)f, &m, &err);
        if ((unsigned)st >= QDC_STATUS_COUNT || (st == QDC_OK) != (m != NULL) ||
            (st != QDC_OK && err.status != st))
            __builtin_trap();
        if (m && f != MESHIO_AUTO && f != MESHIO_TETGEN) {
            /* Medit files may carry refs the binary formats drop: compare in kind */
            check_roundtrip(m, (meshio_format)f);
        }
        mesh_free(m);
        m = NULL;
    }
    return 0;
}
