/* opt.c - one run of the QDC optimizer, as docs/method.md tells it: the
 * mesh normalized and its system set up (§1-§4, ctx.c), the global phase of
 * the semi-implicit gradient flow (paper Eq. 15) with the safeguards of §5
 * and harmonic guidance (§6, global.c), the finishing phase (§5a,
 * finishing.c), do no harm (§5, hold.c), the best iterate mapped back. The
 * rerun policy of slide mode and opt_run are in rerun.c. */
#include "opt/run.h"

#include "geom/metric_int.h"
#include "opt/ctx.h"
#include "opt/finishing.h"
#include "opt/global.h"
#include "opt/hold.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

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
           (unsigned)o->solver <= OPT_SOLVER_PCG &&
           (unsigned)o->topology <= OPT_TOPOLOGY_FULL;
}

/* In the smoothing of the topology modes, under a bound, the corners of each tet with
 * three boundary faces move free within the bound of where they are, as the loose
 * vertices of a rerun do: such a tet hangs on an edge of four boundary
 * triangles, its shape is its surface's, no flip removes it while the
 * triangles are kept, and sliding leaves it as flat as it came (the 100k-tet
 * bone-scan of scripts/corpus.py --seed 1 has 16: with --topology flips the
 * worst was the mesh's worst, 0.66 degrees, 0.71 in the input; 1.16 with
 * them free). Only a fin under a mean ratio of FIN_QMAX: the corner tet of
 * a box, on three planes, has its corners on the box's edges (feature lines),
 * which a good tet's corners must not leave. Corners, flat patches, straight
 * lines and fixed or pinned vertices stay as they are: what a free vertex
 * moves is what the rounds of the topology modes count against the bound
 * (spend.c). Returns how many vertices were freed, -1 when out of memory.
 * (Freeing the corners of every tet of four boundary corners under 0.05 took
 * bone-lowq's smallest angle from 0.14 to 0.53 degrees, but by freeing the
 * vertices of its feature lines, thousands of them: not done.) */
#define FIN_QMAX 0.1

/* Boundary vertex v of the run freed from its surface (slide_release) and
 * from its least-squares row: a rerun's loose vertex, a bad fin's corner. */
static void set_loose(ctx_t *c, int32_t v, int unbounded)
{
    slide_release(c->sl, v, unbounded);
    c->locked[v] = 0;
    c->bw2[v] = 1.0;
}

static int is_fin(const ctx_t *c, const mesh_topo *tp, const uint8_t *bf, int32_t t)
{
    const int32_t *tt = tp->tets + 4 * (size_t)t;
    metric_parts pt;

    if (bf[t] != 3)
        return 0;
    metric_parts_for(OPT_METRIC_MIVL, c->x0 + 3 * (size_t)tt[0],
                     c->x0 + 3 * (size_t)tt[1], c->x0 + 3 * (size_t)tt[2],
                     c->x0 + 3 * (size_t)tt[3], &pt);
    return metric_mean_ratio(&pt) < FIN_QMAX;
}

static int32_t free_fins(ctx_t *c, const mesh_topo *tp, const uint8_t *pins)
{
    uint8_t *bf = qdc_calloc((size_t)tp->nt + 1, 1),
            *freed = qdc_calloc((size_t)tp->nv + 1, 1);
    int32_t n = 0;

    if (!bf || !freed) {
        qdc_free(bf);
        qdc_free(freed);
        return -1;
    }
    for (int32_t i = 0; i < tp->nbf; i++)
        bf[tp->bface_of[i] >> 2]++;
    for (int32_t t = 0; t < tp->nt; t++) {
        if (!is_fin(c, tp, bf, t))
            continue;
        for (int k = 0; k < 4; k++) {
            int32_t v = tp->tets[4 * (size_t)t + k];
            int kind = slide_kind(c->sl, v);
            if (freed[v] || (tp->vflag[v] & (MESH_V_FIXED | MESH_V_UNUSED)) ||
                (pins && pins[v]) || slide_flat(c->sl, v) ||
                (kind != SLIDE_SURFACE && kind != SLIDE_LINE))
                continue;
            set_loose(c, v, 0);
            freed[v] = 1;
            n++;
        }
    }
    qdc_free(bf);
    qdc_free(freed);
    return n;
}

/* The context of one run: topology (shared, the caller's, if not NULL; else
 * built into *own), ctx, loose and pinned vertices, the solver, the input's
 * record (reported). */
static qdc_status run_setup(ctx_t *c, mesh_t *m, const opt_options *o,
                            const uint8_t *pins, const uint8_t *loose,
                            const mesh_topo *shared, mesh_topo **own, opt_result *res,
                            opt_progress *r, qdc_error *err)
{
    const mesh_topo *tp = shared;
    double t0 = c->t0, bound;
    int32_t nloose = 0;
    qdc_status st = shared ? QDC_OK : mesh_topo_build(m, own, err);

    if (st != QDC_OK)
        return st;
    if (!shared)
        tp = *own;
    st = ctx_init(c, m, tp, o); /* clears c */
    c->t0 = t0;
    if (st != QDC_OK)
        return st;
    bound = c->hbound;
    for (int32_t v = 0; loose && c->sl && v < c->nv; v++)
        if (loose[v] && !(tp->vflag[v] & MESH_V_FIXED)) {
            set_loose(c, v, loose[v] == SLIDE_LOOSE_UNBOUNDED);
            nloose++;
        }
    /* the default's freed vertices (tets left inverted where sliding within
     * the bound could not undo them) move within OPT_HAUSD_STUCK: at 3e-3 a
     * tangled 100k-tet scanned bone (scripts/corpus.py --seed 8) kept 4 tets
     * inverted, at 1e-2 1, free as far as they like 1 too; the run's bound
     * is then that larger one */
    if (nloose && c->autob && OPT_HAUSD_STUCK > c->hbound) {
        slide_set_loose_bound(c->sl, OPT_HAUSD_STUCK);
        bound = OPT_HAUSD_STUCK;
    }
    if (c->sl && c->hbound > 0 && o->free_fins) {
        int32_t nfin = free_fins(c, tp, pins);
        if (nfin < 0)
            return qdc_fail(err, QDC_ENOMEM, "out of memory");
        if (nfin > 0)
            ctx_log(c, 0,
                    "%d corners of tets with three boundary faces free within the bound",
                    (int)nfin);
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
    ctx_log(c, 0, "%d vertices (%d boundary), %d tets; solver %s (analysis %.3g flops)",
            (int)m->nv, (int)tp->nb, (int)m->nt, opt_solver_name(res->solver),
            res->solver_flops);
    res->t_setup = qdc_now() - c->t0;
    ctx_evaluate_x(c, r);
    r->phase = "input";
    c->input = c->best = *r;
    res->before = *r;
    res->hausd_bound = bound * c->scale;
    ctx_set_stop(res, OPT_STOP_MAX_ITER);
    return QDC_OK;
}

/* hold_back, with the best record brought up to date. */
static void hold_back_best(ctx_t *c, opt_result *res)
{
    int32_t back = opt_hold_back(c);
    opt_progress b;

    if (back <= 0)
        return;
    ctx_evaluate(c, c->xbest, &b, NULL);
    if (c->input.n_inverted == 0 && b.q_mean < c->input.q_mean) {
        /* what is left no longer beats the input's mean: the input it is */
        memcpy(c->xbest, c->x0, 3 * (size_t)c->nv * sizeof(double));
        c->best = c->input;
        c->best_it = 0;
        ctx_log(c, 0,
                "holding back %d vertices took the mean ratio under the input's: "
                "the input is returned",
                (int)back);
        return;
    }
    b.iteration = c->best.iteration;
    b.phase = c->best.phase;
    c->best = b;
    res->held_back = back;
    ctx_log(c, 0,
            "%d vertices held at their input positions (no tet below the input's worst)",
            (int)back);
}

/* What the reruns read (rerun.c, hold.h): in slide mode the corners of the
 * squashed ears (if squashed) and the stuck boundary (if stuck). */
static qdc_status rerun_masks(const ctx_t *c, uint8_t **squashed, uint8_t **stuck)
{
    qdc_status st = QDC_OK;

    if (squashed && c->sl && c->best_it > 0 && c->input.n_inverted > 0)
        st = opt_squashed_ears(c, squashed);
    if (st == QDC_OK && stuck && c->sl && c->autob && c->best.n_inverted > 0)
        st = opt_stuck_boundary(c, stuck);
    return st;
}

/* The best iterate into m's coordinates, and the result's closing fields. */
static void map_back(ctx_t *c, mesh_t *m, const mesh_topo *tp, opt_result *res)
{
    /* map back; locked vertices keep their exact input coordinates, and if the
     * input itself is the best iterate the mesh is left bit-for-bit as it was */
    for (int32_t v = 0; c->best_it > 0 && v < c->nv; v++)
        if (!c->locked[v])
            for (int k = 0; k < 3; k++)
                m->xyz[3 * (size_t)v + k] =
                    c->xbest[3 * (size_t)v + k] * c->scale + c->center[k];
    /* counted again on the coordinates the caller gets: mapping back rounds,
     * and a tet of near-zero volume can change sign (measured on a tangled
     * thin bone of 94k tets: one tet positive here, -1e-19 in the file) */
    if (c->best_it > 0) {
        int32_t n = mesh_count_inverted(tp, m->xyz);
        c->best.n_inverted = n > c->best.n_inverted ? n : c->best.n_inverted;
    }
    res->after = c->best;
    res->best_iteration = c->best_it;
    res->last_record = c->last_record;
    res->outcome = res->stop == OPT_STOP_CONVERGED || res->stop == OPT_STOP_MAX_ITER ||
                           res->stop == OPT_STOP_NO_DESCENT
                       ? OPT_CONVERGED
                       : OPT_STOPPED;
}

static qdc_status run_once(mesh_t *m, const opt_options *opts, const mesh_topo *shared,
                           const uint8_t *pins, const uint8_t *loose, uint8_t **squashed,
                           uint8_t **stuck, int keep_surface, int region,
                           opt_result *res_out, qdc_error *err);

/* The repair hook of a run (ctx.h): one run of a region of its mesh, itself
 * without the hook. */
static qdc_status run_region(mesh_t *m, const opt_options *o, int keep_surface,
                             const uint8_t *loose, opt_result *r, qdc_error *err)
{
    return run_once(m, o, NULL, NULL, loose, NULL, NULL, keep_surface, 1, r, err);
}

qdc_status opt_run_once(mesh_t *m, const opt_options *opts, const mesh_topo *tp,
                        const uint8_t *pins, const uint8_t *loose, uint8_t **squashed,
                        uint8_t **stuck, int keep_surface, opt_result *res_out,
                        qdc_error *err)
{
    return run_once(m, opts, tp, pins, loose, squashed, stuck, keep_surface, 0, res_out,
                    err);
}

/* One optimization of m, on the topology shared (of m; NULL: its own). pins
 * (nv flags, may be NULL): extra vertices that
 * keep their input position; loose (may be NULL): sliding vertices that move
 * freely (slide_release). In slide mode *squashed (if not NULL) receives the
 * corners of the ears this run squashed (opt_squashed_ears), and *stuck (if
 * not NULL) the boundary vertices around tets left inverted (opt_stuck_boundary);
 * else NULL. keep_surface: the finishing pass folds no tet at the surface
 * (finish.h). region: a run of local.c's region (no repair hook). */
static qdc_status run_once(mesh_t *m, const opt_options *opts, const mesh_topo *shared,
                           const uint8_t *pins, const uint8_t *loose, uint8_t **squashed,
                           uint8_t **stuck, int keep_surface, int region,
                           opt_result *res_out, qdc_error *err)
{
    opt_options o;
    opt_result res;
    mesh_topo *own = NULL;
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
    st = run_setup(&c, m, &o, pins, loose, shared, &own, &res, &r, err);
    if (st != QDC_OK)
        goto out;
    c.keep_surface = keep_surface;
    c.repair = region ? NULL : run_region;
    if (ctx_report(&c, &r)) {
        stop = 1;
        ctx_set_stop(&res, OPT_STOP_CANCELLED);
    }
    st = opt_global_phase(&c, &res, &r, &stop, err);
    if (st != QDC_OK)
        goto out;
    res.before_finish = c.best;
    c.rerun_stuck = stuck && c.sl && c.autob;
    if (o.finish && !stop && o.finish_sweeps > 0) {
        st = opt_finishing_phase(&c, &res, &r);
        if (st != QDC_OK)
            goto out;
    }
    hold_back_best(&c, &res);
    st = rerun_masks(&c, squashed, stuck);
    if (st != QDC_OK)
        goto out;
    map_back(&c, m, c.tp, &res);
    st = QDC_OK;
out:
    res.t_total = qdc_now() - c.t0;
    if (st != QDC_OK)
        res.outcome = OPT_FAILED;
    if (res_out)
        *res_out = res;
    ctx_free(&c);
    mesh_topo_free(own);
    if (saved_threads > 0)
        omp_set_num_threads(saved_threads);
    return st;
}
