/* untangle.c - max-min volume untangling of what the passes leave inverted
 * (docs/method.md §5a). */
#include "opt/untangle.h"
#include "core/tet.h"
#include "opt/select.h"
#include "opt/star.h"

#include <math.h>
#include <string.h>

/* ---- untangling by max-min volume (Freitag & Plassmann) ---- */

#define UNTANGLE_INNER 40
#define UNTANGLE_SWEEPS 12
#define UNTANGLE_ACT 16

/* Smallest 6 x volume over v's star with v at y, and its inverted tets. */
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

/* g replaced by its part along v's surface or line (slide_tangent). */
static void tangent(const slide_ctx *sl, int32_t v, double g[3])
{
    double t[3];

    slide_tangent(sl, v, g, t);
    memcpy(g, t, sizeof t);
}

/* Max-min ascent of the star's signed volumes for one vertex (valid stars
 * too: their tets open room for the inverted ones). The direction is the
 * minimum-norm point of the hull of the gradients of the volumes that a step
 * of length s could make the smallest (within s |g| of it); a step is taken
 * when the smallest volume rises and the star gains no inverted tet. With sl
 * (a sliding vertex) the gradients are those along its surface or line and
 * the trial point is put back on it (star_trial_point). */
static int32_t untangle_vertex(const mesh_topo *tp, const slide_ctx *sl, double *x,
                               int32_t v, double lbar)
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
            if (sl)
                tangent(sl, v, gk);
            gmax = fmax(gmax, sqrt(gk[0] * gk[0] + gk[1] * gk[1] + gk[2] * gk[2]));
        }
        if (!isfinite(f0))
            break;
        for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
            double gk[3], vk = star_vol6(tp, x, k, xv, gk, NULL);
            if (sl)
                tangent(sl, v, gk);
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
        if (!nact || !star_min_norm_point(g, nact, d)) {
            s *= 0.5;
            continue;
        }
        dn = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (!(dn > 1e-12 * gmax) || !isfinite(dn)) {
            s *= 0.5; /* a corner at this scale: look closer */
            continue;
        }
        star_trial_point(sl, v, xv, d, s / dn, y);
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

/* 0 for an interior vertex, 1 for one sliding on a surface or a line of sl,
 * -1 for one that stays (a corner, or a boundary vertex without sl). */
static int slides(const mesh_topo *tp, const slide_ctx *sl, int32_t v)
{
    int k = sl ? slide_kind(sl, v) : SLIDE_INTERIOR;

    if (!(tp->vflag[v] & (MESH_V_BOUNDARY | MESH_V_INTERFACE)))
        return 0;
    return k == SLIDE_SURFACE || k == SLIDE_LINE ? 1 : k == SLIDE_INTERIOR && sl ? 0 : -1;
}

/* The vertices finish_untangle moves: the movable ones (that may move:
 * slides >= 0) of the inverted tets and of the tets around them, as the
 * pass's vworst (0; 2 for the others). bad[] (nt) and near[] (nv) are
 * scratch. Each tet, then each vertex, decides its own, in parallel. */
static void untangle_set(const mesh_topo *tp, const uint8_t *movable, const slide_ctx *sl,
                         const double *x, uint8_t *bad, uint8_t *near, double *vworst)
{
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < tp->nt; t++)
        bad[t] = (uint8_t)geom_tet_bad(x, tp->tets + 4 * (size_t)t);
#pragma omp parallel for schedule(static)
    for (int32_t v = 0; v < tp->nv; v++) { /* a corner of an inverted tet */
        uint8_t in = 0;
        for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++)
            in |= bad[tp->vt_idx[k] >> 2];
        near[v] = in;
    }
#pragma omp parallel for schedule(static)
    for (int32_t v = 0; v < tp->nv; v++) { /* a tet of v's star has such a corner */
        int in = 0;
        for (int32_t k = tp->vt_ptr[v]; !in && k < tp->vt_ptr[v + 1]; k++) {
            const int32_t *tt = tp->tets + 4 * (size_t)(tp->vt_idx[k] >> 2);
            in = near[tt[0]] | near[tt[1]] | near[tt[2]] | near[tt[3]];
        }
        vworst[v] = in && movable[v] && slides(tp, sl, v) >= 0 ? 0.0 : 2.0;
    }
}

qdc_status finish_untangle(const mesh_topo *tp, const uint8_t *movable,
                           const slide_ctx *sl, double *x, double lbar,
                           int (*stop)(void *), void *stop_ctx, int32_t *n_inverted)
{
    uint8_t *near = qdc_mallocn((size_t)tp->nv + 1, 1);
    uint8_t *bad = qdc_mallocn((size_t)tp->nt + 1, 1);
    double *vworst = qdc_mallocn((size_t)tp->nv + 1, sizeof(double));
    vq_pair *list = NULL;
    int32_t n = 0, *start = NULL, ncol = -1;

    if (near && bad && vworst) {
        untangle_set(tp, movable, sl, x, bad, near, vworst);
        ncol = select_vertices(tp, movable, vworst, &list, &n, &start);
    }
    qdc_free(near);
    qdc_free(bad);
    qdc_free(vworst);
    if (ncol < 0)
        return QDC_ENOMEM;
    /* classes in turn (Gauss-Seidel), the vertices of a class at once: no two
     * share a tet, so each reads only positions no other moves (the same
     * bytes at any thread count) */
    for (int s = 0; s < UNTANGLE_SWEEPS && !(stop && stop(stop_ctx)); s++) {
        int32_t moves = 0;
        for (int32_t c = 0; c < ncol; c++)
#pragma omp parallel for reduction(+ : moves) schedule(dynamic, 16) if (c < COLOUR_SHARED)
            for (int32_t i = start[c]; i < start[c + 1]; i++)
                moves += untangle_vertex(tp, slides(tp, sl, list[i].v) ? sl : NULL, x,
                                         list[i].v, lbar);
        if (!moves)
            break;
    }
    *n_inverted = mesh_count_inverted(tp, x);
    qdc_free(list);
    qdc_free(start);
    return QDC_OK;
}
