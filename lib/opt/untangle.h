/* untangle.h - max-min volume untangling (docs/method.md §5a; beyond the
 * paper). Thread-safe: pure over caller arrays. */
#ifndef QDC_UNTANGLE_H
#define QDC_UNTANGLE_H

#include "core/mesh_int.h"
#include "opt/slide.h"

/* Untangling of what the passes leave inverted (Freitag & Plassmann's
 * max-min of volumes): sweeps over the movable vertices of the inverted tets
 * and of the tets around them, each vertex moved up the smallest signed
 * volume of its star while its star gains no inverted tet, until a sweep
 * moves none (at most 12). Interior vertices move freely; with sl (slide
 * mode, may be NULL) boundary and interface vertices that slide on a surface
 * or a line move along it (an inverted tet whose four corners all slide, as
 * where a tangle reached a cube's edge, has no interior vertex to move), the
 * others stay. *n_inverted: the mesh's inverted tets after. stop (may be
 * NULL) is asked before each sweep: nonzero ends the sweeps there (a run out
 * of time: from 100 inverted tets the sweeps took 0.7 s of a 20k-tet run). */
qdc_status finish_untangle(const mesh_topo *tp, const uint8_t *movable,
                           const slide_ctx *sl, double *x, double lbar,
                           int (*stop)(void *), void *stop_ctx, int32_t *n_inverted);

#endif
