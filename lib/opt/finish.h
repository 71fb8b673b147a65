/* finish.h - worst-tet finishing sweeps (docs/method.md §5a; beyond the paper).
 * Per-vertex minimization of the local objective sum_{t in T(v)} q~_t on the
 * movable vertices of the worst tets and of every inverted tet: damped Newton
 * with the analytic 3x3 Hessian for interior vertices (MIVL, MIMR), normalized
 * gradient steps for sliding vertices and MICN. A move is kept only if the
 * local objective decreases and no tet of the star becomes inverted (so the
 * number of inverted tets never grows). Thread-safe: pure over caller arrays. */
#ifndef QDC_FINISH_H
#define QDC_FINISH_H

#include "core/mesh_int.h"
#include "opt/opt.h"
#include "opt/slide.h"

/* Step halvings a move tries (the sweeps' Newton steps and the angle polish). */
#define FINISH_HALVINGS 12

typedef struct {
    int32_t n_verts;                  /* vertices visited */
    int32_t n_moves;                  /* accepted moves */
    double delta;                     /* regularization used in this sweep */
    double score_before, score_after; /* angle sweep: mean of the frac smallest
                                       * per-tet dihedral sines, before and after */
    double floor_before, floor_after; /* angle sweep: the smallest sine */
} finish_stats;

/* One sweep over x (normalized coordinates, 3 per vertex). movable: nv flags.
 * eta: the mean ratio of every tet at x; delta: the regularization for x.
 * frac: share of the worst tets (by mean ratio) whose vertices are visited.
 * lbar: mean edge length (in x's units).
 * sl (may be NULL): constraints of sliding boundary vertices (movable ones with
 * a SLIDE_SURFACE/SLIDE_LINE kind move tangentially and are projected back).
 * rtol: a vertex stops once a step lowers its local objective by less than
 * rtol times its value (0: all inner steps).
 * keep_surface: on a tangled mesh (delta > 0) a move may trade an inverted star
 * tet for a valid one; with keep_surface not a valid tet whose face opposite
 * the moving vertex has three boundary corners (a fold at the surface). */
qdc_status finish_sweep(const mesh_topo *tp, const uint8_t *movable, const slide_ctx *sl,
                        double *x, opt_metric m, const double *eta, double delta,
                        double lbar, double frac, double rtol, int keep_surface,
                        finish_stats *st);

#endif
