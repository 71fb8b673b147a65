/* bderr_bvh.c - exact point-triangle distances and a BVH over triangles for
 * closest-point queries (bderr_int.h): the boundary error and the sliding
 * boundary mode. */
#include "geom/bderr_int.h"
#include "geom/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Small vector helpers                                                      */

/* r = a + s * d */
static void axpy3(double r[3], const double a[3], double s, const double d[3])
{
    r[0] = a[0] + s * d[0];
    r[1] = a[1] + s * d[1];
    r[2] = a[2] + s * d[2];
}

static double dist2(const double a[3], const double b[3])
{
    double d[3];

    vec3_sub(a, b, d);
    return vec3_dot(d, d);
}

/* ------------------------------------------------------------------------ */
/* Point-triangle distance                                                   */

/* Closest point to p on segment [a, b]; squared distance. */
static double closest_on_segment(const double p[3], const double a[3], const double b[3],
                                 double q[3])
{
    double ab[3], ap[3], len2, t;

    vec3_sub(b, a, ab);
    vec3_sub(p, a, ap);
    len2 = vec3_dot(ab, ab);
    t = len2 > 0 ? vec3_dot(ap, ab) / len2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    axpy3(q, a, t, ab);
    return dist2(p, q);
}

/* Ericson, Real-Time Collision Detection, 5.1.5: find the Voronoi region of p
 * (three vertices, three edges, the face) from signed barycentric areas. The
 * divisions are guarded: a zero-length edge or a zero-area face, where the
 * book's formulas give 0/0, falls back to the nearest of the three edges, which
 * is exact for a degenerate triangle. Returns the squared distance. */
static double closest_on_triangle(const double p[3], const double a[3], const double b[3],
                                  const double c[3], double q[3])
{
    double ab[3], ac[3], ap[3], bp[3], cp[3], bc[3];
    double d1, d2, d3, d4, d5, d6, va, vb, vc, den, v, w;

    vec3_sub(b, a, ab);
    vec3_sub(c, a, ac);
    vec3_sub(p, a, ap);
    d1 = vec3_dot(ab, ap);
    d2 = vec3_dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) {
        memcpy(q, a, 3 * sizeof(double));
        return dist2(p, q);
    }
    vec3_sub(p, b, bp);
    d3 = vec3_dot(ab, bp);
    d4 = vec3_dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) {
        memcpy(q, b, 3 * sizeof(double));
        return dist2(p, q);
    }
    vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0 && d1 - d3 > 0) {
        axpy3(q, a, d1 / (d1 - d3), ab);
        return dist2(p, q);
    }
    vec3_sub(p, c, cp);
    d5 = vec3_dot(ab, cp);
    d6 = vec3_dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) {
        memcpy(q, c, 3 * sizeof(double));
        return dist2(p, q);
    }
    vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0 && d2 - d6 > 0) {
        axpy3(q, a, d2 / (d2 - d6), ac);
        return dist2(p, q);
    }
    va = d3 * d6 - d5 * d4;
    if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0 && (d4 - d3) + (d5 - d6) > 0) {
        vec3_sub(c, b, bc);
        axpy3(q, b, (d4 - d3) / ((d4 - d3) + (d5 - d6)), bc);
        return dist2(p, q);
    }
    den = va + vb + vc;
    if (den > 0 && isfinite(den)) {
        v = vb / den;
        w = vc / den;
        q[0] = a[0] + ab[0] * v + ac[0] * w;
        q[1] = a[1] + ab[1] * v + ac[1] * w;
        q[2] = a[2] + ab[2] * v + ac[2] * w;
        return dist2(p, q);
    }
    {
        double q2[3], q3[3];
        double e1 = closest_on_segment(p, a, b, q);
        double e2 = closest_on_segment(p, b, c, q2);
        double e3 = closest_on_segment(p, c, a, q3);
        if (e2 < e1) {
            memcpy(q, q2, sizeof q2);
            e1 = e2;
        }
        if (e3 < e1) {
            memcpy(q, q3, sizeof q3);
            e1 = e3;
        }
        return e1;
    }
}

double bderr_point_segment(const double p[3], const double a[3], const double b[3],
                           double cp[3])
{
    double q[3], d2 = closest_on_segment(p, a, b, q);

    if (cp)
        memcpy(cp, q, sizeof q);
    return sqrt(d2);
}

double bderr_point_triangle(const double p[3], const double a[3], const double b[3],
                            const double c[3], double cp[3])
{
    double q[3];

    return sqrt(closest_on_triangle(p, a, b, c, cp ? cp : q));
}

/* ------------------------------------------------------------------------ */
/* BVH                                                                       */

enum { BVH_LEAF = 4, BVH_STACK = 128 };

typedef struct {
    double lo[3], hi[3];
    int32_t a; /* leaf: first triangle; inner: right child (the left one is next) */
    int32_t n; /* leaf: triangle count (> 0); inner: 0 */
} bvh_node;

struct bderr_bvh {
    int32_t ntri, nnode;
    bvh_node *nodes;
    const double *xyz; /* the caller's coordinates (bderr.h) */
    int32_t *tv;       /* 3 vertex indices per triangle, in leaf order (a copy of the
                        * corners was 72 bytes a triangle: 150 MB on a 5M-tet ball) */
    int32_t *id;       /* caller's index of each triangle, in leaf order */
    int32_t *at;       /* leaf position of each caller's triangle (id's inverse) */
    int32_t *up;       /* each node's parent (-1 for the root) */
    int32_t *leaf;     /* the leaf node holding each leaf position */
    float *ball;       /* per leaf position a ball holding the triangle: centre
                        * and radius (see tri_ball) */
    double slack;      /* what the ball test allows for rounding (ball_far) */
};

/* A ball in floats around triangle (a, b, c): the centre is the centroid
 * rounded to float, the radius the largest distance from it to a corner,
 * rounded up (then up by a float ulp more for the rounding of the double
 * distances), so the ball holds the triangle. 16 bytes a triangle. */
static void tri_ball(const double *a, const double *b, const double *c, float o[4])
{
    const double *p[3] = {a, b, c};
    double r2 = 0, cf[3];

    for (int d = 0; d < 3; d++) {
        o[d] = (float)((a[d] + b[d] + c[d]) / 3);
        cf[d] = o[d];
    }
    for (int v = 0; v < 3; v++) {
        double e = dist2(p[v], cf);
        r2 = e > r2 ? e : r2;
    }
    o[3] = nextafterf(nextafterf((float)sqrt(r2), INFINITY), INFINITY);
}

/* The balls of b's triangles on coordinates xyz, and the slack of the ball
 * test: 1e-13 of the largest coordinate (the rounding of a distance between
 * two points of that size is far below it). */
static void set_balls(bderr_bvh *b, const double *xyz)
{
    double m = 0;

#ifdef _OPENMP
#pragma omp parallel for schedule(static) reduction(max : m)
#endif
    for (int32_t i = 0; i < b->ntri; i++) {
        const int32_t *t = b->tv + 3 * (size_t)i;
        float *o = b->ball + 4 * (size_t)i;
        tri_ball(xyz + 3 * (size_t)t[0], xyz + 3 * (size_t)t[1], xyz + 3 * (size_t)t[2],
                 o);
        for (int d = 0; d < 3; d++)
            m = fabs(o[d]) + o[3] > m ? fabs(o[d]) + o[3] : m;
    }
    b->slack = 1e-13 * m;
}

/* Reorder ix[lo, hi) so ix[k] has the k-th smallest key and no smaller key
 * follows it (Hoare's selection; keys are finite). */
static void select_kth(int32_t *ix, const double *key, int32_t lo, int32_t hi, int32_t k)
{
    hi--;
    while (hi > lo) {
        double pivot = key[ix[lo + (hi - lo) / 2]];
        int32_t i = lo, j = hi;
        while (i <= j) {
            while (key[ix[i]] < pivot)
                i++;
            while (key[ix[j]] > pivot)
                j--;
            if (i <= j) {
                int32_t t = ix[i];
                ix[i++] = ix[j];
                ix[j--] = t;
            }
        }
        if (k <= j)
            hi = j;
        else if (k >= i)
            lo = i;
        else
            return;
    }
}

typedef struct {
    bderr_bvh *b;
    const double *xyz;
    const int32_t *tris;
    const double *cen; /* 3 per triangle */
    double *key;       /* scratch: the split axis coordinate of each centroid */
    int32_t *ix;
    int depth;
} bvh_builder;

/* The box of a leaf: its triangles' corners (coordinates are finite). */
static void leaf_box(const bvh_builder *bb, bvh_node *nd, int32_t lo, int32_t hi)
{
    for (int d = 0; d < 3; d++) {
        nd->lo[d] = INFINITY;
        nd->hi[d] = -INFINITY;
    }
    for (int32_t i = lo; i < hi; i++) {
        const int32_t *t = bb->tris + 3 * (size_t)bb->ix[i];
        for (int v = 0; v < 3; v++)
            for (int d = 0; d < 3; d++) {
                double x = bb->xyz[3 * (size_t)t[v] + d];
                nd->lo[d] = x < nd->lo[d] ? x : nd->lo[d];
                nd->hi[d] = x > nd->hi[d] ? x : nd->hi[d];
            }
    }
}

/* The box of inner node self: the union of its children's. */
static void box_union(bvh_node *nodes, int32_t self)
{
    bvh_node *nd = &nodes[self];
    const bvh_node *L = &nodes[self + 1], *R = &nodes[nd->a];

    for (int d = 0; d < 3; d++) {
        nd->lo[d] = L->lo[d] < R->lo[d] ? L->lo[d] : R->lo[d];
        nd->hi[d] = L->hi[d] > R->hi[d] ? L->hi[d] : R->hi[d];
    }
}

/* Nodes N(a) and N(a + 1) of subtrees over a and a + 1 triangles (median
 * splits: a node over m has children over m / 2 and m - m / 2), from those of
 * a / 2: O(log a). */
static void bvh_nodes2(int32_t a, int32_t *na, int32_t *na1)
{
    int32_t x = 1, y = 1;

    if (a >= BVH_LEAF)
        bvh_nodes2(a / 2, &x, &y);
    *na = a <= BVH_LEAF ? 1 : a % 2 == 0 ? 1 + 2 * x : 1 + x + y;
    *na1 = a + 1 <= BVH_LEAF ? 1 : a % 2 == 0 ? 1 + x + y : 1 + 2 * y;
}

/* Nodes of a subtree over n triangles. */
static int32_t bvh_nodes(int32_t n)
{
    int32_t a, b;

    bvh_nodes2(n, &a, &b);
    return a;
}

enum { BVH_TASK = 32768 }; /* subtrees at least this big are built as tasks */

/* Node self over ix[lo..hi): split at the median centroid along the
 * centroids' longest extent; the left child is node self + 1, the right one
 * follows the left subtree, so the two are built independently (as tasks
 * when big: the serial build was 0.5 s of a 5M-tet run's setup). An inner
 * node's box is the union of its children's (each level used to rescan every
 * corner of its triangles with fmin/fmax: 1.6 s of setup on a 4M-tet ball).
 * Returns the subtree's depth. */
static int bvh_build_node(bvh_builder *bb, int32_t self, int32_t lo, int32_t hi,
                          int depth)
{
    bvh_node *nd = &bb->b->nodes[self];
    int32_t mid, r;
    double clo[3] = {INFINITY, INFINITY, INFINITY},
           chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    int axis = 0, dl = 0, dr;

    if (hi - lo <= BVH_LEAF) {
        leaf_box(bb, nd, lo, hi);
        nd->a = lo;
        nd->n = hi - lo;
        for (int32_t i = lo; i < hi; i++)
            bb->b->leaf[i] = self;
        return depth;
    }
    for (int32_t i = lo; i < hi; i++) {
        const double *c = bb->cen + 3 * (size_t)bb->ix[i];
        for (int d = 0; d < 3; d++) {
            clo[d] = c[d] < clo[d] ? c[d] : clo[d];
            chi[d] = c[d] > chi[d] ? c[d] : chi[d];
        }
    }
    for (int d = 1; d < 3; d++)
        if (chi[d] - clo[d] > chi[axis] - clo[axis])
            axis = d;
    for (int32_t i = lo; i < hi; i++)
        bb->key[bb->ix[i]] = bb->cen[3 * (size_t)bb->ix[i] + axis];
    mid = lo + (hi - lo) / 2;
    select_kth(bb->ix, bb->key, lo, hi, mid);
    r = self + 1 + bvh_nodes(mid - lo);
    bb->b->up[self + 1] = bb->b->up[r] = self;
#pragma omp task shared(dl) if (mid - lo >= BVH_TASK)
    dl = bvh_build_node(bb, self + 1, lo, mid, depth + 1);
    dr = bvh_build_node(bb, r, mid, hi, depth + 1);
#pragma omp taskwait
    nd->a = r;
    nd->n = 0;
    box_union(bb->b->nodes, self);
    return dl > dr ? dl : dr;
}

/* Triangle indices in [0, nv) and finite coordinates on every used vertex. */
static qdc_status check_surface(const double *xyz, int32_t nv, const int32_t *tris,
                                int32_t ntri, const char *what, qdc_error *err)
{
    if (nv < 0 || ntri < 0 || (ntri > 0 && (!tris || !xyz)))
        return qdc_fail(err, QDC_EINVAL, "%s: invalid surface arguments", what);
    for (int64_t i = 0; i < 3 * (int64_t)ntri; i++) {
        int32_t v = tris[i];
        if (v < 0 || v >= nv)
            return qdc_fail(err, QDC_EINVAL, "%s: triangle %lld: vertex %d out of range",
                            what, (long long)(i / 3), v);
        if (!isfinite(xyz[3 * (size_t)v]) || !isfinite(xyz[3 * (size_t)v + 1]) ||
            !isfinite(xyz[3 * (size_t)v + 2]))
            return qdc_fail(err, QDC_EINVAL, "%s: vertex %d is not finite", what, v);
    }
    return QDC_OK;
}

qdc_status bderr_bvh_build(const double *xyz, int32_t nv, const int32_t *tris,
                           int32_t ntri, bderr_bvh **out, qdc_error *err)
{
    bderr_bvh *b;
    bvh_builder bb;
    double *cen = NULL;
    qdc_status st;

    if (!out)
        return qdc_fail(err, QDC_EINVAL, "bderr_bvh_build: NULL out");
    *out = NULL;
    st = check_surface(xyz, nv, tris, ntri, "bderr_bvh_build", err);
    if (st != QDC_OK)
        return st;
    b = qdc_calloc(1, sizeof *b);
    if (!b)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for a BVH");
    b->ntri = ntri;
    b->nodes = qdc_mallocn(2 * (size_t)ntri + 1, sizeof *b->nodes);
    b->xyz = xyz;
    b->tv = qdc_mallocn(3 * (size_t)ntri + 1, sizeof(int32_t));
    b->id = qdc_mallocn((size_t)ntri + 1, sizeof(int32_t));
    b->at = qdc_mallocn((size_t)ntri + 1, sizeof(int32_t));
    b->up = qdc_mallocn(2 * (size_t)ntri + 1, sizeof(int32_t));
    b->leaf = qdc_mallocn((size_t)ntri + 1, sizeof(int32_t));
    b->ball = qdc_mallocn(4 * (size_t)ntri + 1, sizeof(float));
    cen = qdc_mallocn(3 * (size_t)ntri, sizeof(double));
    memset(&bb, 0, sizeof bb);
    bb.key = qdc_mallocn((size_t)ntri, sizeof(double));
    if (!b->nodes || !b->tv || !b->id || !b->at || !b->up || !b->leaf || !b->ball ||
        !cen || !bb.key) {
        st = qdc_fail(err, QDC_ENOMEM, "out of memory for a BVH of %d triangles", ntri);
        goto out;
    }
    for (int32_t t = 0; t < ntri; t++) {
        b->id[t] = t;
        for (int d = 0; d < 3; d++)
            cen[3 * (size_t)t + d] = (xyz[3 * (size_t)tris[3 * (size_t)t] + d] +
                                      xyz[3 * (size_t)tris[3 * (size_t)t + 1] + d] +
                                      xyz[3 * (size_t)tris[3 * (size_t)t + 2] + d]) /
                                     3;
    }
    if (ntri > 0) {
        bb.b = b;
        bb.xyz = xyz;
        bb.tris = tris;
        bb.cen = cen;
        bb.ix = b->id;
        b->nnode = bvh_nodes(ntri);
        b->up[0] = -1;
#pragma omp parallel
#pragma omp single
        bb.depth = bvh_build_node(&bb, 0, 0, ntri, 1);
    }
    /* Median splits keep the depth near log2(ntri / BVH_LEAF), far below the
     * traversal stack. */
    if (2 * bb.depth + 2 > BVH_STACK) {
        st = qdc_fail(err, QDC_EINTERNAL, "BVH too deep (%d)", bb.depth);
        goto out;
    }
    for (int32_t i = 0; i < ntri; i++) {
        b->at[b->id[i]] = i;
        for (int v = 0; v < 3; v++)
            b->tv[3 * (size_t)i + v] = tris[3 * (size_t)b->id[i] + v];
    }
    set_balls(b, xyz);
out:
    qdc_free(cen);
    qdc_free(bb.key);
    if (st != QDC_OK) {
        bderr_bvh_free(b);
        return st;
    }
    *out = b;
    return QDC_OK;
}

qdc_status bderr_bvh_refit(const bderr_bvh *src, const double *xyz, int32_t nv,
                           bderr_bvh **out, qdc_error *err)
{
    bderr_bvh *b;
    qdc_status st;
    int32_t nt;

    if (!src || !out)
        return qdc_fail(err, QDC_EINVAL, "bderr_bvh_refit: NULL argument");
    *out = NULL;
    nt = src->ntri;
    st = check_surface(xyz, nv, src->tv, nt, "bderr_bvh_refit", err);
    if (st != QDC_OK)
        return st;
    b = qdc_calloc(1, sizeof *b);
    if (!b)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for a BVH");
    *b = *src;
    b->xyz = xyz;
    b->nodes = qdc_mallocn(2 * (size_t)nt + 1, sizeof *b->nodes);
    b->tv = qdc_mallocn(3 * (size_t)nt + 1, sizeof(int32_t));
    b->id = qdc_mallocn((size_t)nt + 1, sizeof(int32_t));
    b->at = qdc_mallocn((size_t)nt + 1, sizeof(int32_t));
    b->up = qdc_mallocn((size_t)src->nnode + 1, sizeof(int32_t));
    b->leaf = qdc_mallocn((size_t)nt + 1, sizeof(int32_t));
    b->ball = qdc_mallocn(4 * (size_t)nt + 1, sizeof(float));
    if (!b->nodes || !b->tv || !b->id || !b->at || !b->up || !b->leaf || !b->ball) {
        bderr_bvh_free(b);
        return qdc_fail(err, QDC_ENOMEM, "out of memory for a BVH of %d triangles", nt);
    }
    memcpy(b->nodes, src->nodes, (size_t)src->nnode * sizeof *b->nodes);
    memcpy(b->up, src->up, (size_t)src->nnode * sizeof(int32_t));
    memcpy(b->leaf, src->leaf, (size_t)nt * sizeof(int32_t));
    memcpy(b->tv, src->tv, 3 * (size_t)nt * sizeof(int32_t));
    memcpy(b->id, src->id, (size_t)nt * sizeof(int32_t));
    memcpy(b->at, src->at, (size_t)nt * sizeof(int32_t));
#ifdef _OPENMP
#pragma omp parallel for schedule(static)
#endif
    for (int32_t n = 0; n < b->nnode; n++) {
        bvh_node *nd = &b->nodes[n];
        if (nd->n == 0)
            continue;
        for (int d = 0; d < 3; d++) {
            nd->lo[d] = INFINITY;
            nd->hi[d] = -INFINITY;
        }
        for (int32_t i = 3 * nd->a; i < 3 * (nd->a + nd->n); i++)
            for (int d = 0; d < 3; d++) {
                double x = xyz[3 * (size_t)b->tv[i] + d];
                nd->lo[d] = x < nd->lo[d] ? x : nd->lo[d];
                nd->hi[d] = x > nd->hi[d] ? x : nd->hi[d];
            }
    }
    for (int32_t n = b->nnode - 1; n >= 0; n--) { /* children follow their parent */
        if (b->nodes[n].n == 0)
            box_union(b->nodes, n);
    }
    set_balls(b, xyz);
    *out = b;
    return QDC_OK;
}

void bderr_bvh_free(bderr_bvh *b)
{
    if (!b)
        return;
    qdc_free(b->nodes);
    qdc_free(b->tv);
    qdc_free(b->id);
    qdc_free(b->at);
    qdc_free(b->up);
    qdc_free(b->leaf);
    qdc_free(b->ball);
    qdc_free(b);
}

int32_t bderr_bvh_size(const bderr_bvh *b)
{
    return b ? b->ntri : 0;
}

int32_t bderr_bvh_position(const bderr_bvh *b, int32_t tri)
{
    return b && tri >= 0 && tri < b->ntri ? b->at[tri] : -1;
}

/* closest_on_triangle for the triangle at leaf position i. */
static double leaf_closest(const bderr_bvh *b, int32_t i, const double p[3], double q[3])
{
    const int32_t *t = b->tv + 3 * (size_t)i;

    return closest_on_triangle(p, b->xyz + 3 * (size_t)t[0], b->xyz + 3 * (size_t)t[1],
                               b->xyz + 3 * (size_t)t[2], q);
}

/* 1 if the triangle at leaf position i is no nearer to p than sb (not
 * squared; never while sb is infinite) by its ball: then its distance cannot
 * beat a best of sb^2, and closest_on_triangle (some 60 flops and 6
 * branches) is skipped. Most triangles of a leaf near a sample are; the
 * slack keeps the test on the safe side of rounding, so the answers are
 * those without it. */
static int ball_far(const bderr_bvh *b, int32_t i, const double p[3], double sb)
{
    const float *o = b->ball + 4 * (size_t)i;
    double e[3] = {p[0] - o[0], p[1] - o[1], p[2] - o[2]}, lim = o[3] + sb;

    lim += 1e-9 * lim + b->slack;
    return sb < INFINITY && vec3_dot(e, e) > lim * lim;
}

/* Squared distance between the box of nd and box (lo, hi) (0 if they meet). */
static double box_box_dist2(const bvh_node *nd, const double lo[3], const double hi[3])
{
    double s = 0;

    for (int d = 0; d < 3; d++) {
        double e = hi[d] < nd->lo[d]   ? nd->lo[d] - hi[d]
                   : lo[d] > nd->hi[d] ? lo[d] - nd->hi[d]
                                       : 0;
        s += e * e;
    }
    return s;
}

/* Squared distance from p to the box of nd (0 inside). */
static double box_dist2(const bvh_node *nd, const double p[3])
{
    return box_box_dist2(nd, p, p);
}

double bderr_bvh_closest(const bderr_bvh *b, const double p[3], double cp[3],
                         int32_t *tri)
{
    return bderr_bvh_closest_near(b, p, -1, cp, tri);
}

/* The closest triangle to p in the subtree of node root, if closer than
 * *best (squared; *bt its leaf position, bq its closest point): a depth-first
 * search, the nearer child first, every box no nearer than *best skipped. */
static void descend(const bderr_bvh *b, int32_t root, const double p[3], double *best,
                    int32_t *bt, double bq[3])
{
    int32_t stack[BVH_STACK];
    double sd[BVH_STACK], q[3];
    int sp = 0;

    stack[sp] = root;
    sd[sp++] = box_dist2(&b->nodes[root], p);
    while (sp > 0) {
        const bvh_node *nd;
        double dl, dr;
        int32_t l, r;
        sp--;
        if (sd[sp] >= *best)
            continue;
        nd = &b->nodes[stack[sp]];
        if (nd->n > 0) {
            double sb = sqrt(*best);
            for (int32_t i = nd->a; i < nd->a + nd->n; i++) {
                double d;
                if (ball_far(b, i, p, sb))
                    continue;
                d = leaf_closest(b, i, p, q);
                if (d < *best) {
                    sb = sqrt(d);
                    *best = d;
                    *bt = i;
                    memcpy(bq, q, 3 * sizeof(double));
                }
            }
            continue;
        }
        l = (int32_t)(nd - b->nodes) + 1;
        r = nd->a;
        dl = box_dist2(&b->nodes[l], p);
        dr = box_dist2(&b->nodes[r], p);
        if (dl > dr) { /* push the farther child first: the nearer is popped first */
            int32_t ti = l;
            double td = dl;
            l = r;
            r = ti;
            dl = dr;
            dr = td;
        }
        if (dr < *best) {
            stack[sp] = r;
            sd[sp++] = dr;
        }
        if (dl < *best) {
            stack[sp] = l;
            sd[sp++] = dl;
        }
    }
}

double bderr_bvh_closest_near(const bderr_bvh *b, const double p[3], int32_t near,
                              double cp[3], int32_t *tri)
{
    double best = INFINITY, bq[3] = {0, 0, 0};
    int32_t bt = -1;

    if (tri)
        *tri = -1;
    if (!b || b->ntri == 0)
        return INFINITY;
    if (near >= 0 && near < b->ntri && !cp && !tri &&
        bderr_bvh_closest_group(b, 1, p, &near, &best))
        return best; /* the distance only: from near's leaf up */
    if (near >= 0 && near < b->ntri) {
        /* a bound to start from: the search then skips every box farther
         * than this triangle (a sliding vertex stays near its own faces) */
        best = leaf_closest(b, b->at[near], p, bq);
        bt = best == best ? b->at[near] : -1;
        if (bt < 0)
            best = INFINITY;
    }
    descend(b, 0, p, &best, &bt, bq);
    if (bt < 0) /* p had a NaN: every comparison failed */
        return NAN;
    if (cp)
        memcpy(cp, bq, sizeof bq);
    if (tri)
        *tri = b->id[bt];
    return sqrt(best);
}

int32_t bderr_bvh_leaf_of(const bderr_bvh *b, int32_t tri)
{
    return b && tri >= 0 && tri < b->ntri ? b->leaf[b->at[tri]] : -1;
}

/* The largest of best[0..n). */
static double group_bound(const double *best, int32_t n)
{
    double r = 0;

    for (int32_t i = 0; i < n; i++)
        r = best[i] > r ? best[i] : r;
    return r;
}

/* The triangles of the subtree of node root, for every point of the group
 * (box lo, hi; best[i] squared, lowered where a triangle is nearer): a
 * subtree whose box is no nearer to the group's box than the group's largest
 * best is skipped whole, a leaf for a point when its box is no nearer than
 * that point's best. */
static void group_descend(const bderr_bvh *b, int32_t root, int32_t n, const double *p,
                          const double lo[3], const double hi[3], double *best,
                          double *bound)
{
    int32_t stack[BVH_STACK];
    int sp = 0;

    stack[sp++] = root;
    while (sp > 0) {
        const bvh_node *nd = &b->nodes[stack[--sp]];
        if (box_box_dist2(nd, lo, hi) >= *bound)
            continue;
        if (nd->n > 0) {
            int changed = 0;
            for (int32_t k = 0; k < n; k++) {
                const double *pk = p + 3 * (size_t)k;
                double q[3];
                double sb;
                if (box_dist2(nd, pk) >= best[k])
                    continue;
                sb = sqrt(best[k]);
                for (int32_t i = nd->a; i < nd->a + nd->n; i++) {
                    double d;
                    if (ball_far(b, i, pk, sb))
                        continue;
                    d = leaf_closest(b, i, pk, q);
                    if (d < best[k]) {
                        best[k] = d;
                        sb = sqrt(d);
                        changed = 1;
                    }
                }
            }
            if (changed)
                *bound = group_bound(best, n);
            continue;
        }
        /* the farther child first on the stack: the nearer is taken first */
        {
            int32_t l = (int32_t)(nd - b->nodes) + 1, r = nd->a;
            if (box_box_dist2(&b->nodes[l], lo, hi) >
                box_box_dist2(&b->nodes[r], lo, hi)) {
                int32_t t = l;
                l = r;
                r = t;
            }
            stack[sp++] = r;
            stack[sp++] = l;
        }
    }
}

/* From the leaf of the points' triangles up: that leaf's triangles, then at
 * each ancestor the subtree beside the path, unless its box is no nearer
 * than the group's largest best so far. Every triangle is in one of those,
 * so the answers are descend's from the root; when the points lie on or near
 * their triangles (a surface against its own optimized copy) almost every
 * sibling is skipped at its box, where the search from the root walks down
 * the boxes that hold each point (issue #32: the report's boundary distances
 * were a fifth of a 100k-tet run's instructions). */
int bderr_bvh_closest_group(const bderr_bvh *b, int32_t n, const double *p,
                            const int32_t *near, double *d)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY},
           hi[3] = {-INFINITY, -INFINITY, -INFINITY}, bound, q[3];
    int32_t node, leaf = n > 0 ? bderr_bvh_leaf_of(b, near[0]) : -1;
    const bvh_node *lf;

    for (int32_t k = 0; k < n; k++) {
        const double *pk = p + 3 * (size_t)k;
        if (n > BDERR_GROUP_MAX || leaf < 0 || bderr_bvh_leaf_of(b, near[k]) != leaf)
            return 0;
        for (int c = 0; c < 3; c++) {
            if (!isfinite(pk[c]))
                return 0;
            lo[c] = pk[c] < lo[c] ? pk[c] : lo[c];
            hi[c] = pk[c] > hi[c] ? pk[c] : hi[c];
        }
    }
    if (n == 0)
        return 1;
    lf = &b->nodes[leaf];
    for (int32_t k = 0; k < n; k++) {
        d[k] = INFINITY;
        for (int32_t i = lf->a; i < lf->a + lf->n; i++) {
            double e = leaf_closest(b, i, p + 3 * (size_t)k, q);
            d[k] = e < d[k] ? e : d[k];
        }
    }
    bound = group_bound(d, n);
    node = leaf;
    for (int32_t up = b->up[node]; up >= 0; node = up, up = b->up[up]) {
        int32_t sib = node == up + 1 ? b->nodes[up].a : up + 1;
        group_descend(b, sib, n, p, lo, hi, d, &bound);
    }
    for (int32_t k = 0; k < n; k++)
        d[k] = sqrt(d[k]);
    return 1;
}
