/* test_slide.c - sliding boundary: feature detection, projection, and the
 * optimizer keeping the shape, the regions and the locked vertices. */
#include "core/mesh_int.h"
#include "core/tet.h"
#include "geom/bderr_int.h"
#include "opt/slide.h"
#include "qdc.h"
#include "testlib.h"
#include "testmesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int on_cube_edge(const double *p)
{
    int extreme = 0;
    for (int k = 0; k < 3; k++)
        extreme += fabs(p[k]) < 1e-12 || fabs(p[k] - 1) < 1e-12;
    return extreme >= 2;
}

TEST(cube_features_are_its_12_edges_and_8_corners)
{
    int n = 4;
    mesh_t *m = tm_grid(n, 0);
    mesh_topo *tp = NULL;
    slide_ctx *s = NULL;
    int corners = 0, lines = 0, surface = 0;
    ASSERT_OK(mesh_topo_build(m, &tp, NULL));
    ASSERT_OK(slide_new(tp, m->xyz, 30.0, &s, NULL));
    /* 12 cube edges of n segments each */
    ASSERT_EQ_INT(slide_n_feature_edges(s), 12 * n);
    for (int32_t v = 0; v < m->nv; v++) {
        int k = slide_kind(s, v);
        const double *p = m->xyz + 3 * v;
        if (k == SLIDE_CORNER) {
            corners++;
            for (int c = 0; c < 3; c++)
                ASSERT_TRUE(fabs(p[c]) < 1e-12 || fabs(p[c] - 1) < 1e-12);
        } else if (k == SLIDE_LINE) {
            lines++;
            ASSERT_TRUE(on_cube_edge(p));
        } else if (k == SLIDE_SURFACE) {
            surface++;
            ASSERT_TRUE(!on_cube_edge(p));
        }
    }
    ASSERT_EQ_INT(corners, 8);
    ASSERT_EQ_INT(lines, 12 * (n - 1));
    ASSERT_EQ_INT(surface, 6 * (n - 1) * (n - 1));
    slide_free(s);
    mesh_topo_free(tp);
    mesh_free(m);
}

TEST(projection_onto_face_line_and_corner)
{
    int n = 2;
    mesh_t *m = tm_grid(n, 0);
    mesh_topo *tp = NULL;
    slide_ctx *s = NULL;
    /* vertex (0.5, 0.5, 0) is on the z = 0 face; (0.5, 0, 0) on an edge; (0,0,0) a corner
     */
    int32_t vf = 1 + 3 * 1, ve = 1, vc = 0;
    double p[3], q[3], g[3] = {1, 2, 3}, t[3];
    ASSERT_OK(mesh_topo_build(m, &tp, NULL));
    ASSERT_OK(slide_new(tp, m->xyz, 30.0, &s, NULL));
    ASSERT_EQ_INT(slide_kind(s, vf), SLIDE_SURFACE);
    ASSERT_EQ_INT(slide_kind(s, ve), SLIDE_LINE);
    ASSERT_EQ_INT(slide_kind(s, vc), SLIDE_CORNER);
    p[0] = 0.4;
    p[1] = 0.6;
    p[2] = 0.05;
    slide_project(s, vf, p, q);
    ASSERT_NEAR(q[0], 0.4, 1e-12);
    ASSERT_NEAR(q[1], 0.6, 1e-12);
    ASSERT_NEAR(q[2], 0.0, 1e-12);
    slide_tangent(s, vf, g, t);
    ASSERT_NEAR(t[2], 0.0, 1e-12);
    ASSERT_NEAR(t[0], 1.0, 1e-12);
    p[0] = 0.3;
    p[1] = 0.02;
    p[2] = -0.01;
    slide_project(s, ve, p, q);
    ASSERT_NEAR(q[0], 0.3, 1e-12);
    ASSERT_NEAR(q[1], 0.0, 1e-12);
    ASSERT_NEAR(q[2], 0.0, 1e-12);
    slide_tangent(s, ve, g, t);
    ASSERT_NEAR(t[0], 1.0, 1e-12);
    ASSERT_NEAR(t[1], 0.0, 1e-12);
    slide_project(s, vc, p, q);
    ASSERT_NEAR(q[0], 0.0, 0);
    slide_free(s);
    mesh_topo_free(tp);
    mesh_free(m);
}

/* a point projects onto the closest of several triangles */
TEST(bvh_picks_the_closest_triangle)
{
    double xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 2, 1, 0, 2, 0, 1, 2};
    int32_t tris[] = {0, 1, 2, 3, 4, 5};
    bderr_bvh *b = NULL;
    double p[3] = {0.2, 0.2, 1.2}, cp[3];
    int32_t tri = -1;
    ASSERT_OK(bderr_bvh_build(xyz, 6, tris, 2, &b, NULL));
    ASSERT_NEAR(bderr_bvh_closest(b, p, cp, &tri), 0.8, 1e-12);
    ASSERT_EQ_INT(tri, 1);
    ASSERT_NEAR(cp[2], 2.0, 1e-12);
    bderr_bvh_free(b);
}

static void slide_run(int with_region, mesh_t **out, mesh_t **orig, report_quality *q)
{
    int n = 6;
    mesh_t *m = tm_grid(n, with_region ? MESH_WITH_REGION : 0);
    opt_options o;
    /* perturb boundary vertices tangentially too: a face vertex moves in its plane */
    tm_perturb(m, n, 0.35, 41);
    for (int32_t v = 0; v < m->nv; v++) {
        double *p = m->xyz + 3 * v;
        int i = v % (n + 1);
        if (with_region && i == n / 2)
            p[0] = 0.5; /* interface vertices: perturbed within the plane x = 0.5 */
        int onface = -1, extreme = 0;
        for (int k = 0; k < 3; k++)
            if (p[k] == 0.0 || p[k] == 1.0) {
                extreme++;
                onface = k;
            }
        if (extreme == 1 && !(with_region && fabs(p[0] - 0.5) < 1e-12)) {
            p[(onface + 1) % 3] += 0.25 / n * sin(7.0 * v);
            p[(onface + 2) % 3] += 0.25 / n * cos(5.0 * v);
        }
    }
    *orig = mesh_dup(m);
    opt_defaults(&o);
    o.boundary = OPT_BOUNDARY_SLIDE;
    opt_run(m, &o, NULL, NULL);
    report_quality_compute(m, q, NULL);
    *out = m;
}

TEST(slide_keeps_the_cube_and_beats_fixed)
{
    mesh_t *m, *orig, *fx;
    report_quality qs, qf;
    opt_options o;
    bderr_result be;
    slide_run(0, &m, &orig, &qs);
    ASSERT_OK(bderr_meshes(m, orig, 20000, &be, NULL));
    ASSERT_TRUE(be.hausdorff_rel <= 1e-12);
    fx = mesh_dup(orig);
    opt_defaults(&o);
    o.boundary = OPT_BOUNDARY_FIXED;
    ASSERT_OK(opt_run(fx, &o, NULL, NULL));
    report_quality_compute(fx, &qf, NULL);
    ASSERT_TRUE(qs.q_mean > qf.q_mean);
    ASSERT_TRUE(qs.q_min >= qf.q_min);
    /* corners of the cube did not move */
    for (int32_t v = 0; v < m->nv; v++) {
        const double *p = orig->xyz + 3 * v;
        int corner = 1;
        for (int k = 0; k < 3; k++)
            corner &= p[k] == 0.0 || p[k] == 1.0;
        if (corner)
            for (int k = 0; k < 3; k++)
                ASSERT_TRUE(m->xyz[3 * v + k] == p[k]);
    }
    mesh_free(fx);
    mesh_free(orig);
    mesh_free(m);
}

TEST(slide_keeps_region_interfaces_and_tags)
{
    mesh_t *m, *orig;
    report_quality q;
    slide_run(1, &m, &orig, &q);
    ASSERT_TRUE(memcmp(m->region, orig->region, 4 * (size_t)m->nt) == 0);
    /* the grid's interface is the plane x = 0.5 (regions split at i < n/2) */
    int moved = 0;
    for (int32_t v = 0; v < m->nv; v++)
        if (orig->xyz[3 * v] == 0.5) {
            ASSERT_NEAR(m->xyz[3 * v], 0.5, 1e-12);
            moved += m->xyz[3 * v + 1] != orig->xyz[3 * v + 1];
        }
    ASSERT_TRUE(moved > 0); /* they slid within the interface */
    mesh_free(orig);
    mesh_free(m);
}

/* A freed vertex moves in space; with a bound it stays within the bound of
 * its input position (the Hausdorff bound holds through a rerun that frees
 * boundary vertices), without one it is an interior vertex. */
TEST(freed_vertices_keep_the_bound)
{
    int n = 2;
    mesh_t *m = tm_grid(n, 0);
    mesh_topo *tp = NULL;
    slide_ctx *s = NULL;
    int32_t vf = 1 + 3 * 1, vc = 0; /* (0.5, 0.5, 0) on a face, (0, 0, 0) a corner */
    double p[3] = {0.4, 0.6, 0.3}, q[3], d;
    ASSERT_OK(mesh_topo_build(m, &tp, NULL));
    ASSERT_OK(slide_new(tp, m->xyz, 30.0, &s, NULL));
    slide_set_bound(s, 0.01);
    slide_release(s, vf, 1); /* unbounded: only for interface vertices */
    slide_release(s, vc, 0);
    ASSERT_TRUE(slide_lifts(s, vf) && slide_lifts(s, vc));
    slide_project(s, vf, p, q);
    d = sqrt((q[0] - 0.5) * (q[0] - 0.5) + (q[1] - 0.5) * (q[1] - 0.5) + q[2] * q[2]);
    ASSERT_NEAR(d, 0.01, 1e-12);
    ASSERT_TRUE(q[2] > 0.009); /* it left the plane, in the direction asked */
    slide_project(s, vc, p, q);
    ASSERT_NEAR(sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]), 0.01, 1e-12);
    slide_free(s);
    ASSERT_OK(slide_new(tp, m->xyz, 30.0, &s, NULL));
    slide_release(s, vf, 0);
    ASSERT_EQ_INT(slide_kind(s, vf), SLIDE_INTERIOR);
    slide_project(s, vf, p, q);
    ASSERT_NEAR(q[2], 0.3, 0.0);
    slide_free(s);
    mesh_topo_free(tp);
    mesh_free(m);
}

/* An interface vertex on no boundary face released unbounded (a corner of a
 * tet left inverted on a folded interface) moves as an interior vertex even
 * under a bound; released bounded it stays within the bound. */
TEST(interface_vertex_released_unbounded_moves_freely)
{
    int n = 2;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION);
    mesh_topo *tp = NULL;
    slide_ctx *s = NULL;
    int32_t vi = 1 + 3 * (1 + 3 * 1); /* (0.5, 0.5, 0.5): on the interface x = 0.5 */
    double p[3] = {0.8, 0.4, 0.6}, q[3];
    ASSERT_TRUE(m);
    ASSERT_OK(mesh_topo_build(m, &tp, NULL));
    ASSERT_TRUE((tp->vflag[vi] & MESH_V_INTERFACE) && !(tp->vflag[vi] & MESH_V_BOUNDARY));
    for (int unbounded = 0; unbounded < 2; unbounded++) {
        ASSERT_OK(slide_new(tp, m->xyz, 30.0, &s, NULL));
        slide_set_bound(s, 0.01);
        slide_release(s, vi, unbounded);
        slide_project(s, vi, p, q);
        if (unbounded) {
            ASSERT_EQ_INT(slide_kind(s, vi), SLIDE_INTERIOR);
            for (int k = 0; k < 3; k++)
                ASSERT_NEAR(q[k], p[k], 0.0);
        } else {
            double d = sqrt((q[0] - 0.5) * (q[0] - 0.5) + (q[1] - 0.5) * (q[1] - 0.5) +
                            (q[2] - 0.5) * (q[2] - 0.5));
            ASSERT_NEAR(d, 0.01, 1e-12);
        }
        slide_free(s);
    }
    mesh_topo_free(tp);
    mesh_free(m);
}

/* Degenerate is as bad as inverted, pass by pass: small cubes whose every or
 * nearly every tet has four boundary corners, the face vertices slid within
 * their faces and the interior tangled, optimized in every boundary mode. No
 * tet that was usable comes out flat (degenerate, not inverted), the count
 * of unusable tets never rises, and a valid input keeps its worst tet. */
static int32_t count_bad(const mesh_t *m, uint8_t *flat)
{
    int32_t bad = 0;
    for (int32_t t = 0; t < m->nt; t++) {
        const int32_t *tt = m->tets + 4 * t;
        double v6 = geom_tet_vol6(m->xyz, tt), l2 = geom_tet_l2sum(m->xyz, tt);
        bad += geom_tet_bad_vl(v6, l2);
        if (flat)
            flat[t] = (uint8_t)geom_tet_degenerate(v6, l2);
    }
    return bad;
}

static void squash_faces(mesh_t *m, int n, double amp, uint64_t seed)
{
    uint64_t r = seed;
    for (int32_t v = 0; v < m->nv; v++) {
        double *p = m->xyz + 3 * v;
        int onface = -1, extreme = 0;
        for (int k = 0; k < 3; k++)
            if (p[k] == 0.0 || p[k] == 1.0) {
                extreme++;
                onface = k;
            }
        if (extreme == 1) {
            p[(onface + 1) % 3] += amp / n * tm_rand(&r);
            p[(onface + 2) % 3] += amp / n * tm_rand(&r);
        }
    }
}

TEST(no_tet_is_flattened_in_any_boundary_mode)
{
    static const opt_boundary modes[] = {OPT_BOUNDARY_SLIDE, OPT_BOUNDARY_FIXED,
                                         OPT_BOUNDARY_LSQ};
    int tangled = 0, runs = 0;
    for (int n = 2; n <= 3; n++)
        for (uint64_t seed = 1; seed <= 5; seed++)
            for (size_t k = 0; k < sizeof modes / sizeof modes[0]; k++) {
                mesh_t *m = tm_grid(n, 0), *in;
                uint8_t *flat_in, *flat_out;
                report_quality q0, q1;
                opt_options o;
                int32_t bad0, bad1;
                ASSERT_TRUE(m != NULL);
                tm_perturb(m, n, 1.1, seed);
                squash_faces(m, n, 0.9, seed * 7919);
                in = mesh_dup(m);
                flat_in = calloc((size_t)m->nt, 1);
                flat_out = calloc((size_t)m->nt, 1);
                ASSERT_TRUE(in && flat_in && flat_out);
                bad0 = count_bad(in, flat_in);
                report_quality_compute(in, &q0, NULL);
                opt_defaults(&o);
                o.boundary = modes[k];
                ASSERT_OK(opt_run(m, &o, NULL, NULL));
                bad1 = count_bad(m, flat_out);
                report_quality_compute(m, &q1, NULL);
                for (int32_t t = 0; t < m->nt; t++)
                    ASSERT_TRUE(!flat_out[t] || flat_in[t]);
                ASSERT_TRUE(bad1 <= bad0);
                if (bad0 == 0)
                    ASSERT_TRUE(q1.q_min >= q0.q_min);
                tangled += bad0 > 0;
                runs++;
                free(flat_out);
                free(flat_in);
                mesh_free(in);
                mesh_free(m);
            }
    ASSERT_EQ_INT(runs, 30);
    ASSERT_TRUE(tangled >= 5); /* the cases do untangle, not only smooth */
}

TEST_MAIN("slide", T(freed_vertices_keep_the_bound),
          T(interface_vertex_released_unbounded_moves_freely),
          T(no_tet_is_flattened_in_any_boundary_mode),
          T(cube_features_are_its_12_edges_and_8_corners),
          T(projection_onto_face_line_and_corner), T(bvh_picks_the_closest_triangle),
          T(slide_keeps_the_cube_and_beats_fixed),
          T(slide_keeps_region_interfaces_and_tags))
