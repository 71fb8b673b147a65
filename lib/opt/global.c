/* global.c - the global phase (docs/method.md §5, §6): iterations of the
 * semi-implicit gradient flow (paper Eq. 15) with the feasible step, the line
 * search and harmonic guidance. */
#include "opt/global.h"

#include "core/tet.h"
#include "geom/metric_int.h"
#include "opt/encode.h"
#include "opt/harm.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

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
        ctx_log(c, 0, "harmonic guidance: %d medial vertices, omega_B %.3g", (int)nmed,
                wb);
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

/* Whether a trial y spoils tet tt, unusable at y if ybad: it folds or flattens a tet
 * usable at x or, on a valid mesh, takes a tet below the worst mean ratio at x, whose
 * cube is qfloor3 (the worst tet of the mesh never gets worse, so the global phase's work
 * is kept). */
static int spoils_at(const ctx_t *c, int ybad, const double *y, const int32_t *tt,
                     double qfloor3)
{
    if (ybad)
        return !geom_tet_bad(c->x, tt);
    return qfloor3 > 0 && ctx_tet_eta3(y, tt) < qfloor3;
}

/* The same, ybad (whether tt is unusable at y) not known yet. */
static int spoils(const ctx_t *c, const double *y, const int32_t *tt, double qfloor3)
{
    return spoils_at(c, geom_tet_bad(y, tt), y, tt, qfloor3);
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

/* c->trial = the step of length s from c->x toward c->xn, feasible: no tet
 * that is valid at c->x is inverted at the trial, unless c->x is tangled
 * (ninv_x inverted tets) and the whole step leaves no more inverted tets than
 * that; either way the inverted count never rises. Each vertex of a
 * tet the plain step would fold takes half its share of the step, again and
 * again (after 6 halvings none of it), like Mesquite's feasible Newton step
 * but per vertex: the rest of the mesh keeps its whole step. A vertex held at
 * c->x can still leave a neighbour tet folded by its other corners, which are
 * then held in the next round; with every vertex held the trial is c->x,
 * which folds nothing, so the rounds end. Returns 1 if the trial may fold
 * a tet usable at c->x (the whole step taken on a tangled mesh), 0 if it
 * folds none: every tet a round left spoiling had its corners moved and was
 * looked at again. */
static int feasible_trial(ctx_t *c, double s, int32_t ninv_x, double qfloor3)
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
        int ybad = geom_tet_bad(c->trial, tt),
            bad = spoils_at(c, ybad, c->trial, tt, qfloor3);
        ninv += ybad;
        folds += bad;
        if (bad)
            ctx_mark_corners(c, tt);
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
        return folds > 0;
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
            return 0;
        if (round > 64) { /* cannot happen (see above); never loop for ever */
            memcpy(c->trial, c->x, 3 * (size_t)nv * sizeof(double));
            return 0;
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
                    ctx_mark_corners(c, tt);
                    again = 1;
                }
            }
        }
        if (!again)
            return 0;
    }
}

/* One iteration of Eq. 15 plus the line search. Fills r (without quality).
 * Returns QDC_OK; *stepped = 0 when no step decreased the objective. */
/* mu of this step: the paper as written (literal) takes
 * mu_k = ||G^T W^2 g||^2 = ||omega_B^2 b||^2 (constant), else o->mu. */
static double step_mu(const ctx_t *c)
{
    double mu;

    if (c->o->mode == OPT_MODE_LITERAL) {
        mu = 0;
        for (int32_t v = 0; v < c->nv; v++)
            for (int k = 0; k < 3; k++)
                mu += c->bw2[v] * c->bw2[v] * c->x0[3 * (size_t)v + k] *
                      c->x0[3 * (size_t)v + k];
        if (!(mu > 0))
            mu = 1.0;
    } else {
        mu = c->o->mu * c->mu_factor;
    }
    return mu;
}

/* b = Q_F^T W (d - Q x_L) + bw2 x0 + mu x_k into c->rhs, and c->dg: locked
 * vertices move to the right (the per-vertex loops of the iteration run in
 * parallel: each entry alone) */
static void assemble_rhs(ctx_t *c, double mu)
{
#pragma omp parallel for schedule(static)
    for (int32_t v = 0; v < c->nv; v++) {
        for (int k = 0; k < 3; k++)
            c->tmp[3 * (size_t)v + k] = c->locked[v] ? c->x[3 * (size_t)v + k] : 0.0;
        c->dg[v] = c->bw2[v] + mu;
    }
    solve_q_mul(c->tp, c->qval, c->tmp, c->trial);
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
}

static int all_finite(const double *x, size_t n)
{
    int finite = 1;
#pragma omp parallel for reduction(&& : finite) schedule(static)
    for (size_t q = 0; q < n; q++)
        finite = finite && isfinite(x[q]);
    return finite;
}

/* Not in the paper (docs/method.md §5): backtrack on sum q~ with delta frozen;
 * with delta = 0 a trial that inverts a tet costs +inf.
 * A step that lowers sum q~ may still fold valid tets: with delta > 0
 * (any tet below eps, common on sliver meshes) an inverted tet costs
 * a finite q~, and measured on 100k-1M-tet valid meshes with 40-50%
 * boundary vertices the accepted steps folded 26-331 tets. So a trial
 * is accepted only if it folds no valid tet while the mesh is valid,
 * and never raises the inverted count of a tangled one. Returns the step
 * taken (0: none), its trial in c->trial; *may_fold as feasible_trial
 * returned for it. at: the worst mean ratio (cubed) and the unusable tets at
 * c->x, found with f0. */
static double line_search(ctx_t *c, double delta, double f0, const encode_scan *at,
                          int *may_fold)
{
    const opt_options *o = c->o;
    const mesh_topo *tp = c->tp;
    double step = 1.0, qfloor3 = at->eta3_min;
    int h;
    int32_t ninv_x = at->n_bad;

    for (h = 0; h <= o->ls_halvings; h++) {
        *may_fold = feasible_trial(c, step, ninv_x, qfloor3);
        if (encode_objective(tp, c->trial, o->metric, delta, NULL, NULL) < f0)
            break;
        step *= 0.5;
    }
    if (h > o->ls_halvings)
        step = 0.0;
    return step;
}

/* c->x moves to c->trial if step > 0; returns the largest squared move. */
static double apply_step(ctx_t *c, double step)
{
    double move = 0;

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
    return move;
}

static qdc_status iterate(ctx_t *c, opt_result *res, opt_progress *r, int *stepped,
                          qdc_error *err)
{
    const opt_options *o = c->o;
    const mesh_topo *tp = c->tp;
    size_t n3 = 3 * (size_t)c->nv;
    int literal = o->mode == OPT_MODE_LITERAL;
    double t = qdc_now(), delta, f0, mu, step = 1.0, move;
    int cg = 0, may_fold = 1;
    int32_t folded = 0;
    encode_scan at;
    qdc_status st;

    /* q~ at x_k with one global delta (docs/method.md §2): the delta of x_k is
     * the evaluation's that ended setup or the last iteration (x_k has not
     * moved since), the smallest metric argument of the same parts; with it,
     * what the line search needs of x_k, in the same pass, which that
     * evaluation took already when its objective needed one (delta > 0: a
     * tangled mesh) */
    delta = c->eta_delta;
    if (c->xscan_ok) {
        f0 = c->xscan_f;
        at = c->xscan;
    } else {
        f0 = encode_objective_scan(tp, c->x, o->metric, delta, c->qt, &at);
    }
    c->xscan_ok = 0;
    if (literal || o->weights == OPT_WEIGHTS_PAPER)
        encode_paper(tp, c->x, o->metric, c->qt, c->qval, c->d);
    else
        encode_optavg(tp, c->x, o->metric, c->qt, c->fslot, c->qval, c->d);
    res->t_weights += qdc_now() - t;
    t = qdc_now();
    mu = step_mu(c);
    assemble_rhs(c, mu);
    res->t_assembly += qdc_now() - t;
    t = qdc_now();
    memcpy(c->xn, c->x, n3 * sizeof(double));
    st = solve_system(c->sol, c->qval, c->wq2, c->dg, c->rhs, c->xn, &cg, err);
    res->t_solve += qdc_now() - t;
    if (st != QDC_OK)
        return st;
    if (!all_finite(c->xn, n3))
        return qdc_fail(err, QDC_ESOLVE, "linear solve returned a non-finite value");
    t = qdc_now();
    if (!literal)
        step = line_search(c, delta, f0, &at, &may_fold);
    res->t_linesearch += qdc_now() - t;
    if (literal) {
        for (size_t q = 0; q < n3; q++)
            c->trial[q] = c->xn[q];
        project_sliding(c, c->trial);
    } else if (step == 0.0) {
        memcpy(c->trial, c->x, n3 * sizeof(double));
    } /* else c->trial holds the accepted feasible trial */
    /* a trial the line search found fold-free is not scanned again (a whole
     * scan, two orientations per tet, each iteration) */
    if (step > 0.0 && may_fold) {
        int32_t ninv_t;
        folded = count_folds(tp, c->x, c->trial, &ninv_t);
    }
    move = apply_step(c, step);
    ctx_evaluate_x(c, r);
    r->n_folded = folded;
    r->step = step;
    r->max_move = sqrt(move) / c->lbar;
    r->cg_iters = cg;
    *stepped = step > 0.0;
    return QDC_OK;
}

/* The log line of a global phase that stalls at iteration it. */
static void log_stall(const ctx_t *c, int it, double gain, double g_prev)
{
    const opt_options *o = c->o;

    if (gain < o->stall)
        ctx_log(c, 0,
                "iteration %d raised the mean ratio by %.2g (< %g): global phase done",
                it, gain, o->stall);
    else
        ctx_log(c, 0,
                "iteration %d raised the mean ratio by %.2g, the next would by "
                "about %.2g (< %g): global phase done",
                it, gain, gain * gain / g_prev, o->stall);
}

/* The global iterations (Eq. 15 with the line search). *stop is set when the
 * run must end without the finishing pass (cancelled, solver trouble). */
qdc_status opt_global_phase(ctx_t *c, opt_result *res, opt_progress *r, int *stop,
                            qdc_error *err)
{
    const opt_options *o = c->o;
    int total_iters = o->max_iter + (o->harmonic ? o->pre_iters : 0);
    double q_prev = c->input.q_mean, g_prev = INFINITY, gain;
    int32_t inv_prev[2] = {c->input.n_inverted, c->input.n_inverted};

    for (int it = 1; !*stop && it <= total_iters; it++) {
        int stepped = 0, pre = o->harmonic && it <= o->pre_iters;
        qdc_status st;
        if (ctx_should_stop(c, res)) {
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
            ctx_set_stop(res, OPT_STOP_SOLVER);
            ctx_log(c, 1, "iteration %d: %s", it, err ? err->msg : "solve failed");
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
        ctx_consider(c, c->x, r);
        if (ctx_report(c, r)) {
            ctx_set_stop(res, OPT_STOP_CANCELLED);
            *stop = 1;
            break;
        }
        if (!stepped) {
            ctx_set_stop(res, OPT_STOP_NO_DESCENT);
            if (!pre)
                break;
        } else if (r->max_move < o->tol_move && !pre) {
            ctx_set_stop(res, OPT_STOP_CONVERGED);
            break;
        } else if (!pre && o->stall > 0 && it >= (o->stall_early ? 2 : 3) &&
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
            ctx_set_stop(res, OPT_STOP_CONVERGED);
            log_stall(c, it, gain, g_prev);
            break;
        }
        g_prev = gain;
        q_prev = r->q_mean;
        inv_prev[0] = inv_prev[1];
        inv_prev[1] = r->n_inverted;
    }
    return QDC_OK;
}
