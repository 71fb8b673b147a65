/* metric.h - the choice of per-tet quality metric (paper Sec. 3.1,
 * docs/method.md §2-§3); public (qdc.h). The metrics themselves, their
 * gradients and Hessians are internal: metric_int.h. */
#ifndef QDC_METRIC_H
#define QDC_METRIC_H

#include "core/base.h"

/* Which modified inverse quality drives the optimizer (paper Sec. 3.1). It is
 * named for the optimizer option it is, but lives here, with the metrics. */
typedef enum { OPT_METRIC_MIVL = 0, OPT_METRIC_MIMR, OPT_METRIC_MICN } opt_metric;

#endif
