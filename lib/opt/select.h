/* select.h - which vertices and tets a pass visits: the movable vertices of
 * the worst tets, worst first, coloured into classes of independent vertices
 * (no two share a tet, so a class moves in parallel); the k-th smallest of a
 * per-tet value; the few worst tets. Used by the finishing sweeps (finish.c)
 * and the angle polish (angle.c). Thread-safe: pure over caller arrays. */
#ifndef QDC_SELECT_H
#define QDC_SELECT_H

#include "core/mesh_int.h"

typedef struct {
    double q;
    int32_t v;
} vq_pair;

/* The class of vertices that found no free colour: not independent, swept in
 * one thread. Classes below it are independent. */
#define COLOUR_SHARED 64

/* The tets select_worst_tets returns (at most). */
#define SELECT_WORST_TETS 32

/* The movable vertices v with vworst[v] < 2 (the value of v's worst tet in
 * the pass's set; 2: none), worst first, then arranged class by class: class
 * c is (*list_out)[start[c] .. start[c + 1]), independent classes in vertex
 * order, the shared class (COLOUR_SHARED) worst first. *list_out (*n_out
 * entries) and *start_out are the caller's to free. Returns the number of
 * classes, or -1 if out of memory (nothing to free then). */
int32_t select_vertices(const mesh_topo *tp, const uint8_t *movable, const double *vworst,
                        vq_pair **list_out, int32_t *n_out, int32_t **start_out);

/* The k-th smallest (0-based) of a[0..n), whose values lie in [lo, hi], with
 * a unchanged; if sum, the sum of the k + 1 smallest goes there (in one
 * serial pass: independent of the thread count). QDC_ENOMEM if out of
 * memory. */
qdc_status select_kth(const double *a, int32_t n, int32_t k, double lo, double hi,
                      double *kth, double *sum);

/* The SELECT_WORST_TETS tets of smallest val (fewer if the mesh has fewer)
 * into out, sorted, ties by index. Returns how many. */
int32_t select_worst_tets(const double *val, int32_t nt, vq_pair *out);

#endif
