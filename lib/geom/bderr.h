/* bderr.h - boundary error (docs/method.md §9): symmetric Hausdorff distance between two
 * triangle surfaces with exact point-triangle distances through a BVH over
 * Metro-style samples (every vertex, every face centroid, plus area-weighted
 * random points from a fixed seed), and closest-point queries used by the
 * sliding boundary mode. Thread-safe: no global state. */
#ifndef QDC_BDERR_H
#define QDC_BDERR_H

#include "core/base.h"
#include "core/mesh.h"

/* A BVH over triangles (xyz: 3 doubles per vertex, tris: 3 indices per triangle).
 * It copies the triangles' indices but reads the coordinates from xyz, which
 * must stay, unchanged, as long as the BVH does. */
typedef struct bderr_bvh bderr_bvh;

qdc_status bderr_bvh_build(const double *xyz, int32_t nv, const int32_t *tris,
                           int32_t ntri, bderr_bvh **out, qdc_error *err);
void bderr_bvh_free(bderr_bvh *b);

/* Closest point on the surface to p: distance, the point and the triangle index.
 * cp and tri may be NULL. A BVH with no triangles returns +inf. */
double bderr_bvh_closest(const bderr_bvh *b, const double p[3], double cp[3],
                         int32_t *tri);

/* The same, starting from the caller's triangle near (an index into the tris
 * given to bderr_bvh_build, or -1): the same answer, found faster when p is
 * close to that triangle. */
double bderr_bvh_closest_near(const bderr_bvh *b, const double p[3], int32_t near,
                              double cp[3], int32_t *tri);

/* Exact closest point on triangle (a,b,c) to p (Ericson 5.1.5); returns the distance. */
double bderr_point_triangle(const double p[3], const double a[3], const double b[3],
                            const double c[3], double cp[3]);

/* Exact closest point on segment [a, b] to p; returns the distance. */
double bderr_point_segment(const double p[3], const double a[3], const double b[3],
                           double cp[3]);

typedef struct {
    double hausdorff; /* max of the two directed distances (absolute) */
    double h_a_to_b;  /* max over samples of A of the distance to B */
    double h_b_to_a;
    double vertex_max; /* max over the vertices of A of the distance to B */
    double mean, rms;  /* over the samples of both sides */
    double diag;       /* bbox diagonal of B (the reference) */
    double hausdorff_rel, mean_rel, rms_rel; /* divided by diag (0 if diag is 0) */
    double vertex_max_rel;
    int64_t n_samples; /* both sides */
    int32_t ntri_a, ntri_b;
} bderr_result;

/* Distances between surface A (candidate) and B (reference).
 * samples_per_side random points on each side besides vertices and centroids. */
qdc_status bderr_surfaces(const double *xa, int32_t nva, const int32_t *ta, int32_t nta,
                          const double *xb, int32_t nvb, const int32_t *tb, int32_t ntb,
                          int64_t samples_per_side, uint64_t seed, bderr_result *r,
                          qdc_error *err);

/* Boundary surfaces (faces of exactly one tet) of out and ref, then bderr_surfaces.
 * The meshes may have different connectivity. */
qdc_status bderr_meshes(const mesh_t *out, const mesh_t *ref, int64_t samples_per_side,
                        bderr_result *r, qdc_error *err);

#endif
