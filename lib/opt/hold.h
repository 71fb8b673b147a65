/* hold.h - the vertices a finished run holds or frees (hold.c). */
#ifndef QDC_HOLD_H
#define QDC_HOLD_H

#include "opt/ctx.h"

/* Do no harm on a valid input (docs/method.md §5): the corners of tets that
 * break a rule go back to their input positions in c->xbest. Returns how
 * many vertices went back. */
int32_t opt_hold_back(ctx_t *c);
/* Slide mode: the corners of the smooth ears the run squashed, as an nv mask
 * into *out (NULL if none; the caller frees it). */
qdc_status opt_squashed_ears(const ctx_t *c, uint8_t **out);
/* Slide mode, tets left inverted: the boundary and interface vertices around
 * them, as an nv mask into *out (NULL if none; the caller frees it). */
qdc_status opt_stuck_boundary(const ctx_t *c, uint8_t **out);

#endif
