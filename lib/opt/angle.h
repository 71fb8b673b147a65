/* angle.h - the angle polish (docs/method.md §5a; beyond the paper): max-min
 * ascent of the smallest dihedral sines, one vertex at a time and the worst
 * tets' corners together (joint moves). Thread-safe: pure over caller arrays. */
#ifndef QDC_ANGLE_H
#define QDC_ANGLE_H

#include "core/mesh_int.h"
#include "opt/finish.h" /* finish_stats */
#include "opt/slide.h"

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
 * the ascent of their vertex stops, it also tries pattern moves (angle.c). */
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

#endif
