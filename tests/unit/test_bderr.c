/* test_bderr.c - point-triangle distance, BVH queries and Hausdorff distances
 * against hand-computed and analytic values. */
#include "core/base_int.h"
#include "geom/bderr_int.h"
#include "qdc.h"
#include "testlib.h"

#include <stdint.h>
#include <string.h>
#include <unistd.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#if defined(__SANITIZE_ADDRESS__)
enum { BIG_GRID = 20, BIG_SAMPLES = 100000 };
#else
enum { BIG_GRID = 56, BIG_SAMPLES = 1000000 }; /* 6 * 56^3 = 1.05M tets */
#endif

static uint64_t rng_state = 0x243f6a8885a308d3ULL;

static double urand(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) * 0x1.0p-53;
}

static const double A[3] = {0, 0, 0}, B[3] = {1, 0, 0}, C[3] = {0, 1, 0};

/* distance from p to ABC is d with closest point q */
static int pt_case(double px, double py, double pz, double d, double qx, double qy,
                   double qz)
{
    double p[3] = {px, py, pz}, q[3];
    double got = bderr_point_triangle(p, A, B, C, q);

    if (fabs(got - d) > 1e-15 || fabs(q[0] - qx) > 1e-15 || fabs(q[1] - qy) > 1e-15 ||
        fabs(q[2] - qz) > 1e-15) {
        printf("  p=(%g,%g,%g): d=%.17g q=(%g,%g,%g), expected d=%.17g q=(%g,%g,%g)\n",
               px, py, pz, got, q[0], q[1], q[2], d, qx, qy, qz);
        return 1;
    }
    return 0;
}

TEST(point_triangle_regions)
{
    int bad = 0;

    bad += pt_case(0.25, 0.25, 2, 2, 0.25, 0.25, 0);         /* face, above */
    bad += pt_case(0.2, 0.3, -0.5, 0.5, 0.2, 0.3, 0);        /* face, below */
    bad += pt_case(0.1, 0.1, 0, 0, 0.1, 0.1, 0);             /* on the face */
    bad += pt_case(-1, -1, 0, sqrt(2), 0, 0, 0);             /* vertex A */
    bad += pt_case(2, -1, 0, sqrt(2), 1, 0, 0);              /* vertex B */
    bad += pt_case(0, 3, 0, 2, 0, 1, 0);                     /* vertex C */
    bad += pt_case(-1, 2, 1, sqrt(3), 0, 1, 0);              /* vertex C, off plane */
    bad += pt_case(0.5, -1, 1, sqrt(2), 0.5, 0, 0);          /* edge AB */
    bad += pt_case(1, 1, 0, sqrt(0.5), 0.5, 0.5, 0);         /* edge BC */
    bad += pt_case(0.75, 0.75, 1, sqrt(1.125), 0.5, 0.5, 0); /* edge BC, off plane */
    bad += pt_case(-2, 0.5, 0, 2, 0, 0.5, 0);                /* edge AC */
    ASSERT_EQ_INT(bad, 0);
}

TEST(point_triangle_degenerate)
{
    const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {2, 0, 0}, p[3] = {1.5, 1, 0};
    const double s[3] = {1, 1, 1}, p2[3] = {1, 1, 3};
    double q[3];

    ASSERT_NEAR(bderr_point_triangle(p, a, b, c, q), 1, 1e-15);
    ASSERT_NEAR(q[0], 1.5, 1e-15);
    ASSERT_NEAR(bderr_point_triangle(p, c, a, b, q), 1, 1e-15); /* any vertex order */
    ASSERT_NEAR(bderr_point_triangle(p, b, c, a, q), 1, 1e-15);
    ASSERT_NEAR(bderr_point_triangle(p2, s, s, s, q), 2, 0);
    ASSERT_NEAR(bderr_point_triangle(p, a, a, c, NULL), 1, 1e-15); /* repeated vertex */
    /* random degenerate triangles: finite, never above the distance to a corner */
    for (int i = 0; i < 10000; i++) {
        double x[3], y[3], z[3], r[3], t = urand();
        for (int d = 0; d < 3; d++) {
            x[d] = urand();
            y[d] = urand();
            z[d] = x[d] + t * (y[d] - x[d]);
            r[d] = 2 * urand() - 0.5;
        }
        double dd = bderr_point_triangle(r, x, y, z, q);
        ASSERT_TRUE(isfinite(dd) && dd <= sqrt(pow(r[0] - x[0], 2) + pow(r[1] - x[1], 2) +
                                               pow(r[2] - x[2], 2)) +
                                              1e-15);
    }
}

TEST(point_triangle_vs_sampling)
{
    /* the exact distance is below every sampled point and close to the best one */
    for (int it = 0; it < 200; it++) {
        double a[3], b[3], c[3], p[3], q[3], best = INFINITY, d;
        for (int k = 0; k < 3; k++) {
            a[k] = urand();
            b[k] = urand();
            c[k] = urand();
            p[k] = 3 * urand() - 1;
        }
        d = bderr_point_triangle(p, a, b, c, q);
        ASSERT_NEAR(sqrt(pow(p[0] - q[0], 2) + pow(p[1] - q[1], 2) + pow(p[2] - q[2], 2)),
                    d, 1e-14);
        for (int i = 0; i <= 200; i++)
            for (int j = 0; i + j <= 200; j++) {
                double u = i / 200.0, v = j / 200.0, s[3], e;
                for (int k = 0; k < 3; k++)
                    s[k] = a[k] + u * (b[k] - a[k]) + v * (c[k] - a[k]);
                e = sqrt(pow(p[0] - s[0], 2) + pow(p[1] - s[1], 2) + pow(p[2] - s[2], 2));
                ASSERT_TRUE(d <= e + 1e-14);
                best = fmin(best, e);
            }
        ASSERT_TRUE(best - d < 0.02);
    }
}

/* nt small random triangles in the unit cube, each with its own 3 vertices
 * (x: 9 doubles a triangle, t: 3 indices). */
static void random_triangles(double *x, int32_t *t, int nt)
{
    for (int i = 0; i < nt; i++) {
        double o[3] = {urand(), urand(), urand()};
        for (int v = 0; v < 3; v++) {
            for (int d = 0; d < 3; d++)
                x[9 * i + 3 * v + d] = o[d] + 0.1 * urand();
            t[3 * i + v] = 3 * i + v;
        }
    }
}

TEST(bvh_matches_brute_force)
{
    enum { NT = 700, NQ = 2000 };
    double *x = malloc(9 * NT * sizeof(double));
    int32_t *t = malloc(3 * NT * sizeof(int32_t));
    bderr_bvh *b = NULL;
    qdc_error err;

    ASSERT_TRUE(x && t);
    random_triangles(x, t, NT);
    ASSERT_OK(bderr_bvh_build(x, 3 * NT, t, NT, &b, &err));
    for (int q = 0; q < NQ; q++) {
        double p[3] = {2 * urand() - 0.5, 2 * urand() - 0.5, 2 * urand() - 0.5}, cp[3];
        double best = INFINITY, d;
        int32_t tri;
        for (int i = 0; i < NT; i++)
            best = fmin(best, bderr_point_triangle(p, x + 9 * i, x + 9 * i + 3,
                                                   x + 9 * i + 6, NULL));
        d = bderr_bvh_closest(b, p, cp, &tri);
        ASSERT_NEAR(d, best, 0);
        ASSERT_TRUE(tri >= 0 && tri < NT);
        /* starting from any triangle (or none, or an index out of range) gives
         * the same distance */
        ASSERT_NEAR(bderr_bvh_closest_near(b, p, q % NT, NULL, NULL), best, 0);
        ASSERT_NEAR(bderr_bvh_closest_near(b, p, -1, NULL, NULL), best, 0);
        ASSERT_NEAR(bderr_bvh_closest_near(b, p, NT + q, NULL, NULL), best, 0);
        ASSERT_NEAR(
            bderr_point_triangle(p, x + 9 * tri, x + 9 * tri + 3, x + 9 * tri + 6, NULL),
            d, 0);
        ASSERT_NEAR(
            sqrt(pow(p[0] - cp[0], 2) + pow(p[1] - cp[1], 2) + pow(p[2] - cp[2], 2)), d,
            1e-15);
    }
    bderr_bvh_free(b);
    free(x);
    free(t);
}

/* Queries a hair off a fine surface away from the origin (coordinates near
 * 1e3, edges of 1e-3, distances down to 1e-12), the search started from
 * another triangle than the query's own: the triangles skipped by their
 * balls are never the nearest, so the distances are the brute-force ones,
 * bit for bit, from the tree, from a start triangle and in groups. */
TEST(bvh_ball_skips_never_change_the_answer)
{
    enum { N = 24, NT = 2 * N * N, NQ = 3000 };
    double *x = malloc(9 * NT * sizeof(double)), *p = malloc(3 * NQ * sizeof(double));
    int32_t *t = malloc(3 * NT * sizeof(int32_t)), *near = malloc(NQ * sizeof(int32_t));
    double o[3] = {1e3, -2e3, 3e2}, h = 1e-3, *d = malloc(NQ * sizeof(double));
    bderr_bvh *b = NULL;
    qdc_error err;

    ASSERT_TRUE(x && p && t && near && d);
    /* a wavy grid of triangles, each with its own three corners */
    for (int i = 0, k = 0; i < N; i++)
        for (int j = 0; j < N; j++)
            for (int s = 0; s < 2; s++, k++) {
                int c[3][2] = {{i, j}, {i + 1, j + s}, {i + s, j + 1}};
                for (int v = 0; v < 3; v++) {
                    double *q = x + 9 * k + 3 * v;
                    q[0] = o[0] + h * c[v][0];
                    q[1] = o[1] + h * c[v][1];
                    q[2] = o[2] + 0.3 * h * sin(c[v][0] * 0.7) * cos(c[v][1] * 0.5);
                    t[3 * k + v] = 3 * k + v;
                }
            }
    ASSERT_OK(bderr_bvh_build(x, 3 * NT, t, NT, &b, &err));
    for (int q = 0; q < NQ; q++) {
        int k = (int)(urand() * NT);
        double u = urand(), v = urand() * (1 - u), off = pow(10.0, -12 + 9 * urand());
        double best = INFINITY;
        if (k >= NT)
            k = NT - 1;
        if (q % 2) /* by a corner, where triangles tie within the offset */
            u = (q / 2) % 3 == 1, v = (q / 2) % 3 == 2;
        for (int c = 0; c < 3; c++)
            p[3 * q + c] = x[9 * k + c] + u * (x[9 * k + 3 + c] - x[9 * k + c]) +
                           v * (x[9 * k + 6 + c] - x[9 * k + c]) +
                           (q % 2    ? off * (urand() - 0.5)
                            : c == 2 ? off
                                     : 0);
        near[q] = (k + 2 * N + 5) % NT; /* a few rows away */
        for (int i = 0; i < NT; i++)
            best = fmin(best, bderr_point_triangle(p + 3 * q, x + 9 * i, x + 9 * i + 3,
                                                   x + 9 * i + 6, NULL));
        ASSERT_NEAR(bderr_bvh_closest(b, p + 3 * q, NULL, NULL), best, 0);
        ASSERT_NEAR(bderr_bvh_closest_near(b, p + 3 * q, near[q], NULL, NULL), best, 0);
        d[q] = best;
    }
    /* one point at a time as a group of one, against its brute-force answer */
    for (int q = 0; q < NQ; q++) {
        double got;
        ASSERT_TRUE(bderr_bvh_closest_group(b, 1, p + 3 * q, near + q, &got));
        ASSERT_NEAR(got, d[q], 0);
    }
    bderr_bvh_free(b);
    free(x);
    free(p);
    free(t);
    free(near);
    free(d);
}

/* Points grouped by the leaf of their starting triangle get, at once, the
 * brute-force distances (the same bits); groups the call cannot take are
 * refused without touching d. */
TEST(bvh_group_matches_brute_force)
{
    enum { NT = 600, NQ = 3000 };
    double *x = malloc(9 * NT * sizeof(double)), *p = malloc(3 * NQ * sizeof(double));
    int32_t *t = malloc(3 * NT * sizeof(int32_t)), *near = malloc(NQ * sizeof(int32_t));
    int32_t *ord = malloc(NQ * sizeof(int32_t));
    bderr_bvh *b = NULL;
    qdc_error err;
    int groups = 0, multi = 0;

    ASSERT_TRUE(x && p && t && near && ord);
    random_triangles(x, t, NT);
    ASSERT_OK(bderr_bvh_build(x, 3 * NT, t, NT, &b, &err));
    /* each point near a random triangle (on it, then pushed off by up to 0.05) */
    for (int q = 0; q < NQ; q++) {
        int32_t i = (int32_t)(urand() * NT) % NT;
        double u = urand(), v = urand() * (1 - u);
        near[q] = i;
        for (int d = 0; d < 3; d++)
            p[3 * q + d] = x[9 * i + d] + u * (x[9 * i + 3 + d] - x[9 * i + d]) +
                           v * (x[9 * i + 6 + d] - x[9 * i + d]) + 0.05 * (urand() - 0.5);
    }
    /* in order of the leaf (an insertion sort by leaf) */
    for (int q = 0; q < NQ; q++) {
        int j = q;
        ord[q] = q;
        while (j > 0 && bderr_bvh_leaf_of(b, near[ord[j - 1]]) >
                            bderr_bvh_leaf_of(b, near[ord[j]])) {
            int32_t k = ord[j];
            ord[j] = ord[j - 1];
            ord[--j] = k;
        }
    }
    for (int q = 0; q < NQ;) {
        double gp[3 * BDERR_GROUP_MAX], gd[BDERR_GROUP_MAX];
        int32_t gn[BDERR_GROUP_MAX], g = 0, leaf = bderr_bvh_leaf_of(b, near[ord[q]]);
        ASSERT_TRUE(leaf >= 0);
        while (q + g < NQ && g < BDERR_GROUP_MAX &&
               bderr_bvh_leaf_of(b, near[ord[q + g]]) == leaf) {
            memcpy(gp + 3 * g, p + 3 * ord[q + g], 3 * sizeof(double));
            gn[g] = near[ord[q + g]];
            g++;
        }
        ASSERT_EQ_INT(bderr_bvh_closest_group(b, g, gp, gn, gd), 1);
        for (int32_t k = 0; k < g; k++) {
            double best = INFINITY;
            for (int i = 0; i < NT; i++)
                best =
                    fmin(best, bderr_point_triangle(gp + 3 * k, x + 9 * i, x + 9 * i + 3,
                                                    x + 9 * i + 6, NULL));
            ASSERT_NEAR(gd[k], best, 0);
            ASSERT_NEAR(gd[k], bderr_bvh_closest_near(b, gp + 3 * k, gn[k], NULL, NULL),
                        0);
        }
        groups++;
        multi += g > 1;
        q += g;
    }
    ASSERT_TRUE(groups > 1 && multi > 1);
    {
        double gd[2] = {-1, -1}, gp[6] = {0, 0, 0, 0.5, 0.5, 0.5};
        int32_t gn[2] = {0, 0}, other = -1;
        for (int32_t i = 1; i < NT && other < 0; i++)
            if (bderr_bvh_leaf_of(b, i) != bderr_bvh_leaf_of(b, 0))
                other = i;
        ASSERT_TRUE(other > 0);
        gn[1] = other; /* two leaves */
        ASSERT_EQ_INT(bderr_bvh_closest_group(b, 2, gp, gn, gd), 0);
        gn[1] = 0;
        gp[4] = NAN; /* a point not finite */
        ASSERT_EQ_INT(bderr_bvh_closest_group(b, 2, gp, gn, gd), 0);
        ASSERT_NEAR(gd[0], -1, 0);
        gn[0] = NT; /* out of range */
        ASSERT_EQ_INT(bderr_bvh_closest_group(b, 1, gp, gn, gd), 0);
        ASSERT_EQ_INT(bderr_bvh_closest_group(b, BDERR_GROUP_MAX + 1, gp, gn, gd), 0);
        ASSERT_EQ_INT(bderr_bvh_closest_group(b, 0, gp, gn, gd), 1);
        ASSERT_EQ_INT(bderr_bvh_leaf_of(b, -1), -1);
        ASSERT_EQ_INT(bderr_bvh_leaf_of(NULL, 0), -1);
    }
    bderr_bvh_free(b);
    free(x);
    free(p);
    free(t);
    free(near);
    free(ord);
}

TEST(bvh_refit_matches_brute_force)
{
    enum { NT = 500, NQ = 1000 };
    double *x = malloc(9 * NT * sizeof(double)), *y = malloc(9 * NT * sizeof(double));
    int32_t *t = malloc(3 * NT * sizeof(int32_t));
    bderr_bvh *b = NULL, *r = NULL;
    qdc_error err;

    ASSERT_TRUE(x && y && t);
    for (int i = 0; i < NT; i++) {
        double o[3] = {urand(), urand(), urand()};
        for (int v = 0; v < 3; v++) {
            for (int d = 0; d < 3; d++) {
                x[9 * i + 3 * v + d] = o[d] + 0.1 * urand();
                /* moved by up to 0.2: boxes of the old tree no longer fit */
                y[9 * i + 3 * v + d] = x[9 * i + 3 * v + d] + 0.2 * (urand() - 0.5);
            }
            t[3 * i + v] = 3 * i + v;
        }
    }
    ASSERT_OK(bderr_bvh_build(x, 3 * NT, t, NT, &b, &err));
    ASSERT_OK(bderr_bvh_refit(b, y, 3 * NT, &r, &err));
    for (int q = 0; q < NQ; q++) {
        double p[3] = {2 * urand() - 0.5, 2 * urand() - 0.5, 2 * urand() - 0.5};
        double best = INFINITY;
        int32_t tri;
        for (int i = 0; i < NT; i++)
            best = fmin(best, bderr_point_triangle(p, y + 9 * i, y + 9 * i + 3,
                                                   y + 9 * i + 6, NULL));
        ASSERT_NEAR(bderr_bvh_closest(r, p, NULL, &tri), best, 0);
        ASSERT_NEAR(
            bderr_point_triangle(p, y + 9 * tri, y + 9 * tri + 3, y + 9 * tri + 6, NULL),
            best, 0);
        ASSERT_NEAR(bderr_bvh_closest_near(r, p, q % NT, NULL, NULL), best, 0);
    }
    ASSERT_EQ_INT(bderr_bvh_position(r, 7), bderr_bvh_position(b, 7));
    ASSERT_EQ_INT(bderr_bvh_position(r, NT), -1);
    ASSERT_EQ_INT(bderr_bvh_size(r), NT);
    bderr_bvh_free(r);
    y[4] = NAN; /* a coordinate the refit must refuse */
    ASSERT_EQ_INT(bderr_bvh_refit(b, y, 3 * NT, &r, &err), QDC_EINVAL);
    ASSERT_TRUE(r == NULL);
    ASSERT_EQ_INT(bderr_bvh_refit(b, y, 2, &r, &err), QDC_EINVAL); /* indices past nv */
    bderr_bvh_free(b);
    free(x);
    free(y);
    free(t);
}

TEST(bvh_edge_cases)
{
    const double x[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, p[3] = {0, 0, 1},
                 pn[3] = {0, NAN, 0};
    const int32_t t[3] = {0, 1, 2}, bad[3] = {0, 1, 3};
    bderr_bvh *b = NULL;
    int32_t tri = 7;
    qdc_error err;

    ASSERT_OK(bderr_bvh_build(x, 3, t, 0, &b, &err));
    ASSERT_TRUE(isinf(bderr_bvh_closest(b, p, NULL, &tri)) && tri == -1);
    bderr_bvh_free(b);
    ASSERT_EQ_INT(bderr_bvh_build(x, 3, bad, 1, &b, &err), QDC_EINVAL);
    ASSERT_TRUE(b == NULL);
    ASSERT_OK(bderr_bvh_build(x, 3, t, 1, &b, &err));
    ASSERT_NEAR(bderr_bvh_closest(b, p, NULL, &tri), 1, 0);
    ASSERT_EQ_INT(tri, 0);
    ASSERT_TRUE(isnan(bderr_bvh_closest(b, pn, NULL, &tri)) && tri == -1);
    bderr_bvh_free(b);
    bderr_bvh_free(NULL);
}

/* Closed surface of [-0.5, 0.5]^3, n x n squares per side, shifted by dz. */
static void cube_surface(int n, double dz, double **xyz, int32_t *nv, int32_t **tris,
                         int32_t *nt)
{
    int32_t k = 0, m = 0;
    double *x = malloc(6 * (size_t)(n + 1) * (n + 1) * 3 * sizeof(double));
    int32_t *t = malloc(6 * (size_t)n * n * 6 * sizeof(int32_t));

    for (int f = 0; f < 6; f++) {
        int ax = f / 2, u = (ax + 1) % 3, w = (ax + 2) % 3;
        int32_t base = k;
        for (int i = 0; i <= n; i++)
            for (int j = 0; j <= n; j++) {
                double *p = x + 3 * (size_t)k++;
                p[ax] = f % 2 ? 0.5 : -0.5;
                p[u] = -0.5 + (double)i / n;
                p[w] = -0.5 + (double)j / n;
                p[2] += dz;
            }
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++) {
                int32_t v00 = base + i * (n + 1) + j, v10 = v00 + n + 1;
                int32_t q[6] = {v00, v10, v10 + 1, v00, v10 + 1, v00 + 1};
                memcpy(t + 3 * (size_t)m, q, sizeof q);
                m += 2;
            }
    }
    *xyz = x;
    *nv = k;
    *tris = t;
    *nt = m;
}

TEST(hausdorff_translated_cube)
{
    double *xa, *xb;
    int32_t nva, nvb, nta, ntb, *ta, *tb;
    bderr_result r;
    qdc_error err;

    cube_surface(8, 0.01, &xa, &nva, &ta, &nta);
    cube_surface(5, 0.0, &xb, &nvb, &tb, &ntb);
    ASSERT_OK(bderr_surfaces(xa, nva, ta, nta, xb, nvb, tb, ntb, 20000, 1, &r, &err));
    ASSERT_NEAR(r.hausdorff, 0.01, 1e-12);
    ASSERT_NEAR(r.h_a_to_b, 0.01, 1e-12);
    ASSERT_NEAR(r.h_b_to_a, 0.01, 1e-12);
    ASSERT_NEAR(r.diag, sqrt(3), 1e-15);
    ASSERT_NEAR(r.hausdorff_rel, 0.01 / sqrt(3), 1e-12);
    ASSERT_TRUE(r.mean > 0 && r.mean < 0.01 && r.rms >= r.mean && r.rms < 0.01);
    ASSERT_EQ_INT(r.n_samples, nva + nvb + nta + ntb + 40000);
    ASSERT_EQ_INT(r.ntri_a, nta);
    /* the same surface with another triangulation: zero */
    free(xa);
    free(ta);
    cube_surface(8, 0.0, &xa, &nva, &ta, &nta);
    ASSERT_OK(bderr_surfaces(xa, nva, ta, nta, xb, nvb, tb, ntb, 20000, 1, &r, &err));
    ASSERT_NEAR(r.hausdorff, 0, 1e-15);
    free(xa);
    free(xb);
    free(ta);
    free(tb);
}

/* Two unit squares at distance PLANES_D: every sample is exactly that far. */
#define PLANES_D 0.125
static const double sq_a[12] = {0, 0, PLANES_D, 1, 0, PLANES_D,
                                1, 1, PLANES_D, 0, 1, PLANES_D};
static const double sq_b[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
static const int32_t sq_t[6] = {0, 1, 2, 0, 2, 3};

/* bderr_surfaces of the two squares with that many samples a side, checked
 * (a failure marks the calling test failed). */
static void planes_case(int64_t samples)
{
    bderr_result r;
    qdc_error err;

    ASSERT_OK(bderr_surfaces(sq_a, 4, sq_t, 2, sq_b, 4, sq_t, 2, samples, 7, &r, &err));
    ASSERT_NEAR(r.hausdorff, PLANES_D, 1e-15);
    ASSERT_NEAR(r.vertex_max, PLANES_D, 1e-15);
    ASSERT_NEAR(r.mean, PLANES_D, 1e-12);
    ASSERT_NEAR(r.rms, PLANES_D, 1e-12);
    ASSERT_NEAR(r.mean_rel, PLANES_D / sqrt(2), 1e-12);
    ASSERT_EQ_INT(r.n_samples, 2 * (4 + 2 + samples));
}

TEST(parallel_planes_mean_rms)
{
    planes_case(5000);
}

/* Past BDERR_SORT_MAX samples a side, the samples are measured as they are
 * drawn: the same figures. */
TEST(many_samples_in_drawing_order)
{
#if defined(__SANITIZE_ADDRESS__)
    SKIP("16.8M samples: too slow under the sanitizers");
#endif
    planes_case(BDERR_SORT_MAX);
}

TEST(deterministic_and_thread_independent)
{
    double *xa, *xb;
    int32_t nva, nvb, nta, ntb, *ta, *tb;
    bderr_result r1, r2, r3;
    qdc_error err;

    cube_surface(6, 0.0, &xa, &nva, &ta, &nta);
    cube_surface(9, 0.0, &xb, &nvb, &tb, &ntb);
    for (int32_t i = 0; i < nva; i++) /* bump: not on the other surface */
        xa[3 * i] *= 1 + 0.05 * sin(7 * xa[3 * i + 1]) * cos(5 * xa[3 * i + 2]);
    ASSERT_OK(bderr_surfaces(xa, nva, ta, nta, xb, nvb, tb, ntb, 50000, 42, &r1, &err));
#ifdef _OPENMP
    omp_set_num_threads(1);
#endif
    ASSERT_OK(bderr_surfaces(xa, nva, ta, nta, xb, nvb, tb, ntb, 50000, 42, &r2, &err));
#ifdef _OPENMP
    omp_set_num_threads(omp_get_num_procs());
#endif
    ASSERT_TRUE(memcmp(&r1, &r2, sizeof r1) == 0);
    ASSERT_OK(bderr_surfaces(xa, nva, ta, nta, xb, nvb, tb, ntb, 50000, 43, &r3, &err));
    ASSERT_TRUE(r3.mean != r1.mean);
    ASSERT_TRUE(r1.hausdorff > 0.005 && r1.hausdorff < 0.05);
    free(xa);
    free(xb);
    free(ta);
    free(tb);
}

/* The same triangles on both sides (a result and its input: A's tree is then
 * B's refitted) give what an A numbered otherwise gives (its tree built: the
 * same samples, measured in another order), and the largest distance of A's
 * vertices is the brute-force one. */
TEST(shared_triangles_same_as_copies)
{
    double *xa, *xb, *xp, vmax = 0;
    int32_t nva, nvb, nta, ntb, *ta, *tb, *tp;
    bderr_result r1, r2, r3;
    qdc_error err;

    cube_surface(7, 0.0, &xa, &nva, &ta, &nta);
    cube_surface(7, 0.0, &xb, &nvb, &tb, &ntb);
    for (int32_t i = 0; i < nva; i++) /* bumped and slid along the faces */
        for (int d = 0; d < 3; d++)
            xa[3 * i + d] *= 1 + 0.04 * sin(7 * xa[3 * i + (d + 1) % 3] + d);
    xp = malloc(3 * (size_t)nva * sizeof(double)); /* A, its vertices reversed */
    tp = malloc(3 * (size_t)nta * sizeof(int32_t));
    ASSERT_TRUE(xp && tp);
    for (int32_t i = 0; i < nva; i++)
        memcpy(xp + 3 * (size_t)(nva - 1 - i), xa + 3 * (size_t)i, 3 * sizeof(double));
    for (int32_t i = 0; i < 3 * nta; i++)
        tp[i] = nva - 1 - ta[i];
    ASSERT_OK(bderr_surfaces(xa, nva, ta, nta, xb, nvb, tb, ntb, 30000, 5, &r1, &err));
    ASSERT_OK(bderr_surfaces(xp, nva, tp, nta, xb, nvb, tb, ntb, 30000, 5, &r2, &err));
    ASSERT_NEAR(r1.hausdorff, r2.hausdorff, 0);
    ASSERT_NEAR(r1.h_a_to_b, r2.h_a_to_b, 0);
    ASSERT_NEAR(r1.h_b_to_a, r2.h_b_to_a, 0);
    ASSERT_NEAR(r1.vertex_max, r2.vertex_max, 0);
    ASSERT_NEAR(r1.mean, r2.mean, 1e-12 * r2.mean);
    ASSERT_NEAR(r1.rms, r2.rms, 1e-12 * r2.rms);
    ASSERT_TRUE(r1.hausdorff > 0.01 && r1.hausdorff < 0.05);
    for (int32_t i = 0; i < nva; i++) {
        double best = INFINITY;
        for (int32_t k = 0; k < ntb; k++)
            best = fmin(best, bderr_point_triangle(xa + 3 * i, xb + 3 * tb[3 * k],
                                                   xb + 3 * tb[3 * k + 1],
                                                   xb + 3 * tb[3 * k + 2], NULL));
        vmax = fmax(vmax, best);
    }
    ASSERT_NEAR(r1.vertex_max, vmax, 0);
    /* one list or two equal ones: the same bytes, at any thread count */
#ifdef _OPENMP
    omp_set_num_threads(1);
#endif
    ASSERT_OK(bderr_surfaces(xa, nva, tb, ntb, xb, nvb, tb, ntb, 30000, 5, &r3, &err));
#ifdef _OPENMP
    omp_set_num_threads(omp_get_num_procs());
#endif
    ASSERT_TRUE(memcmp(&r1, &r3, sizeof r1) == 0);
    free(xa);
    free(xb);
    free(xp);
    free(ta);
    free(tb);
    free(tp);
}

TEST(surfaces_bad_input)
{
    const double x[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0},
                 nan3[9] = {0, 0, 0, 1, 0, 0, 0, NAN, 0};
    const int32_t t[3] = {0, 1, 2}, bad[3] = {0, 1, -1};
    bderr_result r;
    qdc_error err;

    ASSERT_EQ_INT(bderr_surfaces(x, 3, t, 0, x, 3, t, 1, 10, 1, &r, &err), QDC_EINVAL);
    ASSERT_EQ_INT(bderr_surfaces(x, 3, bad, 1, x, 3, t, 1, 10, 1, &r, &err), QDC_EINVAL);
    ASSERT_EQ_INT(bderr_surfaces(x, 3, t, 1, nan3, 3, t, 1, 10, 1, &r, &err), QDC_EINVAL);
    ASSERT_EQ_INT(bderr_surfaces(x, 3, t, 1, x, 3, t, 1, -1, 1, &r, &err), QDC_EINVAL);
    ASSERT_OK(bderr_surfaces(x, 3, t, 1, x, 3, t, 1, 0, 1, &r, &err));
    ASSERT_NEAR(r.hausdorff, 0, 1e-15);
}

/* [0,1]^3 as n^3 cubes of 6 Kuhn tets each (a conforming mesh). */
static mesh_t *grid_mesh(int n, double dz)
{
    mesh_t *m = mesh_new((n + 1) * (n + 1) * (n + 1), 6 * n * n * n, 0);
    static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                   {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    int32_t t = 0;

    if (!m)
        return NULL;
    for (int i = 0; i <= n; i++)
        for (int j = 0; j <= n; j++)
            for (int k = 0; k <= n; k++) {
                double *p = m->xyz + 3 * (size_t)((i * (n + 1) + j) * (n + 1) + k);
                p[0] = (double)i / n;
                p[1] = (double)j / n;
                p[2] = (double)k / n + dz;
            }
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            for (int k = 0; k < n; k++)
                for (int s = 0; s < 6; s++) {
                    int c[3] = {i, j, k};
                    for (int v = 0; v < 4; v++) {
                        if (v > 0)
                            c[perm[s][v - 1]]++;
                        m->tets[4 * (size_t)t + v] =
                            (c[0] * (n + 1) + c[1]) * (n + 1) + c[2];
                    }
                    t++;
                }
    return m;
}

TEST(meshes_boundary_faces)
{
    mesh_t *a = grid_mesh(4, 0.01), *b = grid_mesh(3, 0);
    bderr_result r;
    qdc_error err;

    ASSERT_TRUE(a && b);
    ASSERT_OK(bderr_meshes(a, b, 10000, &r, &err));
    ASSERT_EQ_INT(r.ntri_a, 6 * 2 * 4 * 4);
    ASSERT_EQ_INT(r.ntri_b, 6 * 2 * 3 * 3);
    ASSERT_NEAR(r.hausdorff, 0.01, 1e-12);
    mesh_free(a);
    a = grid_mesh(4, 0);
    ASSERT_OK(bderr_meshes(a, b, 10000, &r, &err));
    ASSERT_NEAR(r.hausdorff, 0, 1e-15);
    a->tets[5] = a->nv;
    ASSERT_EQ_INT(bderr_meshes(a, b, 10, &r, &err), QDC_EINVAL);
    mesh_free(a);
    mesh_free(b);
}

TEST(meshes_big_grid_speed)
{
    mesh_t *a = grid_mesh(BIG_GRID, 0), *b = grid_mesh(BIG_GRID, 0);
    bderr_result r;
    qdc_error err;
    double t0;

    ASSERT_TRUE(a && b);
    for (int32_t i = 0; i < a->nv; i++) /* a small bump on the whole surface */
        for (int d = 0; d < 3; d++)
            a->xyz[3 * i + d] += 1e-3 * sin(10 * a->xyz[3 * i + (d + 1) % 3]);
    t0 = qdc_now();
    ASSERT_OK(bderr_meshes(a, b, BIG_SAMPLES, &r, &err));
    printf("  # bderr_meshes %d tets, %d + %d faces, %lld samples: %.2f s, H = %.3g\n",
           a->nt, r.ntri_a, r.ntri_b, (long long)r.n_samples, qdc_now() - t0,
           r.hausdorff);
    ASSERT_EQ_INT(r.ntri_a, 12 * BIG_GRID * BIG_GRID);
    ASSERT_TRUE(r.hausdorff > 0 && r.hausdorff < 2e-3);
    mesh_free(a);
    mesh_free(b);
}

TEST(dev_meshes)
{
    const char *root = getenv("ROOT");
    char dev[400], cmd[1200], pa[128], pb[128];
    mesh_t *a = NULL, *b = NULL;
    bderr_result r;
    qdc_error err;

    snprintf(dev, sizeof dev, "%s%stests/data/dev", root ? root : "", root ? "/" : "");
    snprintf(pa, sizeof pa, "/tmp/qdc_test_bderr_%d_a.mesh", (int)getpid());
    snprintf(pb, sizeof pb, "/tmp/qdc_test_bderr_%d_b.mesh", (int)getpid());
    snprintf(cmd, sizeof cmd,
             "gzip -dc %s/cube_h0.1_good.mesh.gz > %s 2>/dev/null && "
             "gzip -dc %s/cube_h0.1_noisy.mesh.gz > %s 2>/dev/null",
             dev, pa, dev, pb);
    if (system(cmd) != 0) {
        unlink(pa);
        unlink(pb);
        ASSERT_TRUE(!"dev meshes missing from tests/data/dev");
    }
    ASSERT_OK(meshio_load(pa, MESHIO_MEDIT, &a, &err));
    ASSERT_OK(meshio_load(pb, MESHIO_MEDIT, &b, &err));
    unlink(pa);
    unlink(pb);
    ASSERT_OK(bderr_meshes(a, a, 10000, &r, &err));
    ASSERT_NEAR(r.hausdorff, 0, 1e-15);
    ASSERT_NEAR(r.diag, sqrt(3), 1e-12);
    ASSERT_OK(bderr_meshes(b, a, 10000, &r, &err));
    printf("  # cube noisy vs good: H = %.4g (rel %.4g), mean %.3g, rms %.3g\n",
           r.hausdorff, r.hausdorff_rel, r.mean, r.rms);
    ASSERT_TRUE(r.hausdorff >= 0 && r.mean <= r.rms && r.rms <= r.hausdorff);
    mesh_free(a);
    mesh_free(b);
}

/* Every allocation failing in turn (build with -DQDC_FAULT_INJECTION). */
TEST(allocation_failures)
{
#ifdef QDC_FAULT_INJECTION
    mesh_t *a = grid_mesh(3, 0.01), *b = grid_mesh(2, 0);
    bderr_result r;
    qdc_error err;
    qdc_status st;

    ASSERT_TRUE(a && b);
    for (long n = 1;; n++) {
        qdc_fault_set(n);
        st = bderr_meshes(a, b, 100, &r, &err);
        qdc_fault_set(0);
        if (st == QDC_OK)
            break;
        ASSERT_EQ_INT(st, QDC_ENOMEM);
    }
    ASSERT_NEAR(r.hausdorff, 0.01, 1e-12);
    mesh_free(a);
    mesh_free(b);
#else
    SKIP("built without QDC_FAULT_INJECTION (make fault runs it)");
#endif
}

TEST_MAIN("bderr", T(point_triangle_regions), T(point_triangle_degenerate),
          T(point_triangle_vs_sampling), T(bvh_matches_brute_force),
          T(bvh_ball_skips_never_change_the_answer), T(bvh_group_matches_brute_force),
          T(bvh_refit_matches_brute_force), T(bvh_edge_cases),
          T(hausdorff_translated_cube), T(parallel_planes_mean_rms),
          T(many_samples_in_drawing_order), T(deterministic_and_thread_independent),
          T(shared_triangles_same_as_copies), T(surfaces_bad_input),
          T(meshes_boundary_faces), T(meshes_big_grid_speed), T(dev_meshes),
          T(allocation_failures))
