/* global.h - the global phase (docs/method.md §5, §6; global.c). */
#ifndef QDC_GLOBAL_H
#define QDC_GLOBAL_H

#include "opt/ctx.h"

/* The global iterations (Eq. 15 with the line search) from c->x, r the
 * input's record. *stop is set when the run must end without the finishing
 * pass (cancelled, solver trouble). */
qdc_status opt_global_phase(ctx_t *c, opt_result *res, opt_progress *r, int *stop,
                            qdc_error *err);

#endif
