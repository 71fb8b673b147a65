/* finish.h - worst-tet finishing pass (METHOD §5a; beyond the paper).
 * Per-vertex descent of the local objective sum_{t in T(v)} q~_t on the movable
 * vertices of the worst tets and of every inverted tet. A move is kept only if
 * the local objective decreases and no tet of the star becomes inverted (so
 * the number of inverted tets never grows). Thread-safe: pure over caller arrays. */
#ifndef QDC_FINISH_H
#define QDC_FINISH_H

#include "mesh.h"
#include "opt.h"
#include "slide.h"

typedef struct {
    int32_t n_verts; /* vertices visited */
    int32_t n_moves; /* accepted moves */
    double delta;    /* regularization used in this sweep */
} finish_stats;

/* One sweep over x (normalized coordinates, 3 per vertex). movable: nv flags.
 * frac: share of the worst tets (by mean ratio) whose vertices are visited.
 * eps: Escobar epsilon, lbar: mean edge length (both in x's units).
 * sl (may be NULL): constraints of sliding boundary vertices (movable ones with
 * a SLIDE_SURFACE/SLIDE_LINE kind move tangentially and are projected back).
 * rtol: a vertex stops once a step lowers its local objective by less than
 * rtol times its value (0: all inner steps). */
qdc_status finish_sweep(const mesh_topo *tp, const uint8_t *movable, const slide_ctx *sl,
                        double *x, opt_metric m, double eps, double lbar, double frac,
                        double rtol, finish_stats *st);

#endif
