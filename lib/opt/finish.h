/* finish.h - worst-tet finishing pass (docs/method.md §5a; beyond the paper).
 * Per-vertex minimization of the local objective sum_{t in T(v)} q~_t on the
 * movable vertices of the worst tets and of every inverted tet: damped Newton
 * with the analytic 3x3 Hessian for interior vertices (MIVL, MIMR), normalized
 * gradient steps for sliding vertices and MICN. A move is kept only if the
 * local objective decreases and no tet of the star becomes inverted (so the
 * number of inverted tets never grows). Thread-safe: pure over caller arrays. */
#ifndef QDC_FINISH_H
#define QDC_FINISH_H

#include "core/mesh.h"
#include "opt/opt.h"
#include "opt/slide.h"

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

/* Worst-angle polish (beyond the paper): max-min ascent of the smallest dihedral
 * sine of each star (Freitag's non-smooth smoothing: the steepest ascent is the
 * minimum-norm point of the active gradients) on the movable vertices of the
 * worst frac of tets by dihedral sine. A move is kept only if the star's
 * smallest sine rises, every star tet stays positive and no star tet's mean
 * ratio falls below qfloor (so the mesh's worst mean ratio never drops under it).
 * smin (nt entries): each tet's smallest dihedral sine at x, read if smin_valid
 * (as the previous sweep left it), else computed; on return it holds the values
 * at the new x. */
qdc_status finish_dihedral_sweep(const mesh_topo *tp, const uint8_t *movable,
                                 const slide_ctx *sl, double *x, double lbar, double frac,
                                 double qfloor, double *smin, int smin_valid,
                                 finish_stats *st);
/* Stars whose smallest sine is under this (sin 1 degree) are "deep": where
 * the ascent of their vertex stops, it also tries pattern moves (finish.c). */
#define FINISH_DEEP_SINE 0.017452

/* Joint moves of the worst tets' corners (after single-vertex sweeps have
 * balanced neighbouring tets): for each of the 32 worst tets, worst first, the
 * max-min ascent of its movable corners together over the union of their
 * stars. FINISH_PATCH_ANGLES: the tets' dihedral sines, under
 * finish_dihedral_sweep's rules (the smallest sine rises, no more tets under
 * the 32nd smallest sine, none under qfloor); val: each tet's smallest sine.
 * FINISH_PATCH_MEAN_RATIO: the tets' mean ratios (no floor; qfloor unused);
 * val: each tet's mean ratio. val is read if val_valid, else computed, and
 * kept up to date; floor: the smallest value, score: the mean of the 32
 * smallest. */
typedef enum { FINISH_PATCH_ANGLES, FINISH_PATCH_MEAN_RATIO } finish_patch_kind;

qdc_status finish_patches(const mesh_topo *tp, const uint8_t *movable,
                          const slide_ctx *sl, double *x, double lbar,
                          finish_patch_kind kind, double qfloor, double *val,
                          int val_valid, finish_stats *st);

/* Untangling of what the passes leave inverted (Freitag & Plassmann's
 * max-min of volumes): sweeps over the movable interior vertices of the
 * inverted tets and of the tets around them, each vertex moved up the
 * smallest signed volume of its star while its star gains no inverted tet,
 * until a sweep moves none (at most 12). *n_inverted: the mesh's inverted
 * tets after. */
qdc_status finish_untangle(const mesh_topo *tp, const uint8_t *movable, double *x,
                           double lbar, int32_t *n_inverted);

#endif
