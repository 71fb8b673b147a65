/* test_opt.c - behaviour of the optimizer on synthetic meshes: it improves,
 * untangles, never returns a worse mesh, respects locked vertices and tags,
 * stops on cancel. */
#include "core/mesh_int.h"
#include "core/tet.h"
#include "geom/metric_int.h"
#include "opt/angle.h"
#include "opt/encode.h"
#include "opt/finish.h"
#include "opt/opt_int.h"
#include "opt/untangle.h"
#include "qdc.h"
#include "testlib.h"
#include "testmesh.h"

#include <math.h>
#include <omp.h>
#include <string.h>

static report_quality quality(const mesh_t *m)
{
    report_quality q;
    report_quality_compute(m, &q, NULL);
    return q;
}

static int all_finite(const mesh_t *m)
{
    for (size_t i = 0; i < 3 * (size_t)m->nv; i++)
        if (!isfinite(m->xyz[i]))
            return 0;
    return 1;
}

TEST(improves_perturbed_grid)
{
    int n = 6;
    mesh_t *m = tm_grid(n, 0);
    opt_options o;
    opt_result r;
    report_quality before, after;
    tm_perturb(m, n, 0.35, 11);
    before = quality(m);
    opt_defaults(&o);
    ASSERT_OK(opt_run(m, &o, &r, NULL));
    after = quality(m);
    ASSERT_TRUE(all_finite(m));
    ASSERT_EQ_INT(after.n_inverted, 0);
    ASSERT_TRUE(after.q_mean > before.q_mean + 0.02);
    ASSERT_TRUE(after.q_min >= before.q_min);
    ASSERT_TRUE(after.dih_min > before.dih_min);
    /* the library's own record agrees with an independent evaluation */
    ASSERT_NEAR(r.after.q_mean, after.q_mean, 1e-9);
    ASSERT_NEAR(r.after.q_min, after.q_min, 1e-9);
    ASSERT_TRUE(r.outcome == OPT_CONVERGED);
    mesh_free(m);
}

TEST(untangles_inverted_grid)
{
    int n = 6;
    mesh_t *m = tm_grid(n, 0);
    opt_options o;
    report_quality before, after;
    /* swap two interior vertices' positions and push others around: tangled */
    tm_perturb(m, n, 1.6, 5);
    before = quality(m);
    ASSERT_TRUE(before.n_inverted > 20);
    opt_defaults(&o);
    ASSERT_OK(opt_run(m, &o, NULL, NULL));
    after = quality(m);
    ASSERT_EQ_INT(after.n_inverted, 0);
    ASSERT_EQ_INT(after.n_degenerate, 0);
    ASSERT_TRUE(after.q_min > 0.1);
    mesh_free(m);
}

/* With a fixed boundary the global step folds no valid tet on the way either
 * (only lsq trades a few folds for more untangled tets, opt.c feasible_trial). */
TEST(fixed_boundary_untangles_without_folding)
{
    int n = 6;
    mesh_t *m = tm_grid(n, 0);
    opt_options o;
    opt_result r;
    report_quality after;
    tm_perturb(m, n, 1.6, 5);
    opt_defaults(&o);
    o.boundary = OPT_BOUNDARY_FIXED;
    ASSERT_OK(opt_run(m, &o, &r, NULL));
    after = quality(m);
    ASSERT_EQ_INT(r.folded_global, 0);
    ASSERT_EQ_INT(after.n_inverted + after.n_degenerate, 0);
    mesh_free(m);
}

TEST(never_worse_than_input)
{
    /* an already regular Kuhn grid with a fixed boundary: any change must keep
     * the worst tet and the inverted count */
    int n = 4;
    mesh_t *m = tm_grid(n, 0);
    opt_options o;
    report_quality before, after;
    before = quality(m);
    for (int mode = 0; mode < 2; mode++) {
        opt_defaults(&o);
        o.mode = (opt_mode)mode;
        o.boundary = OPT_BOUNDARY_FIXED;
        ASSERT_OK(opt_run(m, &o, NULL, NULL));
        after = quality(m);
        ASSERT_TRUE(after.n_inverted <= before.n_inverted);
        ASSERT_TRUE(after.q_min >= before.q_min - 1e-12);
        ASSERT_TRUE(after.q_mean >= before.q_mean - 1e-12);
        ASSERT_TRUE(all_finite(m));
    }
    mesh_free(m);
}

TEST(literal_mode_is_safe_and_reported)
{
    int n = 5;
    mesh_t *m = tm_grid(n, 0);
    opt_options o;
    opt_result r;
    report_quality before, after;
    tm_perturb(m, n, 0.4, 21);
    before = quality(m);
    opt_defaults(&o);
    o.mode = OPT_MODE_LITERAL;
    o.finish = 0;
    ASSERT_OK(opt_run(m, &o, &r, NULL));
    after = quality(m);
    ASSERT_TRUE(after.n_inverted <= before.n_inverted);
    ASSERT_TRUE(after.q_min >= before.q_min);
    ASSERT_TRUE(r.iterations >= 1);
    mesh_free(m);
}

TEST(fixed_boundary_and_user_locks_do_not_move)
{
    int n = 5;
    mesh_t *m = tm_grid(n, MESH_WITH_FIXED), *orig;
    opt_options o;
    mesh_topo *tp = NULL;
    tm_perturb(m, n, 0.4, 3);
    m->fixed[2 + (n + 1) * (2 + (n + 1) * 2)] = 1; /* an interior vertex */
    orig = mesh_dup(m);
    ASSERT_OK(mesh_topo_build(m, &tp, NULL));
    opt_defaults(&o);
    o.boundary = OPT_BOUNDARY_FIXED;
    ASSERT_OK(opt_run(m, &o, NULL, NULL));
    for (int32_t v = 0; v < m->nv; v++)
        if ((tp->vflag[v] & MESH_V_BOUNDARY) || m->fixed[v])
            for (int k = 0; k < 3; k++)
                ASSERT_TRUE(m->xyz[3 * v + k] == orig->xyz[3 * v + k]);
    /* interior vertices did move */
    ASSERT_TRUE(memcmp(m->xyz, orig->xyz, 3 * sizeof(double) * (size_t)m->nv) != 0);
    mesh_topo_free(tp);
    mesh_free(orig);
    mesh_free(m);
}

TEST(regions_and_connectivity_untouched)
{
    int n = 5;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION), *orig;
    opt_options o;
    tm_perturb(m, n, 0.3, 9);
    orig = mesh_dup(m);
    opt_defaults(&o);
    ASSERT_OK(opt_run(m, &o, NULL, NULL));
    ASSERT_TRUE(memcmp(m->tets, orig->tets, 16 * (size_t)m->nt) == 0);
    ASSERT_TRUE(memcmp(m->region, orig->region, 4 * (size_t)m->nt) == 0);
    mesh_free(orig);
    mesh_free(m);
}

static int cancel_at_2(void *ctx, const opt_progress *p)
{
    int *count = ctx;
    (*count)++;
    return p->iteration >= 2;
}

TEST(cancel_from_progress_callback)
{
    int n = 5, calls = 0;
    mesh_t *m = tm_grid(n, 0);
    opt_options o;
    opt_result r;
    report_quality before, after;
    tm_perturb(m, n, 0.4, 4);
    before = quality(m);
    opt_defaults(&o);
    o.progress = cancel_at_2;
    o.progress_ctx = &calls;
    ASSERT_OK(opt_run(m, &o, &r, NULL));
    after = quality(m);
    ASSERT_EQ_INT(calls, 3); /* input, iterations 1 and 2 */
    ASSERT_TRUE(r.outcome == OPT_STOPPED);
    ASSERT_TRUE(strcmp(r.stop_reason, "cancelled") == 0);
    ASSERT_TRUE(after.q_min >= before.q_min);
    mesh_free(m);
}

/* Each global iteration's record waits 0.3 s of wall time: iterations of a
 * known length, whatever the machine's load. */
static int slow_records(void *ctx, const opt_progress *p)
{
    int *count = ctx;
    double t0 = omp_get_wtime();
    (*count)++;
    if (p->iteration > 0 && strcmp(p->phase, "global") == 0)
        while (omp_get_wtime() - t0 < 0.3)
            ;
    return 0;
}

/* --time-limit is not overrun by a whole iteration: with iterations of 0.3 s
 * or more and a 1 s limit the run stops after the third at the latest (the
 * fourth would end at 1.2 s, past the limit, and used to be run), and ends
 * less than one of its own iterations (their mean in this run) past the
 * limit: no fixed slack, which a busy machine overran (1e65a55 gave 0.1 s).
 * A loaded machine may take 0.6 s an iteration and stop after the first. */
TEST(time_limit_not_overrun_by_an_iteration)
{
    int n = 5, calls = 0;
    mesh_t *m = tm_grid(n, 0);
    opt_options o;
    opt_result r;
    tm_perturb(m, n, 0.4, 4);
    opt_defaults(&o);
    o.max_iter = 100;
    o.stall = 0;
    o.tol_move = 0;
    o.finish = 0;
    o.time_limit = 1.0;
    o.progress = slow_records;
    o.progress_ctx = &calls;
    ASSERT_OK(opt_run(m, &o, &r, NULL));
    ASSERT_TRUE(strcmp(r.stop_reason, "time-limit") == 0);
    ASSERT_TRUE(r.iterations >= 1 && r.iterations <= 3);
    ASSERT_TRUE(r.t_total - o.time_limit < r.t_total / r.iterations);
    mesh_free(m);
}

TEST(cancel_flag_before_start)
{
    int n = 3;
    atomic_int flag = 1;
    mesh_t *m = tm_grid(n, 0), *orig;
    opt_options o;
    opt_result r;
    tm_perturb(m, n, 0.3, 4);
    orig = mesh_dup(m);
    opt_defaults(&o);
    o.cancel = &flag;
    ASSERT_OK(opt_run(m, &o, &r, NULL));
    ASSERT_EQ_INT(r.iterations, 0);
    ASSERT_TRUE(memcmp(m->xyz, orig->xyz, 24 * (size_t)m->nv) == 0);
    mesh_free(orig);
    mesh_free(m);
}

TEST(solvers_and_metrics_all_work)
{
    static const opt_solver solvers[] = {OPT_SOLVER_CHOLMOD, OPT_SOLVER_PCG};
    double means[2];
    for (int s = 0; s < 2; s++) {
        int n = 5;
        mesh_t *m = tm_grid(n, 0);
        opt_options o;
        opt_result r;
        tm_perturb(m, n, 0.4, 17);
        opt_defaults(&o);
        o.solver = solvers[s];
        o.finish = 0;
        ASSERT_OK(opt_run(m, &o, &r, NULL));
        ASSERT_EQ_INT(r.solver, solvers[s]);
        means[s] = quality(m).q_mean;
        mesh_free(m);
    }
    /* same method, two solvers: the same result up to CG tolerance effects */
    ASSERT_NEAR(means[0], means[1], 2e-3);
    for (int mm = 0; mm < 3; mm++) {
        int n = 4;
        mesh_t *m = tm_grid(n, 0);
        opt_options o;
        report_quality before;
        tm_perturb(m, n, 0.4, 23);
        before = quality(m);
        opt_defaults(&o);
        o.metric = (opt_metric)mm;
        ASSERT_OK(opt_run(m, &o, NULL, NULL));
        ASSERT_TRUE(quality(m).q_mean > before.q_mean);
        mesh_free(m);
    }
}

TEST(harmonic_guidance_runs)
{
    int n = 6;
    mesh_t *m = tm_grid(n, 0);
    opt_options o;
    opt_result r;
    report_quality before;
    tm_perturb(m, n, 0.4, 31);
    before = quality(m);
    opt_defaults(&o);
    o.harmonic = 1;
    ASSERT_OK(opt_run(m, &o, &r, NULL));
    ASSERT_TRUE(r.iterations > o.pre_iters);
    ASSERT_TRUE(quality(m).q_mean > before.q_mean);
    ASSERT_TRUE(all_finite(m));
    mesh_free(m);
}

/* The optimizer works on its own spatial numbering (core/order.h), so the
 * vertex numbers a file happens to use do not change the result: the same
 * mesh numbered at random comes back with every vertex at the same place. */
TEST(result_does_not_depend_on_vertex_numbering)
{
    int n = 5;
    mesh_t *a = tm_grid(n, 0), *b;
    int32_t *perm;
    uint64_t seed = 7;
    opt_options o;
    opt_result ra, rb;

    tm_perturb(a, n, 0.45, 3);
    b = mesh_dup(a);
    perm = malloc((size_t)a->nv * sizeof *perm);
    ASSERT_TRUE(b && perm);
    for (int32_t v = 0; v < a->nv; v++)
        perm[v] = v;
    for (int32_t v = a->nv - 1; v > 0; v--) { /* Fisher-Yates */
        int32_t j = (int32_t)((tm_rand(&seed) + 1.0) * 0.5 * (v + 1)) % (v + 1),
                t = perm[v];
        perm[v] = perm[j];
        perm[j] = t;
    }
    for (int32_t v = 0; v < a->nv; v++)
        memcpy(b->xyz + 3 * perm[v], a->xyz + 3 * v, 3 * sizeof(double));
    for (size_t i = 0; i < 4 * (size_t)a->nt; i++)
        b->tets[i] = perm[a->tets[i]];
    opt_defaults(&o);
    o.threads = 1;
    ASSERT_OK(opt_run(a, &o, &ra, NULL));
    ASSERT_OK(opt_run(b, &o, &rb, NULL));
    ASSERT_TRUE(ra.after.q_mean > ra.before.q_mean + 0.01);
    ASSERT_NEAR(ra.after.q_mean, rb.after.q_mean, 0.0);
    for (int32_t v = 0; v < a->nv; v++)
        ASSERT_TRUE(memcmp(b->xyz + 3 * perm[v], a->xyz + 3 * v, 3 * sizeof(double)) ==
                    0);
    free(perm);
    mesh_free(a);
    mesh_free(b);
}

TEST(bad_options_and_bad_mesh_rejected)
{
    mesh_t *m = tm_grid(2, 0), *orig = mesh_dup(m);
    opt_options o;
    opt_result r;
    qdc_error e;
    opt_defaults(&o);
    o.mu = -1;
    ASSERT_EQ_INT(opt_run(m, &o, &r, &e), QDC_EINVAL);
    ASSERT_EQ_INT(r.outcome, OPT_FAILED);
    opt_defaults(&o);
    m->tets[3] = 99;
    ASSERT_EQ_INT(opt_run(m, &o, &r, &e), QDC_EMESH);
    m->tets[3] = orig->tets[3];
    ASSERT_TRUE(memcmp(m->xyz, orig->xyz, 24 * (size_t)m->nv) == 0);
    ASSERT_EQ_INT(opt_parse_metric("nope", &o.metric), QDC_EINVAL);
    ASSERT_OK(opt_parse_metric("micn", &o.metric));
    ASSERT_EQ_INT(o.metric, OPT_METRIC_MICN);
    mesh_free(orig);
    mesh_free(m);
}

/* Every allocation of opt_run failing in turn: QDC_ENOMEM, the mesh untouched,
 * no leak (the sanitizer build checks leaks); then a run without faults works. */
TEST(allocation_failures_are_clean)
{
#ifdef QDC_FAULT_INJECTION
    int n = 3;
    mesh_t *m = tm_grid(n, 0), *orig;
    opt_options o;
    qdc_status st = QDC_ENOMEM;
    long k;
    tm_perturb(m, n, 0.4, 2);
    orig = mesh_dup(m);
    opt_defaults(&o);
    for (k = 1; k < 5000 && st == QDC_ENOMEM; k++) {
        qdc_fault_set(k);
        st = opt_run(m, &o, NULL, NULL);
        qdc_fault_set(0);
        if (st == QDC_ENOMEM)
            ASSERT_TRUE(memcmp(m->xyz, orig->xyz, 24 * (size_t)m->nv) == 0);
        /* the connectivity lent to the run comes back as it was, also when
         * there is no memory left to give it back by (in place, then) */
        ASSERT_TRUE(memcmp(m->tets, orig->tets, 16 * (size_t)m->nt) == 0);
    }
    ASSERT_OK(st);
    ASSERT_TRUE(k > 10);
    printf("  # %ld allocation failure points, each clean\n", k - 1);
    mesh_free(orig);
    mesh_free(m);
#else
    SKIP("built without QDC_FAULT_INJECTION (make fault runs it)");
#endif
}

/* smallest dihedral sine and mean ratio of tet t */
static void tet_values(const mesh_t *m, int32_t t, double *smin, double *eta)
{
    const int32_t *tt = m->tets + 4 * (size_t)t;
    double sn[6];
    metric_parts pt;

    metric_dihedral_sines(m->xyz + 3 * tt[0], m->xyz + 3 * tt[1], m->xyz + 3 * tt[2],
                          m->xyz + 3 * tt[3], sn);
    metric_parts_of(m->xyz + 3 * tt[0], m->xyz + 3 * tt[1], m->xyz + 3 * tt[2],
                    m->xyz + 3 * tt[3], &pt);
    *smin = INFINITY;
    for (int e = 0; e < 6; e++)
        *smin = fmin(*smin, sn[e]);
    *eta = metric_mean_ratio(&pt);
}

/* smallest dihedral sine and smallest mean ratio of the mesh */
static void worst_of(const mesh_t *m, double *smin, double *qmin)
{
    *smin = *qmin = INFINITY;
    for (int32_t t = 0; t < m->nt; t++) {
        double s, q;
        tet_values(m, t, &s, &q);
        *smin = fmin(*smin, s);
        *qmin = fmin(*qmin, q);
    }
}

/* A perturbed grid of n^3 cubes for the finishing functions: its topology,
 * its interior vertices movable, a copy of its coordinates, a value per tet. */
typedef struct {
    int n;
    mesh_t *m;
    mesh_topo *tp;
    uint8_t *movable;
    double *x0, *val;
} grid_case;

static int grid_case_new(grid_case *g, int n, double amp, unsigned seed)
{
    g->n = n;
    g->m = tm_grid(n, 0);
    g->tp = NULL;
    tm_perturb(g->m, n, amp, seed);
    if (mesh_topo_build(g->m, &g->tp, NULL) != QDC_OK)
        return 0;
    g->movable = calloc((size_t)g->m->nv, 1);
    g->x0 = malloc(3 * (size_t)g->m->nv * sizeof(double));
    g->val = malloc((size_t)g->m->nt * sizeof(double));
    if (!g->movable || !g->x0 || !g->val)
        return 0;
    for (int32_t v = 0; v < g->m->nv; v++)
        g->movable[v] = !(g->tp->vflag[v] & MESH_V_BOUNDARY);
    memcpy(g->x0, g->m->xyz, 3 * (size_t)g->m->nv * sizeof(double));
    return 1;
}

static void grid_case_free(grid_case *g)
{
    free(g->val);
    free(g->movable);
    free(g->x0);
    mesh_topo_free(g->tp);
    mesh_free(g->m);
}

/* 1 if no vertex that may not move has moved since x0 was taken. */
static int fixed_kept(const grid_case *g)
{
    for (int32_t v = 0; v < g->m->nv; v++)
        if (!g->movable[v] &&
            memcmp(g->m->xyz + 3 * v, g->x0 + 3 * v, 3 * sizeof(double)))
            return 0;
    return 1;
}

/* 1 if val holds each tet's smallest dihedral sine (sines) or mean ratio. */
static int values_current(const grid_case *g, int sines)
{
    for (int32_t t = 0; t < g->m->nt; t++) {
        double s, q;
        tet_values(g->m, t, &s, &q);
        if (fabs(g->val[t] - (sines ? s : q)) > 1e-14)
            return 0;
    }
    return 1;
}

/* Sum of q~ (MIVL, delta 0) and smallest mean ratio over the star of v. */
static double star_sum(const mesh_topo *tp, const double *x, int32_t v, double *qmin)
{
    double f = 0.0;
    *qmin = INFINITY;
    for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
        const int32_t *tt = tp->tets + 4 * (size_t)(tp->vt_idx[k] >> 2);
        metric_parts pt;
        metric_parts_for(OPT_METRIC_MIVL, x + 3 * tt[0], x + 3 * tt[1], x + 3 * tt[2],
                         x + 3 * tt[3], &pt);
        f += metric_qt(OPT_METRIC_MIVL, &pt, 0.0);
        *qmin = fmin(*qmin, metric_mean_ratio(&pt));
    }
    return f;
}

/* In a broad sweep, a vertex sliding on a planar face whose star's smallest
 * mean ratio is at least 0.2 takes a Newton step in the face's plane: one
 * visit moves it further than the descent's two steps can (0.05 + 0.08 of
 * the mean edge), its star's sum drops. A star under 0.2 (the vertex above
 * it pushed down to a twentieth of the layer) takes the descent: it moves at
 * most those two steps, and its sum does not rise. Either way the vertex stays
 * on the plane. */
TEST(sliding_vertex_takes_a_tangent_newton_step_in_a_good_star)
{
    const int n = 4;
    const double h = 1.0 / n;
    for (int c = 0; c < 2; c++) {
        mesh_t *m = tm_grid(n, 0);
        mesh_topo *tp = NULL;
        slide_ctx *sl = NULL;
        int32_t v = 2 + (n + 1) * 2; /* (1/2, 1/2, 0): inside the face z = 0 */
        uint8_t *movable = calloc((size_t)m->nv, 1);
        double *eta = malloc((size_t)m->nt * sizeof(double));
        double p0[3], f0, f1, q0, q1, move = 0.0;
        finish_stats fs;
        ASSERT_TRUE(m && movable && eta);
        ASSERT_OK(mesh_topo_build(m, &tp, NULL));
        ASSERT_OK(slide_new(tp, m->xyz, 30.0, &sl, NULL));
        ASSERT_EQ_INT(slide_kind(sl, v), SLIDE_SURFACE);
        movable[v] = 1;
        if (c == 1) /* the vertex above v, fixed */
            m->xyz[3 * (v + (n + 1) * (n + 1)) + 2] = 0.05 * h;
        m->xyz[3 * v] += 0.25 * h;
        m->xyz[3 * v + 1] += 0.1 * h;
        memcpy(p0, m->xyz + 3 * v, sizeof p0);
        for (int32_t t = 0; t < m->nt; t++) {
            double smin;
            tet_values(m, t, &smin, &eta[t]);
            ASSERT_TRUE(eta[t] > 0.0);
        }
        f0 = star_sum(tp, m->xyz, v, &q0);
        ASSERT_TRUE(c == 0 ? q0 >= 0.2 : q0 < 0.2);
        ASSERT_OK(finish_sweep(tp, movable, sl, m->xyz, OPT_METRIC_MIVL, eta, 0.0, h, 1.0,
                               1e-3, 0, &fs));
        f1 = star_sum(tp, m->xyz, v, &q1);
        for (int k = 0; k < 3; k++)
            move += (m->xyz[3 * v + k] - p0[k]) * (m->xyz[3 * v + k] - p0[k]);
        move = sqrt(move);
        printf("  # star's worst %.3f -> %.3f, moved %.3f of an edge\n", q0, q1,
               move / h);
        ASSERT_TRUE(m->xyz[3 * v + 2] == 0.0); /* on the plane */
        if (c == 0) {
            ASSERT_TRUE(f1 < f0);
            ASSERT_TRUE(move > 0.15 * h);
        } else {
            ASSERT_TRUE(f1 <= f0);
            ASSERT_TRUE(move <= 0.13 * h + 1e-12);
        }
        slide_free(sl);
        mesh_topo_free(tp);
        free(eta);
        free(movable);
        mesh_free(m);
    }
}

TEST(angle_sweep_raises_the_smallest_angle_within_its_rules)
{
    grid_case g;
    double s0, q0, s1, q1;
    finish_stats fs;
    ASSERT_TRUE(grid_case_new(&g, 5, 0.3, 7));
    g.movable[1 + 6 * (1 + 6 * 1)] = 0; /* interior vertex (1,1,1) locked */
    worst_of(g.m, &s0, &q0);
    ASSERT_TRUE(s0 > 0.0);
    ASSERT_OK(finish_dihedral_sweep(g.tp, g.movable, NULL, g.m->xyz, 1.0 / g.n, 0.05, q0,
                                    g.val, 0, &fs));
    worst_of(g.m, &s1, &q1);
    ASSERT_TRUE(fs.n_moves > 0);
    ASSERT_NEAR(fs.floor_before, s0, 1e-12);
    ASSERT_NEAR(fs.floor_after, s1, 1e-12);
    ASSERT_TRUE(s1 > s0);  /* the smallest sine rose */
    ASSERT_TRUE(q1 >= q0); /* no tet fell below the mean-ratio floor */
    ASSERT_TRUE(fixed_kept(&g));
    ASSERT_TRUE(values_current(&g, 1)); /* the sines at the new x */
    grid_case_free(&g);
}

/* Deep stars (smallest sine under FINISH_DEEP_SINE) also take pattern moves:
 * on a grid whose worst tet is under half a degree, sweeps until the smallest
 * sine stays lift it well above the start and keep every rule (the mean-ratio
 * floor, positive tets, fixed vertices, the sines returned at the new x). */
TEST(deep_stars_lift_under_the_same_rules)
{
    grid_case g;
    double s0 = 1.0, q0 = 0.0, s1, q1;
    finish_stats fs;
    int sweeps = 0;
    unsigned seed;
    for (seed = 1; seed < 200; seed++) { /* the first valid grid with a deep tet */
        ASSERT_TRUE(grid_case_new(&g, 5, 0.45, seed));
        worst_of(g.m, &s0, &q0);
        if (s0 > 0.0 && s0 < 0.5 * FINISH_DEEP_SINE)
            break;
        grid_case_free(&g);
    }
    ASSERT_TRUE(seed < 200);
    do {
        ASSERT_OK(finish_dihedral_sweep(g.tp, g.movable, NULL, g.m->xyz, 1.0 / g.n, 0.05,
                                        q0, g.val, sweeps > 0, &fs));
    } while (fs.floor_after > fs.floor_before && ++sweeps < 200);
    worst_of(g.m, &s1, &q1);
    printf("  # seed %u: smallest dihedral sine %.4f -> %.4f after %d sweeps\n", seed, s0,
           s1, sweeps);
    ASSERT_TRUE(s1 > 2.0 * s0); /* well above the start */
    ASSERT_TRUE(q1 >= q0);      /* the mean-ratio floor holds */
    ASSERT_TRUE(fixed_kept(&g));
    ASSERT_TRUE(values_current(&g, 1));
    grid_case_free(&g);
}

/* After single-vertex sweeps stop raising the smallest sine, the joint moves
 * of the worst tets' corners raise it further, under the same rules. */
TEST(joint_moves_lift_what_single_vertices_leave)
{
    grid_case g;
    double s0, q0, s1, q1, s2, q2;
    finish_stats fs;
    int sweeps = 0;
    ASSERT_TRUE(grid_case_new(&g, 6, 0.3, 7));
    worst_of(g.m, &s0, &q0);
    ASSERT_TRUE(s0 > 0.0);
    do { /* single vertices until the smallest sine stays */
        ASSERT_OK(finish_dihedral_sweep(g.tp, g.movable, NULL, g.m->xyz, 1.0 / g.n, 0.05,
                                        q0, g.val, sweeps > 0, &fs));
    } while (fs.floor_after > fs.floor_before && ++sweeps < 50);
    worst_of(g.m, &s1, &q1);
    memcpy(g.x0, g.m->xyz, 3 * (size_t)g.m->nv * sizeof(double));
    ASSERT_OK(finish_patches(g.tp, g.movable, NULL, g.m->xyz, 1.0 / g.n,
                             FINISH_PATCH_ANGLES, q0, g.val, 0, &fs));
    worst_of(g.m, &s2, &q2);
    printf("  # smallest dihedral sine %.4f, single vertices %.4f, joint moves %.4f\n",
           s0, s1, s2);
    ASSERT_NEAR(fs.floor_before, s1, 1e-12);
    ASSERT_NEAR(fs.floor_after, s2, 1e-12);
    ASSERT_TRUE(fs.n_moves > 0);
    ASSERT_TRUE(s2 > s1);  /* what the sweeps could not lift */
    ASSERT_TRUE(q2 >= q0); /* the mean-ratio floor holds */
    ASSERT_TRUE(fixed_kept(&g));
    ASSERT_TRUE(values_current(&g, 1));
    grid_case_free(&g);
}

/* The max-min volume untangling (Freitag & Plassmann) on a tangled grid:
 * fewer inverted tets, the count it returns is the mesh's, the boundary
 * untouched, every coordinate finite. */
TEST(max_min_volume_untangles_a_grid)
{
    grid_case g;
    int32_t before, after = -1;
    ASSERT_TRUE(grid_case_new(&g, 6, 1.6, 5));
    before = mesh_count_inverted(g.tp, g.m->xyz);
    ASSERT_TRUE(before > 20);
    ASSERT_OK(
        finish_untangle(g.tp, g.movable, NULL, g.m->xyz, 1.0 / g.n, NULL, NULL, &after));
    printf("  # inverted tets %d -> %d\n", (int)before, (int)after);
    ASSERT_EQ_INT(after, mesh_count_inverted(g.tp, g.m->xyz));
    ASSERT_TRUE(after < before / 3);
    ASSERT_TRUE(fixed_kept(&g));
    ASSERT_TRUE(all_finite(g.m));
    grid_case_free(&g);
}

/* Untangling moves sliding boundary vertices too, along their face: two
 * neighbours on the face z = 0 of a 4^3 grid pushed across each other (in
 * the plane, each within its input star) fold the face's triangles and
 * invert tets that no interior vertex can open; with the slide constraints
 * the tangle goes, every boundary vertex still on its face plane and the
 * corners where they were. With the boundary held it stays. */
TEST(untangling_slides_boundary_vertices_on_their_faces)
{
    const int n = 4;
    const double h = 1.0 / n;
    int32_t v = 1 + (n + 1) * 2, before, held = -1, after = -1; /* (h, 2h, 0) */
    for (int c = 0; c < 2; c++) {
        mesh_t *m = tm_grid(n, 0);
        mesh_topo *tp = NULL;
        slide_ctx *sl = NULL;
        uint8_t *movable = calloc((size_t)m->nv, 1);
        double *x0 = malloc(3 * (size_t)m->nv * sizeof(double));
        ASSERT_TRUE(m && movable && x0);
        ASSERT_OK(mesh_topo_build(m, &tp, NULL));
        ASSERT_OK(slide_new(tp, m->xyz, 30.0, &sl, NULL));
        ASSERT_EQ_INT(slide_kind(sl, v), SLIDE_SURFACE);
        m->xyz[3 * v] += 0.6 * h;       /* v and its neighbour (2h, 2h, 0) */
        m->xyz[3 * (v + 1)] -= 0.6 * h; /* cross, each within its input star */
        memcpy(x0, m->xyz, 3 * (size_t)m->nv * sizeof(double));
        before = mesh_count_inverted(tp, m->xyz);
        ASSERT_TRUE(before > 0);
        for (int32_t w = 0; w < m->nv; w++)
            movable[w] = c == 1 ? slide_kind(sl, w) != SLIDE_CORNER
                                : !(tp->vflag[w] & MESH_V_BOUNDARY);
        ASSERT_OK(finish_untangle(tp, movable, c == 1 ? sl : NULL, m->xyz, h, NULL, NULL,
                                  c == 1 ? &after : &held));
        ASSERT_EQ_INT(c == 1 ? after : held, mesh_count_inverted(tp, m->xyz));
        for (int32_t w = 0; w < m->nv; w++) {
            const double *p = m->xyz + 3 * (size_t)w, *q = x0 + 3 * (size_t)w;
            ASSERT_TRUE(isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]));
            for (int k = 0; k < 3; k++) /* a face plane's coordinate is kept */
                if (q[k] == 0.0 || q[k] == 1.0)
                    ASSERT_TRUE(p[k] == q[k] || (tp->vflag[w] & MESH_V_BOUNDARY) == 0);
            if (slide_kind(sl, w) == SLIDE_CORNER || (c == 0 && !movable[w]))
                ASSERT_TRUE(p[0] == q[0] && p[1] == q[1] && p[2] == q[2]);
        }
        slide_free(sl);
        mesh_topo_free(tp);
        free(x0);
        free(movable);
        mesh_free(m);
    }
    printf("  # inverted tets %d -> %d with the boundary held, %d sliding\n", (int)before,
           (int)held, (int)after);
    ASSERT_TRUE(held > 0);
    ASSERT_EQ_INT(after, 0);
}

/* The same joint moves on the tets' mean ratios lift the worst of them; the
 * values kept up to date are the mean ratios at the new x. */
TEST(joint_moves_lift_the_worst_mean_ratio)
{
    grid_case g;
    double s0, q0, s1, q1;
    finish_stats fs;
    ASSERT_TRUE(grid_case_new(&g, 6, 0.3, 7));
    worst_of(g.m, &s0, &q0);
    ASSERT_OK(finish_patches(g.tp, g.movable, NULL, g.m->xyz, 1.0 / g.n,
                             FINISH_PATCH_MEAN_RATIO, 0.0, g.val, 0, &fs));
    worst_of(g.m, &s1, &q1);
    printf("  # worst mean ratio %.4f -> %.4f\n", q0, q1);
    ASSERT_NEAR(fs.floor_before, q0, 1e-12);
    ASSERT_NEAR(fs.floor_after, q1, 1e-12);
    ASSERT_TRUE(fs.n_moves > 0);
    ASSERT_TRUE(q1 > q0);
    ASSERT_TRUE(s1 > 0.0); /* nothing inverted */
    ASSERT_TRUE(fixed_kept(&g));
    ASSERT_TRUE(values_current(&g, 0));
    grid_case_free(&g);
}

TEST(angle_polish_option_keeps_every_guarantee)
{
    int n = 6;
    mesh_t *a = tm_grid(n, 0), *b = tm_grid(n, 0);
    opt_options o;
    opt_result ra, rb;
    report_quality qa, qb;
    tm_perturb(a, n, 0.35, 11);
    tm_perturb(b, n, 0.35, 11);
    opt_defaults(&o);
    o.angle_polish = 0;
    ASSERT_OK(opt_run(a, &o, &ra, NULL));
    o.angle_polish = 1;
    ASSERT_OK(opt_run(b, &o, &rb, NULL));
    qa = quality(a);
    qb = quality(b);
    ASSERT_TRUE(all_finite(b));
    ASSERT_EQ_INT(qb.n_inverted, 0);
    ASSERT_TRUE(qb.q_min >= qa.q_min);
    ASSERT_TRUE(fmin(qb.dih_min, 180.0 - qb.dih_max) >=
                fmin(qa.dih_min, 180.0 - qa.dih_max));
    ASSERT_NEAR(rb.after.dih_min, qb.dih_min, 1e-9);
    mesh_free(a);
    mesh_free(b);
}

/* grid_case_new with the cube's faces sliding (*sl) and every vertex but
 * the corners movable; 0 on failure. */
static int sliding_grid(grid_case *g, int n, double amp, unsigned seed, slide_ctx **sl)
{
    if (!grid_case_new(g, n, amp, seed) ||
        slide_new(g->tp, g->x0, 30.0, sl, NULL) != QDC_OK)
        return 0;
    for (int32_t v = 0; v < g->m->nv; v++)
        g->movable[v] = slide_kind(*sl, v) != SLIDE_CORNER;
    return 1;
}

/* 1 if x[0..n) has the bytes of the first x given (*ref, kept on the first
 * call; the caller frees it); 0 if not, or out of memory. */
static int same_as_first(double **ref, const double *x, size_t n)
{
    if (*ref)
        return memcmp(*ref, x, n * sizeof(double)) == 0;
    *ref = malloc(n * sizeof(double));
    if (*ref)
        memcpy(*ref, x, n * sizeof(double));
    return *ref != NULL;
}

/* The finishing sweeps move the vertices of one colour class at once (no two
 * share a tet: select.h), each reading only its own star, which no other
 * vertex of the class writes; the classes go in a fixed order. So the bytes
 * of the result do not depend on the thread count: broad and polish sweeps
 * (interior vertices by Newton, boundary ones sliding on the cube's faces)
 * and an angle sweep give the same coordinates at 1, 2 and 4 threads. */
TEST(finishing_sweeps_do_not_depend_on_the_thread_count)
{
    static const int threads[3] = {1, 2, 4};
    int saved = omp_get_max_threads();
    double *ref = NULL;

    for (int i = 0; i < 3; i++) {
        grid_case g;
        slide_ctx *sl = NULL;
        finish_stats fs;
        double s0, q0;
        int32_t moves = 0;
        size_t n3;
        ASSERT_TRUE(sliding_grid(&g, 7, 0.35, 11, &sl));
        n3 = 3 * (size_t)g.m->nv;
        omp_set_num_threads(threads[i]);
        for (int s = 0; s < 4; s++) {
            for (int32_t t = 0; t < g.m->nt; t++)
                tet_values(g.m, t, &s0, &g.val[t]);
            ASSERT_OK(finish_sweep(g.tp, g.movable, sl, g.m->xyz, OPT_METRIC_MIVL, g.val,
                                   0.0, 1.0 / g.n, s < 3 ? 1.0 : 0.01, s < 3 ? 1e-3 : 0.0,
                                   0, &fs));
            moves += fs.n_moves;
        }
        worst_of(g.m, &s0, &q0);
        ASSERT_OK(finish_dihedral_sweep(g.tp, g.movable, sl, g.m->xyz, 1.0 / g.n, 0.05,
                                        q0, g.val, 0, &fs));
        omp_set_num_threads(saved);
        printf("  # %d threads: %d moves in the sweeps, %d in the angle sweep\n",
               threads[i], (int)moves, (int)fs.n_moves);
        ASSERT_TRUE(moves > 100 && fs.n_moves > 0);
        ASSERT_TRUE(same_as_first(&ref, g.m->xyz, n3));
        slide_free(sl);
        grid_case_free(&g);
    }
    free(ref);
}

/* The untangling moves a colour class at once (select.h), each vertex
 * reading only its own star: a tangled grid, its boundary sliding on the
 * cube's faces, untangles to the same bytes at 1, 2 and 4 threads, with
 * fewer inverted tets than it had. */
TEST(untangling_does_not_depend_on_the_thread_count)
{
    static const int threads[3] = {1, 2, 4};
    int saved = omp_get_max_threads();
    double *ref = NULL;

    for (int i = 0; i < 3; i++) {
        grid_case g;
        slide_ctx *sl = NULL;
        int32_t before, after = -1;
        size_t n3;
        ASSERT_TRUE(sliding_grid(&g, 8, 1.6, 5, &sl));
        n3 = 3 * (size_t)g.m->nv;
        before = mesh_count_inverted(g.tp, g.m->xyz);
        omp_set_num_threads(threads[i]);
        ASSERT_OK(finish_untangle(g.tp, g.movable, sl, g.m->xyz, 1.0 / g.n, NULL, NULL,
                                  &after));
        omp_set_num_threads(saved);
        printf("  # %d threads: inverted tets %d -> %d\n", threads[i], (int)before,
               (int)after);
        ASSERT_EQ_INT(after, mesh_count_inverted(g.tp, g.m->xyz));
        ASSERT_TRUE(before > 20 && after < before / 3);
        ASSERT_TRUE(same_as_first(&ref, g.m->xyz, n3));
        slide_free(sl);
        grid_case_free(&g);
    }
    free(ref);
}

/* The objective's pass that also does the line search's scan
 * (encode_objective_scan): its sum and q~ per tet bit for bit
 * encode_objective's, its smallest mean ratio cubed and unusable count those
 * of a tet-by-tet check, on a tangled grid (delta > 0) and a valid one. */
TEST(objective_scan_matches_the_separate_passes)
{
    for (int k = 0; k < 2; k++) {
        grid_case g;
        double e3 = INFINITY, vmin = INFINITY, delta, f0, f1, *qt0, *qt1;
        int32_t nbad = 0;
        encode_scan sc;
        ASSERT_TRUE(grid_case_new(&g, 6, k ? 1.6 : 0.3, 5));
        for (int32_t t = 0; t < g.tp->nt; t++) {
            const int32_t *tt = g.tp->tets + 4 * (size_t)t;
            const double *x = g.m->xyz;
            metric_parts pt;
            metric_parts_for(OPT_METRIC_MIVL, x + 3 * tt[0], x + 3 * tt[1], x + 3 * tt[2],
                             x + 3 * tt[3], &pt);
            e3 = fmin(e3, metric_mean_ratio_cubed(&pt));
            vmin = fmin(vmin, pt.vol);
            nbad += geom_tet_bad(x, tt);
        }
        delta = metric_delta(vmin, metric_eps(OPT_METRIC_MIVL, 1.0 / g.n, 0.01));
        qt0 = malloc((size_t)g.tp->nt * sizeof(double));
        qt1 = malloc((size_t)g.tp->nt * sizeof(double));
        ASSERT_TRUE(qt0 && qt1);
        f0 = encode_objective(g.tp, g.m->xyz, OPT_METRIC_MIVL, delta, qt0, NULL);
        f1 = encode_objective_scan(g.tp, g.m->xyz, OPT_METRIC_MIVL, delta, qt1, &sc);
        printf("  # %s grid: delta %.3g, %d unusable, smallest mean ratio cubed %.4g\n",
               k ? "tangled" : "valid", delta, (int)sc.n_bad, sc.eta3_min);
        ASSERT_TRUE(isfinite(f0) && f0 == f1);
        ASSERT_TRUE(memcmp(qt0, qt1, (size_t)g.tp->nt * sizeof(double)) == 0);
        ASSERT_TRUE(sc.eta3_min == e3);
        ASSERT_EQ_INT(sc.n_bad, nbad);
        ASSERT_EQ_INT(sc.n_bad, mesh_count_inverted(g.tp, g.m->xyz));
        if (k)
            ASSERT_TRUE(delta > 0.0 && sc.n_bad > 20 && sc.eta3_min < 0.0);
        else
            ASSERT_TRUE(sc.n_bad == 0 && sc.eta3_min > 0.0);
        free(qt0);
        free(qt1);
        grid_case_free(&g);
    }
}

TEST_MAIN("opt", T(fixed_boundary_untangles_without_folding),
          T(result_does_not_depend_on_vertex_numbering),
          T(sliding_vertex_takes_a_tangent_newton_step_in_a_good_star),
          T(angle_sweep_raises_the_smallest_angle_within_its_rules),
          T(deep_stars_lift_under_the_same_rules),
          T(joint_moves_lift_what_single_vertices_leave),
          T(joint_moves_lift_the_worst_mean_ratio),
          T(angle_polish_option_keeps_every_guarantee), T(improves_perturbed_grid),
          T(untangles_inverted_grid), T(never_worse_than_input),
          T(literal_mode_is_safe_and_reported),
          T(fixed_boundary_and_user_locks_do_not_move),
          T(regions_and_connectivity_untouched), T(cancel_from_progress_callback),
          T(cancel_flag_before_start), T(time_limit_not_overrun_by_an_iteration),
          T(solvers_and_metrics_all_work), T(harmonic_guidance_runs),
          T(bad_options_and_bad_mesh_rejected), T(max_min_volume_untangles_a_grid),
          T(untangling_slides_boundary_vertices_on_their_faces),
          T(allocation_failures_are_clean),
          T(finishing_sweeps_do_not_depend_on_the_thread_count),
          T(untangling_does_not_depend_on_the_thread_count),
          T(objective_scan_matches_the_separate_passes))
