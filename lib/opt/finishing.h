/* finishing.h - the finishing phase (docs/method.md §5a; finishing.c). */
#ifndef QDC_FINISHING_H
#define QDC_FINISHING_H

#include "opt/ctx.h"

/* The finishing sweeps, untangling and the angle polish after the global
 * phase; each pass's records numbered on from res->iterations. */
qdc_status opt_finishing_phase(ctx_t *c, opt_result *res, opt_progress *r);

#endif
