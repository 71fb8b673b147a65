/* bderr.c - boundary error (docs/method.md §9): symmetric Hausdorff distance between two
 * triangle surfaces, Metro style.
 *
 * Each side is sampled densely (every surface vertex, every face centroid, and
 * area-weighted random points) and every sample is measured exactly against
 * the other side through a BVH. Sample k of a side is a pure function of
 * (seed, side, k), and partial sums are formed per fixed-size chunk and added
 * in chunk order, so the result does not depend on the number of threads. */
#include "core/mesh_int.h"
#include "core/tet.h"
#include "geom/bderr_int.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Small vector helpers                                                      */

static void sub3(double r[3], const double a[3], const double b[3])
{
    r[0] = a[0] - b[0];
    r[1] = a[1] - b[1];
    r[2] = a[2] - b[2];
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

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

    sub3(d, a, b);
    return dot3(d, d);
}

/* ------------------------------------------------------------------------ */
/* Point-triangle distance                                                   */

/* Closest point to p on segment [a, b]; squared distance. */
static double closest_on_segment(const double p[3], const double a[3], const double b[3],
                                 double q[3])
{
    double ab[3], ap[3], len2, t;

    sub3(ab, b, a);
    sub3(ap, p, a);
    len2 = dot3(ab, ab);
    t = len2 > 0 ? dot3(ap, ab) / len2 : 0;
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

    sub3(ab, b, a);
    sub3(ac, c, a);
    sub3(ap, p, a);
    d1 = dot3(ab, ap);
    d2 = dot3(ac, ap);
    if (d1 <= 0 && d2 <= 0) {
        memcpy(q, a, 3 * sizeof(double));
        return dist2(p, q);
    }
    sub3(bp, p, b);
    d3 = dot3(ab, bp);
    d4 = dot3(ac, bp);
    if (d3 >= 0 && d4 <= d3) {
        memcpy(q, b, 3 * sizeof(double));
        return dist2(p, q);
    }
    vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0 && d1 - d3 > 0) {
        axpy3(q, a, d1 / (d1 - d3), ab);
        return dist2(p, q);
    }
    sub3(cp, p, c);
    d5 = dot3(ab, cp);
    d6 = dot3(ac, cp);
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
        sub3(bc, c, b);
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
};

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
#pragma omp task shared(dl) if (mid - lo >= BVH_TASK)
    dl = bvh_build_node(bb, self + 1, lo, mid, depth + 1);
    dr = bvh_build_node(bb, r, mid, hi, depth + 1);
#pragma omp taskwait
    nd->a = r;
    nd->n = 0;
    for (int d = 0; d < 3; d++) {
        const bvh_node *L = &bb->b->nodes[self + 1], *R = &bb->b->nodes[r];
        nd->lo[d] = L->lo[d] < R->lo[d] ? L->lo[d] : R->lo[d];
        nd->hi[d] = L->hi[d] > R->hi[d] ? L->hi[d] : R->hi[d];
    }
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
    cen = qdc_mallocn(3 * (size_t)ntri, sizeof(double));
    memset(&bb, 0, sizeof bb);
    bb.key = qdc_mallocn((size_t)ntri, sizeof(double));
    if (!b->nodes || !b->tv || !b->id || !b->at || !cen || !bb.key) {
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

void bderr_bvh_free(bderr_bvh *b)
{
    if (!b)
        return;
    qdc_free(b->nodes);
    qdc_free(b->tv);
    qdc_free(b->id);
    qdc_free(b->at);
    qdc_free(b);
}

/* closest_on_triangle for the triangle at leaf position i. */
static double leaf_closest(const bderr_bvh *b, int32_t i, const double p[3], double q[3])
{
    const int32_t *t = b->tv + 3 * (size_t)i;

    return closest_on_triangle(p, b->xyz + 3 * (size_t)t[0], b->xyz + 3 * (size_t)t[1],
                               b->xyz + 3 * (size_t)t[2], q);
}

/* Squared distance from p to the box of nd (0 inside). */
static double box_dist2(const bvh_node *nd, const double p[3])
{
    double s = 0;

    for (int d = 0; d < 3; d++) {
        double e = p[d] < nd->lo[d]   ? nd->lo[d] - p[d]
                   : p[d] > nd->hi[d] ? p[d] - nd->hi[d]
                                      : 0;
        s += e * e;
    }
    return s;
}

double bderr_bvh_closest(const bderr_bvh *b, const double p[3], double cp[3],
                         int32_t *tri)
{
    return bderr_bvh_closest_near(b, p, -1, cp, tri);
}

double bderr_bvh_closest_near(const bderr_bvh *b, const double p[3], int32_t near,
                              double cp[3], int32_t *tri)
{
    int32_t stack[BVH_STACK];
    double sd[BVH_STACK], best = INFINITY, q[3], bq[3] = {0, 0, 0};
    int sp = 0;
    int32_t bt = -1;

    if (tri)
        *tri = -1;
    if (!b || b->ntri == 0)
        return INFINITY;
    if (near >= 0 && near < b->ntri) {
        /* a bound to start from: the search then skips every box farther
         * than this triangle (a sliding vertex stays near its own faces) */
        best = leaf_closest(b, b->at[near], p, bq);
        bt = best == best ? b->at[near] : -1;
        if (bt < 0)
            best = INFINITY;
    }
    stack[sp] = 0;
    sd[sp++] = box_dist2(&b->nodes[0], p);
    while (sp > 0) {
        const bvh_node *nd;
        double dl, dr;
        int32_t l, r;
        sp--;
        if (sd[sp] >= best)
            continue;
        nd = &b->nodes[stack[sp]];
        if (nd->n > 0) {
            for (int32_t i = nd->a; i < nd->a + nd->n; i++) {
                double d = leaf_closest(b, i, p, q);
                if (d < best) {
                    best = d;
                    bt = i;
                    memcpy(bq, q, sizeof q);
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
        if (dr < best) {
            stack[sp] = r;
            sd[sp++] = dr;
        }
        if (dl < best) {
            stack[sp] = l;
            sd[sp++] = dl;
        }
    }
    if (bt < 0) /* p had a NaN: every comparison failed */
        return NAN;
    if (cp)
        memcpy(cp, bq, sizeof bq);
    if (tri)
        *tri = b->id[bt];
    return sqrt(best);
}

/* ------------------------------------------------------------------------ */
/* Sampling                                                                  */

/* splitmix64's output function: a good 64-bit mix, used as a counter-based
 * generator so sample k needs no state from samples before it. */
static uint64_t mix64(uint64_t x)
{
    x += UINT64_C(0x9e3779b97f4a7c15);
    x = (x ^ (x >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    x = (x ^ (x >> 27)) * UINT64_C(0x94d049bb133111eb);
    return x ^ (x >> 31);
}

static double unit_double(uint64_t x)
{
    return (double)(x >> 11) * 0x1.0p-53;
}

typedef struct {
    const double *xyz;
    const int32_t *tris;
    int32_t ntri;
    int32_t *verts; /* vertices used by a triangle */
    int32_t nverts;
    int32_t *tri_of; /* nv: a triangle of each used vertex (-1: unused) */
    double *cdf;     /* ntri running sums of triangle areas */
    int64_t nrand;   /* random samples (0 if the area is 0) */
    uint64_t seed;
} surface;

static void tri_corners(const surface *s, int32_t t, const double *c[3])
{
    for (int v = 0; v < 3; v++)
        c[v] = s->xyz + 3 * (size_t)s->tris[3 * (size_t)t + v];
}

static double tri_area(const double *c[3])
{
    double u[3], v[3], n[3];

    sub3(u, c[1], c[0]);
    sub3(v, c[2], c[0]);
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    return 0.5 * sqrt(dot3(n, n));
}

static qdc_status surface_init(surface *s, const double *xyz, int32_t nv,
                               const int32_t *tris, int32_t ntri, int64_t nrand,
                               uint64_t seed, qdc_error *err)
{
    uint8_t *used;
    double acc = 0;

    memset(s, 0, sizeof *s);
    s->xyz = xyz;
    s->tris = tris;
    s->ntri = ntri;
    s->seed = seed;
    used = qdc_calloc((size_t)nv, 1);
    s->verts = qdc_mallocn((size_t)nv, sizeof(int32_t));
    s->tri_of = qdc_mallocn((size_t)nv + 1, sizeof(int32_t));
    s->cdf = qdc_mallocn((size_t)ntri, sizeof(double));
    if (!used || !s->verts || !s->cdf || !s->tri_of) {
        qdc_free(used);
        return qdc_fail(err, QDC_ENOMEM, "out of memory for surface samples");
    }
    for (int32_t v = 0; v < nv; v++)
        s->tri_of[v] = -1;
    for (int64_t i = 0; i < 3 * (int64_t)ntri; i++) {
        used[tris[i]] = 1;
        s->tri_of[tris[i]] = (int32_t)(i / 3);
    }
    for (int32_t v = 0; v < nv; v++)
        if (used[v])
            s->verts[s->nverts++] = v;
    qdc_free(used);
    for (int32_t t = 0; t < ntri; t++) {
        const double *c[3];
        tri_corners(s, t, c);
        acc += tri_area(c);
        s->cdf[t] = acc;
    }
    s->nrand = acc > 0 ? nrand : 0;
    return QDC_OK;
}

static void surface_free(surface *s)
{
    qdc_free(s->verts);
    qdc_free(s->tri_of);
    qdc_free(s->cdf);
}

static int64_t surface_count(const surface *s)
{
    return (int64_t)s->nverts + s->ntri + s->nrand;
}

/* Sample k: the vertices, then the centroids, then random points. Returns a
 * triangle the sample is on. */
static int32_t surface_point(const surface *s, int64_t k, double p[3])
{
    const double *c[3];
    double u0, s1, u2;
    int32_t lo, hi;

    if (k < s->nverts) {
        memcpy(p, s->xyz + 3 * (size_t)s->verts[k], 3 * sizeof(double));
        return s->tri_of[s->verts[k]];
    }
    k -= s->nverts;
    if (k < s->ntri) {
        tri_corners(s, (int32_t)k, c);
        for (int d = 0; d < 3; d++)
            p[d] = (c[0][d] + c[1][d] + c[2][d]) / 3;
        return (int32_t)k;
    }
    k -= s->ntri;
    u0 = unit_double(mix64(s->seed + 3 * (uint64_t)k)) * s->cdf[s->ntri - 1];
    s1 = sqrt(unit_double(mix64(s->seed + 3 * (uint64_t)k + 1)));
    u2 = unit_double(mix64(s->seed + 3 * (uint64_t)k + 2));
    lo = 0; /* first triangle whose running sum exceeds u0: never a zero-area one */
    hi = s->ntri - 1;
    while (lo < hi) {
        int32_t mid = lo + (hi - lo) / 2;
        if (s->cdf[mid] > u0)
            hi = mid;
        else
            lo = mid + 1;
    }
    tri_corners(s, lo, c);
    /* uniform on the triangle: sqrt for the first coordinate (Osada et al.) */
    for (int d = 0; d < 3; d++)
        p[d] = (1 - s1) * c[0][d] + s1 * (1 - u2) * c[1][d] + s1 * u2 * c[2][d];
    return lo;
}

enum { CHUNK = 1024 };

typedef struct {
    double max, sum, sum2;
    int64_t n;
} dstats;

/* Distances from every sample of s to the surface in b. The search for each
 * starts from the triangle of b with the sample's triangle's index: the same
 * answer (bderr_bvh_closest_near), found sooner when the two surfaces share
 * their triangles, as an input and its optimized mesh do. */
static qdc_status directed(const surface *s, const bderr_bvh *b, dstats *out,
                           qdc_error *err)
{
    int64_t n = surface_count(s), nchunk = (n + CHUNK - 1) / CHUNK;
    double *part = qdc_mallocn((size_t)nchunk, 3 * sizeof(double));

    memset(out, 0, sizeof *out);
    if (!part)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for sample sums");
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 4)
#endif
    for (int64_t c = 0; c < nchunk; c++) {
        double mx = 0, sm = 0, sm2 = 0, p[3];
        int64_t end = (c + 1) * CHUNK < n ? (c + 1) * CHUNK : n;
        for (int64_t k = c * CHUNK; k < end; k++) {
            double d;
            int32_t t = surface_point(s, k, p);
            d = bderr_bvh_closest_near(b, p, t, NULL, NULL);
            mx = d > mx ? d : mx;
            sm += d;
            sm2 += d * d;
        }
        part[3 * c] = mx;
        part[3 * c + 1] = sm;
        part[3 * c + 2] = sm2;
    }
    for (int64_t c = 0; c < nchunk; c++) {
        out->max = part[3 * c] > out->max ? part[3 * c] : out->max;
        out->sum += part[3 * c + 1];
        out->sum2 += part[3 * c + 2];
    }
    out->n = n;
    qdc_free(part);
    return QDC_OK;
}

/* Diagonal of the bounding box of the used vertices. */
static double surface_diag(const surface *s)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY},
           hi[3] = {-INFINITY, -INFINITY, -INFINITY};

    if (s->nverts == 0)
        return 0;
    for (int32_t i = 0; i < s->nverts; i++)
        for (int d = 0; d < 3; d++) {
            double x = s->xyz[3 * (size_t)s->verts[i] + d];
            lo[d] = fmin(lo[d], x);
            hi[d] = fmax(hi[d], x);
        }
    return sqrt(dist2(lo, hi));
}

qdc_status bderr_surfaces(const double *xa, int32_t nva, const int32_t *ta, int32_t nta,
                          const double *xb, int32_t nvb, const int32_t *tb, int32_t ntb,
                          int64_t samples_per_side, uint64_t seed, bderr_result *r,
                          qdc_error *err)
{
    surface sa, sb;
    bderr_bvh *ba = NULL, *bb = NULL;
    dstats da, db;
    qdc_status st;
    int64_t n;

    if (!r || samples_per_side < 0 || samples_per_side > (INT64_C(1) << 40))
        return qdc_fail(err, QDC_EINVAL, "bderr_surfaces: invalid arguments");
    memset(r, 0, sizeof *r);
    if (nta <= 0 || ntb <= 0)
        return qdc_fail(err, QDC_EINVAL,
                        "bderr_surfaces: empty surface (%d and %d triangles)", nta, ntb);
    st = bderr_bvh_build(xa, nva, ta, nta, &ba, err);
    if (st == QDC_OK)
        st = bderr_bvh_build(xb, nvb, tb, ntb, &bb, err);
    if (st != QDC_OK) {
        bderr_bvh_free(ba);
        return st;
    }
    memset(&sb, 0, sizeof sb);
    st = surface_init(&sa, xa, nva, ta, nta, samples_per_side, mix64(seed), err);
    if (st == QDC_OK)
        st = surface_init(&sb, xb, nvb, tb, ntb, samples_per_side, mix64(~seed), err);
    if (st == QDC_OK)
        st = directed(&sa, bb, &da, err);
    if (st == QDC_OK)
        st = directed(&sb, ba, &db, err);
    if (st == QDC_OK) {
        double vmax = 0.0;
#ifdef _OPENMP
#pragma omp parallel for reduction(max : vmax) schedule(dynamic, 1024)
#endif
        for (int32_t i = 0; i < sa.nverts; i++) {
            int32_t v = sa.verts[i];
            double d =
                bderr_bvh_closest_near(bb, xa + 3 * (size_t)v, sa.tri_of[v], NULL, NULL);
            vmax = d > vmax ? d : vmax;
        }
        r->vertex_max = vmax;
    }
    if (st == QDC_OK) {
        n = da.n + db.n;
        r->h_a_to_b = da.max;
        r->h_b_to_a = db.max;
        r->hausdorff = fmax(da.max, db.max);
        r->mean = (da.sum + db.sum) / (double)n;
        r->rms = sqrt((da.sum2 + db.sum2) / (double)n);
        r->diag = surface_diag(&sb);
        if (r->diag > 0) {
            r->hausdorff_rel = r->hausdorff / r->diag;
            r->mean_rel = r->mean / r->diag;
            r->rms_rel = r->rms / r->diag;
            r->vertex_max_rel = r->vertex_max / r->diag;
        }
        r->n_samples = n;
        r->ntri_a = nta;
        r->ntri_b = ntb;
    }
    surface_free(&sa);
    surface_free(&sb);
    bderr_bvh_free(ba);
    bderr_bvh_free(bb);
    return st;
}

/* ------------------------------------------------------------------------ */
/* Boundary faces                                                            */

/* Local faces of a tet, each seen from outside a positive tet. */

typedef struct {
    uint64_t key; /* the two larger vertices of the face */
    int32_t face; /* 4 * tet + local face */
} face_rec;

static int face_cmp(const void *a, const void *b)
{
    uint64_t x = ((const face_rec *)a)->key, y = ((const face_rec *)b)->key;

    return x < y ? -1 : x > y;
}

/* Buckets hold a dozen faces or so: insertion sort, qsort for the odd big one. */
static void sort_faces(face_rec *r, int64_t n)
{
    if (n > 32) {
        qsort(r, (size_t)n, sizeof *r, face_cmp);
        return;
    }
    for (int64_t i = 1; i < n; i++) {
        face_rec x = r[i];
        int64_t j = i;
        while (j > 0 && r[j - 1].key > x.key) {
            r[j] = r[j - 1];
            j--;
        }
        r[j] = x;
    }
}

static void face_sorted(const int32_t *t, int f, int32_t s[3])
{
    tet_sort3(t[tet_face_of[f][0]], t[tet_face_of[f][1]], t[tet_face_of[f][2]], s);
}

/* Faces of exactly one tet, as triangles in the tet's orientation. Faces are
 * bucketed by their smallest vertex (a counting sort), then each small bucket
 * is sorted by the other two, so equal faces end up side by side. */
static qdc_status boundary_faces(const mesh_t *m, const char *what, int32_t **out,
                                 int32_t *nout, qdc_error *err)
{
    int64_t nf = 4 * (int64_t)m->nt;
    int64_t *start = NULL;
    face_rec *rec = NULL;
    int32_t *tris = NULL, nb = 0;
    qdc_status st = QDC_OK;

    *out = NULL;
    *nout = 0;
    if (m->nv < 0 || m->nt < 0 || (m->nt && !m->tets) || (m->nv && !m->xyz))
        return qdc_fail(err, QDC_EINVAL, "%s: invalid mesh", what);
    for (int64_t i = 0; i < nf; i++)
        if (m->tets[i] < 0 || m->tets[i] >= m->nv)
            return qdc_fail(err, QDC_EINVAL, "%s: tet %lld: vertex %d out of range", what,
                            (long long)(i / 4), m->tets[i]);
    start = qdc_calloc((size_t)m->nv + 1, sizeof(int64_t));
    rec = qdc_mallocn((size_t)nf, sizeof *rec);
    if (!start || !rec) {
        st = qdc_fail(err, QDC_ENOMEM, "%s: out of memory for faces", what);
        goto out;
    }
    for (int64_t f = 0; f < nf; f++) {
        int32_t s[3];
        face_sorted(m->tets + 4 * (f / 4), (int)(f % 4), s);
        start[s[0] + 1]++;
    }
    for (int32_t v = 0; v < m->nv; v++)
        start[v + 1] += start[v];
    for (int64_t f = 0; f < nf; f++) {
        int32_t s[3];
        face_sorted(m->tets + 4 * (f / 4), (int)(f % 4), s);
        rec[start[s[0]]].key = (uint64_t)s[1] << 32 | (uint32_t)s[2];
        rec[start[s[0]]++].face = (int32_t)f;
    }
    for (int32_t v = m->nv; v > 0; v--) /* the fill moved each start to the next one */
        start[v] = start[v - 1];
    start[0] = 0;
    for (int32_t v = 0; v < m->nv; v++)
        sort_faces(rec + start[v], start[v + 1] - start[v]);
    /* count, then fill: a run of one record is a boundary face */
    for (int pass = 0; pass < 2; pass++) {
        nb = 0;
        for (int32_t v = 0; v < m->nv; v++) {
            for (int64_t i = start[v]; i < start[v + 1];) {
                int64_t j = i + 1;
                while (j < start[v + 1] && rec[j].key == rec[i].key)
                    j++;
                if (j == i + 1 && pass == 1) {
                    const int32_t *t = m->tets + 4 * (size_t)(rec[i].face / 4);
                    for (int k = 0; k < 3; k++)
                        tris[3 * (size_t)nb + k] = t[tet_face_of[rec[i].face % 4][k]];
                }
                nb += j == i + 1;
                i = j;
            }
        }
        if (pass == 0) {
            tris = qdc_mallocn(3 * (size_t)nb, sizeof(int32_t));
            if (!tris) {
                st = qdc_fail(err, QDC_ENOMEM, "%s: out of memory for faces", what);
                goto out;
            }
        }
    }
    *out = tris;
    *nout = nb;
out:
    qdc_free(start);
    qdc_free(rec);
    return st;
}

/* bderr_meshes on the boundary triangles ta (na) of out and tb (nb) of ref. */
static qdc_status meshes_with(const mesh_t *out, const mesh_t *ref, const int32_t *ta,
                              int32_t na, const int32_t *tb, int32_t nb,
                              int64_t samples_per_side, bderr_result *r, qdc_error *err)
{
    qdc_status st = QDC_OK;
    double lo[3], hi[3], diag, *xa = NULL, *xb = NULL;

    diag = mesh_bbox(ref, lo, hi);
    if (isfinite(diag) && diag > 0 && (diag < 1e-50 || diag > 1e50)) {
        /* squared distances of a mesh of size 1e200 overflow, of 1e-200
         * underflow: measure in units of the reference's diagonal */
        xa = qdc_mallocn(3 * (size_t)out->nv + 1, sizeof(double));
        xb = qdc_mallocn(3 * (size_t)ref->nv + 1, sizeof(double));
        if (!xa || !xb) {
            st = QDC_ENOMEM;
        } else {
            for (size_t i = 0; i < 3 * (size_t)out->nv; i++)
                xa[i] = (out->xyz[i] - lo[i % 3]) / diag;
            for (size_t i = 0; i < 3 * (size_t)ref->nv; i++)
                xb[i] = (ref->xyz[i] - lo[i % 3]) / diag;
            st = bderr_surfaces(xa, out->nv, ta, na, xb, ref->nv, tb, nb,
                                samples_per_side, UINT64_C(0x51ab5eed), r, err);
            if (st == QDC_OK) {
                r->hausdorff *= diag;
                r->h_a_to_b *= diag;
                r->h_b_to_a *= diag;
                r->mean *= diag;
                r->rms *= diag;
                r->diag = diag;
            }
        }
    } else {
        st = bderr_surfaces(out->xyz, out->nv, ta, na, ref->xyz, ref->nv, tb, nb,
                            samples_per_side, UINT64_C(0x51ab5eed), r, err);
    }
    qdc_free(xa);
    qdc_free(xb);
    return st;
}

qdc_status bderr_meshes(const mesh_t *out, const mesh_t *ref, int64_t samples_per_side,
                        bderr_result *r, qdc_error *err)
{
    int32_t *ta = NULL, *tb = NULL, na = 0, nb = 0;
    qdc_status st;

    if (!out || !ref || !r)
        return qdc_fail(err, QDC_EINVAL, "bderr_meshes: NULL argument");
    st = boundary_faces(out, "output mesh", &ta, &na, err);
    if (st == QDC_OK)
        st = boundary_faces(ref, "reference mesh", &tb, &nb, err);
    if (st == QDC_OK)
        st = meshes_with(out, ref, ta, na, tb, nb, samples_per_side, r, err);
    qdc_free(ta);
    qdc_free(tb);
    return st;
}

qdc_status bderr_meshes_faces(const mesh_t *out, const mesh_t *ref, const mesh_faces *f,
                              int64_t samples_per_side, bderr_result *r, qdc_error *err)
{
    if (!f)
        return bderr_meshes(out, ref, samples_per_side, r, err);
    if (!out || !ref || !r || out->nt != f->nt || ref->nt != f->nt || out->nv != ref->nv)
        return qdc_fail(err, QDC_EINVAL, "bderr_meshes_faces: invalid arguments");
    return meshes_with(out, ref, f->tris, f->ntri, f->tris, f->ntri, samples_per_side, r,
                       err);
}
