/* topo.c - the topology driver: a queue of bad tets, worst first, each given its
 * best improving flip (Stellar's topological pass, Klingner and Shewchuk 2007,
 * with Netgen's sum-of-badness preference among improving operations). */
#include "topo/topo.h"

#include "core/tet.h"
#include "geom/metric_int.h"
#include "topo/contract.h"
#include "topo/insert.h"
#include "topo/split.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

void topo_params_default(topo_params *p)
{
    p->maxring = FLIP_MAXRING;
    p->qgoal = 0.6;
    p->margin = 1e-3;
    p->floor4 = 0.1;
    p->rounds = 3;
    p->max_ops = 0;
    p->insert = 0;
    p->qinsert = 0.15;
    p->split = 0;
    p->lsplit = 1.6;
    p->qsplit = 0.5;
    p->sshare = 0.0;
    p->imargin = 0.05;
    p->iangle = 1;
    p->contract = 0;
    p->qcontract = 0.3;
    p->cfloor = 0.0;
    p->bound.hausd = 0.0;
    p->bound.cos_feature = 0.8660254037844387; /* 30 degrees */
    p->recheck = 0;
    p->akeep = 0.0;
    p->nkeep = 0;
    p->keep = NULL;
}

/* The queue is by exact quality. Quantized (16 or 64 bands of mean ratio,
 * index order within a band, for a cache-friendlier walk) it saved 0-13% of the
 * CPU of --topology flips on the 300k-tet bone-lowq and ball-scan of
 * scripts/corpus.py --seed 1 (within the noise of a loaded machine) and kept
 * the mean ratio, but lowered the smallest dihedral angle: at 100k tets with
 * 64 bands ball-scan 20.73 -> 20.06 degrees, part-cad 39.16 -> 38.82, at 300k
 * ball-scan 17.95 -> 16.96. */
typedef struct {
    double q;
    int32_t k[4]; /* the tet's vertices sorted: the tie-break */
    int32_t t;
    uint32_t stamp;
} qent;

/* The queue: the tets queued at the start of a pass sorted (s[si..sn)), the
 * tets made during it in a binary heap (a[0..n)); a pop takes the first of
 * the two by before(). The same order as one heap of them all (two entries
 * never tie but for a removed tet's, which is skipped), at a fraction of the
 * pops' cost: on the 1M-tet ball-scan of scripts/corpus.py, --topology flips,
 * the heap's pops were 9% of the first round of flips. */
typedef struct {
    qent *a;
    size_t n, cap;
    qent *s;
    size_t si, sn, scap;
} heap;

static int before(const qent *x, const qent *y)
{
    if (x->q != y->q)
        return x->q < y->q;
    for (int s = 0; s < 4; s++)
        if (x->k[s] != y->k[s])
            return x->k[s] < y->k[s];
    return 0;
}

static int qent_cmp(const void *x, const void *y)
{
    return before(x, y) ? -1 : before(y, x) ? 1 : 0;
}

/* *a grown to hold n + 1 entries (cap of them). */
static qdc_status qent_room(qent **a, size_t n, size_t *cap)
{
    if (n == *cap) {
        size_t c = *cap ? 2 * *cap : 1024;
        qent *b = qdc_realloc(*a, c * sizeof *b);
        if (!b)
            return QDC_ENOMEM;
        *a = b;
        *cap = c;
    }
    return QDC_OK;
}

static qent qent_of(const tmesh *tm, int32_t t)
{
    qent e;

    e.q = tm->q[t];
    memcpy(e.k, tm->tv + 4 * (size_t)t, sizeof e.k);
    for (int x = 1; x < 4; x++)
        for (int y = x; y > 0 && e.k[y - 1] > e.k[y]; y--) {
            int32_t s = e.k[y];
            e.k[y] = e.k[y - 1];
            e.k[y - 1] = s;
        }
    e.t = t;
    e.stamp = tm->stamp[t];
    return e;
}

/* Entries left in the queue. */
static size_t heap_size(const heap *h)
{
    return h->n + (h->sn - h->si);
}

static qdc_status heap_push(heap *h, const tmesh *tm, int32_t t)
{
    qent e;
    size_t i;

    if (qent_room(&h->a, h->n, &h->cap) != QDC_OK)
        return QDC_ENOMEM;
    e = qent_of(tm, t);
    i = h->n++;
    while (i > 0 && before(&e, &h->a[(i - 1) / 2])) {
        h->a[i] = h->a[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    h->a[i] = e;
    return QDC_OK;
}

/* The first entry; *from its index in s, or SIZE_MAX (from the heap). */
static qent heap_pop(heap *h, size_t *from)
{
    qent top, last;
    size_t i = 0;

    *from = SIZE_MAX;
    if (h->si < h->sn && (h->n == 0 || !before(&h->a[0], &h->s[h->si]))) {
        *from = h->si;
        return h->s[h->si++];
    }
    top = h->a[0];
    last = h->a[--h->n];

    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= h->n)
            break;
        if (c + 1 < h->n && before(&h->a[c + 1], &h->a[c]))
            c++;
        if (!before(&h->a[c], &last))
            break;
        h->a[i] = h->a[c];
        i = c;
    }
    if (h->n > 0)
        h->a[i] = last;
    return top;
}

/* x better than y: larger gain, larger new minimum, then kind and key. */
static int better(const flip_cand *x, const flip_cand *y)
{
    if (x->gain != y->gain)
        return x->gain > y->gain;
    if (x->qmin_new != y->qmin_new)
        return x->qmin_new > y->qmin_new;
    if (x->kind != y->kind)
        return x->kind < y->kind;
    for (int s = 0; s < 3; s++)
        if (x->key[s] != y->key[s])
            return x->key[s] < y->key[s];
    return 0;
}

/* What the flips of a tet depend on, to skip a tet whose evaluation failed
 * and whose neighbourhood has not changed since (the result would be the
 * same: the evaluation reads only the coordinates, which flips keep, and the
 * tets around the tet's vertices and the apexes across its faces: its edges'
 * rings, the tets across its faces, the sandwiched tets of multi-face removal,
 * which hold its apex a or the apex b across its face). Each operation bumps
 * the epoch and stamps the vertices of its new tets, which are those of the
 * tets it removed. Same flips as without it; on the 100k-tet bone-lowq of
 * scripts/corpus.py (--topology flips) the queue's second and third passes of
 * the first round visited 107k tets for 888 flips, and the run took 7.5 CPU s
 * against 10.1 before. Carried from one call to the next (lib/opt/topology.c's
 * rounds) for the tets around which the smoothing between moved no vertex, it
 * would skip next to nothing: on the 100k-tet ball-scan (flips) the smoothing
 * after the first round moved 9300 of the 18244 vertices and left 1 vertex in
 * no tet with a moved one, after the second (only the vertices near the flips
 * free) 8936 and 15; no failed tet could have been kept (2 in full's round).
 * Within a call it is kept across the insertions and contractions between the
 * flip passes (each stamps as a flip does: it replaces tets by tets on their
 * vertices, and moves none): before, each of those passes forgot it, and the
 * next flip pass evaluated every queued tet again. */
typedef struct {
    uint32_t epoch; /* operations applied so far, + 1 */
    uint32_t *vchg; /* vertex: the epoch of its last change (nv entries) */
    uint32_t *fail; /* tet slot: the epoch its flips were found to fail at, 0 */
    int32_t nv, cap;
    /* An edge's removal reads only the tets of its ring, which all hold both
     * its vertices, and is the same whichever of them asks: the edges found
     * not removable (and, with cfloor, not contractible: contract_pass), by
     * key (a < b: (a << 32 | b) + 1, the top bit the kind; 0 empty) and epoch,
     * in an open-addressed table of emask + 1 slots (full: not recorded).
     * On the 100k bone-lowq this halved the edge removals evaluated. */
    uint64_t *ekey;
    uint32_t *efail;
    uint64_t emask;
    int ebits;
} memo;

enum { EDGE_PROBES = 16 };

static void memo_free(memo *mo)
{
    qdc_free(mo->vchg);
    qdc_free(mo->fail);
    qdc_free(mo->ekey);
    qdc_free(mo->efail);
    memset(mo, 0, sizeof *mo);
}

/* A memo for tm; its edge table sized for `kinds` kinds of record. */
static qdc_status memo_init(memo *mo, const tmesh *tm, int kinds)
{
    size_t n = 1024;

    memset(mo, 0, sizeof *mo);
    mo->epoch = 1;
    mo->nv = tm->nv;
    mo->cap = tm->cap;
    mo->ebits = 10;
    while (n < 4 * (size_t)kinds * (size_t)tm->nlive) { /* 1.2 edges a tet: a quarter */
        n *= 2;
        mo->ebits++;
    }
    mo->emask = n - 1;
    mo->vchg = qdc_calloc((size_t)mo->nv + 1, sizeof *mo->vchg);
    mo->fail = qdc_calloc((size_t)mo->cap + 1, sizeof *mo->fail);
    mo->ekey = qdc_calloc(n, sizeof *mo->ekey);
    mo->efail = qdc_calloc(n, sizeof *mo->efail);
    return mo->vchg && mo->fail && mo->ekey && mo->efail ? QDC_OK : QDC_ENOMEM;
}

/* What an edge's record in the table says: not removable (edge removal), or
 * not contractible by gain (contract_pass with cfloor). */
enum { EDGE_REMOVAL = 0, EDGE_CONTRACT = 1 };

/* The key of edge ab (a < b) for a record of kind. */
static uint64_t edge_key(int32_t a, int32_t b, int kind)
{
    return (((uint64_t)(uint32_t)a << 32 | (uint32_t)b) + 1) | (uint64_t)kind << 63;
}

/* The slot of key in the table, or of the first empty slot on its probe; -1
 * when neither within EDGE_PROBES. */
static int64_t edge_slot(const memo *mo, uint64_t key)
{
    uint64_t h = (key * 0x9E3779B97F4A7C15ull) >> (64 - mo->ebits);

    for (int k = 0; k < EDGE_PROBES; k++, h = (h + 1) & mo->emask)
        if (mo->ekey[h] == key || mo->ekey[h] == 0)
            return (int64_t)h;
    return -1;
}

/* 1 when edge ab (a < b) was found failing as kind and the stars of its ends
 * are unchanged (an edge's ring for a removal: it is in both stars). */
static int edge_failed(const memo *mo, int32_t a, int32_t b, int kind)
{
    uint64_t key = edge_key(a, b, kind);
    int64_t h;

    if (a >= mo->nv || b >= mo->nv)
        return 0;
    h = edge_slot(mo, key);
    return h >= 0 && mo->ekey[h] == key && mo->vchg[a] <= mo->efail[h] &&
           mo->vchg[b] <= mo->efail[h];
}

static void edge_fail(memo *mo, int32_t a, int32_t b, int kind)
{
    uint64_t key = edge_key(a, b, kind);
    int64_t h;

    if (a >= mo->nv || b >= mo->nv)
        return;
    h = edge_slot(mo, key);
    if (h >= 0) {
        mo->ekey[h] = key;
        mo->efail[h] = mo->epoch;
    }
}

/* The edges of t in mask (best_flip's efail) recorded as not removable. */
static void memo_fail_edges(memo *mo, const tmesh *tm, int32_t t, unsigned mask)
{
    for (int e = 0; e < 6; e++)
        if (mask & 1u << e) {
            int32_t a = tm->tv[4 * (size_t)t + tmesh_edge[e][0]],
                    b = tm->tv[4 * (size_t)t + tmesh_edge[e][1]];
            edge_fail(mo, a < b ? a : b, a < b ? b : a, EDGE_REMOVAL);
        }
}

/* 1 when nothing the flips of t read changed since epoch at (> 0). */
static int memo_same(const memo *mo, const tmesh *tm, int32_t t, uint32_t at)
{
    if (at == 0)
        return 0;
    for (int i = 0; i < 4; i++) {
        int32_t v = tm->tv[4 * (size_t)t + i], nb = tm->adj[4 * (size_t)t + i];
        if (v >= mo->nv || mo->vchg[v] > at)
            return 0;
        if (nb >= 0 && (tm->tv[nb] >= mo->nv || mo->vchg[tm->tv[nb]] > at))
            return 0;
    }
    return 1;
}

/* 1 when t's flips failed and nothing they read changed since. */
static int memo_skip(const memo *mo, const tmesh *tm, int32_t t)
{
    return memo_same(mo, tm, t, t < mo->cap ? mo->fail[t] : 0);
}

/* An operation applied: its new tets ids[0..n) start unevaluated, their
 * vertices changed. The fail array grows with the tmesh's slots. */
static qdc_status memo_applied(memo *mo, const tmesh *tm, const int32_t *ids, int n)
{
    if (tm->cap > mo->cap) {
        uint32_t *f = qdc_realloc(mo->fail, ((size_t)tm->cap + 1) * sizeof *f);
        if (!f)
            return QDC_ENOMEM;
        memset(f + mo->cap, 0, ((size_t)tm->cap - (size_t)mo->cap) * sizeof *f);
        mo->fail = f;
        mo->cap = tm->cap;
    }
    mo->epoch++;
    for (int j = 0; j < n; j++) {
        mo->fail[ids[j]] = 0;
        for (int i = 0; i < 4; i++) {
            int32_t v = tm->tv[4 * (size_t)ids[j] + i];
            if (v < mo->nv)
                mo->vchg[v] = mo->epoch;
        }
    }
    return QDC_OK;
}

/* The vertices of the live tets old[0..n) (before an operation removes them)
 * into vs (4n entries). */
static void memo_collect(const tmesh *tm, const int32_t *old, int n, int32_t *vs)
{
    for (int o = 0; o < n; o++)
        memcpy(vs + 4 * o, tm->tv + 4 * (size_t)old[o], 4 * sizeof *vs);
}

/* After memo_applied: the vertices vs[0..n) stamped with its epoch too (those
 * of the tets an operation removed, a vertex that went among them). */
static void memo_stamp(memo *mo, const int32_t *vs, int n)
{
    for (int i = 0; i < n; i++)
        if (vs[i] >= 0 && vs[i] < mo->nv)
            mo->vchg[vs[i]] = mo->epoch;
}

/* The smallest dihedral angle (degrees) of the n tets tv[0..n) (4 each). */
static double min_angle(const tmesh *tm, const int32_t (*tv)[4], int n)
{
    double m = 180.0;

    for (int j = 0; j < n; j++) {
        double a0, a1;
        metric_dihedral_range(
            tm->xyz + 3 * (size_t)tv[j][0], tm->xyz + 3 * (size_t)tv[j][1],
            tm->xyz + 3 * (size_t)tv[j][2], tm->xyz + 3 * (size_t)tv[j][3], &a0, &a1);
        m = fmin(m, a0);
    }
    return m;
}

/* 1 when candidate c keeps the smallest dihedral angle: its new tets' is at
 * least akeep degrees or at least its old tets'. */
static int keeps_angle(const tmesh *tm, const flip_cand *c, double akeep)
{
    int32_t old[2 * FLIP_MAXRING][4];
    double anew;

    if (!(akeep > 0.0))
        return 1;
    anew = min_angle(tm, (const int32_t(*)[4])c->newt, c->nnew);
    if (anew >= akeep)
        return 1;
    for (int o = 0; o < c->nold; o++)
        memcpy(old[o], tm->tv + 4 * (size_t)c->old[o], sizeof old[o]);
    return anew >= min_angle(tm, (const int32_t(*)[4])old, c->nold);
}

/* The best improving flip of tet t's edges and faces; 1 if there is one.
 * Reads mo (may be NULL) only: bit e of *efail is set for each edge e found
 * not removable, for the caller to record (memo_fail_edges). */
static int best_flip(const tmesh *tm, int32_t t, const topo_params *p, const memo *mo,
                     flip_cand *best, unsigned *efail)
{
    flip_cand c;
    int have = 0;

    *efail = 0;
    for (int e = 0; e < 6; e++) {
        int32_t a = tm->tv[4 * (size_t)t + tmesh_edge[e][0]],
                b = tm->tv[4 * (size_t)t + tmesh_edge[e][1]], lo = a < b ? a : b,
                hi = a < b ? b : a;
        if (mo && edge_failed(mo, lo, hi, EDGE_REMOVAL))
            continue;
        if (!flip_edge_eval(tm, t, e, p->maxring, p->floor4, p->margin, &c)) {
            *efail |= 1u << e;
        } else if ((!have || better(&c, best)) && keeps_angle(tm, &c, p->akeep)) {
            *best = c;
            have = 1;
        }
    }
    if (p->bound.hausd > 0 && tm->fref) {
        for (int e = 0; e < 6; e++)
            if (flip_bedge_eval(tm, t, e, p->maxring, p->floor4, p->margin, &p->bound,
                                &c) &&
                (!have || better(&c, best))) {
                *best = c;
                have = 1;
            }
        if (flip_peel_eval(tm, t, p->margin, &p->bound, &c) &&
            (!have || better(&c, best))) {
            *best = c;
            have = 1;
        }
    }
    for (int f = 0; f < 4; f++) {
        if (flip_23_eval(tm, t, f, p->floor4, p->margin, &c) &&
            (!have || better(&c, best)) && keeps_angle(tm, &c, p->akeep)) {
            *best = c;
            have = 1;
        }
        if (flip_multiface_eval(tm, t, f, p->maxring, p->floor4, p->margin, &c) &&
            (!have || better(&c, best)) && keeps_angle(tm, &c, p->akeep)) {
            *best = c;
            have = 1;
        }
    }
    return have;
}

/* The queue emptied, then the live tets below q (not inverted) queued. */
static qdc_status queue_below(const tmesh *tm, heap *h, double q)
{
    h->n = 0;
    h->si = h->sn = 0;
    for (int32_t t = 0; t < tm->hi; t++)
        if (tm->tv[4 * (size_t)t] >= 0 && tm->q[t] < q && tm->q[t] >= -1.0) {
            if (qent_room(&h->s, h->sn, &h->scap) != QDC_OK)
                return QDC_ENOMEM;
            h->s[h->sn++] = qent_of(tm, t);
        }
    if (h->sn > 1)
        qsort(h->s, h->sn, sizeof *h->s, qent_cmp);
    return QDC_OK;
}

/* Vertex insertion in the live tets below qinsert, worst first (queued once);
 * the new tets are not revisited. Adds the insertions to *ops and st; mo (NULL:
 * none) is told each as a flip's change (a star replaces a cavity, every
 * vertex of which it holds; the new vertex is past mo's and never skipped). */
static qdc_status insert_pass(tmesh *tm, const topo_params *p, heap *h, memo *mo,
                              topo_stats *st, int64_t *ops, int64_t max_ops,
                              const atomic_int *cancel)
{
    qdc_status s = QDC_OK;

    s = queue_below(tm, h, p->qinsert);
    while (s == QDC_OK && heap_size(h) > 0 && *ops < max_ops) {
        size_t from;
        qent e = heap_pop(h, &from);
        int32_t ids[32];
        int done = 0, nn = 0;
        if (cancel && atomic_load(cancel))
            return QDC_ECANCEL;
        if (tm->tv[4 * (size_t)e.t] < 0 || tm->stamp[e.t] != e.stamp)
            continue;
        s = insert_in_tet(tm, e.t, p->imargin, p->iangle, &done, ids, &nn);
        if (s != QDC_OK || !done)
            continue;
        tmesh_commit(tm);
        (*ops)++;
        st->insertions++;
        if (mo)
            s = memo_applied(mo, tm, ids, nn);
    }
    return s;
}

/* The smallest mean ratio (*q) and dihedral angle (*a, degrees) of tm's live
 * tets that are not inverted (+inf and 180: none). */
static void live_worst(const tmesh *tm, double *q, double *a)
{
    *q = INFINITY;
    *a = 180.0;
    for (int32_t t = 0; t < tm->hi; t++)
        if (tm->tv[4 * (size_t)t] >= 0 && tm->q[t] >= -1.0) {
            *q = fmin(*q, tm->q[t]);
            *a =
                fmin(*a, min_angle(tm, (const int32_t(*)[4])(tm->tv + 4 * (size_t)t), 1));
        }
}

/* c into *best (*have) when it is the first or better: the larger new
 * minimum, then the larger gain. */
static void keep_better(const contract_cand *c, contract_cand *best, int *have)
{
    if (!*have || c->qmin_new > best->qmin_new ||
        (c->qmin_new == best->qmin_new && c->gain > best->gain)) {
        *best = *c;
        *have = 1;
    }
}

/* The best contraction of an interior edge of t into *best (*have), by
 * contract_eval with qfloor; with qfloor > 0 the edges found failing are
 * recorded in mo (may be NULL) and skipped while their stars stay. */
static void contract_inner(const tmesh *tm, const topo_params *p, memo *mo, int32_t t,
                           double qfloor, double afloor, contract_cand *best, int *have)
{
    contract_cand c;
    int memo_it = mo && qfloor > 0.0;

    for (int k = 0; k < 6; k++) {
        int32_t a = tm->tv[4 * (size_t)t + tmesh_edge[k][0]],
                b = tm->tv[4 * (size_t)t + tmesh_edge[k][1]];
        int32_t lo = a < b ? a : b, hi = a < b ? b : a;
        if (memo_it && edge_failed(mo, lo, hi, EDGE_CONTRACT))
            continue;
        if (!contract_eval(tm, t, k, p->floor4, p->margin, qfloor, &c) ||
            (qfloor > 0.0 &&
             min_angle(tm, (const int32_t(*)[4])c.newt, c.nnew) < afloor)) {
            if (memo_it)
                edge_fail(mo, lo, hi, EDGE_CONTRACT);
            continue;
        }
        keep_better(&c, best, have);
    }
}

/* Edge contraction in the live tets below qcontract, worst first (queued
 * once): each tet's best contraction of its edges (of its boundary edges too
 * under a bound). With cfloor > 0 by gain (contract.h's qfloor: the larger of
 * cfloor and the smallest mean ratio of the live tets when the pass starts, so
 * that no contraction makes a tet worse than the mesh's worst). Adds to *ops
 * and st; mo (NULL: none) is told each as a flip's change, the vertices of
 * the tets removed stamped too (no vertex moves: the one that goes is in no
 * tet after). */
static qdc_status contract_pass(tmesh *tm, const topo_params *p, heap *h, memo *mo,
                                topo_stats *st, int64_t *ops, int64_t max_ops,
                                const atomic_int *cancel)
{
    qdc_status s = QDC_OK;
    double qfloor = 0.0, afloor = 0.0;

    if (p->cfloor > 0.0) {
        live_worst(tm, &qfloor, &afloor);
        qfloor = fmax(p->cfloor, qfloor);
    }

    s = queue_below(tm, h, p->qcontract);
    while (s == QDC_OK && heap_size(h) > 0 && *ops < max_ops) {
        size_t from;
        qent e = heap_pop(h, &from);
        contract_cand best, c;
        int32_t ids[CONTRACT_MAX], vs[4 * CONTRACT_MAX];
        int have = 0, applied = 0;
        if (cancel && atomic_load(cancel))
            return QDC_ECANCEL;
        if (tm->tv[4 * (size_t)e.t] < 0 || tm->stamp[e.t] != e.stamp)
            continue;
        contract_inner(tm, p, mo, e.t, qfloor, afloor, &best, &have);
        for (int k = 0; k < 6; k++)
            if (contract_bedge_eval(tm, e.t, k, p->floor4, p->margin, &p->bound, &c))
                keep_better(&c, &best, &have);
        if (!have)
            continue;
        memo_collect(tm, best.old, best.nold, vs);
        if (best.bnd)
            s = tmesh_replace_surface(tm, best.old, best.nold,
                                      (const int32_t(*)[4])best.newt, best.nnew, best.dev,
                                      ids, &applied);
        else
            s = tmesh_replace(tm, best.old, best.nold, (const int32_t(*)[4])best.newt,
                              best.nnew, ids, &applied);
        if (s != QDC_OK || !applied)
            continue;
        tmesh_commit(tm);
        (*ops)++;
        st->contractions++;
        st->bcontractions += best.bnd;
        if (mo) {
            s = memo_applied(mo, tm, ids, best.nnew);
            memo_stamp(mo, vs, 4 * best.nold);
        }
    }
    return s;
}

static void count_flip(topo_stats *st, const flip_cand *c)
{
    if (c->kind == FLIP_EDGE) {
        st->edge_removals++;
        st->by_ring[c->nold]++;
    } else if (c->kind == FLIP_23) {
        st->flips23++;
    } else if (c->kind == FLIP_BEDGE) {
        st->bflips++;
    } else if (c->kind == FLIP_PEEL) {
        st->peels++;
    } else {
        st->multiface++;
    }
}

/* Evaluation ahead of the queue, on every thread: the flips of the tets a
 * pass will take next (the next PRE_WINDOW of its sorted queue, and the tets
 * made since, in the heap, that come before the last of those) are found at
 * once, each read from the mesh as it stands (best_flip reads the mesh and the
 * memo only), and the pass takes a tet's result when nothing it read has
 * changed since (the memo's test for skipping a failed tet, memo_same), else
 * evaluates it again: the same flips in the same order as one thread
 * evaluating each tet in its turn, whatever the thread count. */
enum { PRE_WINDOW = 1024, PRE_POOL = 4096 };

typedef struct {
    flip_cand c;
    int32_t t;
    uint32_t stamp; /* t's when evaluated */
    uint32_t at;    /* the memo's epoch then */
    int have;
    unsigned efail;
} pre_ent;

typedef struct {
    pre_ent *e;    /* PRE_POOL entries, or NULL: no evaluation ahead */
    int32_t n;     /* entries in use */
    int32_t *slot; /* per tet slot: its entry, or -1 (scap slots) */
    int32_t scap;
    int32_t *bfs;  /* PRE_POOL: heap indices to visit */
    size_t until;  /* the sorted queue's entries before this were taken in */
    int64_t since; /* pops since the last fill */
    int64_t used;  /* results taken */
} pre_win;

static void pre_free(pre_win *pw)
{
    qdc_free(pw->e);
    qdc_free(pw->slot);
    qdc_free(pw->bfs);
}

/* Tet q->t a target of the fill, if live, unchanged and not skipped. */
static void pre_take(const tmesh *tm, const memo *mo, const qent *q, pre_win *pw)
{
    if (pw->n == PRE_POOL || tm->tv[4 * (size_t)q->t] < 0 ||
        tm->stamp[q->t] != q->stamp || pw->slot[q->t] >= 0 || memo_skip(mo, tm, q->t))
        return;
    pw->slot[q->t] = pw->n;
    pw->e[pw->n].t = q->t;
    pw->e[pw->n++].stamp = q->stamp;
}

/* The heap's entries before bound (NULL: any), from the top, into the pool. */
static void pre_take_heap(const tmesh *tm, const memo *mo, const heap *h,
                          const qent *bound, pre_win *pw)
{
    size_t nb = 0;

    if (h->n > 0)
        pw->bfs[nb++] = 0;
    for (size_t k = 0; k < nb && pw->n < PRE_POOL; k++) {
        size_t i = (size_t)pw->bfs[k];
        if (bound && !before(&h->a[i], bound))
            continue;
        pre_take(tm, mo, &h->a[i], pw);
        for (size_t c = 2 * i + 1; c <= 2 * i + 2 && c < h->n && nb < PRE_POOL; c++)
            pw->bfs[nb++] = (int32_t)c;
    }
}

/* A new pool: the sorted queue's entries from `from` on, the heap's before
 * the last of them, evaluated in parallel. QDC_ENOMEM. */
static qdc_status pre_fill(const tmesh *tm, const topo_params *p, const memo *mo,
                           const heap *h, size_t from, pre_win *pw)
{
    size_t end = h->sn - from < PRE_WINDOW ? h->sn : from + PRE_WINDOW;

    for (int32_t k = 0; k < pw->n; k++)
        pw->slot[pw->e[k].t] = -1;
    pw->n = 0;
    if (tm->cap > pw->scap) {
        int32_t *g = qdc_realloc(pw->slot, (size_t)tm->cap * sizeof *g);
        if (!g)
            return QDC_ENOMEM;
        for (int32_t t = pw->scap; t < tm->cap; t++)
            g[t] = -1;
        pw->slot = g;
        pw->scap = tm->cap;
    }
    for (size_t i = from; i < end; i++)
        pre_take(tm, mo, &h->s[i], pw);
    pre_take_heap(tm, mo, h, end > from ? &h->s[end - 1] : NULL, pw);
#pragma omp parallel for schedule(dynamic, 8)
    for (int32_t k = 0; k < pw->n; k++) {
        pre_ent *x = &pw->e[k];
        x->have = best_flip(tm, x->t, p, mo, &x->c, &x->efail);
        x->at = mo->epoch;
    }
    pw->until = end;
    pw->since = 0;
    return QDC_OK;
}

/* The best flip of t, queue entry `from` (SIZE_MAX: from the heap), into *c
 * (*have): the pool's result when still good, else evaluated now; a new pool
 * first when the pass reached the end of the sorted queue's part, or missed
 * the pool well after its fill. The failures are recorded in mo (may be
 * NULL). QDC_ENOMEM. */
static qdc_status pass_eval(const tmesh *tm, const topo_params *p, memo *mo,
                            const heap *h, size_t from, int32_t t, pre_win *pw,
                            flip_cand *c, int *have)
{
    unsigned efail = 0;
    int32_t k = -1;

    if (pw->e) {
        k = t < pw->scap ? pw->slot[t] : -1;
        if ((from != SIZE_MAX && from >= pw->until) ||
            (k < 0 && pw->since++ >= PRE_WINDOW / 4)) {
            qdc_status s = pre_fill(tm, p, mo, h, from != SIZE_MAX ? from : h->si, pw);
            if (s != QDC_OK)
                return s;
            k = t < pw->scap ? pw->slot[t] : -1;
        }
    }
    if (k >= 0 && pw->e[k].stamp == tm->stamp[t] && memo_same(mo, tm, t, pw->e[k].at)) {
        *have = pw->e[k].have;
        efail = pw->e[k].efail;
        if (*have)
            *c = pw->e[k].c;
        pw->used++;
    } else {
        *have = best_flip(tm, t, p, mo, c, &efail);
    }
    if (mo)
        memo_fail_edges(mo, tm, t, efail);
    return QDC_OK;
}

/* The flips of one pass: the live tets below qgoal, worst first, each given
 * its best flip; the new tets below qgoal queued too. mo (NULL: none) skips
 * tets known to fail and lets the pass evaluate ahead on every thread. Adds to
 * *ops and st. */
static qdc_status flip_pass(tmesh *tm, const topo_params *p, heap *h, memo *mo,
                            topo_stats *st, int64_t *ops, int64_t max_ops,
                            const atomic_int *cancel)
{
    qdc_status s = queue_below(tm, h, p->qgoal);
    pre_win pw = {0};

    if (mo && omp_get_max_threads() > 1 &&
        (!(pw.e = qdc_malloc(PRE_POOL * sizeof *pw.e)) ||
         !(pw.bfs = qdc_malloc(PRE_POOL * sizeof *pw.bfs))))
        s = QDC_ENOMEM;
    while (s == QDC_OK && heap_size(h) > 0 && *ops < max_ops) {
        size_t from;
        qent e = heap_pop(h, &from);
        flip_cand c;
        int32_t ids[2 * FLIP_MAXRING];
        int applied = 0, have = 0;
        if (cancel && atomic_load(cancel))
            s = QDC_ECANCEL;
        if (s != QDC_OK || tm->tv[4 * (size_t)e.t] < 0 || tm->stamp[e.t] != e.stamp)
            continue; /* removed since it was queued */
        if (mo && memo_skip(mo, tm, e.t))
            continue;
        st->visits++;
        s = pass_eval(tm, p, mo, h, from, e.t, &pw, &c, &have);
        if (s != QDC_OK)
            continue;
        if (!have) {
            if (mo && e.t < mo->cap)
                mo->fail[e.t] = mo->epoch;
            continue;
        }
        if (c.kind == FLIP_BEDGE || c.kind == FLIP_PEEL)
            s = tmesh_replace_surface(tm, c.old, c.nold, (const int32_t(*)[4])c.newt,
                                      c.nnew, c.dev, ids, &applied);
        else
            s = tmesh_replace(tm, c.old, c.nold, (const int32_t(*)[4])c.newt, c.nnew, ids,
                              &applied);
        if (s != QDC_OK || !applied)
            continue;
        tmesh_commit(tm);
        (*ops)++;
        count_flip(st, &c);
        if (mo)
            s = memo_applied(mo, tm, ids, c.nnew);
        for (int j = 0; j < c.nnew && s == QDC_OK; j++)
            if (tm->q[ids[j]] < p->qgoal)
                s = heap_push(h, tm, ids[j]);
    }
    st->ahead += pw.used;
    pre_free(&pw);
    return s;
}

qdc_status topo_improve(tmesh *tm, const topo_params *p, topo_stats *st,
                        const atomic_int *cancel)
{
    qdc_status s = QDC_OK;
    heap h = {0};
    topo_stats local;
    int64_t ops = 0, max_ops = p->max_ops > 0 ? p->max_ops : 4 * (int64_t)tm->nlive;
    /* the boundary operations read more than the memo follows (the stars of
     * the ring's vertices, the surface's deviation): no memo under a bound */
    memo mo = {0}, *use = p->bound.hausd > 0 || p->recheck ? NULL : &mo;

    if (!st)
        st = &local;
    memset(st, 0, sizeof *st);
    st->nt_in = tm->nlive;
    st->nv_in = tm->nv;
    if (p->split) {
        int64_t ns = 0;
        s = split_long_edges(tm, p->lsplit, p->qsplit, p->sshare, &ns, cancel);
        st->splits = ns;
        st->insertions += ns;
        ops += ns;
    }
    if (use && s == QDC_OK)
        s = memo_init(&mo, tm, p->contract && p->cfloor > 0.0 ? 2 : 1);
    for (int r = 0; r < p->rounds && s == QDC_OK; r++) {
        int64_t before = ops;
        s = flip_pass(tm, p, &h, use, st, &ops, max_ops, cancel);
        if (s == QDC_OK && p->contract)
            s = contract_pass(tm, p, &h, use, st, &ops, max_ops, cancel);
        if (s == QDC_OK && p->insert)
            s = insert_pass(tm, p, &h, use, st, &ops, max_ops, cancel);
        if (s != QDC_OK || ops == before || ops >= max_ops)
            break;
    }
    memo_free(&mo);
    qdc_free(h.a);
    qdc_free(h.s);
    st->nt_out = tm->nlive;
    st->nv_out = tm->nv;
    return s;
}

qdc_status topo_flip_arrays(int32_t nv, const double *xyz, int32_t nt,
                            const int32_t *tets, const int32_t *region,
                            const uint8_t *rev, const topo_params *p,
                            const atomic_int *cancel, int32_t *nt_out, int32_t **tets_out,
                            int32_t **region_out, topo_stats *st, qdc_error *err)
{
    topo_params q = *p;
    double *x = NULL;
    int32_t n = 0;
    qdc_status s;

    q.insert = 0;
    q.contract = 0;
    q.split = 0;
    s = topo_full_arrays(nv, xyz, nt, tets, region, rev, &q, cancel, &n, &x, nt_out,
                         tets_out, region_out, NULL, NULL, st, err);
    qdc_free(x);
    return s;
}

static int key_cmp(const void *x, const void *y)
{
    const int32_t *a = x, *b = y;

    for (int s = 0; s < 3; s++)
        if (a[s] != b[s])
            return a[s] < b[s] ? -1 : 1;
    return 0;
}

/* sf's triangles after the run: the input's whose faces were not removed from
 * the boundary, then each boundary face a boundary operation made (with a ref),
 * in slot order, oriented as the input's triangles it replaced. */
static qdc_status surface_out(tmesh *tm, topo_surface *sf)
{
    int32_t nnew = 0, k = 0;

    if (tm->ngone > 0)
        qsort(tm->gone, (size_t)tm->ngone, sizeof *tm->gone, key_cmp);
    for (int32_t t = 0; t < tm->hi; t++)
        for (int i = 0; i < 4 && tm->tv[4 * (size_t)t] >= 0; i++)
            nnew += tm->adj[4 * (size_t)t + i] < 0 && (tm->fsurf[t] >> i & 1) &&
                    tm->fref[4 * (size_t)t + i] != TMESH_NOREF;
    sf->tris_out =
        qdc_mallocn(3 * ((size_t)sf->ntri + (size_t)nnew) + 3, sizeof *sf->tris_out);
    sf->refs_out = qdc_mallocn((size_t)sf->ntri + (size_t)nnew + 1, sizeof *sf->refs_out);
    if (!sf->tris_out || !sf->refs_out)
        return QDC_ENOMEM;
    sf->removed = 0;
    for (int32_t s = 0; s < sf->ntri; s++) {
        const int32_t *tr = sf->tris + 3 * (size_t)s;
        int32_t key[3];
        tet_sort3(tr[0], tr[1], tr[2], key);
        if (tm->ngone > 0 &&
            bsearch(key, tm->gone, (size_t)tm->ngone, sizeof *tm->gone, key_cmp)) {
            sf->removed++;
            continue;
        }
        memcpy(sf->tris_out + 3 * (size_t)k, tr, 3 * sizeof *tr);
        sf->refs_out[k++] = sf->refs ? sf->refs[s] : 0;
    }
    sf->added = nnew;
    for (int32_t t = 0; t < tm->hi; t++)
        for (int i = 0; i < 4 && tm->tv[4 * (size_t)t] >= 0; i++) {
            const int32_t *tt = tm->tv + 4 * (size_t)t;
            int32_t *o = sf->tris_out + 3 * (size_t)k;
            if (tm->adj[4 * (size_t)t + i] >= 0 || !(tm->fsurf[t] >> i & 1) ||
                tm->fref[4 * (size_t)t + i] == TMESH_NOREF)
                continue;
            o[0] = tt[tet_face_of[i][0]];
            o[1] = tt[tet_face_of[i][1]];
            o[2] = tt[tet_face_of[i][2]];
            if (tm->fsurf[t] >> (4 + i) & 1) {
                o[1] = tt[tet_face_of[i][2]];
                o[2] = tt[tet_face_of[i][1]];
            }
            sf->refs_out[k++] = tm->fref[4 * (size_t)t + i];
        }
    sf->ntri_out = k;
    return QDC_OK;
}

/* The vertices after the run: the input's still used, or never used, in their
 * order, then the new ones used (a contraction leaves its vertex unused);
 * tets renumbered in place, *vmap (if asked) each input vertex's new index. */
static qdc_status compact(const tmesh *tm, int32_t nv, int32_t nt, const int32_t *tets,
                          int32_t nt_out, int32_t *tets_out, int32_t *nv_out,
                          double **xyz_out, int32_t **vmap)
{
    int32_t *map = qdc_mallocn((size_t)tm->nv + 1, sizeof *map), n = 0;
    uint8_t *in = qdc_calloc((size_t)tm->nv + 1, 1),
            *out = qdc_calloc((size_t)tm->nv + 1, 1);
    qdc_status s = QDC_OK;

    *xyz_out = qdc_mallocn(3 * (size_t)tm->nv + 3, sizeof **xyz_out);
    if (vmap)
        *vmap = qdc_mallocn((size_t)nv + 1, sizeof **vmap);
    if (!map || !in || !out || !*xyz_out || (vmap && !*vmap)) {
        s = QDC_ENOMEM;
        goto done;
    }
    for (int64_t k = 0; k < 4 * (int64_t)nt; k++)
        in[tets[k]] = 1;
    for (int64_t k = 0; k < 4 * (int64_t)nt_out; k++)
        out[tets_out[k]] = 1;
    for (int32_t v = 0; v < tm->nv; v++) {
        int keep = v < nv ? !in[v] || out[v] : out[v];
        map[v] = keep ? n : -1;
        if (keep) {
            memcpy(*xyz_out + 3 * (size_t)n, tm->xyz + 3 * (size_t)v,
                   3 * sizeof **xyz_out);
            n++;
        }
    }
    for (int64_t k = 0; k < 4 * (int64_t)nt_out; k++)
        tets_out[k] = map[tets_out[k]];
    if (vmap)
        memcpy(*vmap, map, (size_t)nv * sizeof *map);
    *nv_out = n;
done:
    if (s != QDC_OK) {
        qdc_free(*xyz_out);
        *xyz_out = NULL;
        if (vmap) {
            qdc_free(*vmap);
            *vmap = NULL;
        }
    }
    qdc_free(map);
    qdc_free(in);
    qdc_free(out);
    return s;
}

/* Each boundary face's fdev: the largest vdev of its corners (the bound the
 * rounds before spent there). */
static void seed_dev(tmesh *tm, const double *vdev)
{
    for (int32_t t = 0; t < tm->hi; t++)
        for (int i = 0; i < 4 && tm->tv[4 * (size_t)t] >= 0; i++) {
            const int32_t *tt = tm->tv + 4 * (size_t)t;
            double d = 0.0;
            if (tm->adj[4 * (size_t)t + i] >= 0)
                continue;
            for (int k = 0; k < 3; k++)
                d = fmax(d, vdev[tt[tet_face_of[i][k]]]);
            tm->fdev[4 * (size_t)t + i] = d;
        }
}

/* sf->vdev and sf->vop at the corners of the boundary faces the run made. */
static void spent_out(const tmesh *tm, int32_t nv, topo_surface *sf)
{
    for (int32_t t = 0; t < tm->hi; t++)
        for (int i = 0; i < 4 && tm->tv[4 * (size_t)t] >= 0; i++) {
            const int32_t *tt = tm->tv + 4 * (size_t)t;
            if (tm->adj[4 * (size_t)t + i] >= 0 || !(tm->fsurf[t] >> i & 1))
                continue;
            for (int k = 0; k < 3; k++) {
                int32_t v = tt[tet_face_of[i][k]];
                if (v >= nv)
                    continue; /* a new vertex is inside: on no boundary face */
                if (sf->vdev)
                    sf->vdev[v] = fmax(sf->vdev[v], tm->fdev[4 * (size_t)t + i]);
                if (sf->vop)
                    sf->vop[v] = 1;
            }
        }
}

qdc_status topo_full_arrays(int32_t nv, const double *xyz, int32_t nt,
                            const int32_t *tets, const int32_t *region,
                            const uint8_t *rev, const topo_params *p,
                            const atomic_int *cancel, int32_t *nv_out, double **xyz_out,
                            int32_t *nt_out, int32_t **tets_out, int32_t **region_out,
                            int32_t **vmap_out, topo_surface *sf, topo_stats *st,
                            qdc_error *err)
{
    tmesh *tm = NULL;
    qdc_status s = tmesh_new(nv, xyz, nt, tets, region, rev, &tm, err);

    if (s == QDC_OK && p->nkeep > 0 && tmesh_keep_tris(tm, p->nkeep, p->keep) != QDC_OK)
        s = qdc_fail(err, QDC_ENOMEM, "out of memory");

    if (sf) {
        sf->tris_out = NULL;
        sf->refs_out = NULL;
        sf->ntri_out = sf->removed = sf->added = 0;
    }
    if (s == QDC_OK && sf)
        s = tmesh_set_surface(tm, sf->ntri, sf->tris, sf->refs);
    if (s == QDC_OK && sf && sf->vdev)
        seed_dev(tm, sf->vdev);
    if (s == QDC_OK)
        s = topo_improve(tm, p, st, cancel);
    if ((s == QDC_OK || s == QDC_ECANCEL) && sf) {
        qdc_status s2 = surface_out(tm, sf);
        if (s2 != QDC_OK)
            s = s2;
        if (sf->vdev || sf->vop)
            spent_out(tm, nv, sf);
    }
    if (s == QDC_OK || s == QDC_ECANCEL) {
        qdc_status s2 = tmesh_export(tm, nt_out, tets_out, region ? region_out : NULL);
        if (s2 == QDC_OK)
            s2 = compact(tm, nv, nt, tets, *nt_out, *tets_out, nv_out, xyz_out, vmap_out);
        if (s2 != QDC_OK)
            s = s2;
    }
    tmesh_free(tm);
    return s;
}
