/* mesh.c - mesh data, validation and connectivity (docs/method.md §1). */
#include "core/mesh_int.h"
#include "core/tet.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

const int tet_face_of[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
const int mesh_p2_edges[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};

mesh_t *mesh_new(int32_t nv, int32_t nt, unsigned flags)
{
    mesh_t *m;

    if (nv < 0 || nt < 0)
        return NULL;
    m = qdc_calloc(1, sizeof *m);
    if (!m)
        return NULL;
    m->nv = nv;
    m->nt = nt;
    m->xyz = qdc_calloc((size_t)nv * 3, sizeof(double));
    m->tets = qdc_calloc((size_t)nt * 4, sizeof(int32_t));
    if (flags & MESH_WITH_REGION)
        m->region = qdc_calloc((size_t)nt, sizeof(int32_t));
    if (flags & MESH_WITH_FIXED)
        m->fixed = qdc_calloc((size_t)nv, 1);
    if (flags & MESH_WITH_VREF)
        m->vref = qdc_calloc((size_t)nv, sizeof(int32_t));
    if (!m->xyz || !m->tets || ((flags & MESH_WITH_REGION) && !m->region) ||
        ((flags & MESH_WITH_FIXED) && !m->fixed) ||
        ((flags & MESH_WITH_VREF) && !m->vref)) {
        mesh_free(m);
        return NULL;
    }
    return m;
}

qdc_status mesh_set_tris(mesh_t *m, int32_t ntri, int with_ref)
{
    int32_t *tris, *ref = NULL;

    if (!m || ntri < 0)
        return QDC_EINVAL;
    tris = qdc_calloc((size_t)ntri * 3, sizeof(int32_t));
    if (with_ref)
        ref = qdc_calloc((size_t)ntri, sizeof(int32_t));
    if (!tris || (with_ref && !ref)) {
        qdc_free(tris);
        qdc_free(ref);
        return QDC_ENOMEM;
    }
    qdc_free(m->tris);
    qdc_free(m->tri_ref);
    m->tris = tris;
    m->tri_ref = ref;
    m->ntri = ntri;
    return QDC_OK;
}

static void *dup_array(const void *p, size_t n, size_t size, int *fail)
{
    void *q;

    if (!p)
        return NULL;
    q = qdc_mallocn(n ? n : 1, size);
    if (!q) {
        *fail = 1;
        return NULL;
    }
    memcpy(q, p, n * size);
    return q;
}

qdc_status mesh_set_mid(mesh_t *m)
{
    int32_t *mid;

    if (!m || m->nt < 0)
        return QDC_EINVAL;
    mid = qdc_calloc((size_t)m->nt * 6 + 1, sizeof(int32_t));
    if (!mid)
        return QDC_ENOMEM;
    qdc_free(m->mid);
    m->mid = mid;
    return QDC_OK;
}

void mesh_swap_tets(mesh_t *a, mesh_t *b)
{
    int32_t nt = a->nt, *t = a->tets, *g = a->region, *mid = a->mid;

    a->nt = b->nt;
    a->tets = b->tets;
    a->region = b->region;
    b->nt = nt;
    b->tets = t;
    b->region = g;
    a->mid = b->mid;
    b->mid = mid;
}

mesh_t *mesh_dup(const mesh_t *m)
{
    mesh_t *d;
    int fail = 0;

    if (!m)
        return NULL;
    d = qdc_calloc(1, sizeof *d);
    if (!d)
        return NULL;
    d->nv = m->nv;
    d->nt = m->nt;
    d->ntri = m->ntri;
    d->xyz = dup_array(m->xyz, (size_t)m->nv * 3, sizeof(double), &fail);
    d->tets = dup_array(m->tets, (size_t)m->nt * 4, sizeof(int32_t), &fail);
    d->region = dup_array(m->region, (size_t)m->nt, sizeof(int32_t), &fail);
    d->fixed = dup_array(m->fixed, (size_t)m->nv, 1, &fail);
    d->vref = dup_array(m->vref, (size_t)m->nv, sizeof(int32_t), &fail);
    d->tris = dup_array(m->tris, (size_t)m->ntri * 3, sizeof(int32_t), &fail);
    d->tri_ref = dup_array(m->tri_ref, (size_t)m->ntri, sizeof(int32_t), &fail);
    d->mid = dup_array(m->mid, (size_t)m->nt * 6, sizeof(int32_t), &fail);
    if (m->pdata && !(d->pdata = mesh_pdata_dup(m->pdata, m->nv)))
        fail = 1;
    if (fail || !d->xyz || !d->tets) {
        mesh_free(d);
        return NULL;
    }
    return d;
}

void mesh_free(mesh_t *m)
{
    if (!m)
        return;
    qdc_free(m->xyz);
    qdc_free(m->tets);
    qdc_free(m->region);
    qdc_free(m->fixed);
    qdc_free(m->vref);
    qdc_free(m->tris);
    qdc_free(m->tri_ref);
    qdc_free(m->mid);
    mesh_pdata_free(m->pdata);
    if (m->source)
        m->source->release(m->source);
    qdc_free(m);
}

double mesh_bbox(const mesh_t *m, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = m->nv ? m->xyz[k] : 0.0;
        hi[k] = lo[k];
    }
    for (int32_t v = 1; v < m->nv; v++)
        for (int k = 0; k < 3; k++) {
            double x = m->xyz[3 * (size_t)v + k];
            if (x < lo[k])
                lo[k] = x;
            if (x > hi[k])
                hi[k] = x;
        }
    {
        double d[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
        double e = fmax(d[0], fmax(d[1], d[2]));
        /* the usual sum of squares where it can neither overflow nor lose
         * everything to underflow; scaled by the largest extent outside */
        if (e > 1e-140 && e < 1e140)
            return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (!(e > 0) || !isfinite(e))
            return e;
        return e * sqrt((d[0] / e) * (d[0] / e) + (d[1] / e) * (d[1] / e) +
                        (d[2] / e) * (d[2] / e));
    }
}

static double tet_det(const double *x, const int32_t *t)
{
    return geom_tet_vol6(x, t);
}

/* Vertex -> incidence lists (4t+a), counting sort by vertex. */
static qdc_status build_incidence(int32_t nv, int32_t nt, const int32_t *tets,
                                  int32_t **ptr_out, int32_t **idx_out)
{
    int32_t *ptr = qdc_calloc((size_t)nv + 1, sizeof(int32_t));
    int32_t *idx = qdc_mallocn((size_t)nt * 4, sizeof(int32_t));

    if (!ptr || !idx) {
        qdc_free(ptr);
        qdc_free(idx);
        return QDC_ENOMEM;
    }
    for (size_t k = 0; k < (size_t)nt * 4; k++)
        ptr[tets[k] + 1]++;
    for (int32_t v = 0; v < nv; v++)
        ptr[v + 1] += ptr[v];
    for (size_t k = 0; k < (size_t)nt * 4; k++)
        idx[ptr[tets[k]]++] = (int32_t)k;
    for (int32_t v = nv; v > 0; v--)
        ptr[v] = ptr[v - 1];
    ptr[0] = 0;
    *ptr_out = ptr;
    *idx_out = idx;
    return QDC_OK;
}

typedef struct {
    int32_t b, c; /* the two larger vertices of the face */
    int32_t id;   /* 4*t + f */
    int32_t o;    /* the tet's vertex opposite the face (tets[id]) */
} face_rec;

static int face_less(const face_rec *p, const face_rec *q)
{
    if (p->b != q->b)
        return p->b < q->b;
    if (p->c != q->c)
        return p->c < q->c;
    return p->id < q->id;
}

/* Sorts one bucket of faces (their smallest vertex in common) and pairs its
 * equal faces in nbr. 0, or at the first bad face: 1 for a duplicate tet
 * (pair = the two tets), 2 for a face of 3+ tets (pair = its position in the
 * bucket and the count). */
static int match_bucket(face_rec *b, int n, int32_t *nbr, int pair[2])
{
    for (int i = 1; i < n; i++) {
        face_rec key = b[i];
        int j = i - 1;
        while (j >= 0 && face_less(&key, &b[j])) {
            b[j + 1] = b[j];
            j--;
        }
        b[j + 1] = key;
    }
    for (int i = 0; i < n;) {
        int j = i + 1;
        while (j < n && b[j].b == b[i].b && b[j].c == b[i].c)
            j++;
        if (j - i == 1) {
            nbr[b[i].id] = -1;
            i = j;
            continue;
        }
        /* two of the face's tets with the same opposite vertex: one tet
         * given twice (on the boundary the face has those two; inside, the
         * neighbour too, three in all): said as the duplicate it is */
        for (int k = i; k < j; k++)
            for (int l = k + 1; l < j; l++)
                if (b[k].o == b[l].o) {
                    if (pair) {
                        pair[0] = b[k].id >> 2;
                        pair[1] = b[l].id >> 2;
                    }
                    return 1;
                }
        if (j - i > 2) {
            if (pair) {
                pair[0] = i;
                pair[1] = j - i;
            }
            return 2;
        }
        nbr[b[i].id] = b[i + 1].id;
        nbr[b[i + 1].id] = b[i].id;
        i = j;
    }
    return 0;
}

/* For every tet face 4t+f, the matching face of the neighbour tet, or -1 on the
 * boundary. Faces are bucketed by their smallest vertex with a counting sort
 * over the tets in order (sequential reads: the per-vertex walk through
 * incidences was memory-latency bound, 3-7 s at 1M tets), then each small
 * bucket is insertion-sorted. Fails with QDC_EMESH on a face of 3+ tets. */
static qdc_status match_faces(int32_t nv, int32_t nt, const int32_t *tets, int32_t *nbr,
                              qdc_error *err)
{
    /* faces bucketed by their lowest vertex: a counting sort, each of nth
     * ranges of tets counted and placed by its own thread (a range's records
     * follow the previous range's in every bucket: the serial order) */
    int nth = qdc_threads_upto(8);
    size_t w = (size_t)nv + 1;
    int32_t *start = qdc_calloc(w + 1, sizeof(int32_t));
    int32_t *cnt = qdc_calloc((size_t)nth * w, sizeof(int32_t));
    face_rec *rec = qdc_mallocn((size_t)nt * 4 + 1, sizeof *rec);
    qdc_status st = QDC_OK;

    if (!start || !cnt || !rec) {
        qdc_free(start);
        qdc_free(cnt);
        qdc_free(rec);
        return QDC_ENOMEM;
    }
    for (int pass = 0; pass < 2; pass++) {
#pragma omp parallel for schedule(static, 1) num_threads(nth)
        for (int i = 0; i < nth; i++) {
            int32_t *c = cnt + (size_t)i * w;
            for (int32_t t = qdc_part(nt, i, nth); t < qdc_part(nt, i + 1, nth); t++) {
                const int32_t *tt = tets + 4 * (size_t)t;
                for (int f = 0; f < 4; f++) {
                    int32_t x = tt[tet_face_of[f][0]], y = tt[tet_face_of[f][1]];
                    int32_t z = tt[tet_face_of[f][2]];
                    int32_t lo = x < y ? (x < z ? x : z) : (y < z ? y : z);
                    if (pass == 0) {
                        c[lo]++;
                    } else {
                        int32_t hi = x > y ? (x > z ? x : z) : (y > z ? y : z);
                        face_rec *r = rec + c[lo]++;
                        r->b = x + y + z - lo - hi;
                        r->c = hi;
                        r->id = 4 * t + f;
                        r->o = tt[f];
                    }
                }
            }
        }
        if (pass == 0)
            qdc_count_places(cnt, nth, w, nv, start);
    }
    qdc_free(cnt);
    /* now bucket v is rec[start[v] .. start[v + 1]); the buckets are
     * independent (in parallel: 1.0 s at 4M tets serially), and the
     * error reported is the first bad bucket's, as a serial pass finds it */
    {
        int32_t first_bad = nv;
#pragma omp parallel for schedule(dynamic, 4096) reduction(min : first_bad)
        for (int32_t v = 0; v < nv; v++)
            if (match_bucket(rec + start[v], (int)(start[v + 1] - start[v]), nbr, NULL) !=
                    0 &&
                v < first_bad)
                first_bad = v;
        if (first_bad < nv) {
            int pair[2];
            int kind =
                match_bucket(rec + start[first_bad],
                             (int)(start[first_bad + 1] - start[first_bad]), nbr, pair);
            if (kind == 1) {
                int32_t t1 = pair[0], t2 = pair[1];
                st = qdc_fail(
                    err, QDC_EMESH,
                    "tets %d and %d have the same four vertices (a duplicate tet)",
                    (int)(t1 < t2 ? t1 : t2), (int)(t1 < t2 ? t2 : t1));
                if (err) {
                    err->index = t1 < t2 ? t2 : t1;
                    strcpy(err->kind, "tet");
                }
            } else {
                const face_rec *b = rec + start[first_bad] + pair[0];
                st = qdc_fail(err, QDC_EMESH,
                              "face (%d, %d, %d) is shared by %d tets (non-manifold); "
                              "tet %d is one of them",
                              (int)first_bad, (int)b->b, (int)b->c, pair[1],
                              (int)(b->id >> 2));
                if (err) {
                    err->index = b->id >> 2;
                    strcpy(err->kind, "tet");
                }
            }
        }
    }
    qdc_free(start);
    qdc_free(rec);
    return st;
}

qdc_status mesh_face_pairs(int32_t nv, int32_t nt, const int32_t *tets, int32_t *nbr,
                           qdc_error *err)
{
    return match_faces(nv, nt, tets, nbr, err);
}

/* 1 when face f of tet tt and face g of tet tu (the same three vertices) run
 * in opposite cyclic orders, i.e. the two tets are oriented alike: two tets of
 * one orientation see their shared face from opposite sides. */
static int faces_opposite(const int32_t *tt, int f, const int32_t *tu, int g)
{
    int32_t a0 = tt[tet_face_of[f][0]], a1 = tt[tet_face_of[f][1]];
    int32_t b[3] = {tu[tet_face_of[g][0]], tu[tet_face_of[g][1]], tu[tet_face_of[g][2]]};
    int k = b[0] == a0 ? 0 : b[1] == a0 ? 1 : 2;

    return b[(k + 1) % 3] != a1;
}

/* orient_tets' answer, in parallel, for the common mesh: every pair of
 * face neighbours oriented alike as written and every tet of one sign (all
 * positive, or all negative: then all flipped). 1 if so (flip and o set; the
 * components are not counted: o->components 0), 0 if the walk is needed. The
 * serial walk was 0.9 s of a 5M-tet run's setup. */
static int orient_uniform(const mesh_t *m, const int32_t *nbr, uint8_t *flip,
                          mesh_orientation *o)
{
    int32_t nt = m->nt, unlike = 0, npos = 0, nneg = 0;

#pragma omp parallel for reduction(+ : unlike, npos, nneg) schedule(static)
    for (int32_t t = 0; t < nt; t++) {
        const int32_t *tt = m->tets + 4 * (size_t)t;
        double d = tet_det(m->xyz, tt);
        npos += d > 0;
        nneg += d < 0;
        for (int f = 0; f < 4; f++) {
            int32_t other = nbr[4 * (size_t)t + f];
            if (other > 4 * t + f &&
                !faces_opposite(tt, f, m->tets + 4 * (size_t)(other >> 2), other & 3))
                unlike++;
        }
    }
    if (unlike || npos + nneg != nt || (npos && nneg))
        return 0;
    memset(o, 0, sizeof *o);
    memset(flip, nneg > 0, (size_t)nt);
    o->flipped = nneg;
    return 1;
}

/* A union-find forest over the tets with the parity of each link: up[x] =
 * parent << 1 | parity, where the parity is 1 when x and its parent are
 * oriented unlike as written. Every link goes from a larger index to a
 * smaller, so a root is its tree's smallest tet. Safe while other threads
 * link and halve (relaxed atomics: a pointer only ever moves to an ancestor,
 * with the parity of the path it skips). */
static int32_t uf_find(uint32_t *up, int32_t x, unsigned *par)
{
    unsigned p = 0;

    for (;;) {
        uint32_t ux = __atomic_load_n(&up[x], __ATOMIC_RELAXED), uy;
        int32_t y = (int32_t)(ux >> 1), g;
        if (y == x) {
            *par = p;
            return x;
        }
        uy = __atomic_load_n(&up[y], __ATOMIC_RELAXED);
        g = (int32_t)(uy >> 1);
        if (g == y) { /* y was a root */
            p ^= ux & 1;
            x = y;
            continue;
        }
        __atomic_store_n(&up[x], (uint32_t)g << 1 | ((ux ^ uy) & 1), __ATOMIC_RELAXED);
        p ^= (ux ^ uy) & 1;
        x = g;
    }
}

/* a and b, of parity w (1: oriented unlike as written), into one tree: the
 * larger root linked under the smaller. 0 when they already are in one tree
 * with the other parity (the connectivity cannot be oriented). */
static int uf_unite(uint32_t *up, int32_t a, int32_t b, unsigned w)
{
    for (;;) {
        unsigned pa, pb;
        uint32_t root;
        a = uf_find(up, a, &pa);
        b = uf_find(up, b, &pb);
        w ^= pa ^ pb; /* now the parity of the roots a and b */
        if (a == b)
            return w == 0;
        if (a < b) {
            int32_t t = a;
            a = b;
            b = t;
        }
        root = (uint32_t)a << 1;
        if (__atomic_compare_exchange_n(&up[a], &root, (uint32_t)b << 1 | w, 0,
                                        __ATOMIC_RELAXED, __ATOMIC_RELAXED))
            return 1;
    }
}

/* The number of t's component once each root r holds -1 - its number and
 * every other tet its root. */
static int32_t comp_of(const int32_t *up, int32_t t)
{
    return up[t] < 0 ? -1 - up[t] : -1 - up[up[t]];
}

/* Each tet's flip before the majority (its parity to its component's
 * smallest tet, which the walk starts from) into flip, its root into up.
 * 0 if the connectivity cannot be oriented. */
static int orient_forest(const mesh_t *m, const int32_t *nbr, uint32_t *up, uint8_t *flip)
{
    int32_t nt = m->nt, bad = 0;

#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < nt; t++)
        up[t] = (uint32_t)t << 1;
#pragma omp parallel for reduction(| : bad) schedule(dynamic, 4096)
    for (int32_t t = 0; t < nt; t++)
        for (int f = 0; f < 4; f++) {
            int32_t other = nbr[4 * (size_t)t + f];
            if (other > 4 * t + f &&
                !uf_unite(up, t, other >> 2,
                          !faces_opposite(m->tets + 4 * (size_t)t, f,
                                          m->tets + 4 * (size_t)(other >> 2), other & 3)))
                bad = 1;
        }
    if (bad)
        return 0;
        /* every tet linked straight to its root (while others still walk), then
         * the parity taken out */
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < nt; t++) {
        unsigned par;
        int32_t r = uf_find(up, t, &par);
        __atomic_store_n(&up[t], (uint32_t)r << 1 | par, __ATOMIC_RELAXED);
    }
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < nt; t++) {
        flip[t] = up[t] & 1;
        up[t] >>= 1;
    }
    return 1;
}

/* orient_tets in parallel: the components and each tet's orientation within
 * its own by a union-find with parities (the partition, the roots and the
 * parities do not depend on the threads), then each component takes the
 * sign most of its tets have. The same flip and counts as the serial walk,
 * which was 1.0 s of main-thread-only time in a tangled 4M-tet run's setup.
 * 0 (flip undefined) where the connectivity cannot be oriented: the walk
 * then finds the tets to name. QDC_ENOMEM. */
static qdc_status orient_parallel(const mesh_t *m, const int32_t *nbr, uint8_t *flip,
                                  mesh_orientation *o, int *ok)
{
    int32_t nt = m->nt, *up = qdc_mallocn((size_t)nt + 1, sizeof(int32_t)), *cnt;
    int32_t ncomp = 0, flipped = 0;

    *ok = 0;
    if (!up)
        return QDC_ENOMEM;
    if (!orient_forest(m, nbr, (uint32_t *)up, flip)) {
        qdc_free(up);
        return QDC_OK;
    }
    /* the roots numbered in order (a root comes before the rest of its tree),
     * as -1 - number; each tet's sign under its flip counted into its
     * component's */
    for (int32_t t = 0; t < nt; t++)
        if (up[t] == t)
            up[t] = -1 - ncomp++;
    cnt = qdc_calloc(2 * (size_t)ncomp, sizeof(int32_t));
    if (!cnt) {
        qdc_free(up);
        return QDC_ENOMEM;
    }
    for (int32_t t = 0; t < nt; t++) {
        double d = tet_det(m->xyz, m->tets + 4 * (size_t)t);
        if (flip[t])
            d = -d;
        if (d != 0)
            cnt[2 * (size_t)comp_of(up, t) + (d < 0)]++;
    }
    memset(o, 0, sizeof *o);
    o->components = ncomp;
    for (int32_t c = 0; c < ncomp; c++) {
        int32_t npos = cnt[2 * (size_t)c], nneg = cnt[2 * (size_t)c + 1];
        o->inverted += nneg > npos ? npos : nneg;
    }
#pragma omp parallel for reduction(+ : flipped) schedule(static)
    for (int32_t t = 0; t < nt; t++) {
        int32_t c = comp_of(up, t);
        flip[t] ^= cnt[2 * (size_t)c + 1] > cnt[2 * (size_t)c];
        flipped += flip[t];
    }
    o->flipped = flipped;
    qdc_free(cnt);
    qdc_free(up);
    *ok = 1;
    return QDC_OK;
}

/* docs/method.md §1: the orientation comes from the connectivity. Walk each
 * connected component across shared faces (nbr from match_faces), giving every
 * tet the orientation that agrees with the tet it was reached from; a tet
 * reached twice with different answers means the component cannot be oriented
 * (QDC_EMESH). Then each component as a whole takes the sign most of its tets
 * have geometrically, so that a mesh written with its tets in any vertex order
 * (DOLFIN sorts them, GetFEM mixes them) is valid when it is, and a tangled
 * mesh keeps the orientation of its majority. flip[t] = 1 when tet t must have
 * two vertices swapped to be positive under that orientation. */
static qdc_status orient_walk(const mesh_t *m, const int32_t *nbr, uint8_t *flip,
                              mesh_orientation *o, qdc_error *err)
{
    int32_t nt = m->nt;
    int32_t *queue = qdc_mallocn((size_t)nt + 1, sizeof(int32_t));
    uint8_t *seen = qdc_calloc((size_t)nt + 1, 1);
    qdc_status st = QDC_OK;

    memset(o, 0, sizeof *o);
    if (!queue || !seen) {
        qdc_free(queue);
        qdc_free(seen);
        return QDC_ENOMEM;
    }
    for (int32_t t0 = 0; t0 < nt && st == QDC_OK; t0++) {
        int32_t head = 0, tail = 0, npos = 0, nneg = 0;
        if (seen[t0])
            continue;
        o->components++;
        seen[t0] = 1;
        flip[t0] = 0;
        queue[tail++] = t0;
        while (head < tail && st == QDC_OK) {
            int32_t t = queue[head++];
            const int32_t *tt = m->tets + 4 * (size_t)t;
            for (int f = 0; f < 4; f++) {
                int32_t other = nbr[4 * (size_t)t + f], u;
                uint8_t want;
                if (other < 0)
                    continue;
                u = other >> 2;
                want =
                    flip[t] ^ !faces_opposite(tt, f, m->tets + 4 * (size_t)u, other & 3);
                if (!seen[u]) {
                    seen[u] = 1;
                    flip[u] = want;
                    queue[tail++] = u;
                } else if (flip[u] != want) {
                    st = qdc_fail(
                        err, QDC_EMESH,
                        "the tets cannot be oriented consistently (tets %d and %d "
                        "around their shared face disagree with the rest of "
                        "their component: a non-orientable connectivity)",
                        (int)t, (int)u);
                    if (err) {
                        err->index = u;
                        strcpy(err->kind, "tet");
                    }
                    break;
                }
            }
        }
        if (st != QDC_OK)
            break;
#pragma omp parallel for reduction(+ : npos, nneg) schedule(static)
        for (int32_t i = 0; i < tail; i++) {
            double d = tet_det(m->xyz, m->tets + 4 * (size_t)queue[i]);
            if (flip[queue[i]])
                d = -d;
            npos += d > 0;
            nneg += d < 0;
        }
        for (int32_t i = 0; i < tail; i++) {
            if (nneg > npos)
                flip[queue[i]] ^= 1;
            o->flipped += flip[queue[i]];
        }
        o->inverted += nneg > npos ? npos : nneg;
    }
    qdc_free(queue);
    qdc_free(seen);
    return st;
}

/* orient_tets: in parallel, or by the walk where the connectivity cannot be
 * oriented (the walk names the tets in its error). */
static qdc_status orient_tets(const mesh_t *m, const int32_t *nbr, uint8_t *flip,
                              mesh_orientation *o, qdc_error *err)
{
    int ok;
    qdc_status st = orient_parallel(m, nbr, flip, o, &ok);

    if (st != QDC_OK || ok)
        return st;
    return orient_walk(m, nbr, flip, o, err);
}

/* Swap the first two vertices of each flipped tet of tets (in place), and
 * with them the mid-edge nodes (mid, or NULL) of edges 12/02 and 03/13
 * (mesh_p2_edges); edges 01 and 23 stay. */
static void apply_flip(int32_t nt, int32_t *tets, int32_t *mid, const uint8_t *flip)
{
    for (int32_t t = 0; t < nt; t++)
        if (flip[t]) {
            int32_t x = tets[4 * (size_t)t];
            tets[4 * (size_t)t] = tets[4 * (size_t)t + 1];
            tets[4 * (size_t)t + 1] = x;
            if (mid) {
                int32_t *e = mid + 6 * (size_t)t;
                x = e[1], e[1] = e[2], e[2] = x;
                x = e[3], e[3] = e[4], e[4] = x;
            }
        }
}

/* Put tet tt (with nb, its neighbour across the face opposite each corner)
 * in its canonical vertex order: swapped first if flip (then it is positive
 * under the orientation), then the even permutation that brings its smallest
 * vertex to corner 0 and the smallest of the others to corner 1. Every vertex
 * order of one tet with one orientation ends the same, so the optimizer's
 * arithmetic, and its result, do not depend on how the file lists the tets
 * (DOLFIN sorts them, GetFEM mixes orders). Returns where each input corner
 * went: 2 bits per corner. */
static uint8_t canon_tet(int32_t *tt, int32_t *nb, int flip)
{
    int pos[4] = {0, 1, 2, 3}; /* pos[c]: input corner c is now at pos[c] */
    int32_t v[4], n[4];
    uint8_t code = 0;

#define SWAP_AT(i, j)                                                                    \
    do {                                                                                 \
        int32_t x_ = v[i], y_ = n[i];                                                    \
        v[i] = v[j], n[i] = n[j], v[j] = x_, n[j] = y_;                                  \
        for (int c_ = 0; c_ < 4; c_++)                                                   \
            pos[c_] = pos[c_] == (i) ? (j) : pos[c_] == (j) ? (i) : pos[c_];             \
    } while (0)
    memcpy(v, tt, sizeof v);
    memcpy(n, nb, sizeof n);
    if (flip)
        SWAP_AT(0, 1);
    {
        int k = 0;
        for (int i = 1; i < 4; i++)
            k = v[i] < v[k] ? i : k;
        if (k != 0) { /* a double transposition keeps the orientation */
            int l = k == 1 ? 2 : 1, r = 6 - k - l;
            SWAP_AT(0, k);
            SWAP_AT(l, r);
        }
        k = 1;
        for (int i = 2; i < 4; i++)
            k = v[i] < v[k] ? i : k;
        for (; k > 1; k--) { /* a 3-cycle of corners 1..3 keeps it too */
            SWAP_AT(1, 2);
            SWAP_AT(2, 3);
        }
    }
#undef SWAP_AT
    memcpy(tt, v, sizeof v);
    memcpy(nb, n, sizeof n);
    for (int c = 0; c < 4; c++)
        code |= (uint8_t)(pos[c] << (2 * c));
    return code;
}

static qdc_status validate_basic(const mesh_t *m, mesh_check *c, qdc_error *err);

/* The faces matched, then the tets oriented by the parallel union-find, or by
 * the walk when walk is 1. */
static qdc_status orient_by(const mesh_t *m, uint8_t *flip, mesh_orientation *o, int walk,
                            qdc_error *err)
{
    mesh_check chk;
    int32_t *nbr = NULL;
    qdc_status st;

    st = validate_basic(m, &chk, err);
    if (st != QDC_OK)
        return st;
    nbr = qdc_mallocn((size_t)m->nt * 4, sizeof(int32_t));
    if (!nbr)
        return QDC_ENOMEM;
    st = match_faces(m->nv, m->nt, m->tets, nbr, err);
    if (st == QDC_OK)
        st = walk ? orient_walk(m, nbr, flip, o, err) : orient_tets(m, nbr, flip, o, err);
    qdc_free(nbr);
    return st;
}

qdc_status mesh_orient(const mesh_t *m, uint8_t *flip, mesh_orientation *o,
                       qdc_error *err)
{
    return orient_by(m, flip, o, 0, err);
}

qdc_status mesh_orient_walk(const mesh_t *m, uint8_t *flip, mesh_orientation *o,
                            qdc_error *err)
{
    return orient_by(m, flip, o, 1, err);
}

qdc_status mesh_reorient(mesh_t *m, mesh_orientation *o, qdc_error *err)
{
    uint8_t *flip = qdc_calloc((size_t)(m && m->nt > 0 ? m->nt : 0) + 1, 1);
    qdc_status st;

    if (!flip)
        return QDC_ENOMEM;
    st = mesh_orient(m, flip, o, err);
    if (st == QDC_OK)
        apply_flip(m->nt, m->tets, m->mid, flip);
    qdc_free(flip);
    return st;
}

/* A tet's corners out of range or repeated: the message of the first. */
static int tet_indices_bad(const mesh_t *m, int32_t t, qdc_error *err)
{
    const int32_t *tt = m->tets + 4 * (size_t)t;

    for (int a = 0; a < 4; a++) {
        if (tt[a] < 0 || tt[a] >= m->nv) {
            if (err)
                qdc_fail(err, QDC_EMESH, "tet %d: vertex index %d out of range [0, %d)",
                         (int)t, (int)tt[a], (int)m->nv);
            return 1;
        }
        for (int b = 0; b < a; b++)
            if (tt[a] == tt[b]) {
                if (err)
                    qdc_fail(err, QDC_EMESH, "tet %d repeats vertex %d", (int)t,
                             (int)tt[a]);
                return 1;
            }
    }
    return 0;
}

/* validate_basic's pass over the tets, in parallel: the first tet with bad
 * indices (QDC_EMESH, the counts of the tets before it), each tet's corners
 * marked used, the degenerate ones counted into c, the signs into *npos and
 * *nneg, the tets with a first edge under 1e-12 of diag0 into *etiny (0.2 s
 * of a 4M-tet run's setup when serial). */
static qdc_status check_tets(const mesh_t *m, mesh_check *c, uint8_t *used, double diag0,
                             int32_t *npos, int32_t *nneg, int32_t *etiny, qdc_error *err)
{
    int32_t bad = m->nt, pos = 0, neg = 0, tiny = 0, ndeg = 0;

#pragma omp parallel for reduction(min : bad) schedule(static)
    for (int32_t t = 0; t < m->nt; t++)
        if (t < bad && tet_indices_bad(m, t, NULL))
            bad = t;
#pragma omp parallel for reduction(+ : pos, neg, tiny, ndeg) schedule(static)
    for (int32_t t = 0; t < bad; t++) {
        const int32_t *tt = m->tets + 4 * (size_t)t;
        /* the first edge of each tet, for the mean edge length below */
        const double *p0 = m->xyz + 3 * (size_t)tt[0], *p1 = m->xyz + 3 * (size_t)tt[1];
        double e[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        double em = fmax(fabs(e[0]), fmax(fabs(e[1]), fabs(e[2]))), d;
        for (int a = 0; a < 4; a++)
            __atomic_store_n(&used[tt[a]], 1, __ATOMIC_RELAXED);
        tiny += em < 1e-12 * diag0;
        d = tet_det(m->xyz, tt);
        if (geom_tet_degenerate(fabs(d), geom_tet_l2sum(m->xyz, tt)))
            ndeg++;
        else if (d > 0)
            pos++;
        else
            neg++;
    }
    c->n_degenerate = ndeg;
    *npos = pos;
    *nneg = neg;
    *etiny = tiny;
    if (bad == m->nt)
        return QDC_OK;
    tet_indices_bad(m, bad, err);
    if (err) {
        err->index = bad;
        strcpy(err->kind, "tet");
    }
    return QDC_EMESH;
}

/* Counts, coordinates, indices, repeated vertices, orientation: everything but
 * the face matching. */
static qdc_status validate_basic(const mesh_t *m, mesh_check *c, qdc_error *err)
{
    uint8_t *used = NULL;
    int32_t npos = 0, nneg = 0, etiny = 0;
    double bb_lo[3], bb_hi[3], diag0;
    qdc_status st = QDC_OK;

    memset(c, 0, sizeof *c);
    c->first_unreferenced = -1;
    if (!m || m->nv <= 0 || m->nt <= 0 || !m->xyz || !m->tets)
        return qdc_fail(err, QDC_EMESH, "empty mesh: %d vertices, %d tets",
                        m ? (int)m->nv : 0, m ? (int)m->nt : 0);
    for (int32_t v = 0; v < m->nv; v++)
        for (int k = 0; k < 3; k++)
            if (!isfinite(m->xyz[3 * (size_t)v + k])) {
                qdc_fail(err, QDC_EMESH, "vertex %d has a non-finite coordinate", (int)v);
                if (err) {
                    err->index = v;
                    strcpy(err->kind, "vertex");
                }
                return QDC_EMESH;
            }
    {
        double lo[3], hi[3], diag = mesh_bbox(m, lo, hi);
        /* The optimizer and the reports work in coordinates scaled to a unit
         * diagonal; that needs a diagonal that is a normal finite number. */
        if (!isfinite(diag))
            return qdc_fail(err, QDC_EMESH,
                            "the coordinates span more than the largest double (bounding "
                            "box [%g, %g] x [%g, %g] x [%g, %g]): scale the mesh",
                            lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]);
        if (diag < 1e-290)
            return qdc_fail(
                err, QDC_EMESH,
                "the mesh is too small to compute with (bounding-box diagonal "
                "%g, the smallest accepted is 1e-290): scale the mesh",
                diag);
    }
    used = qdc_calloc((size_t)m->nv, 1);
    if (!used)
        return QDC_ENOMEM;
    diag0 = mesh_bbox(m, bb_lo, bb_hi);
    st = check_tets(m, c, used, diag0, &npos, &nneg, &etiny, err);
    /* mid-edge nodes: in range and no tet's corner (the optimizer would move
     * them as corners, and opt/p2.c again as mid-edge nodes) */
    for (size_t i = 0; st == QDC_OK && m->mid && i < (size_t)m->nt * 6; i++)
        if (m->mid[i] < 0 || m->mid[i] >= m->nv || used[m->mid[i]] == 1) {
            st = qdc_fail(err, QDC_EMESH,
                          m->mid[i] < 0 || m->mid[i] >= m->nv
                              ? "tet %d: mid-edge node index %d out of range"
                              : "tet %d: mid-edge node %d is a corner of a tet",
                          (int)(i / 6), (int)m->mid[i]);
            if (err) {
                err->index = (int64_t)(i / 6);
                strcpy(err->kind, "tet");
            }
        } else {
            used[m->mid[i]] = 2; /* in a tet, as its mid-edge node */
        }
    if (st == QDC_OK) {
        for (int32_t v = 0; v < m->nv; v++)
            if (!used[v]) {
                if (c->first_unreferenced < 0)
                    c->first_unreferenced = v;
                c->n_unreferenced++;
            }
        c->negative_majority = nneg > npos;
        c->n_inverted = c->negative_majority ? npos : nneg;
        /* Computing in units of the diagonal (the optimizer, the reports)
         * flattens every tet of a mesh whose edges are 1e-12 of its extent:
         * a coordinate far off (1e308 among ones) or a unit mix-up. */
        if (etiny > m->nt / 2)
            st = qdc_fail(
                err, QDC_EMESH,
                "%d of the %d tets have an edge shorter than 1e-12 of the mesh's "
                "extent (%g): a vertex far from the others? (check the coordinates)",
                (int)etiny, (int)m->nt, diag0);
    }
    qdc_free(used);
    return st;
}

qdc_status mesh_validate(const mesh_t *m, mesh_check *info, qdc_error *err)
{
    mesh_check c;
    mesh_orientation o;
    int32_t *nbr = NULL;
    uint8_t *flip = NULL;
    qdc_status st;

    st = validate_basic(m, &c, err);
    if (info)
        *info = c;
    if (st != QDC_OK)
        return st;
    nbr = qdc_mallocn((size_t)m->nt * 4, sizeof(int32_t));
    flip = qdc_calloc((size_t)m->nt, 1);
    if (!nbr || !flip) {
        qdc_free(nbr);
        qdc_free(flip);
        return QDC_ENOMEM;
    }
    st = match_faces(m->nv, m->nt, m->tets, nbr, err);
    if (st == QDC_OK)
        st = orient_tets(m, nbr, flip, &o, err);
    if (st == QDC_OK && info) {
        info->n_inverted = o.inverted;
        info->n_flipped = o.flipped;
        info->n_components = o.components;
        info->negative_majority = o.flipped > m->nt / 2;
    }
    qdc_free(nbr);
    qdc_free(flip);
    return st;
}

/* The 1-ring of v (v first, then its tets' other vertices in order of first
 * sight) into buf, deduplicated with mark (entries != v mean unseen); its size. */
static int ring_of(const mesh_topo *tp, int32_t v, int32_t *mark, int32_t *buf)
{
    int n = 0;

    buf[n++] = v;
    mark[v] = v;
    for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
        const int32_t *tt = tp->tets + 4 * (size_t)(tp->vt_idx[k] >> 2);
        for (int b = 0; b < 4; b++) {
            int32_t u = tt[b];
            if (mark[u] != v) {
                mark[u] = v;
                buf[n++] = u;
            }
        }
    }
    return n;
}

/* CSR 1-ring (diagonal included), columns ascending: each vertex's incident
 * tets' vertices, deduplicated with a marker array, insertion-sorted. The
 * vertices are independent: each thread takes a range of them in order, with
 * its own marker array and buffer (serial, the random reads of the tets took
 * 0.6 s of setup at 4M tets), and packs its rings into a block of its own,
 * copied into place once the counts are known (the rings found once: a count
 * pass and a fill pass walked the tets twice). */
static qdc_status build_adjacency(mesh_topo *tp)
{
    int32_t nv = tp->nv, maxdeg = 0;
    /* at most 8 marker arrays (nv each) however many threads the caller allows */
    int nth = qdc_threads_upto(8), team = 1, failed = 0;
    int32_t *cnt = qdc_calloc((size_t)nv + 1, sizeof(int32_t)), *mark, *buf;
    int32_t *part[8] = {NULL};
    size_t bufn;
    qdc_status st = QDC_OK;

    if (!cnt)
        return QDC_ENOMEM;
    for (int32_t v = 0; v < nv; v++)
        if (tp->vt_ptr[v + 1] - tp->vt_ptr[v] > maxdeg)
            maxdeg = tp->vt_ptr[v + 1] - tp->vt_ptr[v];
    bufn = (size_t)maxdeg * 3 + 2;
    mark = qdc_mallocn((size_t)nth * ((size_t)nv + 1), sizeof(int32_t));
    buf = qdc_mallocn((size_t)nth * bufn, sizeof(int32_t));
    if (!mark || !buf) {
        qdc_free(cnt);
        qdc_free(mark);
        qdc_free(buf);
        return QDC_ENOMEM;
    }
    for (size_t i = 0; i < (size_t)nth * ((size_t)nv + 1); i++)
        mark[i] = -1;
#pragma omp parallel num_threads(nth) reduction(| : failed)
    {
        int me = omp_get_thread_num(), nt = omp_get_num_threads();
        int32_t *mk = mark + (size_t)me * ((size_t)nv + 1), *bf = buf + (size_t)me * bufn;
        int32_t lo = qdc_part(nv, me, nt), hi = qdc_part(nv, me + 1, nt);
        /* about 15 per vertex in a tet mesh; grown when short */
        size_t cap = (size_t)(hi - lo) * 16 + bufn, len = 0;
        int32_t *out = qdc_mallocn(cap, sizeof(int32_t));

        if (me == 0)
            team = nt;
        for (int32_t v = lo; v < hi && out; v++) {
            int n = ring_of(tp, v, mk, bf);
            for (int i = 1; i < n; i++) {
                int32_t key = bf[i];
                int j = i - 1;
                while (j >= 0 && bf[j] > key) {
                    bf[j + 1] = bf[j];
                    j--;
                }
                bf[j + 1] = key;
            }
            if (len + (size_t)n > cap) {
                int32_t *o = qdc_realloc(out, 2 * (cap + (size_t)n) * sizeof(int32_t));
                if (!o) {
                    qdc_free(out);
                    out = NULL;
                    break;
                }
                out = o;
                cap = 2 * (cap + (size_t)n);
            }
            memcpy(out + len, bf, (size_t)n * sizeof(int32_t));
            len += (size_t)n;
            cnt[v + 1] = n;
        }
        part[me] = out;
        failed |= !out;
    }
    qdc_free(mark);
    qdc_free(buf);
    for (int32_t v = 0; v < nv; v++)
        cnt[v + 1] += cnt[v];
    tp->adj_ptr = cnt;
    tp->adj_idx = failed ? NULL : qdc_mallocn((size_t)cnt[nv] + 1, sizeof(int32_t));
    if (!tp->adj_idx)
        st = QDC_ENOMEM;
    for (int me = 0; me < team; me++) {
        int32_t lo = qdc_part(nv, me, team), hi = qdc_part(nv, me + 1, team);
        if (st == QDC_OK)
            memcpy(tp->adj_idx + cnt[lo], part[me],
                   (size_t)(cnt[hi] - cnt[lo]) * sizeof(int32_t));
        qdc_free(part[me]);
    }
    return st;
}

/* A boundary triangle and its sorted vertices, for the order of mesh_faces. */
typedef struct {
    int32_t s[3];
    int32_t tri[3];
} sorted_tri;

static int sorted_tri_cmp(const void *a, const void *b)
{
    const int32_t *x = ((const sorted_tri *)a)->s, *y = ((const sorted_tri *)b)->s;

    for (int k = 0; k < 3; k++)
        if (x[k] != y[k])
            return x[k] < y[k] ? -1 : 1;
    return 0;
}

/* The input's triangles (m->tris) as sorted keys, and a mark on their
 * vertices: a face inside one region that is among them is a surface the user
 * gave (an embedded surface, facet tags) and is taken as an interface. */
typedef struct {
    int32_t n;
    sorted_tri *key;
    uint8_t *mark;
} tri_set;

static qdc_status tri_set_build(const mesh_t *m, tri_set *ts)
{
    ts->n = 0;
    ts->key = NULL;
    ts->mark = NULL;
    if (m->ntri <= 0 || !m->tris)
        return QDC_OK;
    ts->key = qdc_mallocn((size_t)m->ntri, sizeof *ts->key);
    ts->mark = qdc_calloc((size_t)m->nv, 1);
    if (!ts->key || !ts->mark)
        return QDC_ENOMEM;
    for (int32_t i = 0; i < m->ntri; i++) {
        const int32_t *tr = m->tris + 3 * (size_t)i;
        if (tr[0] < 0 || tr[0] >= m->nv || tr[1] < 0 || tr[1] >= m->nv || tr[2] < 0 ||
            tr[2] >= m->nv)
            continue;
        tet_sort3(tr[0], tr[1], tr[2], ts->key[ts->n].s);
        for (int k = 0; k < 3; k++)
            ts->mark[tr[k]] = 1;
        ts->n++;
    }
    qsort(ts->key, (size_t)ts->n, sizeof *ts->key, sorted_tri_cmp);
    return QDC_OK;
}

static void tri_set_free(tri_set *ts)
{
    qdc_free(ts->key);
    qdc_free(ts->mark);
}

/* 1 when face f of tet tt is one of ts's triangles. */
static int tri_set_has(const tri_set *ts, const int32_t *tt, int f)
{
    int32_t a = tt[tet_face_of[f][0]], b = tt[tet_face_of[f][1]],
            c = tt[tet_face_of[f][2]];
    sorted_tri k;

    if (ts->n == 0 || !ts->mark[a] || !ts->mark[b] || !ts->mark[c])
        return 0;
    tet_sort3(a, b, c, k.s);
    return bsearch(&k, ts->key, (size_t)ts->n, sizeof *ts->key, sorted_tri_cmp) != NULL;
}

/* The boundary faces (no neighbour) and the interfaces between regions or
 * given as the input's triangles (ts; each once, from the tet of lower index) into tp, in
 * tet order, and their vertices' flags. 64 ranges of tets, each counted, then written, by
 * one thread (serial, the two passes took 0.22 s of setup at 5M tets). */
#define FACE_RANGES 64
static qdc_status collect_faces(const mesh_t *m, mesh_topo *tp, const int32_t *nbr,
                                const tri_set *ts)
{
    int32_t cnt[2 * FACE_RANGES] = {0};

    for (int pass = 0; pass < 2; pass++) {
#pragma omp parallel for schedule(static)
        for (int r = 0; r < FACE_RANGES; r++) {
            int32_t t0 = qdc_part(m->nt, r, FACE_RANGES),
                    t1 = qdc_part(m->nt, r + 1, FACE_RANGES);
            int32_t nb = pass ? cnt[2 * r] : 0, ni = pass ? cnt[2 * r + 1] : 0;
            for (int32_t t = t0; t < t1; t++)
                for (int f = 0; f < 4; f++) {
                    int32_t o = nbr[4 * (size_t)t + f];
                    int is_b = o < 0;
                    int is_i = !is_b && o > 4 * t &&
                               ((m->region && m->region[t] != m->region[o >> 2]) ||
                                tri_set_has(ts, tp->tets + 4 * (size_t)t, f));
                    if (!is_b && !is_i)
                        continue;
                    if (pass == 1) {
                        int32_t *dst = is_b ? tp->bfaces + 3 * (size_t)nb
                                            : tp->ifaces + 3 * (size_t)ni;
                        for (int k = 0; k < 3; k++)
                            dst[k] = tp->tets[4 * (size_t)t + tet_face_of[f][k]];
                        if (is_b)
                            tp->bface_of[nb] = 4 * t + f;
                    }
                    nb += is_b;
                    ni += is_i;
                }
            if (pass == 0) {
                cnt[2 * r] = nb;
                cnt[2 * r + 1] = ni;
            }
        }
        if (pass == 0) {
            int32_t nb = 0, ni = 0;
            for (int r = 0; r < FACE_RANGES; r++) { /* counts into first places */
                int32_t b = cnt[2 * r], n = cnt[2 * r + 1];
                cnt[2 * r] = nb;
                cnt[2 * r + 1] = ni;
                nb += b;
                ni += n;
            }
            tp->nbf = nb;
            tp->nif = ni;
            tp->bfaces = qdc_mallocn((size_t)nb * 3 + 1, sizeof(int32_t));
            tp->ifaces = qdc_mallocn((size_t)ni * 3 + 1, sizeof(int32_t));
            tp->bface_of = qdc_mallocn((size_t)nb + 1, sizeof(int32_t));
            if (!tp->bfaces || !tp->ifaces || !tp->bface_of)
                return QDC_ENOMEM;
        }
    }
    for (size_t i = 0; i < 3 * (size_t)tp->nbf; i++)
        tp->vflag[tp->bfaces[i]] |= MESH_V_BOUNDARY;
    for (size_t i = 0; i < 3 * (size_t)tp->nif; i++)
        tp->vflag[tp->ifaces[i]] |= MESH_V_INTERFACE;
    return QDC_OK;
}

qdc_status mesh_topo_build(const mesh_t *m, mesh_topo **out, qdc_error *err)
{
    mesh_topo *tp;
    int32_t *nbr = NULL;
    uint8_t *flip = NULL;
    qdc_status st;

    *out = NULL;
    {
        mesh_check chk;
        st = validate_basic(m, &chk, err);
        if (st != QDC_OK)
            return st;
    }
    tp = qdc_calloc(1, sizeof *tp);
    if (!tp)
        return QDC_ENOMEM;
    tp->nv = m->nv;
    tp->nt = m->nt;
    tp->tets = qdc_mallocn((size_t)m->nt * 4, sizeof(int32_t));
    tp->vflag = qdc_calloc((size_t)m->nv, 1);
    nbr = qdc_mallocn((size_t)m->nt * 4, sizeof(int32_t));
    if (!tp->tets || !tp->vflag || !nbr) {
        st = QDC_ENOMEM;
        goto fail;
    }
    memcpy(tp->tets, m->tets, (size_t)m->nt * 4 * sizeof(int32_t));
    /* the tets oriented from the connectivity (orient_tets); swapping two
     * vertices keeps every face, so nbr stays valid for the flipped copy */
    st = match_faces(m->nv, m->nt, m->tets, nbr, err);
    if (st != QDC_OK)
        goto fail;
    flip = qdc_calloc((size_t)m->nt, 1);
    if (!flip) {
        st = QDC_ENOMEM;
        goto fail;
    }
    if (!orient_uniform(m, nbr, flip, &tp->orientation))
        st = orient_tets(m, nbr, flip, &tp->orientation, err);
    if (st != QDC_OK)
        goto fail;
    tp->oflip = qdc_mallocn((size_t)m->nt, 1);
    if (!tp->oflip) {
        st = QDC_ENOMEM;
        goto fail;
    }
    memcpy(tp->oflip, flip, (size_t)m->nt);
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < m->nt; t++) /* each tet alone: in parallel */
        /* flip[] becomes each tet's permutation code (canon_tet) */
        flip[t] = canon_tet(tp->tets + 4 * (size_t)t, nbr + 4 * (size_t)t, flip[t]);
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < m->nt; t++)
        /* a face's position in its tet moved with the vertex opposite it:
         * renumber the neighbours' references */
        for (int f = 0; f < 4; f++) {
            int32_t *nb = nbr + 4 * (size_t)t + f;
            if (*nb >= 0)
                *nb = (*nb & ~3) | ((flip[*nb >> 2] >> (2 * (*nb & 3))) & 3);
        }
    tp->flipped = tp->orientation.flipped > 0;
    qdc_free(flip);
    flip = NULL;
    st = build_incidence(m->nv, m->nt, tp->tets, &tp->vt_ptr, &tp->vt_idx);
    if (st != QDC_OK)
        goto fail;
    st = build_adjacency(tp);
    if (st != QDC_OK)
        goto fail;
    {
        tri_set ts;
        st = tri_set_build(m, &ts);
        if (st == QDC_OK)
            st = collect_faces(m, tp, nbr, &ts);
        tri_set_free(&ts);
    }
    if (st != QDC_OK)
        goto fail;
    for (int32_t v = 0; v < m->nv; v++) {
        if (m->fixed && m->fixed[v])
            tp->vflag[v] |= MESH_V_FIXED;
        if (tp->vt_ptr[v + 1] == tp->vt_ptr[v])
            tp->vflag[v] |= MESH_V_UNUSED;
        tp->nb += (tp->vflag[v] & MESH_V_BOUNDARY) != 0;
    }
    qdc_free(nbr);
    *out = tp;
    return QDC_OK;
fail:
    qdc_free(nbr);
    qdc_free(flip);
    mesh_topo_free(tp);
    return st;
}

void mesh_topo_free(mesh_topo *t)
{
    if (!t)
        return;
    qdc_free(t->tets);
    qdc_free(t->vt_ptr);
    qdc_free(t->vt_idx);
    qdc_free(t->adj_ptr);
    qdc_free(t->adj_idx);
    qdc_free(t->bfaces);
    qdc_free(t->bface_of);
    qdc_free(t->oflip);
    qdc_free(t->ifaces);
    qdc_free(t->vflag);
    qdc_free(t);
}

int32_t mesh_count_inverted(const mesh_topo *t, const double *xyz)
{
    int32_t n = 0;

#pragma omp parallel for reduction(+ : n) schedule(static)
    for (int32_t i = 0; i < t->nt; i++)
        n += geom_tet_bad(xyz, t->tets + 4 * (size_t)i);
    return n;
}

void mesh_faces_free(mesh_faces *f)
{
    if (!f)
        return;
    qdc_free(f->flip);
    qdc_free(f->tris);
    qdc_free(f);
}

qdc_status mesh_faces_of_topo(const mesh_topo *tp, const int32_t *tets,
                              const int32_t *told, const int32_t *vold, mesh_faces **out)
{
    mesh_faces *f = qdc_calloc(1, sizeof *f);
    sorted_tri *st = qdc_mallocn((size_t)tp->nbf + 1, sizeof *st);

    *out = NULL;
    if (f) {
        f->flip = qdc_mallocn((size_t)tp->nt + 1, 1);
        f->tris = qdc_mallocn(3 * (size_t)tp->nbf + 1, sizeof(int32_t));
    }
    if (!f || !st || !f->flip || !f->tris) {
        mesh_faces_free(f);
        qdc_free(st);
        return QDC_ENOMEM;
    }
    f->nt = tp->nt;
    f->ntri = tp->nbf;
    for (int32_t t = 0; t < tp->nt; t++)
        f->flip[told ? told[t] : t] = tp->oflip[t];
        /* each boundary face in its tet's input vertex order: the corner tp's
         * canonical order put opposite it is found in that order, and the face
         * is that corner's face there (bderr.c's boundary_faces) */
#pragma omp parallel for schedule(static)
    for (int32_t i = 0; i < tp->nbf; i++) {
        int32_t t = tp->bface_of[i] >> 2, w = tp->tets[tp->bface_of[i]];
        const int32_t *tt = tets + 4 * (size_t)t;
        int a = 0;
        while (a < 3 && tt[a] != w)
            a++;
        for (int k = 0; k < 3; k++) {
            int32_t v = tt[tet_face_of[a][k]];
            st[i].tri[k] = vold ? vold[v] : v;
        }
        tet_sort3(st[i].tri[0], st[i].tri[1], st[i].tri[2], st[i].s);
    }
    qsort(st, (size_t)tp->nbf, sizeof *st, sorted_tri_cmp);
    for (int32_t i = 0; i < tp->nbf; i++)
        memcpy(f->tris + 3 * (size_t)i, st[i].tri, sizeof st[i].tri);
    qdc_free(st);
    *out = f;
    return QDC_OK;
}
