/* test_core.c - analytic checks of metrics, QDC encoding and the linear solvers. */
#include "core/mesh_int.h"
#include "core/order.h"
#include "core/tet.h"
#include "core/tri_edges.h"
#include "geom/metric_int.h"
#include "opt/encode.h"
#include "opt/solve.h"
#include "qdc.h"
#include "testlib.h"
#include "testmesh.h"

#include <math.h>
#include <string.h>

/* unit regular tet, positive orientation */
static const double REG[4][3] = {{0, 0, 0},
                                 {1, 0, 0},
                                 {0.5, 0.86602540378443865, 0},
                                 {0.5, 0.28867513459481288, 0.81649658092772603}};

TEST(regular_tet_metrics_are_one)
{
    metric_parts p;
    double ang[6];
    metric_parts_of(REG[0], REG[1], REG[2], REG[3], &p);
    ASSERT_NEAR(metric_qt(OPT_METRIC_MIMR, &p, 0), 1.0, 1e-12);
    ASSERT_NEAR(metric_qt(OPT_METRIC_MICN, &p, 0), 1.0, 1e-12);
    ASSERT_NEAR(metric_qt(OPT_METRIC_MIVL, &p, 0), 1.0, 1e-12);
    ASSERT_NEAR(metric_mean_ratio(&p), 1.0, 1e-12);
    ASSERT_NEAR(metric_vol_length(&p), 1.0, 1e-12);
    ASSERT_NEAR(p.vol, 1.0 / (6.0 * sqrt(2.0)), 1e-14);
    metric_dihedrals(REG[0], REG[1], REG[2], REG[3], ang);
    for (int e = 0; e < 6; e++)
        ASSERT_NEAR(ang[e], acos(1.0 / 3.0) * 180.0 / 3.14159265358979323846, 1e-9);
}

TEST(scaled_regular_tet_is_still_one)
{
    double s[4][3];
    metric_parts p;
    for (int a = 0; a < 4; a++)
        for (int k = 0; k < 3; k++)
            s[a][k] = 7.5 * REG[a][k] + 3.0;
    metric_parts_of(s[0], s[1], s[2], s[3], &p);
    ASSERT_NEAR(metric_qt(OPT_METRIC_MIMR, &p, 0), 1.0, 1e-12);
    ASSERT_NEAR(metric_qt(OPT_METRIC_MICN, &p, 0), 1.0, 1e-12);
    ASSERT_NEAR(metric_qt(OPT_METRIC_MIVL, &p, 0), 1.0, 1e-12);
}

TEST(mivl_is_mimr_to_three_halves)
{
    double t[4][3] = {{0, 0, 0}, {1, 0.1, 0}, {0.2, 0.7, 0.1}, {0.3, 0.2, 0.4}};
    metric_parts p;
    metric_parts_of(t[0], t[1], t[2], t[3], &p);
    ASSERT_NEAR(metric_qt(OPT_METRIC_MIVL, &p, 0),
                pow(metric_qt(OPT_METRIC_MIMR, &p, 0), 1.5), 1e-12);
}

TEST(inverted_tet_negative_mean_ratio_and_infinite_qt)
{
    metric_parts p;
    metric_parts_of(REG[0], REG[2], REG[1], REG[3], &p);
    ASSERT_NEAR(metric_mean_ratio(&p), -1.0, 1e-12);
    ASSERT_TRUE(isinf(metric_qt(OPT_METRIC_MIVL, &p, 0)));
    ASSERT_TRUE(isfinite(metric_qt(OPT_METRIC_MIVL, &p, 1e-3)));
}

TEST(h_is_continuous_and_regularizes)
{
    double d = 0.01;
    ASSERT_NEAR(metric_h(0, d), d, 1e-15);
    ASSERT_NEAR(metric_h(1e-9, d) - metric_h(-1e-9, d), 1e-9, 1e-12);
    ASSERT_NEAR(metric_h(100, d), 100, 1e-5);
    ASSERT_TRUE(metric_h(-100, d) > 0);
    ASSERT_NEAR(metric_h(-0.3, 0), -0.3, 0);
    /* delta rule of Escobar: delta = sqrt(eps (eps - smin)) below eps, else 0 */
    ASSERT_NEAR(metric_delta(0.5, 0.1), 0.0, 0);
    ASSERT_NEAR(metric_delta(-0.3, 0.1), sqrt(0.1 * 0.4), 1e-15);
}

/* closed-form alpha* (docs/method.md §3) against a brute-force 1D search of q~ */
TEST(alpha_closed_form_matches_search)
{
    double f[3][3] = {{0.1, 0.0, 0.0}, {1.2, 0.2, 0.1}, {0.3, 0.9, -0.1}};
    double e1[3], e2[3], n[3], pc[3], len;
    for (int k = 0; k < 3; k++) {
        e1[k] = f[1][k] - f[0][k];
        e2[k] = f[2][k] - f[0][k];
        pc[k] = (f[0][k] + f[1][k] + f[2][k]) / 3;
    }
    n[0] = -(e1[1] * e2[2] - e1[2] * e2[1]);
    n[1] = -(e1[2] * e2[0] - e1[0] * e2[2]);
    n[2] = -(e1[0] * e2[1] - e1[1] * e2[0]);
    len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; k++)
        n[k] /= len;
    for (int mm = 0; mm < 3; mm++) {
        opt_metric m = (opt_metric)mm;
        double best = INFINITY, abest = 0, a = metric_alpha_opt(m, f[0], f[1], f[2]);
        for (int i = 1; i <= 200000; i++) {
            double al = 3.0 * i / 200000, p[3];
            metric_parts pt;
            for (int k = 0; k < 3; k++)
                p[k] = pc[k] + al * n[k];
            /* tet (p, f0, f1, f2) is positive with p on the inward side */
            metric_parts_of(p, f[0], f[1], f[2], &pt);
            double q = metric_qt(m, &pt, 0);
            if (q < best) {
                best = q;
                abest = al;
            }
        }
        ASSERT_NEAR(a, abest, 2e-5);
    }
}

TEST(gradient_matches_finite_differences)
{
    double t[4][3] = {{0, 0, 0}, {1, 0.1, 0}, {0.2, 0.7, 0.1}, {0.3, 0.2, 0.4}};
    for (int mm = 0; mm < 3; mm++)
        for (int a = 0; a < 4; a++)
            for (int dl = 0; dl < 2; dl++) {
                double delta = dl ? 0.02 : 0.0, g[3], h = 1e-6;
                metric_qt_grad((opt_metric)mm, &t[0][0], a, delta, g, NULL);
                for (int k = 0; k < 3; k++) {
                    double tp[4][3], tm[4][3], qp, qm;
                    metric_parts pp, pm;
                    memcpy(tp, t, sizeof t);
                    memcpy(tm, t, sizeof t);
                    tp[a][k] += h;
                    tm[a][k] -= h;
                    metric_parts_of(tp[0], tp[1], tp[2], tp[3], &pp);
                    metric_parts_of(tm[0], tm[1], tm[2], tm[3], &pm);
                    qp = metric_qt((opt_metric)mm, &pp, delta);
                    qm = metric_qt((opt_metric)mm, &pm, delta);
                    ASSERT_NEAR(g[k], (qp - qm) / (2 * h), 1e-5 * (1 + fabs(g[k])));
                }
            }
}

TEST(hessian_matches_finite_differences_of_the_gradient)
{
    double t[4][3] = {{0, 0, 0}, {1, 0.1, 0}, {0.2, 0.7, 0.1}, {0.3, 0.2, 0.4}};
    static const int ij[6][2] = {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}};
    for (int mm = 0; mm < 2; mm++) /* MIVL, MIMR */
        for (int a = 0; a < 4; a++)
            for (int dl = 0; dl < 3; dl++) {
                /* delta 0, moderate, and large enough to matter (vol ~ 0.06) */
                double delta = dl == 0 ? 0.0 : (dl == 1 ? 0.02 : 0.2), g[3], H[6],
                       h = 1e-6;
                double q = metric_qt_hess((opt_metric)mm, &t[0][0], a, delta, g, H, NULL);
                double g0[3];
                ASSERT_NEAR(q,
                            metric_qt_grad((opt_metric)mm, &t[0][0], a, delta, g0, NULL),
                            1e-14);
                for (int k = 0; k < 3; k++)
                    ASSERT_NEAR(g[k], g0[k], 1e-12 * (1 + fabs(g0[k])));
                for (int e = 0; e < 6; e++) {
                    int i = ij[e][0], j = ij[e][1];
                    double tp[4][3], tm[4][3], gp[3], gm[3];
                    memcpy(tp, t, sizeof t);
                    memcpy(tm, t, sizeof t);
                    tp[a][j] += h;
                    tm[a][j] -= h;
                    metric_qt_grad((opt_metric)mm, &tp[0][0], a, delta, gp, NULL);
                    metric_qt_grad((opt_metric)mm, &tm[0][0], a, delta, gm, NULL);
                    ASSERT_NEAR(H[e], (gp[i] - gm[i]) / (2 * h), 1e-5 * (1 + fabs(H[e])));
                }
            }
    {
        double g[3], H[6];
        ASSERT_TRUE(isnan(metric_qt_hess(OPT_METRIC_MICN, &t[0][0], 0, 0.0, g, H, NULL)));
    }
}

/* A face set once (metric_face_set) and its apex moved: the same bits as
 * metric_qt_hess_face, value, gradient, Hessian and the volume and edge
 * sum; 1 and a zero gradient at the apex of the regular tet on the face. */
TEST(face_set_once_gives_the_same_bits)
{
    const double s3 = sqrt(3.0);
    double f[3][3] = {{0, 0, 0}, {1, 0, 0}, {0.5, s3 / 2, 0}};
    double apex[3] = {0.5, s3 / 6, -sqrt(2.0 / 3.0)}; /* tet_face_of: apex below */
    metric_face mf;
    double g[3], H[6], vl[2];

    metric_face_set(f[0], f[1], f[2], &mf);
    for (int mm = 0; mm < 2; mm++) {
        ASSERT_NEAR(metric_qt_hess_at((opt_metric)mm, apex, &mf, 0.0, g, H, vl), 1.0,
                    1e-14);
        for (int k = 0; k < 3; k++)
            ASSERT_NEAR(g[k], 0.0, 1e-14);
        ASSERT_NEAR(vl[0], sqrt(2.0) / 12, 1e-15); /* the unit regular tet */
        ASSERT_NEAR(vl[1], 6.0, 1e-14);
    }
    for (int trial = 0; trial < 200; trial++) {
        double p[3], g1[3], H1[6], vl1[2], g2[3], H2[6], vl2[2], q1, q2;
        for (int k = 0; k < 3; k++)
            p[k] = apex[k] + 0.4 * sin(7.1 * trial + 2.3 * k);
        f[2][0] = 0.5 + 0.1 * cos(3.3 * trial);
        metric_face_set(f[0], f[1], f[2], &mf);
        for (int mm = 0; mm < 2; mm++)
            for (int dl = 0; dl < 2; dl++) {
                double delta = dl ? 0.05 : 0.0;
                int grad = trial % 3 != 0;
                q1 = metric_qt_hess_face((opt_metric)mm, p, f[0], f[1], f[2], delta,
                                         grad ? g1 : NULL, H1, vl1);
                q2 = metric_qt_hess_at((opt_metric)mm, p, &mf, delta, grad ? g2 : NULL,
                                       H2, vl2);
                ASSERT_TRUE(memcmp(&q1, &q2, sizeof q1) == 0);
                ASSERT_TRUE(memcmp(vl1, vl2, sizeof vl1) == 0);
                if (grad && isfinite(q1)) {
                    ASSERT_TRUE(memcmp(g1, g2, sizeof g1) == 0);
                    ASSERT_TRUE(memcmp(H1, H2, sizeof H1) == 0);
                }
            }
    }
    ASSERT_TRUE(isnan(metric_qt_hess_at(OPT_METRIC_MICN, apex, &mf, 0.0, g, H, vl)));
}

/* a regular tet split at its centroid: 4 congruent tets around vertex 4 */
static mesh_t *star_mesh(void)
{
    mesh_t *m = mesh_new(5, 4, 0);
    static const int32_t tets[4][4] = {
        {4, 1, 2, 3}, {0, 4, 2, 3}, {0, 1, 4, 3}, {0, 1, 2, 4}};
    for (int a = 0; a < 4; a++)
        for (int k = 0; k < 3; k++) {
            m->xyz[3 * a + k] = REG[a][k];
            m->xyz[12 + k] += REG[a][k] / 4;
        }
    memcpy(m->tets, tets, sizeof tets);
    return m;
}

TEST(qdc_of_symmetric_star)
{
    mesh_t *m = star_mesh();
    mesh_topo *tp = NULL;
    double qt[4], *qval, d[15];
    ASSERT_OK(mesh_topo_build(m, &tp, NULL));
    ASSERT_EQ_INT(tp->nb, 4);
    ASSERT_EQ_INT(tp->nbf, 4);
    qval = calloc((size_t)tp->adj_ptr[5], sizeof(double));
    encode_objective(tp, m->xyz, OPT_METRIC_MIVL, 0, qt, NULL);
    encode_optavg(tp, m->xyz, OPT_METRIC_MIVL, qt, NULL, qval, d);
    /* centre row: 1 on the diagonal, -1/4 on each corner (3 faces x 1/4 x 1/3) */
    for (int32_t s = tp->adj_ptr[4]; s < tp->adj_ptr[5]; s++)
        ASSERT_NEAR(qval[s], tp->adj_idx[s] == 4 ? 1.0 : -0.25, 1e-14);
    /* the inward normals of the 4 faces cancel: d = 0 */
    for (int k = 0; k < 3; k++)
        ASSERT_NEAR(d[12 + k], 0.0, 1e-14);
    /* every row sums to 0 (weights sum to 1) for both weightings */
    for (int w = 0; w < 2; w++) {
        if (w)
            encode_paper(tp, m->xyz, OPT_METRIC_MIVL, qt, qval, d);
        for (int32_t i = 0; i < 5; i++) {
            double sum = 0;
            for (int32_t s = tp->adj_ptr[i]; s < tp->adj_ptr[i + 1]; s++)
                sum += qval[s];
            ASSERT_NEAR(sum, 0.0, 1e-13);
        }
    }
    free(qval);
    mesh_topo_free(tp);
    mesh_free(m);
}

TEST(optavg_weights_sum_to_one_on_random_mesh)
{
    int n = 4;
    mesh_t *m = tm_grid(n, 0);
    mesh_topo *tp = NULL;
    double *qt, *qval, *d;
    tm_perturb(m, n, 0.3, 7);
    ASSERT_OK(mesh_topo_build(m, &tp, NULL));
    qt = malloc(sizeof(double) * (size_t)m->nt);
    qval = malloc(sizeof(double) * (size_t)tp->adj_ptr[m->nv]);
    d = malloc(sizeof(double) * 3 * (size_t)m->nv);
    encode_objective(tp, m->xyz, OPT_METRIC_MIVL, 0, qt, NULL);
    encode_optavg(tp, m->xyz, OPT_METRIC_MIVL, qt, NULL, qval, d);
    for (int32_t i = 0; i < m->nv; i++) {
        double sum = 0;
        for (int32_t s = tp->adj_ptr[i]; s < tp->adj_ptr[i + 1]; s++) {
            sum += qval[s];
            if (tp->adj_idx[s] != i)
                ASSERT_TRUE(qval[s] <= 0);
        }
        ASSERT_NEAR(sum, 0.0, 1e-13);
    }
    /* the precomputed slots name the entries the search finds: every slot of
     * each star entry's face is that face vertex's, and the rows come out
     * bit for bit the same */
    {
        uint8_t *fs = encode_face_slots(tp);
        double *qv2 = malloc(sizeof(double) * (size_t)tp->adj_ptr[m->nv]);
        double *d2 = malloc(sizeof(double) * 3 * (size_t)m->nv);
        ASSERT_TRUE(fs && qv2 && d2);
        for (int32_t i = 0; i < m->nv; i++)
            for (int32_t k = tp->vt_ptr[i]; k < tp->vt_ptr[i + 1]; k++)
                for (int f = 0; f < 3; f++) {
                    int32_t t = tp->vt_idx[k] >> 2, a = tp->vt_idx[k] & 3;
                    int32_t j = tp->tets[4 * (size_t)t + tet_face_of[a][f]];
                    ASSERT_TRUE(fs[3 * (size_t)k + f] < 255);
                    ASSERT_EQ_INT(tp->adj_idx[tp->adj_ptr[i] + fs[3 * (size_t)k + f]], j);
                }
        encode_optavg(tp, m->xyz, OPT_METRIC_MIVL, qt, fs, qv2, d2);
        ASSERT_TRUE(!memcmp(qv2, qval, sizeof(double) * (size_t)tp->adj_ptr[m->nv]));
        ASSERT_TRUE(!memcmp(d2, d, sizeof(double) * 3 * (size_t)m->nv));
        qdc_free(fs);
        free(qv2);
        free(d2);
    }
    free(qt);
    free(qval);
    free(d);
    mesh_topo_free(tp);
    mesh_free(m);
}

/* Dense reference: A = Q_F^T W Q_F + diag(dg) solved by Gaussian elimination. */
static void dense_solve(const mesh_topo *tp, const uint8_t *locked, const double *qval,
                        const double *w2, const double *dg, const double *b, double *x)
{
    int n = tp->nv;
    double *A = calloc((size_t)n * n, sizeof(double)),
           *B = malloc(sizeof(double) * 3 * n);
    for (int i = 0; i < n; i++)
        for (int32_t s1 = tp->adj_ptr[i]; s1 < tp->adj_ptr[i + 1]; s1++)
            for (int32_t s2 = tp->adj_ptr[i]; s2 < tp->adj_ptr[i + 1]; s2++)
                A[(size_t)tp->adj_idx[s1] * n + tp->adj_idx[s2]] +=
                    w2[i] * qval[s1] * qval[s2];
    for (int i = 0; i < n; i++) {
        A[(size_t)i * n + i] += dg[i];
        for (int k = 0; k < 3; k++)
            B[3 * i + k] = b[3 * i + k];
        if (locked[i]) { /* identity row: x_i = 0 (caller moved locked terms to b) */
            for (int j = 0; j < n; j++)
                A[(size_t)i * n + j] = A[(size_t)j * n + i] = 0;
            A[(size_t)i * n + i] = 1;
            B[3 * i] = B[3 * i + 1] = B[3 * i + 2] = 0;
        }
    }
    for (int c = 0; c < n; c++) {
        for (int r = c + 1; r < n; r++) {
            double f = A[(size_t)r * n + c] / A[(size_t)c * n + c];
            for (int j = c; j < n; j++)
                A[(size_t)r * n + j] -= f * A[(size_t)c * n + j];
            for (int k = 0; k < 3; k++)
                B[3 * r + k] -= f * B[3 * c + k];
        }
    }
    for (int r = n - 1; r >= 0; r--)
        for (int k = 0; k < 3; k++) {
            double s = B[3 * r + k];
            for (int j = r + 1; j < n; j++)
                s -= A[(size_t)r * n + j] * x[3 * j + k];
            x[3 * r + k] = s / A[(size_t)r * n + r];
        }
    free(A);
    free(B);
}

TEST(cholmod_and_pcg_agree_with_dense)
{
    int n = 3;
    mesh_t *m = tm_grid(n, 0);
    mesh_topo *tp = NULL;
    uint64_t seed = 99;
    int32_t nv = m->nv;
    double *qt, *qval, *d, *w2, *dg, *b, *xd, *xc, *xp;
    uint8_t *locked;
    solve_ctx *sc = NULL, *sp = NULL;
    int it;
    tm_perturb(m, n, 0.3, 3);
    ASSERT_OK(mesh_topo_build(m, &tp, NULL));
    qt = malloc(sizeof(double) * (size_t)m->nt);
    qval = malloc(sizeof(double) * (size_t)tp->adj_ptr[nv]);
    d = malloc(sizeof(double) * 3 * nv);
    w2 = malloc(sizeof(double) * nv);
    dg = malloc(sizeof(double) * nv);
    b = malloc(sizeof(double) * 3 * nv);
    xd = calloc(3 * (size_t)nv, sizeof(double));
    xc = calloc(3 * (size_t)nv, sizeof(double));
    xp = calloc(3 * (size_t)nv, sizeof(double));
    locked = calloc((size_t)nv, 1);
    encode_objective(tp, m->xyz, OPT_METRIC_MIVL, 0, qt, NULL);
    encode_optavg(tp, m->xyz, OPT_METRIC_MIVL, qt, NULL, qval, d);
    for (int32_t i = 0; i < nv; i++) {
        w2[i] = 1.0 + 0.5 * tm_rand(&seed);
        dg[i] = 1.0 + ((tp->vflag[i] & MESH_V_BOUNDARY) ? 1.0 : 0.0);
        locked[i] = i % 7 == 0;
        for (int k = 0; k < 3; k++)
            b[3 * i + k] = tm_rand(&seed);
    }
    dense_solve(tp, locked, qval, w2, dg, b, xd);
    ASSERT_OK(solve_new(tp, locked, OPT_SOLVER_CHOLMOD, &sc, NULL));
    ASSERT_EQ_INT(solve_kind(sc), OPT_SOLVER_CHOLMOD);
    ASSERT_TRUE(solve_flops(sc) > 0);
    ASSERT_OK(solve_system(sc, qval, w2, dg, b, xc, &it, NULL));
    ASSERT_OK(solve_new(tp, locked, OPT_SOLVER_PCG, &sp, NULL));
    ASSERT_EQ_INT(solve_kind(sp), OPT_SOLVER_PCG);
    ASSERT_OK(solve_system(sp, qval, w2, dg, b, xp, &it, NULL));
    ASSERT_TRUE(it > 0);
    for (int32_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) {
            if (locked[i])
                continue;
            ASSERT_NEAR(xc[3 * i + k], xd[3 * i + k], 1e-9);
            ASSERT_NEAR(xp[3 * i + k], xd[3 * i + k], 1e-7);
        }
    solve_free(sc);
    solve_free(sp);
    free(qt);
    free(qval);
    free(d);
    free(w2);
    free(dg);
    free(b);
    free(xd);
    free(xc);
    free(xp);
    free(locked);
    mesh_topo_free(tp);
    mesh_free(m);
}

TEST(topology_of_grid)
{
    int n = 3;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION);
    mesh_topo *tp = NULL;
    mesh_check c;
    ASSERT_OK(mesh_validate(m, &c, NULL));
    ASSERT_EQ_INT(c.n_inverted, 0);
    ASSERT_EQ_INT(c.n_unreferenced, 0);
    ASSERT_OK(mesh_topo_build(m, &tp, NULL));
    /* boundary: 6 faces x n^2 squares x 2 triangles; boundary vertices (n+1)^3-(n-1)^3 */
    ASSERT_EQ_INT(tp->nbf, 12 * n * n);
    ASSERT_EQ_INT(tp->nb, (n + 1) * (n + 1) * (n + 1) - (n - 1) * (n - 1) * (n - 1));
    ASSERT_EQ_INT(tp->flipped, 0);
    /* the region interface x = 1/3 is a plane of n^2 squares */
    ASSERT_EQ_INT(tp->nif, 2 * n * n);
    mesh_topo_free(tp);
    mesh_free(m);
}

TEST(topology_does_not_depend_on_vertex_order)
{
    /* every one of the 24 orders of each tet (odd ones flip it; the
     * connectivity's orientation puts it back): the same canonical tets,
     * boundary faces and neighbours, so the optimizer sees one mesh */
    int n = 3;
    mesh_t *m = tm_grid(n, 0), *p = tm_grid(n, 0);
    mesh_topo *a = NULL, *b = NULL;
    static const int perm[24][4] = {
        {0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 1, 3}, {0, 2, 3, 1}, {0, 3, 1, 2},
        {0, 3, 2, 1}, {1, 0, 2, 3}, {1, 0, 3, 2}, {1, 2, 0, 3}, {1, 2, 3, 0},
        {1, 3, 0, 2}, {1, 3, 2, 0}, {2, 0, 1, 3}, {2, 0, 3, 1}, {2, 1, 0, 3},
        {2, 1, 3, 0}, {2, 3, 0, 1}, {2, 3, 1, 0}, {3, 0, 1, 2}, {3, 0, 2, 1},
        {3, 1, 0, 2}, {3, 1, 2, 0}, {3, 2, 0, 1}, {3, 2, 1, 0}};
    for (int32_t t = 0; t < p->nt; t++)
        for (int c = 0; c < 4; c++)
            p->tets[4 * (size_t)t + c] = m->tets[4 * (size_t)t + perm[t % 24][c]];
    ASSERT_OK(mesh_topo_build(m, &a, NULL));
    ASSERT_OK(mesh_topo_build(p, &b, NULL));
    ASSERT_TRUE(b->flipped);
    ASSERT_EQ_INT(b->orientation.inverted, 0);
    ASSERT_TRUE(memcmp(a->tets, b->tets, 16 * (size_t)m->nt) == 0);
    ASSERT_EQ_INT(a->nbf, b->nbf);
    ASSERT_TRUE(memcmp(a->bfaces, b->bfaces, 12 * (size_t)a->nbf) == 0);
    ASSERT_TRUE(memcmp(a->vt_idx, b->vt_idx, 16 * (size_t)m->nt) == 0);
    /* canonical: the smallest vertex first, then the smallest of the others,
     * and every tet positive */
    for (int32_t t = 0; t < m->nt; t++) {
        const int32_t *tt = b->tets + 4 * (size_t)t;
        ASSERT_TRUE(tt[0] < tt[1] && tt[1] < tt[2] && tt[1] < tt[3]);
        ASSERT_TRUE(geom_tet_vol6(m->xyz, tt) > 0);
    }
    mesh_topo_free(a);
    mesh_topo_free(b);
    mesh_free(m);
    mesh_free(p);
}

/* The corners of a 2x2x2 grid, numbered at random: the Morton curve puts
 * (i, j, k) at i + 2 j + 4 k (x in the lowest bit); tets come by their lowest
 * new vertex; the renumbered copy holds the same tets and coordinates. */
TEST(spatial_order_is_the_morton_curve)
{
    mesh_t *m = tm_grid(1, MESH_WITH_REGION | MESH_WITH_FIXED), *p;
    static const int32_t shuffle[8] = {5, 2, 7, 0, 3, 6, 1, 4};
    mesh_order o;
    double *xyz = malloc(24 * sizeof(double));
    int32_t *tets = malloc(24 * sizeof(int32_t));
    int32_t seen[8] = {0}, tseen[6] = {0}, lo_prev = -1;

    ASSERT_TRUE(xyz && tets);
    memcpy(xyz, m->xyz, 24 * sizeof(double));
    memcpy(tets, m->tets, 24 * sizeof(int32_t));
    for (int32_t v = 0; v < 8; v++)
        memcpy(m->xyz + 3 * shuffle[v], xyz + 3 * v, 3 * sizeof(double));
    for (int32_t i = 0; i < 24; i++)
        m->tets[i] = shuffle[tets[i]];
    for (int32_t t = 0; t < 6; t++)
        m->region[t] = 10 + t;
    m->fixed[shuffle[7]] = 1;
    ASSERT_OK(mesh_order_build(m, &o));
    for (int32_t v = 0; v < 8; v++) {
        const double *x = m->xyz + 3 * v;
        ASSERT_EQ_INT(o.vnew[v], (int)(x[0] + 2 * x[1] + 4 * x[2]));
        seen[o.vnew[v]]++;
    }
    for (int32_t t = 0; t < 6; t++)
        tseen[o.told[t]]++;
    for (int i = 0; i < 8; i++)
        ASSERT_EQ_INT(seen[i], 1);
    for (int i = 0; i < 6; i++)
        ASSERT_EQ_INT(tseen[i], 1);
    p = mesh_order_apply(m, &o);
    ASSERT_TRUE(p != NULL);
    ASSERT_EQ_INT(p->fixed[7], 1); /* the corner (1, 1, 1) */
    for (int32_t t = 0; t < 6; t++) {
        int32_t s = o.told[t], lo = 8;
        for (int a = 0; a < 4; a++) {
            int32_t w = p->tets[4 * t + a];
            ASSERT_EQ_INT(w, o.vnew[m->tets[4 * s + a]]);
            ASSERT_TRUE(memcmp(p->xyz + 3 * w, m->xyz + 3 * m->tets[4 * s + a],
                               3 * sizeof(double)) == 0);
            lo = w < lo ? w : lo;
        }
        ASSERT_TRUE(lo >= lo_prev);
        lo_prev = lo;
        ASSERT_EQ_INT(p->region[t], m->region[s]);
    }
    /* back into the caller's numbering */
    for (int i = 0; i < 24; i++)
        p->xyz[i] += 1.0;
    memcpy(xyz, m->xyz, 24 * sizeof(double));
    mesh_order_restore_xyz(&o, p, m);
    for (int i = 0; i < 24; i++)
        ASSERT_NEAR(m->xyz[i], xyz[i] + 1.0, 0.0);
    /* the same copy with the connectivity moved, and back as it was */
    {
        mesh_t *q;
        int32_t tets0[24], region0[6];
        memcpy(tets0, m->tets, sizeof tets0);
        memcpy(region0, m->region, sizeof region0);
        q = mesh_order_take(m, &o);
        ASSERT_TRUE(q != NULL);
        ASSERT_TRUE(m->tets == NULL && m->region == NULL);
        ASSERT_TRUE(memcmp(q->tets, p->tets, sizeof tets0) == 0);
        ASSERT_TRUE(memcmp(q->region, p->region, sizeof region0) == 0);
        for (int32_t v = 0; v < 8; v++)
            ASSERT_EQ_INT(o.vold[o.vnew[v]], v);
        mesh_order_give_back(&o, q, m);
        ASSERT_TRUE(q->tets == NULL && q->region == NULL);
        ASSERT_TRUE(memcmp(m->tets, tets0, sizeof tets0) == 0);
        ASSERT_TRUE(memcmp(m->region, region0, sizeof region0) == 0);
        mesh_free(q);
    }
    /* an index out of range is refused, a non-finite coordinate is not a crash */
    m->xyz[4] = NAN;
    mesh_order_free(&o);
    ASSERT_OK(mesh_order_build(m, &o));
    mesh_order_free(&o);
    m->tets[5] = 8;
    ASSERT_EQ_INT(mesh_order_build(m, &o), QDC_EINVAL);
    mesh_free(p);
    mesh_free(m);
    free(xyz);
    free(tets);
}

TEST(swap_tets_exchanges_tets_regions_and_counts)
{
    mesh_t *a = mesh_new(5, 1, MESH_WITH_REGION), *b = mesh_new(5, 2, 0);
    ASSERT_TRUE(a && b);
    int32_t *ta = a->tets, *tb = b->tets, *ra = a->region;
    double *xa = a->xyz;
    mesh_swap_tets(a, b);
    ASSERT_EQ_INT(a->nt, 2);
    ASSERT_EQ_INT(b->nt, 1);
    ASSERT_TRUE(a->tets == tb && b->tets == ta);
    ASSERT_TRUE(a->region == NULL && b->region == ra);
    ASSERT_TRUE(a->xyz == xa && a->nv == 5);
    mesh_free(a);
    mesh_free(b);
}

TEST(validation_errors)
{
    mesh_t *m = tm_grid(2, 0);
    qdc_error e;
    qdc_error_clear(&e);
    m->tets[4 * 5 + 2] = m->nv;
    ASSERT_EQ_INT(mesh_validate(m, NULL, &e), QDC_EMESH);
    ASSERT_EQ_INT(e.index, 5);
    ASSERT_TRUE(strstr(e.msg, "out of range") != NULL);
    m->tets[4 * 5 + 2] = m->tets[4 * 5 + 1];
    ASSERT_EQ_INT(mesh_validate(m, NULL, &e), QDC_EMESH);
    ASSERT_TRUE(strstr(e.msg, "repeats") != NULL);
    mesh_free(m);
    m = tm_grid(2, 0);
    m->xyz[7] = NAN;
    ASSERT_EQ_INT(mesh_validate(m, NULL, &e), QDC_EMESH);
    ASSERT_EQ_INT(e.index, 2);
    mesh_free(m);
    m = mesh_new(0, 0, 0);
    ASSERT_EQ_INT(mesh_validate(m, NULL, &e), QDC_EMESH);
    ASSERT_TRUE(strstr(e.msg, "empty") != NULL);
    mesh_free(m);
    /* a face shared by three tets */
    m = star_mesh();
    {
        mesh_t *b = mesh_new(6, 5, 0);
        memcpy(b->xyz, m->xyz, 15 * sizeof(double));
        b->xyz[15] = 0.5;
        b->xyz[16] = 0.3;
        b->xyz[17] = -0.5;
        memcpy(b->tets, m->tets, 16 * sizeof(int32_t));
        b->tets[16] = 4; /* tet (4, 1, 2, 5) shares face (1,2,4) with tets 0 and 3 */
        b->tets[17] = 1;
        b->tets[18] = 2;
        b->tets[19] = 5;
        ASSERT_EQ_INT(mesh_validate(b, NULL, &e), QDC_EMESH);
        ASSERT_TRUE(strstr(e.msg, "non-manifold") != NULL);
        mesh_free(b);
    }
    mesh_free(m);
    /* a tet given twice inside the mesh: the star numbered from its centre (0),
     * so that the first faces matched are inner ones, each of three tets (the
     * tet, its twin, the neighbour): said as the duplicate, not as a face of
     * three tets */
    {
        static const int32_t tets[5][4] = {
            {0, 2, 3, 4}, {1, 0, 3, 4}, {1, 2, 0, 4}, {1, 2, 3, 0}, {4, 3, 2, 0}};
        m = mesh_new(5, 5, 0);
        for (int a = 0; a < 4; a++)
            for (int k = 0; k < 3; k++) {
                m->xyz[3 * (a + 1) + k] = REG[a][k];
                m->xyz[k] += REG[a][k] / 4;
            }
        memcpy(m->tets, tets, sizeof tets);
        ASSERT_EQ_INT(mesh_validate(m, NULL, &e), QDC_EMESH);
        ASSERT_TRUE(strstr(e.msg, "tets 0 and 4 have the same four vertices") != NULL);
        ASSERT_EQ_INT(e.index, 4);
        mesh_free(m);
    }
}

TEST(dihedral_sines_are_the_sines_of_the_angles)
{
    /* regular tet: every angle is acos(1/3), sine 2 sqrt2 / 3 */
    double s[6], ang[6],
        t[4][3] = {{0, 0, 0}, {1, 0.1, 0}, {0.2, 0.7, 0.1}, {0.3, 0.2, 0.4}};
    metric_dihedral_sines(REG[0], REG[1], REG[2], REG[3], s);
    for (int e = 0; e < 6; e++)
        ASSERT_NEAR(s[e], 2.0 * sqrt(2.0) / 3.0, 1e-12);
    /* the corner tet (0, e1, e2, e3): 90 degrees at the axis edges 01 02 03,
     * acos(1/sqrt3) (sine sqrt(2/3)) at the edges 12 13 23 of the slanted face */
    {
        double c[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        metric_dihedral_sines(c[0], c[1], c[2], c[3], s);
        for (int e = 0; e < 6; e++)
            ASSERT_NEAR(s[e], e < 3 ? 1.0 : sqrt(2.0 / 3.0), 1e-12);
    }
    /* a generic tet agrees with the acos-based angles */
    metric_dihedral_sines(t[0], t[1], t[2], t[3], s);
    metric_dihedrals(t[0], t[1], t[2], t[3], ang);
    for (int e = 0; e < 6; e++)
        ASSERT_NEAR(s[e], sin(ang[e] * 3.14159265358979323846 / 180.0), 1e-12);
    /* inverted: the same magnitudes, negative */
    {
        double si[6];
        metric_dihedral_sines(t[0], t[2], t[1], t[3], si);
        for (int e = 0; e < 6; e++)
            ASSERT_TRUE(si[e] < 0.0);
    }
}

TEST(cubed_mean_ratio_orders_like_the_mean_ratio)
{
    /* corner tet (0, e1, e2, e3): V = 1/6, l2sum = 3 + 3 * 2 = 9, so
     * eta = 12 (9 / 36)^(1/3) / 9 and eta^3 = 15552 / 36 / 729 = 16 / 27 */
    double c[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, s[6], s2[6];
    double t[4][3] = {{0, 0, 0}, {1, 0.1, 0}, {0.2, 0.7, 0.1}, {0.3, 0.2, 0.4}};
    metric_parts p;
    metric_parts_of(c[0], c[1], c[2], c[3], &p);
    ASSERT_NEAR(metric_mean_ratio_cubed(&p), 16.0 / 27.0, 1e-14);
    ASSERT_NEAR(metric_mean_ratio(&p), cbrt(16.0 / 27.0), 1e-14);
    ASSERT_NEAR(metric_dihedral_sines_eta3(c[0], c[1], c[2], c[3], s), 16.0 / 27.0,
                1e-14);
    metric_dihedral_sines(c[0], c[1], c[2], c[3], s2);
    for (int e = 0; e < 6; e++)
        ASSERT_NEAR(s[e], s2[e], 0.0);
    /* regular: 1; the mirror image: -1 (signed like the mean ratio) */
    metric_parts_of(REG[0], REG[1], REG[2], REG[3], &p);
    ASSERT_NEAR(metric_mean_ratio_cubed(&p), 1.0, 1e-12);
    ASSERT_NEAR(metric_dihedral_sines_eta3(REG[0], REG[2], REG[1], REG[3], s), -1.0,
                1e-12);
    /* a generic tet and its mirror: the cube of the signed mean ratio */
    metric_parts_of(t[0], t[1], t[2], t[3], &p);
    ASSERT_NEAR(metric_mean_ratio_cubed(&p), pow(metric_mean_ratio(&p), 3.0), 1e-14);
    ASSERT_NEAR(metric_dihedral_sines_eta3(t[0], t[1], t[2], t[3], s),
                pow(metric_mean_ratio(&p), 3.0), 1e-14);
    metric_parts_of(t[0], t[2], t[1], t[3], &p);
    ASSERT_NEAR(metric_dihedral_sines_eta3(t[0], t[2], t[1], t[3], s),
                -pow(-metric_mean_ratio(&p), 3.0), 1e-14);
    /* degenerate (all four points on a plane): 0 */
    c[3][2] = 0.0;
    metric_parts_of(c[0], c[1], c[2], c[3], &p);
    ASSERT_NEAR(metric_mean_ratio_cubed(&p), 0.0, 0.0);
}

/* A tet (0, e1, e2, (1/2, 1/2, h)) has 6V = h and l2sum = 5.5 + 3 h^2: flat
 * (degenerate) exactly when h <= GEOM_FLAT_EPS ((5.5 + 3 h^2) / 6)^(3/2), at
 * any scale and offset, and a tet at the floor has mean ratio
 * 2 (GEOM_FLAT_EPS / 2)^(2/3) (core/tet.h). */
TEST(flat_tets_are_degenerate_at_every_scale)
{
    const int32_t tt[4] = {0, 1, 2, 3};
    const double hfloor = GEOM_FLAT_EPS * pow(5.5 / 6.0, 1.5);
    const double hs[5] = {0.0, 0.5 * hfloor, 2.0 * hfloor, 1e-3, -1e-3};
    const int flat[5] = {1, 1, 0, 0, 0}, inv[5] = {0, 0, 0, 0, 1};
    const double scales[3] = {1.0, 1e6, 1e-6}, offs[3] = {0.0, 3e6, -2e-6};

    for (int k = 0; k < 3; k++)
        for (int i = 0; i < 5; i++) {
            double b[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 0.5, hs[i]}}, x[12];
            double v6, l2;
            for (int a = 0; a < 12; a++)
                x[a] = scales[k] * b[a / 3][a % 3] + offs[k];
            v6 = geom_tet_vol6(x, tt);
            l2 = geom_tet_l2sum(x, tt);
            ASSERT_NEAR(l2, scales[k] * scales[k] * (5.5 + 3 * hs[i] * hs[i]),
                        1e-12 * scales[k] * scales[k]);
            ASSERT_EQ_INT(geom_tet_degenerate(v6, l2), flat[i]);
            ASSERT_EQ_INT(geom_tet_inverted(v6), inv[i]);
            ASSERT_EQ_INT(geom_tet_bad_vl(v6, l2), flat[i] || inv[i]);
            ASSERT_EQ_INT(geom_tet_bad(x, tt), flat[i] || inv[i]);
        }
    {
        double x[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 0.5, hfloor}};
        metric_parts p;
        metric_parts_of(x[0], x[1], x[2], x[3], &p);
        ASSERT_NEAR(metric_mean_ratio(&p), 2.0 * pow(GEOM_FLAT_EPS / 2.0, 2.0 / 3.0),
                    1e-9 * 2.0 * pow(GEOM_FLAT_EPS / 2.0, 2.0 / 3.0));
    }
    /* NaN coordinates are unusable */
    {
        double x[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, NAN};
        ASSERT_TRUE(geom_tet_bad(x, tt));
    }
}

/* A tet's four faces, a fin on its edge (0, 1) and a triangle with a repeated
 * vertex: every edge paired with the triangles that have it, in order. */
TEST(triangle_edges_pair_up_in_order)
{
    static const int32_t tris[] = {1, 2, 3, 0, 3, 2, 0, 1, 3, 0, 2, 1, 1, 0, 4, 5, 5, 6};
    /* the runs: (lo, hi, count) in sorted order */
    static const int32_t runs[][3] = {{0, 1, 3}, {0, 2, 2}, {0, 3, 2}, {0, 4, 1},
                                      {1, 2, 2}, {1, 3, 2}, {1, 4, 1}, {2, 3, 2},
                                      {5, 5, 1}, {5, 6, 2}};
    tri_edge *e = NULL;
    size_t n = 18, i = 0, r = 0;

    ASSERT_OK(tri_edges_sorted(tris, 6, 7, &e));
    for (size_t j = 0; j < n; j++) {
        int32_t a = tris[3 * e[j].tri + e[j].k],
                b = tris[3 * e[j].tri + (e[j].k + 1) % 3];
        ASSERT_EQ_INT(e[j].lo, a < b ? a : b);
        ASSERT_EQ_INT(e[j].hi, a < b ? b : a);
        if (j > 0 && e[j].lo == e[j - 1].lo && e[j].hi == e[j - 1].hi)
            ASSERT_TRUE(e[j].tri > e[j - 1].tri ||
                        (e[j].tri == e[j - 1].tri && e[j].k > e[j - 1].k));
    }
    for (; i < n; r++) {
        size_t j = tri_edges_run(e, n, i);
        ASSERT_TRUE(r < 10);
        ASSERT_EQ_INT(e[i].lo, runs[r][0]);
        ASSERT_EQ_INT(e[i].hi, runs[r][1]);
        ASSERT_EQ_INT((int32_t)(j - i), runs[r][2]);
        i = j;
    }
    ASSERT_EQ_INT((int32_t)r, 10);
    ASSERT_EQ_INT(e[0].tri, 2); /* (0, 1): the tet's faces 2 and 3, then the fin */
    ASSERT_EQ_INT(e[2].tri, 4);
    qdc_free(e);
    ASSERT_OK(tri_edges_sorted(tris, 0, 7, &e));
    ASSERT_TRUE(e != NULL);
    qdc_free(e);
}

TEST_MAIN("core", T(triangle_edges_pair_up_in_order),
          T(flat_tets_are_degenerate_at_every_scale),
          T(hessian_matches_finite_differences_of_the_gradient),
          T(face_set_once_gives_the_same_bits),
          T(dihedral_sines_are_the_sines_of_the_angles),
          T(cubed_mean_ratio_orders_like_the_mean_ratio), T(regular_tet_metrics_are_one),
          T(scaled_regular_tet_is_still_one), T(mivl_is_mimr_to_three_halves),
          T(inverted_tet_negative_mean_ratio_and_infinite_qt),
          T(h_is_continuous_and_regularizes), T(alpha_closed_form_matches_search),
          T(gradient_matches_finite_differences), T(qdc_of_symmetric_star),
          T(optavg_weights_sum_to_one_on_random_mesh),
          T(cholmod_and_pcg_agree_with_dense), T(topology_of_grid),
          T(topology_does_not_depend_on_vertex_order),
          T(spatial_order_is_the_morton_curve), T(validation_errors),
          T(swap_tets_exchanges_tets_regions_and_counts))
