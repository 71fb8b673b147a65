/* outcome.c - the outcome of a run in words (outcome.h; thresholds in docs/defaults.md).
 */
#include "eval/outcome.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* Appends to a fixed text; a text that does not fit is cut (never overrun). */
static void add(char *buf, size_t cap, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void add(char *buf, size_t cap, const char *fmt, ...)
{
    size_t n = strlen(buf);
    va_list ap;

    if (n + 1 >= cap)
        return;
    va_start(ap, fmt);
    vsnprintf(buf + n, cap - n, fmt, ap);
    va_end(ap);
}

/* Appends a text to a list of at most OUTCOME_MAX (the warnings, the suggestions). */
static void push(char (*list)[OUTCOME_TEXT], int *n, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void push(char (*list)[OUTCOME_TEXT], int *n, const char *fmt, ...)
{
    va_list ap;

    if (*n >= OUTCOME_MAX)
        return;
    va_start(ap, fmt);
    vsnprintf(list[(*n)++], OUTCOME_TEXT, fmt, ap);
    va_end(ap);
}
#define warn(o, ...) push((o)->warnings, &(o)->n_warnings, __VA_ARGS__)
#define suggest(o, ...) push((o)->suggestions, &(o)->n_suggestions, __VA_ARGS__)

/* "3", "12 (0.12%)": a count and its share of the tets when it is not 0 */
static void count_of(char *buf, size_t cap, int32_t n, int32_t nt)
{
    if (n > 0 && nt > 0)
        snprintf(buf, cap, "%d (%.2g%%)", (int)n, 100.0 * n / nt);
    else
        snprintf(buf, cap, "%d", (int)n);
}

/* The figures before: the report's scan of the input, else the run's input record. */
static void improved_text(const report_t *r, outcome_t *o)
{
    const report_quality *a = r->after;
    double qm, qmin, dmin;

    if (r->before) {
        qm = r->before->q_mean;
        qmin = r->before->q_min;
        dmin = r->before->dih_min;
    } else if (r->run) {
        qm = r->run->before.q_mean;
        qmin = r->run->before.q_min;
        dmin = r->run->before.dih_min;
    } else {
        add(o->improved, sizeof o->improved,
            "mean ratio %.4f, worst tet %+.4f, smallest dihedral %.2f°", a->q_mean,
            a->q_min, a->dih_min);
        return;
    }
    add(o->improved, sizeof o->improved,
        "mean ratio %.4f -> %.4f, worst tet %+.4f -> %+.4f, smallest dihedral "
        "%.2f° -> %.2f°",
        qm, a->q_mean, qmin, a->q_min, dmin, a->dih_min);
}

static void left_bad_text(const report_t *r, outcome_t *o)
{
    const report_quality *a = r->after;
    char small[48], large[48], inv[48];

    o->n_tets = a->nt;
    o->n_small = a->n_dmin_lt[0];
    o->n_large = a->n_dmax_gt[0];
    o->n_inverted = a->n_inverted;
    o->worst_tet = a->worst_tet;
    o->worst_q = a->q_min;
    memcpy(o->worst_centroid, a->worst_centroid, sizeof o->worst_centroid);
    count_of(small, sizeof small, o->n_small, a->nt);
    count_of(large, sizeof large, o->n_large, a->nt);
    count_of(inv, sizeof inv, o->n_inverted, a->nt);
    add(o->left_bad, sizeof o->left_bad,
        "left: %s of %d tets under 5° and %s over 175° dihedral, %s inverted; "
        "worst tet %d (from 0) at (%.4g, %.4g, %.4g), mean ratio %+.4f",
        small, (int)a->nt, large, inv, (int)a->worst_tet, a->worst_centroid[0],
        a->worst_centroid[1], a->worst_centroid[2], a->q_min);
}

static void boundary_text(const report_t *r, outcome_t *o)
{
    double diag = r->boundary && r->boundary->diag > 0 ? r->boundary->diag
                  : r->before                          ? r->before->diag
                                                       : r->after->diag;
    double bound = r->run ? r->run->hausd_bound : 0;

    o->moved_rel = r->boundary ? r->boundary->hausdorff_rel : -1;
    o->bound_rel = bound > 0 && diag > 0 ? bound / diag : 0;
    if (r->boundary && o->bound_rel > 0)
        add(o->boundary, sizeof o->boundary,
            "boundary moved %.3g%% of the diagonal, %.0f%% of its bound (%.3g%%)",
            100 * o->moved_rel, 100 * o->moved_rel / o->bound_rel, 100 * o->bound_rel);
    else if (r->boundary)
        add(o->boundary, sizeof o->boundary,
            "boundary moved %.3g%% of the diagonal (no bound)", 100 * o->moved_rel);
    else if (o->bound_rel > 0)
        add(o->boundary, sizeof o->boundary,
            "boundary bound %.3g%% of the diagonal (distance not measured)",
            100 * o->bound_rel);
}

/* docs/defaults.md, "The outcome in words": when much is left bad, why, and what to try.
 */
static void advise(const report_t *r, outcome_t *o)
{
    const opt_options *op = r->options;
    int topo = op ? (int)op->topology : -1;
    int at_bound = o->bound_rel > 0 && o->moved_rel >= OUTCOME_BOUND_FRAC * o->bound_rel;
    /* the surface's sharp edges, the input's when measured */
    const report_quality *sq =
        r->before && r->before->n_surf_lt5 >= 0 ? r->before : r->after;

    if (o->n_inverted > 0)
        warn(o, "%d tets are left inverted", (int)o->n_inverted);
    if (o->n_tets > 0 && o->n_small > OUTCOME_SMALL_FRAC * o->n_tets)
        warn(o, "%d tets (%.2g%%, over %.2g%%) are left with a dihedral angle under 5°",
             (int)o->n_small, 100.0 * o->n_small / o->n_tets, 100 * OUTCOME_SMALL_FRAC);
    if (o->worst_q < OUTCOME_WORST_Q)
        warn(o, "the worst tet's mean ratio is %+.4f (under %.2f)", o->worst_q,
             OUTCOME_WORST_Q);
    if (!o->n_warnings)
        return;
    if (topo == OPT_TOPOLOGY_NONE)
        suggest(o, "try --topology flips (or --topology full): the connectivity was kept "
                   "(--topology none) and limits the worst tets");
    else if (topo >= 0 && topo != OPT_TOPOLOGY_FULL)
        suggest(o, "try --topology full: it inserts vertices where flips alone are not "
                   "enough");
    if (at_bound)
        suggest(
            o,
            "the boundary reached its bound: try a looser --hausd, e.g. --hausd %.3g%%",
            200 * o->bound_rel);
    else if (op && op->boundary == OPT_BOUNDARY_FIXED)
        suggest(o,
                "try --boundary slide: fixed boundary vertices keep the tets along the "
                "boundary as they are");
    if (sq && sq->n_surf_lt5 > 0 && o->n_small > 0)
        suggest(o,
                "%d edges of the %s surface have a solid angle under 5° (smallest "
                "%.2g°): a tet on such an edge has no larger dihedral angle there while "
                "the surface is kept",
                (int)sq->n_surf_lt5, sq == r->before ? "input's" : "result's",
                sq->surf_angle_min);
    if (r->run &&
        (r->run->stop == OPT_STOP_TIME_LIMIT || r->run->stop == OPT_STOP_CANCELLED))
        suggest(o, "the run was stopped (%s) before it converged: give it more time",
                r->run->stop_reason);
    if (!o->n_suggestions)
        suggest(o,
                "look at the mesh around the worst tet (%.4g, %.4g, %.4g): the input's "
                "shape or sizing there may be what limits the quality",
                o->worst_centroid[0], o->worst_centroid[1], o->worst_centroid[2]);
}

qdc_status outcome_compute(const report_t *r, outcome_t *o)
{
    memset(o, 0, sizeof *o);
    o->worst_tet = -1;
    o->moved_rel = -1;
    if (!r || !r->after)
        return QDC_EINVAL;
    improved_text(r, o);
    left_bad_text(r, o);
    boundary_text(r, o);
    advise(r, o);
    add(o->summary, sizeof o->summary, "%s; %s", o->improved, o->left_bad);
    if (o->boundary[0])
        add(o->summary, sizeof o->summary, "; %s", o->boundary);
    return QDC_OK;
}
