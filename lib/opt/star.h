/* star.h - what the passes do to one vertex's star (the tets around it):
 * trial points of a move, the signed volume of a star tet with the vertex
 * moved, the steepest ascent direction of a max-min. Used by the finishing
 * sweeps, the angle polish and untangling. Thread-safe: pure. */
#ifndef QDC_STAR_H
#define QDC_STAR_H

#include "core/mesh_int.h"
#include "opt/slide.h"

/* 6 x the signed volume of star tet k (position in vt_idx) of v with v placed
 * at y, and (if g) its gradient with respect to y (constant: the volume is
 * linear in y). */
double star_vol6(const mesh_topo *tp, const double *x, int32_t k, const double *y,
                 double g[3]);

/* y = xv + t dir, put back on v's surface or line if sl (a sliding vertex). */
void star_trial_point(const slide_ctx *sl, int32_t v, const double *xv,
                      const double dir[3], double t, double y[3]);

/* Minimum-norm point d of the convex hull of g[0..n): the steepest ascent
 * direction of min_i f_i. Returns 0 if the hull contains the origin (no
 * ascent direction). */
int star_min_norm_point(double g[][3], int n, double d[3]);

#endif
