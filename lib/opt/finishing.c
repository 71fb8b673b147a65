/* finishing.c - the finishing phase (docs/method.md §5a): the sweeps
 * (finish.c), untangling (untangle.c) and the angle polish (angle.c) in turn
 * from the global phase's result, each pass kept by the best-iterate rule. */
#include "opt/finishing.h"

#include "opt/angle.h"
#include "opt/finish.h"
#include "opt/local.h"
#include "opt/untangle.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
        delta = ctx_scan_light(c, c->x, c->eta, &cur);
    }
    for (int s = 0; s < o->finish_sweeps; s++) {
        finish_stats fs;
        qdc_status st;
        double mean0 = cur.q_mean;
        if (ctx_should_stop(c, res))
            return QDC_OK;
        /* broad sweeps: one Newton step per vertex (finish.c) */
        st = finish_sweep(c->tp, movable, c->sl, c->x, o->metric, c->eta, delta, c->lbar,
                          o->finish_frac, 1e-3, c->keep_surface, &fs);
        if (st != QDC_OK)
            return st;
        swept |= fs.n_moves > 0;
        moves += fs.n_moves;
        visits += fs.n_verts;
        delta = ctx_scan_light(c, c->x, c->eta, &cur);
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
        if (ctx_should_stop(c, res))
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
        delta = ctx_scan_light(c, c->x, c->eta, &cur);
        if (!ctx_better(&cur, &keep))
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
    ctx_pass_record(c, r, next, "finish");
    r->step = visits > 0 ? moves / visits : 0; /* accepted moves per visited vertex */
    ctx_consider(c, c->x, r);
    if (ctx_report(c, r))
        ctx_set_stop(res, OPT_STOP_CANCELLED);
    return QDC_OK;
}

/* Worst-angle polish (angle.h) from the best iterate: a round of joint moves
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
/* What the angle pass kept: whether some sweep or round was (its result in
 * c->trial), and their moves and visited vertices. */
typedef struct {
    int kept;
    double moves, visits;
} angle_tally;

/* c->x, the result of a sweep or round with stats fs, is kept. */
static void tally_kept(ctx_t *c, angle_tally *t, const finish_stats *fs)
{
    memcpy(c->trial, c->x, 3 * (size_t)c->nv * sizeof(double));
    t->kept = 1;
    t->moves += fs->n_moves;
    t->visits += fs->n_verts;
}

/* One round of joint moves of the worst tets' corners on their mean ratios
 * (angle.h) from c->x, kept if the worst tet improves on base: the angle
 * moves then start from it, with the floor of the best iterate. */
static qdc_status mean_ratio_round(ctx_t *c, const uint8_t *movable, const slide_ctx *sl,
                                   const opt_progress *base, angle_tally *t)
{
    finish_stats fs;
    opt_progress cur;
    qdc_status st = finish_patches(c->tp, movable, sl, c->x, c->lbar,
                                   FINISH_PATCH_MEAN_RATIO, 0.0, c->eta, 0, &fs);
    if (st != QDC_OK)
        return st;
    (void)ctx_scan_light(c, c->x, c->eta, &cur);
    if (ctx_better(&cur, base))
        tally_kept(c, t, &fs);
    else
        memcpy(c->x, c->xbest, 3 * (size_t)c->nv * sizeof(double));
    return QDC_OK;
}

/* Rounds of joint moves of the worst tets' corners on their sines (angle.h),
 * while that lifts the smallest sine. smin_ok: smin is of c->trial. */
static qdc_status patch_rounds(ctx_t *c, const uint8_t *movable, const slide_ctx *sl,
                               const opt_progress *base, double *smin, int smin_ok,
                               opt_result *res, angle_tally *t)
{
    size_t n3 = 3 * (size_t)c->nv;

    for (int round = 0; round < ANGLE_PATCH_ROUNDS; round++) {
        finish_stats fs;
        qdc_status st;
        if (ctx_should_stop(c, res))
            break;
        memcpy(c->x, t->kept ? c->trial : c->xbest, n3 * sizeof(double));
        st = finish_patches(c->tp, movable, sl, c->x, c->lbar, FINISH_PATCH_ANGLES,
                            base->q_min, smin, round > 0 || smin_ok, &fs);
        if (st != QDC_OK)
            return st;
        if (!(fs.floor_after > fs.floor_before))
            break;
        tally_kept(c, t, &fs);
        if (!(fs.floor_after > fs.floor_before * (1 + 1e-3)))
            break;
    }
    return QDC_OK;
}

static qdc_status angle_pass(ctx_t *c, const uint8_t *movable, const slide_ctx *sl,
                             opt_result *res, opt_progress *r, int *next)
{
    /* the tet sines a sweep leaves are those the next one starts from (a
     * rejected sweep ends the pass); c->eta is free scratch here, c->trial
     * holds the last accepted sweep */
    double *smin = c->eta;
    const opt_progress base = c->best;
    size_t n3 = 3 * (size_t)c->nv;
    int slow = 0, smin_ok = 0; /* smin is of c->trial */
    angle_tally t = {0, 0, 0};
    qdc_status st;

    memcpy(c->x, c->xbest, n3 * sizeof(double));
    if (!ctx_should_stop(c, res)) {
        st = mean_ratio_round(c, movable, sl, &base, &t);
        if (st != QDC_OK)
            return st;
    }
    for (int s = 0; s < ANGLE_SWEEPS; s++) {
        finish_stats fs;
        int floor_up;
        if (ctx_should_stop(c, res))
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
        tally_kept(c, &t, &fs);
        floor_up = fs.floor_after > fs.floor_before * (1 + 1e-3) &&
                   fs.floor_after - fs.floor_before > ANGLE_MIN_RISE;
        if (fs.n_moves == 0 ||
            !(floor_up || fs.score_after > fs.score_before * (1 + 1e-3)))
            break;
        slow = floor_up || fs.score_after > fs.score_before * 1.01 ? 0 : slow + 1;
        if (slow >= ANGLE_SLOW)
            break;
    }
    st = patch_rounds(c, movable, sl, &base, smin, smin_ok, res, &t);
    if (st != QDC_OK || !t.kept)
        return st;
    /* one record for the pass (a record costs a sweep's worth of work) */
    ctx_pass_record(c, r, next, "angles");
    r->step = t.visits > 0 ? t.moves / t.visits : 0;
    if (ctx_eligible(c, r) && r->n_inverted <= base.n_inverted &&
        r->q_min >= base.q_min) {
        c->best = *r;
        c->best_it = r->iteration;
        memcpy(c->xbest, c->x, n3 * sizeof(double));
    }
    if (ctx_report(c, r))
        ctx_set_stop(res, OPT_STOP_CANCELLED);
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

typedef struct {
    ctx_t *c;
    opt_result *res;
} stop_arg;

static int stop_asked(void *arg)
{
    stop_arg *a = arg;
    return ctx_should_stop(a->c, a->res);
}

/* Inverted tets the finishing pass left: the max-min volume untangling of
 * their interior vertices (untangle.h) from the best iterate, kept through the
 * best-iterate rule (fewer inverted tets first). */
static qdc_status untangle_pass(ctx_t *c, const uint8_t *movable, opt_result *res,
                                opt_progress *r, int *next)
{
    int32_t ninv;
    qdc_status st;
    stop_arg sa = {c, res};

    memcpy(c->trial, c->xbest, 3 * (size_t)c->nv * sizeof(double));
    st =
        finish_untangle(c->tp, movable, c->sl, c->trial, c->lbar, stop_asked, &sa, &ninv);
    if (st != QDC_OK || ninv >= c->best.n_inverted)
        return st;
    ctx_pass_record(c, r, next, "untangle");
    r->step = 0;
    ctx_consider(c, c->x, r);
    if (ctx_report(c, r))
        ctx_set_stop(res, OPT_STOP_CANCELLED);
    return QDC_OK;
}

/* The first pass's result (c->x, its record r), not kept because of the
 * tets it left inverted: those untangled (untangle_pass) and repaired locally
 * (local_pass, the regions holding their planes and lines: hold_flat) as if
 * it were the best iterate. Kept if it then is eligible and better than the
 * best iterate before; else the best iterate, and the run's bound, are put
 * back. Before, such a pass was thrown away and the untangling started from
 * the global phase's iterate: measured on the cubes of scripts/corpus.py
 * --only cube-lowq, at 809k tets the mean ratio 0.6447 -> 0.6663 with the
 * second pass saved, at 3.97M tets 0.6344 -> 0.6544 (tets under 5 degrees
 * 39875 -> 7103). */
static qdc_status repair_first_pass(ctx_t *c, const uint8_t *movable, opt_result *res,
                                    opt_progress *r, int *next)
{
    size_t n3 = 3 * (size_t)c->nv;
    double *saved = qdc_mallocn(n3 + 1, sizeof(double)), bound = res->hausd_bound;
    opt_progress best = c->best;
    int best_it = c->best_it, first = r->iteration, was = r->n_inverted;
    qdc_status st;

    if (!saved)
        return QDC_ENOMEM;
    memcpy(saved, c->xbest, n3 * sizeof(double));
    memcpy(c->xbest, c->x, n3 * sizeof(double));
    c->best = *r;
    c->best_it = first;
    c->hold_flat = 1; /* the pass may leave folds at the surface */
    st = untangle_pass(c, movable, res, r, next);
    if (r->iteration > first) { /* untangled: the local repair starts from there */
        memcpy(c->xbest, c->x, n3 * sizeof(double));
        c->best = *r;
        c->best_it = r->iteration;
    }
    if (st == QDC_OK && c->best.n_inverted > 0 && res->stop != OPT_STOP_CANCELLED)
        st = local_pass(c, res, r, next);
    c->hold_flat = 0;
    if (st != QDC_OK || !ctx_eligible(c, &c->best) || !ctx_better(&c->best, &best)) {
        memcpy(c->xbest, saved, n3 * sizeof(double));
        c->best = best;
        c->best_it = best_it;
        res->hausd_bound = bound;
    } else {
        ctx_log(c, 0,
                "the finishing pass's result, its %d inverted tets repaired, is kept",
                was);
    }
    qdc_free(saved);
    return st;
}

/* The finishing pass and the angle polish. */
qdc_status opt_finishing_phase(ctx_t *c, opt_result *res, opt_progress *r)
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
    if (st == QDC_OK && next > res->iterations + 1 && c->best_it <= res->iterations &&
        r->n_inverted > 0 && res->stop != OPT_STOP_CANCELLED)
        st = repair_first_pass(c, movable, res, r, &next);
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
    /* still inverted: their neighbourhoods again on their own (local.c) */
    if (st == QDC_OK && c->best.n_inverted > 0 && res->stop != OPT_STOP_CANCELLED)
        st = local_pass(c, res, r, &next);
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
