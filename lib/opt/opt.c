/* opt.c - the QDC optimizer: outer loop of the semi-implicit gradient flow
 * (paper Eq. 15) with the safeguards of docs/method.md §5 (mu = 1 in normalized units,
 * backtracking line search on sum q~, best iterate kept), harmonic guidance
 * (§6) and the finishing pass (§5a). */
#include "opt/opt.h"

#include "core/order.h"
#include "core/tet.h"
#include "geom/metric.h"
#include "opt/encode.h"
#include "opt/finish.h"
#include "opt/harm.h"
#include "opt/slide.h"
#include "opt/solve.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void opt_defaults(opt_options *o)
{
    memset(o, 0, sizeof *o);
    o->metric = OPT_METRIC_MIVL;
    o->boundary = OPT_BOUNDARY_SLIDE;
    o->hausd_rel = OPT_HAUSD_AUTO;
    o->mode = OPT_MODE_SAFE;
    o->weights = OPT_WEIGHTS_OPTAVG;
    o->solver = OPT_SOLVER_AUTO;
    o->harmonic = 0;
    o->pre_iters = 3;
    o->finish = 1;
    o->max_iter = 10;
    o->ls_halvings = 10;
    o->mu = 1.0;
    o->tol_move = 1e-3;
    o->stall = 2e-3;
    o->eps_rel = 1e-3;
    o->finish_frac = 1.0;
    o->finish_sweeps = 32;
    o->finish_gain = 5e-4;
    o->angle_polish = 1;
    o->feature_angle = 30.0;
}

static const char *const metric_names[] = {"mivl", "mimr", "micn"};
static const char *const boundary_names[] = {"lsq", "fixed", "slide"};
static const char *const mode_names[] = {"safe", "literal"};
static const char *const weights_names[] = {"optavg", "paper"};
static const char *const solver_names[] = {"auto", "cholmod", "pcg"};

static qdc_status parse_word(const char *s, const char *const *names, int n, int *out)
{
    for (int i = 0; s && i < n; i++)
        if (strcmp(s, names[i]) == 0) {
            *out = i;
            return QDC_OK;
        }
    return QDC_EINVAL;
}

#define PARSER(fn, type, names)                                                          \
    qdc_status fn(const char *s, type *out)                                              \
    {                                                                                    \
        int v;                                                                           \
        qdc_status st = parse_word(s, names, (int)(sizeof names / sizeof names[0]), &v); \
        if (st == QDC_OK)                                                                \
            *out = (type)v;                                                              \
        return st;                                                                       \
    }
PARSER(opt_parse_metric, opt_metric, metric_names)
PARSER(opt_parse_boundary, opt_boundary, boundary_names)
PARSER(opt_parse_mode, opt_mode, mode_names)
PARSER(opt_parse_weights, opt_weights, weights_names)
PARSER(opt_parse_solver, opt_solver, solver_names)

/* A finite, non-negative number filling all of s (no spaces, no trailing bytes). */
static int parse_nonneg(const char *s, double *out)
{
    char *end;
    double v;

    if (!s || !*s || isspace((unsigned char)*s))
        return -1;
    errno = 0;
    v = strtod(s, &end);
    if (end == s || *end || errno || !isfinite(v) || v < 0)
        return -1;
    *out = v;
    return 0;
}

qdc_status opt_parse_hausd(const char *s, opt_options *o)
{
    size_t n = s ? strlen(s) : 0;
    double v;
    char buf[64];

    if (!n || n >= sizeof buf)
        return QDC_EINVAL;
    if (!strcmp(s, "auto") || !strcmp(s, "none")) {
        o->hausd = 0;
        o->hausd_rel = s[0] == 'a' ? OPT_HAUSD_AUTO : 0.0;
        return QDC_OK;
    }
    if (!strncmp(s, "rel:", 4)) {
        if (parse_nonneg(s + 4, &v))
            return QDC_EINVAL;
        o->hausd = 0;
        o->hausd_rel = v;
        return QDC_OK;
    }
    if (s[n - 1] == '%') {
        memcpy(buf, s, n - 1);
        buf[n - 1] = 0;
        if (parse_nonneg(buf, &v))
            return QDC_EINVAL;
        o->hausd = 0;
        o->hausd_rel = v / 100.0;
        return QDC_OK;
    }
    if (parse_nonneg(s, &v))
        return QDC_EINVAL;
    o->hausd = v;
    o->hausd_rel = 0;
    return QDC_OK;
}

#define NAMER(fn, type, names)                                                           \
    const char *fn(type v)                                                               \
    {                                                                                    \
        return (unsigned)v < sizeof names / sizeof names[0] ? names[v] : "?";            \
    }
NAMER(opt_metric_name, opt_metric, metric_names)
NAMER(opt_boundary_name, opt_boundary, boundary_names)
NAMER(opt_mode_name, opt_mode, mode_names)
NAMER(opt_weights_name, opt_weights, weights_names)
NAMER(opt_solver_name, opt_solver, solver_names)

typedef struct {
    const opt_options *o;
    const mesh_topo *tp;
    int32_t nv, nt;
    double center[3], scale; /* x = (X - center) / scale */
    double lbar, eps;
    double *x, *x0, *xn, *xbest, *trial, *tmp, *rhs;
    uint8_t *locked;  /* not an unknown of the linear system */
    double *vfac;     /* nv: share of the step each vertex takes (feasible step) */
    double hbound;    /* --hausd in normalized units (0: none) */
    int autob;        /* the default bound (--hausd auto under slide) */
    int rerun_stuck;  /* tets left inverted get a rerun (run_once's stuck): no angle
                       * pass on such a result, the rerun's own does it */
    int keep_surface; /* the finishing pass folds no tet at the surface (finish.h) */
    uint8_t *vmark;   /* nv: scratch marks */
    int32_t *vlist;   /* nv: scratch list of vertices */
    double *wq2;      /* squared QDC row weights */
    double *bw2;      /* squared boundary row weights (0: no row) */
    double *dg;       /* bw2 + mu */
    double *qt, *qval, *d;
    uint8_t *fslot; /* encode_face_slots (NULL: searched) */
    double *eta; /* nt: mean ratio per tet at the x of the last evaluate() that asked */
    double eta_delta;   /* and the delta of that x */
    double mu_factor;   /* omega_B^2 once harmonic guidance is on and mu_scaled */
    const double *bref; /* targets of the boundary rows: x0 (lsq) or x_k (slide) */
    slide_ctx *sl;      /* slide mode only */
    solve_ctx *sol;
    double t0;
    opt_progress input, best;
    int best_it;
    int last_record; /* number of the last progress record */
} ctx_t;

static void logf_(const ctx_t *c, int level, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void logf_(const ctx_t *c, int level, const char *fmt, ...)
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
 * tet's mean ratio for the finishing pass. */
static double evaluate(const ctx_t *c, const double *x, opt_progress *r, double *eta_out)
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
    r->objective =
        fuse && delta == 0.0 ? obj : encode_objective(tp, x, m, delta, NULL, NULL);
    r->elapsed = qdc_now() - c->t0;
    r->solver = c->sol ? (int)solve_kind(c->sol) : 0;
    return delta;
}

/* Mean ratio of every tet into eta and the fields of r that the choice of
 * the best iterate reads (mean, worst, inverted count; fixed chunks summed in
 * order); returns the delta of x. */
static double scan_light(const ctx_t *c, const double *x, double *eta, opt_progress *r)
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
static int better(const opt_progress *a, const opt_progress *b)
{
    if (a->n_inverted != b->n_inverted)
        return a->n_inverted < b->n_inverted;
    if (fabs(a->q_min - b->q_min) > 1e-4)
        return a->q_min > b->q_min;
    return a->q_mean > b->q_mean;
}

/* ... and on a valid input, never one with a lower mean ratio either (an
 * sfepy file's mean fell 0.7274 -> 0.7246 while its worst tet rose). */
static int eligible(const ctx_t *c, const opt_progress *r)
{
    return r->n_inverted <= c->input.n_inverted && r->q_min >= c->input.q_min &&
           (c->input.n_inverted > 0 || r->q_mean >= c->input.q_mean);
}

static void consider(ctx_t *c, const double *x, const opt_progress *r)
{
    if (eligible(c, r) && better(r, &c->best)) {
        c->best = *r;
        c->best_it = r->iteration;
        memcpy(c->xbest, x, 3 * (size_t)c->nv * sizeof(double));
    }
}

static int report(ctx_t *c, opt_progress *r)
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

/* The reason a run stops: the enum decides, the name is for reports. */
static void set_stop(opt_result *res, opt_stop s)
{
    res->stop = s;
    snprintf(res->stop_reason, sizeof res->stop_reason, "%s", opt_stop_name(s));
}

static int should_stop(const ctx_t *c, opt_result *res)
{
    if (c->o->cancel && atomic_load(c->o->cancel)) {
        set_stop(res, OPT_STOP_CANCELLED);
        return 1;
    }
    if (c->o->time_limit > 0 && qdc_now() - c->t0 > c->o->time_limit) {
        set_stop(res, OPT_STOP_TIME_LIMIT);
        return 1;
    }
    return 0;
}

static qdc_status ctx_init(ctx_t *c, const mesh_t *m, const mesh_topo *tp,
                           const opt_options *o)
{
    size_t n3 = 3 * (size_t)m->nv;
    double lo[3], hi[3], diag, esum = 0;
    int64_t ecount = 0;

    memset(c, 0, sizeof *c);
    c->o = o;
    c->tp = tp;
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
    for (int32_t i = 0; i < tp->nv; i++)
        for (int32_t s = tp->adj_ptr[i]; s < tp->adj_ptr[i + 1]; s++) {
            int32_t j = tp->adj_idx[s];
            const double *a = c->x + 3 * (size_t)i, *b = c->x + 3 * (size_t)j;
            if (j <= i)
                continue;
            esum += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                         (a[2] - b[2]) * (a[2] - b[2]));
            ecount++;
        }
    c->lbar = ecount ? esum / (double)ecount : 1.0;
    c->bref = c->x0;
    c->mu_factor = 1.0;
    /* the default (auto, under slide): the Hausdorff bound OPT_HAUSD_DEFAULT */
    c->autob = o->hausd <= 0 && o->hausd_rel == OPT_HAUSD_AUTO &&
               o->boundary == OPT_BOUNDARY_SLIDE;
    c->hbound = o->hausd > 0       ? o->hausd / c->scale
                : o->hausd_rel > 0 ? o->hausd_rel
                : c->autob         ? OPT_HAUSD_DEFAULT
                                   : 0.0;
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

static void ctx_free(ctx_t *c)
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

/* Harmonic guidance (Eq. 10): QDC rows weighted omega_1 h_i, boundary rows
 * omega_B, omega_B = n / n_boundary, omega_1 = 0.4 omega_B (paper Sec. 5.1). */
static qdc_status set_harmonic(ctx_t *c, opt_result *res, qdc_error *err)
{
    double t = qdc_now(), *h = qdc_mallocn((size_t)c->nv, sizeof(double));
    double wb = (double)c->nv / (c->tp->nb > 0 ? c->tp->nb : 1), w1 = 0.4 * wb;
    int32_t nmed = 0;
    qdc_status st;

    if (!h)
        return QDC_ENOMEM;
    st = harm_field(c->tp, c->x, h, &nmed, err);
    if (st == QDC_OK) {
        for (int32_t v = 0; v < c->nv; v++) {
            c->wq2[v] = (w1 * h[v]) * (w1 * h[v]);
            if (c->bw2[v] > 0)
                c->bw2[v] = wb * wb;
        }
        if (c->o->mu_scaled)
            c->mu_factor = wb * wb;
        logf_(c, 0, "harmonic guidance: %d medial vertices, omega_B %.3g", (int)nmed, wb);
    }
    qdc_free(h);
    res->t_harmonic += qdc_now() - t;
    return st;
}

/* Slide mode: put the sliding vertices of y back on their input surface/line. */
static void project_sliding(const ctx_t *c, double *y)
{
    if (!c->sl)
        return;
#pragma omp parallel for schedule(dynamic, 256)
    for (int32_t v = 0; v < c->nv; v++) {
        int k = slide_kind(c->sl, v);
        if (k == SLIDE_SURFACE || k == SLIDE_LINE) {
            double p[3];
            slide_project(c->sl, v, y + 3 * (size_t)v, p);
            memcpy(y + 3 * (size_t)v, p, sizeof p);
        }
    }
}

/* Tets inverted or flat at y (*ninv), and of those the ones usable at x (the
 * tets a move from x to y folds or flattens), in one parallel scan. */
static int32_t count_folds(const mesh_topo *tp, const double *x, const double *y,
                           int32_t *ninv)
{
    int32_t folds = 0, n = 0;

#pragma omp parallel for reduction(+ : folds, n) schedule(static)
    for (int32_t t = 0; t < tp->nt; t++) {
        const int32_t *tt = tp->tets + 4 * (size_t)t;
        int bad = geom_tet_bad(y, tt);
        n += bad;
        folds += bad && !geom_tet_bad(x, tt);
    }
    *ninv = n;
    return folds;
}

/* --hausd under lsq: boundary and interface vertices within c->hbound of their
 * input positions (slide mode does it in slide_project). */
static void clamp_boundary(const ctx_t *c, double *y)
{
    if (!(c->hbound > 0) || c->sl)
        return;
#pragma omp parallel for schedule(static)
    for (int32_t v = 0; v < c->nv; v++)
        if (c->tp->vflag[v] & (MESH_V_BOUNDARY | MESH_V_INTERFACE))
            slide_clamp(c->x0, v, c->hbound, y + 3 * (size_t)v);
}

/* c->trial = the step of length s from c->x toward c->xn, feasible: no tet
 * that is valid at c->x is inverted at the trial, unless c->x is tangled
 * (ninv_x inverted tets) and the whole step leaves no more inverted tets than
 * that; either way the inverted count never rises. Each vertex of a
 * tet the plain step would fold takes half its share of the step, again and
 * again (after 6 halvings none of it), like Mesquite's feasible Newton step
 * but per vertex: the rest of the mesh keeps its whole step. A vertex held at
 * c->x can still leave a neighbour tet folded by its other corners, which are
 * then held in the next round; with every vertex held the trial is c->x,
 * which folds nothing, so the rounds end. */
/* The cube of tet tt's mean ratio at y (signed; MIVL's parts need no
 * adjugate): compared with a cubed floor, no cube root per tet. */
static double tet_eta3(const double *y, const int32_t *tt)
{
    metric_parts pt;
    metric_parts_for(OPT_METRIC_MIVL, y + 3 * (size_t)tt[0], y + 3 * (size_t)tt[1],
                     y + 3 * (size_t)tt[2], y + 3 * (size_t)tt[3], &pt);
    return metric_mean_ratio_cubed(&pt);
}

/* Whether a trial spoils tet tt: it folds or flattens a tet usable at x or, on a valid
 * mesh, takes a tet below the worst mean ratio at x, whose cube is qfloor3
 * (the worst tet of the mesh never gets worse, so the global phase's work is
 * kept). */
static int spoils(const ctx_t *c, const double *y, const int32_t *tt, double qfloor3)
{
    if (geom_tet_bad(y, tt))
        return !geom_tet_bad(c->x, tt);
    return qfloor3 > 0 && tet_eta3(y, tt) < qfloor3;
}

/* c->trial of vertex v: its share vfac[v] of the step s, then onto its
 * sliding constraint or within the --hausd bound (as project_sliding and
 * clamp_boundary do for the whole mesh). */
static void place_vertex(ctx_t *c, int32_t v, double s)
{
    double *y = c->trial + 3 * (size_t)v;

    for (int k = 0; k < 3; k++) {
        size_t q = 3 * (size_t)v + k;
        y[k] = c->x[q] + s * c->vfac[v] * (c->xn[q] - c->x[q]);
    }
    if (c->sl) {
        int kind = slide_kind(c->sl, v);
        if (kind == SLIDE_SURFACE || kind == SLIDE_LINE) {
            double p[3];
            slide_project(c->sl, v, y, p);
            memcpy(y, p, sizeof p);
        }
    } else if (c->hbound > 0 &&
               (c->tp->vflag[v] & (MESH_V_BOUNDARY | MESH_V_INTERFACE))) {
        slide_clamp(c->x0, v, c->hbound, y);
    }
}

static void mark_corners(ctx_t *c, const int32_t *tt)
{
    for (int a = 0; a < 4; a++) {
#pragma omp atomic write
        c->vmark[tt[a]] = 1;
    }
}

static void feasible_trial(ctx_t *c, double s, int32_t ninv_x, double qfloor3)
{
    const mesh_topo *tp = c->tp;
    int32_t nv = c->nv, folds = 0, ninv = 0;

#pragma omp parallel for schedule(static)
    for (int32_t v = 0; v < nv; v++) {
        c->vfac[v] = 1.0;
        for (int k = 0; k < 3; k++) {
            size_t q = 3 * (size_t)v + k;
            c->trial[q] = c->x[q] + s * (c->xn[q] - c->x[q]);
        }
    }
    project_sliding(c, c->trial);
    clamp_boundary(c, c->trial);
#pragma omp parallel for reduction(+ : folds, ninv) schedule(static)
    for (int32_t t = 0; t < tp->nt; t++) {
        const int32_t *tt = tp->tets + 4 * (size_t)t;
        int bad = spoils(c, c->trial, tt, qfloor3);
        ninv += geom_tet_bad(c->trial, tt);
        folds += bad;
        if (bad)
            mark_corners(c, tt);
    }
    /* A tangled mesh untangles faster when a step may fold a few valid
     * tets while it frees more (measured on the tangled dev meshes: the
     * strict rule cost 0.008 of mean ratio on sphere and torus): the
     * whole step is taken when the inverted count does not rise, under
     * lsq only. Not while sliding: there such steps squashed smooth ears
     * flat (bunny_tangled-low_10k: worst tet 6e-11 instead of 0.054); not
     * with a fixed boundary, where they folded 458-2826 valid tets of the
     * tangled dev meshes for no gain (mean ratio equal within 0.0002,
     * none left inverted either way). */
    if (!folds || (ninv_x > 0 && ninv <= ninv_x && c->o->boundary == OPT_BOUNDARY_LSQ)) {
        if (folds)
            memset(c->vmark, 0, (size_t)nv);
        return;
    }
    /* Then only the marked vertices move back, and only their tets can
     * change: each round looks at those alone (a whole-mesh scan per round
     * made the line search 24x slower at 1M tets). */
    for (int round = 0;; round++) {
        int32_t n = 0, again = 0;
        for (int32_t v = 0; v < nv; v++)
            if (c->vmark[v]) {
                c->vmark[v] = 0;
                c->vlist[n++] = v;
            }
        if (!n)
            return;
        if (round > 64) { /* cannot happen (see above); never loop for ever */
            memcpy(c->trial, c->x, 3 * (size_t)nv * sizeof(double));
            return;
        }
        /* in parallel: a vertex writes only its own trial position, and the
         * marks are a set (measured on a thin bone of 100k tets, where half
         * the vertices are held in the first round, the serial rounds took
         * 40 ms of each iteration's 50 ms of line search) */
#pragma omp parallel for schedule(dynamic, 256)
        for (int32_t i = 0; i < n; i++) {
            int32_t v = c->vlist[i];
            c->vfac[v] = round < 6 && c->vfac[v] > 0.0 ? 0.5 * c->vfac[v] : 0.0;
            place_vertex(c, v, s);
        }
#pragma omp parallel for reduction(| : again) schedule(dynamic, 256)
        for (int32_t i = 0; i < n; i++) {
            int32_t v = c->vlist[i];
            for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
                const int32_t *tt = tp->tets + 4 * (size_t)(tp->vt_idx[k] >> 2);
                if (spoils(c, c->trial, tt, qfloor3)) {
                    mark_corners(c, tt);
                    again = 1;
                }
            }
        }
        if (!again)
            return;
    }
}

/* One iteration of Eq. 15 plus the line search. Fills r (without quality).
 * Returns QDC_OK; *stepped = 0 when no step decreased the objective. */
static qdc_status iterate(ctx_t *c, opt_result *res, opt_progress *r, int *stepped,
                          qdc_error *err)
{
    const opt_options *o = c->o;
    const mesh_topo *tp = c->tp;
    size_t n3 = 3 * (size_t)c->nv;
    int literal = o->mode == OPT_MODE_LITERAL;
    double t = qdc_now(), delta, f0, mu, step = 1.0, move = 0;
    int cg = 0;
    int32_t folded = 0;
    qdc_status st;

    /* q~ at x_k with one global delta (docs/method.md §2) */
    delta = metric_delta(encode_min_arg(tp, c->x, o->metric), c->eps);
    f0 = encode_objective(tp, c->x, o->metric, delta, c->qt, NULL);
    if (literal || o->weights == OPT_WEIGHTS_PAPER)
        encode_paper(tp, c->x, o->metric, c->qt, c->qval, c->d);
    else
        encode_optavg(tp, c->x, o->metric, c->qt, c->fslot, c->qval, c->d);
    res->t_weights += qdc_now() - t;
    t = qdc_now();
    if (literal) {
        /* paper as written: mu_k = ||G^T W^2 g||^2 = ||omega_B^2 b||^2 (constant) */
        mu = 0;
        for (int32_t v = 0; v < c->nv; v++)
            for (int k = 0; k < 3; k++)
                mu += c->bw2[v] * c->bw2[v] * c->x0[3 * (size_t)v + k] *
                      c->x0[3 * (size_t)v + k];
        if (!(mu > 0))
            mu = 1.0;
    } else {
        mu = o->mu * c->mu_factor;
    }
    /* b = Q_F^T W (d - Q x_L) + bw2 x0 + mu x_k: locked vertices move to the right
     * (the per-vertex loops of the iteration run in parallel: each entry alone) */
#pragma omp parallel for schedule(static)
    for (int32_t v = 0; v < c->nv; v++) {
        for (int k = 0; k < 3; k++)
            c->tmp[3 * (size_t)v + k] = c->locked[v] ? c->x[3 * (size_t)v + k] : 0.0;
        c->dg[v] = c->bw2[v] + mu;
    }
    solve_q_mul(tp, c->qval, c->tmp, c->trial);
#pragma omp parallel for schedule(static)
    for (int32_t v = 0; v < c->nv; v++)
        for (int k = 0; k < 3; k++) {
            size_t q = 3 * (size_t)v + k;
            c->trial[q] = c->wq2[v] * (c->d[q] - c->trial[q]);
        }
    solve_qt_mul(c->sol, c->qval, c->trial, c->rhs);
#pragma omp parallel for schedule(static)
    for (int32_t v = 0; v < c->nv; v++)
        for (int k = 0; k < 3; k++) {
            size_t q = 3 * (size_t)v + k;
            c->rhs[q] += c->bw2[v] * c->bref[q] + mu * c->x[q];
        }
    res->t_assembly += qdc_now() - t;
    t = qdc_now();
    memcpy(c->xn, c->x, n3 * sizeof(double));
    st = solve_system(c->sol, c->qval, c->wq2, c->dg, c->rhs, c->xn, &cg, err);
    res->t_solve += qdc_now() - t;
    if (st != QDC_OK)
        return st;
    {
        int finite = 1;
#pragma omp parallel for reduction(&& : finite) schedule(static)
        for (size_t q = 0; q < n3; q++)
            finite = finite && isfinite(c->xn[q]);
        if (!finite)
            return qdc_fail(err, QDC_ESOLVE, "linear solve returned a non-finite value");
    }
    t = qdc_now();
    if (!literal) {
        /* Not in the paper (docs/method.md §5): backtrack on sum q~ with delta frozen;
         * with delta = 0 a trial that inverts a tet costs +inf. */
        /* A step that lowers sum q~ may still fold valid tets: with delta > 0
         * (any tet below eps, common on sliver meshes) an inverted tet costs
         * a finite q~, and measured on 100k-1M-tet valid meshes with 40-50%
         * boundary vertices the accepted steps folded 26-331 tets. So a trial
         * is accepted only if it folds no valid tet while the mesh is valid,
         * and never raises the inverted count of a tangled one. */
        int h;
        int32_t ninv_x = 0;
        double qfloor3 = INFINITY;
#pragma omp parallel for reduction(min : qfloor3) reduction(+ : ninv_x) schedule(static)
        for (int32_t e = 0; e < tp->nt; e++) {
            const int32_t *tt = tp->tets + 4 * (size_t)e;
            double q = tet_eta3(c->x, tt);
            qfloor3 = q < qfloor3 ? q : qfloor3;
            ninv_x += geom_tet_bad(c->x, tt);
        }
        for (h = 0; h <= o->ls_halvings; h++) {
            feasible_trial(c, step, ninv_x, qfloor3);
            if (encode_objective(tp, c->trial, o->metric, delta, NULL, NULL) < f0)
                break;
            step *= 0.5;
        }
        if (h > o->ls_halvings)
            step = 0.0;
    }
    res->t_linesearch += qdc_now() - t;
    if (literal) {
        for (size_t q = 0; q < n3; q++)
            c->trial[q] = c->xn[q];
        project_sliding(c, c->trial);
    } else if (step == 0.0) {
        memcpy(c->trial, c->x, n3 * sizeof(double));
    } /* else c->trial holds the accepted feasible trial */
    {
        int32_t ninv_t;
        folded = step > 0.0 ? count_folds(tp, c->x, c->trial, &ninv_t) : 0;
    }
#pragma omp parallel for reduction(max : move) schedule(static)
    for (int32_t v = 0; v < c->nv; v++) {
        double dd = 0;
        for (int k = 0; k < 3; k++) {
            size_t q = 3 * (size_t)v + k;
            double dx = step > 0.0 ? c->trial[q] - c->x[q] : 0.0;
            c->x[q] += dx;
            dd += dx * dx;
        }
        if (dd > move)
            move = dd;
    }
    c->eta_delta = evaluate(c, c->x, r, c->eta);
    r->n_folded = folded;
    r->step = step;
    r->max_move = sqrt(move) / c->lbar;
    r->cg_iters = cg;
    *stepped = step > 0.0;
    return QDC_OK;
}

/* The record of a finishing or angle pass, whose result is in c->trial. */
static void pass_record(ctx_t *c, opt_progress *r, int *next, const char *phase)
{
    memcpy(c->x, c->trial, 3 * (size_t)c->nv * sizeof(double));
    evaluate(c, c->x, r, NULL);
    r->iteration = (*next)++;
    r->phase = phase;
}

/* The finishing pass (docs/method.md §5a) from c->x: regular sweeps over the worst
 * finish_frac of tets, then polish sweeps over the worst 1% while the worst tet
 * still improves (measured on the dev corpus: it keeps rising for a few more
 * sweeps). Each sweep is a progress record numbered from *next. */
static qdc_status finish_pass(ctx_t *c, const uint8_t *movable, int x_evaluated,
                              opt_result *res, opt_progress *r, int *next)
{
    const opt_options *o = c->o;
    size_t n3 = 3 * (size_t)c->nv;
    opt_progress cur, keep;
    double delta, moves = 0, visits = 0;
    int swept = 0;

    /* The sweeps need the tet qualities and delta of x, which the last global
     * iterate's record already has. Between sweeps only a light scan (a full
     * record costs 3x as much); one record for the whole pass. */
    if (x_evaluated) {
        delta = c->eta_delta;
        cur = *r;
    } else {
        delta = scan_light(c, c->x, c->eta, &cur);
    }
    for (int s = 0; s < o->finish_sweeps; s++) {
        finish_stats fs;
        qdc_status st;
        double mean0 = cur.q_mean;
        if (should_stop(c, res))
            return QDC_OK;
        /* broad sweeps: one Newton step per vertex (finish.c) */
        st = finish_sweep(c->tp, movable, c->sl, c->x, o->metric, c->eta, delta, c->lbar,
                          o->finish_frac, 1e-3, c->keep_surface, &fs);
        if (st != QDC_OK)
            return st;
        swept |= fs.n_moves > 0;
        moves += fs.n_moves;
        visits += fs.n_verts;
        delta = scan_light(c, c->x, c->eta, &cur);
        if (fs.n_moves == 0 ||
            (o->finish_gain > 0 && !(cur.q_mean - mean0 > o->finish_gain)))
            break;
    }
    /* polish sweeps over the worst 1% while the worst tet rises by 1e-3; the
     * best state by (inverted, worst, mean) is kept in c->trial */
    keep = cur;
    memcpy(c->trial, c->x, n3 * sizeof(double));
    for (int s = 0; s < 8; s++) {
        finish_stats fs;
        qdc_status st;
        if (should_stop(c, res))
            break;
        st = finish_sweep(c->tp, movable, c->sl, c->x, o->metric, c->eta, delta, c->lbar,
                          0.01, 0.0, c->keep_surface, &fs);
        if (st != QDC_OK)
            return st;
        if (fs.n_moves == 0)
            break;
        swept = 1;
        moves += fs.n_moves;
        visits += fs.n_verts;
        delta = scan_light(c, c->x, c->eta, &cur);
        if (!better(&cur, &keep))
            break;
        memcpy(c->trial, c->x, n3 * sizeof(double));
        if (cur.q_min < keep.q_min + 1e-3) {
            keep = cur;
            break;
        }
        keep = cur;
    }
    if (!swept)
        return QDC_OK;
    pass_record(c, r, next, "finish");
    r->step = visits > 0 ? moves / visits : 0; /* accepted moves per visited vertex */
    consider(c, c->x, r);
    if (report(c, r))
        set_stop(res, OPT_STOP_CANCELLED);
    return QDC_OK;
}

/* Worst-angle polish (finish.h) from the best iterate: a round of joint moves
 * on the worst mean ratios, sweeps over the worst 1% of tets by dihedral sine
 * while their mean sine rises by 0.1%, then rounds of joint moves on the
 * sines. The worst mean ratio may not fall below the best iterate's (the floor
 * of every move) and the smallest sine cannot drop, so a sweep that raises the
 * score is kept. */
#define ANGLE_SWEEPS 12
/* ... and ends after ANGLE_SLOW sweeps in a row that leave the smallest sine
 * where it was and raise that mean by less than 1%: measured on the thin bones
 * (scripts/corpus.py --tets 100000), bone-scan's last 4 of 9 sweeps raised
 * it by 0.8% in all; on the 21 dev meshes and the 100k
 * ball no smallest angle changed (the mean ratio by at most +0.0001) */
#define ANGLE_SLOW 2
/* ... where a sweep lifting the smallest sine by less than sin 0.05 degrees
 * does not count as lifting it: measured on bone-scan (scripts/corpus.py at
 * 100k tets), whose slivers no move opens, the sweeps went on for 9 sweeps
 * lifting it from 0.069 to 0.108 degrees, 0.1 s of a 1.0 s run */
#define ANGLE_MIN_RISE 8.7e-4
#define ANGLE_PATCH_ROUNDS 4
static qdc_status angle_pass(ctx_t *c, const uint8_t *movable, const slide_ctx *sl,
                             opt_result *res, opt_progress *r, int *next)
{
    /* the tet sines a sweep leaves are those the next one starts from (a
     * rejected sweep ends the pass); c->eta is free scratch here, c->trial
     * holds the last accepted sweep */
    double *smin = c->eta;
    const opt_progress base = c->best;
    size_t n3 = 3 * (size_t)c->nv;
    int kept = 0, slow = 0, smin_ok = 0; /* smin is of c->trial */
    double moves = 0, visits = 0;

    memcpy(c->x, c->xbest, n3 * sizeof(double));
    /* first one round of joint moves of the worst tets' corners on their mean
     * ratios (finish.h), kept if the worst tet improves: the angle moves then
     * start from it, with the floor of the best iterate */
    if (!should_stop(c, res)) {
        finish_stats fs;
        opt_progress cur;
        qdc_status st = finish_patches(c->tp, movable, sl, c->x, c->lbar,
                                       FINISH_PATCH_MEAN_RATIO, 0.0, c->eta, 0, &fs);
        if (st != QDC_OK)
            return st;
        (void)scan_light(c, c->x, c->eta, &cur);
        if (better(&cur, &base)) {
            memcpy(c->trial, c->x, n3 * sizeof(double));
            kept = 1;
            moves += fs.n_moves;
            visits += fs.n_verts;
        } else {
            memcpy(c->x, c->xbest, n3 * sizeof(double));
        }
    }
    for (int s = 0; s < ANGLE_SWEEPS; s++) {
        finish_stats fs;
        qdc_status st;
        int floor_up;
        if (should_stop(c, res))
            break;
        st = finish_dihedral_sweep(c->tp, movable, sl, c->x, c->lbar, 0.01, base.q_min,
                                   smin, s > 0, &fs);
        if (st != QDC_OK)
            return st;
        /* the floor keeps q_min and positivity keeps the inverted count; a
         * sweep is kept if it raises the smallest sine of the mesh, or keeps it
         * and raises the mean of the worst 1% (measured on bunny_good_10k: the
         * smallest angle 10.3 -> 11.7 degrees while that mean dips by 0.1%) */
        smin_ok = fs.floor_after > fs.floor_before ||
                  (fs.floor_after >= fs.floor_before && fs.score_after > fs.score_before);
        if (!smin_ok)
            break;
        memcpy(c->trial, c->x, n3 * sizeof(double));
        kept = 1;
        moves += fs.n_moves;
        visits += fs.n_verts;
        floor_up = fs.floor_after > fs.floor_before * (1 + 1e-3) &&
                   fs.floor_after - fs.floor_before > ANGLE_MIN_RISE;
        if (fs.n_moves == 0 ||
            !(floor_up || fs.score_after > fs.score_before * (1 + 1e-3)))
            break;
        slow = floor_up || fs.score_after > fs.score_before * 1.01 ? 0 : slow + 1;
        if (slow >= ANGLE_SLOW)
            break;
    }
    /* then the worst tets' corners together (finish.h), while that lifts the
     * smallest sine */
    for (int round = 0; round < ANGLE_PATCH_ROUNDS; round++) {
        finish_stats fs;
        qdc_status st;
        if (should_stop(c, res))
            break;
        memcpy(c->x, kept ? c->trial : c->xbest, n3 * sizeof(double));
        st = finish_patches(c->tp, movable, sl, c->x, c->lbar, FINISH_PATCH_ANGLES,
                            base.q_min, smin, round > 0 || smin_ok, &fs);
        if (st != QDC_OK)
            return st;
        if (!(fs.floor_after > fs.floor_before))
            break;
        memcpy(c->trial, c->x, n3 * sizeof(double));
        kept = 1;
        moves += fs.n_moves;
        visits += fs.n_verts;
        if (!(fs.floor_after > fs.floor_before * (1 + 1e-3)))
            break;
    }
    if (!kept)
        return QDC_OK;
    /* one record for the pass (a record costs a sweep's worth of work) */
    pass_record(c, r, next, "angles");
    r->step = visits > 0 ? moves / visits : 0;
    if (eligible(c, r) && r->n_inverted <= base.n_inverted && r->q_min >= base.q_min) {
        c->best = *r;
        c->best_it = r->iteration;
        memcpy(c->xbest, c->x, n3 * sizeof(double));
    }
    if (report(c, r))
        set_stop(res, OPT_STOP_CANCELLED);
    return QDC_OK;
}

/* lsq's angle pass without --hausd: how far a curved part's vertex may leave
 * the input surface (of the diagonal) */
#define LSQ_POLISH_LIFT 1e-3

/* The angle pass; with lsq, boundary vertices take part too, on the input
 * surface as in slide mode (projected back onto its triangles, off a curved
 * part by at most the default allowance): the worst tets of good meshes often
 * have all four corners on the boundary (measured: bunny_good_10k 11.7 -> 14.9,
 * torus_h0.1_good 10.4 -> 14.2 degrees, boundary error unchanged at the lsq
 * level). */
static qdc_status lsq_angle_pass(ctx_t *c, const uint8_t *movable, opt_result *res,
                                 opt_progress *r, int *next)
{
    slide_ctx *sl = NULL;
    uint8_t *mv = NULL;
    qdc_status st;

    if (c->sl || c->o->boundary != OPT_BOUNDARY_LSQ)
        return angle_pass(c, movable, c->sl, res, r, next);
    st = slide_new(c->tp, c->x0, c->o->feature_angle, &sl, NULL);
    /* without a bound, a curved part's vertices may leave the input surface
     * by LSQ_POLISH_LIFT: lsq has moved the boundary already, and sliding
     * alone cannot reopen an ear the global step flattened (measured on
     * torus_h0.1_good: smallest dihedral 12.6 degrees sliding, 14.2 with it) */
    if (st == QDC_OK && c->hbound > 0)
        slide_set_bound(sl, c->hbound);
    else if (st == QDC_OK)
        slide_set_lift(sl, LSQ_POLISH_LIFT);
    mv = st == QDC_OK ? qdc_mallocn((size_t)c->nv, 1) : NULL;
    if (!mv) {
        slide_free(sl);
        return QDC_ENOMEM;
    }
    for (int32_t v = 0; v < c->nv; v++)
        mv[v] = movable[v] || (!c->locked[v] && slide_kind(sl, v) != SLIDE_CORNER);
    st = angle_pass(c, mv, sl, res, r, next);
    qdc_free(mv);
    slide_free(sl);
    return st;
}

/* Mean ratio of tet t at coordinates x. */
static double tet_mean_ratio(const mesh_topo *tp, const double *x, int32_t t)
{
    const int32_t *tt = tp->tets + 4 * (size_t)t;
    metric_parts pt;
    metric_parts_of(x + 3 * (size_t)tt[0], x + 3 * (size_t)tt[1], x + 3 * (size_t)tt[2],
                    x + 3 * (size_t)tt[3], &pt);
    return metric_mean_ratio(&pt);
}

/* Slide mode: the corners of the smooth ears (slide.h) that the run squashed
 * to less than half their input mean ratio and to among the worst tets of its
 * result (under twice its worst mean ratio, or inverted), as an nv mask (NULL
 * if none). An ear squashed but still far above the worst tet costs nothing
 * that holding it would buy back: measured on a tangled thin bone
 * (scripts/corpus.py --tets 100000, bone-scan-tangled), three reruns for such
 * ears, each worse than the first run (worst mean ratio 0.0032 -> 0.0026 and
 * below), took 4.7x the time. */
static qdc_status squashed_ears(const ctx_t *c, uint8_t **out)
{
    const mesh_topo *tp = c->tp;
    uint8_t *ear = qdc_mallocn((size_t)tp->nt + 1, 1), *pins = NULL;
    const double worst = 2.0 * fmax(c->best.q_min, 0.0);
    int32_t n;

    *out = NULL;
    if (!ear)
        return QDC_ENOMEM;
    n = slide_smooth_ears(c->sl, tp, ear);
    if (n < 0) {
        qdc_free(ear);
        return QDC_ENOMEM;
    }
    for (int32_t t = 0; n > 0 && t < tp->nt; t++) {
        double q;
        if (!ear[t])
            continue;
        q = tet_mean_ratio(tp, c->xbest, t);
        if (!(q < 0.5 * tet_mean_ratio(tp, c->x0, t)) || !(q < worst || q <= 0.0))
            continue;
        if (!pins && !(pins = qdc_calloc((size_t)c->nv, 1))) {
            qdc_free(ear);
            return QDC_ENOMEM;
        }
        for (int a = 0; a < 4; a++)
            pins[tp->tets[4 * (size_t)t + a]] = 1;
    }
    qdc_free(ear);
    *out = pins;
    return QDC_OK;
}

/* Do no harm on a valid input (docs/method.md §5): no tet of the returned mesh
 * may be inverted, below the input's worst mean ratio or below its smallest
 * dihedral angle. The best iterate already keeps the first two over the whole
 * mesh; the finishing and angle passes can still trade the smallest angle
 * for the mean (a structured cube: 45 -> 39 degrees). The corners of every
 * tet that breaks a rule go back to their input positions, and again while
 * the tets around them break one; with all corners back the mesh is the
 * input, so the rounds end. Returns how many vertices went back. */
static int32_t hold_back(ctx_t *c)
{
    const mesh_topo *tp = c->tp;
    double cmax0 = -2.0, qmin0 = c->input.q_min;
    int32_t back = 0;

    if (c->input.n_inverted > 0 || c->best_it == 0)
        return 0;
#pragma omp parallel for reduction(max : cmax0) schedule(static)
    for (int32_t t = 0; t < tp->nt; t++) {
        const int32_t *tt = tp->tets + 4 * (size_t)t;
        double lo, hi;
        metric_dihedral_cos_range(c->x0 + 3 * (size_t)tt[0], c->x0 + 3 * (size_t)tt[1],
                                  c->x0 + 3 * (size_t)tt[2], c->x0 + 3 * (size_t)tt[3],
                                  &lo, &hi);
        cmax0 = hi > cmax0 ? hi : cmax0;
    }
    memset(c->vmark, 0, (size_t)c->nv);
    for (;;) {
        int32_t n = 0;
#pragma omp parallel for schedule(static)
        for (int32_t t = 0; t < tp->nt; t++) {
            const int32_t *tt = tp->tets + 4 * (size_t)t;
            const double *y = c->xbest;
            double lo, hi;
            if (geom_tet_bad(y, tt)) {
                mark_corners(c, tt);
                continue;
            }
            metric_dihedral_cos_range(y + 3 * (size_t)tt[0], y + 3 * (size_t)tt[1],
                                      y + 3 * (size_t)tt[2], y + 3 * (size_t)tt[3], &lo,
                                      &hi);
            if (hi > cmax0 || tet_eta3(y, tt) < qmin0 * qmin0 * qmin0)
                mark_corners(c, tt);
        }
        for (int32_t v = 0; v < c->nv; v++) {
            double *y = c->xbest + 3 * (size_t)v;
            const double *o = c->x0 + 3 * (size_t)v;
            if (!c->vmark[v])
                continue;
            c->vmark[v] = 0;
            if (y[0] != o[0] || y[1] != o[1] || y[2] != o[2]) {
                memcpy(y, o, 3 * sizeof(double));
                n++;
            }
        }
        if (!n)
            return back;
        back += n;
    }
}

/* The default slide mode, on a tangled input, when the best iterate still
 * has inverted tets: the boundary and interface vertices of those tets, of the
 * tets inverted in the input and of the tets around them, as an nv mask (NULL
 * if none). Where the tangle
 * reaches the boundary, sliding on the input surface may not undo it
 * (torus_h0.1_tangled: 15 tets left inverted; lsq: none); opt_run then runs
 * again with these vertices free. */
static qdc_status stuck_boundary(const ctx_t *c, uint8_t **out)
{
    const mesh_topo *tp = c->tp;
    uint8_t *core = qdc_calloc((size_t)c->nv + 1, 1), *mask = NULL;
    int32_t n = 0;

    *out = NULL;
    if (!core)
        return QDC_ENOMEM;
    for (int32_t t = 0; t < tp->nt; t++) {
        const int32_t *tt = tp->tets + 4 * (size_t)t;
        if (geom_tet_bad(c->xbest, tt) ||
            geom_tet_bad(c->x0, tt))
            for (int a = 0; a < 4; a++)
                core[tt[a]] = 1;
    }
    mask = qdc_calloc((size_t)c->nv + 1, 1);
    if (!mask) {
        qdc_free(core);
        return QDC_ENOMEM;
    }
    for (int32_t t = 0; t < tp->nt; t++) {
        const int32_t *tt = tp->tets + 4 * (size_t)t;
        if (!(core[tt[0]] | core[tt[1]] | core[tt[2]] | core[tt[3]]))
            continue;
        for (int a = 0; a < 4; a++)
            if ((tp->vflag[tt[a]] & (MESH_V_BOUNDARY | MESH_V_INTERFACE)) &&
                !mask[tt[a]]) {
                mask[tt[a]] = 1;
                n++;
            }
    }
    qdc_free(core);
    if (!n) {
        qdc_free(mask);
        mask = NULL;
    }
    *out = mask;
    return QDC_OK;
}

/* Whether o is a set of options opt_run accepts (the table's ranges). */
static int options_valid(const opt_options *o)
{
    return o->hausd >= 0 && isfinite(o->hausd) &&
           ((o->hausd_rel >= 0 && isfinite(o->hausd_rel)) ||
            o->hausd_rel == OPT_HAUSD_AUTO) &&
           o->max_iter >= 0 && o->ls_halvings >= 0 && o->ls_halvings <= 60 && o->mu > 0 &&
           o->tol_move >= 0 && o->stall >= 0 && o->stall <= 1 && o->eps_rel > 0 &&
           o->finish_frac >= 0 && o->finish_frac <= 1 && o->finish_sweeps >= 0 &&
           o->pre_iters >= 0 && o->threads >= 0 &&
           (unsigned)o->metric <= OPT_METRIC_MICN &&
           (unsigned)o->boundary <= OPT_BOUNDARY_SLIDE &&
           (unsigned)o->mode <= OPT_MODE_LITERAL &&
           (unsigned)o->weights <= OPT_WEIGHTS_PAPER &&
           (unsigned)o->solver <= OPT_SOLVER_PCG;
}

/* The context of one run: topology, ctx, loose and pinned vertices, the
 * solver, the input's record (reported). */
static qdc_status run_setup(ctx_t *c, mesh_t *m, const opt_options *o,
                            const uint8_t *pins, const uint8_t *loose, mesh_topo **tpp,
                            opt_result *res, opt_progress *r, qdc_error *err)
{
    mesh_topo *tp;
    double t0 = c->t0;
    qdc_status st = mesh_topo_build(m, tpp, err);

    if (st != QDC_OK)
        return st;
    tp = *tpp;
    st = ctx_init(c, m, tp, o); /* clears c */
    c->t0 = t0;
    if (st != QDC_OK)
        return st;
    for (int32_t v = 0; loose && c->sl && v < c->nv; v++)
        if (loose[v] && !(tp->vflag[v] & MESH_V_FIXED)) {
            slide_release(c->sl, v);
            c->locked[v] = 0;
            c->bw2[v] = 1.0;
        }
    for (int32_t v = 0; pins && v < c->nv; v++)
        if (pins[v]) {
            c->locked[v] = 1;
            c->bw2[v] = 0.0;
        }
    st = solve_new(tp, c->locked, o->solver, &c->sol, err);
    if (st != QDC_OK)
        return st;
    res->solver = solve_kind(c->sol);
    res->solver_flops = solve_flops(c->sol);
    logf_(c, 0, "%d vertices (%d boundary), %d tets; solver %s (analysis %.3g flops)",
          (int)m->nv, (int)tp->nb, (int)m->nt, opt_solver_name(res->solver),
          res->solver_flops);
    res->t_setup = qdc_now() - c->t0;
    c->eta_delta = evaluate(c, c->x, r, c->eta);
    r->phase = "input";
    c->input = c->best = *r;
    res->before = *r;
    res->hausd_bound = c->hbound * c->scale;
    set_stop(res, OPT_STOP_MAX_ITER);
    return QDC_OK;
}

/* The global iterations (Eq. 15 with the line search). *stop is set when the
 * run must end without the finishing pass (cancelled, solver trouble). */
static qdc_status global_phase(ctx_t *c, opt_result *res, opt_progress *r, int *stop,
                               qdc_error *err)
{
    const opt_options *o = c->o;
    int total_iters = o->max_iter + (o->harmonic ? o->pre_iters : 0);
    double q_prev = c->input.q_mean, g_prev = INFINITY, gain;
    int32_t inv_prev[2] = {c->input.n_inverted, c->input.n_inverted};

    for (int it = 1; !*stop && it <= total_iters; it++) {
        int stepped = 0, pre = o->harmonic && it <= o->pre_iters;
        qdc_status st;
        if (should_stop(c, res)) {
            *stop = 1;
            break;
        }
        if (o->harmonic && it == o->pre_iters + 1) {
            st = set_harmonic(c, res, err);
            if (st != QDC_OK)
                return st;
        }
        st = iterate(c, res, r, &stepped, err);
        if (st == QDC_ESOLVE) {
            /* solver trouble: stop with the best mesh so far (docs/style.md §3) */
            set_stop(res, OPT_STOP_SOLVER);
            logf_(c, 1, "iteration %d: %s", it, err ? err->msg : "solve failed");
            *stop = 1;
            break;
        }
        if (st != QDC_OK)
            return st;
        r->iteration = it;
        r->phase = pre ? "pre" : "global";
        res->iterations = it;
        if (r->n_inverted > res->max_inverted_global)
            res->max_inverted_global = r->n_inverted;
        res->folded_global += r->n_folded;
        gain = r->q_mean - q_prev;
        consider(c, c->x, r);
        if (report(c, r)) {
            set_stop(res, OPT_STOP_CANCELLED);
            *stop = 1;
            break;
        }
        if (!stepped) {
            set_stop(res, OPT_STOP_NO_DESCENT);
            if (!pre)
                break;
        } else if (r->max_move < o->tol_move && !pre) {
            set_stop(res, OPT_STOP_CONVERGED);
            break;
        } else if (!pre && o->stall > 0 && it >= 3 &&
                   (r->n_inverted == 0 || r->n_inverted >= inv_prev[0]) &&
                   o->mode != OPT_MODE_LITERAL &&
                   (gain < o->stall || gain * gain < o->stall * g_prev)) {
            /* the global phase has done its work (docs/defaults.md: at 800k
             * tets iterations 5..10 added 0.0009 of final mean ratio for 60%
             * of the run's time); the finishing pass takes it from here. The
             * gains fall off geometrically: when the next one, predicted from
             * the last two (gain^2 / g_prev), is below the threshold, it is
             * not run either (at 5M tets: 2 iterations of 3.6 s for 0.0022,
             * the same final mean ratio) */
            set_stop(res, OPT_STOP_CONVERGED);
            if (gain < o->stall)
                logf_(c, 0,
                      "iteration %d raised the mean ratio by %.2g (< %g): global phase "
                      "done",
                      it, gain, o->stall);
            else
                logf_(c, 0,
                      "iteration %d raised the mean ratio by %.2g, the next would by "
                      "about %.2g (< %g): global phase done",
                      it, gain, gain * gain / g_prev, o->stall);
            break;
        }
        g_prev = gain;
        q_prev = r->q_mean;
        inv_prev[0] = inv_prev[1];
        inv_prev[1] = r->n_inverted;
    }
    return QDC_OK;
}

/* The finishing pass and the angle polish. */
/* Inverted tets the finishing pass left: the max-min volume untangling of
 * their interior vertices (finish.h) from the best iterate, kept through the
 * best-iterate rule (fewer inverted tets first). */
static qdc_status untangle_pass(ctx_t *c, const uint8_t *movable, opt_result *res,
                                opt_progress *r, int *next)
{
    int32_t ninv;
    qdc_status st;

    memcpy(c->trial, c->xbest, 3 * (size_t)c->nv * sizeof(double));
    st = finish_untangle(c->tp, movable, c->trial, c->lbar, &ninv);
    if (st != QDC_OK || ninv >= c->best.n_inverted)
        return st;
    pass_record(c, r, next, "untangle");
    r->step = 0;
    consider(c, c->x, r);
    if (report(c, r))
        set_stop(res, OPT_STOP_CANCELLED);
    return QDC_OK;
}

static qdc_status finishing_phase(ctx_t *c, opt_result *res, opt_progress *r)
{
    const mesh_topo *tp = c->tp;
    double t = qdc_now();
    uint8_t *movable = qdc_mallocn((size_t)c->nv, 1);
    int from_last = c->best_it != res->iterations;
    int next = res->iterations + 1;
    qdc_status st;

    if (!movable)
        return QDC_ENOMEM;
    /* Boundary and interface vertices move here only in slide mode, along
     * their input surface; lsq and fixed leave them where the global step put them. */
    for (int32_t v = 0; v < c->nv; v++)
        movable[v] = !c->locked[v] &&
                     (c->sl || !(tp->vflag[v] & (MESH_V_BOUNDARY | MESH_V_INTERFACE)));
    /* Start from the last global iterate (the lowest objective), as the
     * oracle does, even if it has inverted tets: with delta > 0 the pass
     * drives them out (measured on a 1.1M-tet sliver cube: the global phase
     * leaves 49 inverted tets; starting from the best iterate instead, which
     * was the input, threw the whole global phase away). */
    st = finish_pass(c, movable, 1, res, r, &next);
    /* From the last iterate the pass may fail to lift the worst tets back
     * above the input's (seen with slide on curved surfaces): then run it
     * again from the best global iterate. */
    if (st == QDC_OK && from_last && c->best_it <= res->iterations &&
        res->stop != OPT_STOP_CANCELLED) {
        memcpy(c->x, c->xbest, 3 * (size_t)c->nv * sizeof(double));
        st = finish_pass(c, movable, 0, res, r, &next);
    }
    if (st == QDC_OK && c->best.n_inverted > 0 && res->stop != OPT_STOP_CANCELLED)
        st = untangle_pass(c, movable, res, r, &next);
    /* (measured on a 4M-tet cube whose finished mesh kept one inverted tet:
     * the angle pass took 12 s, from an unfinished iterate, for a result the
     * rerun replaced) */
    if (st == QDC_OK && c->o->angle_polish && res->stop != OPT_STOP_CANCELLED &&
        !(c->rerun_stuck && c->best.n_inverted > 0))
        st = lsq_angle_pass(c, movable, res, r, &next);
    qdc_free(movable);
    res->t_finish = qdc_now() - t;
    return st;
}

/* hold_back, with the best record brought up to date. */
static void hold_back_best(ctx_t *c, opt_result *res)
{
    int32_t back = hold_back(c);
    opt_progress b;

    if (back <= 0)
        return;
    evaluate(c, c->xbest, &b, NULL);
    if (c->input.n_inverted == 0 && b.q_mean < c->input.q_mean) {
        /* what is left no longer beats the input's mean: the input it is */
        memcpy(c->xbest, c->x0, 3 * (size_t)c->nv * sizeof(double));
        c->best = c->input;
        c->best_it = 0;
        logf_(c, 0, "holding back %d vertices took the mean ratio under the input's: "
                    "the input is returned", (int)back);
        return;
    }
    b.iteration = c->best.iteration;
    b.phase = c->best.phase;
    c->best = b;
    res->held_back = back;
    logf_(c, 0,
          "%d vertices held at their input positions (no tet below the input's worst)",
          (int)back);
}

/* One optimization of m. pins (nv flags, may be NULL): extra vertices that
 * keep their input position; loose (may be NULL): sliding vertices that move
 * freely (slide_release). In slide mode *squashed (if not NULL) receives the
 * corners of the ears this run squashed (see squashed_ears), and *stuck (if
 * not NULL) the boundary vertices around tets left inverted (stuck_boundary);
 * else NULL. keep_surface: the finishing pass folds no tet at the surface
 * (finish.h). */
static qdc_status run_once(mesh_t *m, const opt_options *opts, const uint8_t *pins,
                           const uint8_t *loose, uint8_t **squashed, uint8_t **stuck,
                           int keep_surface, opt_result *res_out, qdc_error *err)
{
    opt_options o;
    opt_result res;
    mesh_topo *tp = NULL;
    ctx_t c;
    qdc_status st;
    int stop = 0, saved_threads = 0;
    opt_progress r;

    memset(&res, 0, sizeof res);
    memset(&c, 0, sizeof c);
    c.t0 = qdc_now();
    res.outcome = OPT_FAILED;
    if (opts)
        o = *opts;
    else
        opt_defaults(&o);
    if (!options_valid(&o)) {
        st = qdc_fail(err, QDC_EINVAL, "invalid optimizer options");
        goto out;
    }
    /* nthreads-var is per thread in OpenMP: this sets the team size of this
     * job's regions (on the caller's thread), and is put back at the end so
     * the caller's later parallel regions are not affected */
    saved_threads = omp_get_max_threads();
    if (o.threads > 0)
        omp_set_num_threads(o.threads);
    st = run_setup(&c, m, &o, pins, loose, &tp, &res, &r, err);
    if (st != QDC_OK)
        goto out;
    c.keep_surface = keep_surface;
    if (report(&c, &r)) {
        stop = 1;
        set_stop(&res, OPT_STOP_CANCELLED);
    }
    st = global_phase(&c, &res, &r, &stop, err);
    if (st != QDC_OK)
        goto out;
    res.before_finish = c.best;
    c.rerun_stuck = stuck && c.sl && c.autob;
    if (o.finish && !stop && o.finish_sweeps > 0) {
        st = finishing_phase(&c, &res, &r);
        if (st != QDC_OK)
            goto out;
    }
    hold_back_best(&c, &res);
    if (squashed && c.sl && c.best_it > 0 && c.input.n_inverted > 0) {
        st = squashed_ears(&c, squashed);
        if (st != QDC_OK)
            goto out;
    }
    if (stuck && c.sl && c.autob && c.best.n_inverted > 0) {
        st = stuck_boundary(&c, stuck);
        if (st != QDC_OK)
            goto out;
    }
    /* map back; locked vertices keep their exact input coordinates, and if the
     * input itself is the best iterate the mesh is left bit-for-bit as it was */
    for (int32_t v = 0; c.best_it > 0 && v < c.nv; v++)
        if (!c.locked[v])
            for (int k = 0; k < 3; k++)
                m->xyz[3 * (size_t)v + k] =
                    c.xbest[3 * (size_t)v + k] * c.scale + c.center[k];
    /* counted again on the coordinates the caller gets: mapping back rounds,
     * and a tet of near-zero volume can change sign (measured on a tangled
     * thin bone of 94k tets: one tet positive here, -1e-19 in the file) */
    if (c.best_it > 0) {
        int32_t n = mesh_count_inverted(tp, m->xyz);
        c.best.n_inverted = n > c.best.n_inverted ? n : c.best.n_inverted;
    }
    res.after = c.best;
    res.best_iteration = c.best_it;
    res.last_record = c.last_record;
    res.outcome = res.stop == OPT_STOP_CONVERGED || res.stop == OPT_STOP_MAX_ITER ||
                          res.stop == OPT_STOP_NO_DESCENT
                      ? OPT_CONVERGED
                      : OPT_STOPPED;
    st = QDC_OK;
out:
    res.t_total = qdc_now() - c.t0;
    if (st != QDC_OK)
        res.outcome = OPT_FAILED;
    if (res_out)
        *res_out = res;
    ctx_free(&c);
    mesh_topo_free(tp);
    if (saved_threads > 0)
        omp_set_num_threads(saved_threads);
    return st;
}

/* Progress of the second slide run: numbered after the first run's records,
 * its starting record labelled "rerun". */
typedef struct {
    opt_progress_fn fn;
    void *ctx;
    int offset;
    double t_offset;
} rerun_progress;

static int rerun_report(void *ctx, const opt_progress *p)
{
    const rerun_progress *rp = ctx;
    opt_progress q = *p;
    q.iteration += rp->offset;
    q.elapsed += rp->t_offset;
    if (p->iteration == 0)
        q.phase = "rerun";
    return rp->fn(rp->ctx, &q);
}

/* run_once again after the run prev, its progress records numbered on. */
static qdc_status run_again(mesh_t *m, const opt_options *opts, const opt_result *prev,
                            const uint8_t *pins, const uint8_t *loose, uint8_t **squashed,
                            uint8_t **stuck, int keep_surface, opt_result *r,
                            qdc_error *err)
{
    opt_options o2 = *opts;
    /* the last record's number: global iterations plus finishing sweeps */
    rerun_progress rp = {opts->progress, opts->progress_ctx, prev->last_record + 1,
                         prev->t_total};

    if (opts->progress) {
        o2.progress = rerun_report;
        o2.progress_ctx = &rp;
    }
    return run_once(m, &o2, pins, loose, squashed, stuck, keep_surface, r, err);
}

/* After a rerun r with coordinates x: best and xbest become r's if better;
 * either way the times add up and the records go on. */
static void keep_better(opt_result *best, opt_result *r, double *xbest, const double *x,
                        size_t n3)
{
    double *tb[] = {&best->t_setup,  &best->t_weights,    &best->t_assembly,
                    &best->t_solve,  &best->t_linesearch, &best->t_harmonic,
                    &best->t_finish, &best->t_total};
    double *tr[] = {&r->t_setup,      &r->t_weights,  &r->t_assembly, &r->t_solve,
                    &r->t_linesearch, &r->t_harmonic, &r->t_finish,   &r->t_total};

    for (int i = 0; i < 8; i++) /* the phase times of all runs add up */
        *tr[i] += *tb[i];
    if (better(&r->after, &best->after)) {
        *best = *r;
        memcpy(xbest, x, n3 * sizeof(double));
    } else {
        for (int i = 0; i < 8; i++)
            *tb[i] = *tr[i];
        best->last_record = r->last_record;
    }
}

/* The stuck rerun: the whole run again from the input with the stuck
 * vertices free, kept if better. (Measured and dropped on 2026-11-25: the
 * finishing pass alone, from the first run's result or its last global
 * iterate, with those vertices free: on a 4M-tet cube with one flat inverted
 * boundary tet it fixed the tet once and failed twice, which then cost the
 * whole run on top; the global phase is what moves the freed vertices.) */
static qdc_status free_stuck(mesh_t *m, const opt_options *opts, opt_result *best,
                             const uint8_t *pins, const uint8_t *loose, const double *xin,
                             double *xbest, qdc_error *err)
{
    size_t n3 = 3 * (size_t)m->nv;
    int32_t nfree = 0;
    opt_result r;
    qdc_status st;

    for (int32_t v = 0; v < m->nv; v++)
        nfree += loose[v];
    if (opts->log) {
        char msg[200];
        snprintf(msg, sizeof msg,
                 "%d tets left inverted by sliding: again with %d boundary vertices "
                 "around them free",
                 (int)best->after.n_inverted, (int)nfree);
        opts->log(opts->log_ctx, 0, msg);
    }
    memcpy(m->xyz, xin, n3 * sizeof(double));
    st = run_again(m, opts, best, pins, loose, NULL, NULL, 0, &r, err);
    if (st == QDC_OK)
        keep_better(best, &r, xbest, m->xyz, n3);
    return st;
}

/* opt_run in the mesh's own numbering. */
static qdc_status run_numbered(mesh_t *m, const opt_options *opts, opt_result *res_out,
                               qdc_error *err)
{
    uint8_t *pins = NULL, *sq = NULL, *stk = NULL, *loose = NULL;
    double *xin = NULL, *xbest = NULL;
    opt_result best, r;
    opt_options dflt;
    qdc_status st;
    size_t n3 = 3 * (size_t)(m && m->nv > 0 ? m->nv : 0);

    memset(&best, 0, sizeof best);
    best.outcome = OPT_FAILED;
    if (!opts) {
        opt_defaults(&dflt);
        opts = &dflt;
    }
    if (opts->boundary != OPT_BOUNDARY_SLIDE)
        return run_once(m, opts, NULL, NULL, NULL, NULL, 0, res_out, err);
    xin = qdc_mallocn(n3 + 1, sizeof(double));
    xbest = qdc_mallocn(n3 + 1, sizeof(double));
    pins = qdc_calloc(n3 / 3 + 1, 1);
    if (!xin || !xbest || !pins) {
        st = qdc_fail(err, QDC_ENOMEM, "out of memory");
        if (res_out)
            *res_out = best;
        goto out;
    }
    memcpy(xin, m->xyz, n3 * sizeof(double));
    st = run_once(m, opts, NULL, NULL, &sq, &stk, 0, &best, err);
    if (st != QDC_OK) {
        if (res_out)
            *res_out = best;
        goto out;
    }
    memcpy(xbest, m->xyz, n3 * sizeof(double));
    /* Slide squashed some smooth ears (measured on bunny_tangled-low_10k: an ear
     * of mean ratio 0.061 ended at 1e-10): run again with their corners held,
     * and again while a run squashes ears it did not hold (at most 3 reruns);
     * keep the best result. Only for tangled inputs: on a valid one hold_back
     * already keeps every tet above the input's worst, and the reruns changed
     * no result (measured 2026-11-25 on the 21 dev meshes and the 12 meshes of
     * scripts/corpus.py at 20k tets: identical quality) while taking up to 5x
     * the time (bone-lowq, 20k tets: 5.1 s against 1.05 s). */
    for (int round = 0;
         round < 3 && sq && best.before.n_inverted > 0 && best.outcome == OPT_CONVERGED;
         round++) {
        int32_t added = 0, held = 0;
        for (int32_t v = 0; v < m->nv; v++) {
            added += sq[v] && !pins[v];
            pins[v] |= sq[v];
            held += pins[v];
        }
        qdc_free(sq);
        sq = NULL;
        if (!added)
            break;
        memcpy(m->xyz, xin, n3 * sizeof(double));
        if (opts->log) {
            char msg[160];
            snprintf(
                msg, sizeof msg,
                "slide squashed ears of the surface: again with their %d corners held",
                (int)held);
            opts->log(opts->log_ctx, 0, msg);
        }
        st = run_again(m, opts, &best, pins, loose, &sq, stk ? NULL : &stk, 0, &r, err);
        if (st != QDC_OK)
            break;
        keep_better(&best, &r, xbest, m->xyz, n3);
    }
    /* Inverted tets left where the tangle reaches the boundary: once more with
     * the boundary vertices around them free (stuck_boundary), ears held as
     * before; kept only if better (fewer inverted tets first). */
    if (st == QDC_OK && stk && best.outcome == OPT_CONVERGED &&
        best.after.n_inverted > 0) {
        loose = stk;
        stk = NULL;
        st = free_stuck(m, opts, &best, pins, loose, xin, xbest, err);
    }
    /* Tets still left inverted (measured on tangled thin bones of
     * scripts/corpus.py at 100k-200k tets, where the finishing pass had traded
     * them in at the surface): once more with no fold at the surface allowed
     * (finish.h, keep_surface), the ears held, the boundary sliding (with the
     * stuck vertices free, the 100k bone kept its inverted tet); kept only if
     * better. Not on every run: on the tangled 1M-tet ball the rule left 17
     * tets inverted where the run without it leaves none. */
    if (st == QDC_OK && best.outcome == OPT_CONVERGED && best.after.n_inverted > 0) {
        if (opts->log) {
            char msg[160];
            snprintf(msg, sizeof msg,
                     "%d tets left inverted: again with no fold at the surface",
                     (int)best.after.n_inverted);
            opts->log(opts->log_ctx, 0, msg);
        }
        memcpy(m->xyz, xin, n3 * sizeof(double));
        st = run_again(m, opts, &best, pins, NULL, NULL, NULL, 1, &r, err);
        if (st == QDC_OK)
            keep_better(&best, &r, xbest, m->xyz, n3);
    }
    /* a failed rerun leaves the best result so far */
    memcpy(m->xyz, xbest, n3 * sizeof(double));
    st = QDC_OK;
    if (res_out)
        *res_out = best;
out:
    qdc_free(sq);
    qdc_free(stk);
    qdc_free(loose);
    qdc_free(pins);
    qdc_free(xin);
    qdc_free(xbest);
    return st;
}

/* The run works on a copy of the mesh numbered along a space-filling curve
 * (core/order.h): measured on an 800k-tet ball whose vertices came in random
 * order, 7.7 -> 5.7 s, the global phase 40% faster. A failure that names a
 * vertex or tet is found again in the caller's numbering, for its message. */
qdc_status opt_run(mesh_t *m, const opt_options *opts, opt_result *res, qdc_error *err)
{
    mesh_order ord;
    mesh_t *pm;
    qdc_status st;

    if (!m || m->nv <= 0 || m->nt <= 0 || !m->xyz || !m->tets)
        return run_numbered(m, opts, res, err);
    st = mesh_order_build(m, &ord);
    if (st == QDC_EINVAL)
        return run_numbered(m, opts, res, err);
    pm = st == QDC_OK ? mesh_order_take(m, &ord) : NULL;
    if (!pm) {
        mesh_order_free(&ord);
        if (res)
            memset(res, 0, sizeof *res);
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    }
    st = run_numbered(pm, opts, res, err);
    mesh_order_give_back(&ord, pm, m);
    if (st == QDC_OK)
        mesh_order_restore_xyz(&ord, pm, m);
    mesh_free(pm);
    mesh_order_free(&ord);
    if (st != QDC_OK && err && err->index >= 0)
        st = run_numbered(m, opts, res, err);
    return st;
}
