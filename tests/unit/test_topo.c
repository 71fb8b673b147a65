/* test_topo.c - the topology layer: exact orientation, the mutable mesh and its
 * journal, edge removal, the 2-3 flip, their constraints, and the driver. */
#include "core/mesh_int.h"
#include "core/tet.h"
#include "geom/metric_int.h"
#include "opt/opt.h"
#include "testlib.h"

#include "testmesh.h"
#include "topo/contract.h"
#include "topo/exact.h"
#include "topo/flip.h"
#include "topo/insert.h"
#include "topo/split.h"
#include "topo/tmesh.h"
#include "topo/topo.h"
#include <omp.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

/* Points exactly on the plane x = y with one of them moved off it by k units in
 * the last place of its x: the exact sign is sign(k) times the sign of the
 * derivative along x, which a move of 1 (well conditioned) shows. */
TEST(orient3d_exact_near_coplanar)
{
    uint64_t s = 12345;
    int naive_wrong = 0, trials = 0;

    for (int it = 0; it < 2000; it++) {
        double p[4][3], ta, g;
        for (int v = 0; v < 4; v++) {
            double t = 0.5 + 0.5 * tm_rand(&s);
            p[v][0] = t;
            p[v][1] = t;
            p[v][2] = 0.5 + 0.5 * tm_rand(&s);
        }
        ASSERT_EQ_INT(exact_orient3d(p[0], p[1], p[2], p[3]), 0);
        ta = p[0][0];
        p[0][0] = ta + 1.0;
        g = geom_tet_vol6(&p[0][0], (const int32_t[4]){0, 1, 2, 3});
        p[0][0] = ta;
        if (fabs(g) < 1e-3)
            continue;
        for (int k = -3; k <= 3; k++) {
            double x = ta, naive;
            int want;
            if (k == 0)
                continue;
            for (int r = 0; r < abs(k); r++)
                x = nextafter(x, k > 0 ? 2.0 : -2.0);
            p[0][0] = x;
            want = (k > 0) == (g > 0) ? 1 : -1;
            ASSERT_EQ_INT(exact_orient3d(p[0], p[1], p[2], p[3]), want);
            naive = geom_tet_vol6(&p[0][0], (const int32_t[4]){0, 1, 2, 3});
            naive_wrong += !(naive * want > 0);
            trials++;
        }
        p[0][0] = ta;
    }
    ASSERT_TRUE(trials > 1000);
    /* the case is hard: the plain determinant gets many of them wrong */
    ASSERT_TRUE(naive_wrong > trials / 10);
}

/* a, b on the z axis; n ring points around it in z = 0 at the angles deg
 * (degrees, counterclockwise from +z; NULL: evenly spaced); the n tets (a, b,
 * p_k, p_k+1) of one tag. */
static tmesh *ring_mesh_at(int n, const double *deg, double za, double zb,
                           const int32_t *tags)
{
    double x[3 * 12];
    int32_t tv[4 * 10];
    tmesh *tm = NULL;

    x[0] = 0;
    x[1] = 0;
    x[2] = za;
    x[3] = 0;
    x[4] = 0;
    x[5] = zb;
    for (int k = 0; k < n; k++) {
        double r = deg ? deg[k] * PI / 180 : 2 * PI * k / n;
        x[3 * (2 + k)] = cos(r);
        x[3 * (2 + k) + 1] = sin(r);
        x[3 * (2 + k) + 2] = 0;
        tv[4 * k] = 0;
        tv[4 * k + 1] = 1;
        tv[4 * k + 2] = 2 + k;
        tv[4 * k + 3] = 2 + (k + 1) % n;
    }
    if (tmesh_new(n + 2, x, n, tv, tags, NULL, &tm, NULL) != QDC_OK)
        return NULL;
    return tm;
}

static tmesh *ring_mesh(int n, double za, double zb, const int32_t *tags)
{
    return ring_mesh_at(n, NULL, za, zb, tags);
}

static double total_vol6(const tmesh *tm)
{
    double v = 0;
    for (int32_t t = 0; t < tm->hi; t++)
        if (tm->tv[4 * t] >= 0)
            v += geom_tet_vol6(tm->xyz, tm->tv + 4 * t);
    return v;
}

static int consistent(const tmesh *tm)
{
    char why[128];
    int32_t ninv;
    int r = tmesh_check(tm, &ninv, why, sizeof why);
    if (r != 0)
        printf("  check: %s\n", why);
    return r == 0 && ninv == 0;
}

/* The 3-ring with exactly representable corners: the bipyramid over the
 * triangle (1,0) (-0.5,0.75) (-0.5,-0.75) (area 9/8) of height 2, 6V = 4.5. */
TEST(edge_removal_3_2_keeps_volume)
{
    double x[5 * 3] = {0, 0, -1, 0, 0, 1, 1, 0, 0, -0.5, 0.75, 0, -0.5, -0.75, 0};
    int32_t tv[12] = {0, 1, 2, 3, 0, 1, 3, 4, 0, 1, 4, 2};
    tmesh *tm = NULL;
    flip_cand c;
    int applied = 0, e01 = 0;

    ASSERT_OK(tmesh_new(5, x, 3, tv, NULL, NULL, &tm, NULL));
    ASSERT_TRUE(consistent(tm));
    ASSERT_NEAR(total_vol6(tm), 4.5, 0);
    ASSERT_EQ_INT(tm->econs[0] >> e01 & 1, 0); /* the axis is inside */
    ASSERT_EQ_INT(flip_edge_eval(tm, 0, e01, 10, 0.0, -INFINITY, &c), 1);
    ASSERT_EQ_INT(c.nold, 3);
    ASSERT_EQ_INT(c.nnew, 2);
    ASSERT_OK(tmesh_replace(tm, c.old, c.nold, (const int32_t(*)[4])c.newt, c.nnew, NULL,
                            &applied));
    ASSERT_EQ_INT(applied, 1);
    tmesh_commit(tm);
    ASSERT_EQ_INT(tm->nlive, 2);
    ASSERT_TRUE(consistent(tm));
    ASSERT_NEAR(geom_tet_vol6(x, c.newt[0]), 2.25, 0); /* each half: height 1 */
    ASSERT_NEAR(geom_tet_vol6(x, c.newt[1]), 2.25, 0);
    ASSERT_NEAR(total_vol6(tm), 4.5, 0);
    /* the outer faces kept their boundary bits; the shared face is inside */
    for (int32_t t = 0; t < tm->hi; t++)
        if (tm->tv[4 * t] >= 0) {
            int f = tmesh_local(tm, t, 0) >= 0 ? tmesh_local(tm, t, 0)
                                               : tmesh_local(tm, t, 1);
            ASSERT_EQ_INT(tm->fcons[t], 15 & ~(1 << f));
        }
    tmesh_free(tm);
}

/* Rings of 3..8 around the axis: 2(n-2) tets out, the volume of the
 * bipyramid over the regular n-gon (area n/2 sin(2pi/n), height 2). */
TEST(edge_removal_rings_3_to_8)
{
    for (int n = 3; n <= 8; n++) {
        tmesh *tm = ring_mesh(n, -1, 1, NULL);
        double v6 = 2.0 * n * sin(2 * PI / n); /* 6 * area * 2 / 3 */
        flip_cand c;
        int applied = 0;
        ASSERT_TRUE(tm);
        ASSERT_NEAR(total_vol6(tm), v6, 1e-13);
        ASSERT_EQ_INT(flip_edge_eval(tm, 0, 0, 10, 0.0, -INFINITY, &c), 1);
        ASSERT_EQ_INT(c.nold, n);
        ASSERT_EQ_INT(c.nnew, 2 * (n - 2));
        ASSERT_OK(tmesh_replace(tm, c.old, c.nold, (const int32_t(*)[4])c.newt, c.nnew,
                                NULL, &applied));
        ASSERT_EQ_INT(applied, 1);
        tmesh_commit(tm);
        ASSERT_EQ_INT(tm->nlive, 2 * (n - 2));
        ASSERT_TRUE(consistent(tm));
        ASSERT_NEAR(total_vol6(tm), v6, 1e-13);
        /* a ring larger than allowed is refused */
        tmesh_free(tm);
        tm = ring_mesh(n, -1, 1, NULL);
        ASSERT_EQ_INT(flip_edge_eval(tm, 0, 0, n - 1, 0.0, -INFINITY, &c), 0);
        tmesh_free(tm);
    }
}

/* Two tets on the triangle (0,0,0) (1,0,0) (0,1,0), apexes above and below:
 * three tets around the new edge, volumes 1/6 (d) + 1/6 (e) in all. */
TEST(flip_2_3)
{
    double x[5 * 3] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.25, 0.25, 1, 0.25, 0.25, -1};
    int32_t tv[8] = {0, 1, 2, 3, 0, 2, 1, 4};
    tmesh *tm = NULL;
    flip_cand c;
    int applied = 0, f = 3; /* face opposite vertex 3 of tet 0 */

    ASSERT_OK(tmesh_new(5, x, 2, tv, NULL, NULL, &tm, NULL));
    ASSERT_TRUE(consistent(tm));
    ASSERT_EQ_INT(tm->adj[4 * 0 + f] / 4, 1);
    ASSERT_EQ_INT(flip_23_eval(tm, 0, f, 0.0, -INFINITY, &c), 1);
    ASSERT_EQ_INT(c.nnew, 3);
    ASSERT_OK(
        tmesh_replace(tm, c.old, 2, (const int32_t(*)[4])c.newt, 3, NULL, &applied));
    ASSERT_EQ_INT(applied, 1);
    tmesh_commit(tm);
    ASSERT_EQ_INT(tm->nlive, 3);
    ASSERT_TRUE(consistent(tm));
    ASSERT_NEAR(total_vol6(tm), 2.0, 1e-15);
    for (int j = 0; j < 3; j++) { /* each holds the new edge 3-4 */
        int has = 0;
        for (int s = 0; s < 4; s++)
            has += c.newt[j][s] == 3 || c.newt[j][s] == 4;
        ASSERT_EQ_INT(has, 2);
    }
    /* the same face between two tags is an interface: refused */
    tmesh_free(tm);
    ASSERT_OK(tmesh_new(5, x, 2, tv, (const int32_t[2]){1, 2}, NULL, &tm, NULL));
    ASSERT_EQ_INT(tm->fcons[0] >> f & 1, 1);
    ASSERT_EQ_INT(flip_23_eval(tm, 0, f, 0.0, -INFINITY, &c), 0);
    /* a boundary face is refused */
    ASSERT_EQ_INT(flip_23_eval(tm, 0, 0, 0.0, -INFINITY, &c), 0);
    tmesh_free(tm);
}

/* Multi-face removal undoes an edge removal: the pentagon's bipyramid cut into
 * 6 tets (3 faces between the apexes) goes back to the 5 tets around the axis. */
TEST(multiface_removal_restores_the_ring)
{
    tmesh *tm = ring_mesh(5, -1, 1, NULL);
    double v6 = 2.0 * 5 * sin(2 * PI / 5);
    flip_cand c;
    int applied = 0, found = 0;

    ASSERT_TRUE(tm);
    ASSERT_EQ_INT(flip_edge_eval(tm, 0, 0, 10, 0.0, -INFINITY, &c), 1);
    ASSERT_OK(tmesh_replace(tm, c.old, c.nold, (const int32_t(*)[4])c.newt, c.nnew, NULL,
                            &applied));
    tmesh_commit(tm);
    ASSERT_EQ_INT(tm->nlive, 6);
    for (int32_t t = 0; t < tm->hi && !found; t++) {
        int la = tmesh_local(tm, t, 0);
        if (tm->tv[4 * t] < 0 || la < 0)
            continue;
        ASSERT_EQ_INT(flip_multiface_eval(tm, t, la, 10, 0.0, -INFINITY, &c), 1);
        found = 1;
    }
    ASSERT_EQ_INT(found, 1);
    ASSERT_EQ_INT(c.kind, FLIP_MULTIFACE);
    ASSERT_EQ_INT(c.nold, 6);
    ASSERT_EQ_INT(c.nnew, 5);
    ASSERT_OK(tmesh_replace(tm, c.old, c.nold, (const int32_t(*)[4])c.newt, c.nnew, NULL,
                            &applied));
    ASSERT_EQ_INT(applied, 1);
    tmesh_commit(tm);
    ASSERT_EQ_INT(tm->nlive, 5);
    ASSERT_TRUE(consistent(tm));
    ASSERT_NEAR(total_vol6(tm), v6, 1e-13);
    for (int32_t t = 0; t < tm->hi; t++) /* every tet has the axis again */
        if (tm->tv[4 * t] >= 0)
            ASSERT_TRUE(tmesh_local(tm, t, 0) >= 0 && tmesh_local(tm, t, 1) >= 0);
    /* on a boundary face there is nothing across: refused */
    for (int32_t t = 0; t < tm->hi; t++)
        for (int f = 0; f < 4; f++)
            if (tm->tv[4 * t] >= 0 && tm->adj[4 * t + f] < 0)
                ASSERT_EQ_INT(flip_multiface_eval(tm, t, f, 10, 0.0, -INFINITY, &c), 0);
    tmesh_free(tm);
}

/* A face of three tets (the triangle 0 1 2 with apexes 3, 4 and 5) and a tet
 * given twice are not a tmesh: QDC_EMESH naming a tet, nothing allocated. */
TEST(tmesh_refuses_a_face_of_three_tets)
{
    double x[6 * 3] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 1, 1, 1};
    int32_t three[12] = {0, 1, 2, 3, 0, 2, 1, 4, 0, 1, 2, 5};
    int32_t twice[8] = {0, 1, 2, 3, 0, 1, 2, 3};
    tmesh *tm = NULL;
    qdc_error err;

    memset(&err, 0, sizeof err);
    ASSERT_EQ_INT(tmesh_new(6, x, 3, three, NULL, NULL, &tm, &err), QDC_EMESH);
    ASSERT_TRUE(tm == NULL);
    ASSERT_TRUE(strstr(err.msg, "shared by 3 tets") != NULL);
    ASSERT_TRUE(err.index >= 0 && err.index < 3);
    memset(&err, 0, sizeof err);
    ASSERT_EQ_INT(tmesh_new(6, x, 2, twice, NULL, NULL, &tm, &err), QDC_EMESH);
    ASSERT_TRUE(tm == NULL);
    ASSERT_TRUE(strstr(err.msg, "duplicate tet") != NULL);
    ASSERT_EQ_INT(err.index, 1);
}

/* Tets the caller writes in the other vertex order come back so, and the tets
 * that replace them follow the cavity's convention. */
TEST(export_keeps_the_callers_vertex_order)
{
    double x[5 * 3] = {0, 0, -1, 0, 0, 1, 1, 0, 0, -0.5, 0.75, 0, -0.5, -0.75, 0};
    int32_t tv[12] = {0, 1, 2, 3, 0, 1, 3, 4, 0, 1, 4, 2}, nt, *out = NULL;
    const uint8_t rev[3] = {1, 1, 1};
    tmesh *tm = NULL;
    flip_cand c;
    int applied = 0;

    ASSERT_OK(tmesh_new(5, x, 3, tv, NULL, rev, &tm, NULL));
    ASSERT_OK(tmesh_export(tm, &nt, &out, NULL));
    ASSERT_EQ_INT(nt, 3);
    for (int t = 0; t < 3; t++) {
        ASSERT_EQ_INT(out[4 * t], tv[4 * t + 1]);
        ASSERT_EQ_INT(out[4 * t + 1], tv[4 * t]);
    }
    qdc_free(out);
    ASSERT_EQ_INT(flip_edge_eval(tm, 0, 0, 10, 0.0, -INFINITY, &c), 1);
    ASSERT_OK(tmesh_replace(tm, c.old, c.nold, (const int32_t(*)[4])c.newt, c.nnew, NULL,
                            &applied));
    tmesh_commit(tm);
    ASSERT_OK(tmesh_export(tm, &nt, &out, NULL));
    ASSERT_EQ_INT(nt, 2);
    for (int t = 0; t < 2; t++)
        ASSERT_NEAR(geom_tet_vol6(x, out + 4 * t), -2.25, 0);
    qdc_free(out);
    tmesh_free(tm);
}

TEST(mixed_tag_shell_blocks_removal)
{
    const int32_t tags[3] = {1, 1, 2};
    tmesh *tm = ring_mesh(3, -1, 1, tags);
    flip_cand c;

    ASSERT_TRUE(tm);
    ASSERT_EQ_INT(tm->econs[0] & 1, 1); /* the axis is on the interface */
    ASSERT_EQ_INT(flip_edge_eval(tm, 0, 0, 10, 0.0, -INFINITY, &c), 0);
    tmesh_free(tm);
    tm = ring_mesh(3, -1, 1, (const int32_t[3]){2, 2, 2});
    ASSERT_EQ_INT(flip_edge_eval(tm, 0, 0, 10, 0.0, -INFINITY, &c), 1);
    tmesh_free(tm);
}

/* a and b both above the ring: the three tets are valid, but the edge does not
 * pierce the ring's triangle, so every retriangulation inverts a tet. */
TEST(non_convex_ring_refused)
{
    tmesh *tm = ring_mesh(3, 1, 2, NULL);
    flip_cand c;

    ASSERT_TRUE(tm);
    ASSERT_TRUE(consistent(tm));
    ASSERT_EQ_INT(flip_edge_eval(tm, 0, 0, 10, 0.0, -INFINITY, &c), 0);
    /* the same ring with the edge through it is accepted */
    tmesh_free(tm);
    tm = ring_mesh(3, -1, 2, NULL);
    ASSERT_EQ_INT(flip_edge_eval(tm, 0, 0, 10, 0.0, -INFINITY, &c), 1);
    tmesh_free(tm);
}

/* A flat bipyramid: the two new tets have all four corners on the boundary and
 * a mean ratio under the floor, so the removal is refused with the floor. */
TEST(four_boundary_corner_floor)
{
    tmesh *tm = ring_mesh(3, -0.02, 0.02, NULL);
    flip_cand c;

    ASSERT_TRUE(tm);
    ASSERT_EQ_INT(flip_edge_eval(tm, 0, 0, 10, 0.1, -INFINITY, &c), 0);
    ASSERT_EQ_INT(flip_edge_eval(tm, 0, 0, 10, 0.0, -INFINITY, &c), 1);
    ASSERT_TRUE(c.qmin_new < 0.1);
    tmesh_free(tm);
}

typedef struct {
    int32_t hi, nlive, nfree;
    int32_t *tv, *adj, *tag, *freel;
    uint8_t *f, *e;
    double *q;
    uint32_t *stamp;
} snap;

static int snap_take(const tmesh *tm, snap *s)
{
    size_t n = (size_t)tm->hi;
    s->hi = tm->hi;
    s->nlive = tm->nlive;
    s->nfree = tm->nfree;
    s->tv = malloc(16 * n);
    s->adj = malloc(16 * n);
    s->tag = malloc(4 * n);
    s->freel = malloc(4 * n + 4);
    s->f = malloc(n);
    s->e = malloc(n);
    s->q = malloc(8 * n);
    s->stamp = malloc(4 * n);
    if (!s->tv || !s->adj || !s->tag || !s->freel || !s->f || !s->e || !s->q || !s->stamp)
        return 0;
    memcpy(s->tv, tm->tv, 16 * n);
    memcpy(s->adj, tm->adj, 16 * n);
    memcpy(s->tag, tm->tag, 4 * n);
    memcpy(s->freel, tm->freel, 4 * (size_t)tm->nfree);
    memcpy(s->f, tm->fcons, n);
    memcpy(s->e, tm->econs, n);
    memcpy(s->q, tm->q, 8 * n);
    memcpy(s->stamp, tm->stamp, 4 * n);
    return 1;
}

static int snap_same(const tmesh *tm, const snap *s)
{
    size_t n = (size_t)s->hi;
    return tm->hi == s->hi && tm->nlive == s->nlive && tm->nfree == s->nfree &&
           !memcmp(s->tv, tm->tv, 16 * n) && !memcmp(s->adj, tm->adj, 16 * n) &&
           !memcmp(s->tag, tm->tag, 4 * n) &&
           !memcmp(s->freel, tm->freel, 4 * (size_t)s->nfree) &&
           !memcmp(s->f, tm->fcons, n) && !memcmp(s->e, tm->econs, n) &&
           !memcmp(s->q, tm->q, 8 * n) && !memcmp(s->stamp, tm->stamp, 4 * n);
}

static void snap_free(snap *s)
{
    free(s->tv);
    free(s->adj);
    free(s->tag);
    free(s->freel);
    free(s->f);
    free(s->e);
    free(s->q);
    free(s->stamp);
}

/* A 6-ring removed (slots reused and one taken from hi), then a 2-3 flip inside
 * it (slots from the free list and from hi) rolled back: every array as it was. */
TEST(rollback_restores_exactly)
{
    tmesh *tm = ring_mesh(6, -1, 1, NULL);
    flip_cand c;
    snap s;
    int applied = 0, done = 0;

    ASSERT_TRUE(tm);
    ASSERT_EQ_INT(flip_edge_eval(tm, 0, 0, 10, 0.0, -INFINITY, &c), 1);
    ASSERT_OK(tmesh_replace(tm, c.old, c.nold, (const int32_t(*)[4])c.newt, c.nnew, NULL,
                            &applied));
    tmesh_commit(tm);
    ASSERT_EQ_INT(tm->nlive, 8);
    ASSERT_TRUE(snap_take(tm, &s));
    for (int32_t t = 0; t < tm->hi && !done; t++)
        for (int f = 0; f < 4 && !done; f++)
            if (tm->tv[4 * t] >= 0 && flip_23_eval(tm, t, f, 0.0, -INFINITY, &c)) {
                ASSERT_OK(tmesh_replace(tm, c.old, 2, (const int32_t(*)[4])c.newt, 3,
                                        NULL, &applied));
                ASSERT_EQ_INT(applied, 1);
                ASSERT_EQ_INT(tm->nlive, 9);
                ASSERT_TRUE(consistent(tm));
                ASSERT_TRUE(!snap_same(tm, &s));
                tmesh_rollback(tm);
                done = 1;
            }
    ASSERT_EQ_INT(done, 1);
    ASSERT_TRUE(snap_same(tm, &s));
    ASSERT_TRUE(consistent(tm));
    snap_free(&s);
    tmesh_free(tm);
}

/* Sorted boundary (tag -1) and interface (the two tags) faces of the live tets,
 * as rows of 5: three vertices, the tags. */
static int cmp5(const void *x, const void *y)
{
    const int32_t *a = x, *b = y;
    for (int s = 0; s < 5; s++)
        if (a[s] != b[s])
            return a[s] < b[s] ? -1 : 1;
    return 0;
}

static int32_t *cons_faces(const tmesh *tm, int32_t *n)
{
    int32_t *r = malloc(20 * (size_t)tm->hi * 4 + 20), k = 0;
    if (!r)
        return NULL;
    for (int32_t t = 0; t < tm->hi; t++)
        for (int i = 0; i < 4 && tm->tv[4 * t] >= 0; i++) {
            int32_t nb = tm->adj[4 * t + i], v[3];
            if (!(tm->fcons[t] >> i & 1))
                continue;
            tet_sort3(tm->tv[4 * t + tet_face_of[i][0]],
                      tm->tv[4 * t + tet_face_of[i][1]],
                      tm->tv[4 * t + tet_face_of[i][2]], v);
            memcpy(r + 5 * k, v, sizeof v);
            r[5 * k + 3] = tm->tag[t];
            r[5 * k + 4] = nb < 0 ? -1 : tm->tag[nb / 4];
            k++;
        }
    qsort(r, (size_t)k, 5 * sizeof *r, cmp5);
    *n = k;
    return r;
}

static void tag_vols(const tmesh *tm, double v[3])
{
    v[0] = v[1] = v[2] = 0;
    for (int32_t t = 0; t < tm->hi; t++)
        if (tm->tv[4 * t] >= 0)
            v[tm->tag[t]] += geom_tet_vol6(tm->xyz, tm->tv + 4 * t);
}

static double min_q(const tmesh *tm)
{
    double m = 2;
    for (int32_t t = 0; t < tm->hi; t++)
        if (tm->tv[4 * t] >= 0 && tm->q[t] < m)
            m = tm->q[t];
    return m;
}

/* A perturbed 7^3 grid of two regions: thousands of random legal flips (any
 * quality), then the driver; the adjacency stays consistent, the volume of
 * each region, the boundary and interface triangles stay as they were, no tet
 * inverts, and the driver raises the smallest mean ratio. */
TEST(random_flips_keep_invariants)
{
    const int n = 7;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION);
    tmesh *tm = NULL;
    int32_t nf0, nf1, *f0, *f1;
    double v0[3], v1[3], q0;
    uint64_t s = 99;
    int64_t done = 0, nmf = 0;
    topo_params p;
    topo_stats st;

    ASSERT_TRUE(m);
    tm_perturb(m, n, 0.25, 7);
    ASSERT_OK(tmesh_new(m->nv, m->xyz, m->nt, m->tets, m->region, NULL, &tm, NULL));
    ASSERT_TRUE(consistent(tm));
    f0 = cons_faces(tm, &nf0);
    ASSERT_TRUE(f0);
    tag_vols(tm, v0);
    for (int it = 0; it < 20000; it++) {
        int32_t t = (int32_t)((tm_rand(&s) + 1) * 0.5 * tm->hi) % tm->hi;
        int which = (int)((tm_rand(&s) + 1) * 7) % 14, applied = 0;
        flip_cand c;
        int ok;
        if (tm->tv[4 * t] < 0)
            continue;
        ok = which < 6 ? flip_edge_eval(tm, t, which, 10, 0.05, -INFINITY, &c)
             : which < 10
                 ? flip_23_eval(tm, t, which - 6, 0.05, -INFINITY, &c)
                 : flip_multiface_eval(tm, t, which - 10, 10, 0.05, -INFINITY, &c);
        nmf += ok && which >= 10;
        if (!ok)
            continue;
        ASSERT_OK(tmesh_replace(tm, c.old, c.nold, (const int32_t(*)[4])c.newt, c.nnew,
                                NULL, &applied));
        ASSERT_EQ_INT(applied, 1);
        tmesh_commit(tm);
        done++;
    }
    ASSERT_TRUE(done > 1000);
    ASSERT_TRUE(nmf > 10);
    ASSERT_TRUE(consistent(tm));
    q0 = min_q(tm);
    topo_params_default(&p);
    p.qgoal = 0.9;
    ASSERT_OK(topo_improve(tm, &p, &st, NULL));
    ASSERT_TRUE(st.edge_removals + st.flips23 + st.multiface > 100);
    ASSERT_TRUE(consistent(tm));
    ASSERT_TRUE(min_q(tm) > q0);
    f1 = cons_faces(tm, &nf1);
    ASSERT_TRUE(f1);
    ASSERT_EQ_INT(nf1, nf0);
    ASSERT_TRUE(!memcmp(f0, f1, 20 * (size_t)nf0));
    tag_vols(tm, v1);
    for (int r = 1; r <= 2; r++)
        ASSERT_NEAR(v1[r], v0[r], 1e-12 * fabs(v0[r]));
    free(f0);
    free(f1);
    tmesh_free(tm);
    mesh_free(m);
}

/* The worst live tet of tm whose four faces are interior and unconstrained. */
static int32_t worst_inner(const tmesh *tm)
{
    int32_t w = -1;
    for (int32_t t = 0; t < tm->hi; t++)
        if (tm->tv[4 * t] >= 0 && tm->fcons[t] == 0 && (w < 0 || tm->q[t] < tm->q[w]))
            w = t;
    return w;
}

/* A vertex inserted in the worst inner tet of a perturbed grid (any quality
 * accepted): one vertex more, its star of at least 12 tets (the tet and its
 * four neighbours at least), the volume, adjacency and
 * constrained faces kept, none inverted; undone, every array as it was. */
TEST(insertion_in_a_bad_tet)
{
    const int n = 4;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION);
    tmesh *tm = NULL;
    int32_t ids[32], t, nv, nf0, nf1, *f0, *f1;
    double v0, v1;
    int done = 0, nn = 0;
    snap s;

    ASSERT_TRUE(m);
    tm_perturb(m, n, 0.3, 11);
    ASSERT_OK(tmesh_new(m->nv, m->xyz, m->nt, m->tets, m->region, NULL, &tm, NULL));
    t = worst_inner(tm);
    ASSERT_TRUE(t >= 0);
    nv = tm->nv;
    v0 = total_vol6(tm);
    f0 = cons_faces(tm, &nf0);
    ASSERT_TRUE(f0);
    ASSERT_TRUE(snap_take(tm, &s));
    ASSERT_OK(insert_in_tet(tm, t, -INFINITY, 0, &done, ids, &nn));
    ASSERT_EQ_INT(done, 1);
    ASSERT_TRUE(nn >= 12 && nn <= 32);
    ASSERT_EQ_INT(tm->nv, nv + 1);
    ASSERT_TRUE(tm->nlive > m->nt);
    ASSERT_TRUE(consistent(tm));
    v1 = total_vol6(tm);
    ASSERT_NEAR(v1, v0, 1e-12 * v0);
    for (int j = 0; j < nn; j++) {
        ASSERT_TRUE(tmesh_local(tm, ids[j], nv) >= 0);
        ASSERT_TRUE(tm->q[ids[j]] > 0);
    }
    f1 = cons_faces(tm, &nf1);
    ASSERT_TRUE(f1);
    ASSERT_EQ_INT(nf1, nf0);
    ASSERT_TRUE(!memcmp(f0, f1, 20 * (size_t)nf0));
    insert_undo(tm);
    ASSERT_EQ_INT(tm->nv, nv);
    ASSERT_TRUE(snap_same(tm, &s));
    ASSERT_TRUE(consistent(tm));
    free(f0);
    free(f1);
    snap_free(&s);
    tmesh_free(tm);
    mesh_free(m);
}

/* An insertion that cannot raise the cavity's minimum by the margin is refused
 * with nothing changed; in a tet of one boundary face the face stays. */
TEST(insertion_refused_leaves_the_mesh)
{
    tmesh *tm = ring_mesh(4, -1, 1, NULL);
    int32_t ids[32], nf0, nf1, *f0, *f1;
    int done = 1, nn = 0;
    snap s;

    ASSERT_TRUE(tm);
    ASSERT_TRUE(snap_take(tm, &s));
    ASSERT_OK(insert_in_tet(tm, 0, 10.0, 0, &done, ids, &nn));
    ASSERT_EQ_INT(done, 0);
    ASSERT_EQ_INT(tm->nv, 6);
    ASSERT_TRUE(snap_same(tm, &s));
    f0 = cons_faces(tm, &nf0);
    ASSERT_TRUE(f0);
    ASSERT_OK(insert_in_tet(tm, 0, -INFINITY, 0, &done, ids, &nn));
    ASSERT_EQ_INT(done, 1);
    ASSERT_TRUE(consistent(tm));
    f1 = cons_faces(tm, &nf1);
    ASSERT_TRUE(f1);
    ASSERT_EQ_INT(nf1, nf0);
    ASSERT_TRUE(!memcmp(f0, f1, 20 * (size_t)nf0));
    tmesh_commit(tm);
    free(f0);
    free(f1);
    snap_free(&s);
    tmesh_free(tm);
}

/* The smallest dihedral angle (degrees) over the live tets of tm from slot lo. */
static double min_dihedral_from(const tmesh *tm, int32_t lo)
{
    double m = 180.0, a0, a1;
    for (int32_t t = lo; t < tm->hi; t++) {
        const int32_t *v = tm->tv + 4 * t;
        if (v[0] < 0)
            continue;
        metric_dihedral_range(tm->xyz + 3 * v[0], tm->xyz + 3 * v[1], tm->xyz + 3 * v[2],
                              tm->xyz + 3 * v[3], &a0, &a1);
        m = fmin(m, a0);
    }
    return m;
}

/* Insertion in the octahedron of the ring of 4 tets around the z axis, its
 * apexes at z = -h and h, the ring points at distance 1. The star of its
 * centre is 8 trirectangular tets (0, h e_z, e_x, e_y) and mirrors: mean
 * ratio 12 (h / 2)^(2/3) / (6 + 3 h^2) against the ring's 12 h^(2/3) /
 * (6 + 8 h^2); smallest dihedral atan(h sqrt2) (at the ring edge, where the
 * ring's tet has 2 atan(h sqrt2)) and acos(h / sqrt(2 h^2 + 1)) (at the
 * apex-to-ring edges, as the ring's).
 * h = 0.5 (flat): the star's mean ratio 0.7055 < 0.9449 and smallest angle
 * 35.26 deg < 65.91: with any margin it is made without the angle check
 * (the vertex at the centre), and refused with it, nothing changed.
 * h = 2 (tall): 0.6667 > 0.5013, the smallest angle 48.19 both: made with the
 * angle check and a margin of 0.1. */
TEST(insertion_keeps_the_smallest_angle)
{
    const double flat = 0.5, tall = 2.0;
    double qs = 12 * pow(flat / 2, 2.0 / 3) / (6 + 3 * flat * flat);
    double qt = 12 * pow(tall / 2, 2.0 / 3) / (6 + 3 * tall * tall);
    double q0 = 12 * pow(tall, 2.0 / 3) / (6 + 8 * tall * tall);
    tmesh *tm = ring_mesh(4, -flat, flat, NULL);
    int32_t ids[32];
    int done = 1, nn = 0;
    snap s;

    ASSERT_TRUE(tm);
    ASSERT_NEAR(min_dihedral_from(tm, 0),
                acos(flat / sqrt(2 * flat * flat + 1)) * 180 / PI, 1e-9);
    ASSERT_TRUE(snap_take(tm, &s));
    ASSERT_OK(insert_in_tet(tm, 0, -INFINITY, 1, &done, ids, &nn));
    ASSERT_EQ_INT(done, 0);
    ASSERT_EQ_INT(tm->nv, 6);
    ASSERT_TRUE(snap_same(tm, &s));
    snap_free(&s);
    ASSERT_OK(insert_in_tet(tm, 0, -INFINITY, 0, &done, ids, &nn));
    ASSERT_EQ_INT(done, 1);
    ASSERT_EQ_INT(nn, 8);
    ASSERT_EQ_INT(tm->nlive, 8);
    ASSERT_TRUE(consistent(tm));
    for (int d = 0; d < 3; d++)
        ASSERT_NEAR(tm->xyz[3 * 6 + d], 0.0, 1e-12);
    for (int j = 0; j < nn; j++)
        ASSERT_NEAR(tm->q[ids[j]], qs, 1e-9);
    ASSERT_NEAR(min_dihedral_from(tm, 0), atan(flat * sqrt(2.0)) * 180 / PI, 1e-9);
    tmesh_commit(tm);
    tmesh_free(tm);

    tm = ring_mesh(4, -tall, tall, NULL);
    ASSERT_TRUE(tm);
    ASSERT_NEAR(tm->q[0], q0, 1e-12);
    ASSERT_OK(insert_in_tet(tm, 0, 0.1, 1, &done, ids, &nn));
    ASSERT_EQ_INT(done, 1);
    ASSERT_EQ_INT(nn, 8);
    ASSERT_TRUE(consistent(tm));
    for (int d = 0; d < 3; d++)
        ASSERT_NEAR(tm->xyz[3 * 6 + d], 0.0, 1e-12);
    for (int j = 0; j < nn; j++)
        ASSERT_NEAR(tm->q[ids[j]], qt, 1e-9);
    ASSERT_NEAR(min_dihedral_from(tm, 0),
                acos(tall / sqrt(2 * tall * tall + 1)) * 180 / PI, 1e-9);
    tmesh_commit(tm);
    tmesh_free(tm);
}

/* A sliver on the surface, held by it: the ring of 4 tets around the z axis
 * (apexes at z = -1 and 1, ring points at distance 1 and angles 0, 178, 240,
 * 300 degrees) is all boundary, and its first tet (a, b, p0, p1) spans 179.5
 * degrees around ab: its four corners and two of its faces on the surface,
 * mean ratio 0.032. Every tet of the star of its first cavity (the tet
 * and the two across its faces on the axis) that the cavity can cross stands
 * on an inner face; its worst stands on the surface. The cavity grows past
 * that tet to the whole ring, and the star of 8 tets over the 8 boundary
 * triangles is made with the margin and the angle check: its smallest mean
 * ratio above 0.2, its smallest dihedral angle above 20 degrees, the volume and
 * the boundary faces kept. */
TEST(insertion_grows_past_the_surface)
{
    const double deg[4] = {0, 179.5, 240, 300};
    double v0, q0, qn = 2;
    int32_t ids[32], nf0, nf1, *f0, *f1;
    tmesh *tm = ring_mesh_at(4, deg, -1, 1, NULL);
    int done = 0, nn = 0;

    ASSERT_TRUE(tm);
    q0 = min_q(tm);
    ASSERT_TRUE(q0 > 0.03 && q0 < 0.035 && tm->q[0] == q0);
    ASSERT_TRUE(min_dihedral_from(tm, 0) < 2.0);
    v0 = total_vol6(tm);
    f0 = cons_faces(tm, &nf0);
    ASSERT_TRUE(f0);
    ASSERT_EQ_INT(nf0, 8);
    ASSERT_OK(insert_in_tet(tm, 0, 0.05, 1, &done, ids, &nn));
    ASSERT_EQ_INT(done, 1);
    ASSERT_EQ_INT(nn, 8);
    ASSERT_EQ_INT(tm->nlive, 8);
    ASSERT_EQ_INT(tm->nv, 7);
    ASSERT_TRUE(consistent(tm));
    ASSERT_NEAR(total_vol6(tm), v0, 1e-12 * v0);
    for (int j = 0; j < nn; j++) {
        ASSERT_TRUE(tmesh_local(tm, ids[j], 6) >= 0);
        qn = fmin(qn, tm->q[ids[j]]);
    }
    ASSERT_TRUE(qn > 0.2);
    ASSERT_TRUE(min_dihedral_from(tm, 0) > 20.0);
    f1 = cons_faces(tm, &nf1);
    ASSERT_TRUE(f1);
    ASSERT_EQ_INT(nf1, nf0);
    ASSERT_TRUE(!memcmp(f0, f1, 20 * (size_t)nf0));
    tmesh_commit(tm);
    free(f0);
    free(f1);
    tmesh_free(tm);
}

/* The cap of a face: 1 for an equilateral triangle (the regular tet on it),
 * 0 for a degenerate one; on a scalene triangle reached by the apex over the
 * centroid at height sqrt(2L/9), and above the mean ratio of every tet on the
 * face with the apex anywhere (a grid of 9261 places). */
TEST(insertion_face_cap)
{
    const double eq[9] = {0, 0, 0, 2, 0, 0, 1, sqrt(3.0), 0};
    const double line[9] = {0, 0, 0, 1, 1, 1, 3, 3, 3};
    const double f[9] = {0, 0, 0, 3, 0, 0, 0.4, 0.7, 0};
    double l = 9 + 0.4 * 0.4 + 0.7 * 0.7 + 2.6 * 2.6 + 0.7 * 0.7, cap,
           h = sqrt(2 * l / 9);
    double apex[3] = {3.4 / 3, 0.7 / 3, h}, q, top = 0;
    int32_t v[4] = {0, 1, 2, 3};
    tmesh *tm = NULL;
    double x[12];
    int32_t tv[4] = {0, 1, 2, 3};

    ASSERT_NEAR(insert_face_cap(eq, eq + 3, eq + 6), 1.0, 1e-12);
    ASSERT_TRUE(insert_face_cap(line, line + 3, line + 6) == 0.0);
    cap = insert_face_cap(f, f + 3, f + 6);
    ASSERT_TRUE(cap > 0.2 && cap < 0.9);
    memcpy(x, f, sizeof f);
    memcpy(x + 9, apex, sizeof apex);
    ASSERT_OK(tmesh_new(4, x, 1, tv, NULL, NULL, &tm, NULL));
    ASSERT_NEAR(tm->q[0], cap, 1e-12);
    for (int i = 0; i <= 20; i++)
        for (int j = 0; j <= 20; j++)
            for (int k = 0; k <= 20; k++) {
                tm->xyz[9] = -1 + 0.25 * i;
                tm->xyz[10] = -2 + 0.2 * j;
                tm->xyz[11] = 0.02 + 0.2 * k;
                q = tmesh_quality(tm, v, -INFINITY);
                ASSERT_TRUE(q <= cap * (1 + 1e-12));
                top = fmax(top, q);
            }
    ASSERT_TRUE(top > 0.95 * cap);
    tmesh_free(tm);
}

/* The driver with insertion on a perturbed two-region grid: vertices added,
 * the smallest mean ratio above the flips' alone, the constrained faces and
 * region volumes kept, adjacency consistent, none inverted. */
TEST(driver_with_insertion)
{
    const int n = 6;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION);
    tmesh *a = NULL, *b = NULL;
    int32_t nf0, nf1, *f0, *f1;
    double v0[3], v1[3];
    topo_params p;
    topo_stats st;

    ASSERT_TRUE(m);
    tm_perturb(m, n, 0.3, 5);
    ASSERT_OK(tmesh_new(m->nv, m->xyz, m->nt, m->tets, m->region, NULL, &a, NULL));
    ASSERT_OK(tmesh_new(m->nv, m->xyz, m->nt, m->tets, m->region, NULL, &b, NULL));
    f0 = cons_faces(b, &nf0);
    ASSERT_TRUE(f0);
    tag_vols(b, v0);
    topo_params_default(&p);
    p.qgoal = 0.9;
    ASSERT_OK(topo_improve(a, &p, &st, NULL));
    p.insert = 1;
    p.qinsert = 0.5;
    p.imargin = 1e-3;
    ASSERT_OK(topo_improve(b, &p, &st, NULL));
    ASSERT_TRUE(st.insertions > 0);
    ASSERT_EQ_INT(st.nv_out, st.nv_in + (int32_t)st.insertions);
    ASSERT_TRUE(consistent(b));
    ASSERT_TRUE(min_q(b) >= min_q(a));
    f1 = cons_faces(b, &nf1);
    ASSERT_TRUE(f1);
    ASSERT_EQ_INT(nf1, nf0);
    ASSERT_TRUE(!memcmp(f0, f1, 20 * (size_t)nf0));
    tag_vols(b, v1);
    for (int r = 1; r <= 2; r++)
        ASSERT_NEAR(v1[r], v0[r], 1e-12 * fabs(v0[r]));
    free(f0);
    free(f1);
    tmesh_free(a);
    tmesh_free(b);
    mesh_free(m);
}

/* Twice the same run: the same tets in the same order. */
TEST(driver_is_deterministic)
{
    const int n = 6;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION);
    int32_t nt[2], *tv[2] = {NULL, NULL}, *rg[2] = {NULL, NULL};
    topo_params p;
    topo_stats st;

    ASSERT_TRUE(m);
    tm_perturb(m, n, 0.3, 3);
    topo_params_default(&p);
    for (int r = 0; r < 2; r++)
        ASSERT_OK(topo_flip_arrays(m->nv, m->xyz, m->nt, m->tets, m->region, NULL, &p,
                                   NULL, &nt[r], &tv[r], &rg[r], &st, NULL));
    ASSERT_TRUE(st.edge_removals + st.flips23 + st.multiface > 0);
    ASSERT_EQ_INT(st.nt_out, nt[0]);
    ASSERT_EQ_INT(nt[0], nt[1]);
    ASSERT_TRUE(!memcmp(tv[0], tv[1], 16 * (size_t)nt[0]));
    ASSERT_TRUE(!memcmp(rg[0], rg[1], 4 * (size_t)nt[0]));
    for (int r = 0; r < 2; r++) {
        qdc_free(tv[r]);
        qdc_free(rg[r]);
    }
    mesh_free(m);
}

/* One thread and two: the same flips in the same visits, the same tets and
 * tags; with two, the flips of the tets next in the queue were found ahead
 * (each taken only while nothing it read had changed), with one none. The
 * same for a run with insertion and contraction, vertices included. */
TEST(driver_same_on_one_and_two_threads)
{
    const int n = 9;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION);
    int32_t nt[2], nv[2], *tv[2] = {NULL, NULL}, *rg[2] = {NULL, NULL};
    double *xo[2] = {NULL, NULL};
    int saved = omp_get_max_threads();
    topo_params p;
    topo_stats st[2];

    ASSERT_TRUE(m);
    tm_perturb(m, n, 0.35, 11);
    topo_params_default(&p);
    p.qgoal = 0.9;
    p.qinsert = 0.6;
    p.qcontract = 0.7;
    p.imargin = 1e-3;
    for (int full = 0; full < 2; full++) {
        p.insert = p.contract = full;
        for (int r = 0; r < 2; r++) {
            omp_set_num_threads(1 + r);
            if (full)
                ASSERT_OK(topo_full_arrays(m->nv, m->xyz, m->nt, m->tets, m->region, NULL,
                                           &p, NULL, &nv[r], &xo[r], &nt[r], &tv[r],
                                           &rg[r], NULL, NULL, &st[r], NULL));
            else
                ASSERT_OK(topo_flip_arrays(m->nv, m->xyz, m->nt, m->tets, m->region, NULL,
                                           &p, NULL, &nt[r], &tv[r], &rg[r], &st[r],
                                           NULL));
        }
        omp_set_num_threads(saved);
        ASSERT_TRUE(st[0].edge_removals + st[0].flips23 + st[0].multiface > 100);
        ASSERT_EQ_INT(st[0].ahead, 0);
        ASSERT_TRUE(st[1].ahead > st[1].visits / 4);
        ASSERT_EQ_INT(st[0].visits, st[1].visits);
        ASSERT_EQ_INT(st[0].edge_removals, st[1].edge_removals);
        ASSERT_EQ_INT(st[0].multiface, st[1].multiface);
        ASSERT_EQ_INT(st[0].insertions, st[1].insertions);
        ASSERT_EQ_INT(st[0].contractions, st[1].contractions);
        ASSERT_EQ_INT(nt[0], nt[1]);
        ASSERT_TRUE(!memcmp(tv[0], tv[1], 16 * (size_t)nt[0]));
        ASSERT_TRUE(!memcmp(rg[0], rg[1], 4 * (size_t)nt[0]));
        if (full) {
            ASSERT_TRUE(st[0].insertions + st[0].contractions > 0);
            ASSERT_EQ_INT(nv[0], nv[1]);
            ASSERT_TRUE(!memcmp(xo[0], xo[1], 24 * (size_t)nv[0]));
        }
        for (int r = 0; r < 2; r++) {
            qdc_free(tv[r]);
            qdc_free(rg[r]);
            qdc_free(xo[r]);
            tv[r] = rg[r] = NULL;
            xo[r] = NULL;
        }
    }
    mesh_free(m);
}

/* Runs r = 0 (skips) and 1 (recheck) made the same flips and the same tets
 * and tags, the first in fewer visits (a failure marks the test failed). */
static void same_as_recheck(const topo_stats st[2], const int32_t nt[2],
                            int32_t *const tv[2], int32_t *const rg[2])
{
    ASSERT_EQ_INT(st[0].edge_removals, st[1].edge_removals);
    ASSERT_EQ_INT(st[0].multiface, st[1].multiface);
    ASSERT_EQ_INT(nt[0], nt[1]);
    ASSERT_TRUE(!memcmp(tv[0], tv[1], 16 * (size_t)nt[0]));
    ASSERT_TRUE(!memcmp(rg[0], rg[1], 4 * (size_t)nt[0]));
    ASSERT_TRUE(st[0].visits < st[1].visits);
}

/* Skipping the tets and edges whose failed evaluation nothing has changed
 * since gives the same tets as evaluating them all again, in fewer visits. */
TEST(driver_skips_only_what_cannot_change)
{
    const int n = 7;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION);
    int32_t nt[2], *tv[2] = {NULL, NULL}, *rg[2] = {NULL, NULL};
    topo_params p;
    topo_stats st[2];

    ASSERT_TRUE(m);
    tm_perturb(m, n, 0.3, 5);
    topo_params_default(&p);
    p.qgoal = 0.9;
    for (int r = 0; r < 2; r++) {
        p.recheck = r;
        ASSERT_OK(topo_flip_arrays(m->nv, m->xyz, m->nt, m->tets, m->region, NULL, &p,
                                   NULL, &nt[r], &tv[r], &rg[r], &st[r], NULL));
    }
    ASSERT_TRUE(st[0].edge_removals + st[0].flips23 + st[0].multiface > 50);
    same_as_recheck(st, nt, tv, rg);
    for (int r = 0; r < 2; r++) {
        qdc_free(tv[r]);
        qdc_free(rg[r]);
    }
    mesh_free(m);
}

static double mean_ratio_of(const double *p, const double *q, const double *r,
                            const double *s);

/* The smallest mean ratio of the nt tets tv (4 each) over the coordinates x. */
static double worst_of(const double *x, const int32_t *tv, int32_t nt)
{
    double q = INFINITY;

    for (int32_t t = 0; t < nt; t++) {
        const int32_t *v = tv + 4 * (size_t)t;
        q = fmin(q, mean_ratio_of(x + 3 * (size_t)v[0], x + 3 * (size_t)v[1],
                                  x + 3 * (size_t)v[2], x + 3 * (size_t)v[3]));
    }
    return q;
}

/* The same with insertion and contraction between the flip passes (the
 * skips carried across them): the same vertices and tets as evaluating every
 * queued tet again, in fewer visits.
 * With contraction by gain (cfloor) instead of insertion: the same, some
 * vertices gone, and the mesh's worst tet not worse than the input's. */
TEST(driver_skips_across_insertions_and_contractions)
{
    const int n = 7;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION);
    topo_params p;

    ASSERT_TRUE(m);
    tm_perturb(m, n, 0.35, 7);
    for (int gain = 0; gain < 2; gain++) {
        int32_t nt[2], nv[2], *tv[2] = {NULL, NULL}, *rg[2] = {NULL, NULL};
        int32_t *vmap[2] = {NULL, NULL};
        double *xo[2] = {NULL, NULL};
        topo_stats st[2];
        topo_params_default(&p);
        p.qgoal = gain ? 0.8 : 0.9;
        p.insert = !gain;
        p.contract = 1;
        p.qinsert = 0.6;
        p.qcontract = gain ? 0.8 : 0.7;
        p.cfloor = gain ? 0.5 : 0.0;
        p.imargin = 1e-3;
        for (int r = 0; r < 2; r++) {
            p.recheck = r;
            ASSERT_OK(topo_full_arrays(m->nv, m->xyz, m->nt, m->tets, m->region, NULL, &p,
                                       NULL, &nv[r], &xo[r], &nt[r], &tv[r], &rg[r],
                                       &vmap[r], NULL, &st[r], NULL));
        }
        ASSERT_TRUE((gain || st[0].insertions > 0) && st[0].contractions > 0);
        ASSERT_EQ_INT(st[0].insertions, st[1].insertions);
        ASSERT_EQ_INT(st[0].contractions, st[1].contractions);
        ASSERT_EQ_INT(nv[0], m->nv + (int32_t)(st[0].insertions - st[0].contractions));
        ASSERT_EQ_INT(nv[0], nv[1]);
        ASSERT_TRUE(!memcmp(xo[0], xo[1], 24 * (size_t)nv[0]));
        same_as_recheck(st, nt, tv, rg);
        if (gain)
            ASSERT_TRUE(worst_of(xo[0], tv[0], nt[0]) >=
                        worst_of(m->xyz, m->tets, m->nt));
        for (int r = 0; r < 2; r++) {
            qdc_free(tv[r]);
            qdc_free(rg[r]);
            qdc_free(xo[r]);
            qdc_free(vmap[r]);
        }
    }
    mesh_free(m);
}

/* With akeep, each flip's new tets have a smallest dihedral angle at least
 * that of the tets it removed or akeep: so, by induction over the flips, the
 * mesh's smallest angle never falls below the least of its first and akeep;
 * without, the same flips on the same mesh take it lower. */
TEST(driver_keeps_the_smallest_angle)
{
    const int n = 7;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION);
    double a0 = 0.0, a1[2] = {0.0, 0.0};
    topo_params p;
    topo_stats st;

    ASSERT_TRUE(m);
    tm_perturb(m, n, 0.15, 5);
    topo_params_default(&p);
    p.qgoal = 1.0; /* every tet queued, a small margin: flips that lower the
                    * smallest angle are among those taken without akeep */
    p.margin = 1e-6;
    for (int r = 0; r < 2; r++) {
        tmesh *tm = NULL;
        ASSERT_OK(tmesh_new(m->nv, m->xyz, m->nt, m->tets, m->region, NULL, &tm, NULL));
        a0 = min_dihedral_from(tm, 0);
        p.akeep = r ? 60.0 : 0.0; /* above every angle of the input */
        ASSERT_OK(topo_improve(tm, &p, &st, NULL));
        ASSERT_TRUE(st.edge_removals + st.flips23 + st.multiface > 20);
        ASSERT_TRUE(consistent(tm));
        a1[r] = min_dihedral_from(tm, 0);
        tmesh_free(tm);
    }
    ASSERT_TRUE(a1[1] >= a0);
    ASSERT_TRUE(a1[0] < a0);
    mesh_free(m);
}

static int cmp3(const void *x, const void *y)
{
    const int32_t *a = x, *b = y;
    for (int s = 0; s < 3; s++)
        if (a[s] != b[s])
            return a[s] < b[s] ? -1 : 1;
    return 0;
}

/* n faces (3 each) as sorted keys in sorted order, in a new array. */
static int32_t *face_set(const int32_t *f, int32_t n)
{
    int32_t *r = malloc(12 * (size_t)n + 12);
    if (!r)
        return NULL;
    for (int32_t i = 0; i < n; i++)
        tet_sort3(f[3 * i], f[3 * i + 1], f[3 * i + 2], r + 3 * i);
    qsort(r, (size_t)n, 12, cmp3);
    return r;
}

/* opt_run with --topology flips on a perturbed two-region grid whose vertices
 * are all fixed (so that only the flips can improve it): other tets, the same
 * boundary and interface triangles (as sets), no tet inverted, the counts in the
 * result, and a higher mean ratio than --topology none. */
TEST(opt_run_flips_keeps_the_model)
{
    const int n = 6;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION | MESH_WITH_FIXED), *m0;
    mesh_topo *t0 = NULL, *t1 = NULL;
    opt_options o;
    opt_result r0, r1;
    int32_t *b0, *b1, *i0, *i1;

    ASSERT_TRUE(m);
    tm_perturb(m, n, 0.25, 11);
    memset(m->fixed, 1, (size_t)m->nv);
    m0 = mesh_dup(m);
    ASSERT_TRUE(m0);
    ASSERT_OK(mesh_topo_build(m, &t0, NULL));
    ASSERT_EQ_INT(mesh_count_inverted(t0, m->xyz), 0);
    opt_defaults(&o);
    o.threads = 1;
    ASSERT_OK(opt_run(m0, &o, &r0, NULL));
    ASSERT_EQ_INT(m0->nt, m->nt);
    ASSERT_EQ_INT(r0.tets_in, 0); /* none: nothing counted */
    o.topology = OPT_TOPOLOGY_FLIPS;
    ASSERT_OK(opt_run(m, &o, &r1, NULL));
    ASSERT_EQ_INT(r1.tets_in, t0->nt);
    ASSERT_EQ_INT(r1.tets_out, m->nt);
    ASSERT_TRUE(r1.topo_edge_removals + r1.topo_flips23 + r1.topo_multiface > 0);
    ASSERT_TRUE(r1.topo_rounds >= 1);
    ASSERT_OK(mesh_topo_build(m, &t1, NULL));
    ASSERT_EQ_INT(mesh_count_inverted(t1, m->xyz), 0);
    ASSERT_EQ_INT(t1->nbf, t0->nbf);
    ASSERT_EQ_INT(t1->nif, t0->nif);
    b0 = face_set(t0->bfaces, t0->nbf);
    b1 = face_set(t1->bfaces, t1->nbf);
    i0 = face_set(t0->ifaces, t0->nif);
    i1 = face_set(t1->ifaces, t1->nif);
    ASSERT_TRUE(b0 && b1 && i0 && i1);
    ASSERT_TRUE(!memcmp(b0, b1, 12 * (size_t)t0->nbf));
    ASSERT_TRUE(!memcmp(i0, i1, 12 * (size_t)t0->nif));
    ASSERT_TRUE(r1.after.q_mean > r0.after.q_mean);
    ASSERT_TRUE(r1.after.q_min >= r0.after.q_min);
    free(b0);
    free(b1);
    free(i0);
    free(i1);
    mesh_topo_free(t0);
    mesh_topo_free(t1);
    mesh_free(m0);
    mesh_free(m);
}

/* The mean ratio of the tet (p, q, r, s): 12 (3 |V|)^(2/3) / (sum of its six
 * squared edges). */
static double mean_ratio_of(const double *p, const double *q, const double *r,
                            const double *s)
{
    metric_parts pt;

    metric_parts_for(OPT_METRIC_MIMR, p, q, r, s, &pt);
    return fabs(metric_mean_ratio(&pt));
}

/* With --boundary fixed no floor keeps a flat tet of four boundary corners
 * (TOPO_FLOOR4_FIXED): the three tets around the edge cd, every vertex on the
 * surface, a (-1,0,0) b (1,0,0) c (0,-1,0) d (0,1,0.003) and x near the plane
 * (abcd flat, mean ratio 0.016). Removing cd leaves abxc and abxd, mean ratio
 * 0.048 (under Stellar's floor of 0.1, three times the flat tet's) and a
 * larger smallest angle: taken, nothing moved. */
TEST(opt_run_fixed_flips_take_a_flat_tet)
{
    const double x0[15] = {-1, 0, 0, 1,     0,      0,      0,   -1,
                           0,  0, 1, 0.003, -0.441, -0.008, 0.01};
    const int32_t tv[12] = {0, 1, 2, 3, 2, 3, 1, 4, 2, 3, 4, 0};
    mesh_t *m = mesh_new(5, 3, 0);
    opt_options o;
    opt_result r;
    double q;

    ASSERT_TRUE(m);
    memcpy(m->xyz, x0, sizeof x0);
    memcpy(m->tets, tv, sizeof tv);
    q = fmin(mean_ratio_of(x0, x0 + 3, x0 + 12, x0 + 6),
             mean_ratio_of(x0, x0 + 3, x0 + 12, x0 + 9));
    ASSERT_TRUE(q > 0.04 && q < 0.1);
    opt_defaults(&o);
    o.threads = 1;
    o.topology = OPT_TOPOLOGY_FLIPS;
    o.boundary = OPT_BOUNDARY_FIXED;
    ASSERT_OK(opt_run(m, &o, &r, NULL));
    ASSERT_NEAR(r.before.q_min, mean_ratio_of(x0, x0 + 3, x0 + 6, x0 + 9), 1e-9);
    ASSERT_TRUE(r.before.q_min < 0.02);
    ASSERT_EQ_INT(r.tets_in, 3);
    ASSERT_EQ_INT(m->nt, 2);
    ASSERT_EQ_INT(r.topo_edge_removals, 1);
    ASSERT_NEAR(r.after.q_min, q, 1e-9);
    ASSERT_TRUE(!memcmp(m->xyz, x0, sizeof x0));
    mesh_free(m);
}

/* A unit cube of 2x2x2 cells, each cut into five tets (corners cut off, the
 * cut corners alternating so that the faces match), positively ordered. */
static mesh_t *five_tet_cube(void)
{
    mesh_t *m = mesh_new(27, 40, 0);
    int32_t nt = 0;

    if (!m)
        return NULL;
    for (int v = 0; v < 27; v++) {
        m->xyz[3 * v] = 0.5 * (v % 3);
        m->xyz[3 * v + 1] = 0.5 * (v / 3 % 3);
        m->xyz[3 * v + 2] = 0.5 * (v / 9);
    }
    for (int k = 0; k < 2; k++)
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < 2; i++) {
                /* the cell's corner b (bits x, y, z) and the cut ones */
                int32_t c[8];
                static const int cut[2][5][4] = {{{0, 1, 2, 4},
                                                  {3, 1, 2, 7},
                                                  {5, 1, 4, 7},
                                                  {6, 2, 4, 7},
                                                  {1, 2, 4, 7}},
                                                 {{1, 0, 3, 5},
                                                  {2, 0, 3, 6},
                                                  {4, 0, 5, 6},
                                                  {7, 3, 5, 6},
                                                  {0, 3, 5, 6}}};
                int par = (i + j + k) % 2;
                for (int b = 0; b < 8; b++)
                    c[b] = (i + (b & 1)) + 3 * (j + (b >> 1 & 1)) + 9 * (k + (b >> 2));
                for (int t = 0; t < 5; t++, nt++) {
                    int32_t *tt = m->tets + 4 * nt;
                    for (int a = 0; a < 4; a++)
                        tt[a] = c[cut[par][t][a]];
                    if (mean_ratio_of(m->xyz + 3 * tt[0], m->xyz + 3 * tt[1],
                                      m->xyz + 3 * tt[2], m->xyz + 3 * tt[3]) < 0) {
                        int32_t w = tt[0];
                        tt[0] = tt[1];
                        tt[1] = w;
                    }
                }
            }
    return m;
}

/* The corner tet of a box is a tet with three boundary faces, a good one:
 * its corners on the box's edges stay on them (lib/opt/opt.c free_fins frees
 * only a bad fin's). The box bent (z + 0.3 x (1 - x)), so that its edges along
 * x are not straight (the corners of a straight one slide on it anyway), the
 * centre moved off so that the smoothing has work: the midpoints of those
 * edges keep their y (0 or 1, the plane of the edge's faces' other side). */
TEST(flips_keep_a_good_corner_tets_edges)
{
    mesh_t *m = five_tet_cube();
    opt_options o;
    opt_result r;
    int on_edges = 0;

    ASSERT_TRUE(m);
    for (int v = 0; v < 27; v++)
        m->xyz[3 * v + 2] += 0.3 * m->xyz[3 * v] * (1 - m->xyz[3 * v]);
    m->xyz[3 * 13] += 0.12; /* the centre */
    m->xyz[3 * 13 + 1] -= 0.07;
    m->xyz[3 * 13 + 2] += 0.05;
    opt_defaults(&o);
    o.threads = 1;
    o.topology = OPT_TOPOLOGY_FLIPS;
    ASSERT_OK(opt_run(m, &o, &r, NULL));
    ASSERT_EQ_INT(r.after.n_inverted, 0);
    /* the midpoints of the 4 edges along x: y as given (0 or 1) */
    for (int v = 1; v < 27; v += 3) {
        int gy = v / 3 % 3, gz = v / 9;
        if (gy == 1 || gz == 1)
            continue;
        ASSERT_TRUE(m->xyz[3 * v + 1] == 0.5 * gy);
        on_edges++;
    }
    ASSERT_EQ_INT(on_edges, 4);
    mesh_free(m);
}

/* What the rounds of --topology flips rely on to orient the tets once per
 * round (lib/opt/topology.c, orient_memo_get): a flip mesh_orient found stays
 * its answer after the vertices move, as long as every tet is positive
 * under it (written orders mixed, then every tet reversed). */
TEST(orientation_found_again_while_positive)
{
    const int n = 4;
    mesh_t *m = tm_grid(n, 0);
    uint8_t *f0, *f1;
    mesh_orientation mo;

    ASSERT_TRUE(m);
    f0 = malloc((size_t)m->nt);
    f1 = malloc((size_t)m->nt);
    ASSERT_TRUE(f0 && f1);
    for (int pass = 0; pass < 2; pass++) {
        for (int32_t t = 0; t < m->nt; t++)
            if (pass == 1 || t % 3 == 0) {
                int32_t x = m->tets[4 * t];
                m->tets[4 * t] = m->tets[4 * t + 1];
                m->tets[4 * t + 1] = x;
            }
        ASSERT_OK(mesh_orient(m, f0, &mo, NULL));
        tm_perturb(m, n, 0.2, 3 + (uint64_t)pass);
        for (int32_t t = 0; t < m->nt; t++) {
            double d = geom_tet_vol6(m->xyz, m->tets + 4 * t);
            ASSERT_TRUE(f0[t] ? d < 0 : d > 0);
        }
        ASSERT_OK(mesh_orient(m, f1, &mo, NULL));
        ASSERT_TRUE(!memcmp(f0, f1, (size_t)m->nt));
    }
    free(f0);
    free(f1);
    mesh_free(m);
}

/* Inverted input tets (all vertices fixed, so nothing untangles them) are left
 * as they are: no cavity holds one, and no new tet is inverted. */
TEST(opt_run_flips_leaves_inverted_input_alone)
{
    const int n = 6;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION | MESH_WITH_FIXED);
    mesh_topo *t0 = NULL, *t1 = NULL;
    opt_options o;
    opt_result r;
    int32_t inv0;

    ASSERT_TRUE(m);
    tm_perturb(m, n, 0.35, 11);
    memset(m->fixed, 1, (size_t)m->nv);
    ASSERT_OK(mesh_topo_build(m, &t0, NULL));
    inv0 = mesh_count_inverted(t0, m->xyz);
    ASSERT_TRUE(inv0 > 0);
    opt_defaults(&o);
    o.topology = OPT_TOPOLOGY_FLIPS;
    ASSERT_OK(opt_run(m, &o, &r, NULL));
    ASSERT_TRUE(r.topo_edge_removals + r.topo_flips23 + r.topo_multiface > 0);
    ASSERT_OK(mesh_topo_build(m, &t1, NULL));
    ASSERT_EQ_INT(mesh_count_inverted(t1, m->xyz), inv0);
    mesh_topo_free(t0);
    mesh_topo_free(t1);
    mesh_free(m);
}

/* --topology runs on the mesh numbered along a space-filling curve
 * (lib/opt/toporder.c) and gives the vertices back in the caller's order: a
 * grid (numbered by rows, which the curve reorders) keeps each vertex's
 * number with flips, its ref and point value with it; with full the input's
 * kept vertices come first, in their order, the new ones after with ref 0. */
TEST(topology_keeps_the_vertex_numbers)
{
    const int n = 6;

    for (int mode = 0; mode < 2; mode++) {
        mesh_t *m = tm_grid(n, MESH_WITH_REGION | MESH_WITH_FIXED | MESH_WITH_VREF), *m0;
        double *id;
        opt_options o;
        opt_result r;
        int32_t last = -1, kept = 0;

        ASSERT_TRUE(m);
        tm_perturb(m, n, 0.3, 7);
        id = qdc_mallocn((size_t)m->nv, sizeof *id);
        ASSERT_TRUE(id);
        for (int32_t v = 0; v < m->nv; v++) {
            m->vref[v] = 100 + v;
            id[v] = v;
            m->fixed[v] = v % 5 == 0;
        }
        ASSERT_OK(mesh_pdata_add(m, "id", 2, 1, 1, NULL, id, NULL));
        m0 = mesh_dup(m);
        ASSERT_TRUE(m0);
        opt_defaults(&o);
        o.topology = mode ? OPT_TOPOLOGY_FULL : OPT_TOPOLOGY_FLIPS;
        ASSERT_OK(opt_run(m, &o, &r, NULL));
        ASSERT_TRUE(r.topo_edge_removals + r.topo_flips23 + r.topo_multiface > 0);
        if (!mode)
            ASSERT_EQ_INT(m->nv, m0->nv);
        for (int32_t v = 0; v < m->nv; v++) {
            int32_t u = m->vref[v] - 100;
            if (m->vref[v] == 0) { /* full's new vertices come last */
                ASSERT_TRUE(mode == 1 && v >= kept);
                ASSERT_TRUE(m->pdata->made[v] == 1);
                continue;
            }
            ASSERT_TRUE(u > last && u < m0->nv); /* the input's, in its order */
            ASSERT_TRUE(v == kept);
            ASSERT_TRUE(m->pdata->a[0].v[v] == u);
            ASSERT_EQ_INT(m->fixed[v], m0->fixed[u]);
            if (m0->fixed[u]) /* where it was, bit for bit */
                ASSERT_TRUE(!memcmp(m->xyz + 3 * v, m0->xyz + 3 * (size_t)u, 24));
            last = u;
            kept++;
        }
        if (!mode)
            ASSERT_EQ_INT(kept, m0->nv);
        mesh_free(m0);
        mesh_free(m);
    }
}

/* A run that changes no tet gives them back in their order too, so that a
 * file can be written back as it was read: a cube cut into five tets per cell,
 * none under the flips' goal. */
TEST(topology_without_a_flip_keeps_the_tets_in_order)
{
    mesh_t *m = five_tet_cube(), *m0;
    opt_options o;
    opt_result r;

    ASSERT_TRUE(m);
    m->xyz[3 * 13] += 0.02; /* the centre, off */
    m0 = mesh_dup(m);
    ASSERT_TRUE(m0);
    opt_defaults(&o);
    o.topology = OPT_TOPOLOGY_FLIPS;
    ASSERT_OK(opt_run(m, &o, &r, NULL));
    ASSERT_EQ_INT(r.topo_edge_removals + r.topo_flips23 + r.topo_multiface, 0);
    ASSERT_EQ_INT(m->nt, m0->nt);
    ASSERT_TRUE(!memcmp(m->tets, m0->tets, 16 * (size_t)m->nt));
    ASSERT_TRUE(fabs(m->xyz[3 * 13] - 0.5) < 0.01); /* the centre moved back */
    mesh_free(m0);
    mesh_free(m);
}

#ifdef QDC_FAULT_INJECTION
/* opt_run on a copy of m0 under o: without a failure (that copy into *clean,
 * its allocations counted in *total), then with the allocations failing from
 * the k-th on, for k = 1, 1 + stride, ... up to *total: either QDC_ENOMEM with
 * the mesh as it came in (counted in *failed), or a valid mesh (none
 * inverted). */
static void fault_sweep(const mesh_t *m0, const opt_options *o, long stride,
                        mesh_t **clean, long *total, long *failed)
{
    *clean = mesh_dup(m0);
    ASSERT_TRUE(*clean);
    qdc_fault_set(0);
    ASSERT_OK(opt_run(*clean, o, NULL, NULL));
    *total = qdc_fault_count();
    for (long k = 1; k <= *total; k += stride) {
        mesh_topo *tp = NULL;
        mesh_t *m = mesh_dup(m0);
        qdc_status st;
        ASSERT_TRUE(m);
        qdc_fault_set(k);
        st = opt_run(m, o, NULL, NULL);
        qdc_fault_set(0);
        if (st != QDC_OK) {
            ASSERT_EQ_INT(st, QDC_ENOMEM);
            ASSERT_EQ_INT(m->nt, m0->nt);
            ASSERT_EQ_INT(m->nv, m0->nv);
            ASSERT_TRUE(!memcmp(m->tets, m0->tets, 16 * (size_t)m->nt));
            ASSERT_TRUE(!memcmp(m->xyz, m0->xyz, 24 * (size_t)m->nv));
            (*failed)++;
        } else {
            ASSERT_OK(mesh_topo_build(m, &tp, NULL));
            ASSERT_EQ_INT(mesh_count_inverted(tp, m->xyz), 0);
            mesh_topo_free(tp);
        }
        mesh_free(m);
    }
}
#endif

/* Every allocation of a flips run failed in turn: either the run fails with the
 * mesh as it was, or it returns a valid mesh (a later round's failure returns
 * the mesh of the round before, as a stopped run). */
TEST(flips_allocation_failures_are_clean)
{
#ifdef QDC_FAULT_INJECTION
    const int n = 3;
    mesh_t *m0 = tm_grid(n, MESH_WITH_REGION | MESH_WITH_FIXED), *m;
    opt_options o;
    long total = 0, failed = 0;

    ASSERT_TRUE(m0);
    tm_perturb(m0, n, 0.25, 5);
    memset(m0->fixed, 1, (size_t)m0->nv);
    opt_defaults(&o);
    o.topology = OPT_TOPOLOGY_FLIPS;
    o.threads = 1;
    fault_sweep(m0, &o, 1, &m, &total, &failed);
    ASSERT_TRUE(m && (m->nt != m0->nt || memcmp(m->tets, m0->tets, 16 * (size_t)m->nt)));
    mesh_free(m);
    ASSERT_TRUE(failed > 10);
    printf("  # %ld allocation failure points, %ld failed the run, each clean\n", total,
           failed);
    mesh_free(m0);
#else
    SKIP("built without QDC_FAULT_INJECTION (make fault runs it)");
#endif
}

/* --topology full on a perturbed 6x6x6 grid, whose last round contracts
 * vertices by gain (vertices renumbered, the smoothing held to the vertices
 * near the contractions): an allocation failure at every fourth point in turn
 * either fails the run with QDC_ENOMEM and the mesh as it came in, or the run
 * ends valid (a round that failed is dropped); no leak (ASan in make fault).
 * A failure after the first smoothing used to return QDC_ENOMEM with the
 * vertices moved. */
TEST(full_allocation_failures_are_clean)
{
#ifdef QDC_FAULT_INJECTION
    const int n = 6;
    mesh_t *m0 = tm_grid(n, MESH_WITH_REGION), *m;
    opt_options o;
    long total = 0, failed = 0;

    ASSERT_TRUE(m0);
    tm_perturb(m0, n, 0.4, 6);
    opt_defaults(&o);
    o.topology = OPT_TOPOLOGY_FULL;
    o.threads = 1;
    fault_sweep(m0, &o, 4, &m, &total, &failed); /* every fourth: a run is slow */
    ASSERT_TRUE(m && m->nv < m0->nv);            /* vertices went */
    mesh_free(m);
    ASSERT_TRUE(failed > 10);
    printf("  # %ld allocation failure points, every fourth tried, %ld failed the run, "
           "each clean\n",
           total, failed);
    mesh_free(m0);
#else
    SKIP("built without QDC_FAULT_INJECTION (make fault runs it)");
#endif
}

/* The boundary faces of tm as triangles in tet_face_of order (outward), ref
 * top for those in z >= ztop, else 3; *n their count (room for 16). */
static void surface_of(const tmesh *tm, double ztop, int32_t top, int32_t tris[16][3],
                       int32_t refs[16], int32_t *n)
{
    *n = 0;
    for (int32_t t = 0; t < tm->hi; t++)
        for (int i = 0; i < 4 && tm->tv[4 * t] >= 0; i++) {
            int up = 1;
            if (tm->adj[4 * t + i] >= 0)
                continue;
            for (int s = 0; s < 3; s++) {
                tris[*n][s] = tm->tv[4 * t + tet_face_of[i][s]];
                up &= tm->xyz[3 * tris[*n][s] + 2] >= ztop;
            }
            refs[(*n)++] = up ? top : 3;
        }
}

/* Two tets under the rhombus a (-2,0,0) b (2,0,0) c (0,-1,z) d (0,1,0) over
 * p (0,0,-1), around the boundary edge ab; 6V = 4 each when z = 0. */
static tmesh *rhombus_pair(double z)
{
    double x[5 * 3] = {-2, 0, 0, 2, 0, 0, 0, -1, z, 0, 1, 0, 0, 0, -1};
    int32_t tv[8] = {0, 1, 2, 4, 1, 0, 3, 4};
    tmesh *tm = NULL;

    if (tmesh_new(5, x, 2, tv, NULL, NULL, &tm, NULL) != QDC_OK)
        return NULL;
    return tm;
}

/* The coplanar pair: edge ab (length 4) becomes cd (length 2), the volume
 * exactly kept, the surface not moved; the two top triangles (ref 7) replaced
 * by two with ref 7, their removal logged; refused without a bound, across
 * refs, and beyond the bound when c leaves the plane. */
TEST(boundary_flip_2_2_coplanar)
{
    tmesh *tm = rhombus_pair(0.0);
    int32_t tris[16][3], refs[16], n = 0, ids[4];
    flip_bound bd = {1e-9, cos(30 * PI / 180)}, none = {0.0, bd.cos_feature};
    flip_cand c;
    int applied = 0, e = -1, made = 0;

    ASSERT_TRUE(tm != NULL);
    surface_of(tm, 0.0, 7, tris, refs, &n);
    ASSERT_EQ_INT(n, 6);
    ASSERT_OK(tmesh_set_surface(tm, n, &tris[0][0], refs));
    for (int k = 0; k < 6; k++) /* edge ab of tet 0 */
        if ((tm->tv[tmesh_edge[k][0]] == 0 && tm->tv[tmesh_edge[k][1]] == 1) ||
            (tm->tv[tmesh_edge[k][0]] == 1 && tm->tv[tmesh_edge[k][1]] == 0))
            e = k;
    ASSERT_TRUE(e >= 0);
    ASSERT_EQ_INT(flip_edge_eval(tm, 0, e, 10, 0.0, -INFINITY, &c), 0); /* constrained */
    ASSERT_EQ_INT(flip_bedge_eval(tm, 0, e, 10, 0.0, 0.0, &none, &c), 0);
    ASSERT_EQ_INT(flip_bedge_eval(tm, 0, e, 10, 0.0, 0.0, &bd, &c), 1);
    ASSERT_EQ_INT(c.kind, FLIP_BEDGE);
    ASSERT_EQ_INT(c.nold, 2);
    ASSERT_EQ_INT(c.nnew, 2);
    ASSERT_NEAR(c.dev, 0.0, 0);
    ASSERT_TRUE(c.qmin_new > c.qmin_old);
    ASSERT_OK(tmesh_replace_surface(tm, c.old, c.nold, (const int32_t(*)[4])c.newt,
                                    c.nnew, c.dev, ids, &applied));
    ASSERT_EQ_INT(applied, 1);
    tmesh_commit(tm);
    ASSERT_TRUE(consistent(tm));
    ASSERT_EQ_INT(tm->nlive, 2);
    ASSERT_NEAR(geom_tet_vol6(tm->xyz, tm->tv + 4 * ids[0]), 4.0, 0);
    ASSERT_NEAR(geom_tet_vol6(tm->xyz, tm->tv + 4 * ids[1]), 4.0, 0);
    ASSERT_NEAR(total_vol6(tm), 8.0, 0);
    ASSERT_EQ_INT(tm->ngone, 2);
    for (int j = 0; j < 2; j++) {
        const int32_t *tt = tm->tv + 4 * ids[j];
        ASSERT_TRUE(tmesh_local(tm, ids[j], 2) >= 0 && tmesh_local(tm, ids[j], 3) >= 0);
        for (int i = 0; i < 4; i++)
            if (tm->fsurf[ids[j]] >> i & 1) { /* a new top face: ref 7, cd constrained */
                ASSERT_EQ_INT(tm->adj[4 * ids[j] + i], -1);
                ASSERT_EQ_INT(tm->fref[4 * ids[j] + i], 7);
                ASSERT_EQ_INT(tt[i], 4); /* opposite p */
                made++;
            }
        ASSERT_EQ_INT(tm->econs[ids[j]], 63); /* every edge on the surface */
    }
    ASSERT_EQ_INT(made, 2);
    tmesh_free(tm);

    /* c lifted by 0.1: the slab is 6V / |ab x cd| = 0.4 / |(0, 0.4, 8)| thick */
    tm = rhombus_pair(0.1);
    ASSERT_TRUE(tm != NULL);
    surface_of(tm, -0.5, 7, tris, refs, &n);
    for (int k = 0; k < n; k++) /* the top two: ref 7, the rest 3 */
        refs[k] = (tris[k][0] == 4 || tris[k][1] == 4 || tris[k][2] == 4) ? 3 : 7;
    ASSERT_OK(tmesh_set_surface(tm, n, &tris[0][0], refs));
    bd.hausd = 0.049;
    ASSERT_EQ_INT(flip_bedge_eval(tm, 0, e, 10, 0.0, 0.0, &bd, &c), 0);
    bd.hausd = 0.051;
    ASSERT_EQ_INT(flip_bedge_eval(tm, 0, e, 10, 0.0, 0.0, &bd, &c), 1);
    ASSERT_NEAR(c.dev, 0.4 / sqrt(64.16), 1e-15);
    for (int k = 0; k < n; k++) /* the top triangles' refs differ: refused */
        if (refs[k] == 7 && (tris[k][0] == 3 || tris[k][1] == 3 || tris[k][2] == 3))
            refs[k] = 8;
    ASSERT_OK(tmesh_set_surface(tm, n, &tris[0][0], refs));
    ASSERT_EQ_INT(flip_bedge_eval(tm, 0, e, 10, 0.0, 0.0, &bd, &c), 0);
    tmesh_free(tm);
}

/* Peeling the sliver (a, b, c, d), a (-2,0,0) b (2,0,0) c (0,-1,-1/8)
 * d (0,1,-1/8), 6V = 8h = 1, off the tets (d, c, a, p) and (c, d, b, p),
 * p (0,0,-1), 6V = 4 - 4h = 3.5 each: 6V 8 -> 7, the faces cda and cdb
 * become boundary (ref 7, the sliver's), edge cd constrained, the surface
 * moved by the slab h = 1/8; rolled back exactly. */
TEST(peeling_a_flat_boundary_tet)
{
    double x[5 * 3] = {-2, 0, 0, 2, 0, 0, 0, -1, -0.125, 0, 1, -0.125, 0, 0, -1};
    int32_t tv[12] = {0, 1, 2, 3, 3, 2, 0, 4, 2, 3, 1, 4};
    int32_t tris[16][3], refs[16], n = 0;
    flip_bound bd = {0.124, cos(30 * PI / 180)};
    tmesh *tm = NULL;
    flip_cand c;
    int applied = 0;

    ASSERT_OK(tmesh_new(5, x, 3, tv, NULL, NULL, &tm, NULL));
    ASSERT_NEAR(total_vol6(tm), 8.0, 0);
    surface_of(tm, 0.0, 7, tris, refs, &n);
    for (int k = 0; k < n; k++) /* the sliver's top faces: ref 7 */
        refs[k] = (tris[k][0] == 4 || tris[k][1] == 4 || tris[k][2] == 4) ? 3 : 7;
    ASSERT_OK(tmesh_set_surface(tm, n, &tris[0][0], refs));
    ASSERT_EQ_INT(flip_peel_eval(tm, 0, 0.0, &bd, &c), 0); /* beyond the bound */
    bd.hausd = 0.126;
    ASSERT_EQ_INT(flip_peel_eval(tm, 0, 0.0, &bd, &c), 1);
    ASSERT_EQ_INT(c.kind, FLIP_PEEL);
    ASSERT_EQ_INT(c.nnew, 0);
    ASSERT_NEAR(c.dev, 0.125, 1e-15);
    ASSERT_TRUE(c.qmin_new > c.qmin_old);
    ASSERT_OK(tmesh_replace_surface(tm, c.old, c.nold, NULL, 0, c.dev, NULL, &applied));
    ASSERT_EQ_INT(applied, 1);
    ASSERT_TRUE(consistent(tm));
    ASSERT_EQ_INT(tm->nlive, 2);
    ASSERT_NEAR(total_vol6(tm), 7.0, 0);
    ASSERT_EQ_INT(tm->ngone, 2);
    for (int32_t t = 1; t < 3; t++) {
        int f = tmesh_local(tm, t, 4); /* the face opposite p: cda or cdb */
        int lc = tmesh_local(tm, t, 2), ld = tmesh_local(tm, t, 3), ecd = -1;
        ASSERT_EQ_INT(tm->adj[4 * t + f], -1);
        ASSERT_EQ_INT(tm->fref[4 * t + f], 7);
        ASSERT_NEAR(tm->fdev[4 * t + f], 0.125, 1e-15);
        for (int k = 0; k < 6; k++)
            if ((tmesh_edge[k][0] == lc && tmesh_edge[k][1] == ld) ||
                (tmesh_edge[k][0] == ld && tmesh_edge[k][1] == lc))
                ecd = k;
        ASSERT_EQ_INT(tm->econs[t] >> ecd & 1, 1);
    }
    tmesh_rollback(tm);
    ASSERT_TRUE(consistent(tm));
    ASSERT_EQ_INT(tm->nlive, 3);
    ASSERT_EQ_INT(tm->ngone, 0);
    ASSERT_NEAR(total_vol6(tm), 8.0, 0);
    ASSERT_EQ_INT(tm->fcons[1] >> tmesh_local(tm, 1, 4) & 1, 0);
    tmesh_free(tm);
}

/* The driver with a bound on the coplanar pair: one boundary flip, and the
 * triangles handed back are the four untouched ones in their order, then the
 * two new top ones with ref 7, facing up (+z) as the input's did. */
TEST(driver_writes_the_new_boundary_triangles)
{
    double x[5 * 3] = {-2, 0, 0, 2, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, -1};
    int32_t tv[8] = {0, 1, 2, 4, 1, 0, 3, 4}, tris[16][3], refs[16], n = 0;
    int32_t nt = 0, nv = 0, *tets = NULL;
    double *xo = NULL;
    tmesh *tm = rhombus_pair(0.0);
    topo_params p;
    topo_stats st;
    topo_surface sf = {0};

    ASSERT_TRUE(tm != NULL);
    surface_of(tm, 0.0, 7, tris, refs, &n);
    tmesh_free(tm);
    topo_params_default(&p);
    p.qgoal = 1.0;
    p.bound.hausd = 1e-9;
    sf.ntri = n;
    sf.tris = &tris[0][0];
    sf.refs = refs;
    ASSERT_OK(topo_full_arrays(5, x, 2, tv, NULL, NULL, &p, NULL, &nv, &xo, &nt, &tets,
                               NULL, NULL, &sf, &st, NULL));
    ASSERT_EQ_INT(st.bflips, 1);
    ASSERT_EQ_INT(nt, 2);
    ASSERT_EQ_INT(sf.removed, 2);
    ASSERT_EQ_INT(sf.added, 2);
    ASSERT_EQ_INT(sf.ntri_out, 6);
    for (int k = 0, j = 0; k < n; k++)
        if (refs[k] != 7) {
            ASSERT_EQ_INT(memcmp(sf.tris_out + 3 * j, tris[k], sizeof tris[k]), 0);
            j++;
        }
    for (int k = 4; k < 6; k++) {
        const int32_t *t = sf.tris_out + 3 * k;
        double u[3], v[3];
        ASSERT_EQ_INT(sf.refs_out[k], 7);
        for (int s = 0; s < 3; s++) {
            u[s] = x[3 * t[1] + s] - x[3 * t[0] + s];
            v[s] = x[3 * t[2] + s] - x[3 * t[0] + s];
        }
        ASSERT_TRUE(u[0] * v[1] - u[1] * v[0] > 0); /* facing +z */
        ASSERT_TRUE((t[0] == 2 || t[1] == 2 || t[2] == 2) &&
                    (t[0] == 3 || t[1] == 3 || t[2] == 3));
    }
    qdc_free(sf.tris_out);
    qdc_free(sf.refs_out);
    qdc_free(tets);
    qdc_free(xo);
}

/* The bound spent before a run (topo_surface.vdev): the peel of the sliver of
 * peeling_a_flat_boundary_tet moves the surface by h = 1/8. With nothing
 * spent and the bound 0.126 it is made, and the corners of the two faces it
 * makes (a, b, c, d; not p) come back with 1/8 spent and marked; with 0.002
 * spent at a (on the sliver's top faces, so they start at 0.002) 1/8 more is
 * over the bound: refused, nothing marked, vdev as it was. */
TEST(driver_spends_one_bound)
{
    double x[5 * 3] = {-2, 0, 0, 2, 0, 0, 0, -1, -0.125, 0, 1, -0.125, 0, 0, -1};
    int32_t tv[12] = {0, 1, 2, 3, 3, 2, 0, 4, 2, 3, 1, 4};
    int32_t tris[16][3], refs[16], n = 0, nt = 0, nv = 0, *tets = NULL;
    double vdev[5], *xo = NULL;
    uint8_t vop[5];
    tmesh *tm = NULL;
    topo_params p;
    topo_stats st;
    topo_surface sf = {0};

    ASSERT_OK(tmesh_new(5, x, 3, tv, NULL, NULL, &tm, NULL));
    surface_of(tm, 0.0, 7, tris, refs, &n);
    tmesh_free(tm);
    for (int k = 0; k < n; k++)
        refs[k] = (tris[k][0] == 4 || tris[k][1] == 4 || tris[k][2] == 4) ? 3 : 7;
    topo_params_default(&p);
    p.qgoal = 1.0;
    p.bound.hausd = 0.126;
    for (int pass = 0; pass < 2; pass++) {
        memset(vdev, 0, sizeof vdev);
        memset(vop, 0, sizeof vop);
        vdev[0] = pass ? 0.002 : 0.0;
        vdev[4] = 0.01; /* on none of the sliver's faces */
        sf.ntri = n;
        sf.tris = &tris[0][0];
        sf.refs = refs;
        sf.vdev = vdev;
        sf.vop = vop;
        ASSERT_OK(topo_full_arrays(5, x, 3, tv, NULL, NULL, &p, NULL, &nv, &xo, &nt,
                                   &tets, NULL, NULL, &sf, &st, NULL));
        ASSERT_EQ_INT(st.peels, pass ? 0 : 1);
        for (int v = 0; v < 4; v++) {
            ASSERT_NEAR(vdev[v], pass ? (v == 0 ? 0.002 : 0.0) : 0.125, 0);
            ASSERT_EQ_INT(vop[v], pass ? 0 : 1);
        }
        ASSERT_NEAR(vdev[4], 0.01, 0);
        ASSERT_EQ_INT(vop[4], 0);
        qdc_free(sf.tris_out);
        qdc_free(sf.refs_out);
        qdc_free(tets);
        qdc_free(xo);
        tets = NULL;
        xo = NULL;
    }
}

/* Contraction on a 4x4x4 Kuhn grid of the unit cube (coordinates in quarters,
 * the centre vertex moved by (1/64, 1/128, 0): every 6V a multiple of 2^-13,
 * sums exact): some interior edge contracts; the volume is kept exactly, the
 * tets of the edge's ring vanish, the vertex that went is used by no tet, the
 * adjacency stays consistent; an edge with a boundary end never contracts. */
TEST(contraction_keeps_the_volume_exactly)
{
    mesh_t *m = tm_grid(4, 0);
    tmesh *tm = NULL;
    contract_cand c;
    int32_t centre = 2 + 5 * (2 + 5 * 2);
    double v0;
    int found = 0, applied = 0, refused = 1;

    ASSERT_TRUE(m);
    m->xyz[3 * centre] += 1.0 / 64;
    m->xyz[3 * centre + 1] += 1.0 / 128;
    ASSERT_OK(tmesh_new(m->nv, m->xyz, m->nt, m->tets, NULL, NULL, &tm, NULL));
    v0 = total_vol6(tm);
    ASSERT_NEAR(v0, 6.0, 0);
    for (int32_t t = 0; t < tm->hi && !found; t++)
        for (int e = 0; e < 6 && !found; e++) {
            int32_t a = tm->tv[4 * t + tmesh_edge[e][0]],
                    b = tm->tv[4 * t + tmesh_edge[e][1]];
            int ok = contract_eval(tm, t, e, 0.0, -INFINITY, 0.0, &c);
            if (tm->vcons[a] || tm->vcons[b])
                refused &= !ok;
            else if (ok && (c.gone == centre || c.keep == centre))
                found = 1;
        }
    ASSERT_TRUE(refused);
    ASSERT_TRUE(found);
    ASSERT_TRUE(c.nnew < c.nold);
    ASSERT_OK(tmesh_replace(tm, c.old, c.nold, (const int32_t(*)[4])c.newt, c.nnew, NULL,
                            &applied));
    ASSERT_EQ_INT(applied, 1);
    tmesh_commit(tm);
    ASSERT_TRUE(consistent(tm));
    ASSERT_EQ_INT(tm->nlive, m->nt - (c.nold - c.nnew));
    ASSERT_NEAR(total_vol6(tm), v0, 0);
    for (int32_t t = 0; t < tm->hi; t++)
        if (tm->tv[4 * t] >= 0)
            ASSERT_TRUE(tmesh_local(tm, t, c.gone) < 0);
    tmesh_free(tm);
    mesh_free(m);
}

/* Contraction by gain (qfloor 0.5) on a 6x6x6 Kuhn grid with its interior
 * vertices perturbed: each candidate removes tets, every new tet's mean ratio
 * is above the floor, its gain is the sum of (1 - q) over the old tets less
 * that over the new (recomputed here); some of them the contraction that must
 * raise the smallest quality refuses (the two criteria differ). */
TEST(contraction_by_gain_keeps_new_tets_above_the_floor)
{
    const int n = 6;
    mesh_t *m = tm_grid(n, 0);
    tmesh *tm = NULL;
    int found = 0, gain_only = 0;

    ASSERT_TRUE(m);
    tm_perturb(m, n, 0.35, 7);
    ASSERT_OK(tmesh_new(m->nv, m->xyz, m->nt, m->tets, NULL, NULL, &tm, NULL));
    for (int32_t t = 0; t < tm->hi; t++)
        for (int e = 0; e < 6; e++) {
            contract_cand c, d;
            double g = 0.0;
            if (!contract_eval(tm, t, e, 0.0, 1e-3, 0.5, &c))
                continue;
            found++;
            ASSERT_TRUE(c.nnew < c.nold);
            ASSERT_TRUE(c.qmin_new > 0.5);
            for (int k = 0; k < c.nold; k++)
                g += 1.0 - tm->q[c.old[k]];
            for (int k = 0; k < c.nnew; k++) {
                double q = tmesh_quality(tm, c.newt[k], 0.0);
                ASSERT_TRUE(q > 0.5);
                g -= 1.0 - q;
            }
            ASSERT_TRUE(c.gain > 0.0);
            ASSERT_NEAR(c.gain, g, 1e-12);
            gain_only += !contract_eval(tm, t, e, 0.0, 1e-3, 0.0, &d);
        }
    ASSERT_TRUE(found > 0);
    ASSERT_TRUE(gain_only > 0);
    tmesh_free(tm);
    mesh_free(m);
}

/* The boundary faces of tm (faces with no tet across). */
static int32_t open_faces(const tmesh *tm)
{
    int32_t n = 0;
    for (int32_t t = 0; t < tm->hi; t++)
        for (int i = 0; i < 4 && tm->tv[4 * t] >= 0; i++)
            n += tm->adj[4 * t + i] < 0;
    return n;
}

/* Boundary edge contraction on the 4x4x4 Kuhn grid of the unit cube, the
 * centre vertex u of the top face moved in its plane by (1/64, 1/128, 0):
 * never without a bound; with one, u goes onto a neighbour w of the top face,
 * the move bound is in (0, |uw|], the cube is kept (volume exactly 6/6, the
 * boundary two triangles fewer, u in no tet); a vertex on an edge of the cube
 * goes only along it (elsewhere its side triangles would fold); no candidate
 * moves the surface by more than the bound. */
TEST(boundary_contraction_keeps_a_flat_face)
{
    mesh_t *m = tm_grid(4, 0);
    tmesh *tm = NULL;
    flip_bound bd = {10.0, cos(30 * PI / 180)}, none = {0.0, bd.cos_feature};
    contract_cand c, pick;
    int32_t u = 2 + 5 * (2 + 5 * 4), dummy[3] = {0, 1, 2}, nb0;
    double v0, uw;
    int found = 0, applied = 0, refused = 1, along = 1, bounded = 1;

    ASSERT_TRUE(m);
    m->xyz[3 * u] += 1.0 / 64;
    m->xyz[3 * u + 1] += 1.0 / 128;
    ASSERT_OK(tmesh_new(m->nv, m->xyz, m->nt, m->tets, NULL, NULL, &tm, NULL));
    ASSERT_OK(tmesh_set_surface(tm, 0, dummy, NULL));
    v0 = total_vol6(tm);
    nb0 = open_faces(tm);
    ASSERT_NEAR(v0, 6.0, 0);
    for (int32_t t = 0; t < tm->hi; t++)
        for (int e = 0; e < 6; e++) {
            const double *g, *k;
            int on_edge;
            refused &= !contract_bedge_eval(tm, t, e, 0.0, -INFINITY, &none, &c);
            if (!contract_bedge_eval(tm, t, e, 0.0, -INFINITY, &bd, &c))
                continue;
            ASSERT_EQ_INT(c.bnd, 1);
            g = tm->xyz + 3 * c.gone;
            k = tm->xyz + 3 * c.keep;
            on_edge = (g[0] == 0 || g[0] == 1) + (g[1] == 0 || g[1] == 1) +
                          (g[2] == 0 || g[2] == 1) ==
                      2;
            for (int d = 0; d < 3 && on_edge; d++)
                if ((g[d] == 0 || g[d] == 1) && k[d] != g[d])
                    along = 0;
            if (c.gone == u && !found) {
                pick = c;
                found = 1;
            }
        }
    ASSERT_TRUE(refused);
    ASSERT_TRUE(along);
    ASSERT_TRUE(found);
    uw = sqrt(pow(tm->xyz[3 * u] - tm->xyz[3 * pick.keep], 2) +
              pow(tm->xyz[3 * u + 1] - tm->xyz[3 * pick.keep + 1], 2) +
              pow(tm->xyz[3 * u + 2] - tm->xyz[3 * pick.keep + 2], 2));
    ASSERT_TRUE(pick.dev > 0 && pick.dev <= uw);
    ASSERT_NEAR(tm->xyz[3 * pick.keep + 2], 1.0, 0);
    /* a bound just under this move: no candidate exceeds it */
    bd.hausd = 0.999 * pick.dev;
    for (int32_t t = 0; t < tm->hi; t++)
        for (int e = 0; e < 6; e++)
            if (contract_bedge_eval(tm, t, e, 0.0, -INFINITY, &bd, &c))
                bounded &= c.dev <= bd.hausd && !(c.gone == u && c.keep == pick.keep);
    ASSERT_TRUE(bounded);
    ASSERT_OK(tmesh_replace_surface(tm, pick.old, pick.nold,
                                    (const int32_t(*)[4])pick.newt, pick.nnew, pick.dev,
                                    NULL, &applied));
    ASSERT_EQ_INT(applied, 1);
    tmesh_commit(tm);
    ASSERT_TRUE(consistent(tm));
    ASSERT_NEAR(total_vol6(tm), v0, 0);
    ASSERT_EQ_INT(open_faces(tm), nb0 - 2);
    for (int32_t t = 0; t < tm->hi; t++)
        if (tm->tv[4 * t] >= 0)
            ASSERT_TRUE(tmesh_local(tm, t, u) < 0);
    tmesh_free(tm);
    mesh_free(m);
}

/* The ring of 4 tets around the axis from (0,0,-3) to (0,0,3) over the unit
 * square's corners (an octahedron, 6V = 4 * 6 = 24, every face on the
 * boundary but those with the axis): its axis split at (0,0,0) gives 8 tets,
 * the volume exactly, the boundary faces as they were, and the split undone
 * gives the mesh back exactly. */
TEST(edge_split_at_the_midpoint)
{
    tmesh *tm = ring_mesh(4, -3, 3, NULL);
    int32_t ids[2 * SPLIT_MAXRING], nf0, nf1, *f0, *f1;
    int done = 0, nn = 0;
    snap s;

    ASSERT_TRUE(tm);
    ASSERT_NEAR(total_vol6(tm), 24.0, 1e-12);
    f0 = cons_faces(tm, &nf0);
    ASSERT_TRUE(f0);
    ASSERT_TRUE(snap_take(tm, &s));
    ASSERT_EQ_INT(tmesh_local(tm, 0, 0), 0);
    ASSERT_EQ_INT(tmesh_local(tm, 0, 1), 1); /* edge 0 of tet 0 is the axis */
    ASSERT_OK(split_edge(tm, 0, 0, 0.5, &done, ids, &nn));
    ASSERT_EQ_INT(done, 1);
    ASSERT_EQ_INT(nn, 8);
    ASSERT_EQ_INT(tm->nv, 7);
    ASSERT_EQ_INT(tm->nlive, 8);
    ASSERT_EQ_INT(tm->vcons[6], 0);
    ASSERT_NEAR(tm->xyz[18], 0.0, 0);
    ASSERT_NEAR(tm->xyz[19], 0.0, 0);
    ASSERT_NEAR(tm->xyz[20], 0.0, 0);
    ASSERT_TRUE(consistent(tm));
    ASSERT_NEAR(total_vol6(tm), 24.0, 1e-12);
    for (int j = 0; j < nn; j++) {
        ASSERT_TRUE(tmesh_local(tm, ids[j], 6) >= 0);
        /* each half: the pole, the centre and two unit-square corners */
        ASSERT_TRUE((tmesh_local(tm, ids[j], 0) >= 0) !=
                    (tmesh_local(tm, ids[j], 1) >= 0));
    }
    f1 = cons_faces(tm, &nf1);
    ASSERT_TRUE(f1);
    ASSERT_EQ_INT(nf1, nf0);
    ASSERT_TRUE(!memcmp(f0, f1, 20 * (size_t)nf0));
    split_undo(tm);
    ASSERT_EQ_INT(tm->nv, 6);
    ASSERT_TRUE(snap_same(tm, &s));
    ASSERT_TRUE(consistent(tm));
    free(f0);
    free(f1);
    snap_free(&s);
    tmesh_free(tm);
}

/* A constrained edge (a boundary edge of the octahedron) is never split, nor
 * an edge whose halves would fall under qfrac times the ring's smallest mean
 * ratio: nothing changed either way. */
TEST(edge_split_refused_leaves_the_mesh)
{
    tmesh *tm = ring_mesh(4, -3, 3, NULL);
    int32_t ids[2 * SPLIT_MAXRING];
    int done = 1, nn = 1;
    snap s;

    ASSERT_TRUE(tm);
    ASSERT_TRUE(snap_take(tm, &s));
    ASSERT_TRUE(tm->econs[0] >> 5 & 1); /* edge 23: two square corners */
    ASSERT_OK(split_edge(tm, 0, 5, 0.0, &done, ids, &nn));
    ASSERT_EQ_INT(done, 0);
    ASSERT_EQ_INT(nn, 0);
    ASSERT_OK(split_edge(tm, 0, 0, 10.0, &done, ids, &nn));
    ASSERT_EQ_INT(done, 0);
    ASSERT_EQ_INT(tm->nv, 6);
    ASSERT_TRUE(snap_same(tm, &s));
    snap_free(&s);
    tmesh_free(tm);
}

/* The pass splits an edge only when it is long against the sizes of its ends
 * (a vertex on the boundary: the mean of its boundary edges). The octahedron
 * of height 6: the axis is 6 long, its ends' size sqrt(10) (their boundary
 * edges to the square), 6 / sqrt(10) = 1.90 > 1.6: split once (its halves,
 * 3 / sqrt(10) < 1, stay). Of height 2: 2 / sqrt(2) = 1.41: none. */
TEST(split_pass_splits_only_the_long_edges)
{
    tmesh *tall = ring_mesh(4, -3, 3, NULL), *flat = ring_mesh(4, -1, 1, NULL);
    int64_t n = -1;

    ASSERT_TRUE(tall && flat);
    ASSERT_OK(split_long_edges(tall, 1.6, 0.5, 0.0, &n, NULL));
    ASSERT_EQ_INT(n, 1);
    ASSERT_EQ_INT(tall->nlive, 8);
    ASSERT_TRUE(consistent(tall));
    ASSERT_NEAR(total_vol6(tall), 24.0, 1e-12);
    ASSERT_OK(split_long_edges(tall, 1.6, 0.5, 0.0, &n, NULL));
    ASSERT_EQ_INT(n, 0); /* the halves are not long */
    ASSERT_OK(split_long_edges(flat, 1.6, 0.5, 0.0, &n, NULL));
    ASSERT_EQ_INT(n, 0);
    ASSERT_EQ_INT(flat->nlive, 4);
    ASSERT_OK(split_long_edges(flat, 1.3, 0.5, 0.0, &n, NULL));
    ASSERT_EQ_INT(n, 1); /* 1.41 > 1.3 */
    ASSERT_TRUE(consistent(flat));
    tmesh_free(tall);
    tmesh_free(flat);
}

/* With a share, the pass splits only when the long edges are at least that
 * share of the mesh's edges: the tall octahedron has 13 (4 on the square, 8
 * to the apexes, the axis; Euler's count 6 + 4 + 8 / 2 - 1), one long (the
 * axis, 1/13 = 0.077): none at 0.08, the axis at 0.07. */
TEST(split_pass_waits_for_a_share_of_long_edges)
{
    tmesh *tm = ring_mesh(4, -3, 3, NULL);
    int64_t n = -1;
    snap s;

    ASSERT_TRUE(tm);
    ASSERT_TRUE(snap_take(tm, &s));
    ASSERT_OK(split_long_edges(tm, 1.6, 0.5, 0.08, &n, NULL));
    ASSERT_EQ_INT(n, 0);
    ASSERT_TRUE(snap_same(tm, &s));
    ASSERT_OK(split_long_edges(tm, 1.6, 0.5, 0.07, &n, NULL));
    ASSERT_EQ_INT(n, 1);
    ASSERT_EQ_INT(tm->nlive, 8);
    ASSERT_TRUE(consistent(tm));
    snap_free(&s);
    tmesh_free(tm);
}

/* A face inside one region that the caller keeps (tmesh_keep_tris) is
 * constrained on both sides, with its edges and corners: in the 3-ring around
 * the z axis, keeping the face (0,1,3) between tets 0 and 1 blocks the removal
 * of the axis that the same ring allows without it; a triangle that is no face
 * is passed over. */
TEST(kept_inner_face_blocks_removal)
{
    const int32_t tri[6] = {3, 0, 1, 2, 3, 4}; /* a face, and the ring's triangle */
    tmesh *tm = ring_mesh(3, -1, 1, NULL);
    flip_cand c;

    ASSERT_TRUE(tm);
    ASSERT_EQ_INT(flip_edge_eval(tm, 0, 0, 10, 0.0, -INFINITY, &c), 1);
    ASSERT_EQ_INT(tm->fcons[0] >> 2 & 1, 0);
    ASSERT_OK(tmesh_keep_tris(tm, 2, tri));
    ASSERT_EQ_INT(tm->fcons[0] >> 2 & 1, 1); /* tet 0 (0,1,2,3): face opposite 2 */
    ASSERT_EQ_INT(tm->fcons[1] >> 3 & 1, 1); /* tet 1 (0,1,3,4): face opposite 4 */
    ASSERT_EQ_INT(tm->fcons[2] >> 2 & 1, 0); /* tet 2 (0,1,4,2): (0,1,2) not kept */
    ASSERT_EQ_INT(tm->econs[0] & 1, 1);      /* the axis, an edge of the kept face */
    ASSERT_EQ_INT(tm->vcons[0] + tm->vcons[1] + tm->vcons[3], 3);
    ASSERT_TRUE(consistent(tm));
    ASSERT_EQ_INT(flip_edge_eval(tm, 0, 0, 10, 0.0, -INFINITY, &c), 0);
    tmesh_free(tm);
}

/* The live tets of tm that have the three vertices of tri. */
static int tets_on(const tmesh *tm, const int32_t *tri)
{
    int n = 0;
    for (int32_t t = 0; t < tm->hi; t++) {
        int k = 0;
        for (int s = 0; s < 3 && tm->tv[4 * t] >= 0; s++)
            k += tmesh_local(tm, t, tri[s]) >= 0;
        n += k == 3;
    }
    return n;
}

/* The faces of the perturbed grid in its middle plane y = 1/2 (inside a region:
 * a surface the user gave, as an embedded surface or facet tags): kept face
 * for face through flips, insertion and contraction when kept (each still
 * between two tets), some of them gone when not. */
TEST(driver_keeps_an_inner_surface)
{
    const int n = 6;
    mesh_t *m = tm_grid(n, MESH_WITH_REGION);
    int32_t tri[3 * 6 * 6 * 4];
    int ntri = 0, lost[2] = {0, 0};
    topo_params p;
    topo_stats st;

    ASSERT_TRUE(m);
    for (int32_t t = 0; t < m->nt; t++)
        for (int i = 0; i < 4; i++) {
            int32_t f[3];
            int on = 1, dup = 0;
            for (int s = 0; s < 3; s++) {
                f[s] = m->tets[4 * t + tet_face_of[i][s]];
                on &= (f[s] / (n + 1)) % (n + 1) == n / 2;
            }
            tet_sort3(f[0], f[1], f[2], f);
            for (int k = 0; k < ntri && on && !dup; k++)
                dup = !memcmp(tri + 3 * k, f, sizeof f);
            if (on && !dup && ntri < 6 * 6 * 4) {
                memcpy(tri + 3 * ntri, f, sizeof f);
                ntri++;
            }
        }
    ASSERT_EQ_INT(ntri, 2 * n * n); /* two triangles per square of the plane */
    tm_perturb(m, n, 0.3, 5);
    topo_params_default(&p);
    p.qgoal = 0.9;
    p.insert = p.contract = 1;
    p.qinsert = 0.5;
    p.imargin = 1e-3;
    for (int keep = 0; keep < 2; keep++) {
        tmesh *tm = NULL;
        ASSERT_OK(tmesh_new(m->nv, m->xyz, m->nt, m->tets, m->region, NULL, &tm, NULL));
        if (keep)
            ASSERT_OK(tmesh_keep_tris(tm, ntri, tri));
        ASSERT_OK(topo_improve(tm, &p, &st, NULL));
        ASSERT_TRUE(st.edge_removals + st.flips23 + st.insertions > 0);
        ASSERT_TRUE(consistent(tm));
        for (int k = 0; k < ntri; k++)
            lost[keep] += tets_on(tm, tri + 3 * k) != 2;
        tmesh_free(tm);
    }
    ASSERT_TRUE(lost[0] > 0);
    ASSERT_EQ_INT(lost[1], 0);
    mesh_free(m);
}

TEST_MAIN("topo", T(kept_inner_face_blocks_removal), T(driver_keeps_an_inner_surface),
          T(edge_split_at_the_midpoint), T(edge_split_refused_leaves_the_mesh),
          T(split_pass_splits_only_the_long_edges),
          T(split_pass_waits_for_a_share_of_long_edges),
          T(contraction_keeps_the_volume_exactly),
          T(boundary_contraction_keeps_a_flat_face), T(boundary_flip_2_2_coplanar),
          T(peeling_a_flat_boundary_tet), T(driver_writes_the_new_boundary_triangles),
          T(driver_spends_one_bound), T(insertion_in_a_bad_tet),
          T(insertion_refused_leaves_the_mesh), T(insertion_keeps_the_smallest_angle),
          T(insertion_grows_past_the_surface), T(insertion_face_cap),
          T(opt_run_fixed_flips_take_a_flat_tet), T(flips_keep_a_good_corner_tets_edges),
          T(driver_with_insertion), T(orient3d_exact_near_coplanar),
          T(edge_removal_3_2_keeps_volume), T(edge_removal_rings_3_to_8), T(flip_2_3),
          T(multiface_removal_restores_the_ring), T(tmesh_refuses_a_face_of_three_tets),
          T(export_keeps_the_callers_vertex_order), T(mixed_tag_shell_blocks_removal),
          T(non_convex_ring_refused), T(four_boundary_corner_floor),
          T(rollback_restores_exactly), T(random_flips_keep_invariants),
          T(driver_is_deterministic), T(driver_same_on_one_and_two_threads),
          T(driver_skips_only_what_cannot_change),
          T(driver_skips_across_insertions_and_contractions),
          T(driver_keeps_the_smallest_angle), T(opt_run_flips_keeps_the_model),
          T(orientation_found_again_while_positive),
          T(opt_run_flips_leaves_inverted_input_alone),
          T(topology_keeps_the_vertex_numbers),
          T(topology_without_a_flip_keeps_the_tets_in_order),
          T(flips_allocation_failures_are_clean),
          T(contraction_by_gain_keeps_new_tets_above_the_floor),
          T(full_allocation_failures_are_clean))
