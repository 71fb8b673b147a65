/* finish.c - worst-tet finishing pass (METHOD §5a). */
#include "finish.h"

#include "encode.h"
#include "metric.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define FINISH_INNER 8
#define FINISH_HALVINGS 12

typedef struct {
    double q;
    int32_t v;
} vq_pair;

static int vq_cmp(const void *a, const void *b)
{
    const vq_pair *x = a, *y = b;
    if (x->q != y->q)
        return x->q < y->q ? -1 : 1;
    return (x->v > y->v) - (x->v < y->v);
}

/* k-th smallest of a[0..n) (0-based), reordering a: Hoare quickselect with a
 * median-of-three pivot, O(n) expected. */
static double kth_smallest(double *a, int32_t n, int32_t k)
{
    int32_t lo = 0, hi = n - 1;

    while (lo < hi) {
        int32_t mid = lo + (hi - lo) / 2, i = lo, j = hi;
        double x = a[lo], y = a[mid], z = a[hi];
        double piv = x < y ? (y < z ? y : (x < z ? z : x)) : (x < z ? x : (y < z ? z : y));
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

/* Local objective of vertex v placed at y: sum of q~ over its star, the number
 * of star tets that are not positive, and (if g) the gradient with respect to y. */
static double star_eval(const mesh_topo *tp, const double *x, int32_t v, const double *y,
                        opt_metric m, double delta, int32_t *nbad, double *qmax, double *g)
{
    double f = 0.0, worst = 0.0;
    int32_t bad = 0;

    if (g)
        g[0] = g[1] = g[2] = 0.0;
    for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
        int32_t t = tp->vt_idx[k] >> 2, a = tp->vt_idx[k] & 3;
        double p[4][3], gt[3], q;
        metric_parts pt;
        for (int b = 0; b < 4; b++)
            memcpy(p[b], b == a ? y : x + 3 * (size_t)tp->tets[4 * (size_t)t + b], sizeof p[b]);
        if (g) {
            q = metric_qt_grad(m, &p[0][0], a, delta, gt, &pt);
            if (isfinite(q))
                for (int c = 0; c < 3; c++)
                    g[c] += gt[c];
        } else {
            metric_parts_for(m, p[0], p[1], p[2], p[3], &pt);
            q = metric_qt(m, &pt, delta);
        }
        bad += !(pt.vol > 0.0);
        f += q;
        worst = q > worst ? q : worst;
    }
    *nbad = bad;
    *qmax = worst;
    return f;
}

/* Adaptive normalized-gradient descent of one vertex (METHOD §5a): step along
 * -g/|g|, start 0.05 mean edge, x1.6 after a success (cap 0.3), halve up to 12
 * times until the local objective decreases without inverting a star tet. */
static int32_t relax_vertex(const mesh_topo *tp, const slide_ctx *sl, double *x, int32_t v,
                            opt_metric m, double delta, double lbar, double rtol)
{
    int sliding = sl && slide_kind(sl, v) != SLIDE_INTERIOR;
    double s = 0.05 * lbar, *xv = x + 3 * (size_t)v;
    int32_t moves = 0;

    for (int it = 0; it < FINISH_INNER; it++) {
        double g[3], gn, y[3], f0, f1, w0, w1;
        int32_t bad0, bad1;
        int ok = 0;
        f0 = star_eval(tp, x, v, xv, m, delta, &bad0, &w0, g);
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
        for (int h = 0; h < FINISH_HALVINGS; h++) {
            for (int c = 0; c < 3; c++)
                y[c] = xv[c] - s * g[c] / gn;
            if (sliding) {
                double yp[3];
                slide_project(sl, v, y, yp);
                memcpy(y, yp, sizeof yp);
            }
            f1 = star_eval(tp, x, v, y, m, delta, &bad1, &w1, NULL);
            /* The sum must drop and the inverted count must not grow. A sliding
             * boundary vertex must not worsen its worst star tet either: on curved
             * surfaces it otherwise flattens all-boundary tets (measured on the
             * sphere: worst tet 0.259 -> 0.230). For interior vertices that rule
             * blocks useful moves (measured -0.005 mean on the dev corpus). */
            if (f1 < f0 && bad1 <= bad0 && (!sliding || w1 <= w0)) {
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

/* Greedy colouring of the visit list (worst first): no two vertices of a class
 * share an edge, hence no tet, so a class can move in parallel. colour[] is
 * scratch of nv entries; returns the number of classes and fills start[]. */
static int32_t colour_classes(const mesh_topo *tp, vq_pair *list, int32_t n, int32_t *colour,
                              int32_t **start_out)
{
    int32_t ncol = 0, *cnt, *start;
    uint64_t used;
    vq_pair *tmp;

    for (int32_t i = 0; i < n; i++)
        colour[list[i].v] = -1;
    for (int32_t i = 0; i < n; i++) {
        int32_t v = list[i].v, c = 0;
        used = 0;
        for (int32_t k = tp->adj_ptr[v]; k < tp->adj_ptr[v + 1]; k++) {
            int32_t u = tp->adj_idx[k];
            if (u != v && colour[u] >= 0 && colour[u] < 64)
                used |= 1ULL << colour[u];
        }
        while (c < 64 && (used >> c & 1))
            c++;
        colour[v] = c; /* 64+ only on absurd valences: all share the last class */
        if (c + 1 > ncol)
            ncol = c + 1;
    }
    cnt = qdc_calloc((size_t)ncol + 1, sizeof(int32_t));
    tmp = qdc_mallocn((size_t)n + 1, sizeof *tmp);
    if (!cnt || !tmp) {
        qdc_free(cnt);
        qdc_free(tmp);
        return -1;
    }
    for (int32_t i = 0; i < n; i++)
        cnt[colour[list[i].v] + 1]++;
    for (int32_t c = 0; c < ncol; c++)
        cnt[c + 1] += cnt[c];
    start = cnt;
    {
        int32_t *pos = qdc_mallocn((size_t)ncol + 1, sizeof(int32_t));
        if (!pos) {
            qdc_free(cnt);
            qdc_free(tmp);
            return -1;
        }
        memcpy(pos, cnt, ((size_t)ncol + 1) * sizeof(int32_t));
        for (int32_t i = 0; i < n; i++)
            tmp[pos[colour[list[i].v]]++] = list[i];
        qdc_free(pos);
    }
    memcpy(list, tmp, (size_t)n * sizeof *list);
    qdc_free(tmp);
    *start_out = start;
    return ncol;
}

qdc_status finish_sweep(const mesh_topo *tp, const uint8_t *movable, const slide_ctx *sl,
                        double *x, opt_metric m, double eps, double lbar, double frac,
                        double rtol, finish_stats *st)
{
    double *eta = qdc_mallocn((size_t)tp->nt, sizeof(double));
    double *sorted = qdc_mallocn((size_t)tp->nt, sizeof(double));
    double *vworst = qdc_mallocn((size_t)tp->nv, sizeof(double));
    vq_pair *list = NULL;
    int32_t n = 0, k;
    double thresh, delta;

    memset(st, 0, sizeof *st);
    if (!eta || !sorted || !vworst) {
        qdc_free(eta);
        qdc_free(sorted);
        qdc_free(vworst);
        return QDC_ENOMEM;
    }
    for (int32_t t = 0; t < tp->nt; t++) {
        const int32_t *tt = tp->tets + 4 * (size_t)t;
        metric_parts pt;
        metric_parts_of(x + 3 * (size_t)tt[0], x + 3 * (size_t)tt[1], x + 3 * (size_t)tt[2],
                        x + 3 * (size_t)tt[3], &pt);
        eta[t] = metric_mean_ratio(&pt);
    }
    memcpy(sorted, eta, (size_t)tp->nt * sizeof(double));
    k = (int32_t)(frac * tp->nt);
    if (k < 1)
        k = 1;
    if (k > tp->nt)
        k = tp->nt;
    thresh = kth_smallest(sorted, tp->nt, k - 1);
    delta = metric_delta(encode_min_arg(tp, x, m), eps);
    st->delta = delta;
    for (int32_t v = 0; v < tp->nv; v++)
        vworst[v] = 2.0;
    for (int32_t t = 0; t < tp->nt; t++) {
        if (!(eta[t] <= thresh || eta[t] <= 0.0))
            continue;
        for (int a = 0; a < 4; a++) {
            int32_t v = tp->tets[4 * (size_t)t + a];
            if (eta[t] < vworst[v])
                vworst[v] = eta[t];
        }
    }
    for (int32_t v = 0; v < tp->nv; v++)
        n += movable[v] && vworst[v] < 2.0;
    list = qdc_mallocn((size_t)n + 1, sizeof *list);
    if (!list) {
        qdc_free(eta);
        qdc_free(sorted);
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
    qsort(list, (size_t)n, sizeof *list, vq_cmp);
    {
        int32_t *start = NULL, ncol = -1;
        int32_t *colour = qdc_mallocn((size_t)tp->nv, sizeof(int32_t));
        if (colour)
            ncol = colour_classes(tp, list, n, colour, &start);
        qdc_free(colour);
        if (ncol < 0) {
            qdc_free(list);
            qdc_free(eta);
            qdc_free(sorted);
            qdc_free(vworst);
            return QDC_ENOMEM;
        }
        for (int32_t c = 0; c < ncol; c++) {
            int32_t moves = 0;
#pragma omp parallel for reduction(+ : moves) schedule(dynamic, 16)
            for (int32_t i = start[c]; i < start[c + 1]; i++)
                moves += relax_vertex(tp, sl, x, list[i].v, m, delta, lbar, rtol);
            st->n_moves += moves;
        }
        qdc_free(start);
    }
    st->n_verts = n;
    qdc_free(list);
    qdc_free(eta);
    qdc_free(sorted);
    qdc_free(vworst);
    return QDC_OK;
}
