/* bderr_int.h - the internal part of bderr.h: a BVH over triangles and exact
 * closest-point queries (the sliding boundary mode and the Hausdorff distance).
 * Thread-safe: no global state; a built BVH may be queried by several threads. */
#ifndef QDC_BDERR_INT_H
#define QDC_BDERR_INT_H

#include "core/base.h"
#include "geom/bderr.h"

#include <stdint.h>

/* bderr_surfaces measures up to this many samples of a side in the order of
 * the BVH's leaves (each costs 32 bytes while it runs); more in the order they
 * are drawn. The same distances either way. */
#define BDERR_SORT_MAX (INT64_C(1) << 23)

/* A BVH over triangles (xyz: 3 doubles per vertex, tris: 3 indices per triangle).
 * It copies the triangles' indices but reads the coordinates from xyz, which
 * must stay, unchanged, as long as the BVH does. */
typedef struct bderr_bvh bderr_bvh;

qdc_status bderr_bvh_build(const double *xyz, int32_t nv, const int32_t *tris,
                           int32_t ntri, bderr_bvh **out, qdc_error *err);
void bderr_bvh_free(bderr_bvh *b);
/* A BVH over src's triangles with the coordinates xyz (nv vertices) instead:
 * src's tree with its boxes recomputed, far cheaper than bderr_bvh_build and
 * as good while the vertices have moved less than the triangles' size (an
 * optimized mesh against its input). Queries give the same answers as a
 * BVH built on xyz. xyz must stay as for bderr_bvh_build; src is only read.
 * QDC_EINVAL (a NULL argument, a vertex out of [0, nv), a coordinate not
 * finite), QDC_ENOMEM. */
qdc_status bderr_bvh_refit(const bderr_bvh *src, const double *xyz, int32_t nv,
                           bderr_bvh **out, qdc_error *err);

/* Closest point on the surface to p: distance, the point and the triangle index.
 * cp and tri may be NULL. A BVH with no triangles returns +inf. */
double bderr_bvh_closest(const bderr_bvh *b, const double p[3], double cp[3],
                         int32_t *tri);

/* The same, starting from the caller's triangle near (an index into the tris
 * given to bderr_bvh_build, or -1): the same answer, found faster when p is
 * close to that triangle. */
double bderr_bvh_closest_near(const bderr_bvh *b, const double p[3], int32_t near,
                              double cp[3], int32_t *tri);

/* Closest distances from n points at once (p: 3 doubles each) whose starting
 * triangles near[] (the caller's indices) all lie in one leaf of b, as
 * bderr_bvh_leaf_of tells: d[k] is bderr_bvh_closest_near's answer for point
 * k, the same bits, with the tree walked once for the group (the points of one
 * surface against its optimized copy lie within a few triangles of their own:
 * the boxes beside the leaf's path are tested once for all). 1 if done; 0 (d
 * not set) if n > BDERR_GROUP_MAX, the triangles are not in one leaf or a
 * point is not finite. */
#define BDERR_GROUP_MAX 64
int bderr_bvh_closest_group(const bderr_bvh *b, int32_t n, const double *p,
                            const int32_t *near, double *d);
/* The leaf of b holding the caller's triangle tri, -1 if out of range. */
int32_t bderr_bvh_leaf_of(const bderr_bvh *b, int32_t tri);
/* The number of triangles of b (0 if b is NULL). */
int32_t bderr_bvh_size(const bderr_bvh *b);
/* The position of the caller's triangle tri among b's leaves: triangles close
 * in position are close in space. -1 if tri is out of range. */
int32_t bderr_bvh_position(const bderr_bvh *b, int32_t tri);

/* Exact closest point on triangle (a,b,c) to p (Ericson 5.1.5); returns the distance. */
double bderr_point_triangle(const double p[3], const double a[3], const double b[3],
                            const double c[3], double cp[3]);

/* Exact closest point on segment [a, b] to p; returns the distance. */
double bderr_point_segment(const double p[3], const double a[3], const double b[3],
                           double cp[3]);

#endif
