/* tri_edges.c - see tri_edges.h. */
#include "core/tri_edges.h"

#include "core/base_int.h"

#include <string.h>

static int edge_less(const tri_edge *p, const tri_edge *q)
{
    if (p->lo != q->lo)
        return p->lo < q->lo;
    if (p->hi != q->hi)
        return p->hi < q->hi;
    if (p->tri != q->tri)
        return p->tri < q->tri;
    return p->k < q->k;
}

/* Insertion sort of one vertex's bucket (a dozen edges or so). */
static void sort_bucket(tri_edge *b, size_t n)
{
    for (size_t i = 1; i < n; i++) {
        tri_edge key = b[i];
        size_t j = i;
        while (j > 0 && edge_less(&key, &b[j - 1])) {
            b[j] = b[j - 1];
            j--;
        }
        b[j] = key;
    }
}

qdc_status tri_edges_sorted(const int32_t *tris, int32_t ntri, int32_t nv, tri_edge **out)
{
    size_t ne = 3 * (size_t)(ntri > 0 ? ntri : 0);
    size_t *start = qdc_calloc((size_t)nv + 2, sizeof(size_t));
    tri_edge *e = qdc_mallocn(ne + 1, sizeof *e);

    *out = NULL;
    if (!start || !e) {
        qdc_free(start);
        qdc_free(e);
        return QDC_ENOMEM;
    }
    for (int32_t i = 0; i < ntri; i++)
        for (int k = 0; k < 3; k++) {
            int32_t a = tris[3 * (size_t)i + k], b = tris[3 * (size_t)i + (k + 1) % 3];
            start[(a < b ? a : b) + 2]++;
        }
    for (int32_t v = 0; v < nv; v++)
        start[v + 2] += start[v + 1];
    for (int32_t i = 0; i < ntri; i++) {
        for (int k = 0; k < 3; k++) {
            int32_t a = tris[3 * (size_t)i + k], b = tris[3 * (size_t)i + (k + 1) % 3];
            int32_t lo = a < b ? a : b;
            e[start[lo + 1]++] = (tri_edge){lo, a < b ? b : a, i, k};
        }
    }
    /* now vertex v's bucket is e[start[v] .. start[v + 1]) */
#pragma omp parallel for schedule(dynamic, 4096)
    for (int32_t v = 0; v < nv; v++) /* each bucket on its own: any thread count */
        sort_bucket(e + start[v], start[v + 1] - start[v]);
    qdc_free(start);
    *out = e;
    return QDC_OK;
}

size_t tri_edges_run(const tri_edge *e, size_t n, size_t i)
{
    size_t j = i + 1;

    while (j < n && e[j].lo == e[i].lo && e[j].hi == e[i].hi)
        j++;
    return j;
}
