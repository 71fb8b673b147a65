/* tri_edges.h - the edges of a set of triangles, paired: every triangle's
 * three edges as (lo, hi) vertex pairs, sorted so that the triangles sharing
 * an edge sit next to each other. What the sliding boundary needs for its
 * feature edges and the report for the surface's angles at its edges.
 * Thread-safe, no global state. */
#ifndef QDC_TRI_EDGES_H
#define QDC_TRI_EDGES_H

#include "core/base.h"

#include <stddef.h>
#include <stdint.h>

/* Triangle tri's edge from its vertex k to vertex (k + 1) % 3, as lo < hi
 * (lo == hi on a triangle with a repeated vertex). */
typedef struct {
    int32_t lo, hi, tri, k;
} tri_edge;

/* The 3 * ntri edges of tris (ntri triangles of vertices in [0, nv)) sorted
 * by (lo, hi, tri, k), into *out (qdc_free it); a counting sort by lo, each
 * vertex's few edges then sorted in place (qsort took 0.25 s on a surface of
 * 833k triangles), the buckets in parallel. QDC_ENOMEM (*out NULL). */
qdc_status tri_edges_sorted(const int32_t *tris, int32_t ntri, int32_t nv,
                            tri_edge **out);

/* The end of the run of edges equal to e[i] in (lo, hi): the j > i with e[j]
 * the first of another edge, or n. */
size_t tri_edges_run(const tri_edge *e, size_t n, size_t i);

#endif
