/* finish.c - worst-tet finishing pass (docs/method.md §5a). */
#include "opt/finish.h"
#include "core/tet.h"

#include "geom/metric.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define FINISH_INNER 8
/* Broad sweeps take one Newton step per vertex (and more sweeps do the rest):
 * measured on 8 dev meshes, mean ratio 0.7729 against 0.7733 with up to 8
 * steps, for 30% less work. */
#define FINISH_HALVINGS 12
/* The normalized-gradient descent (boundary vertices in slide mode) halves
 * its step at most 6 times a try: 12 cost 12% more of the pass on an 800k-tet
 * ball for the same result (mean ratio 0.6807; bones of 100k tets within
 * 0.0002), the tries past 6 being steps of under 1/1000 of an edge. */
#define RELAX_HALVINGS 6
/* ... and takes at most 2 steps a visit in the broad sweeps, as the interior
 * vertices take one Newton step (the sweeps do the rest): on the 800k-tet ball
 * the pass 2.15 -> 1.90 s, mean ratio the same (0.6807), smallest dihedral
 * 5.0 -> 5.6 degrees; the files of other tools +0.0386 against +0.0388. */
#define RELAX_BROAD 2

typedef struct {
    double q;
    int32_t v;
} vq_pair;

/* Worst first, for the colouring: a stable counting sort of list[0..n) (built
 * in vertex order) into 1024 buckets of q in [-1, 1] (mean ratios and sines),
 * O(n) where qsort cost 2% of the pass. 0 if out of memory. */
#define VQ_BUCKETS 1024
static int vq_bucket(double q)
{
    return q > -1.0 ? (q < 1.0 ? (int)((q + 1.0) * (VQ_BUCKETS / 2)) : VQ_BUCKETS - 1)
                    : 0;
}

#define VQ_RANGES 8

static int vq_sort(vq_pair *list, int32_t n)
{
    int32_t *cnt = qdc_calloc((size_t)VQ_RANGES * VQ_BUCKETS + 1, sizeof(int32_t));
    vq_pair *tmp = qdc_mallocn((size_t)n + 1, sizeof *tmp);

    if (!cnt || !tmp) {
        qdc_free(cnt);
        qdc_free(tmp);
        return 0;
    }
    /* each range of the list counted and placed by one thread, the places
     * bucket by bucket and range by range: the order of one serial pass */
#pragma omp parallel for schedule(static)
    for (int r = 0; r < VQ_RANGES; r++) {
        int32_t *c = cnt + (size_t)r * VQ_BUCKETS;
        for (int32_t i = qdc_part(n, r, VQ_RANGES); i < qdc_part(n, r + 1, VQ_RANGES);
             i++)
            c[vq_bucket(list[i].q)]++;
    }
    qdc_count_places(cnt, VQ_RANGES, VQ_BUCKETS, VQ_BUCKETS, NULL);
#pragma omp parallel for schedule(static)
    for (int r = 0; r < VQ_RANGES; r++) {
        int32_t *c = cnt + (size_t)r * VQ_BUCKETS;
        for (int32_t i = qdc_part(n, r, VQ_RANGES); i < qdc_part(n, r + 1, VQ_RANGES);
             i++)
            tmp[c[vq_bucket(list[i].q)]++] = list[i];
    }
    memcpy(list, tmp, (size_t)n * sizeof *list);
    qdc_free(cnt);
    qdc_free(tmp);
    return 1;
}

/* k-th smallest of a[0..n) (0-based), reordering a: Hoare quickselect with a
 * median-of-three pivot, O(n) expected. */
static double kth_smallest(double *a, int32_t n, int32_t k)
{
    int32_t lo = 0, hi = n - 1;

    while (lo < hi) {
        int32_t mid = lo + (hi - lo) / 2, i = lo, j = hi;
        double x = a[lo], y = a[mid], z = a[hi];
        double piv =
            x < y ? (y < z ? y : (x < z ? z : x)) : (x < z ? x : (y < z ? z : y));
        while (i <= j) {
            while (a[i] < piv)
                i++;
            while (a[j] > piv)
                j--;
            if (i <= j) {
                double t = a[i];
                a[i++] = a[j];
                a[j--] = t;
            }
        }
        if (k <= j)
            hi = j;
        else if (k >= i)
            lo = i;
        else
            return a[k];
    }
    return a[k];
}

#define SEL_BUCKETS 4096
static int sel_bucket(double x, double lo, double scale)
{
    double b = (x - lo) * scale;

    return b < SEL_BUCKETS - 1 ? (b > 0.0 ? (int)b : 0) : SEL_BUCKETS - 1;
}

/* The k-th smallest (0-based) of a[0..n), whose values lie in [lo, hi], with
 * a unchanged; if sum, the sum of the k + 1 smallest goes there. A parallel
 * histogram of 4096 buckets over [lo, hi] finds the bucket that holds it (the
 * bucket is monotone in the value, so the answer is exact), then quickselect
 * over that bucket's values only: the serial copy and quickselect over every
 * tet cost 0.17 s a call at 5M tets. The sum is taken in one serial pass, so
 * it does not depend on the thread count. Where [lo, hi] is not a finite
 * range, the serial quickselect over a copy. QDC_ENOMEM if out of memory. */
static qdc_status kth_smallest_of(const double *a, int32_t n, int32_t k, double lo,
                                  double hi, double *kth, double *sum)
{
    int nth = qdc_threads_upto(64);
    int32_t *cnt = NULL, bk = 0, below = 0, m = 0;
    double *sel = NULL, scale = 0.0, s = 0.0;
    int coarse = isfinite(lo) && isfinite(hi) && hi > lo && n > SEL_BUCKETS;

    if (coarse) {
        scale = SEL_BUCKETS / (hi - lo);
        cnt = qdc_calloc((size_t)nth * SEL_BUCKETS, sizeof(int32_t));
        if (!cnt)
            return QDC_ENOMEM;
#pragma omp parallel num_threads(nth)
        {
            int32_t *c = cnt + (size_t)omp_get_thread_num() * SEL_BUCKETS;
#pragma omp for schedule(static)
            for (int32_t i = 0; i < n; i++)
                c[sel_bucket(a[i], lo, scale)]++;
        }
        for (bk = 0; bk < SEL_BUCKETS; bk++) {
            int32_t in = 0;
            for (int i = 0; i < nth; i++)
                in += cnt[(size_t)i * SEL_BUCKETS + bk];
            if (below + in > k) {
                m = in;
                break;
            }
            below += in;
        }
    } else {
        m = n;
    }
    sel = qdc_mallocn((size_t)m + 1, sizeof(double));
    if (!sel) {
        qdc_free(cnt);
        return QDC_ENOMEM;
    }
    if (coarse) {
        int32_t j = 0;
        for (int32_t i = 0; i < n; i++) {
            int b = sel_bucket(a[i], lo, scale);
            if (b < bk)
                s += a[i];
            else if (b == bk)
                sel[j++] = a[i];
        }
    } else {
        memcpy(sel, a, (size_t)n * sizeof(double));
    }
    *kth = kth_smallest(sel, m, k - below);
    /* after quickselect sel[0..k - below] holds the smallest of the bucket */
    if (sum) {
        for (int32_t i = 0; i <= k - below; i++)
            s += sel[i];
        *sum = s;
    }
    qdc_free(cnt);
    qdc_free(sel);
    return QDC_OK;
}

/* What star_eval finds besides the objective. */
typedef struct {
    int32_t bad;  /* star tets that are not positive */
    int32_t kmax; /* position (in vt_idx) of the star tet of largest q~ */
    double qmax;  /* its q~ */
    double emin3; /* the cube of the star's smallest mean ratio (if asked) */
} star_out;

/* q~ of star tet k (position in vt_idx) of v with v placed at y, and its parts. */
static double star_tet_qt(const mesh_topo *tp, const double *x, int32_t k,
                          const double *y, opt_metric m, double delta, double *g,
                          metric_parts *pt)
{
    int32_t t = tp->vt_idx[k] >> 2, a = tp->vt_idx[k] & 3;
    double p[4][3];

    for (int b = 0; b < 4; b++)
        memcpy(p[b], b == a ? y : x + 3 * (size_t)tp->tets[4 * (size_t)t + b],
               sizeof p[b]);
    if (g)
        return metric_qt_grad(m, &p[0][0], a, delta, g, pt);
    metric_parts_for(m, p[0], p[1], p[2], p[3], pt);
    return metric_qt(m, pt, delta);
}

/* Local objective of vertex v placed at y: sum of q~ over its star, what o
 * receives (emin3 as star_min_eta3 finds it, from the same parts, if want3)
 * and (if g) the gradient with respect to y. A trial that must not raise the
 * star's largest q~ above cap is rejected as soon as one tet does, tet first
 * (the worst at the start, most often the one) before the others: NAN then,
 * and o is incomplete. cap = INFINITY evaluates the whole star. */
static double star_eval(const mesh_topo *tp, const double *x, int32_t v, const double *y,
                        opt_metric m, double delta, double cap, int32_t first, int want3,
                        star_out *o, double *g)
{
    double f = 0.0, worst = 0.0, e3 = INFINITY;
    int32_t bad = 0, kw = -1;
    metric_parts pt;

    if (g)
        g[0] = g[1] = g[2] = 0.0;
    if (cap < INFINITY && first >= 0 &&
        star_tet_qt(tp, x, first, y, m, delta, NULL, &pt) > cap)
        return NAN;
    for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
        double gt[3], q = star_tet_qt(tp, x, k, y, m, delta, g ? gt : NULL, &pt);
        if (q > cap)
            return NAN;
        if (g && isfinite(q))
            for (int c = 0; c < 3; c++)
                g[c] += gt[c];
        bad += geom_tet_bad_vl(6.0 * pt.vol, pt.l2sum);
        f += q;
        if (q > worst) {
            worst = q;
            kw = k;
        }
        if (want3) {
            double e = metric_mean_ratio_cubed(&pt);
            e3 = e < e3 ? e : e3;
        }
    }
    o->bad = bad;
    o->qmax = worst;
    o->kmax = kw;
    o->emin3 = e3;
    return f;
}

/* What star_hess finds besides the objective. */
typedef struct {
    int32_t bad; /* star tets that are not positive */
    int32_t low; /* star tets under the mean-ratio floor it was given (0 if none) */
} star_info;

/* Local objective of vertex v placed at y with its gradient and Hessian
 * (upper triangle; both skipped if g is NULL); NAN if the metric has no
 * Hessian. so, if not NULL, receives what star_eval finds of the star (its
 * worst tet and smallest mean ratio cubed; the inverted count is si's). A tet
 * is under the floor qfloor > 0 when its mean ratio 12 (9 V^2)^(1/3) / A is,
 * tested as 15552 V^2 < (qfloor A)^3 (no cube root). */
static double star_hess(const mesh_topo *tp, const double *x, int32_t v, const double *y,
                        opt_metric m, double delta, double qfloor, star_info *si,
                        double g[3], double H[6], star_out *so)
{
    double f = 0.0;

    si->bad = si->low = 0;
    if (so) {
        so->qmax = 0.0;
        so->kmax = -1;
        so->emin3 = INFINITY;
    }
    if (g) {
        memset(H, 0, 6 * sizeof(double));
        g[0] = g[1] = g[2] = 0.0;
    }
    for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
        int32_t t = tp->vt_idx[k] >> 2, a = tp->vt_idx[k] & 3;
        const int32_t *tt = tp->tets + 4 * (size_t)t;
        double gt[3], Ht[6], q, vl[2];
        q = metric_qt_hess_face(m, y, x + 3 * (size_t)tt[tet_face_of[a][0]],
                                x + 3 * (size_t)tt[tet_face_of[a][1]],
                                x + 3 * (size_t)tt[tet_face_of[a][2]], delta,
                                g ? gt : NULL, Ht, vl);
        si->bad += geom_tet_bad_vl(6.0 * vl[0], vl[1]);
        if (so) {
            double e =
                vl[0] > 0.0 ? 15552.0 * vl[0] * vl[0] / (vl[1] * vl[1] * vl[1]) : 0.0;
            if (q > so->qmax) {
                so->qmax = q;
                so->kmax = k;
            }
            so->emin3 = e < so->emin3 ? e : so->emin3;
        }
        if (qfloor > 0.0) {
            double fa = qfloor * vl[1];
            si->low += !(15552.0 * vl[0] * vl[0] >= fa * fa * fa) || !(vl[0] > 0.0);
        }
        f += q;
        if (!g || !isfinite(q))
            continue;
        for (int c = 0; c < 3; c++)
            g[c] += gt[c];
        for (int e = 0; e < 6; e++)
            H[e] += Ht[e];
    }
    return f;
}

/* Cube of the smallest mean ratio over the star of v placed at y (no cube
 * root: compared with cubed floors). */
static double star_min_eta3(const mesh_topo *tp, const double *x, int32_t v,
                            const double *y)
{
    double e = INFINITY;

    for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
        int32_t t = tp->vt_idx[k] >> 2, a = tp->vt_idx[k] & 3;
        const double *p[4];
        metric_parts pt;
        double q;
        for (int b = 0; b < 4; b++)
            p[b] = b == a ? y : x + 3 * (size_t)tp->tets[4 * (size_t)t + b];
        metric_parts_for(OPT_METRIC_MIVL, p[0], p[1], p[2], p[3], &pt);
        q = metric_mean_ratio_cubed(&pt);
        e = q < e ? q : e;
    }
    return e;
}

/* On a valid mesh a move must not take a star tet below the mesh's worst
 * mean ratio qfloor (> 0), unless that star was already below it and its
 * worst does not drop: else a sweep that raises the mean lowers the worst
 * tet, and the whole pass is thrown away by the best-iterate rule (measured
 * on a thin surface-heavy bone: the pass took the worst tet from 6e-4 to 0).
 * In cubes: e1, e0 the star's smallest mean ratio cubed after and before. */
static int floor_kept(double qfloor, double e1, double e0)
{
    return !(qfloor > 0.0) || e1 >= qfloor * qfloor * qfloor || e1 >= e0;
}

/* The cubed floor of a move's star: the mean ratio floor qfloor cubed, and
 * never a degenerate tet (core/tet.h), even where no floor is set (a tangled
 * mesh). A move must keep the star's smallest cube strictly above it. */
static double floor_cubed(double qfloor)
{
    double q3 = qfloor * qfloor * qfloor;

    return q3 > GEOM_FLAT_ETA3 ? q3 : GEOM_FLAT_ETA3;
}

static int keeps_floor(const mesh_topo *tp, const double *x, int32_t v, const double *y,
                       double qfloor)
{
    if (!(qfloor > 0.0))
        return 1;
    return floor_kept(qfloor, star_min_eta3(tp, x, v, y),
                      star_min_eta3(tp, x, v, x + 3 * (size_t)v));
}

/* Solve H d = -g for a symmetric positive definite 3x3 H (upper triangle);
 * 0 if H is not safely positive definite. */
static int newton_dir(const double H[6], const double g[3], double d[3])
{
    double l00, l10, l20, l11, l21, l22, y0, y1, y2, t;

    if (!(H[0] > 0.0))
        return 0;
    l00 = sqrt(H[0]);
    l10 = H[1] / l00;
    l20 = H[2] / l00;
    t = H[3] - l10 * l10;
    if (!(t > 1e-12 * H[3]))
        return 0;
    l11 = sqrt(t);
    l21 = (H[4] - l20 * l10) / l11;
    t = H[5] - l20 * l20 - l21 * l21;
    if (!(t > 1e-12 * H[5]))
        return 0;
    l22 = sqrt(t);
    y0 = -g[0] / l00;
    y1 = (-g[1] - l10 * y0) / l11;
    y2 = (-g[2] - l20 * y0 - l21 * y1) / l22;
    d[2] = y2 / l22;
    d[1] = (y1 - l21 * d[2]) / l11;
    d[0] = (y0 - l10 * d[1] - l20 * d[2]) / l00;
    return isfinite(d[0]) && isfinite(d[1]) && isfinite(d[2]);
}

/* Broad sweeps (one step per visit) over-relax the Newton step, as SOR does
 * Gauss-Seidel: measured on an 800k-tet ball, the pass 2.3 s against 2.5 s and
 * mean ratio 0.6807 against 0.6805 with the plain step (bones of 100k tets:
 * +0.0002); 1.6 overshoots and takes more sweeps. */
#define FINISH_OMEGA 1.3
static void shape_step(double d[3], int inner, double lbar)
{
    double dn;

    if (inner == 1)
        for (int c = 0; c < 3; c++)
            d[c] *= FINISH_OMEGA;
    dn = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (dn > 0.3 * lbar) /* at most 0.3 mean edge */
        for (int c = 0; c < 3; c++)
            d[c] *= 0.3 * lbar / dn;
}

/* 6 x the signed volume of star tet k of v with v placed at y, (if g) its
 * gradient with respect to y (constant: the volume is linear in y) and (if l2)
 * the sum of its squared edge lengths. */
static double star_vol6(const mesh_topo *tp, const double *x, int32_t k, const double *y,
                        double g[3], double *l2)
{
    static const int32_t corner[4] = {0, 1, 2, 3};
    int32_t t = tp->vt_idx[k] >> 2, a = tp->vt_idx[k] & 3;
    const int32_t *tt = tp->tets + 4 * (size_t)t;
    double p[12], v0;

    for (int b = 0; b < 4; b++)
        memcpy(p + 3 * b, b == a ? y : x + 3 * (size_t)tt[b], 3 * sizeof(double));
    v0 = geom_tet_vol6(p, corner);
    if (l2)
        *l2 = geom_tet_l2sum(p, corner);
    if (g)
        for (int c = 0; c < 3; c++) {
            double s = p[3 * a + c];
            p[3 * a + c] = s + 1.0;
            g[c] = geom_tet_vol6(p, corner) - v0;
            p[3 * a + c] = s;
        }
    return v0;
}

/* 1 if v placed at y folds (or flattens) a star tet that is usable at x and whose face
 * opposite v has its three corners on the boundary (a vertex pushed out
 * through the surface, or a flat tet along it folded by a sliding corner).
 * A move that keeps the star's inverted count may trade an inverted tet for
 * a valid one, which untangling needs; at the surface of a thin tangled mesh
 * no later move undid some of those trades, and a rerun that forbids them
 * (keep_surface, see finish_sweep) untangles it. */
static int folds_at_surface(const mesh_topo *tp, const double *x, int32_t v,
                            const double *y)
{
    for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
        int32_t a = tp->vt_idx[k] & 3;
        const int32_t *tt = tp->tets + 4 * (size_t)(tp->vt_idx[k] >> 2);
        uint8_t f = MESH_V_BOUNDARY;
        for (int b = 0; b < 4; b++)
            if (b != a)
                f &= tp->vflag[tt[b]];
        if (f && !geom_tet_bad(x, tt)) {
            double l2, w = star_vol6(tp, x, k, y, NULL, &l2);
            if (geom_tet_bad_vl(w, l2))
                return 1;
        }
    }
    return 0;
}

/* The keep_surface rule of a trial y of v whose star has bad1 inverted tets
 * (no fold without one). */
static int surface_kept(const mesh_topo *tp, const double *x, int32_t v, const double *y,
                        int32_t bad1, int ks)
{
    return !ks || bad1 == 0 || !folds_at_surface(tp, x, v, y);
}

/* A trial y of v is taken when the star's sum drops, no star tet inverts and
 * the floor holds (and with ks, keep_surface, nothing folds at the surface). */
static int step_ok(const mesh_topo *tp, const double *x, int32_t v, const double *y,
                   double f0, double f1, const star_info *s0, const star_info *s1,
                   double qfloor, int ks)
{
    return f1 < f0 && s1->bad <= s0->bad &&
           (s1->low == 0 || keeps_floor(tp, x, v, y, qfloor)) &&
           surface_kept(tp, x, v, y, s1->bad, ks);
}

/* y = xv + t dir, put back on v's surface or line if sl (a sliding vertex). */
static void trial_point(const slide_ctx *sl, int32_t v, const double *xv,
                        const double dir[3], double t, double y[3])
{
    for (int c = 0; c < 3; c++)
        y[c] = xv[c] + t * dir[c];
    if (sl) {
        double yp[3];
        slide_project(sl, v, y, yp);
        memcpy(y, yp, sizeof yp);
    }
}

/* Trials y = xv + d, xv + d/2, ... until one is taken (step_ok); 1 then,
 * with its value *f1, *s1 and (if g1) derivatives. */
static int try_steps(const mesh_topo *tp, const double *x, int32_t v, const double d[3],
                     opt_metric m, double delta, double qfloor, double f0,
                     const star_info *s0, double g1[3], double H1[6], double y[3],
                     double *f1, star_info *s1, int ks)
{
    const double *xv = x + 3 * (size_t)v;
    double sc = 1.0;

    for (int h = 0; h < FINISH_HALVINGS; h++, sc *= 0.5) {
        trial_point(NULL, v, xv, d, sc, y);
        *f1 = star_hess(tp, x, v, y, m, delta, qfloor, s1, g1, H1, NULL);
        if (step_ok(tp, x, v, y, f0, *f1, s0, s1, qfloor, ks))
            return 1;
    }
    return 0;
}

/* Damped Newton on one interior vertex: full step first (capped at 0.3 mean
 * edge), halved until the local objective drops without a new inverted tet;
 * where the Hessian is not positive definite, the normalized gradient step. */
static int32_t newton_vertex(const mesh_topo *tp, double *x, int32_t v, opt_metric m,
                             double delta, double lbar, double rtol, int inner,
                             double qfloor, int ks)
{
    double *xv = x + 3 * (size_t)v, g[3], H[6], f0;
    int32_t moves = 0;
    star_info s0, s1;

    f0 = star_hess(tp, x, v, xv, m, delta, 0.0, &s0, g, H, NULL);
    for (int it = 0; it < inner && isfinite(f0); it++) {
        double d[3] = {0, 0, 0}, y[3], f1 = f0, g1[3], H1[6];
        if (newton_dir(H, g, d)) {
            /* predicted decrease -g.d/2 at rounding level: converged (else the
             * line search would burn all its halvings) */
            if (!(-0.5 * (g[0] * d[0] + g[1] * d[1] + g[2] * d[2]) > 1e-13 * f0))
                break;
        } else {
            double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
            if (!(gn > 0.0) || !isfinite(gn))
                break;
            for (int c = 0; c < 3; c++)
                d[c] = -0.05 * lbar * g[c] / gn;
        }
        shape_step(d, inner, lbar);
        /* a trial is evaluated with its derivatives (the full step is nearly
         * always taken, and they serve the next iteration), except in the last
         * iteration */
        if (!try_steps(tp, x, v, d, m, delta, qfloor, f0, &s0, it + 1 < inner ? g1 : NULL,
                       H1, y, &f1, &s1, ks))
            break;
        memcpy(xv, y, sizeof y);
        moves++;
        if (it + 1 == inner)
            break;
        memcpy(g, g1, sizeof g1);
        memcpy(H, H1, sizeof H1);
        if (f0 - f1 < rtol * f0)
            break;
        f0 = f1;
        s0 = s1;
    }
    return moves;
}

/* Adaptive normalized-gradient descent of one vertex (docs/method.md §5a): step along
 * -g/|g|, start 0.05 mean edge, x1.6 after a success (cap 0.3), halve up to 6
 * times until the local objective decreases without inverting a star tet; 2
 * steps in a broad sweep (rtol > 0), up to 8 in a polish sweep. */
static int32_t relax_vertex(const mesh_topo *tp, const slide_ctx *sl, double *x,
                            int32_t v, opt_metric m, double delta, double lbar,
                            double rtol, double qfloor, int ks)
{
    int sliding = sl && slide_kind(sl, v) != SLIDE_INTERIOR;
    double s = 0.05 * lbar, *xv = x + 3 * (size_t)v;
    int32_t moves = 0;

    for (int it = 0; it < (rtol > 0.0 ? RELAX_BROAD : FINISH_INNER); it++) {
        double g[3], gn, y[3], f0, f1;
        star_out s0, s1;
        int ok = 0;
        f0 = star_eval(tp, x, v, xv, m, delta, INFINITY, -1, qfloor > 0.0, &s0, g);
        if (!isfinite(f0))
            break;
        if (sliding) {
            double gt[3];
            slide_tangent(sl, v, g, gt);
            memcpy(g, gt, sizeof gt);
        }
        gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        if (!(gn > 0.0) || !isfinite(gn))
            break;
        for (int h = 0; h < RELAX_HALVINGS; h++) {
            trial_point(sliding ? sl : NULL, v, xv, g, -s / gn, y);
            /* The sum must drop and the inverted count must not grow. A sliding
             * boundary vertex must not worsen its worst star tet either: on curved
             * surfaces it otherwise flattens all-boundary tets (measured on the
             * sphere: worst tet 0.259 -> 0.230). For interior vertices that rule
             * blocks useful moves (measured -0.005 mean on the dev corpus). Most
             * trials of a sliding vertex fail by that rule (87% on a thin bone of
             * 100k tets), so they are cut short at the first tet above it. */
            f1 = star_eval(tp, x, v, y, m, delta, sliding ? s0.qmax : INFINITY, s0.kmax,
                           qfloor > 0.0, &s1, NULL);
            /* keeps_floor's test, on the cubes star_eval found */
            if (f1 < f0 && s1.bad <= s0.bad && floor_kept(qfloor, s1.emin3, s0.emin3) &&
                surface_kept(tp, x, v, y, s1.bad, ks)) {
                ok = 1;
                break;
            }
            s *= 0.5;
        }
        if (!ok)
            break;
        memcpy(xv, y, sizeof y);
        moves++;
        s = fmin(s * 1.6, 0.3 * lbar);
        if (f0 - f1 < rtol * f0)
            break; /* converged enough (measured: same quality, 3-4x faster pass) */
    }
    return moves;
}

/* A vertex sliding on a surface takes a Newton step in its tangent plane in
 * the broad sweeps when its star's smallest mean ratio is at least this.
 * Everywhere (tried 2026-11-25), it was better on an 800k-tet ball (mean
 * ratio 0.6815 against 0.6807, the pass 1.7 s against 2.3 s) but worse on the
 * thin bones of scripts/corpus.py at 100k tets (bone-lowq 0.5706 against
 * 0.5804, bone-scan 0.5940 against 0.6122): where a star's sum is ruled by
 * slivers no move opens, the Newton step trades the good tets for them, and
 * those stars keep the descent. The gate is the star's smallest mean ratio
 * when the sweep began (no extra evaluation). Measured with it (2026-11-27,
 * against the descent alone): the 1M-tet ball 0.6792 -> 0.6802, the 5M-tet
 * one 0.6675 -> 0.6693 with the run 40.8 -> 38.7 s; the 28 runs of the dev
 * meshes, the 100k corpus and the 100k bones +0.0001 on average (-0.0027 ..
 * +0.0012), the bones within 0.0003; gates 0.1 and 0.3 (tested on the star as
 * it is at the visit) gave the same within the noise of the smallest angle
 * (tenths of a degree either way). */
#define SLIDE_NEWTON_GATE 0.2

/* One broad-sweep step of sliding surface vertex v: Newton in its tangent
 * plane ((P H P + I - P) d = -P g: the normal direction, where it may not go,
 * has unit curvature), over-relaxed and capped as an interior vertex's, put
 * back on the surface; taken, or half of it, under relax_vertex's rules (the
 * sum drops, no star tet inverts, the floor holds, the star's worst tet gets
 * no worse). 1 if v moved, 0 if it is converged, -1 if the descent must
 * decide (no Newton direction, no step taken). */
static int32_t slide_newton(const mesh_topo *tp, const slide_ctx *sl, double *x,
                            int32_t v, opt_metric m, double delta, double lbar,
                            double qfloor, int ks)
{
    double *xv = x + 3 * (size_t)v, g[3], H[6], A[6], pg[3], d[3], y[3], col[3][3];
    star_info si;
    star_out s0, s1;
    double f0 = star_hess(tp, x, v, xv, m, delta, 0.0, &si, g, H, &s0);

    if (!isfinite(f0))
        return -1;
    s0.bad = si.bad;
    slide_tangent(sl, v, g, pg);
    for (int j = 0; j < 3; j++) { /* column j of P H P + I - P */
        double e[3] = {0, 0, 0}, pe[3], hpe[3];
        e[j] = 1.0;
        slide_tangent(sl, v, e, pe);
        hpe[0] = H[0] * pe[0] + H[1] * pe[1] + H[2] * pe[2];
        hpe[1] = H[1] * pe[0] + H[3] * pe[1] + H[4] * pe[2];
        hpe[2] = H[2] * pe[0] + H[4] * pe[1] + H[5] * pe[2];
        slide_tangent(sl, v, hpe, col[j]);
        for (int c = 0; c < 3; c++)
            col[j][c] += e[c] - pe[c];
    }
    A[0] = col[0][0];
    A[1] = col[1][0];
    A[2] = col[2][0];
    A[3] = col[1][1];
    A[4] = col[2][1];
    A[5] = col[2][2];
    if (!newton_dir(A, pg, d))
        return -1;
    /* predicted decrease at rounding level: converged */
    if (!(-0.5 * (pg[0] * d[0] + pg[1] * d[1] + pg[2] * d[2]) > 1e-13 * f0))
        return 0;
    shape_step(d, 1, lbar);
    for (int h = 0; h < 2; h++) {
        double f1;
        trial_point(sl, v, xv, d, h ? 0.5 : 1.0, y);
        f1 = star_eval(tp, x, v, y, m, delta, s0.qmax, s0.kmax, qfloor > 0.0, &s1, NULL);
        if (f1 < f0 && s1.bad <= s0.bad && floor_kept(qfloor, s1.emin3, s0.emin3) &&
            surface_kept(tp, x, v, y, s1.bad, ks)) {
            memcpy(xv, y, sizeof y);
            return 1;
        }
    }
    return -1;
}

/* One finishing visit of v, whose star's smallest mean ratio was qstar when
 * the sweep began: Newton where the metric has a Hessian (in the broad
 * sweeps, one step; for a sliding surface vertex, in its tangent plane if
 * qstar is at least the gate), else the normalized-gradient descent. */
static int32_t visit_vertex(const mesh_topo *tp, const slide_ctx *sl, double *x,
                            int32_t v, double qstar, opt_metric m, double delta,
                            double lbar, double rtol, double qfloor, int ks)
{
    int inner = rtol > 0.0 ? 1 : FINISH_INNER;

    if (m == OPT_METRIC_MICN)
        return relax_vertex(tp, sl, x, v, m, delta, lbar, rtol, qfloor, ks);
    if (!(sl && slide_kind(sl, v) != SLIDE_INTERIOR))
        return newton_vertex(tp, x, v, m, delta, lbar, rtol, inner, qfloor, ks);
    if (rtol > 0.0 && qstar >= SLIDE_NEWTON_GATE && slide_kind(sl, v) == SLIDE_SURFACE) {
        int32_t n = slide_newton(tp, sl, x, v, m, delta, lbar, qfloor, ks);
        if (n >= 0)
            return n;
    }
    return relax_vertex(tp, sl, x, v, m, delta, lbar, rtol, qfloor, ks);
}

#define COLOUR_SHARED 64 /* the class of vertices that found no free colour */
#define COLOUR_NONE                                                                      \
    255 /* not in the list: a byte a vertex keeps the scratch in                         \
         * cache (int32 colours: the colouring was 10% of a                              \
         * broad sweep at 800k tets) */

#define CLASS_RANGES 16 /* ranges of vertices placed by one thread each */

/* Greedy colouring of the visit list (worst first): no two vertices of a class
 * share an edge, hence no tet, so a class can move in parallel. colour[] is
 * scratch of nv entries; returns the number of classes and fills start[]. */
static int32_t colour_classes(const mesh_topo *tp, vq_pair *list, int32_t n,
                              uint8_t *colour, int32_t **start_out)
{
    int32_t ncol = 0, *cnt, *start, rc[CLASS_RANGES][COLOUR_SHARED + 1];
    uint64_t used;
    vq_pair *tmp;

    /* every vertex, not only the listed ones: a stale entry of a neighbour
     * outside the list would block colours at random and make the result
     * depend on the heap's contents (found by the angle-polish unit test) */
    memset(colour, COLOUR_NONE, (size_t)tp->nv);
    for (int32_t i = 0; i < n; i++) {
        int32_t v = list[i].v, c = 0;
        /* the list is worst first, so v jumps through memory: its adjacency
         * is fetched some visits ahead (the colouring of a broad sweep of a
         * 1.26M-tet ball 0.033 -> 0.014 s) */
        if (i + 16 < n)
            QDC_PREFETCH(&tp->adj_ptr[list[i + 16].v]);
        if (i + 8 < n) {
            QDC_PREFETCH(&tp->adj_idx[tp->adj_ptr[list[i + 8].v]]);
            QDC_PREFETCH(&colour[list[i + 8].v]);
        }
        used = 0;
        for (int32_t k = tp->adj_ptr[v]; k < tp->adj_ptr[v + 1]; k++) {
            int32_t u = tp->adj_idx[k];
            if (u != v && colour[u] < 64)
                used |= 1ULL << colour[u];
        }
        while (c < 64 && (used >> c & 1))
            c++;
        /* 64 only where a vertex has neighbours of all 64 colours: that class
         * is not independent and is swept in one thread (COLOUR_SHARED) */
        colour[v] = c;
    }
    /* the classes' places: counted per range of vertices, in parallel */
    cnt = qdc_calloc(COLOUR_SHARED + 2, sizeof(int32_t));
    tmp = qdc_mallocn((size_t)n + 1, sizeof *tmp);
    if (!cnt || !tmp) {
        qdc_free(cnt);
        qdc_free(tmp);
        return -1;
    }
    memset(rc, 0, sizeof rc);
#pragma omp parallel for schedule(static)
    for (int r = 0; r < CLASS_RANGES; r++)
        for (int32_t v = qdc_part(tp->nv, r, CLASS_RANGES);
             v < qdc_part(tp->nv, r + 1, CLASS_RANGES); v++)
            if (colour[v] != COLOUR_NONE)
                rc[r][colour[v]]++;
    for (int c = 0; c <= COLOUR_SHARED; c++)
        for (int r = 0; r < CLASS_RANGES; r++) {
            int32_t k = rc[r][c];
            rc[r][c] = cnt[c + 1];
            cnt[c + 1] += k;
            ncol = k > 0 && c + 1 > ncol ? c + 1 : ncol;
        }
    for (int c = 0; c <= COLOUR_SHARED; c++) {
        for (int r = 0; r < CLASS_RANGES; r++)
            rc[r][c] += cnt[c];
        cnt[c + 1] += cnt[c];
    }
    start = cnt;
    /* an independent class in vertex order: the order of its visits changes
     * nothing, and vertex order is memory order (the vertices follow a
     * space-filling curve): a broad sweep of a 5M-tet mesh took 4.0 s with
     * each class worst first. The shared class, swept in order, stays worst
     * first. */
#pragma omp parallel for schedule(static)
    for (int r = 0; r < CLASS_RANGES; r++)
        for (int32_t v = qdc_part(tp->nv, r, CLASS_RANGES);
             v < qdc_part(tp->nv, r + 1, CLASS_RANGES); v++)
            if (colour[v] < COLOUR_SHARED) {
                tmp[rc[r][colour[v]]].q = 0.0;
                tmp[rc[r][colour[v]]++].v = v;
            }
    if (cnt[COLOUR_SHARED + 1] > cnt[COLOUR_SHARED])
        for (int32_t i = 0, p = cnt[COLOUR_SHARED]; i < n; i++)
            if (colour[list[i].v] == COLOUR_SHARED)
                tmp[p++] = list[i];
    memcpy(list, tmp, (size_t)n * sizeof *list);
    qdc_free(tmp);
    *start_out = start;
    return ncol;
}

qdc_status finish_sweep(const mesh_topo *tp, const uint8_t *movable, const slide_ctx *sl,
                        double *x, opt_metric m, const double *eta, double delta,
                        double lbar, double frac, double rtol, int keep_surface,
                        finish_stats *st)
{
    double *vworst = qdc_mallocn((size_t)tp->nv, sizeof(double));
    vq_pair *list = NULL;
    int32_t n = 0, k;
    double thresh, qfloor;

    memset(st, 0, sizeof *st);
    if (!vworst)
        return QDC_ENOMEM;
    k = (int32_t)(frac * tp->nt);
    if (k < 1)
        k = 1;
    if (k > tp->nt)
        k = tp->nt;
    /* the smallest and the largest by one parallel scan (the largest is the
     * threshold of a broad sweep, over every tet), the k-th smallest only when
     * it is needed */
    qfloor = INFINITY; /* > 0 only on a valid mesh */
    thresh = -INFINITY;
#pragma omp parallel for reduction(min : qfloor) reduction(max : thresh) schedule(static)
    for (int32_t t = 0; t < tp->nt; t++) {
        qfloor = eta[t] < qfloor ? eta[t] : qfloor;
        thresh = eta[t] > thresh ? eta[t] : thresh;
    }
    if (k < tp->nt &&
        kth_smallest_of(eta, tp->nt, k - 1, qfloor, thresh, &thresh, NULL) != QDC_OK) {
        qdc_free(vworst);
        return QDC_ENOMEM;
    }
    st->delta = delta;
    /* each vertex's worst listed tet (in parallel, per vertex: a min) */
#pragma omp parallel for schedule(static)
    for (int32_t v = 0; v < tp->nv; v++) {
        double w = 2.0;
        for (int32_t kk = tp->vt_ptr[v]; kk < tp->vt_ptr[v + 1]; kk++) {
            double e = eta[tp->vt_idx[kk] >> 2];
            if ((e <= thresh || e <= 0.0) && e < w)
                w = e;
        }
        vworst[v] = w;
    }
    for (int32_t v = 0; v < tp->nv; v++)
        n += movable[v] && vworst[v] < 2.0;
    list = qdc_mallocn((size_t)n + 1, sizeof *list);
    if (!list) {
        qdc_free(vworst);
        return QDC_ENOMEM;
    }
    n = 0;
    for (int32_t v = 0; v < tp->nv; v++)
        if (movable[v] && vworst[v] < 2.0) {
            list[n].q = vworst[v];
            list[n].v = v;
            n++;
        }
    /* worst first into the colouring; classes in turn (Gauss-Seidel), the
     * vertices of a class at once (independent stars) */
    {
        int32_t *start = NULL, ncol = -1;
        uint8_t *colour = qdc_mallocn((size_t)tp->nv + 1, 1);
        if (colour && vq_sort(list, n))
            ncol = colour_classes(tp, list, n, colour, &start);
        qdc_free(colour);
        if (ncol < 0) {
            qdc_free(list);
            qdc_free(vworst);
            return QDC_ENOMEM;
        }
        for (int32_t c = 0; c < ncol; c++) {
            int32_t moves = 0;
#pragma omp parallel for reduction(+ : moves) schedule(dynamic, 16) if (c < COLOUR_SHARED)
            for (int32_t i = start[c]; i < start[c + 1]; i++)
                moves += visit_vertex(tp, sl, x, list[i].v, vworst[list[i].v], m, delta,
                                      lbar, rtol, qfloor, keep_surface);
            st->n_moves += moves;
        }
        qdc_free(start);
    }
    st->n_verts = n;
    qdc_free(list);
    qdc_free(vworst);
    return QDC_OK;
}

/* ---- worst-angle polish: max-min of dihedral sines (Freitag's non-smooth
 * smoothing, as in Stellar) ---- */

#define DIH_ACTIVE 1e-3 /* functions within this of the minimum are active */
#define DIH_MAXACT 8
#define DIH_INNER 10
/* A move may lower the star's smallest mean ratio (down to the floor) where
 * the star holds one of the mesh's worst angles, its smallest sine within 10%
 * of the mesh's: measured on the 21 dev meshes and the 100k corpus (28 runs),
 * the smallest dihedral +0.95 degrees on average (up to +4.5), the mean ratio
 * -0.0005; elsewhere the star's smallest mean ratio may not drop (relaxed
 * everywhere: the same angles, -0.0006). */
#define DIH_RELAX 1.1
/* a sweep lifts the tets below min(1% quantile, 1.25 x the smallest sine):
 * raising the floor step by step costs the neighbours little (measured on the
 * good dev meshes: -0.0006 mean against -0.002 when every star of the worst
 * 1% goes to its own optimum, same smallest angle) */
#define LEVEL_MULT 1.25
/* ... but at least up to sin 3 degrees: from a near-zero floor, steps of 1.25x
 * never get anywhere (measured on bone-lowq at 100k tets: 6e-5 degrees became
 * 1.3e-3 with this floor, 6e-5 without) */
#define DIH_LEVEL_MIN 0.0523

typedef struct {
    int32_t k; /* position in v's star (vt_idx) */
    int e;     /* edge 0..5 */
} dih_fn;

/* Function (k, e) of value f into the active list act[0..*n) (values av[],
 * sorted, at most cap: a larger value than the last of a full list stays out). */
static void act_insert(dih_fn *act, double *av, int *n, int cap, double f, int32_t k,
                       int e)
{
    int i;

    if (*n == cap && f >= av[*n - 1])
        return;
    i = *n < cap ? (*n)++ : *n - 1;
    while (i > 0 && av[i - 1] > f) {
        av[i] = av[i - 1];
        act[i] = act[i - 1];
        i--;
    }
    av[i] = f;
    act[i].k = k;
    act[i].e = e;
}

/* Corners of star tet k of v with v placed at y; returns v's corner index. */
static int star_tet(const mesh_topo *tp, const double *x, int32_t k, const double *y,
                    double p[4][3])
{
    int32_t t = tp->vt_idx[k] >> 2;
    int a = tp->vt_idx[k] & 3;

    for (int b = 0; b < 4; b++)
        memcpy(p[b], b == a ? y : x + 3 * (size_t)tp->tets[4 * (size_t)t + b],
               sizeof p[b]);
    return a;
}

/* Smallest dihedral sine of v's star with v at y, the cube of the smallest
 * mean ratio (*qmin) and, if act, the active functions (at most DIH_MAXACT, the
 * smallest). */
static double star_sines(const mesh_topo *tp, const double *x, int32_t v, const double *y,
                         double level, int *nbelow, double *qmin, dih_fn *act, int *nact)
{
    double smin = INFINITY, q = INFINITY;
    double av[DIH_MAXACT];
    int n = 0, below = 0;

    for (int pass = 0; pass < (act ? 2 : 1); pass++)
        for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
            double p[4][3], s[6], q3;
            star_tet(tp, x, k, y, p);
            q3 = metric_dihedral_sines_eta3(p[0], p[1], p[2], p[3], s);
            if (pass == 0) {
                double tmin = INFINITY;
                q = fmin(q, q3);
                for (int e = 0; e < 6; e++)
                    tmin = fmin(tmin, s[e]);
                smin = fmin(smin, tmin);
                below += tmin < level;
                continue;
            }
            for (int e = 0; e < 6; e++)
                if (s[e] <= smin + DIH_ACTIVE)
                    act_insert(act, av, &n, DIH_MAXACT, s[e], k, e);
        }
    if (nact)
        *nact = n;
    *nbelow = below;
    *qmin = q;
    return smin;
}

/* Gradient of one dihedral sine with respect to v's position (central
 * differences; h in x's units). */
static void sine_grad(const mesh_topo *tp, const double *x, const double *y, dih_fn f,
                      double h, double g[3])
{
    for (int c = 0; c < 3; c++) {
        double yp[3], p[4][3], sp[6], sm[6];
        memcpy(yp, y, sizeof yp);
        yp[c] = y[c] + h;
        star_tet(tp, x, f.k, yp, p);
        metric_dihedral_sines(p[0], p[1], p[2], p[3], sp);
        yp[c] = y[c] - h;
        star_tet(tp, x, f.k, yp, p);
        metric_dihedral_sines(p[0], p[1], p[2], p[3], sm);
        g[c] = (sp[f.e] - sm[f.e]) / (2.0 * h);
    }
}

/* Minimum-norm point d of the convex hull of g[0..n): the steepest ascent
 * direction of min_i f_i (every active f_i rises at rate >= |d|^2 along d).
 * In 3-D it lies on a face spanned by at most 3 points, so the candidates are
 * the points, the segments and the triangles. Returns 0 if the hull contains
 * the origin (no ascent direction). */
static int min_norm_point(double g[][3], int n, double d[3])
{
    double best = INFINITY, cand[3];

    for (int i = 0; i < n; i++)
        for (int j = i; j < n; j++)
            for (int k = j; k < n; k++) {
                double u[3], w[3], uu, uw, ww, gu, gw, a = 0, b = 0, nn;
                if ((j == i && k != i) || (k == j && j != i))
                    continue; /* subsets {i}, {i,j}, {i,j,k} only */
                for (int c = 0; c < 3; c++) {
                    u[c] = g[j][c] - g[i][c];
                    w[c] = g[k][c] - g[i][c];
                }
                uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
                ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
                uw = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
                gu = g[i][0] * u[0] + g[i][1] * u[1] + g[i][2] * u[2];
                gw = g[i][0] * w[0] + g[i][1] * w[1] + g[i][2] * w[2];
                if (j == i) {
                    a = b = 0;
                } else if (k == j) {
                    if (!(uu > 0))
                        continue;
                    a = -gu / uu;
                    if (!(a > 0 && a < 1))
                        continue;
                } else {
                    double det = uu * ww - uw * uw;
                    if (!(det > 1e-14 * uu * ww))
                        continue;
                    a = (-gu * ww + gw * uw) / det;
                    b = (-gw * uu + gu * uw) / det;
                    if (!(a > 0 && b > 0 && a + b < 1))
                        continue;
                }
                for (int c = 0; c < 3; c++)
                    cand[c] = g[i][c] + a * u[c] + b * w[c];
                nn = cand[0] * cand[0] + cand[1] * cand[1] + cand[2] * cand[2];
                if (nn < best) {
                    best = nn;
                    memcpy(d, cand, sizeof cand);
                }
            }
    if (!(best > 0) || !isfinite(best))
        return 0;
    /* optimality: every point sees d at least as far as d itself; else the
     * origin is inside the hull */
    for (int i = 0; i < n; i++)
        if (g[i][0] * d[0] + g[i][1] * d[1] + g[i][2] * d[2] < best * (1.0 - 1e-9))
            return 0;
    return 1;
}

/* The rules of an angle move from a star at (f0 smallest sine, nb0 tets
 * under the level, q0 smallest mean ratio cubed) to (f1, nb1, q1): the
 * smallest sine rises, no more tets under the level (a stricter rule, no tet
 * of the set getting worse, stalls: sphere_h0.1_good 13.1 against 16.0
 * degrees), no tet under the floor, and the star's smallest mean ratio does
 * not drop unless the star's smallest sine is under relax. */
static int sine_move_ok(double f0, int nb0, double q0, double f1, int nb1, double q1,
                        double relax, double qf3)
{
    return f1 > f0 && nb1 <= nb0 && (q1 >= q0 || f0 < relax) && q1 >= qf3;
}

/* Pattern moves (pattern_move): PATTERN_RAND hashed directions besides the
 * axes (measured on bone-scan, scripts/corpus.py at 100k tets, with stars
 * deep under 3 degrees and free to lower their smallest mean ratio: 8 such
 * directions lifted its smallest angle to 0.21 degrees, 2 to 0.18, none
 * 0.12; the run 1.02, 0.95 and 0.89 s) */
#define PATTERN_RAND 2
/* ... for the stars whose smallest sine is within PATTERN_BAND of the mesh's
 * (and deep): all deep stars gave the same smallest angles on the thin bones
 * at twice the time of the run (bone-scan, 100k tets: 1.9 against 0.9 s).
 * Deep was first under 3 degrees: on the 5M-tet ball (scripts/corpus.py),
 * whose worst angles sit near 3 degrees, that ended at 2.38 against 2.78
 * degrees and 46 s against 39 s (docs/method.md, section 5a) */
#define PATTERN_BAND 2.0
static uint64_t mix64(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static void pattern_dir(int32_t v, int it, int k, double d[3])
{
    if (k < 6) {
        d[0] = d[1] = d[2] = 0.0;
        d[k >> 1] = (k & 1) ? -1.0 : 1.0;
        return;
    }
    uint64_t z = mix64(((uint64_t)(uint32_t)v << 16) ^ ((uint64_t)it << 8) ^ (uint64_t)k);
    for (int c = 0; c < 3; c++) /* 21 bits each, in [-0.5, 0.5] */
        d[c] = (double)((z >> (21 * c)) & 0x1fffff) / 0x1fffff - 0.5;
}

/* Pattern moves of a deep star's vertex, tried where the ascent stops: at
 * flat tets with four corners on a curved surface (a thin bone's Delaunay
 * shells, scripts/corpus.py) the active sines balance each other (no ascent
 * direction) while a longer move still lifts them all. Directions: the 3
 * axes both ways and PATTERN_RAND more from a hash of the vertex and the
 * ascent step (runs repeat); steps 0.2, 0.05, 0.0125 mean edge, the largest
 * that lifts the star first, the best direction of it. f0, nb0, q0: the
 * star at v's position, as the ascent found it (star_sines). 1 if v moved. */
static int pattern_move(const mesh_topo *tp, const slide_ctx *sl, double *x, int32_t v,
                        int sliding, double lbar, double target, double relax, double qf3,
                        int it, double f0, int nb0, double q0)
{
    double *xv = x + 3 * (size_t)v, best[3], fb = f0;
    int found = 0;

    for (double sc = 0.2 * lbar; sc > 0.01 * lbar && !found; sc *= 0.25)
        for (int k = 0; k < 6 + PATTERN_RAND; k++) {
            double d[3], y[3], q1, f1, dn;
            int nb1;
            pattern_dir(v, it, k, d);
            dn = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (!(dn > 0.0))
                continue;
            trial_point(sliding ? sl : NULL, v, xv, d, sc / dn, y);
            f1 = star_sines(tp, x, v, y, target, &nb1, &q1, NULL, NULL);
            if (f1 > fb && sine_move_ok(f0, nb0, q0, f1, nb1, q1, relax, qf3)) {
                fb = f1;
                memcpy(best, y, sizeof best);
                found = 1;
            }
        }
    if (found)
        memcpy(xv, best, sizeof best);
    return found;
}

/* Max-min ascent of one vertex: raise the smallest dihedral sine of its star
 * under sine_move_ok's rules; where the ascent stops, a star whose smallest
 * sine is under pattern tries pattern moves. */
static int32_t dihedral_vertex(const mesh_topo *tp, const slide_ctx *sl, double *x,
                               int32_t v, double lbar, double qfloor, double target,
                               double relax, double pattern)
{
    int sliding = sl && slide_kind(sl, v) != SLIDE_INTERIOR;
    double *xv = x + 3 * (size_t)v, s = 0.02 * lbar, h = 1e-6 * lbar;
    const double qf3 = floor_cubed(qfloor); /* star_sines gives cubes */
    int32_t moves = 0;

    for (int it = 0; it < DIH_INNER; it++) {
        dih_fn act[DIH_MAXACT];
        double g[DIH_MAXACT][3], d[3], dn, y[3], q0, q1, f0, f1;
        int nact = 0, ok = 0, nb0, nb1;
        f0 = star_sines(tp, x, v, xv, target, &nb0, &q0, act, &nact);
        if (!(f0 > 0.0) || nact == 0 || f0 >= target)
            break; /* inverted stars are the smooth pass's job */
        for (int i = 0; i < nact; i++) {
            sine_grad(tp, x, xv, act[i], h, g[i]);
            if (sliding) {
                double gt[3];
                slide_tangent(sl, v, g[i], gt);
                memcpy(g[i], gt, sizeof gt);
            }
        }
        if (min_norm_point(g, nact, d)) {
            dn = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (int hv = 0; hv < FINISH_HALVINGS; hv++) {
                trial_point(sliding ? sl : NULL, v, xv, d, s / dn, y);
                f1 = star_sines(tp, x, v, y, target, &nb1, &q1, NULL, NULL);
                if (sine_move_ok(f0, nb0, q0, f1, nb1, q1, relax, qf3)) {
                    ok = 1;
                    break;
                }
                s *= 0.5;
            }
        }
        if (!ok) {
            if (f0 < pattern && pattern_move(tp, sl, x, v, sliding, lbar, target, relax,
                                             qf3, it, f0, nb0, q0)) {
                moves++;
                s = 0.02 * lbar;
                continue;
            }
            break;
        }
        memcpy(xv, y, sizeof y);
        moves++;
        s = fmin(s * 1.6, 0.1 * lbar);
        if (f1 - f0 < 1e-5)
            break;
    }
    return moves;
}

/* The smallest dihedral sine of tet t at x. */
static double tet_min_sine(const mesh_topo *tp, const double *x, int32_t t)
{
    const int32_t *tt = tp->tets + 4 * (size_t)t;
    double s[6], m = INFINITY;

    metric_dihedral_sines(x + 3 * (size_t)tt[0], x + 3 * (size_t)tt[1],
                          x + 3 * (size_t)tt[2], x + 3 * (size_t)tt[3], s);
    for (int e = 0; e < 6; e++)
        m = fmin(m, s[e]);
    return m;
}

static void fresh_sines(const mesh_topo *tp, const double *x, double *smin)
{
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < tp->nt; t++)
        smin[t] = tet_min_sine(tp, x, t);
}

/* Smallest dihedral sine of every tet into smin[] (if fresh; else smin[] is
 * up to date); *mean: the mean of the k smallest (the sweep's score), *kth:
 * the k-th smallest, *lo: the smallest. QDC_ENOMEM if out of memory. */
static qdc_status tet_sines(const mesh_topo *tp, const double *x, double *smin, int fresh,
                            int32_t k, double *kth, double *lo, double *mean)
{
    double low = INFINITY, hi = -INFINITY, sum = 0.0;
    qdc_status st;

    if (fresh)
        fresh_sines(tp, x, smin);
#pragma omp parallel for schedule(static) reduction(min : low) reduction(max : hi)
    for (int32_t t = 0; t < tp->nt; t++) {
        low = smin[t] < low ? smin[t] : low;
        hi = smin[t] > hi ? smin[t] : hi;
    }
    *lo = low;
    st = kth_smallest_of(smin, tp->nt, k - 1, low, hi, kth, &sum);
    *mean = sum / k;
    return st;
}

qdc_status finish_dihedral_sweep(const mesh_topo *tp, const uint8_t *movable,
                                 const slide_ctx *sl, double *x, double lbar, double frac,
                                 double qfloor, double *smin, int smin_valid,
                                 finish_stats *st)
{
    double *vworst = qdc_mallocn((size_t)tp->nv, sizeof(double));
    uint8_t *colour = qdc_mallocn((size_t)tp->nv + 1, 1);
    int32_t *start = NULL, n = 0, k, ncol;
    vq_pair *list = NULL;
    double thresh, dummy, pattern;
    qdc_status st_ = QDC_ENOMEM;

    memset(st, 0, sizeof *st);
    if (!vworst || !colour)
        goto out;
    k = (int32_t)(frac * tp->nt);
    k = k < 1 ? 1 : (k > tp->nt ? tp->nt : k);
    if (tet_sines(tp, x, smin, !smin_valid, k, &thresh, &st->floor_before,
                  &st->score_before) != QDC_OK)
        goto out;
    if (st->floor_before > 0.0)
        thresh = fmin(thresh, fmax(LEVEL_MULT * st->floor_before, DIH_LEVEL_MIN));
    for (int32_t v = 0; v < tp->nv; v++)
        vworst[v] = 2.0;
    for (int32_t t = 0; t < tp->nt; t++)
        if (smin[t] <= thresh)
            for (int a = 0; a < 4; a++) {
                int32_t v = tp->tets[4 * (size_t)t + a];
                vworst[v] = fmin(vworst[v], smin[t]);
            }
    for (int32_t v = 0; v < tp->nv; v++)
        n += movable[v] && vworst[v] < 2.0;
    list = qdc_mallocn((size_t)n + 1, sizeof *list);
    if (!list)
        goto out;
    n = 0;
    for (int32_t v = 0; v < tp->nv; v++)
        if (movable[v] && vworst[v] < 2.0) {
            list[n].q = vworst[v];
            list[n].v = v;
            n++;
        }
    if (!vq_sort(list, n))
        goto out;
    ncol = colour_classes(tp, list, n, colour, &start);
    if (ncol < 0)
        goto out;
    /* pattern moves for the deep stars near the mesh's smallest sine
     * (PATTERN_BAND) */
    pattern = fmin(FINISH_DEEP_SINE, PATTERN_BAND * st->floor_before);
    /* a vertex stops once its star leaves the worst set (measured: moving it
     * further, to its own max-min optimum, costs the neighbours' mean ratio:
     * -0.005 against -0.002 mean on the good dev meshes, same smallest angle) */
    for (int32_t c = 0; c < ncol; c++) {
        int32_t moves = 0;
#pragma omp parallel for reduction(+ : moves) schedule(dynamic, 4) if (c < COLOUR_SHARED)
        for (int32_t i = start[c]; i < start[c + 1]; i++) {
            int32_t mv = dihedral_vertex(tp, sl, x, list[i].v, lbar, qfloor, thresh,
                                         DIH_RELAX * st->floor_before, pattern);
            list[i].q =
                mv > 0 ? -INFINITY : list[i].q; /* mark the moved (sines are >= -1) */
            moves += mv;
        }
        st->n_moves += moves;
    }
    st->n_verts = n;
    /* only the stars of the moved vertices changed */
    for (int32_t i = 0; i < n; i++) {
        int32_t v = list[i].v;
        if (list[i].q != -INFINITY)
            continue;
        for (int32_t kk = tp->vt_ptr[v]; kk < tp->vt_ptr[v + 1]; kk++)
            smin[tp->vt_idx[kk] >> 2] = tet_min_sine(tp, x, tp->vt_idx[kk] >> 2);
    }
    st_ = tet_sines(tp, x, smin, 0, k, &dummy, &st->floor_after, &st->score_after);
out:
    qdc_free(start);
    qdc_free(list);
    qdc_free(colour);
    qdc_free(vworst);
    return st_;
}

/* ---- joint moves of the worst tets' corners ----
 * One vertex at a time, the max-min ascent stops where the smallest sines of
 * a few neighbouring tets balance each other (measured on a 1M-tet ball: the
 * three worst tets, around one short boundary edge, at 5.1-5.2 degrees after
 * the sweeps). Moving the corners of a worst tet together is the same ascent
 * in up to 12 dimensions over the union of their stars. */
#define PATCH_TETS 32  /* the worst tets tried in a round */
#define PATCH_MAXT 384 /* tets of the corners' stars (larger: skipped) */
#define PATCH_ACT 16   /* active functions */
#define PATCH_INNER 8  /* ascent steps per tet */
#define PATCH_HALVINGS 12

typedef struct {
    int eta; /* the functions: 0 the tets' dihedral sines, 1 their mean ratios cubed */
    int nv;  /* movable corners */
    int32_t v[4];
    double y[4][3]; /* their positions */
    int32_t nt;     /* tets of their stars */
    int32_t t[PATCH_MAXT];
} patch_t;

static void patch_tet(const mesh_topo *tp, const double *x, const patch_t *pc,
                      const double (*y)[3], int32_t t, double p[4][3])
{
    const int32_t *tt = tp->tets + 4 * (size_t)t;

    for (int b = 0; b < 4; b++) {
        const double *src = x + 3 * (size_t)tt[b];
        for (int j = 0; j < pc->nv; j++)
            if (tt[b] == pc->v[j])
                src = y[j];
        memcpy(p[b], src, sizeof p[b]);
    }
}

/* The functions of tet i of the patch with its corners at y into f[] (6
 * sines, or the mean ratio cubed once); returns how many, and its mean ratio
 * cubed in *q3. */
static int patch_fns(const mesh_topo *tp, const double *x, const patch_t *pc,
                     const double (*y)[3], int32_t i, double f[6], double *q3)
{
    double p[4][3];

    patch_tet(tp, x, pc, y, pc->t[i], p);
    *q3 = metric_dihedral_sines_eta3(p[0], p[1], p[2], p[3], f);
    if (!pc->eta)
        return 6;
    f[0] = *q3;
    return 1;
}

/* Smallest function value over the patch's tets with its corners at y; the
 * tets with a value below level (*nbelow) and the active functions (within
 * DIH_ACTIVE of the smallest, or 1% of it for mean ratios; k: position in
 * pc->t). */
static double patch_values(const mesh_topo *tp, const double *x, const patch_t *pc,
                           const double (*y)[3], double level, int *nbelow, dih_fn *act,
                           int *nact)
{
    double fmin_ = INFINITY, fv[PATCH_MAXT][6], av[PATCH_ACT], tol;
    int below = 0, n = 0, nf = 6;

    for (int32_t i = 0; i < pc->nt; i++) {
        double tmin = INFINITY, q3;
        nf = patch_fns(tp, x, pc, y, i, fv[i], &q3);
        for (int e = 0; e < nf; e++)
            tmin = fmin(tmin, fv[i][e]);
        fmin_ = fmin(fmin_, tmin);
        below += tmin < level;
    }
    tol = pc->eta ? 0.01 * fabs(fmin_) : DIH_ACTIVE;
    /* the smallest PATCH_ACT active functions, sorted */
    for (int32_t i = 0; i < pc->nt; i++)
        for (int e = 0; e < nf; e++)
            if (fv[i][e] <= fmin_ + tol)
                act_insert(act, av, &n, PATCH_ACT, fv[i][e], i, e);
    *nact = n;
    *nbelow = below;
    return fmin_;
}

/* 1 if the patch with its corners at y keeps the ascent's rules: every tet's
 * smallest value above f0 (into *f1, the smallest), no more of them below level
 * than nb0, no mean ratio cubed under qcap. The active functions' tets are
 * tried first and the scan stops at the first tet that breaks a rule: most
 * trials fail there (a full scan per trial was most of the angle pass on 20k-tet
 * meshes). */
static int patch_trial_ok(const mesh_topo *tp, const double *x, const patch_t *pc,
                          const double (*y)[3], double f0, int nb0, double qcap,
                          double level, const dih_fn *act, int nact, double *f1)
{
    double lo = INFINITY;
    int below = 0;

    for (int pass = 0; pass < 2; pass++)
        for (int32_t i = 0; i < (pass ? pc->nt : nact); i++) {
            int32_t k = pass ? i : act[i].k;
            double f[6], q3, tmin = INFINITY;
            int nf, first = 1;
            for (int a = 0; a < i && !pass && first; a++)
                first = act[a].k != k;
            if (!first)
                continue; /* that tet was tried already */
            nf = patch_fns(tp, x, pc, y, k, f, &q3);
            for (int e = 0; e < nf; e++)
                tmin = fmin(tmin, f[e]);
            if (!(tmin > f0) || q3 < qcap)
                return 0;
            if (pass) {
                below += tmin < level;
                if (below > nb0)
                    return 0;
                lo = fmin(lo, tmin);
            }
        }
    *f1 = lo;
    return 1;
}

/* Euclidean projection of l[0..m) onto the unit simplex. */
static void simplex_project(double *l, int m)
{
    double u[PATCH_ACT], run = 0.0, theta = 0.0;

    memcpy(u, l, (size_t)m * sizeof *u);
    for (int i = 1; i < m; i++) /* descending */
        for (int j = i; j > 0 && u[j] > u[j - 1]; j--) {
            double t = u[j];
            u[j] = u[j - 1];
            u[j - 1] = t;
        }
    for (int i = 0; i < m; i++) {
        run += u[i];
        if (u[i] - (run - 1.0) / (i + 1) > 0.0)
            theta = (run - 1.0) / (i + 1);
    }
    for (int i = 0; i < m; i++)
        l[i] = fmax(l[i] - theta, 0.0);
}

/* An ascent direction d (dim entries) for min_i f_i from the gradients g[0..m):
 * the minimum-norm point of their convex hull, by projected gradient on the
 * simplex of weights (m <= 16: a few hundred cheap steps). 0 if no direction
 * raises every active function. */
static int patch_direction(double g[][12], int m, int dim, double d[12])
{
    double G[PATCH_ACT][PATCH_ACT], l[PATCH_ACT], L = 0.0, dd = 0.0;

    for (int i = 0; i < m; i++) {
        double row = 0.0;
        for (int j = 0; j < m; j++) {
            G[i][j] = 0.0;
            for (int c = 0; c < dim; c++)
                G[i][j] += g[i][c] * g[j][c];
            row += fabs(G[i][j]);
        }
        L = fmax(L, row);
        l[i] = 1.0 / m;
    }
    if (!(L > 0.0) || !isfinite(L))
        return 0;
    for (int it = 0; it < 100 && m > 1; it++) {
        double gl[PATCH_ACT], prev[PATCH_ACT], change = 0.0;
        memcpy(prev, l, (size_t)m * sizeof *l);
        for (int i = 0; i < m; i++) {
            gl[i] = 0.0;
            for (int j = 0; j < m; j++)
                gl[i] += G[i][j] * l[j];
        }
        for (int i = 0; i < m; i++)
            l[i] -= gl[i] / L;
        simplex_project(l, m);
        for (int i = 0; i < m; i++)
            change = fmax(change, fabs(l[i] - prev[i]));
        if (change < 1e-6) /* the weights have settled */
            break;
    }
    for (int c = 0; c < dim; c++) {
        d[c] = 0.0;
        for (int i = 0; i < m; i++)
            d[c] += l[i] * g[i][c];
        dd += d[c] * d[c];
    }
    if (!(dd > 0.0) || !isfinite(dd))
        return 0;
    for (int i = 0; i < m; i++) {
        double gd = 0.0;
        for (int c = 0; c < dim; c++)
            gd += g[i][c] * d[c];
        if (!(gd > 0.0))
            return 0;
    }
    return 1;
}

/* The patch of tet t: its movable corners and the tets of their stars; 0 if
 * none moves or the stars are too many. */
static int patch_of(const mesh_topo *tp, const uint8_t *movable, const double *x,
                    int32_t t, patch_t *pc)
{
    pc->nv = pc->nt = 0;
    for (int b = 0; b < 4; b++) {
        int32_t v = tp->tets[4 * (size_t)t + b];
        if (!movable[v])
            continue;
        pc->v[pc->nv] = v;
        memcpy(pc->y[pc->nv++], x + 3 * (size_t)v, 3 * sizeof(double));
        for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
            int32_t s = tp->vt_idx[k] >> 2, dup = 0;
            for (int32_t i = 0; i < pc->nt && !dup; i++)
                dup = pc->t[i] == s;
            if (dup)
                continue;
            if (pc->nt == PATCH_MAXT)
                return 0;
            pc->t[pc->nt++] = s;
        }
    }
    return pc->nv > 0;
}

/* Max-min ascent of a patch's corners together (dihedral_vertex's rules over
 * the union of their stars; for mean ratios, without the floor); the moves are
 * written to x. */
static int32_t patch_ascent(const mesh_topo *tp, const slide_ctx *sl, double *x,
                            patch_t *pc, double lbar, double qfloor, double level)
{
    const double qf3 = floor_cubed(qfloor), h = 1e-6 * lbar;
    double s = 0.02 * lbar;
    int32_t moves = 0;
    int dim = 3 * pc->nv;

    for (int it = 0; it < PATCH_INNER; it++) {
        dih_fn act[PATCH_ACT];
        double g[PATCH_ACT][12], d[12], dn = 0.0, y[4][3], f0, f1 = 0.0;
        int nact = 0, ok = 0, nb0;
        f0 = patch_values(tp, x, pc, (const double(*)[3])pc->y, level, &nb0, act, &nact);
        if (!(f0 > 0.0) || nact == 0)
            break;
        for (int i = 0; i < nact; i++) {
            int32_t t = pc->t[act[i].k];
            for (int j = 0; j < pc->nv; j++) {
                double *gj = g[i] + 3 * j;
                int in = 0;
                for (int b = 0; b < 4; b++)
                    in |= tp->tets[4 * (size_t)t + b] == pc->v[j];
                gj[0] = gj[1] = gj[2] = 0.0;
                if (!in)
                    continue;
                for (int c = 0; c < 3; c++) {
                    double yy[4][3], fp[6], fm[6], q3;
                    memcpy(yy, pc->y, sizeof yy);
                    yy[j][c] += h;
                    patch_fns(tp, x, pc, (const double(*)[3])yy, act[i].k, fp, &q3);
                    yy[j][c] -= 2.0 * h;
                    patch_fns(tp, x, pc, (const double(*)[3])yy, act[i].k, fm, &q3);
                    gj[c] = (fp[act[i].e] - fm[act[i].e]) / (2.0 * h);
                }
                if (sl && slide_kind(sl, pc->v[j]) != SLIDE_INTERIOR) {
                    double gt[3];
                    slide_tangent(sl, pc->v[j], gj, gt);
                    memcpy(gj, gt, sizeof gt);
                }
            }
        }
        if (!patch_direction(g, nact, dim, d))
            break;
        for (int c = 0; c < dim; c++)
            dn += d[c] * d[c];
        dn = sqrt(dn);
        for (int hv = 0; hv < PATCH_HALVINGS; hv++) {
            for (int j = 0; j < pc->nv; j++) {
                int sliding = sl && slide_kind(sl, pc->v[j]) != SLIDE_INTERIOR;
                trial_point(sliding ? sl : NULL, pc->v[j], pc->y[j], d + 3 * j, s / dn,
                            y[j]);
            }
            if (patch_trial_ok(tp, x, pc, (const double(*)[3])y, f0, nb0,
                               pc->eta ? GEOM_FLAT_ETA3 : qf3, level, act, nact, &f1)) {
                ok = 1;
                break;
            }
            s *= 0.5;
        }
        if (!ok)
            break;
        memcpy(pc->y, y, sizeof y);
        moves++;
        s = fmin(s * 1.6, 0.1 * lbar);
        if (f1 - f0 < (pc->eta ? 1e-5 * f0 : 1e-6))
            break;
    }
    for (int j = 0; moves && j < pc->nv; j++)
        memcpy(x + 3 * (size_t)pc->v[j], pc->y[j], 3 * sizeof(double));
    return moves;
}

/* (value, tet) pairs by value, ties by tet. */
static int vq_cmp(const void *a, const void *b)
{
    const vq_pair *p = a, *q = b;
    return p->q < q->q ? -1 : p->q > q->q ? 1 : (p->v > q->v) - (p->v < q->v);
}

/* The PATCH_TETS tets of smallest smin (fewer if the mesh has fewer), sorted,
 * ties by index: each of 16 ranges of tets keeps its own smallest, in
 * parallel, then the 16 lists are sorted together. Returns how many. */
#define WORST_RANGES 16
static int32_t worst_tets(const double *smin, int32_t nt, vq_pair *out)
{
    vq_pair cand[WORST_RANGES][PATCH_TETS], all[WORST_RANGES * PATCH_TETS];
    int32_t nc[WORST_RANGES], n = 0;

#pragma omp parallel for schedule(static)
    for (int r = 0; r < WORST_RANGES; r++) {
        vq_pair *c = cand[r];
        int32_t m = 0;
        for (int32_t t = qdc_part(nt, r, WORST_RANGES);
             t < qdc_part(nt, r + 1, WORST_RANGES); t++) {
            vq_pair p = {smin[t], t};
            int32_t j;
            if (m == PATCH_TETS && !(p.q < c[m - 1].q))
                continue; /* t is larger than the last: ties keep the lower index */
            j = m < PATCH_TETS ? m++ : m - 1;
            while (j > 0 && vq_cmp(&c[j - 1], &p) > 0) {
                c[j] = c[j - 1];
                j--;
            }
            c[j] = p;
        }
        nc[r] = m;
    }
    for (int r = 0; r < WORST_RANGES; r++)
        for (int32_t j = 0; j < nc[r]; j++)
            all[n++] = cand[r][j];
    qsort(all, (size_t)n, sizeof *all, vq_cmp);
    n = n < PATCH_TETS ? n : PATCH_TETS;
    memcpy(out, all, (size_t)n * sizeof *out);
    return n;
}

static double mean_q(const vq_pair *p, int32_t n)
{
    double s = 0.0;

    for (int32_t i = 0; i < n; i++)
        s += p[i].q;
    return n > 0 ? s / n : 0.0;
}

/* The mean ratio of tet t at x, as the driver's scans compute it. */
static double tet_eta(const mesh_topo *tp, const double *x, int32_t t)
{
    const int32_t *tt = tp->tets + 4 * (size_t)t;
    metric_parts pt;

    metric_parts_for(OPT_METRIC_MIVL, x + 3 * (size_t)tt[0], x + 3 * (size_t)tt[1],
                     x + 3 * (size_t)tt[2], x + 3 * (size_t)tt[3], &pt);
    return metric_mean_ratio(&pt);
}

qdc_status finish_patches(const mesh_topo *tp, const uint8_t *movable,
                          const slide_ctx *sl, double *x, double lbar,
                          finish_patch_kind kind, double qfloor, double *val,
                          int val_valid, finish_stats *st)
{
    vq_pair worst[PATCH_TETS];
    patch_t *pc = qdc_malloc(sizeof *pc);
    int eta = kind == FINISH_PATCH_MEAN_RATIO;
    double level;
    int32_t n;

    memset(st, 0, sizeof *st);
    if (!pc)
        return QDC_ENOMEM;
    if (!val_valid && eta) {
#pragma omp parallel for schedule(static)
        for (int32_t t = 0; t < tp->nt; t++)
            val[t] = tet_eta(tp, x, t);
    } else if (!val_valid) {
        fresh_sines(tp, x, val);
    }
    n = worst_tets(val, tp->nt, worst);
    st->floor_before = n > 0 ? worst[0].q : INFINITY;
    st->score_before = mean_q(worst, n);
    level = n > 0 ? worst[n - 1].q : 0.0;
    if (eta) /* the ascent compares mean ratios cubed */
        level = level * level * level;
    /* worst first, one patch after the other (they share vertices); the
     * values of a moved patch's tets are brought up to date */
    for (int32_t i = 0; i < n; i++) {
        int32_t moves;
        if (!patch_of(tp, movable, x, worst[i].v, pc))
            continue;
        pc->eta = eta;
        st->n_verts += pc->nv;
        moves = patch_ascent(tp, sl, x, pc, lbar, qfloor, level);
        st->n_moves += moves;
        for (int32_t j = 0; moves && j < pc->nt; j++)
            val[pc->t[j]] =
                eta ? tet_eta(tp, x, pc->t[j]) : tet_min_sine(tp, x, pc->t[j]);
    }
    n = worst_tets(val, tp->nt, worst);
    st->floor_after = n > 0 ? worst[0].q : INFINITY;
    st->score_after = mean_q(worst, n);
    qdc_free(pc);
    return QDC_OK;
}

/* ---- untangling by max-min volume (Freitag & Plassmann) ---- */

#define UNTANGLE_INNER 40
#define UNTANGLE_SWEEPS 12
#define UNTANGLE_ACT 16

/* Smallest 6 x volume over v's star with v at y, and its inverted or
 * degenerate tets. */
static double star_min_vol6(const mesh_topo *tp, const double *x, int32_t v,
                            const double *y, int32_t *bad)
{
    double m = INFINITY;

    *bad = 0;
    for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
        double l2, w = star_vol6(tp, x, k, y, NULL, &l2);
        *bad += geom_tet_bad_vl(w, l2);
        m = w < m ? w : m;
    }
    return m;
}

/* Max-min ascent of the star's signed volumes for one interior vertex (valid
 * stars too: their tets open room for the inverted ones). The direction is
 * the minimum-norm point of the hull of the gradients of the volumes that a
 * step of length s could make the smallest (within s |g| of it); a step is
 * taken when the smallest volume rises and the star gains no inverted tet. */
static int32_t untangle_vertex(const mesh_topo *tp, double *x, int32_t v, double lbar)
{
    double *xv = x + 3 * (size_t)v, s = 0.1 * lbar;
    int32_t moves = 0;

    for (int it = 0; it < UNTANGLE_INNER && s > 1e-6 * lbar; it++) {
        double g[UNTANGLE_ACT][3], d[3], dn, y[3], f0, f1 = 0.0, w[UNTANGLE_ACT],
                                                       gmax = 0;
        int32_t nb0, nb1;
        int nact = 0;
        f0 = INFINITY;
        nb0 = 0;
        for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
            double gk[3], l2, vk = star_vol6(tp, x, k, xv, gk, &l2);
            f0 = fmin(f0, vk);
            nb0 += geom_tet_bad_vl(vk, l2);
            gmax = fmax(gmax, sqrt(gk[0] * gk[0] + gk[1] * gk[1] + gk[2] * gk[2]));
        }
        if (!isfinite(f0))
            break;
        for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
            double gk[3], vk = star_vol6(tp, x, k, xv, gk, NULL);
            if (vk - f0 > 2.0 * s * gmax)
                continue;
            if (nact < UNTANGLE_ACT) {
                memcpy(g[nact], gk, sizeof gk);
                w[nact++] = vk;
            } else { /* keep the UNTANGLE_ACT smallest */
                int j = 0;
                for (int i = 1; i < nact; i++)
                    j = w[i] > w[j] ? i : j;
                if (vk < w[j]) {
                    memcpy(g[j], gk, sizeof gk);
                    w[j] = vk;
                }
            }
        }
        if (!nact || !min_norm_point(g, nact, d)) {
            s *= 0.5;
            continue;
        }
        dn = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (!(dn > 1e-12 * gmax) || !isfinite(dn)) {
            s *= 0.5; /* a corner at this scale: look closer */
            continue;
        }
        trial_point(NULL, v, xv, d, s / dn, y);
        f1 = star_min_vol6(tp, x, v, y, &nb1);
        if (!(f1 > f0 && nb1 <= nb0)) {
            s *= 0.5;
            continue;
        }
        memcpy(xv, y, sizeof y);
        moves++;
        s = fmin(s * 1.5, 0.3 * lbar);
    }
    return moves;
}

qdc_status finish_untangle(const mesh_topo *tp, const uint8_t *movable, double *x,
                           double lbar, int32_t *n_inverted)
{
    uint8_t *mark = qdc_calloc((size_t)tp->nv + 1, 1);
    int32_t *list = NULL, n = 0;

    if (!mark)
        return QDC_ENOMEM;
    /* the interior vertices of the inverted (or flat) tets and of the tets
     * around them */
    for (int32_t t = 0; t < tp->nt; t++)
        if (geom_tet_bad(x, tp->tets + 4 * (size_t)t))
            for (int a = 0; a < 4; a++)
                mark[tp->tets[4 * (size_t)t + a]] = 1;
    for (int32_t v = 0; v < tp->nv; v++)
        if (mark[v] & 1)
            for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
                const int32_t *tt = tp->tets + 4 * (size_t)(tp->vt_idx[k] >> 2);
                for (int a = 0; a < 4; a++)
                    mark[tt[a]] |= 2;
            }
    list = qdc_mallocn((size_t)tp->nv + 1, sizeof *list);
    if (!list) {
        qdc_free(mark);
        return QDC_ENOMEM;
    }
    for (int32_t v = 0; v < tp->nv; v++)
        if (mark[v] && movable[v] &&
            !(tp->vflag[v] & (MESH_V_BOUNDARY | MESH_V_INTERFACE)))
            list[n++] = v;
    for (int s = 0; s < UNTANGLE_SWEEPS; s++) {
        int32_t moves = 0;
        for (int32_t i = 0; i < n; i++)
            moves += untangle_vertex(tp, x, list[i], lbar);
        if (!moves)
            break;
    }
    *n_inverted = mesh_count_inverted(tp, x);
    qdc_free(list);
    qdc_free(mark);
    return QDC_OK;
}
