/* select.c - which vertices and tets a pass visits (select.h): the worst
 * first, the k-th smallest value, the colouring into independent classes. */
#include "opt/select.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

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

static int select_sort(vq_pair *list, int32_t n)
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
qdc_status select_kth(const double *a, int32_t n, int32_t k, double lo, double hi,
                      double *kth, double *sum)
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

#define COLOUR_NONE                                                                      \
    255 /* not in the list: a byte a vertex keeps the scratch in                         \
         * cache (int32 colours: the colouring was 10% of a                              \
         * broad sweep at 800k tets) */

#define CLASS_RANGES 16 /* ranges of vertices placed by one thread each */

/* Each listed vertex's colour (worst first): the smallest not taken by a
 * neighbour, 64 (COLOUR_SHARED) if all are; COLOUR_NONE elsewhere. */
static void greedy_colour(const mesh_topo *tp, const vq_pair *list, int32_t n,
                          uint8_t *colour)
{
    uint64_t used;

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
}

/* Greedy colouring of the visit list (worst first): no two vertices of a class
 * share an edge, hence no tet, so a class can move in parallel. colour[] is
 * scratch of nv entries; returns the number of classes and fills start[]. */
static int32_t select_colour(const mesh_topo *tp, vq_pair *list, int32_t n,
                             uint8_t *colour, int32_t **start_out)
{
    int32_t ncol = 0, *cnt, *start, rc[CLASS_RANGES][COLOUR_SHARED + 1];
    vq_pair *tmp;

    greedy_colour(tp, list, n, colour);
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

int32_t select_vertices(const mesh_topo *tp, const uint8_t *movable, const double *vworst,
                        vq_pair **list_out, int32_t *n_out, int32_t **start_out)
{
    vq_pair *list;
    uint8_t *colour;
    int32_t n = 0, ncol = -1;

    *list_out = NULL;
    *start_out = NULL;
    for (int32_t v = 0; v < tp->nv; v++)
        n += movable[v] && vworst[v] < 2.0;
    list = qdc_mallocn((size_t)n + 1, sizeof *list);
    if (!list)
        return -1;
    n = 0;
    for (int32_t v = 0; v < tp->nv; v++)
        if (movable[v] && vworst[v] < 2.0) {
            list[n].q = vworst[v];
            list[n].v = v;
            n++;
        }
    /* worst first into the colouring */
    colour = qdc_mallocn((size_t)tp->nv + 1, 1);
    if (colour && select_sort(list, n))
        ncol = select_colour(tp, list, n, colour, start_out);
    qdc_free(colour);
    if (ncol < 0) {
        qdc_free(list);
        return -1;
    }
    *list_out = list;
    *n_out = n;
    return ncol;
}

/* (value, tet) pairs by value, ties by tet. */
static int vq_cmp(const void *a, const void *b)
{
    const vq_pair *p = a, *q = b;
    return p->q < q->q ? -1 : p->q > q->q ? 1 : (p->v > q->v) - (p->v < q->v);
}

/* The SELECT_WORST_TETS tets of smallest smin (fewer if the mesh has fewer), sorted,
 * ties by index: each of 16 ranges of tets keeps its own smallest, in
 * parallel, then the 16 lists are sorted together. Returns how many. */
#define WORST_RANGES 16
int32_t select_worst_tets(const double *smin, int32_t nt, vq_pair *out)
{
    vq_pair cand[WORST_RANGES][SELECT_WORST_TETS], all[WORST_RANGES * SELECT_WORST_TETS];
    int32_t nc[WORST_RANGES], n = 0;

#pragma omp parallel for schedule(static)
    for (int r = 0; r < WORST_RANGES; r++) {
        vq_pair *c = cand[r];
        int32_t m = 0;
        for (int32_t t = qdc_part(nt, r, WORST_RANGES);
             t < qdc_part(nt, r + 1, WORST_RANGES); t++) {
            vq_pair p = {smin[t], t};
            int32_t j;
            if (m == SELECT_WORST_TETS && !(p.q < c[m - 1].q))
                continue; /* t is larger than the last: ties keep the lower index */
            j = m < SELECT_WORST_TETS ? m++ : m - 1;
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
    n = n < SELECT_WORST_TETS ? n : SELECT_WORST_TETS;
    memcpy(out, all, (size_t)n * sizeof *out);
    return n;
}
