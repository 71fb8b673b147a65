/* test_orient.c - the orientation of a mesh from its connectivity (core/mesh.h
 * mesh_orient, mesh_topo_build, the faces a run hands to the report, and
 * the quality report that uses them): tets
 * written in either vertex order are valid when their geometry agrees with
 * their component's orientation, whatever the file's vertex order. */
#include "core/mesh_int.h"
#include "qdc.h"
#include "testlib.h"
#include "testmesh.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

static double det4(const mesh_t *m, const int32_t *t)
{
    const double *a = m->xyz + 3 * (size_t)t[0], *b = m->xyz + 3 * (size_t)t[1];
    const double *c = m->xyz + 3 * (size_t)t[2], *d = m->xyz + 3 * (size_t)t[3];
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
        w[k] = d[k] - a[k];
    }
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
           u[2] * (v[0] * w[1] - v[1] * w[0]);
}

static void swap01(int32_t *t)
{
    int32_t x = t[0];
    t[0] = t[1];
    t[1] = x;
}

/* Sort each tet's vertices by index, as DOLFIN writes them. */
static void sort_tets(mesh_t *m)
{
    for (int32_t t = 0; t < m->nt; t++) {
        int32_t *v = m->tets + 4 * (size_t)t;
        for (int i = 1; i < 4; i++)
            for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
                int32_t x = v[j];
                v[j] = v[j - 1];
                v[j - 1] = x;
            }
    }
}

TEST(two_tets_either_vertex_order)
{
    /* tets (0,1,2,3) and (1,0,2,4) share face (0,1,2) from opposite sides */
    static const double xyz[5][3] = {
        {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, 1}, {0.3, 0.3, -1}};
    mesh_t *m = mesh_new(5, 2, 0);
    uint8_t flip[2];
    mesh_orientation o;
    memcpy(m->xyz, xyz, sizeof xyz);
    int32_t t[8] = {0, 1, 2, 3, 1, 0, 2, 4};
    memcpy(m->tets, t, sizeof t);
    ASSERT_TRUE(det4(m, m->tets) > 0 && det4(m, m->tets + 4) > 0);
    ASSERT_OK(mesh_orient(m, flip, &o, NULL));
    ASSERT_EQ_INT(o.components, 1);
    ASSERT_EQ_INT(o.flipped, 0);
    ASSERT_EQ_INT(o.inverted, 0);
    /* the second written the other way: still valid, one flip */
    swap01(m->tets + 4);
    ASSERT_OK(mesh_orient(m, flip, &o, NULL));
    ASSERT_EQ_INT(flip[0], 0);
    ASSERT_EQ_INT(flip[1], 1);
    ASSERT_EQ_INT(o.flipped, 1);
    ASSERT_EQ_INT(o.inverted, 0);
    /* the apex of the second pushed through the shared face: now it is
     * inverted, whichever way it is written */
    m->xyz[14] = 1.0;
    ASSERT_OK(mesh_orient(m, flip, &o, NULL));
    ASSERT_EQ_INT(o.inverted, 1);
    swap01(m->tets + 4);
    ASSERT_OK(mesh_orient(m, flip, &o, NULL));
    ASSERT_EQ_INT(o.inverted, 1);
    mesh_free(m);
}

TEST(dolfin_sorted_grid_is_valid)
{
    mesh_t *m = tm_grid(4, 0);
    uint8_t *flip = calloc((size_t)m->nt, 1);
    mesh_orientation o;
    mesh_check c;
    int32_t nneg = 0;
    sort_tets(m);
    for (int32_t t = 0; t < m->nt; t++)
        nneg += det4(m, m->tets + 4 * (size_t)t) < 0;
    ASSERT_TRUE(nneg > 0 && nneg < m->nt); /* mixed orientation indeed */
    ASSERT_OK(mesh_orient(m, flip, &o, NULL));
    ASSERT_EQ_INT(o.components, 1);
    ASSERT_EQ_INT(o.inverted, 0);
    ASSERT_EQ_INT(o.flipped, nneg);
    for (int32_t t = 0; t < m->nt; t++)
        ASSERT_EQ_INT(flip[t], det4(m, m->tets + 4 * (size_t)t) < 0);
    ASSERT_OK(mesh_validate(m, &c, NULL));
    ASSERT_EQ_INT(c.n_inverted, 0);
    ASSERT_EQ_INT(c.n_flipped, nneg);
    /* the optimizer's oriented copy is positive everywhere */
    {
        mesh_topo *tp = NULL;
        ASSERT_OK(mesh_topo_build(m, &tp, NULL));
        ASSERT_EQ_INT(mesh_count_inverted(tp, m->xyz), 0);
        ASSERT_EQ_INT(tp->orientation.flipped, nneg);
        /* boundary faces point out: 12 n^2 of them, as for the unsorted grid */
        ASSERT_EQ_INT(tp->nbf, 12 * 16);
        mesh_topo_free(tp);
    }
    /* the report counts no inverted tet and the same quality as unsorted */
    {
        mesh_t *g = tm_grid(4, 0);
        report_quality qs, qg;
        ASSERT_OK(report_quality_compute(m, &qs, NULL));
        ASSERT_OK(report_quality_compute(g, &qg, NULL));
        ASSERT_EQ_INT(qs.n_inverted, 0);
        ASSERT_NEAR(qs.q_mean, qg.q_mean, 1e-12);
        ASSERT_NEAR(qs.q_min, qg.q_min, 1e-12);
        ASSERT_NEAR(qs.dih_min, qg.dih_min, 1e-9);
        mesh_free(g);
    }
    /* mesh_reorient writes them back positive */
    ASSERT_OK(mesh_reorient(m, &o, NULL));
    for (int32_t t = 0; t < m->nt; t++)
        ASSERT_TRUE(det4(m, m->tets + 4 * (size_t)t) > 0);
    free(flip);
    mesh_free(m);
}

TEST(all_inverted_components_each_flip_whole)
{
    /* two grids side by side, not touching: two components; the second has
     * every tet written negative */
    mesh_t *g = tm_grid(2, 0);
    mesh_t *m = mesh_new(2 * g->nv, 2 * g->nt, 0);
    uint8_t *flip = calloc((size_t)m->nt, 1);
    mesh_orientation o;
    for (int32_t v = 0; v < g->nv; v++)
        for (int k = 0; k < 3; k++) {
            m->xyz[3 * v + k] = g->xyz[3 * v + k];
            m->xyz[3 * (g->nv + v) + k] = g->xyz[3 * v + k] + (k == 0 ? 5.0 : 0.0);
        }
    for (int32_t i = 0; i < 4 * g->nt; i++) {
        m->tets[i] = g->tets[i];
        m->tets[4 * g->nt + i] = g->tets[i] + g->nv;
    }
    for (int32_t t = g->nt; t < m->nt; t++)
        swap01(m->tets + 4 * (size_t)t);
    ASSERT_OK(mesh_orient(m, flip, &o, NULL));
    ASSERT_EQ_INT(o.components, 2);
    ASSERT_EQ_INT(o.flipped, g->nt);
    ASSERT_EQ_INT(o.inverted, 0);
    for (int32_t t = 0; t < m->nt; t++)
        ASSERT_EQ_INT(flip[t], t >= g->nt);
    free(flip);
    mesh_free(m);
    mesh_free(g);
}

TEST(tangled_component_keeps_its_majority)
{
    /* a grid with 3 interior vertices pushed far: the tets around them turn
     * over; the orientation stays the majority's and they count as inverted,
     * whether the file writes the tets sorted or not */
    mesh_t *m = tm_grid(3, 0);
    uint8_t *flip = calloc((size_t)m->nt, 1);
    mesh_orientation o, os;
    int32_t nneg = 0;
    tm_perturb(m, 3, 0.2, 3); /* a valid, irregular grid first */
    m->xyz[3 * 21] += 0.9;    /* vertex (1,1,1) of the 4x4x4 lattice */
    for (int32_t t = 0; t < m->nt; t++)
        nneg += det4(m, m->tets + 4 * (size_t)t) < 0;
    ASSERT_TRUE(nneg > 0);
    ASSERT_OK(mesh_orient(m, flip, &o, NULL));
    ASSERT_EQ_INT(o.inverted, nneg);
    sort_tets(m);
    ASSERT_OK(mesh_orient(m, flip, &os, NULL));
    ASSERT_EQ_INT(os.inverted, nneg);
    free(flip);
    mesh_free(m);
}

/* A solid Moebius band: k triangular prisms in a ring, each split into 3
 * tets, the last glued to the first with a reflection of the triangle. Every
 * face belongs to at most two tets, but no orientation fits all of them. */
TEST(non_orientable_connectivity_is_an_error)
{
    enum { K = 4 };
    mesh_t *m = mesh_new(3 * K, 3 * K, 0);
    qdc_error e;
    uint8_t flip[3 * K];
    mesh_orientation o;
    uint64_t seed = 7;
    for (int32_t v = 0; v < m->nv; v++)
        for (int k = 0; k < 3; k++)
            m->xyz[3 * v + k] = tm_rand(&seed);
    for (int i = 0; i < K; i++) {
        int32_t a = 3 * i, b = 3 * i + 1, c = 3 * i + 2;
        int32_t a2 = 3 * ((i + 1) % K), b2 = a2 + 1, c2 = a2 + 2;
        if (i == K - 1) { /* the twist: a and b trade places */
            int32_t x = a2;
            a2 = b2;
            b2 = x;
        }
        int32_t t[12] = {a, b, c, a2, b, c, a2, b2, c, a2, b2, c2};
        memcpy(m->tets + 12 * i, t, sizeof t);
    }
    qdc_error_clear(&e);
    ASSERT_EQ_INT(mesh_orient(m, flip, &o, &e), QDC_EMESH);
    ASSERT_TRUE(strstr(e.msg, "cannot be oriented") != NULL);
    ASSERT_TRUE(e.index >= 0 && e.index < m->nt);
    ASSERT_EQ_INT(mesh_validate(m, NULL, NULL), QDC_EMESH);
    {
        mesh_topo *tp = NULL;
        ASSERT_EQ_INT(mesh_topo_build(m, &tp, NULL), QDC_EMESH);
        ASSERT_TRUE(tp == NULL);
    }
    /* without the twist the same ring is fine */
    for (int k = 0; k < 12; k++)
        m->tets[12 * (K - 1) + k] =
            (int32_t[]){9, 10, 11, 0, 10, 11, 0, 1, 11, 0, 1, 2}[k];
    ASSERT_OK(mesh_orient(m, flip, &o, NULL));
    ASSERT_EQ_INT(o.components, 1);
    mesh_free(m);
}

/* mesh_topo_build takes a shortcut when every neighbour pair is oriented
 * alike and every tet has one sign: the same flips and inverted count as the
 * walk (mesh_orient), on meshes that take it and on meshes that do not. */
TEST(topo_shortcut_agrees_with_the_walk)
{
    for (int c = 0; c < 5; c++) {
        mesh_t *m = tm_grid(3, 0);
        uint8_t *flip = calloc((size_t)m->nt, 1);
        mesh_orientation o;
        mesh_topo *tp = NULL;
        tm_perturb(m, 3, 0.2, 5);
        if (c == 1 || c == 4) /* every tet written negative */
            for (int32_t t = 0; t < m->nt; t++)
                swap01(m->tets + 4 * (size_t)t);
        if (c == 2) /* DOLFIN's order: mixed signs */
            sort_tets(m);
        if (c == 3 || c == 4) /* a tangle: two signs */
            m->xyz[3 * 21] += 0.9;
        ASSERT_OK(mesh_orient(m, flip, &o, NULL));
        ASSERT_OK(mesh_topo_build(m, &tp, NULL));
        ASSERT_EQ_INT(tp->orientation.flipped, o.flipped);
        ASSERT_EQ_INT(mesh_count_inverted(tp, m->xyz), o.inverted);
        if (c == 1)
            ASSERT_EQ_INT(o.flipped, m->nt);
        if (c >= 3)
            ASSERT_TRUE(o.inverted > 0);
        mesh_topo_free(tp);
        free(flip);
        mesh_free(m);
    }
}

/* The faces a run hands out (opt_run_faces: found on its renumbered copy,
 * mapped back) are those the report would find itself: mesh_orient's flips,
 * and the same quality and boundary distances (every field, to the bit) for
 * the input and for the result, in either vertex order, on a tangle, with
 * the vertices numbered against the space-filling curve. */
TEST(run_faces_are_the_reports_own)
{
    for (int c = 0; c < 4; c++) {
        mesh_t *m = tm_grid(4, 0), *in;
        uint8_t *flip = calloc((size_t)m->nt, 1);
        mesh_orientation o;
        mesh_faces *f = NULL;
        report_quality qa, qb;
        bderr_result ba, bb;
        opt_result res;
        opt_options opts;
        tm_perturb(m, 4, 0.2, 7);
        if (c == 1) /* DOLFIN's order: mixed vertex orders */
            sort_tets(m);
        if (c == 2) /* every tet written negative */
            for (int32_t t = 0; t < m->nt; t++)
                swap01(m->tets + 4 * (size_t)t);
        if (c == 3) /* a tangle */
            m->xyz[3 * 31] += 0.3;
        for (int32_t t = 0; c == 3 && t < m->nt / 2; t++) { /* tets reversed */
            int32_t *a = m->tets + 4 * (size_t)t,
                    *b = m->tets + 4 * (size_t)(m->nt - 1 - t);
            for (int k = 0; k < 4; k++) {
                int32_t x = a[k];
                a[k] = b[k];
                b[k] = x;
            }
        }
        in = mesh_dup(m);
        opt_defaults(&opts);
        ASSERT_OK(opt_run_faces(m, &opts, &res, &f, NULL));
        ASSERT_TRUE(f != NULL);
        ASSERT_OK(mesh_orient(in, flip, &o, NULL));
        ASSERT_EQ_INT(f->nt, m->nt);
        ASSERT_TRUE(memcmp(f->flip, flip, (size_t)m->nt) == 0);
        for (int side = 0; side < 2; side++) {
            const mesh_t *q = side ? m : in;
            ASSERT_OK(report_quality_compute(q, &qa, NULL));
            ASSERT_OK(report_quality_faces(q, f, &qb, NULL));
            ASSERT_TRUE(memcmp(&qa, &qb, sizeof qa) == 0);
        }
        memset(&ba, 0, sizeof ba);
        memset(&bb, 0, sizeof bb);
        ASSERT_OK(bderr_meshes(m, in, 5000, &ba, NULL));
        ASSERT_OK(bderr_meshes_faces(m, in, f, 5000, &bb, NULL));
        ASSERT_EQ_INT(bb.ntri_a, f->ntri);
        ASSERT_TRUE(memcmp(&ba, &bb, sizeof ba) == 0);
        ASSERT_TRUE(ba.n_samples > 0 && bb.ntri_b == f->ntri);
        mesh_faces_free(f);
        free(flip);
        mesh_free(in);
        mesh_free(m);
    }
}

/* Three grids side by side, not touching (three components): the first
 * tangled, the second written negative and tangled, the third plain. */
static mesh_t *three_grids(void)
{
    mesh_t *g = tm_grid(3, 0);
    mesh_t *m = mesh_new(3 * g->nv, 3 * g->nt, 0);
    tm_perturb(g, 3, 0.2, 11);
    for (int c = 0; c < 3; c++) {
        for (int32_t v = 0; v < g->nv; v++)
            for (int k = 0; k < 3; k++)
                m->xyz[3 * (c * g->nv + v) + k] =
                    g->xyz[3 * v + k] + (k == 0 ? 3.0 * c : 0);
        for (int32_t i = 0; i < 4 * g->nt; i++)
            m->tets[4 * c * g->nt + i] = g->tets[i] + c * g->nv;
    }
    for (int32_t t = g->nt; t < 2 * g->nt; t++)
        swap01(m->tets + 4 * (size_t)t);
    m->xyz[3 * 21] += 0.9;
    m->xyz[3 * (g->nv + 42) + 1] -= 0.8;
    mesh_free(g);
    return m;
}

/* mesh_orient finds the components and each tet's orientation in parallel
 * (a union-find with parities): the same flips and counts at 1 and 2 threads
 * as the serial walk, on three pieces (one tangled, one written negative and
 * tangled), with tets written the other way here and there, and sorted as
 * DOLFIN writes them. */
TEST(parallel_orientation_agrees_with_the_walk)
{
    for (int c = 0; c < 3; c++) {
        mesh_t *m = three_grids();
        uint8_t *fw = calloc((size_t)m->nt, 1), *fp = calloc((size_t)m->nt, 1);
        mesh_orientation ow, op;
        if (c == 1)
            for (int32_t t = 5; t < m->nt; t += 7)
                swap01(m->tets + 4 * (size_t)t);
        if (c == 2)
            sort_tets(m);
        ASSERT_OK(mesh_orient_walk(m, fw, &ow, NULL));
        ASSERT_EQ_INT(ow.components, 3);
        ASSERT_TRUE(ow.inverted > 0);
        for (int n = 1; n <= 2; n++) {
            omp_set_num_threads(n);
            memset(fp, 7, (size_t)m->nt);
            ASSERT_OK(mesh_orient(m, fp, &op, NULL));
            ASSERT_TRUE(memcmp(fw, fp, (size_t)m->nt) == 0);
            ASSERT_EQ_INT(op.components, ow.components);
            ASSERT_EQ_INT(op.flipped, ow.flipped);
            ASSERT_EQ_INT(op.inverted, ow.inverted);
        }
        omp_set_num_threads(omp_get_num_procs());
        if (c == 0)
            ASSERT_EQ_INT(ow.flipped, m->nt / 3);
        free(fw);
        free(fp);
        mesh_free(m);
    }
}

/* The quality report (its scan of the tets in ranges, its surface angles)
 * has the same bits at 1 and 2 threads, on a tangle of three pieces. */
TEST(report_same_at_any_thread_count)
{
    mesh_t *m = three_grids();
    report_quality q1, q2;
    omp_set_num_threads(1);
    ASSERT_OK(report_quality_compute(m, &q1, NULL));
    omp_set_num_threads(2);
    ASSERT_OK(report_quality_compute(m, &q2, NULL));
    omp_set_num_threads(omp_get_num_procs());
    ASSERT_TRUE(memcmp(&q1, &q2, sizeof q1) == 0);
    ASSERT_TRUE(q1.n_inverted > 0);
    ASSERT_TRUE(q1.n_surf_lt5 >= 0 && q1.surf_angle_min > 0 && q1.surf_angle_min < 360);
    mesh_free(m);
}

TEST_MAIN("orient", T(two_tets_either_vertex_order), T(dolfin_sorted_grid_is_valid),
          T(all_inverted_components_each_flip_whole),
          T(tangled_component_keeps_its_majority),
          T(non_orientable_connectivity_is_an_error),
          T(topo_shortcut_agrees_with_the_walk), T(run_faces_are_the_reports_own),
          T(parallel_orientation_agrees_with_the_walk),
          T(report_same_at_any_thread_count))
