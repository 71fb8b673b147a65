/* opt_int.h - the internal part of opt.h: the option words' parsers and
 * names (the options table, opt_set and the report read them; callers of the
 * library set options through opt_set, options.h) and the stop reasons' names.
 * Thread-safe: constant tables. */
#ifndef QDC_OPT_INT_H
#define QDC_OPT_INT_H

#include "core/base.h"
#include "opt/opt.h"

/* opt_stop's word: "converged", "max-iter"...; what opt_result.stop_reason holds. */
const char *opt_stop_name(opt_stop s);

/* --hausd: "H" (absolute, mesh units), "P%" (percent of the bounding-box
 * diagonal) or "rel:F" (fraction of it); sets o->hausd or o->hausd_rel.
 * QDC_EINVAL for anything else, a negative, NaN or infinite value. */
qdc_status opt_parse_hausd(const char *s, opt_options *o);

/* Parse option words ("mivl", "lsq", "safe", ...) into o; QDC_EINVAL if unknown. */
qdc_status opt_parse_metric(const char *s, opt_metric *out);
qdc_status opt_parse_boundary(const char *s, opt_boundary *out);
qdc_status opt_parse_mode(const char *s, opt_mode *out);
qdc_status opt_parse_weights(const char *s, opt_weights *out);
qdc_status opt_parse_solver(const char *s, opt_solver *out);
qdc_status opt_parse_topology(const char *s, opt_topology *out);
const char *opt_metric_name(opt_metric m);
const char *opt_boundary_name(opt_boundary b);
const char *opt_mode_name(opt_mode m);
const char *opt_weights_name(opt_weights w);

#endif
