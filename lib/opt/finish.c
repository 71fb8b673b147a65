/* finish.c - the finishing sweeps: worst-tet Newton and sliding moves
 * (docs/method.md §5a). */
#include "opt/finish.h"
#include "core/tet.h"
#include "geom/metric_int.h"
#include "opt/select.h"
#include "opt/star.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define FINISH_INNER 8
/* Broad sweeps take one Newton step per vertex (and more sweeps do the rest):
 * measured on 8 dev meshes, mean ratio 0.7729 against 0.7733 with up to 8
 * steps, for 30% less work. */
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

/* The faces opposite v in its star (metric_face), set once for the trials
 * of one visit: only v moves during it. A star of more than STAR_FACES tets
 * is evaluated without them (n = -1), the same way. Measured
 * on the 100k-tet ball-scan of scripts/corpus.py (one thread, instructions
 * counted by valgrind): the sweeps 2.17e9 -> 2.07e9, the same bits. */
#define STAR_FACES 96
typedef struct {
    int32_t n;
    metric_face f[STAR_FACES];
} star_faces;

/* The face opposite the star's vertex in incidence k (vt_idx), set. */
static void star_face(const mesh_topo *tp, const double *x, int32_t k, metric_face *mf)
{
    int32_t a = tp->vt_idx[k] & 3;
    const int32_t *tt = tp->tets + 4 * (size_t)(tp->vt_idx[k] >> 2);

    metric_face_set(x + 3 * (size_t)tt[tet_face_of[a][0]],
                    x + 3 * (size_t)tt[tet_face_of[a][1]],
                    x + 3 * (size_t)tt[tet_face_of[a][2]], mf);
}

static void star_faces_set(const mesh_topo *tp, const double *x, int32_t v,
                           star_faces *sf)
{
    int32_t k0 = tp->vt_ptr[v], n = tp->vt_ptr[v + 1] - k0;

    sf->n = n <= STAR_FACES ? n : -1;
    for (int32_t k = 0; k < sf->n; k++)
        star_face(tp, x, k0 + k, &sf->f[k]);
}

/* Local objective of vertex v placed at y with its gradient and Hessian
 * (upper triangle; both skipped if g is NULL); NAN if the metric has no
 * Hessian. so, if not NULL, receives what star_eval finds of the star (its
 * worst tet and smallest mean ratio cubed; the inverted count is si's). A tet
 * is under the floor qfloor > 0 when its mean ratio 12 (9 V^2)^(1/3) / A is,
 * tested as 15552 V^2 < (qfloor A)^3 (no cube root). */
static double star_hess(const mesh_topo *tp, const double *x, int32_t v, const double *y,
                        opt_metric m, double delta, double qfloor, star_info *si,
                        double g[3], double H[6], star_out *so, const star_faces *sf)
{
    double f = 0.0;
    int32_t k0 = tp->vt_ptr[v];

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
    for (int32_t k = k0; k < tp->vt_ptr[v + 1]; k++) {
        double gt[3], Ht[6], q, vl[2];
        metric_face own;
        const metric_face *mf = &own;
        if (sf && sf->n >= 0)
            mf = &sf->f[k - k0];
        else
            star_face(tp, x, k, &own);
        q = metric_qt_hess_at(m, y, mf, delta, g ? gt : NULL, Ht, vl);
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

/* 1 if v placed at y folds a star tet that is positive at x and whose face
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

/* Trials y = xv + d, xv + d/2, ... until one is taken (step_ok); 1 then,
 * with its value *f1, *s1 and (if g1) derivatives. */
static int try_steps(const mesh_topo *tp, const double *x, int32_t v, const double d[3],
                     opt_metric m, double delta, double qfloor, double f0,
                     const star_info *s0, double g1[3], double H1[6], double y[3],
                     double *f1, star_info *s1, int ks, const star_faces *sf)
{
    const double *xv = x + 3 * (size_t)v;
    double sc = 1.0;

    for (int h = 0; h < FINISH_HALVINGS; h++, sc *= 0.5) {
        star_trial_point(NULL, v, xv, d, sc, y);
        *f1 = star_hess(tp, x, v, y, m, delta, qfloor, s1, g1, H1, NULL, sf);
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
    star_faces sf;

    star_faces_set(tp, x, v, &sf);
    f0 = star_hess(tp, x, v, xv, m, delta, 0.0, &s0, g, H, NULL, &sf);
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
                       H1, y, &f1, &s1, ks, &sf))
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
            star_trial_point(sliding ? sl : NULL, v, xv, g, -s / gn, y);
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
    double f0 = star_hess(tp, x, v, xv, m, delta, 0.0, &si, g, H, &s0, NULL);

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
        star_trial_point(sl, v, xv, d, h ? 0.5 : 1.0, y);
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

/* The threshold of a sweep over the worst frac of tets by eta (every tet:
 * the largest eta), and *qfloor, the smallest eta. QDC_ENOMEM if out of
 * memory. */
static qdc_status sweep_threshold(const mesh_topo *tp, const double *eta, double frac,
                                  double *thresh_out, double *qfloor_out)
{
    int32_t k = (int32_t)(frac * tp->nt);
    double thresh, qfloor;

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
    *qfloor_out = qfloor;
    if (k < tp->nt &&
        select_kth(eta, tp->nt, k - 1, qfloor, thresh, &thresh, NULL) != QDC_OK)
        return QDC_ENOMEM;
    *thresh_out = thresh;
    return QDC_OK;
}

/* Each vertex's worst tet at or under thresh (or inverted), 2.0 if none (in
 * parallel, per vertex: a min). */
static void sweep_vworst(const mesh_topo *tp, const double *eta, double thresh,
                         double *vworst)
{
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
}

qdc_status finish_sweep(const mesh_topo *tp, const uint8_t *movable, const slide_ctx *sl,
                        double *x, opt_metric m, const double *eta, double delta,
                        double lbar, double frac, double rtol, int keep_surface,
                        finish_stats *st)
{
    double *vworst = qdc_mallocn((size_t)tp->nv, sizeof(double));
    vq_pair *list = NULL;
    int32_t n = 0, *start = NULL, ncol;
    double thresh, qfloor;

    memset(st, 0, sizeof *st);
    if (!vworst)
        return QDC_ENOMEM;
    if (sweep_threshold(tp, eta, frac, &thresh, &qfloor) != QDC_OK) {
        qdc_free(vworst);
        return QDC_ENOMEM;
    }
    st->delta = delta;
    sweep_vworst(tp, eta, thresh, vworst);
    /* worst first into the colouring; classes in turn (Gauss-Seidel), the
     * vertices of a class at once (independent stars) */
    ncol = select_vertices(tp, movable, vworst, &list, &n, &start);
    if (ncol < 0) {
        qdc_free(vworst);
        return QDC_ENOMEM;
    }
    for (int32_t c = 0; c < ncol; c++) {
        int32_t moves = 0;
#pragma omp parallel for reduction(+ : moves) schedule(dynamic, 16) if (c < COLOUR_SHARED)
        for (int32_t i = start[c]; i < start[c + 1]; i++)
            moves += visit_vertex(tp, sl, x, list[i].v, vworst[list[i].v], m, delta, lbar,
                                  rtol, qfloor, keep_surface);
        st->n_moves += moves;
    }
    qdc_free(start);
    st->n_verts = n;
    qdc_free(list);
    qdc_free(vworst);
    return QDC_OK;
}
