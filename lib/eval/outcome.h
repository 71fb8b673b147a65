/* outcome.h - the outcome of a run in words (docs/defaults.md, "The outcome in words"):
 * what improved, what is left bad and where, how far the boundary moved against
 * its bound, and a warning with suggestions when much is left bad. Computed once
 * here; the report's "outcome" object, the CLI's last lines, the console and the
 * Python client all show these texts. Public (qdc.h). Thread-safe: no global
 * state; the texts are in the struct (no allocation). */
#ifndef QDC_OUTCOME_H
#define QDC_OUTCOME_H

#include "eval/report.h"

/* When much is left bad (docs/defaults.md): more than this fraction of the tets with
 * a dihedral angle under 5 degrees, ... */
#define OUTCOME_SMALL_FRAC 1e-3
/* ... or a worst mean ratio under this, or any tet left inverted */
#define OUTCOME_WORST_Q 0.05
/* the boundary was the limit when it moved this fraction of its bound or more */
#define OUTCOME_BOUND_FRAC 0.9

#define OUTCOME_TEXT 256
#define OUTCOME_MAX 4

typedef struct {
    char summary[3 * OUTCOME_TEXT]; /* improved; left bad; boundary: one paragraph */
    char improved[OUTCOME_TEXT]; /* mean ratio, worst tet, smallest dihedral in -> out */
    char left_bad[OUTCOME_TEXT]; /* tets under 5 and over 175 deg, inverted, worst */
    char boundary[OUTCOME_TEXT]; /* moved against the bound; "" when neither known */
    int32_t n_tets, n_small, n_large, n_inverted; /* small: min dihedral < 5, large: max
                                                   * dihedral > 175 degrees */
    int32_t worst_tet;        /* tet of the worst mean ratio (from 0), -1 unknown */
    double worst_q;           /* its mean ratio */
    double worst_centroid[3]; /* its centroid, mesh units */
    double moved_rel;         /* boundary Hausdorff / diagonal, -1 not measured */
    double bound_rel;         /* the bound applied / diagonal, 0 none */
    int n_warnings, n_suggestions;
    char warnings[OUTCOME_MAX][OUTCOME_TEXT];
    char suggestions[OUTCOME_MAX][OUTCOME_TEXT];
} outcome_t;

/* The outcome of the run r describes, into *o. Reads r->after (required: else
 * QDC_EINVAL), r->before or else r->run->before for what improved, r->run and
 * r->options for the stop, bound and topology, r->boundary (may be NULL: the
 * boundary text then gives the bound only). The report's JSON writes it
 * (report_write_json). */
qdc_status outcome_compute(const report_t *r, outcome_t *o);

#endif
