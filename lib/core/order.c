/* order.c - spatial numbering of a mesh (order.h). */
#include "core/order.h"

#include <math.h>
#include <string.h>

#define MORTON_BITS 21 /* per axis: 63-bit keys */

/* The low 21 bits of a spread to every third bit. */
static uint64_t spread3(uint64_t a)
{
    a &= 0x1fffffULL;
    a = (a | a << 32) & 0x1f00000000ffffULL;
    a = (a | a << 16) & 0x1f0000ff0000ffULL;
    a = (a | a << 8) & 0x100f00f00f00f00fULL;
    a = (a | a << 4) & 0x10c30c30c30c30c3ULL;
    a = (a | a << 2) & 0x1249249249249249ULL;
    return a;
}

typedef struct {
    uint64_t key;
    int32_t id;
} keyed;

/* Stable LSD radix sort of a[0..n) by key, 16 bits a pass; 0 if out of memory. */
static int radix_sort(keyed *a, int32_t n)
{
    keyed *b = qdc_mallocn((size_t)n + 1, sizeof *b);
    size_t *cnt = qdc_mallocn(65536 + 1, sizeof *cnt);

    if (!b || !cnt) {
        qdc_free(b);
        qdc_free(cnt);
        return 0;
    }
    for (int shift = 0; shift < 64; shift += 16) {
        memset(cnt, 0, (65536 + 1) * sizeof *cnt);
        for (int32_t i = 0; i < n; i++)
            cnt[(a[i].key >> shift & 0xffff) + 1]++;
        if (cnt[1] == (size_t)n && shift > 0)
            continue; /* every digit 0 here: this pass changes nothing */
        for (int d = 0; d < 65536; d++)
            cnt[d + 1] += cnt[d];
        for (int32_t i = 0; i < n; i++)
            b[cnt[a[i].key >> shift & 0xffff]++] = a[i];
        memcpy(a, b, (size_t)n * sizeof *a);
    }
    qdc_free(b);
    qdc_free(cnt);
    return 1;
}

/* Keys scale the bounding box's largest extent to 21 bits (0 for a box
 * without a finite positive extent: every key 0). */
static double key_scale(const mesh_t *m, double lo[3])
{
    double hi[3], ext;

    mesh_bbox(m, lo, hi);
    ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    return ext > 0.0 && isfinite(ext) ? ((double)(1 << MORTON_BITS) - 1.0) / ext : 0.0;
}

static uint64_t morton_key(const double *p, const double lo[3], double scale)
{
    uint64_t key = 0;

    for (int c = 0; c < 3; c++) {
        double q = (p[c] - lo[c]) * scale;
        uint64_t u =
            q > 0.0 && isfinite(q) ? (uint64_t)(q < 2097151.0 ? q : 2097151.0) : 0;
        key |= spread3(u) << c;
    }
    return key;
}

/* Tets by their lowest new vertex number (a counting sort, stable): each of
 * nth ranges of tets counted and placed by its own thread, a range's tets
 * after the previous range's in every bucket (the serial order). */
static qdc_status order_tets(const mesh_t *m, mesh_order *o)
{
    int nth = qdc_threads_upto(8);
    size_t w = (size_t)m->nv + 1;
    int32_t *cnt = qdc_calloc((size_t)nth * w, sizeof(int32_t));
    int32_t *key = qdc_mallocn((size_t)m->nt + 1, sizeof(int32_t));

    if (!cnt || !key) {
        qdc_free(cnt);
        qdc_free(key);
        return QDC_ENOMEM;
    }
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < m->nt; t++) {
        int32_t lo = m->nv;
        for (int a = 0; a < 4; a++) {
            int32_t x = o->vnew[m->tets[4 * (size_t)t + a]];
            lo = x < lo ? x : lo;
        }
        key[t] = lo;
    }
    for (int pass = 0; pass < 2; pass++) {
#pragma omp parallel for schedule(static, 1) num_threads(nth)
        for (int i = 0; i < nth; i++) {
            int32_t *c = cnt + (size_t)i * w;
            for (int32_t t = qdc_part(m->nt, i, nth); t < qdc_part(m->nt, i + 1, nth);
                 t++) {
                if (pass == 0)
                    c[key[t]]++;
                else
                    o->told[c[key[t]]++] = t;
            }
        }
        if (pass == 0)
            qdc_count_places(cnt, nth, w, m->nv, NULL);
    }
    qdc_free(cnt);
    qdc_free(key);
    return QDC_OK;
}

qdc_status mesh_order_build(const mesh_t *m, mesh_order *o)
{
    keyed *k;
    double lo[3], scale;
    qdc_status st;
    int bad = 0;

    memset(o, 0, sizeof *o);
#pragma omp parallel for reduction(| : bad) schedule(static)
    for (int32_t t = 0; t < m->nt; t++)
        for (int a = 0; a < 4; a++)
            bad |= m->tets[4 * (size_t)t + a] < 0 || m->tets[4 * (size_t)t + a] >= m->nv;
    if (bad)
        return QDC_EINVAL;
    k = qdc_mallocn((size_t)m->nv + 1, sizeof *k);
    o->vnew = qdc_mallocn((size_t)m->nv + 1, sizeof(int32_t));
    o->told = qdc_mallocn((size_t)m->nt + 1, sizeof(int32_t));
    if (!k || !o->vnew || !o->told) {
        qdc_free(k);
        mesh_order_free(o);
        return QDC_ENOMEM;
    }
    o->nv = m->nv;
    o->nt = m->nt;
    scale = key_scale(m, lo);
#pragma omp parallel for schedule(static)
    for (int32_t v = 0; v < m->nv; v++) {
        k[v].key = morton_key(m->xyz + 3 * (size_t)v, lo, scale);
        k[v].id = v;
    }
    if (!radix_sort(k, m->nv)) {
        qdc_free(k);
        mesh_order_free(o);
        return QDC_ENOMEM;
    }
    for (int32_t i = 0; i < m->nv; i++)
        o->vnew[k[i].id] = i;
    qdc_free(k);
    st = order_tets(m, o);
    if (st != QDC_OK)
        mesh_order_free(o);
    return st;
}

mesh_t *mesh_order_apply(const mesh_t *m, const mesh_order *o)
{
    mesh_t *p =
        mesh_new(m->nv, m->nt,
                 (m->region ? MESH_WITH_REGION : 0u) | (m->fixed ? MESH_WITH_FIXED : 0u));

    if (!p)
        return NULL;
#pragma omp parallel for schedule(static)
    for (int32_t v = 0; v < m->nv; v++) {
        memcpy(p->xyz + 3 * (size_t)o->vnew[v], m->xyz + 3 * (size_t)v,
               3 * sizeof(double));
        if (m->fixed)
            p->fixed[o->vnew[v]] = m->fixed[v];
    }
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < m->nt; t++) {
        int32_t s = o->told[t];
        for (int a = 0; a < 4; a++)
            p->tets[4 * (size_t)t + a] = o->vnew[m->tets[4 * (size_t)s + a]];
        if (m->region)
            p->region[t] = m->region[s];
    }
    /* the triangles (renumbered; an index out of range as -1): a face inside
     * a region among them is a surface the user gave (mesh_topo_build) */
    if (m->ntri > 0 && m->tris) {
        if (mesh_set_tris(p, m->ntri, 0) != QDC_OK) {
            mesh_free(p);
            return NULL;
        }
        for (size_t k = 0; k < 3 * (size_t)m->ntri; k++) {
            int32_t v = m->tris[k];
            p->tris[k] = v >= 0 && v < m->nv ? o->vnew[v] : -1;
        }
    }
    return p;
}

mesh_t *mesh_order_take(mesh_t *m, mesh_order *o)
{
    mesh_t *p = mesh_order_apply(m, o);

    if (p) {
        o->vold = qdc_mallocn((size_t)m->nv + 1, sizeof(int32_t));
        o->done = qdc_mallocn((size_t)m->nt + 1, 1);
    }
    if (!p || !o->vold || !o->done) {
        mesh_free(p);
        qdc_free(o->vold);
        qdc_free(o->done);
        o->vold = NULL;
        o->done = NULL;
        return NULL;
    }
    for (int32_t v = 0; v < m->nv; v++)
        o->vold[o->vnew[v]] = v;
    qdc_free(m->tets);
    qdc_free(m->region);
    m->tets = NULL;
    m->region = NULL;
    return p;
}

/* Records of size sz (at most 32 bytes) every step bytes from a, moved so
 * that the one at i goes to to[i] (a permutation), in place: each cycle
 * followed once, done[] marking the places filled. */
static void permute_step(char *a, size_t sz, size_t step, int32_t n, const int32_t *to,
                         uint8_t *done)
{
    char carry[32], tmp[32];

    memset(done, 0, (size_t)n);
    for (int32_t i = 0; i < n; i++) {
        int32_t j = i;
        if (done[i])
            continue;
        memcpy(carry, a + (size_t)i * step, sz);
        do {
            j = to[j];
            memcpy(tmp, a + (size_t)j * step, sz);
            memcpy(a + (size_t)j * step, carry, sz);
            memcpy(carry, tmp, sz);
            done[j] = 1;
        } while (j != i);
    }
}

/* permute_step of records side by side. */
static void permute_to(char *a, size_t sz, int32_t n, const int32_t *to, uint8_t *done)
{
    permute_step(a, sz, sz, n, to, done);
}

/* Records of w int32 each in a (n of them), moved so that the one at i goes
 * to to[i] and each value v becomes map[v] (if map): scattered into a new
 * array where there is memory for one (independent stores, 4x faster than
 * following the cycles, whose every step waits for the previous one's cache
 * miss), else in place. Returns the array that holds them. */
static int32_t *put_back(int32_t *a, int w, int32_t n, const int32_t *to,
                         const int32_t *map, uint8_t *done)
{
    int32_t *b = qdc_mallocn((size_t)w * (size_t)n + 1, sizeof(int32_t));

    if (b) {
        for (int32_t i = 0; i < n; i++)
            for (int k = 0; k < w; k++) {
                int32_t v = a[(size_t)w * i + k];
                b[(size_t)w * to[i] + k] = map ? map[v] : v;
            }
        qdc_free(a);
        return b;
    }
    permute_to((char *)a, 4 * (size_t)w, n, to, done);
    for (size_t i = 0; map && i < (size_t)w * n; i++)
        a[i] = map[a[i]];
    return a;
}

void mesh_order_give_back(mesh_order *o, mesh_t *pm, mesh_t *m)
{
    m->tets = put_back(pm->tets, 4, pm->nt, o->told, o->vold, o->done);
    m->region =
        pm->region ? put_back(pm->region, 1, pm->nt, o->told, NULL, o->done) : NULL;
    pm->tets = NULL;
    pm->region = NULL;
}

void mesh_order_restore_xyz(const mesh_order *o, const mesh_t *pm, mesh_t *m)
{
    for (int32_t v = 0; v < m->nv; v++)
        memcpy(m->xyz + 3 * (size_t)v, pm->xyz + 3 * (size_t)o->vnew[v],
               3 * sizeof(double));
}

void mesh_order_free(mesh_order *o)
{
    qdc_free(o->vnew);
    qdc_free(o->told);
    qdc_free(o->vold);
    qdc_free(o->done);
    o->vnew = o->told = o->vold = NULL;
    o->done = NULL;
}

/* The n records of w int32 at a moved by to (NULL: kept in place), in place,
 * then each value v in [0, nv) replaced by vto[v] (vto NULL: kept). */
static void renumber_ints(int32_t *a, int w, int32_t n, const int32_t *to, int32_t nv,
                          const int32_t *vto, uint8_t *done)
{
    if (!a)
        return;
    if (to)
        permute_to((char *)a, 4 * (size_t)w, n, to, done);
    if (!vto)
        return;
#pragma omp parallel for schedule(static)
    for (int64_t k = 0; k < (int64_t)w * n; k++)
        if (a[k] >= 0 && a[k] < nv)
            a[k] = vto[a[k]];
}

void mesh_renumber(mesh_t *m, const int32_t *vto, const int32_t *tto, uint8_t *done)
{
    int32_t nv = m->nv;

    if (m->xyz)
        permute_to((char *)m->xyz, 3 * sizeof(double), nv, vto, done);
    if (m->fixed)
        permute_to((char *)m->fixed, 1, nv, vto, done);
    renumber_ints(m->vref, 1, nv, vto, 0, NULL, done);
    for (int32_t i = 0; m->pdata && i < m->pdata->n; i++) /* a component at a time */
        for (size_t c = 0; c < (size_t)m->pdata->a[i].ncomp; c++)
            permute_step((char *)(m->pdata->a[i].v + c), sizeof(double),
                         (size_t)m->pdata->a[i].ncomp * sizeof(double), nv, vto, done);
    if (m->pdata && m->pdata->made)
        permute_to((char *)m->pdata->made, 1, nv, vto, done);
    renumber_ints(m->tets, 4, m->nt, tto, nv, vto, done);
    renumber_ints(m->region, 1, m->nt, tto, 0, NULL, done);
    renumber_ints(m->mid, 6, m->nt, tto, nv, vto, done);
    renumber_ints(m->tris, 3, m->ntri, NULL, nv, vto, done);
}
