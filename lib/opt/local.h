/* local.h - local repair of the tets the finishing pass left inverted
 * (local.c). */
#ifndef QDC_LOCAL_H
#define QDC_LOCAL_H

#include "opt/ctx.h"

/* While c->best counts unusable tets and c->repair is set: the tets within 3,
 * then 6, then 12 vertex rings of them optimized as a mesh of their own by
 * c->repair (held: the cut to the rest and the locked vertices; every vertex
 * at c->xbest), under the run's bound and then (slide mode, or the default
 * bound) under the wider bound (the default's: OPT_HAUSD_STUCK) with the
 * boundary corners of the unusable tets free to leave their surface within
 * it; each result recorded as phase "local"
 * (numbered *next on) and kept by the best-iterate rule, res->hausd_bound
 * raised to the bound of a result kept. */
qdc_status local_pass(ctx_t *c, opt_result *res, opt_progress *r, int *next);

#endif
