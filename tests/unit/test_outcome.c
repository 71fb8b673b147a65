/* test_outcome.c - the outcome in words (eval/outcome.h): the worst tet and its
 * centroid from the quality scan, the warnings at their thresholds, the
 * suggestions from the options and the boundary, on two-tet meshes whose
 * figures are known in closed form. */
#include "qdc.h"
#include "testlib.h"

#include <string.h>

/* Two separate tets: a regular one (corners of a unit cube's alternate
 * vertices: mean ratio 1) and, second, a flat one (apex h above the centroid
 * of a unit triangle): a sliver with dihedral angles near 0 when h is small. */
static mesh_t *two_tets(double h)
{
    static const double reg[12] = {0, 0, 0, 1, 1, 0, 1, 0, 1, 0, 1, 1};
    const double tri[12] = {
        10, 0, 0, 11, 0, 0, 10.5, 0.8660254037844386, 0, 10.5, 0.28867513459481287, h};
    mesh_t *m = mesh_new(8, 2, 0);
    if (!m)
        return NULL;
    memcpy(m->xyz, reg, sizeof reg);
    memcpy(m->xyz + 12, tri, sizeof tri);
    for (int i = 0; i < 8; i++)
        m->tets[i] = i;
    return m;
}

static int has(const char *s, const char *sub)
{
    return strstr(s, sub) != NULL;
}

TEST(worst_tet_and_centroid)
{
    mesh_t *m = two_tets(0.01);
    report_quality q;
    ASSERT_TRUE(m);
    ASSERT_OK(report_quality_compute(m, &q, NULL));
    ASSERT_EQ_INT(q.worst_tet, 1);
    ASSERT_NEAR(q.worst_centroid[0], 10.5, 1e-12);
    ASSERT_NEAR(q.worst_centroid[1], (0.8660254037844386 + 0.28867513459481287) / 4,
                1e-12);
    ASSERT_NEAR(q.worst_centroid[2], 0.0025, 1e-12);
    ASSERT_NEAR(q.diag, sqrt(11 * 11 + 1 + 1), 1e-12);
    mesh_free(m);
}

TEST(bad_result_warned)
{
    mesh_t *m = two_tets(0.001);
    report_quality q;
    opt_options o;
    outcome_t out;
    opt_defaults(&o);
    ASSERT_TRUE(m);
    ASSERT_OK(report_quality_compute(m, &q, NULL));
    report_t r = {&q, &q, NULL, &o, NULL};
    ASSERT_OK(outcome_compute(&r, &out));
    ASSERT_EQ_INT(out.n_tets, 2);
    ASSERT_EQ_INT(out.n_small, 1);
    ASSERT_EQ_INT(out.n_large, 1); /* a flat tet has a dihedral angle near 180 too */
    ASSERT_EQ_INT(out.n_inverted, 0);
    ASSERT_EQ_INT(out.worst_tet, 1);
    /* 1 of 2 under 5 degrees (over 0.1%) and a worst mean ratio under 0.05 */
    ASSERT_EQ_INT(out.n_warnings, 2);
    ASSERT_TRUE(has(out.warnings[0], "1 tets (50%, over 0.1%) are left with a dihedral"));
    ASSERT_TRUE(has(out.warnings[1], "the worst tet's mean ratio is +0.0"));
    ASSERT_EQ_INT(out.n_suggestions, 2);
    ASSERT_TRUE(has(out.suggestions[0], "try --topology flips (or --topology full)"));
    /* the flat tet's three base edges are edges of the surface */
    ASSERT_TRUE(has(out.suggestions[1],
                    "3 edges of the input's surface have a solid angle "
                    "under 5° (smallest 0.2°)"));
    ASSERT_TRUE(has(out.left_bad, "worst tet 1 (from 0) at (10.5, 0.2887, 0.00025)"));
    ASSERT_TRUE(has(out.summary, out.improved) && has(out.summary, out.left_bad));
    ASSERT_EQ_INT(out.boundary[0], 0); /* neither measured nor bounded */
    ASSERT_NEAR(out.moved_rel, -1, 0);
    /* after flips: full is suggested; a boundary at its bound: a looser --hausd */
    {
        opt_result res;
        bderr_result b;
        memset(&res, 0, sizeof res);
        memset(&b, 0, sizeof b);
        res.hausd_bound = 0.02;
        b.diag = 10;
        b.hausdorff_rel = 0.0019; /* 95% of the bound 0.2% */
        o.topology = OPT_TOPOLOGY_FLIPS;
        report_t r2 = {&q, &q, &res, &o, &b};
        ASSERT_OK(outcome_compute(&r2, &out));
        ASSERT_EQ_INT(out.n_suggestions, 3);
        ASSERT_TRUE(has(out.suggestions[0], "try --topology full"));
        ASSERT_TRUE(has(out.suggestions[1], "looser --hausd, e.g. --hausd 0.4%"));
        ASSERT_TRUE(has(out.suggestions[2], "3 edges of the input's surface"));
        ASSERT_TRUE(has(out.boundary,
                        "boundary moved 0.19% of the diagonal, 95% of its bound (0.2%)"));
    }
    mesh_free(m);
}

TEST(good_result_quiet)
{
    mesh_t *m = two_tets(0.8);
    report_quality q;
    opt_options o;
    outcome_t out;
    opt_defaults(&o);
    ASSERT_TRUE(m);
    ASSERT_OK(report_quality_compute(m, &q, NULL));
    report_t r = {NULL, &q, NULL, &o, NULL};
    ASSERT_OK(outcome_compute(&r, &out));
    ASSERT_EQ_INT(out.n_small + out.n_large + out.n_inverted, 0);
    ASSERT_EQ_INT(out.n_warnings, 0);
    ASSERT_EQ_INT(out.n_suggestions, 0);
    ASSERT_TRUE(has(out.left_bad, "left: 0 of 2 tets under 5° and 0 over 175° dihedral"));
    /* no after: refused */
    report_t none = {&q, NULL, NULL, &o, NULL};
    ASSERT_EQ_INT(outcome_compute(&none, &out), QDC_EINVAL);
    mesh_free(m);
}

/* Each tet alone: every edge is an edge of the surface, and the solid's angle
 * there is the tet's dihedral angle. The flat tet's base edges: atan(h / r),
 * r the inradius of its base; the regular tet's edges: acos(1/3). The same
 * with every tet in the other vertex order (the triangles inward). */
TEST(surface_edges_bound_the_dihedral)
{
    const double r = 0.28867513459481287, deg = 180 / 3.14159265358979323846;
    for (int mirror = 0; mirror < 2; mirror++) {
        for (int k = 0; k < 2; k++) {
            double h = k ? 0.8 : 0.001;
            mesh_t *m = two_tets(h);
            report_quality q;
            ASSERT_TRUE(m);
            for (int t = 0; t < 2 && mirror; t++) {
                int32_t v = m->tets[4 * t];
                m->tets[4 * t] = m->tets[4 * t + 1];
                m->tets[4 * t + 1] = v;
            }
            ASSERT_OK(report_quality_compute(m, &q, NULL));
            ASSERT_EQ_INT(q.n_surf_lt5, k ? 0 : 3);
            /* h = 0.8: the base edges' 70.16 deg, under the regular tet's 70.53 */
            ASSERT_NEAR(q.surf_angle_min, atan(h / r) * deg, 1e-9);
            ASSERT_TRUE(atan(h / r) * deg < acos(1.0 / 3) * deg);
            /* no tet has a smaller dihedral than the surface allows at its edges */
            ASSERT_TRUE(q.dih_min <= q.surf_angle_min + 1e-9);
            mesh_free(m);
        }
    }
}

/* Each tet's 6 dihedral angles (edges 01 02 03 12 13 23) in degrees by a
 * formula of the test's own, not the scan's: at edge (i, j), the angle
 * between the other two corners' offsets with their parts along the edge
 * taken out, by atan2. */
static void angles_atan2(const double *x, double ang[6])
{
    static const int ends[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2},
                                   {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
    for (int e = 0; e < 6; e++) {
        const double *pi = x + 3 * ends[e][0], *pj = x + 3 * ends[e][1];
        const double *pk = x + 3 * ends[e][2], *pl = x + 3 * ends[e][3];
        double d[3], u[3], v[3], dd = 0, du = 0, dv = 0, cr[3], dot;
        for (int k = 0; k < 3; k++) {
            d[k] = pj[k] - pi[k];
            u[k] = pk[k] - pi[k];
            v[k] = pl[k] - pi[k];
            dd += d[k] * d[k];
            du += d[k] * u[k];
            dv += d[k] * v[k];
        }
        for (int k = 0; k < 3; k++) {
            u[k] -= du / dd * d[k];
            v[k] -= dv / dd * d[k];
        }
        cr[0] = u[1] * v[2] - u[2] * v[1];
        cr[1] = u[2] * v[0] - u[0] * v[2];
        cr[2] = u[0] * v[1] - u[1] * v[0];
        dot = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
        ang[e] = atan2(sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]), dot) *
                 (180.0 / 3.14159265358979323846);
    }
}

/* The histogram has every angle in its whole-degree bin: 2000 tets of random
 * shapes (separate vertices), checked against angles found another way
 * (angles within 1e-6 degree of a whole one, where rounding decides, left
 * out of the count on both sides), and a flat tet's 0 and 180 degrees in the
 * first and last bins. */
TEST(dihedral_histogram_bins_each_angle)
{
    enum { NT = 2000 };
    mesh_t *m = mesh_new(4 * NT, NT, 0);
    report_quality q;
    int64_t want[REPORT_HIST_BINS] = {0}, near_whole = 0;
    uint64_t s = 12345;
    ASSERT_TRUE(m);
    for (int t = 0; t < NT; t++) {
        double *x = m->xyz + 12 * (size_t)t, ang[6], vol, a[3], b[3], c[3];
        for (int i = 0; i < 12; i++) {
            s = s * 6364136223846793005ULL + 1442695040888963407ULL;
            x[i] = (double)(s >> 11) / 9007199254740992.0;
        }
        for (int d = 0; d < 3; d++) {
            a[d] = x[3 + d] - x[d];
            b[d] = x[6 + d] - x[d];
            c[d] = x[9 + d] - x[d];
        }
        vol = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
              a[2] * (b[0] * c[1] - b[1] * c[0]);
        for (int k = 0; k < 4; k++) /* positive: the scan's orientation of a lone tet */
            m->tets[4 * t + k] = 4 * t + (vol < 0 && k < 2 ? 1 - k : k);
        angles_atan2(x, ang);
        for (int e = 0; e < 6; e++) {
            double ae = ang[e];
            if (fabs(ae - floor(ae + 0.5)) < 1e-6)
                near_whole++;
            else
                want[(int)ae]++;
        }
    }
    ASSERT_OK(report_quality_compute(m, &q, NULL));
    ASSERT_EQ_INT(q.n_inverted, 0);
    {
        int64_t got = 0, total = 0;
        for (int b = 0; b < REPORT_HIST_BINS; b++) {
            total += q.hist[b];
            if (near_whole == 0)
                ASSERT_EQ_INT((int)q.hist[b], (int)want[b]);
            got += q.hist[b] == want[b];
        }
        ASSERT_EQ_INT((int)total, 6 * NT);
        ASSERT_EQ_INT((int)near_whole, 0); /* the seed gives none: the check is whole */
        ASSERT_EQ_INT((int)got, REPORT_HIST_BINS);
    }
    mesh_free(m);
    m = two_tets(0.0);
    ASSERT_TRUE(m);
    ASSERT_OK(report_quality_compute(m, &q, NULL));
    /* the regular tet: six 70.53 deg; the flat one: 0 deg at its base edges,
     * 180 at the apex edges (in the last bin) */
    ASSERT_EQ_INT((int)q.hist[70], 6);
    ASSERT_EQ_INT((int)q.hist[0], 3);
    ASSERT_EQ_INT((int)q.hist[REPORT_HIST_BINS - 1], 3);
    ASSERT_EQ_INT((int)(q.dih_max * 1e6), (int)(180.0 * 1e6));
    ASSERT_EQ_INT((int)(q.dih_min * 1e6), 0);
    mesh_free(m);
}

TEST_MAIN("outcome", T(worst_tet_and_centroid), T(bad_result_warned),
          T(good_result_quiet), T(surface_edges_bound_the_dihedral),
          T(dihedral_histogram_bins_each_angle))
