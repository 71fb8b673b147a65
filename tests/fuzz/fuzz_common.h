/* fuzz_common.h - shared by the libFuzzer targets: read one buffer in one
 * format, check the status contract, and for what parses, write-then-read
 * must give the same mesh back. Traps on any violation. */
#ifndef QDC_FUZZ_COMMON_H
#define QDC_FUZZ_COMMON_H

#include "../unit/testio.h" /* sink, sink_write */
#include "qdc.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static int same(const void *a, const void *b, size_t n)
{
    return n == 0 || (!a && !b) || (a && b && memcmp(a, b, n) == 0);
}

/* What each format carries: QMESH and JSON drop vref and triangles; Gmsh and
 * VTK keep triangles and their tags; DOLFIN keeps vertices and tets only;
 * Medit binary keeps what Medit does, triangle refs too; the writers of the
 * formats of other FE tools (Abaqus, Netgen, MSH 1, Nastran, I-DEAS) keep
 * the coordinates, the tets with their tags and the triangles, in an order
 * and a tagging of their own (same_fe); MED's writer (the frames of qdc-h5
 * med-new) keeps them all in order, its families read back as the tags; a
 * format without a writer of qdc's own would refuse a mesh without a
 * source. */
static int fe_writer(meshio_format f)
{
    return f == MESHIO_ABAQUS || f == MESHIO_NETGEN || f == MESHIO_MSH1 ||
           f == MESHIO_BDF || f == MESHIO_UNV;
}

static int rec_cmp(const void *x, const void *y)
{
    return memcmp(x, y, 4 * sizeof(int32_t));
}

/* The n records of k ints of a and of b (with tag arrays ta, tb appended
 * when both are given) the same as multisets. */
static int same_set(const int32_t *a, const int32_t *ta, const int32_t *b,
                    const int32_t *tb, int32_t n, int k)
{
    int w = ta && tb ? k + 1 : k, ok;
    int32_t *ra = calloc((size_t)n * 4 + 1, sizeof *ra),
            *rb = calloc((size_t)n * 4 + 1, 4);

    ok = ra && rb;
    for (int32_t i = 0; ok && i < n; i++) {
        memcpy(ra + 4 * i, a + k * (size_t)i, 4 * (size_t)k);
        memcpy(rb + 4 * i, b + k * (size_t)i, 4 * (size_t)k);
        if (w > k) {
            ra[4 * i + k] = ta[i];
            rb[4 * i + k] = tb[i];
        }
    }
    if (ok) {
        qsort(ra, (size_t)n, 16, rec_cmp);
        qsort(rb, (size_t)n, 16, rec_cmp);
        ok = memcmp(ra, rb, 16 * (size_t)n) == 0;
    }
    free(ra);
    free(rb);
    return ok;
}

/* b, m written by an FE tool's format and read back: the same coordinates,
 * tets (with their regions when both have them) and triangles (with their
 * refs when both have them), in any order. */
static int same_fe(const mesh_t *m, const mesh_t *b)
{
    return b->nv == m->nv && b->nt == m->nt && b->ntri == m->ntri &&
           same(b->xyz, m->xyz, 24 * (size_t)m->nv) &&
           same_set(m->tets, m->region, b->tets, b->region, m->nt, 4) &&
           same_set(m->tris, m->tri_ref, b->tris, b->tri_ref, m->ntri, 3);
}

/* b's point data the same values as m's when f's writer keeps them: array
 * for array in order (Gmsh: only when the counts agree, as a view written
 * twice under one name reads back as its last time step). */
static int same_pdata(const mesh_t *m, const mesh_t *b, meshio_format f)
{
    int gmsh = f == MESHIO_GMSH41 || f == MESHIO_GMSH41_BIN || f == MESHIO_GMSH22 ||
               f == MESHIO_GMSH22_BIN || f == MESHIO_GMSH40;
    int32_t n = m->pdata ? m->pdata->n : 0, nb = b->pdata ? b->pdata->n : 0;

    if (!meshio_writes_pdata(f))
        return 1;
    if (n != nb)
        return gmsh && n > nb;
    for (int32_t i = 0; i < n; i++) {
        const mesh_parray *x = &m->pdata->a[i], *y = &b->pdata->a[i];
        if (x->ncomp != y->ncomp ||
            !same(x->v, y->v, 8 * (size_t)m->nv * (size_t)x->ncomp))
            return 0;
    }
    return 1;
}

static void check_roundtrip(const mesh_t *m, meshio_format f)
{
    sink s = {0};
    mesh_t *b = NULL;
    int text = f == MESHIO_MEDIT || f == MESHIO_MESHB,
        tris = text || (f >= MESHIO_GMSH41 && f != MESHIO_DOLFIN);
    int regions = f != MESHIO_DOLFIN;
    /* held vertices (Gmsh $Periodic pairs) are written by QMESH and JSON only */
    int keeps_fixed = f == MESHIO_QMESH || f == MESHIO_JSON;

    if (!meshio_has_writer(f)) {
        if (meshio_write(m, f, sink_write, &s, NULL) == QDC_OK) /* no source: refused */
            __builtin_trap();
        free(s.b);
        return;
    }

    if (meshio_write(m, f, sink_write, &s, NULL) != QDC_OK ||
        meshio_read(s.b, s.n, f, &b, NULL) != QDC_OK)
        __builtin_trap();
    if (fe_writer(f)) {
        if (!same_fe(m, b))
            __builtin_trap();
    } else if (b->nv != m->nv || b->nt != m->nt ||
               !same(b->xyz, m->xyz, 24 * (size_t)m->nv) ||
               !same(b->tets, m->tets, 16 * (size_t)m->nt) ||
               (regions && !same(b->region, m->region, 4 * (size_t)m->nt)) ||
               (keeps_fixed && !same(b->fixed, m->fixed, (size_t)m->nv)) ||
               (text && !same(b->vref, m->vref, 4 * (size_t)m->nv)) ||
               (tris &&
                (b->ntri != m->ntri || !same(b->tris, m->tris, 12 * (size_t)m->ntri) ||
                 (f != MESHIO_MEDIT &&
                  !same(b->tri_ref, m->tri_ref, 4 * (size_t)m->ntri)))) ||
               !same_pdata(m, b, f))
        __builtin_trap();
    mesh_free(b);
    free(s.b);
}

/* Read buf as format f (TETGEN: first half .node, second .ele); check the
 * status contract and, for a mesh, the round trip through f. */
static void fuzz_read(const char *buf, size_t size, meshio_format f)
{
    mesh_t *m = NULL;
    qdc_error err;
    qdc_status st;

    if (f == MESHIO_TETGEN)
        st = meshio_read_tetgen(buf, size / 2, buf + size / 2, size - size / 2, &m, &err);
    else
        st = meshio_read(buf, size, f, &m, &err);
    if ((unsigned)st >= QDC_STATUS_COUNT || (st == QDC_OK) != (m != NULL) ||
        (st != QDC_OK && err.status != st))
        __builtin_trap();
    if (m && f != MESHIO_AUTO && f != MESHIO_TETGEN)
        check_roundtrip(m, f);
    mesh_free(m);
    /* kept as the source: written back unchanged and with moved coordinates */
    if (f != MESHIO_TETGEN && splice_check(buf, size, f))
        __builtin_trap();
}

#endif
