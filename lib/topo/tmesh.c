/* tmesh.c - the mutable tet mesh of the topology layer: building it (faces
 * paired by core/mesh.c's matcher), cavity replacement with a journal, export,
 * check. */
#include "topo/tmesh.h"

#include "core/mesh_int.h"
#include "core/tet.h"
#include "geom/metric_int.h"
#include "topo/exact.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const int tmesh_edge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

/* Largest cavity tmesh_replace takes: edge removal of a ring of 10 makes 16
 * tets out of 10; multi-face removal stays below these too; an edge
 * contraction takes a vertex's star (contract.h). */
enum { CAV_OLD = 64, CAV_NEW = 64 };

enum { J_NEW, J_DEL, J_ADJ, J_FACE };

struct tmesh_jent {
    int kind;
    int32_t id;
    int32_t v[4];
    int32_t a[4];
    int32_t tag;
    uint8_t f, e, rev, fs;
    double q;
    uint32_t stamp;
    int32_t fref[4]; /* the surface's, when attached */
    double fdev[4];
};

/* The sorted vertices of face i of the tet with vertices v. */
static void face_key(const int32_t *v, int i, int32_t k[3])
{
    tet_sort3(v[tet_face_of[i][0]], v[tet_face_of[i][1]], v[tet_face_of[i][2]], k);
}

static int same_key(const int32_t a[3], const int32_t b[3])
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

static qdc_status grow_tets(tmesh *tm, int32_t need)
{
    int32_t cap;

    if (need <= tm->cap)
        return QDC_OK;
    if (need > INT32_MAX / 4 - 1024)
        return QDC_ENOMEM;
    cap = need + need / 4 + 64;
    if (cap > INT32_MAX / 4)
        cap = INT32_MAX / 4;
#define GROW(p, n)                                                                       \
    do {                                                                                 \
        void *np_ = qdc_realloc((p), (size_t)(n) * sizeof *(p));                         \
        if (!np_)                                                                        \
            return QDC_ENOMEM;                                                           \
        (p) = np_;                                                                       \
    } while (0)
    GROW(tm->tv, 4 * (size_t)cap);
    GROW(tm->adj, 4 * (size_t)cap);
    GROW(tm->tag, cap);
    GROW(tm->rev, cap);
    GROW(tm->fcons, cap);
    GROW(tm->econs, cap);
    GROW(tm->q, cap);
    GROW(tm->stamp, cap);
    GROW(tm->freel, cap);
    GROW(tm->mark, cap);
    if (tm->fref) {
        GROW(tm->fref, 4 * (size_t)cap);
        GROW(tm->fdev, 4 * (size_t)cap);
        GROW(tm->fsurf, cap);
    }
#undef GROW
    memset(tm->mark + tm->cap, 0, (size_t)(cap - tm->cap));
    memset(tm->stamp + tm->cap, 0, (size_t)(cap - tm->cap) * sizeof *tm->stamp);
    for (int32_t t = tm->cap; t < cap; t++)
        tm->tv[4 * (size_t)t] = -1;
    tm->cap = cap;
    return QDC_OK;
}

static qdc_status grow_journal(tmesh *tm, int32_t need)
{
    tmesh_jent *j;

    if (need <= tm->capjr)
        return QDC_OK;
    need = need < INT32_MAX / 2 ? 2 * need : need;
    j = qdc_realloc(tm->jr, (size_t)need * sizeof *j);
    if (!j)
        return QDC_ENOMEM;
    tm->jr = j;
    tm->capjr = need;
    return QDC_OK;
}

void tmesh_free(tmesh *tm)
{
    if (!tm)
        return;
    qdc_free(tm->xyz);
    qdc_free(tm->vcons);
    qdc_free(tm->tv);
    qdc_free(tm->adj);
    qdc_free(tm->tag);
    qdc_free(tm->rev);
    qdc_free(tm->fcons);
    qdc_free(tm->econs);
    qdc_free(tm->q);
    qdc_free(tm->stamp);
    qdc_free(tm->freel);
    qdc_free(tm->mark);
    qdc_free(tm->jr);
    qdc_free(tm->fref);
    qdc_free(tm->fdev);
    qdc_free(tm->fsurf);
    qdc_free(tm->gone);
    qdc_free(tm->vdeg);
    qdc_free(tm);
}

double tmesh_quality_above(const tmesh *tm, const int32_t v[4], double floor4,
                           double qneed)
{
    const double *p0 = tm->xyz + 3 * (size_t)v[0], *p1 = tm->xyz + 3 * (size_t)v[1];
    const double *p2 = tm->xyz + 3 * (size_t)v[2], *p3 = tm->xyz + 3 * (size_t)v[3];
    metric_parts pt;
    double q;

    metric_parts_for(OPT_METRIC_MIMR, p0, p1, p2, p3, &pt);
    /* the cube of the mean ratio, a few roundings from the cube of
     * tmesh_quality's: below qneed^3 by far more than those, the mean ratio
     * is below qneed (and a tet inverted in floating point has one <= 0) */
    if (qneed > 0.0 &&
        metric_mean_ratio_cubed(&pt) < qneed * qneed * qneed * (1.0 - 1e-9))
        return -4.0;
    if (exact_orient3d(p0, p1, p2, p3) <= 0)
        return -2.0;
    q = metric_mean_ratio(&pt);
    if (q < floor4 && tm->vcons[v[0]] && tm->vcons[v[1]] && tm->vcons[v[2]] &&
        tm->vcons[v[3]])
        return -3.0;
    return q;
}

double tmesh_quality(const tmesh *tm, const int32_t v[4], double floor4)
{
    return tmesh_quality_above(tm, v, floor4, 0.0); /* no threshold: no filter */
}

/* Edge bits: every edge of a constrained face, in every tet that has it (a
 * tet may touch the surface by an edge alone). Edges bucketed by lower vertex. */
static qdc_status mark_edges(tmesh *tm, int32_t nt)
{
    int32_t nv = tm->nv, ne = 0;
    int32_t *ptr = qdc_calloc((size_t)nv + 1, sizeof *ptr), *hiv = NULL;
    qdc_status st = QDC_OK;

    if (!ptr)
        return QDC_ENOMEM;
    for (int pass = 0; pass < 2; pass++) {
        for (int32_t t = 0; t < nt; t++)
            for (int i = 0; i < 4; i++) {
                if (!(tm->fcons[t] >> i & 1))
                    continue;
                int32_t k[3];
                face_key(tm->tv + 4 * (size_t)t, i, k);
                for (int s = 0; s < 3; s++) {
                    int32_t lo = k[s == 2 ? 1 : 0], hv = k[s == 0 ? 1 : 2];
                    if (pass == 0)
                        ptr[lo + 1]++;
                    else
                        hiv[ptr[lo]++] = hv;
                }
            }
        if (pass == 0) {
            for (int32_t v = 0; v < nv; v++)
                ptr[v + 1] += ptr[v];
            ne = ptr[nv];
            hiv = qdc_mallocn((size_t)ne + 1, sizeof *hiv);
            if (!hiv) {
                st = QDC_ENOMEM;
                goto out;
            }
        }
    }
    /* pass 1 advanced each start to the next bucket's: shift back */
    for (int32_t v = nv; v > 0; v--)
        ptr[v] = ptr[v - 1];
    ptr[0] = 0;
    for (int32_t t = 0; t < nt; t++) {
        const int32_t *tt = tm->tv + 4 * (size_t)t;
        uint8_t bits = 0;
        for (int e = 0; e < 6; e++) {
            int32_t u = tt[tmesh_edge[e][0]], w = tt[tmesh_edge[e][1]];
            int32_t lo = u < w ? u : w, hv = u < w ? w : u;
            for (int32_t i = ptr[lo]; i < ptr[lo + 1]; i++)
                if (hiv[i] == hv) {
                    bits |= (uint8_t)(1u << e);
                    break;
                }
        }
        tm->econs[t] = bits;
    }
out:
    qdc_free(ptr);
    qdc_free(hiv);
    return st;
}

qdc_status tmesh_new(int32_t nv, const double *xyz, int32_t nt, const int32_t *tets,
                     const int32_t *region, const uint8_t *rev, tmesh **out,
                     qdc_error *err)
{
    qdc_status st = QDC_OK;
    tmesh *tm;

    *out = NULL;
    if (nv <= 0 || nt <= 0)
        return qdc_fail(err, QDC_EINVAL, "empty mesh");
    tm = qdc_calloc(1, sizeof *tm);
    if (!tm)
        return QDC_ENOMEM;
    tm->nv = nv;
    tm->vcap = nv;
    tm->xyz = qdc_mallocn(3 * (size_t)nv, sizeof *tm->xyz);
    tm->vcons = qdc_calloc((size_t)nv, 1);
    tm->vdeg = qdc_calloc((size_t)nv, sizeof *tm->vdeg);
    if (!tm->xyz || !tm->vcons || !tm->vdeg) {
        st = QDC_ENOMEM;
        goto out;
    }
    memcpy(tm->xyz, xyz, 3 * (size_t)nv * sizeof *xyz);
    st = grow_tets(tm, nt);
    if (st != QDC_OK)
        goto out;
    for (int32_t t = 0; t < nt; t++) {
        const int32_t *tt = tets + 4 * (size_t)t;
        for (int a = 0; a < 4; a++) {
            if (tt[a] < 0 || tt[a] >= nv) {
                st = qdc_fail(err, QDC_EMESH, "tet %ld: vertex index out of range",
                              (long)t);
                goto bad_tet;
            }
            for (int b = 0; b < a; b++)
                if (tt[b] == tt[a]) {
                    st = qdc_fail(err, QDC_EMESH, "tet %ld: a repeated vertex", (long)t);
                    goto bad_tet;
                }
        }
        memcpy(tm->tv + 4 * (size_t)t, tt, 4 * sizeof *tt);
        for (int a = 0; a < 4; a++)
            tm->vdeg[tt[a]]++;
        tm->tag[t] = region ? region[t] : 0;
        tm->rev[t] = rev ? rev[t] != 0 : 0;
        tm->stamp[t] = 1;
        continue;
    bad_tet:
        if (err)
            err->index = t;
        goto out;
    }
    tm->hi = nt;
    tm->nlive = nt;
    /* the face pairs as core/mesh.c finds them, in parallel (this file's
     * serial counting sort and pairing was 0.35 s of each round's 0.55 s
     * set-up at 1M tets) */
    st = mesh_face_pairs(nv, nt, tm->tv, tm->adj, err);
    if (st != QDC_OK)
        goto out;
    for (int32_t t = 0; t < nt; t++) {
        uint8_t f = 0;
        for (int i = 0; i < 4; i++) {
            int32_t n = tm->adj[4 * (size_t)t + i];
            if (n < 0 || tm->tag[n / 4] != tm->tag[t]) {
                f |= (uint8_t)(1u << i);
                for (int s = 0; s < 3; s++)
                    tm->vcons[tm->tv[4 * (size_t)t + tet_face_of[i][s]]] = 1;
            }
        }
        tm->fcons[t] = f;
    }
    st = mark_edges(tm, nt);
    if (st != QDC_OK)
        goto out;
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < nt; t++) /* in parallel: 0.1 of 0.5 s at 1M tets */
        tm->q[t] = tmesh_quality(tm, tm->tv + 4 * (size_t)t, -INFINITY);
    *out = tm;
    tm = NULL;
out:
    tmesh_free(tm);
    return st;
}

qdc_status tmesh_export(const tmesh *tm, int32_t *nt, int32_t **tets, int32_t **region)
{
    int32_t *tv = qdc_mallocn(4 * (size_t)tm->nlive + 4, sizeof *tv), *rg = NULL, k = 0;

    if (!tv)
        return QDC_ENOMEM;
    if (region) {
        rg = qdc_mallocn((size_t)tm->nlive + 1, sizeof *rg);
        if (!rg) {
            qdc_free(tv);
            return QDC_ENOMEM;
        }
    }
    for (int32_t t = 0; t < tm->hi; t++) {
        if (tm->tv[4 * (size_t)t] < 0)
            continue;
        memcpy(tv + 4 * (size_t)k, tm->tv + 4 * (size_t)t, 4 * sizeof *tv);
        if (tm->rev[t]) {
            tv[4 * (size_t)k] = tm->tv[4 * (size_t)t + 1];
            tv[4 * (size_t)k + 1] = tm->tv[4 * (size_t)t];
        }
        if (rg)
            rg[k] = tm->tag[t];
        k++;
    }
    *nt = k;
    *tets = tv;
    if (region)
        *region = rg;
    return QDC_OK;
}

static tmesh_jent *jpush(tmesh *tm, int kind, int32_t id)
{
    tmesh_jent *j = tm->jr + tm->njr++;
    j->kind = kind;
    j->id = id;
    return j;
}

/* The face data of t (bits and surface) into j. */
static void save_faces(const tmesh *tm, int32_t t, tmesh_jent *j)
{
    j->f = tm->fcons[t];
    j->e = tm->econs[t];
    if (tm->fref) {
        j->fs = tm->fsurf[t];
        memcpy(j->fref, tm->fref + 4 * (size_t)t, sizeof j->fref);
        memcpy(j->fdev, tm->fdev + 4 * (size_t)t, sizeof j->fdev);
    }
}

static void load_faces(tmesh *tm, int32_t t, const tmesh_jent *j)
{
    tm->fcons[t] = j->f;
    tm->econs[t] = j->e;
    if (tm->fref) {
        tm->fsurf[t] = j->fs;
        memcpy(tm->fref + 4 * (size_t)t, j->fref, sizeof j->fref);
        memcpy(tm->fdev + 4 * (size_t)t, j->fdev, sizeof j->fdev);
    }
}

static void del_tet(tmesh *tm, int32_t t)
{
    tmesh_jent *j = jpush(tm, J_DEL, t);
    memcpy(j->v, tm->tv + 4 * (size_t)t, sizeof j->v);
    memcpy(j->a, tm->adj + 4 * (size_t)t, sizeof j->a);
    j->tag = tm->tag[t];
    save_faces(tm, t, j);
    j->rev = tm->rev[t];
    j->q = tm->q[t];
    j->stamp = tm->stamp[t];
    for (int s = 0; tm->vdeg && s < 4; s++)
        tm->vdeg[tm->tv[4 * (size_t)t + s]]--;
    tm->tv[4 * (size_t)t] = -1;
    tm->freel[tm->nfree++] = t;
    tm->nlive--;
}

static int32_t new_tet(tmesh *tm)
{
    int from_hi = tm->nfree == 0;
    int32_t t = from_hi ? tm->hi++ : tm->freel[--tm->nfree];
    tmesh_jent *j = jpush(tm, J_NEW, t);
    j->a[0] = from_hi;
    j->stamp = tm->stamp[t];
    tm->stamp[t]++;
    tm->nlive++;
    return t;
}

static void set_adj(tmesh *tm, int32_t slot, int32_t val)
{
    tmesh_jent *j = jpush(tm, J_ADJ, slot);
    j->a[0] = tm->adj[slot];
    tm->adj[slot] = val;
}

void tmesh_commit(tmesh *tm)
{
    tm->njr = 0;
    tm->ngone_op = tm->ngone;
}

void tmesh_rollback(tmesh *tm)
{
    while (tm->njr > 0) {
        tmesh_jent *j = tm->jr + --tm->njr;
        int32_t t = j->id;
        switch (j->kind) {
        case J_ADJ:
            tm->adj[t] = j->a[0];
            break;
        case J_FACE:
            load_faces(tm, t, j);
            break;
        case J_NEW:
            for (int s = 0; tm->vdeg && s < 4; s++)
                tm->vdeg[tm->tv[4 * (size_t)t + s]]--;
            tm->tv[4 * (size_t)t] = -1;
            tm->stamp[t] = j->stamp;
            tm->nlive--;
            /* back where the slot came from: hi, else the free list's top */
            if (j->a[0])
                tm->hi--;
            else
                tm->freel[tm->nfree++] = t;
            break;
        default: /* J_DEL: its slot is the free list's top again */
            tm->nfree--;
            memcpy(tm->tv + 4 * (size_t)t, j->v, sizeof j->v);
            memcpy(tm->adj + 4 * (size_t)t, j->a, sizeof j->a);
            for (int s = 0; tm->vdeg && s < 4; s++)
                tm->vdeg[j->v[s]]++;
            tm->tag[t] = j->tag;
            load_faces(tm, t, j);
            tm->rev[t] = j->rev;
            tm->q[t] = j->q;
            tm->stamp[t] = j->stamp;
            tm->nlive++;
            break;
        }
    }
    tm->ngone = tm->ngone_op;
}

/* The constraint bit of edge (u, w) in the first of the tets old that has it, or
 * 0 for an edge none of them has (a new edge, inside the cavity). */
static uint8_t edge_bit(const tmesh *tm, const int32_t *old, int nold, int32_t u,
                        int32_t w)
{
    for (int o = 0; o < nold; o++) {
        const int32_t *tt = tm->tv + 4 * (size_t)old[o];
        for (int e = 0; e < 6; e++) {
            int32_t x = tt[tmesh_edge[e][0]], y = tt[tmesh_edge[e][1]];
            if ((x == u && y == w) || (x == w && y == u))
                return (uint8_t)(tm->econs[old[o]] >> e & 1);
        }
    }
    return 0;
}

/* Journal the face data of t before it changes. */
static qdc_status jface(tmesh *tm, int32_t t)
{
    qdc_status st = grow_journal(tm, tm->njr + 1);

    if (st == QDC_OK)
        save_faces(tm, t, jpush(tm, J_FACE, t));
    return st;
}

/* The edge index joining local vertices x and y. */
static int edge_of(int x, int y)
{
    for (int e = 0; e < 6; e++)
        if ((tmesh_edge[e][0] == x && tmesh_edge[e][1] == y) ||
            (tmesh_edge[e][0] == y && tmesh_edge[e][1] == x))
            return e;
    return 0;
}

/* Set the constraint bit of edge (u, w) in every tet around it, from tet t0
 * (journaled): both ways round from t0 until the boundary or back at t0. */
static qdc_status constrain_edge(tmesh *tm, int32_t t0, int32_t u, int32_t w)
{
    for (int dir = 0; dir < 2; dir++) {
        int32_t cur = t0, p = -1;
        int k = 0;
        for (int s = 0; s < 4; s++) {
            int32_t x = tm->tv[4 * (size_t)t0 + s];
            if (x != u && x != w && k++ == dir)
                p = x;
        }
        /* a shell has fewer tets than this; the bound guards a corrupt mesh */
        for (int guard = 0; guard < 4096; guard++) {
            const int32_t *tt = tm->tv + 4 * (size_t)cur;
            int e = edge_of(tmesh_local(tm, cur, u), tmesh_local(tm, cur, w));
            int32_t q = -1, nb;
            if (!(tm->econs[cur] >> e & 1)) {
                qdc_status st = jface(tm, cur);
                if (st != QDC_OK)
                    return st;
                tm->econs[cur] |= (uint8_t)(1u << e);
            }
            for (int s = 0; s < 4; s++)
                if (tt[s] != u && tt[s] != w && tt[s] != p)
                    q = tt[s];
            nb = tm->adj[4 * (size_t)cur + tmesh_local(tm, cur, p)];
            if (nb < 0)
                break;
            cur = nb / 4;
            p = q;
            if (cur == t0)
                return QDC_OK;
        }
    }
    return QDC_OK;
}

/* 1 when (u, w) is no edge of the cavity old but an edge of a tet around u
 * outside it; with x >= 0 the same for the face (u, w, x). The cavity's edges
 * (most of a new tet's) are answered before u's star is walked (it was walked
 * first, then the edge often found in the cavity: on the 1M-tet ball-scan of
 * scripts/corpus.py, --topology flips' first round of flips took 14.7 CPU s
 * with the walk first, 11.6 without). */
static int new_edge_taken(const tmesh *tm, const int32_t *old, int nold, int32_t u,
                          int32_t w, int32_t x)
{
    int32_t star[256];
    int n = -1, first = -1;

    for (int o = 0; o < nold; o++)
        if (tmesh_local(tm, old[o], u) >= 0) {
            if (x < 0 && tmesh_local(tm, old[o], w) >= 0)
                return 0; /* an edge of the cavity */
            if (first < 0)
                first = o;
        }
    if (first >= 0)
        n = tmesh_star(tm, old[first], u, star, 256);
    if (n >= 0 && n != tm->vdeg[u])
        return 1; /* a pinched star: its other piece may hold the edge */
    for (int k = 0; k < n; k++)
        if (!tm->mark[star[k]] && tmesh_local(tm, star[k], w) >= 0 &&
            (x < 0 || tmesh_local(tm, star[k], x) >= 0))
            return 1;
    return 0;
}

enum { LINK_BND = INT16_MIN };

static qdc_status replace_impl(tmesh *tm, const int32_t *old, int nold,
                               const int32_t (*newt)[4], int nnew, int32_t *new_ids,
                               int *applied, int bnd, double dev)
{
    int32_t okey[4 * CAV_OLD][3], onb[4 * CAV_OLD], oslot[4 * CAV_OLD], ids[CAV_NEW];
    uint8_t obit[4 * CAV_OLD], oused[4 * CAV_OLD], ebits[CAV_NEW];
    int16_t link[CAV_NEW][4]; /* >= 0: outer face; LINK_BND: a new boundary face;
                               * else -1 - (4 * new tet + face) */
    double qn[CAV_NEW], bdev = 0.0;
    int nout = 0, ok = 1, nsrc = 0, nmade = 0;
    int32_t tag, sref = TMESH_NOREF;
    uint8_t rev, srev = 0;
    qdc_status st;

    *applied = 0;
    if (nold < 1 || nold > CAV_OLD || nnew < (bnd ? 0 : 1) || nnew > CAV_NEW ||
        (bnd && !tm->fref))
        return QDC_OK;
    tag = tm->tag[old[0]];
    rev = tm->rev[old[0]];
    for (int o = 0; o < nold; o++)
        if (tm->tv[4 * (size_t)old[o]] < 0 || tm->tag[old[o]] != tag ||
            tm->mark[old[o]] || tm->q[old[o]] < -1.0)
            ok = 0;
        else
            tm->mark[old[o]] = 1;
    for (int j = 0; ok && j < nnew; j++) {
        qn[j] = tmesh_quality(tm, newt[j], -INFINITY);
        if (qn[j] < -1.0)
            ok = 0;
    }
    /* the cavity's outer faces, then each new face linked to one of them or to
     * the one other new face with its vertices */
    for (int o = 0; ok && o < nold; o++)
        for (int i = 0; i < 4; i++) {
            int32_t n = tm->adj[4 * (size_t)old[o] + i];
            if (n >= 0 && tm->mark[n / 4])
                continue;
            face_key(tm->tv + 4 * (size_t)old[o], i, okey[nout]);
            onb[nout] = n;
            oslot[nout] = 4 * old[o] + i;
            obit[nout] = (uint8_t)(tm->fcons[old[o]] >> i & 1);
            oused[nout] = 0;
            nout++;
        }
    for (int j = 0; ok && j < nnew; j++)
        for (int i = 0; ok && i < 4; i++) {
            int32_t k[3];
            int found = 0;
            face_key(newt[j], i, k);
            for (int o = 0; o < nout && !found; o++)
                if (!oused[o] && same_key(k, okey[o])) {
                    oused[o] = 1;
                    link[j][i] = (int16_t)o;
                    found = 1;
                }
            for (int j2 = 0; j2 < nnew && !found; j2++)
                for (int i2 = 0; i2 < 4 && !found; i2++) {
                    int32_t k2[3];
                    if (j2 == j)
                        continue;
                    face_key(newt[j2], i2, k2);
                    if (same_key(k, k2)) {
                        link[j][i] = (int16_t)(-1 - (4 * j2 + i2));
                        found = 1;
                    }
                }
            if (!found && bnd) {
                link[j][i] = LINK_BND;
                nmade++;
            } else if (!found) {
                ok = 0;
            }
        }
    /* an outer face left open: a boundary face removed (the source of the new
     * ones' ref), or an interior face that becomes boundary */
    for (int o = 0; ok && o < nout; o++) {
        int32_t t = oslot[o] / 4, i = oslot[o] % 4;
        if (oused[o])
            continue;
        if (!bnd || (onb[o] >= 0 && obit[o])) {
            ok = 0; /* not allowed here, or an interface */
        } else if (onb[o] >= 0) {
            nmade++;
        } else {
            int32_t r = tm->fref[oslot[o]];
            uint8_t rv = (uint8_t)(tm->fsurf[t] >> (4 + i) & 1);
            if (nsrc && (r != sref || rv != srev))
                ok = 0;
            sref = r;
            srev = rv;
            if (tm->fdev[oslot[o]] > bdev)
                bdev = tm->fdev[oslot[o]];
            nsrc++;
        }
    }
    if (bnd && (!nsrc || !nmade))
        ok = 0;
    /* a new edge, and a face inside the cavity, must be new to the mesh: one
     * elsewhere (where the input overlaps itself, at a pinched vertex) would
     * leave faces of three tets */
    for (int j = 0; ok && j < nnew; j++)
        for (int e = 0; ok && e < 6; e++)
            ok = !new_edge_taken(tm, old, nold, newt[j][tmesh_edge[e][0]],
                                 newt[j][tmesh_edge[e][1]], -1);
    for (int j = 0; ok && j < nnew; j++)
        for (int i = 0; ok && i < 4; i++)
            if (link[j][i] < 0)
                ok = !new_edge_taken(tm, old, nold, newt[j][tet_face_of[i][0]],
                                     newt[j][tet_face_of[i][1]],
                                     newt[j][tet_face_of[i][2]]);
    for (int j = 0; ok && j < nnew; j++) {
        ebits[j] = 0;
        for (int e = 0; e < 6; e++)
            ebits[j] |= (uint8_t)(edge_bit(tm, old, nold, newt[j][tmesh_edge[e][0]],
                                           newt[j][tmesh_edge[e][1]])
                                  << e);
    }
    for (int o = 0; o < nold; o++)
        tm->mark[old[o]] = 0;
    if (!ok)
        return QDC_OK;
    st = grow_tets(tm, tm->hi + nnew);
    if (st == QDC_OK)
        st = grow_journal(tm, nold + nnew + 2 * nout + 1);
    if (st == QDC_OK && tm->ngone + nsrc > tm->capgone) {
        int32_t cap = 2 * (tm->ngone + nsrc) + 64;
        int32_t(*g)[3] = qdc_realloc(tm->gone, (size_t)cap * sizeof *g);
        if (!g)
            st = QDC_ENOMEM;
        else {
            tm->gone = g;
            tm->capgone = cap;
        }
    }
    if (st != QDC_OK)
        return st;
    tm->njr = 0;
    tm->ngone_op = tm->ngone;
    bdev += dev;
    for (int o = 0; o < nold; o++)
        del_tet(tm, old[o]);
    for (int j = 0; j < nnew; j++) {
        int32_t t = new_tet(tm);
        ids[j] = t;
        memcpy(tm->tv + 4 * (size_t)t, newt[j], 4 * sizeof(int32_t));
        for (int s = 0; tm->vdeg && s < 4; s++)
            tm->vdeg[newt[j][s]]++;
        tm->tag[t] = tag;
        tm->rev[t] = rev;
        tm->q[t] = qn[j];
        tm->econs[t] = ebits[j];
        tm->fcons[t] = 0;
        if (tm->fref) {
            tm->fsurf[t] = 0;
            for (int i = 0; i < 4; i++) {
                tm->fref[4 * (size_t)t + i] = TMESH_NOREF;
                tm->fdev[4 * (size_t)t + i] = 0.0;
            }
        }
    }
    for (int j = 0; j < nnew; j++)
        for (int i = 0; i < 4; i++) {
            int32_t slot = 4 * ids[j] + i;
            if (link[j][i] == LINK_BND) {
                tm->adj[slot] = -1;
                tm->fcons[ids[j]] |= (uint8_t)(1u << i);
                tm->fref[slot] = sref;
                tm->fdev[slot] = bdev;
                tm->fsurf[ids[j]] |= (uint8_t)((1u << i) | (unsigned)srev << (4 + i));
            } else if (link[j][i] >= 0) {
                int o = link[j][i];
                int32_t os = oslot[o];
                tm->adj[slot] = onb[o];
                tm->fcons[ids[j]] |= (uint8_t)(obit[o] << i);
                if (tm->fref && obit[o]) { /* the face's surface data moves along */
                    const tmesh_jent *dj = NULL;
                    for (int x = 0; x < tm->njr && !dj; x++)
                        if (tm->jr[x].kind == J_DEL && tm->jr[x].id == os / 4)
                            dj = tm->jr + x;
                    tm->fref[slot] = dj->fref[os % 4];
                    tm->fdev[slot] = dj->fdev[os % 4];
                    tm->fsurf[ids[j]] |=
                        (uint8_t)(((dj->fs >> (os % 4) & 1u) << i) |
                                  ((dj->fs >> (4 + os % 4) & 1u) << (4 + i)));
                }
                if (onb[o] >= 0)
                    set_adj(tm, onb[o], slot);
            } else {
                int r = -1 - link[j][i];
                tm->adj[slot] = 4 * ids[r / 4] + r % 4;
            }
        }
    /* open outer faces: removed ones logged, interior ones made boundary */
    for (int o = 0; bnd && o < nout; o++) {
        int32_t n = onb[o];
        if (oused[o])
            continue;
        if (n < 0) {
            memcpy(tm->gone[tm->ngone++], okey[o], sizeof okey[o]);
            continue;
        }
        st = jface(tm, n / 4);
        if (st != QDC_OK)
            goto undo;
        set_adj(tm, n, -1);
        tm->fcons[n / 4] |= (uint8_t)(1u << (n % 4));
        tm->fref[n] = sref;
        tm->fdev[n] = bdev;
        tm->fsurf[n / 4] |= (uint8_t)((1u << (n % 4)) | (unsigned)srev << (4 + n % 4));
    }
    /* the edges of the new boundary faces are constrained all round */
    for (int j = 0; bnd && j < nnew; j++)
        for (int i = 0; i < 4; i++)
            for (int s = 0; s < 3 && link[j][i] == LINK_BND; s++) {
                st = constrain_edge(tm, ids[j], newt[j][tet_face_of[i][s]],
                                    newt[j][tet_face_of[i][(s + 1) % 3]]);
                if (st != QDC_OK)
                    goto undo;
            }
    for (int o = 0; bnd && o < nout; o++) {
        int32_t n = onb[o], t;
        if (oused[o] || n < 0)
            continue;
        t = n / 4;
        for (int s = 0; s < 3; s++) {
            st = constrain_edge(tm, t, tm->tv[4 * (size_t)t + tet_face_of[n % 4][s]],
                                tm->tv[4 * (size_t)t + tet_face_of[n % 4][(s + 1) % 3]]);
            if (st != QDC_OK)
                goto undo;
        }
    }
    if (new_ids)
        memcpy(new_ids, ids, (size_t)nnew * sizeof *ids);
    *applied = 1;
    return QDC_OK;
undo:
    tmesh_rollback(tm);
    return st;
}

qdc_status tmesh_replace(tmesh *tm, const int32_t *old, int nold,
                         const int32_t (*newt)[4], int nnew, int32_t *new_ids,
                         int *applied)
{
    return replace_impl(tm, old, nold, newt, nnew, new_ids, applied, 0, 0.0);
}

qdc_status tmesh_replace_surface(tmesh *tm, const int32_t *old, int nold,
                                 const int32_t (*newt)[4], int nnew, double dev,
                                 int32_t *new_ids, int *applied)
{
    return replace_impl(tm, old, nold, newt, nnew, new_ids, applied, 1, dev);
}

/* Order of sorted triangle keys with their index (tmesh_set_surface). */
typedef struct {
    int32_t k[3];
    int32_t i;
} tri_key;

/* Order of triangle keys alone (tmesh_keep_tris). */
static int tri_key_only(const void *x, const void *y)
{
    const tri_key *a = x, *b = y;

    for (int s = 0; s < 3; s++)
        if (a->k[s] != b->k[s])
            return a->k[s] < b->k[s] ? -1 : 1;
    return 0;
}

static int tri_key_cmp(const void *x, const void *y)
{
    const tri_key *a = x, *b = y;
    int c = tri_key_only(x, y);

    return c ? c : a->i < b->i ? -1 : a->i > b->i;
}

qdc_status tmesh_keep_tris(tmesh *tm, int32_t ntri, const int32_t *tris)
{
    tri_key *keys;
    int any = 0;

    if (ntri <= 0)
        return QDC_OK;
    keys = qdc_mallocn((size_t)ntri, sizeof *keys);
    if (!keys)
        return QDC_ENOMEM;
    for (int32_t s = 0; s < ntri; s++) {
        tet_sort3(tris[3 * (size_t)s], tris[3 * (size_t)s + 1], tris[3 * (size_t)s + 2],
                  keys[s].k);
        keys[s].i = s;
    }
    qsort(keys, (size_t)ntri, sizeof *keys, tri_key_only);
    for (int32_t t = 0; t < tm->hi; t++)
        for (int i = 0; i < 4; i++) {
            const int32_t *tt = tm->tv + 4 * (size_t)t;
            int32_t nb = tm->adj[4 * (size_t)t + i];
            tri_key want;
            if (tt[0] < 0 || nb < 0 || (tm->fcons[t] >> i & 1))
                continue;
            face_key(tt, i, want.k);
            want.i = 0;
            if (!bsearch(&want, keys, (size_t)ntri, sizeof *keys, tri_key_only))
                continue;
            tm->fcons[t] |= (uint8_t)(1u << i);
            tm->fcons[nb / 4] |= (uint8_t)(1u << (nb % 4));
            for (int s = 0; s < 3; s++)
                tm->vcons[tt[tet_face_of[i][s]]] = 1;
            any = 1;
        }
    qdc_free(keys);
    return any ? mark_edges(tm, tm->hi) : QDC_OK;
}

/* 1 when (p, q, r) is (x, y, z) rotated. */
static int same_turn(const int32_t *p, int32_t x, int32_t y, int32_t z)
{
    return (p[0] == x && p[1] == y && p[2] == z) ||
           (p[0] == y && p[1] == z && p[2] == x) || (p[0] == z && p[1] == x && p[2] == y);
}

qdc_status tmesh_set_surface(tmesh *tm, int32_t ntri, const int32_t *tris,
                             const int32_t *refs)
{
    tri_key *keys = ntri > 0 ? qdc_mallocn((size_t)ntri, sizeof *keys) : NULL;

    if (ntri > 0 && !keys)
        return QDC_ENOMEM;
    qdc_free(tm->fref);
    qdc_free(tm->fdev);
    qdc_free(tm->fsurf);
    tm->fref = qdc_mallocn(4 * (size_t)tm->cap, sizeof *tm->fref);
    tm->fdev = qdc_calloc(4 * (size_t)tm->cap, sizeof *tm->fdev);
    tm->fsurf = qdc_calloc((size_t)tm->cap, 1);
    if (!tm->fref || !tm->fdev || !tm->fsurf) {
        qdc_free(keys);
        return QDC_ENOMEM;
    }
    for (int32_t s = 0; s < ntri; s++) {
        tet_sort3(tris[3 * (size_t)s], tris[3 * (size_t)s + 1], tris[3 * (size_t)s + 2],
                  keys[s].k);
        keys[s].i = s;
    }
    if (ntri > 0)
        qsort(keys, (size_t)ntri, sizeof *keys, tri_key_cmp);
    for (int32_t t = 0; t < tm->cap; t++)
        for (int i = 0; i < 4; i++) {
            const int32_t *tt = tm->tv + 4 * (size_t)t;
            tri_key want;
            const tri_key *hit;
            tm->fref[4 * (size_t)t + i] = TMESH_NOREF;
            if (t >= tm->hi || tt[0] < 0 || tm->adj[4 * (size_t)t + i] >= 0 || !ntri)
                continue;
            face_key(tt, i, want.k);
            want.i = -1; /* sorts before every triangle of that key: the first */
            hit = keys;
            {
                size_t lo = 0, hi = (size_t)ntri;
                while (lo < hi) {
                    size_t mid = lo + (hi - lo) / 2;
                    if (tri_key_cmp(keys + mid, &want) < 0)
                        lo = mid + 1;
                    else
                        hi = mid;
                }
                hit =
                    lo < (size_t)ntri && same_key(keys[lo].k, want.k) ? keys + lo : NULL;
            }
            if (!hit)
                continue;
            tm->fref[4 * (size_t)t + i] = refs ? refs[hit->i] : 0;
            if (!same_turn(tris + 3 * (size_t)hit->i, tt[tet_face_of[i][0]],
                           tt[tet_face_of[i][1]], tt[tet_face_of[i][2]]))
                tm->fsurf[t] |= (uint8_t)(1u << (4 + i));
        }
    qdc_free(keys);
    return QDC_OK;
}

/* Slots of the set of tets found, a power of two at least twice the largest
 * cap asked for (256), so that a probe ends soon: the linear search of the
 * list it replaces cost 7% of a flips run on the 100k-tet bone-lowq. */
enum { STAR_SET = 512 };

/* 1 when u was in the set (open addressing), else 0 and u added. */
static int star_seen(int32_t *set, int32_t u)
{
    uint32_t h = ((uint32_t)u * 2654435761u) >> 23; /* 9 bits: STAR_SET */

    while (set[h] >= 0) {
        if (set[h] == u)
            return 1;
        h = (h + 1) & (STAR_SET - 1);
    }
    set[h] = u;
    return 0;
}

int tmesh_star(const tmesh *tm, int32_t t0, int32_t v, int32_t *out, int cap)
{
    int32_t set[STAR_SET];
    int n = 0;

    if (cap < 1)
        return -1;
    if (cap > STAR_SET / 2)
        cap = STAR_SET / 2; /* no caller asks for more */
    memset(set, 0xff, sizeof set);
    out[n++] = t0;
    star_seen(set, t0);
    for (int k = 0; k < n; k++) {
        int lv = tmesh_local(tm, out[k], v);
        for (int i = 0; i < 4; i++) {
            int32_t nb = tm->adj[4 * (size_t)out[k] + i], u;
            if (i == lv || nb < 0)
                continue;
            u = nb / 4;
            if (star_seen(set, u))
                continue;
            if (n == cap)
                return -1;
            out[n++] = u;
        }
    }
    return n;
}

int tmesh_check(const tmesh *tm, int32_t *ninv, char *why, size_t n)
{
    int32_t live = 0;

    *ninv = 0;
    for (int32_t t = 0; t < tm->hi; t++) {
        const int32_t *tt = tm->tv + 4 * (size_t)t;
        if (tt[0] < 0)
            continue;
        live++;
        if (exact_orient3d(tm->xyz + 3 * (size_t)tt[0], tm->xyz + 3 * (size_t)tt[1],
                           tm->xyz + 3 * (size_t)tt[2],
                           tm->xyz + 3 * (size_t)tt[3]) <= 0) {
            (*ninv)++;
            if (!(tm->q[t] < -1.0)) {
                snprintf(why, n, "tet %ld is not positive but has a quality", (long)t);
                return -1;
            }
        }
        for (int i = 0; i < 4; i++) {
            int32_t nb = tm->adj[4 * (size_t)t + i], k[3], k2[3];
            int want = nb < 0;
            if (nb >= 0) {
                const int32_t *tu = tm->tv + 4 * (size_t)(nb / 4);
                if (tu[0] < 0 || tm->adj[nb] != 4 * t + i) {
                    snprintf(why, n, "tet %ld face %d: neighbour not linked back",
                             (long)t, i);
                    return -1;
                }
                face_key(tt, i, k);
                face_key(tu, nb % 4, k2);
                if (!same_key(k, k2)) {
                    snprintf(why, n, "tet %ld face %d: neighbour's face differs", (long)t,
                             i);
                    return -1;
                }
                want = tm->tag[nb / 4] != tm->tag[t];
                /* a face inside a region kept as the user's (tmesh_keep_tris):
                 * constrained on both sides */
                if (!want && (tm->fcons[t] >> i & 1) &&
                    (tm->fcons[nb / 4] >> (nb % 4) & 1))
                    want = 1;
            }
            if ((tm->fcons[t] >> i & 1) != want) {
                snprintf(why, n, "tet %ld face %d: constraint bit wrong", (long)t, i);
                return -1;
            }
            if (want) /* the edges of a constrained face are constrained */
                for (int e = 0; e < 6; e++)
                    if (tmesh_edge[e][0] != i && tmesh_edge[e][1] != i &&
                        !(tm->econs[t] >> e & 1)) {
                        snprintf(why, n, "tet %ld edge %d: constraint bit missing",
                                 (long)t, e);
                        return -1;
                    }
        }
    }
    if (live != tm->nlive) {
        snprintf(why, n, "%ld live tets counted, %ld recorded", (long)live,
                 (long)tm->nlive);
        return -1;
    }
    return 0;
}
