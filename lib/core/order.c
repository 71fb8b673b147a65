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

/* Tets by their lowest new vertex number (a counting sort, stable). */
static qdc_status order_tets(const mesh_t *m, mesh_order *o)
{
    int32_t *start = qdc_calloc((size_t)m->nv + 1, sizeof(int32_t));

    if (!start)
        return QDC_ENOMEM;
    for (int pass = 0; pass < 2; pass++) {
        for (int32_t t = 0; t < m->nt; t++) {
            int32_t lo = m->nv;
            for (int a = 0; a < 4; a++) {
                int32_t w = o->vnew[m->tets[4 * (size_t)t + a]];
                lo = w < lo ? w : lo;
            }
            if (pass == 0)
                start[lo + 1]++;
            else
                o->told[start[lo]++] = t;
        }
        if (pass == 0)
            for (int32_t v = 0; v < m->nv; v++)
                start[v + 1] += start[v];
    }
    qdc_free(start);
    return QDC_OK;
}

qdc_status mesh_order_build(const mesh_t *m, mesh_order *o)
{
    keyed *k;
    double lo[3], scale;
    qdc_status st;

    memset(o, 0, sizeof *o);
    for (size_t i = 0; i < 4 * (size_t)m->nt; i++)
        if (m->tets[i] < 0 || m->tets[i] >= m->nv)
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
    for (int32_t v = 0; v < m->nv; v++) {
        memcpy(p->xyz + 3 * (size_t)o->vnew[v], m->xyz + 3 * (size_t)v,
               3 * sizeof(double));
        if (m->fixed)
            p->fixed[o->vnew[v]] = m->fixed[v];
    }
    for (int32_t t = 0; t < m->nt; t++) {
        int32_t s = o->told[t];
        for (int a = 0; a < 4; a++)
            p->tets[4 * (size_t)t + a] = o->vnew[m->tets[4 * (size_t)s + a]];
        if (m->region)
            p->region[t] = m->region[s];
    }
    return p;
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
    o->vnew = o->told = NULL;
}
