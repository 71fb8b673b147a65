/* pdata.c - point-data arrays of a mesh (mesh.h, "Point data"): kept,
 * copied, and carried to the vertices of a changed mesh, a new vertex
 * taking the linear interpolation of the mesh before at its position. */
#include "core/mesh_int.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void mesh_pdata_free(mesh_pdata *p)
{
    if (!p)
        return;
    for (int32_t i = 0; i < p->n; i++) {
        qdc_free(p->a[i].name);
        qdc_free(p->a[i].v);
    }
    qdc_free(p->a);
    qdc_free(p->made);
    qdc_free(p);
}

qdc_status mesh_pdata_add(mesh_t *m, const char *name, size_t nlen, int32_t ncomp,
                          int integer, const char *type, double *v, qdc_error *err)
{
    size_t n;
    mesh_pdata *p;
    mesh_parray *a, *na;

    if (!m || !name || !nlen || ncomp < 1 || !v || m->nv < 0) {
        qdc_free(v);
        return qdc_fail(err, QDC_EINVAL, "point data: no name, vertices or components");
    }
    n = (size_t)m->nv * (size_t)ncomp;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i])) {
            qdc_free(v);
            qdc_fail(err, QDC_EINVAL,
                     "point data %.*s: value %zu is not finite (NaN/Inf)",
                     (int)(nlen > 64 ? 64 : nlen), name, i);
            err->index = (int64_t)(i / (size_t)ncomp);
            return QDC_EINVAL;
        }
    p = m->pdata ? m->pdata : qdc_calloc(1, sizeof *p);
    na = p ? qdc_realloc(p->a, ((size_t)p->n + 1) * sizeof *na) : NULL;
    if (na)
        p->a = na;
    a = na ? &na[p->n] : NULL;
    if (a) {
        memset(a, 0, sizeof *a);
        a->name = qdc_malloc(nlen + 1);
    }
    if (!a || !a->name) {
        if (p && p != m->pdata)
            mesh_pdata_free(p);
        qdc_free(v);
        return qdc_fail(err, QDC_ENOMEM, "out of memory for point data");
    }
    /* a control byte (a NUL inside the file's name too) as '_': names are
     * written back as text, and "medit:ref\0..." must not come back as
     * the vertex refs' "medit:ref" */
    for (size_t i = 0; i < nlen; i++)
        a->name[i] = (unsigned char)name[i] < 0x20 || name[i] == 0x7f ? '_' : name[i];
    a->name[nlen] = 0;
    a->ncomp = ncomp;
    a->integer = integer != 0;
    snprintf(a->type, sizeof a->type, "%s", type ? type : "");
    a->v = v;
    p->n++;
    m->pdata = p;
    return QDC_OK;
}

/* d: an array like s (name, components, kind) with nval values of 0; -1 out
 * of memory (what was allocated is d's, for mesh_pdata_free). */
static int parray_like(mesh_parray *d, const mesh_parray *s, size_t nval)
{
    size_t len = strlen(s->name);

    *d = *s;
    d->name = qdc_malloc(len + 1);
    d->v = qdc_calloc(nval + 1, sizeof *d->v);
    if (!d->name || !d->v)
        return -1;
    memcpy(d->name, s->name, len + 1);
    return 0;
}

mesh_pdata *mesh_pdata_dup(const mesh_pdata *p, int32_t nv)
{
    mesh_pdata *d;

    if (!p)
        return NULL;
    d = qdc_calloc(1, sizeof *d);
    if (!d || !(d->a = qdc_calloc((size_t)p->n + 1, sizeof *d->a)))
        goto fail;
    d->ninterp = p->ninterp;
    if (p->made) {
        if (!(d->made = qdc_malloc((size_t)nv + 1)))
            goto fail;
        memcpy(d->made, p->made, (size_t)nv);
    }
    for (int32_t i = 0; i < p->n; i++) {
        size_t n = (size_t)nv * (size_t)p->a[i].ncomp;
        d->n = i + 1;
        if (parray_like(&d->a[i], &p->a[i], n))
            goto fail;
        memcpy(d->a[i].v, p->a[i].v, n * sizeof *d->a[i].v);
    }
    return d;
fail:
    mesh_pdata_free(d);
    return NULL;
}

static double det3(const double *a, const double *b, const double *c)
{
    return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
           a[2] * (b[0] * c[1] - b[1] * c[0]);
}

/* The barycentric weights w of p in tet t (corner coordinates at xyz);
 * returns the smallest, -INFINITY for a flat tet. */
static double bary(const double *xyz, const int32_t *t, const double *p, double w[4])
{
    const double *a = xyz + 3 * (size_t)t[0];
    double e[3][3], q[3], d;

    for (int i = 0; i < 3; i++) {
        for (int k = 0; k < 3; k++)
            e[i][k] = xyz[3 * (size_t)t[i + 1] + k] - a[k];
        q[i] = p[i] - a[i];
    }
    d = det3(e[0], e[1], e[2]);
    if (!(fabs(d) > 0))
        return -INFINITY;
    w[1] = det3(q, e[1], e[2]) / d;
    w[2] = det3(e[0], q, e[2]) / d;
    w[3] = det3(e[0], e[1], q) / d;
    w[0] = 1.0 - w[1] - w[2] - w[3];
    return fmin(fmin(w[0], w[1]), fmin(w[2], w[3]));
}

/* The new vertices to place, bucketed in a grid over the old mesh's box. */
typedef struct {
    int32_t n, *idx;    /* new vertex indices */
    const double *xyz;  /* their coordinates (the new array) */
    int g;              /* cells per axis */
    double lo[3], h[3]; /* the grid's corner and cell sizes */
    int32_t *start;     /* g^3 + 1: CSR of the cells */
    int32_t *cell;      /* n: positions in idx, by cell */
    int32_t *best;      /* n: the best tet so far, -1 none */
    double *score;      /* n: its smallest weight */
} locator;

static int cell_of(const locator *L, int axis, double x)
{
    double c = floor((x - L->lo[axis]) / L->h[axis]);

    return c < 0 || !(c == c) ? 0 : c >= L->g ? L->g - 1 : (int)c;
}

static int pt_cell(const locator *L, const double *p)
{
    return (cell_of(L, 0, p[0]) * L->g + cell_of(L, 1, p[1])) * L->g +
           cell_of(L, 2, p[2]);
}

static qdc_status locator_build(locator *L, const mesh_t *m, qdc_error *err)
{
    size_t nc;
    double hi[3];

    L->g = (int)cbrt((double)L->n) + 1;
    L->g = L->g > 64 ? 64 : L->g;
    nc = (size_t)L->g * L->g * L->g;
    mesh_bbox(m, L->lo, hi);
    for (int k = 0; k < 3; k++)
        L->h[k] = hi[k] > L->lo[k] ? (hi[k] - L->lo[k]) / L->g : 1.0;
    L->start = qdc_calloc(nc + 2, sizeof *L->start);
    L->cell = qdc_mallocn((size_t)L->n + 1, sizeof *L->cell);
    L->best = qdc_mallocn((size_t)L->n + 1, sizeof *L->best);
    L->score = qdc_mallocn((size_t)L->n + 1, sizeof *L->score);
    if (!L->start || !L->cell || !L->best || !L->score)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    for (int32_t k = 0; k < L->n; k++) {
        L->start[pt_cell(L, L->xyz + 3 * (size_t)L->idx[k]) + 2]++;
        L->best[k] = -1;
        L->score[k] = -INFINITY;
    }
    for (size_t c = 0; c < nc; c++)
        L->start[c + 2] += L->start[c + 1];
    for (int32_t k = 0; k < L->n; k++)
        L->cell[L->start[pt_cell(L, L->xyz + 3 * (size_t)L->idx[k]) + 1]++] = k;
    return QDC_OK;
}

/* Tet t against the new vertices in the cells its box (grown by half its
 * size, for points just outside the mesh) meets. */
static void locate_tet(locator *L, const mesh_t *m, int32_t t)
{
    const int32_t *tt = m->tets + 4 * (size_t)t;
    double lo[3], hi[3], w[4];
    int c0[3], c1[3];

    for (int k = 0; k < 3; k++) {
        lo[k] = hi[k] = m->xyz[3 * (size_t)tt[0] + k];
        for (int i = 1; i < 4; i++) {
            lo[k] = fmin(lo[k], m->xyz[3 * (size_t)tt[i] + k]);
            hi[k] = fmax(hi[k], m->xyz[3 * (size_t)tt[i] + k]);
        }
        double grow = 0.5 * (hi[k] - lo[k]);
        lo[k] -= grow;
        hi[k] += grow;
        c0[k] = cell_of(L, k, lo[k]);
        c1[k] = cell_of(L, k, hi[k]);
    }
    for (int x = c0[0]; x <= c1[0]; x++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int z = c0[2]; z <= c1[2]; z++) {
                int c = (x * L->g + y) * L->g + z;
                for (int32_t j = L->start[c]; j < L->start[c + 1]; j++) {
                    int32_t k = L->cell[j];
                    const double *p = L->xyz + 3 * (size_t)L->idx[k];
                    if (p[0] < lo[0] || p[0] > hi[0] || p[1] < lo[1] || p[1] > hi[1] ||
                        p[2] < lo[2] || p[2] > hi[2] || L->score[k] >= 0)
                        continue;
                    double s = bary(m->xyz, tt, p, w);
                    if (s > L->score[k]) {
                        L->score[k] = s;
                        L->best[k] = t;
                    }
                }
            }
}

/* Vertex v's values: the weights w of the corners tt of m's arrays. */
static void interp_at(const mesh_pdata *p, const mesh_pdata *q, const int32_t *tt,
                      const double *w, int32_t v)
{
    int top = 0;

    for (int i = 1; i < 4; i++)
        if (w[i] > w[top])
            top = i;
    for (int32_t i = 0; i < p->n; i++) {
        const mesh_parray *a = &p->a[i];
        double *out = q->a[i].v + (size_t)v * (size_t)a->ncomp;
        for (int32_t c = 0; c < a->ncomp; c++) {
            double s = 0.0;
            for (int j = 0; j < 4; j++)
                s += w[j] * a->v[(size_t)tt[j] * (size_t)a->ncomp + (size_t)c];
            out[c] =
                a->integer ? a->v[(size_t)tt[top] * (size_t)a->ncomp + (size_t)c] : s;
        }
    }
}

/* The new vertices' values, each from the tet L found for it (or, if none
 * was near, the tet of m with the largest smallest weight), its weights
 * clamped to it. */
static void place_new(locator *L, const mesh_t *m, mesh_pdata *q)
{
    for (int32_t k = 0; k < L->n; k++) {
        const double *p = L->xyz + 3 * (size_t)L->idx[k];
        double w[4], s = 0.0;
        if (L->best[k] < 0)
            for (int32_t t = 0; t < m->nt; t++) {
                double sc = bary(m->xyz, m->tets + 4 * (size_t)t, p, w);
                if (sc > L->score[k]) {
                    L->score[k] = sc;
                    L->best[k] = t;
                }
            }
        if (L->best[k] < 0)
            continue; /* every tet flat: the zeros of the copy */
        const int32_t *tt = m->tets + 4 * (size_t)L->best[k];
        bary(m->xyz, tt, p, w);
        for (int j = 0; j < 4; j++) {
            w[j] = w[j] > 0 ? w[j] : 0.0;
            s += w[j];
        }
        for (int j = 0; j < 4; j++)
            w[j] = s > 0 ? w[j] / s : 0.25;
        interp_at(m->pdata, q, tt, w, L->idx[k]);
    }
}

/* q: m's arrays for nv vertices, the kept ones' values in place, the rest 0;
 * is_new[v] = 1 for the vertices no vmap entry names. */
static mesh_pdata *carry_kept(const mesh_t *m, int32_t nv, const int32_t *vmap,
                              uint8_t *is_new)
{
    const mesh_pdata *p = m->pdata;
    mesh_pdata *q = qdc_calloc(1, sizeof *q);

    if (!q || !(q->a = qdc_calloc((size_t)p->n + 1, sizeof *q->a)) ||
        !(q->made = qdc_calloc((size_t)nv + 1, 1))) {
        mesh_pdata_free(q);
        return NULL;
    }
    for (int32_t i = 0; i < p->n; i++) {
        const mesh_parray *a = &p->a[i];
        size_t nc = (size_t)a->ncomp;
        q->n = i + 1;
        if (parray_like(&q->a[i], a, (size_t)nv * nc)) {
            mesh_pdata_free(q);
            return NULL;
        }
        for (int32_t v = 0; v < m->nv; v++)
            if (vmap[v] >= 0)
                memcpy(q->a[i].v + (size_t)vmap[v] * nc, a->v + (size_t)v * nc,
                       nc * sizeof(double));
    }
    memset(is_new, 1, (size_t)nv);
    for (int32_t v = 0; v < m->nv; v++)
        if (vmap[v] >= 0) {
            is_new[vmap[v]] = 0;
            q->made[vmap[v]] = p->made ? p->made[v] : 0;
        }
    return q;
}

qdc_status mesh_pdata_remap(const mesh_t *m, int32_t nv, const double *xyz,
                            const int32_t *vmap, mesh_pdata **out, qdc_error *err)
{
    locator L;
    uint8_t *is_new;
    mesh_pdata *q;
    qdc_status st = QDC_OK;

    *out = NULL;
    if (!m->pdata)
        return QDC_OK;
    memset(&L, 0, sizeof L);
    is_new = qdc_malloc((size_t)nv + 1);
    q = is_new ? carry_kept(m, nv, vmap, is_new) : NULL;
    if (q)
        L.idx = qdc_mallocn((size_t)nv + 1, sizeof *L.idx);
    if (!L.idx) {
        st = qdc_fail(err, QDC_ENOMEM, "out of memory for the point data");
        goto out;
    }
    L.xyz = xyz;
    for (int32_t v = 0; v < nv; v++)
        if (is_new[v])
            L.idx[L.n++] = v;
    if (L.n > 0 && m->nt > 0) {
        st = locator_build(&L, m, err);
        if (st != QDC_OK)
            goto out;
        for (int32_t t = 0; t < m->nt; t++)
            locate_tet(&L, m, t);
        place_new(&L, m, q);
    }
    for (int32_t k = 0; k < L.n; k++)
        q->made[L.idx[k]] = 1;
    for (int32_t v = 0; v < nv; v++)
        q->ninterp += q->made[v];
    *out = q;
    q = NULL;
out:
    mesh_pdata_free(q);
    qdc_free(is_new);
    qdc_free(L.idx);
    qdc_free(L.start);
    qdc_free(L.cell);
    qdc_free(L.best);
    qdc_free(L.score);
    return st;
}
