/* split.c - interior edge split: a long unconstrained edge's ring cut in two
 * at the edge's midpoint, in sweeps over the edges longest against the sizes
 * at their ends. */
#include "topo/split.h"

#include "topo/insert.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { STAR_CAP = 256, SWEEPS = 3 };

qdc_status split_edge(tmesh *tm, int32_t t, int e, double qfrac, int *done,
                      int32_t *new_ids, int *nnew)
{
    int32_t star[STAR_CAP], ring[SPLIT_MAXRING], newt[2 * SPLIT_MAXRING][4], a, b, m;
    double p[3], qold = INFINITY, qnew = INFINITY;
    int ns, nr = 0, applied = 0;
    qdc_status st;

    *done = 0;
    *nnew = 0;
    if (tm->tv[4 * (size_t)t] < 0 || (tm->econs[t] >> e & 1))
        return QDC_OK;
    a = tm->tv[4 * (size_t)t + tmesh_edge[e][0]];
    b = tm->tv[4 * (size_t)t + tmesh_edge[e][1]];
    ns = tmesh_star(tm, t, a, star, STAR_CAP);
    for (int k = 0; k < ns; k++) {
        if (tmesh_local(tm, star[k], b) < 0)
            continue;
        if (nr == SPLIT_MAXRING || tm->q[star[k]] < -1.0)
            return QDC_OK;
        ring[nr++] = star[k];
        qold = fmin(qold, tm->q[star[k]]);
    }
    if (nr < 3)
        return QDC_OK; /* not a closed ring: ns < 0, or the edge is not interior */
    for (int d = 0; d < 3; d++)
        p[d] = 0.5 * (tm->xyz[3 * (size_t)a + d] + tm->xyz[3 * (size_t)b + d]);
    st = tmesh_add_vertex(tm, p);
    if (st != QDC_OK)
        return st;
    m = tm->nv - 1;
    for (int k = 0; k < nr; k++) {
        const int32_t *v = tm->tv + 4 * (size_t)ring[k];
        int32_t *lo = newt[2 * k], *hi = newt[2 * k + 1];
        memcpy(lo, v, 4 * sizeof *v);
        memcpy(hi, v, 4 * sizeof *v);
        lo[tmesh_local(tm, ring[k], b)] = m;
        hi[tmesh_local(tm, ring[k], a)] = m;
        qnew = fmin(qnew, fmin(tmesh_quality(tm, lo, -INFINITY),
                               tmesh_quality(tm, hi, -INFINITY)));
    }
    if (!(qnew > -1.0) || !(qnew >= qfrac * qold)) {
        tm->nv--;
        return QDC_OK;
    }
    st =
        tmesh_replace(tm, ring, nr, (const int32_t(*)[4])newt, 2 * nr, new_ids, &applied);
    if (st != QDC_OK || !applied) {
        tm->nv--;
        return st;
    }
    *done = 1;
    *nnew = 2 * nr;
    return QDC_OK;
}

void split_undo(tmesh *tm)
{
    insert_undo(tm); /* the same undo: the journal, then the vertex added last */
}

typedef struct {
    double r;       /* length over the mean size of its ends */
    int32_t a, b;   /* a < b */
    int32_t t;      /* a tet of the edge, */
    uint32_t stamp; /* as it was */
    int e;
} cand;

static int by_edge(const void *x, const void *y)
{
    const cand *p = x, *q = y;

    if (p->a != q->a)
        return p->a < q->a ? -1 : 1;
    if (p->b != q->b)
        return p->b < q->b ? -1 : 1;
    return p->t < q->t ? -1 : p->t > q->t;
}

static int by_ratio(const void *x, const void *y)
{
    const cand *p = x, *q = y;

    if (p->r != q->r)
        return p->r > q->r ? -1 : 1;
    return by_edge(x, y);
}

static double edge_len(const tmesh *tm, int32_t a, int32_t b)
{
    const double *x = tm->xyz + 3 * (size_t)a, *y = tm->xyz + 3 * (size_t)b;

    return sqrt((x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) +
                (x[2] - y[2]) * (x[2] - y[2]));
}

/* h[v] for the vertices as the pass begins (split_long_edges). */
static qdc_status sizes(const tmesh *tm, double *h)
{
    int32_t *cnt = qdc_calloc((size_t)tm->nv + 1, sizeof *cnt);

    if (!cnt)
        return QDC_ENOMEM;
    memset(h, 0, (size_t)tm->nv * sizeof *h);
    for (int32_t t = 0; t < tm->hi; t++)
        for (int e = 0; e < 6 && tm->tv[4 * (size_t)t] >= 0; e++) {
            int32_t a = tm->tv[4 * (size_t)t + tmesh_edge[e][0]],
                    b = tm->tv[4 * (size_t)t + tmesh_edge[e][1]];
            int cons = tm->econs[t] >> e & 1;
            double l = edge_len(tm, a, b);
            if (cons || !tm->vcons[a]) {
                h[a] += l;
                cnt[a]++;
            }
            if (cons || !tm->vcons[b]) {
                h[b] += l;
                cnt[b]++;
            }
        }
    for (int32_t v = 0; v < tm->nv; v++)
        h[v] = cnt[v] > 0 ? h[v] / cnt[v] : 0.0;
    qdc_free(cnt);
    return QDC_OK;
}

/* The edges of this sweep, one entry each, relatively longest first: *c
 * (qdc_malloc) and *n. */
static qdc_status candidates(const tmesh *tm, const double *h, double lratio, cand **c,
                             size_t *n)
{
    size_t cap = 0, k = 0;

    *c = NULL;
    *n = 0;
    for (int32_t t = 0; t < tm->hi; t++)
        for (int e = 0; e < 6 && tm->tv[4 * (size_t)t] >= 0; e++) {
            int32_t a = tm->tv[4 * (size_t)t + tmesh_edge[e][0]],
                    b = tm->tv[4 * (size_t)t + tmesh_edge[e][1]];
            double hm = 0.5 * (h[a] + h[b]), l;
            cand x;
            if ((tm->econs[t] >> e & 1) || !(hm > 0.0))
                continue;
            l = edge_len(tm, a, b);
            if (!(l > lratio * hm))
                continue;
            if (k == cap) {
                size_t nc = cap ? 2 * cap : 1024;
                cand *g = qdc_realloc(*c, nc * sizeof *g);
                if (!g) {
                    qdc_free(*c);
                    *c = NULL;
                    return QDC_ENOMEM;
                }
                *c = g;
                cap = nc;
            }
            x.r = l / hm;
            x.a = a < b ? a : b;
            x.b = a < b ? b : a;
            x.t = t;
            x.stamp = tm->stamp[t];
            x.e = e;
            (*c)[k++] = x;
        }
    if (k > 0) {
        size_t u = 0;
        qsort(*c, k, sizeof **c, by_edge);
        for (size_t i = 0; i < k; i++)
            if (u == 0 || (*c)[u - 1].a != (*c)[i].a || (*c)[u - 1].b != (*c)[i].b)
                (*c)[u++] = (*c)[i];
        k = u;
        qsort(*c, k, sizeof **c, by_ratio);
    }
    *n = k;
    return QDC_OK;
}

/* The mesh's edges by Euler's formula (V - E + F - T = 1, each inner face
 * shared by two tets): nv + nt + (boundary faces) / 2 - 1. */
static double edges_euler(const tmesh *tm)
{
    int64_t nb = 0;

    for (int32_t t = 0; t < tm->hi; t++)
        for (int i = 0; i < 4 && tm->tv[4 * (size_t)t] >= 0; i++)
            nb += tm->adj[4 * (size_t)t + i] < 0;
    return (double)tm->nv + (double)tm->nlive + 0.5 * (double)nb - 1.0;
}

qdc_status split_long_edges(tmesh *tm, double lratio, double qfrac, double share,
                            int64_t *nsplit, const atomic_int *cancel)
{
    double *h = qdc_mallocn((size_t)tm->nv + 1, sizeof *h);
    qdc_status st;

    *nsplit = 0;
    if (!h)
        return QDC_ENOMEM;
    st = sizes(tm, h);
    for (int sweep = 0; sweep < SWEEPS && st == QDC_OK; sweep++) {
        cand *c = NULL;
        size_t n = 0;
        int64_t before = *nsplit;
        double *g;
        st = candidates(tm, h, lratio, &c, &n);
        if (st != QDC_OK || n == 0 ||
            (sweep == 0 && share > 0.0 && (double)n < share * edges_euler(tm))) {
            qdc_free(c);
            break;
        }
        /* room for a size at each vertex this sweep may add */
        g = qdc_realloc(h, ((size_t)tm->nv + n + 1) * sizeof *h);
        if (!g) {
            qdc_free(c);
            st = QDC_ENOMEM;
            break;
        }
        h = g;
        for (size_t i = 0; i < n && st == QDC_OK; i++) {
            int32_t ids[2 * SPLIT_MAXRING];
            int done = 0, nn = 0;
            if (cancel && atomic_load(cancel)) {
                st = QDC_ECANCEL;
                break;
            }
            if (tm->tv[4 * (size_t)c[i].t] < 0 || tm->stamp[c[i].t] != c[i].stamp)
                continue; /* a split of an edge next to it took its tet */
            st = split_edge(tm, c[i].t, c[i].e, qfrac, &done, ids, &nn);
            if (st != QDC_OK || !done)
                continue;
            tmesh_commit(tm);
            h[tm->nv - 1] = 0.5 * (h[c[i].a] + h[c[i].b]);
            (*nsplit)++;
        }
        qdc_free(c);
        if (*nsplit == before)
            break;
    }
    qdc_free(h);
    return st;
}
