/* rerun.c - the rerun policy (docs/method.md §5a): in slide mode the whole
 * run again with squashed ears held, with stuck boundary vertices free, with
 * no fold at the surface; in every mode, while tets stay inverted, with a
 * wider regularization; the best result kept. Also opt_run_smooth (opt_run
 * without --topology), which runs it in the mesh's space-filling-curve
 * numbering. */
#include "opt/opt.h"

#include "core/order.h"
#include "opt/ctx.h"
#include "opt/run.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* A run whose records were published from number offset on: its record
 * numbers (the last, the best) in the whole run's numbering. */
static void numbered_on(opt_result *r, int offset)
{
    r->last_record += offset;
    r->best_iteration += offset;
}

/* Whether a rerun may follow the runs so far (best): the last one ended
 * as it should (not stopped: cancelled, out of time, solver trouble) and a
 * time limit, which is the whole call's, has time left (measured: a 20k-tet
 * tangled torus with --time-limit 3 took 7.9 s through its reruns, each of
 * which had the whole limit to itself). */
static int rerun_allowed(const opt_options *opts, const opt_result *best)
{
    return best->outcome == OPT_CONVERGED &&
           (opts->time_limit <= 0 || best->t_total < opts->time_limit);
}

/* What a time limit leaves to a rerun after the runs so far (best): the
 * limit less their time (at least a millisecond: rerun_allowed decides
 * whether one starts); 0 (none) stays 0. */
static double limit_left(const opt_options *opts, const opt_result *best)
{
    return ctx_time_left(opts->time_limit, best->t_total);
}

/* run_once again after the run prev, its progress records numbered on, with
 * what is left of the time limit. */
static qdc_status run_again(mesh_t *m, const opt_options *opts, const mesh_topo *tp,
                            const opt_result *prev, const uint8_t *pins,
                            const uint8_t *loose, uint8_t **squashed, uint8_t **stuck,
                            int keep_surface, opt_result *r, qdc_error *err)
{
    opt_options o2 = *opts;
    /* the last record's number: global iterations plus finishing sweeps */
    rerun_progress rp = {opts->progress, opts->progress_ctx, prev->last_record + 1,
                         prev->t_total};

    qdc_status st;

    if (opts->progress) {
        o2.progress = rerun_report;
        o2.progress_ctx = &rp;
    }
    o2.time_limit = limit_left(opts, prev);
    st = opt_run_once(m, &o2, tp, pins, loose, squashed, stuck, keep_surface, r, err);
    numbered_on(r, rp.offset);
    return st;
}

/* After a rerun r with coordinates x: best and xbest become r's if better;
 * either way the times and the global iterations add up and the records go
 * on (docs/defaults.md, "One iteration count"). */
static void keep_better(opt_result *best, opt_result *r, double *xbest, const double *x,
                        size_t n3)
{
    double *tb[] = {&best->t_setup,  &best->t_weights,    &best->t_assembly,
                    &best->t_solve,  &best->t_linesearch, &best->t_harmonic,
                    &best->t_finish, &best->t_total};
    double *tr[] = {&r->t_setup,      &r->t_weights,  &r->t_assembly, &r->t_solve,
                    &r->t_linesearch, &r->t_harmonic, &r->t_finish,   &r->t_total};

    int global = best->iterations + r->iterations;

    for (int i = 0; i < 8; i++) /* the phase times of all runs add up */
        *tr[i] += *tb[i];
    if (ctx_better(&r->after, &best->after)) {
        *best = *r;
        memcpy(xbest, x, n3 * sizeof(double));
    } else {
        for (int i = 0; i < 8; i++)
            *tb[i] = *tr[i];
        best->last_record = r->last_record;
    }
    best->iterations = global;
}

/* A rerun's log line, if the caller logs. */
static void rerun_log(const opt_options *opts, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static void rerun_log(const opt_options *opts, const char *fmt, ...)
{
    char msg[200];
    va_list ap;

    if (!opts->log)
        return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    opts->log(opts->log_ctx, 0, msg);
}

/* run_again from the input coordinates xin (pins held, loose free,
 * keep_surface as run_once takes it), its result kept in best and xbest if
 * better. */
static qdc_status rerun_from_input(mesh_t *m, const opt_options *opts,
                                   const mesh_topo *tp, opt_result *best,
                                   const uint8_t *pins, const uint8_t *loose,
                                   int keep_surface, const double *xin, double *xbest,
                                   qdc_error *err)
{
    size_t n3 = 3 * (size_t)m->nv;
    opt_result r;
    qdc_status st;

    memcpy(m->xyz, xin, n3 * sizeof(double));
    st = run_again(m, opts, tp, best, pins, loose, NULL, NULL, keep_surface, &r, err);
    if (st == QDC_OK)
        keep_better(best, &r, xbest, m->xyz, n3);
    return st;
}

/* The stuck rerun: the whole run again from the input with the stuck
 * vertices free, kept if better. (Measured and dropped on 2026-11-25: the
 * finishing pass alone, from the first run's result or its last global
 * iterate, with those vertices free: on a 4M-tet cube with one flat inverted
 * boundary tet it fixed the tet once and failed twice, which then cost the
 * whole run on top; the global phase is what moves the freed vertices.) */
static qdc_status free_stuck(mesh_t *m, const opt_options *opts, const mesh_topo *tp,
                             opt_result *best, const uint8_t *pins, const uint8_t *loose,
                             const double *xin, double *xbest, qdc_error *err)
{
    int32_t nfree = 0;

    for (int32_t v = 0; v < m->nv; v++)
        nfree += loose[v];
    rerun_log(opts,
              "%d tets left inverted by sliding: again with %d boundary vertices "
              "around them free",
              (int)best->after.n_inverted, (int)nfree);
    return rerun_from_input(m, opts, tp, best, pins, loose, 0, xin, xbest, err);
}

/* The ear reruns: while the last run squashed ears it did not hold (*sq),
 * again from the input xin with their corners added to pins (at most 3
 * reruns), the best result kept in best and xbest. */
static qdc_status hold_ears(mesh_t *m, const opt_options *opts, const mesh_topo *tp,
                            opt_result *best, uint8_t *pins, const uint8_t *loose,
                            uint8_t **sq, uint8_t **stk, const double *xin, double *xbest,
                            qdc_error *err)
{
    size_t n3 = 3 * (size_t)m->nv;
    qdc_status st = QDC_OK;
    opt_result r;

    for (int round = 0;
         round < 3 && *sq && best->before.n_inverted > 0 && rerun_allowed(opts, best);
         round++) {
        int32_t added = 0, held = 0;
        for (int32_t v = 0; v < m->nv; v++) {
            added += (*sq)[v] && !pins[v];
            pins[v] |= (*sq)[v];
            held += pins[v];
        }
        qdc_free(*sq);
        *sq = NULL;
        if (!added)
            break;
        memcpy(m->xyz, xin, n3 * sizeof(double));
        rerun_log(opts,
                  "slide squashed ears of the surface: again with their %d corners held",
                  (int)held);
        st = run_again(m, opts, tp, best, pins, loose, sq, *stk ? NULL : stk, 0, &r, err);
        if (st != QDC_OK)
            break;
        keep_better(best, &r, xbest, m->xyz, n3);
    }
    return st;
}

/* The rerun with no fold at the surface (keep_surface) from the input xin,
 * pins held, kept if better. */
static qdc_status run_numbered(mesh_t *m, const opt_options *opts, const mesh_topo *tp,
                               int wider, opt_result *res_out, qdc_error *err);

static qdc_status rerun_no_fold(mesh_t *m, const opt_options *opts, const mesh_topo *tp,
                                opt_result *best, const uint8_t *pins, const double *xin,
                                double *xbest, qdc_error *err)
{
    size_t n3 = 3 * (size_t)m->nv;
    opt_options wide;
    rerun_progress rp;
    opt_result r;
    qdc_status st;

    rerun_log(opts, "%d tets left inverted: again with no fold at the surface",
              (int)best->after.n_inverted);
    st = rerun_from_input(m, opts, tp, best, pins, NULL, 1, xin, xbest, err);
    /* Still inverted under the default bound: once more from the input with
     * the whole boundary within OPT_HAUSD_STUCK, the bound the result then
     * reports (a tangled 100k-tet scanned bone of scripts/corpus.py kept 1
     * tet inverted with only the vertices around it freed to 1e-2, none with
     * the whole boundary so bound); kept only if better. */
    if (st != QDC_OK || !rerun_allowed(opts, best) || best->after.n_inverted == 0 ||
        opts->hausd > 0 || opts->hausd_rel != OPT_HAUSD_AUTO)
        return st;
    rerun_log(opts,
              "%d tets left inverted within the default bound: again from the input "
              "with the boundary within %g of the diagonal",
              (int)best->after.n_inverted, OPT_HAUSD_STUCK);
    wide = *opts;
    wide.hausd_rel = OPT_HAUSD_STUCK;
    wide.time_limit = limit_left(opts, best);
    rp = (rerun_progress){opts->progress, opts->progress_ctx, best->last_record + 1,
                          best->t_total};
    if (opts->progress) {
        wide.progress = rerun_report;
        wide.progress_ctx = &rp;
    }
    memcpy(m->xyz, xin, n3 * sizeof(double));
    st = run_numbered(m, &wide, tp, 0, &r,
                      err); /* not again: its bound is not the default */
    numbered_on(&r, rp.offset);
    if (st == QDC_OK)
        keep_better(best, &r, xbest, m->xyz, n3);
    return st;
}

/* Tets still inverted after the run and its reruns: the run again from the
 * input xin (pins held) with Escobar's regularization RERUN_EPS_WIDER times
 * wider, then that again, each kept only if better (fewer inverted tets
 * first). The softer barrier lets through a vertex that a tangle pushed
 * beyond the boundary of the shape, which the default's cannot bring back:
 * on the torus of scripts/corpus.py --tets 20000 --seed 7 --tangle-frac 0.05
 * (507 tets inverted, 81 interior vertices pushed) the default left 3 tets
 * inverted in every mode, around one such vertex 1.8 edges from where the
 * untangled mesh has it and its neighbours dragged along, no place for any
 * of them alone opening its star; with eps_rel 1e-2 none (1e-1 with the
 * boundary fixed). Not the default: eps also sets where the smoothing of a
 * valid mesh starts regularizing its slivers. */
#define RERUN_EPS_WIDER 10.0
#define RERUN_EPS_STEPS 2

static qdc_status rerun_wider(mesh_t *m, const opt_options *opts, const mesh_topo *tp,
                              opt_result *best, const uint8_t *pins, const double *xin,
                              double *xbest, qdc_error *err)
{
    opt_options wide = *opts;
    qdc_status st = QDC_OK;
    /* under the default bound, with the boundary within the bound of the
     * last slide rerun (rerun_no_fold): on that torus 0 tets left at 1e-2
     * (mean ratio 0.6303) where the default bound needed 1e-1 (0.6108) */
    int widened = opts->boundary == OPT_BOUNDARY_SLIDE && opts->hausd <= 0 &&
                  opts->hausd_rel == OPT_HAUSD_AUTO;

    /* only after a run that untangled some of its input */
    if (best->after.n_inverted >= best->before.n_inverted)
        return QDC_OK;
    if (widened)
        wide.hausd_rel = OPT_HAUSD_STUCK;
    for (int k = 0; k < RERUN_EPS_STEPS && st == QDC_OK && best->after.n_inverted > 0 &&
                    rerun_allowed(opts, best) && wide.eps_rel * RERUN_EPS_WIDER <= 1.0;
         k++) {
        wide.eps_rel *= RERUN_EPS_WIDER;
        char also[64] = "";
        if (widened)
            snprintf(also, sizeof also, " and the boundary within %g of the diagonal",
                     OPT_HAUSD_STUCK);
        rerun_log(opts, "%d tets left inverted: again from the input with eps_rel %g%s",
                  (int)best->after.n_inverted, wide.eps_rel, also);
        st = rerun_from_input(m, &wide, tp, best, pins, NULL, 0, xin, xbest, err);
    }
    return st;
}

/* The reruns of slide mode after its first run (best, xbest): ears held,
 * stuck boundary vertices free, no fold at the surface; *sq, *stk and *loose
 * the masks (freed by the caller). */
static qdc_status slide_reruns(mesh_t *m, const opt_options *opts, const mesh_topo *tp,
                               opt_result *best, uint8_t *pins, uint8_t **sq,
                               uint8_t **stk, uint8_t **loose, const double *xin,
                               double *xbest, qdc_error *err)
{
    /* Slide squashed some smooth ears (measured on bunny_tangled-low_10k: an ear
     * of mean ratio 0.061 ended at 1e-10): run again with their corners held,
     * and again while a run squashes ears it did not hold (at most 3 reruns);
     * keep the best result. Only for tangled inputs: on a valid one hold_back
     * already keeps every tet above the input's worst, and the reruns changed
     * no result (measured 2026-11-25 on the 21 dev meshes and the 12 meshes of
     * scripts/corpus.py at 20k tets: identical quality) while taking up to 5x
     * the time (bone-lowq, 20k tets: 5.1 s against 1.05 s). */
    qdc_status st = hold_ears(m, opts, tp, best, pins, *loose, sq, stk, xin, xbest, err);

    /* Inverted tets left where the tangle reaches the boundary: once more with
     * the boundary vertices around them free (stuck_boundary), ears held as
     * before; kept only if better (fewer inverted tets first). */
    if (st == QDC_OK && *stk && rerun_allowed(opts, best) && best->after.n_inverted > 0) {
        *loose = *stk;
        *stk = NULL;
        st = free_stuck(m, opts, tp, best, pins, *loose, xin, xbest, err);
    }
    /* Tets still left inverted (measured on tangled thin bones of
     * scripts/corpus.py at 100k-200k tets, where the finishing pass had traded
     * them in at the surface): once more with no fold at the surface allowed
     * (finish.h, keep_surface), the ears held, the boundary sliding (with the
     * stuck vertices free, the 100k bone kept its inverted tet); kept only if
     * better. Not on every run: on the tangled 1M-tet ball the rule left 17
     * tets inverted where the run without it leaves none. */
    if (st == QDC_OK && rerun_allowed(opts, best) && best->after.n_inverted > 0)
        st = rerun_no_fold(m, opts, tp, best, pins, xin, xbest, err);
    return st;
}

/* opt_run in the mesh's own numbering, on m's topology tp (NULL: each run
 * builds its own); wider: rerun_wider allowed. */
static qdc_status run_numbered(mesh_t *m, const opt_options *opts, const mesh_topo *tp,
                               int wider, opt_result *res_out, qdc_error *err)
{
    uint8_t *pins = NULL, *sq = NULL, *stk = NULL, *loose = NULL;
    double *xin = NULL, *xbest = NULL;
    opt_result best;
    opt_options dflt;
    qdc_status st;
    size_t n3 = 3 * (size_t)(m && m->nv > 0 ? m->nv : 0);
    int slide;

    memset(&best, 0, sizeof best);
    best.outcome = OPT_FAILED;
    if (!opts) {
        opt_defaults(&dflt);
        opts = &dflt;
    }
    if (n3 == 0) /* no mesh or no vertex: the run says why */
        return opt_run_once(m, opts, tp, NULL, NULL, NULL, NULL, 0, res_out, err);
    slide = opts->boundary == OPT_BOUNDARY_SLIDE;
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
    st = opt_run_once(m, opts, tp, NULL, NULL, slide ? &sq : NULL, slide ? &stk : NULL, 0,
                      &best, err);
    if (st != QDC_OK) {
        if (res_out)
            *res_out = best;
        goto out;
    }
    memcpy(xbest, m->xyz, n3 * sizeof(double));
    /* under a time limit, reruns from the input only when one would have as
     * long as the first run took: cut short, it costs its setup and passes
     * for nothing (with a limit of 45% of the whole run, the first run at
     * 40%, a rerun started in the last 5% took the call to 69% of it) */
    if (opts->time_limit > 0 && opts->time_limit - best.t_total < best.t_total)
        slide = wider = 0;
    if (slide)
        st = slide_reruns(m, opts, tp, &best, pins, &sq, &stk, &loose, xin, xbest, err);
    if (st == QDC_OK && wider)
        st = rerun_wider(m, opts, tp, &best, pins, xin, xbest, err);
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

/* m's topology for a run (NULL if it cannot be built: the run then builds
 * its own and fails with the reason), and the time it took into *t. */
static mesh_topo *shared_topo(const mesh_t *m, double *t)
{
    mesh_topo *tp = NULL;
    double t0 = qdc_now();

    if (mesh_topo_build(m, &tp, NULL) != QDC_OK)
        tp = NULL;
    *t = qdc_now() - t0;
    return tp;
}

/* run_numbered of m on one topology built for it and all its reruns: the
 * building counted in the setup time, the faces handed out if asked for
 * (in the numbering told, vold: see mesh_faces_of_topo). */
static qdc_status run_shared(mesh_t *m, const opt_options *opts, int wider,
                             opt_result *res, const int32_t *told, const int32_t *vold,
                             mesh_faces **faces, qdc_error *err)
{
    double t;
    mesh_topo *tp = shared_topo(m, &t);
    opt_options o;
    qdc_status st;

    /* the limit counts the building too (0.3-0.6 s of a 1M-tet run) */
    if (opts && opts->time_limit > 0) {
        o = *opts;
        o.time_limit = ctx_time_left(o.time_limit, t);
        opts = &o;
    }
    st = run_numbered(m, opts, tp, wider, res, err);

    if (res && tp) {
        res->t_setup += t;
        res->t_total += t;
    }
    if (st == QDC_OK && tp && faces && (!res || res->outcome != OPT_FAILED) &&
        mesh_faces_of_topo(tp, m->tets, told, vold, faces) != QDC_OK)
        *faces = NULL; /* out of memory: the report finds them itself */
    mesh_topo_free(tp);
    return st;
}

/* The run works on a copy of the mesh numbered along a space-filling curve
 * (core/order.h): measured on an 800k-tet ball whose vertices came in random
 * order, 7.7 -> 5.7 s, the global phase 40% faster. A failure that names a
 * vertex or tet is found again in the caller's numbering, for its message. */
static qdc_status run_smooth(mesh_t *m, const opt_options *opts, int wider,
                             opt_result *res, mesh_faces **faces, qdc_error *err)
{
    mesh_order ord;
    mesh_t *pm;
    qdc_status st;

    if (!m || m->nv <= 0 || m->nt <= 0 || !m->xyz || !m->tets)
        return run_numbered(m, opts, NULL, wider, res, err);
    st = mesh_order_build(m, &ord);
    if (st == QDC_EINVAL)
        return run_shared(m, opts, wider, res, NULL, NULL, faces, err);
    pm = st == QDC_OK ? mesh_order_take(m, &ord) : NULL;
    if (!pm) {
        mesh_order_free(&ord);
        if (res)
            memset(res, 0, sizeof *res);
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    }
    st = run_shared(pm, opts, wider, res, ord.told, ord.vold, faces, err);
    mesh_order_give_back(&ord, pm, m);
    if (st == QDC_OK)
        mesh_order_restore_xyz(&ord, pm, m);
    mesh_free(pm);
    mesh_order_free(&ord);
    if (st != QDC_OK && err && err->index >= 0)
        st = run_numbered(m, opts, NULL, wider, res, err);
    return st;
}

qdc_status opt_run_smooth(mesh_t *m, const opt_options *opts, opt_result *res,
                          qdc_error *err)
{
    return run_smooth(m, opts, 1, res, NULL, err);
}

qdc_status opt_run_smooth_round(mesh_t *m, const opt_options *opts, opt_result *res,
                                qdc_error *err)
{
    return run_smooth(m, opts, 0, res, NULL, err);
}

qdc_status opt_run_smooth_faces(mesh_t *m, const opt_options *opts, opt_result *res,
                                mesh_faces **faces, qdc_error *err)
{
    qdc_status st = run_smooth(m, opts, 1, res, faces, err);

    if (st != QDC_OK) {
        mesh_faces_free(*faces);
        *faces = NULL;
    }
    return st;
}
