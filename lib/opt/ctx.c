/* ctx.c - the state of one optimizer run and what every phase does with it
 * (ctx.h): the quality scans, the best-iterate rule, progress records, the
 * stop tests. */
#include "opt/ctx.h"
#include "opt/opt_int.h"

#include "core/tet.h"
#include "geom/metric_int.h"
#include "opt/encode.h"

#include <math.h>
#include <omp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void ctx_log(const ctx_t *c, int level, const char *fmt, ...)
{
    char buf[256];
    va_list ap;

    if (!c->o->log)
        return;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    c->o->log(c->o->log_ctx, level, buf);
}

#define EVAL_CHUNKS 256
#define M_PI_ 3.14159265358979323846

/* Quality record of x (normalized coordinates; mean ratio and angles are
 * scale-invariant) in one pass over the tets, then the objective with the
 * delta of x, which is returned. eta (nt entries, may be NULL) receives each
 * tet's mean ratio for the finishing pass. When the objective takes a pass of
 * its own, qt and sc (may be NULL) receive what encode_objective_scan finds
 * in it, and *scanned is 1 (else 0). */
static double evaluate(const ctx_t *c, const double *x, opt_progress *r, double *eta_out,
                       double *qt, encode_scan *sc, int *scanned)
{
    const mesh_topo *tp = c->tp;
    const opt_metric m = c->o->metric;
    double psum[EVAL_CHUNKS], psum2[EVAL_CHUNKS], pobj[EVAL_CHUNKS], obj = 0;
    /* the objective comes with the scan when delta turns out 0 (no tet below
     * eps: the usual case once untangled); MICN needs parts the scan lacks */
    const int fuse = m != OPT_METRIC_MICN;
    double sum = 0, sum2 = 0, qmin = INFINITY, cmax = -2, cmin = 2, amin = INFINITY,
           delta;
    int32_t ninv = 0, ndeg = 0;

    /* fixed chunks summed in order: reports do not depend on the thread count */
#pragma omp parallel for reduction(+ : ninv, ndeg) reduction(min : qmin, cmin, amin) \
    reduction(max : cmax) schedule(static)
    for (int ch = 0; ch < EVAL_CHUNKS; ch++) {
        int32_t t0 = qdc_part(tp->nt, ch, EVAL_CHUNKS);
        int32_t t1 = qdc_part(tp->nt, ch + 1, EVAL_CHUNKS);
        double s = 0, s2 = 0, so = 0;
        for (int32_t t = t0; t < t1; t++) {
            const int32_t *tt = tp->tets + 4 * (size_t)t;
            const double *p0 = x + 3 * (size_t)tt[0], *p1 = x + 3 * (size_t)tt[1];
            const double *p2 = x + 3 * (size_t)tt[2], *p3 = x + 3 * (size_t)tt[3];
            metric_parts pt;
            double eta, lo, hi, arg;
            metric_parts_for(OPT_METRIC_MIVL, p0, p1, p2, p3, &pt);
            eta = metric_mean_ratio(&pt);
            if (fuse)
                so += metric_qt(m, &pt, 0.0);
            if (eta_out)
                eta_out[t] = eta;
            s += eta;
            s2 += eta * eta;
            qmin = eta < qmin ? eta : qmin;
            ninv += geom_tet_bad_vl(6.0 * pt.vol, pt.l2sum);
            ndeg += geom_tet_degenerate(6.0 * pt.vol, pt.l2sum);
            arg = metric_arg(m, &pt); /* every metric's argument is a multiple of vol */
            amin = arg < amin ? arg : amin;
            metric_dihedral_cos_range(p0, p1, p2, p3, &lo, &hi);
            cmin = lo < cmin ? lo : cmin;
            cmax = hi > cmax ? hi : cmax;
        }
        psum[ch] = s;
        psum2[ch] = s2;
        pobj[ch] = so;
    }
    for (int ch = 0; ch < EVAL_CHUNKS; ch++) {
        sum += psum[ch];
        sum2 += psum2[ch];
        obj += pobj[ch];
    }
    memset(r, 0, sizeof *r);
    r->q_mean = sum / tp->nt;
    r->q_std = sqrt(fmax(0.0, sum2 / tp->nt - r->q_mean * r->q_mean));
    r->q_min = qmin;
    r->dih_min = acos(cmax) * (180.0 / M_PI_);
    r->dih_max = acos(cmin) * (180.0 / M_PI_);
    r->n_inverted = ninv;
    r->n_degenerate = ndeg;
    delta = metric_delta(amin, c->eps);
    *scanned = !(fuse && delta == 0.0);
    /* (encode_objective_scan's sum is encode_objective's, bit for bit) */
    r->objective = *scanned ? encode_objective_scan(tp, x, m, delta, qt, sc) : obj;
    r->elapsed = qdc_now() - c->t0;
    r->solver = c->sol ? (int)solve_kind(c->sol) : 0;
    return delta;
}

double ctx_evaluate(const ctx_t *c, const double *x, opt_progress *r, double *eta_out)
{
    int scanned;

    return evaluate(c, x, r, eta_out, NULL, NULL, &scanned);
}

void ctx_evaluate_x(ctx_t *c, opt_progress *r)
{
    c->eta_delta = evaluate(c, c->x, r, c->eta, c->qt, &c->xscan, &c->xscan_ok);
    c->xscan_f = r->objective;
}

/* Mean ratio of every tet into eta and the fields of r that the choice of
 * the best iterate reads (mean, worst, inverted count; fixed chunks summed in
 * order); returns the delta of x. */
double ctx_scan_light(const ctx_t *c, const double *x, double *eta, opt_progress *r)
{
    const mesh_topo *tp = c->tp;
    double psum[EVAL_CHUNKS], sum = 0, amin = INFINITY, qmin = INFINITY;
    int32_t ninv = 0, ndeg = 0;

#pragma omp parallel for reduction(min : amin, qmin) reduction(+ : ninv, ndeg) schedule(static)
    for (int ch = 0; ch < EVAL_CHUNKS; ch++) {
        int32_t t0 = qdc_part(tp->nt, ch, EVAL_CHUNKS);
        int32_t t1 = qdc_part(tp->nt, ch + 1, EVAL_CHUNKS);
        double sm = 0;
        for (int32_t t = t0; t < t1; t++) {
            const int32_t *tt = tp->tets + 4 * (size_t)t;
            metric_parts pt;
            double arg;
            metric_parts_for(OPT_METRIC_MIVL, x + 3 * (size_t)tt[0],
                             x + 3 * (size_t)tt[1], x + 3 * (size_t)tt[2],
                             x + 3 * (size_t)tt[3], &pt);
            eta[t] = metric_mean_ratio(&pt);
            sm += eta[t];
            qmin = eta[t] < qmin ? eta[t] : qmin;
            ninv += geom_tet_bad_vl(6.0 * pt.vol, pt.l2sum);
            ndeg += geom_tet_degenerate(6.0 * pt.vol, pt.l2sum);
            arg = metric_arg(c->o->metric, &pt);
            amin = arg < amin ? arg : amin;
        }
        psum[ch] = sm;
    }
    for (int ch = 0; ch < EVAL_CHUNKS; ch++)
        sum += psum[ch];
    memset(r, 0, sizeof *r);
    r->q_mean = sum / tp->nt;
    r->q_min = qmin;
    r->n_inverted = ninv;
    r->n_degenerate = ndeg;
    return metric_delta(amin, c->eps);
}

/* docs/method.md §5: keep the best iterate (fewest inverted, then best worst tet, then
 * best mean). Never accept one with more inverted tets or a worse worst tet
 * than the input. Worst-tet differences under 1e-4 count as ties so that the
 * mean decides between iterates whose worst tet did not really change. */
int ctx_better(const opt_progress *a, const opt_progress *b)
{
    if (a->n_inverted != b->n_inverted)
        return a->n_inverted < b->n_inverted;
    if (fabs(a->q_min - b->q_min) > 1e-4)
        return a->q_min > b->q_min;
    return a->q_mean > b->q_mean;
}

/* ... and on a valid input, never one with a lower mean ratio either (an
 * sfepy file's mean fell 0.7274 -> 0.7246 while its worst tet rose). */
int ctx_eligible(const ctx_t *c, const opt_progress *r)
{
    return r->n_inverted <= c->input.n_inverted && r->q_min >= c->input.q_min &&
           (c->input.n_inverted > 0 || r->q_mean >= c->input.q_mean);
}

void ctx_consider(ctx_t *c, const double *x, const opt_progress *r)
{
    if (ctx_eligible(c, r) && ctx_better(r, &c->best)) {
        c->best = *r;
        c->best_it = r->iteration;
        memcpy(c->xbest, x, 3 * (size_t)c->nv * sizeof(double));
    }
}

int ctx_report(ctx_t *c, opt_progress *r)
{
    r->elapsed = qdc_now() - c->t0;
    c->last_record = r->iteration;
    if (c->o->progress && c->o->progress(c->o->progress_ctx, r))
        return 1;
    return 0;
}

static const char *const stop_names[] = {"max-iter",  "converged",  "no-descent",
                                         "cancelled", "time-limit", "solver"};

const char *opt_stop_name(opt_stop s)
{
    return (unsigned)s < sizeof stop_names / sizeof stop_names[0] ? stop_names[s] : "?";
}

double ctx_time_left(double limit, double spent)
{
    return limit > 0 ? fmax(limit - spent, 1e-3) : 0.0;
}

/* The reason a run stops: the enum decides, the name is for reports. */
void ctx_set_stop(opt_result *res, opt_stop s)
{
    res->stop = s;
    snprintf(res->stop_reason, sizeof res->stop_reason, "%s", opt_stop_name(s));
}

int ctx_should_stop(ctx_t *c, opt_result *res)
{
    double now;

    if (c->o->cancel && atomic_load(c->o->cancel)) {
        ctx_set_stop(res, OPT_STOP_CANCELLED);
        return 1;
    }
    if (c->o->time_limit <= 0)
        return 0;
    now = qdc_now();
    c->t_unit = c->t_check > 0 ? now - c->t_check : 0.0;
    c->t_check = now;
    if (now - c->t0 + c->t_unit > c->o->time_limit) {
        ctx_set_stop(res, OPT_STOP_TIME_LIMIT);
        return 1;
    }
    return 0;
}

/* The mean edge length of x (1 if there is no edge). */
static double mean_edge(const mesh_topo *tp, const double *x)
{
    double esum = 0;
    int64_t ecount = 0;

    for (int32_t i = 0; i < tp->nv; i++)
        for (int32_t s = tp->adj_ptr[i]; s < tp->adj_ptr[i + 1]; s++) {
            int32_t j = tp->adj_idx[s];
            const double *a = x + 3 * (size_t)i, *b = x + 3 * (size_t)j;
            if (j <= i)
                continue;
            esum += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                         (a[2] - b[2]) * (a[2] - b[2]));
            ecount++;
        }
    return ecount ? esum / (double)ecount : 1.0;
}

/* The bounding-box diagonal of the boundary vertices: the surface whose
 * diagonal the report's boundary error is relative to. 0 if there is none or
 * its size is out of the plain formula's range. */
static double surface_diag(const mesh_t *m, const mesh_topo *tp)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY},
           hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double d[3], e;

    for (int32_t v = 0; v < m->nv; v++)
        if (tp->vflag[v] & MESH_V_BOUNDARY)
            for (int k = 0; k < 3; k++) {
                double x = m->xyz[3 * (size_t)v + k];
                if (x < lo[k])
                    lo[k] = x;
                if (x > hi[k])
                    hi[k] = x;
            }
    for (int k = 0; k < 3; k++)
        d[k] = hi[k] - lo[k];
    e = fmax(d[0], fmax(d[1], d[2]));
    return e > 1e-140 && e < 1e140 ? sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) : 0.0;
}

/* c->autob and c->hbound (normalized units) from o's bound. */
static void set_bound(ctx_t *c, const mesh_t *m, const mesh_topo *tp,
                      const opt_options *o)
{
    /* the default (auto, under slide): the Hausdorff bound OPT_HAUSD_DEFAULT */
    c->autob = o->hausd <= 0 && o->hausd_rel == OPT_HAUSD_AUTO &&
               o->boundary == OPT_BOUNDARY_SLIDE;
    c->hbound = o->hausd > 0       ? o->hausd / c->scale
                : o->hausd_rel > 0 ? o->hausd_rel
                : c->autob         ? OPT_HAUSD_DEFAULT
                                   : 0.0;
    /* a relative bound is of the surface's diagonal, as the report measures:
     * not the same as the mesh's only where vertices lie outside the surface's
     * box (a tangle, second-order mid-edge nodes, unused vertices) */
    if (o->hausd <= 0 && c->hbound > 0) {
        double sd = surface_diag(m, tp);
        if (sd > 0 && sd != c->scale)
            c->hbound *= sd / c->scale;
    }
}

qdc_status ctx_init(ctx_t *c, const mesh_t *m, const mesh_topo *tp, const opt_options *o)
{
    size_t n3 = 3 * (size_t)m->nv;
    double lo[3], hi[3], diag;

    memset(c, 0, sizeof *c);
    c->o = o;
    c->tp = tp;
    c->region = m->region;
    c->nv = m->nv;
    c->nt = m->nt;
    c->x = qdc_mallocn(n3, sizeof(double));
    c->x0 = qdc_mallocn(n3, sizeof(double));
    c->xn = qdc_mallocn(n3, sizeof(double));
    c->xbest = qdc_mallocn(n3, sizeof(double));
    c->trial = qdc_mallocn(n3, sizeof(double));
    c->tmp = qdc_mallocn(n3, sizeof(double));
    c->rhs = qdc_mallocn(n3, sizeof(double));
    c->d = qdc_mallocn(n3, sizeof(double));
    c->locked = qdc_calloc((size_t)m->nv, 1);
    c->vfac = qdc_mallocn((size_t)m->nv, sizeof(double));
    c->vmark = qdc_calloc((size_t)m->nv, 1);
    c->vlist = qdc_mallocn((size_t)m->nv + 1, sizeof(int32_t));
    c->wq2 = qdc_mallocn((size_t)m->nv, sizeof(double));
    c->bw2 = qdc_calloc((size_t)m->nv, sizeof(double));
    c->dg = qdc_mallocn((size_t)m->nv, sizeof(double));
    c->qt = qdc_mallocn((size_t)m->nt, sizeof(double));
    c->eta = qdc_mallocn((size_t)m->nt, sizeof(double));
    c->qval = qdc_mallocn((size_t)tp->adj_ptr[tp->nv], sizeof(double));
    if (o->weights != OPT_WEIGHTS_PAPER && o->mode != OPT_MODE_LITERAL)
        c->fslot = encode_face_slots(tp); /* optional: NULL is a slower search */
    if (!c->x || !c->x0 || !c->xn || !c->xbest || !c->trial || !c->tmp || !c->rhs ||
        !c->d || !c->locked || !c->vfac || !c->vmark || !c->vlist || !c->wq2 || !c->bw2 ||
        !c->dg || !c->qt || !c->eta || !c->qval)
        return QDC_ENOMEM;
    /* docs/method.md §1: bbox centre to 0, diagonal to 1; every tolerance is in these
     * units */
    diag = mesh_bbox(m, lo, hi);
    c->scale = diag > 0 ? diag : 1.0;
    for (int k = 0; k < 3; k++)
        c->center[k] = 0.5 * (lo[k] + hi[k]);
    for (int32_t v = 0; v < m->nv; v++)
        for (int k = 0; k < 3; k++)
            c->x[3 * (size_t)v + k] =
                (m->xyz[3 * (size_t)v + k] - c->center[k]) / c->scale;
    memcpy(c->x0, c->x, n3 * sizeof(double));
    memcpy(c->xbest, c->x, n3 * sizeof(double));
    c->lbar = mean_edge(tp, c->x);
    c->bref = c->x0;
    c->mu_factor = 1.0;
    set_bound(c, m, tp, o);
    if (o->boundary == OPT_BOUNDARY_SLIDE) {
        qdc_status st = slide_new(tp, c->x0, o->feature_angle, &c->sl, NULL);
        if (st != QDC_OK)
            return st;
        slide_set_bound(c->sl, c->hbound);
        c->bref = c->x; /* rows keep a sliding vertex near where it is */
    }
    c->eps = metric_eps(o->metric, c->lbar, o->eps_rel);
    for (int32_t v = 0; v < m->nv; v++) {
        uint8_t f = tp->vflag[v];
        int on_b = (f & (MESH_V_BOUNDARY | MESH_V_INTERFACE)) != 0;
        c->locked[v] = (f & (MESH_V_FIXED | MESH_V_UNUSED)) ||
                       (on_b && o->boundary == OPT_BOUNDARY_FIXED) ||
                       (c->sl && slide_kind(c->sl, v) == SLIDE_CORNER);
        /* Eq. 9: boundary rows B x = b with b the ORIGINAL positions (lsq) */
        c->bw2[v] = on_b && !c->locked[v] ? 1.0 : 0.0;
        c->wq2[v] = 1.0;
    }
    return QDC_OK;
}

void ctx_free(ctx_t *c)
{
    solve_free(c->sol);
    slide_free(c->sl);
    qdc_free(c->vfac);
    qdc_free(c->vmark);
    qdc_free(c->vlist);
    qdc_free(c->x);
    qdc_free(c->x0);
    qdc_free(c->xn);
    qdc_free(c->xbest);
    qdc_free(c->trial);
    qdc_free(c->tmp);
    qdc_free(c->rhs);
    qdc_free(c->d);
    qdc_free(c->locked);
    qdc_free(c->wq2);
    qdc_free(c->bw2);
    qdc_free(c->dg);
    qdc_free(c->qt);
    qdc_free(c->eta);
    qdc_free(c->qval);
    qdc_free(c->fslot);
}

/* The cube of tet tt's mean ratio at y (signed; MIVL's parts need no
 * adjugate): compared with a cubed floor, no cube root per tet. */
double ctx_tet_eta3(const double *y, const int32_t *tt)
{
    metric_parts pt;
    metric_parts_for(OPT_METRIC_MIVL, y + 3 * (size_t)tt[0], y + 3 * (size_t)tt[1],
                     y + 3 * (size_t)tt[2], y + 3 * (size_t)tt[3], &pt);
    return metric_mean_ratio_cubed(&pt);
}

void ctx_mark_corners(ctx_t *c, const int32_t *tt)
{
    for (int a = 0; a < 4; a++) {
#pragma omp atomic write
        c->vmark[tt[a]] = 1;
    }
}

/* The record of a finishing or angle pass, whose result is in c->trial. */
void ctx_pass_record(ctx_t *c, opt_progress *r, int *next, const char *phase)
{
    memcpy(c->x, c->trial, 3 * (size_t)c->nv * sizeof(double));
    ctx_evaluate(c, c->x, r, NULL);
    r->iteration = (*next)++;
    r->phase = phase;
}
