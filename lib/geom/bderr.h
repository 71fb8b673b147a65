/* bderr.h - boundary error (docs/method.md §9): symmetric Hausdorff distance between two
 * triangle surfaces with exact point-triangle distances through a BVH over
 * Metro-style samples (every vertex, every face centroid, plus area-weighted
 * random points from a fixed seed); public (qdc.h). The BVH and its
 * closest-point queries, used by the sliding boundary mode, are in
 * bderr_int.h. Thread-safe: no global state. */
#ifndef QDC_BDERR_H
#define QDC_BDERR_H

#include "core/base.h"
#include "core/mesh.h"

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

/* Distances between surface A (candidate: xa 3*nva coordinates, ta 3*nta
 * 0-based indices) and surface B (reference, the same for xb, tb): every
 * vertex, every triangle centroid and samples_per_side (>= 0) random points
 * of each side, drawn from seed. Reads the arrays only; fills *r (not NULL).
 * QDC_EINVAL (an empty surface, an index out of range, samples_per_side
 * negative or over 2^40), QDC_ENOMEM. */
qdc_status bderr_surfaces(const double *xa, int32_t nva, const int32_t *ta, int32_t nta,
                          const double *xb, int32_t nvb, const int32_t *tb, int32_t ntb,
                          int64_t samples_per_side, uint64_t seed, bderr_result *r,
                          qdc_error *err);

/* The boundary surfaces (faces of exactly one tet) of out and ref, then
 * bderr_surfaces with a fixed seed: the boundary error of an optimized mesh
 * against its input. The meshes may have different connectivity; both are
 * only read; fills *r. QDC_EINVAL (a NULL argument, a tet index out of
 * range, no boundary), QDC_ENOMEM. */
qdc_status bderr_meshes(const mesh_t *out, const mesh_t *ref, int64_t samples_per_side,
                        bderr_result *r, qdc_error *err);
/* bderr_meshes of two meshes with the same tets (a result and its input), on
 * the boundary f already found (mesh_faces: from the run, opt_run_faces);
 * f NULL: bderr_meshes. The same result as bderr_meshes, without finding the
 * faces again. QDC_EINVAL (counts that differ from f's), QDC_ENOMEM. */
qdc_status bderr_meshes_faces(const mesh_t *out, const mesh_t *ref, const mesh_faces *f,
                              int64_t samples_per_side, bderr_result *r, qdc_error *err);

#endif
