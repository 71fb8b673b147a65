/* spend.c - one Hausdorff bound for all the rounds of a --topology run (spend.h). */
#include "opt/spend.h"

#include "core/base_int.h"
#include "core/mesh_int.h"
#include "opt/slide.h"

#include <math.h>
#include <string.h>

void spend_free(spend *s)
{
    if (!s)
        return;
    qdc_free(s->x0);
    qdc_free(s->spent);
    qdc_free(s->op);
    qdc_free(s->xin);
    qdc_free(s->reach);
    qdc_free(s->kind);
    s->x0 = s->spent = s->xin = s->reach = NULL;
    s->op = s->kind = NULL;
}

/* s's arrays for nv vertices (the old ones freed); 0 when out of memory. */
static int alloc(spend *s, int32_t nv)
{
    spend_free(s);
    s->nv = nv;
    s->x0 = qdc_mallocn(3 * (size_t)nv + 3, sizeof *s->x0);
    s->spent = qdc_calloc((size_t)nv + 1, sizeof *s->spent);
    s->op = qdc_calloc((size_t)nv + 1, 1);
    s->xin = qdc_mallocn(3 * (size_t)nv + 3, sizeof *s->xin);
    s->reach = qdc_calloc((size_t)nv + 1, sizeof *s->reach);
    s->kind = qdc_calloc((size_t)nv + 1, 1);
    return s->x0 && s->spent && s->op && s->xin && s->reach && s->kind;
}

qdc_status spend_new(const mesh_t *m, const opt_options *o, spend *s, qdc_error *err)
{
    memset(s, 0, sizeof *s);
    s->slide = o->boundary == OPT_BOUNDARY_SLIDE;
    s->feature = o->feature_angle;
    if (!alloc(s, m->nv)) {
        spend_free(s);
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    }
    memcpy(s->x0, m->xyz, 3 * (size_t)m->nv * sizeof *s->x0);
    return QDC_OK;
}

qdc_status spend_copy(spend *b, const spend *a, qdc_error *err)
{
    *b = *a;
    b->x0 = b->spent = b->xin = b->reach = NULL;
    b->op = b->kind = NULL;
    if (!alloc(b, a->nv)) {
        spend_free(b);
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    }
    memcpy(b->x0, a->x0, 3 * (size_t)a->nv * sizeof *b->x0);
    memcpy(b->spent, a->spent, (size_t)a->nv * sizeof *b->spent);
    memcpy(b->op, a->op, (size_t)a->nv);
    return QDC_OK;
}

static double dist(const double *p, const double *q)
{
    return sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                (p[2] - q[2]) * (p[2] - q[2]));
}

/* s->kind of m's vertices as the smoother bounds them (opt.h, slide.h): 1 a
 * boundary or interface vertex that moves within the bound of where it was;
 * 2 one that does not move (fixed, a corner) or slides on the input's shape (a
 * planar patch, a straight line: nothing of the shape changes); 0 inside. The
 * spent of a vertex of kind 1 on the input's triangles only, from where it is
 * (of kind 2: what it spent before, kept: a vertex that moved as kind 1 and is
 * a corner or flat in a later round's mesh is still that far from the input;
 * it was set to 0 there, and on the 100k-tet ball-scan of scripts/corpus.py
 * --seed 1 `--topology full --hausd rel:3e-3` ended 11% over its bound, a
 * boundary flip and a smoothing built on such a vertex); and s->reach: the
 * largest spent over the boundary and interface triangles at v. */
static qdc_status classify(spend *s, const mesh_t *m, qdc_error *err)
{
    mesh_topo *tp = NULL;
    slide_ctx *sl = NULL;
    qdc_status st = mesh_topo_build(m, &tp, err);

    if (st == QDC_OK && s->slide)
        st = slide_new_kinds(tp, m->xyz, s->feature, &sl, err);
    if (st != QDC_OK)
        goto out;
    for (int32_t v = 0; v < m->nv; v++) {
        uint8_t f = tp->vflag[v];
        s->kind[v] =
            !(f & (MESH_V_BOUNDARY | MESH_V_INTERFACE)) ? 0
            : (f & MESH_V_FIXED) ||
                    (sl && (slide_flat(sl, v) || slide_kind(sl, v) == SLIDE_CORNER))
                ? 2
                : 1;
        if (!s->op[v] && s->kind[v] == 1) /* the triangles at v are the input's */
            s->spent[v] = dist(m->xyz + 3 * (size_t)v, s->x0 + 3 * (size_t)v);
        s->reach[v] = s->spent[v];
    }
    for (int pass = 0; pass < 2; pass++) {
        const int32_t *f = pass ? tp->ifaces : tp->bfaces;
        int32_t n = pass ? tp->nif : tp->nbf;
        for (int32_t k = 0; k < n; k++) {
            const int32_t *tr = f + 3 * (size_t)k;
            double w = fmax(s->spent[tr[0]], fmax(s->spent[tr[1]], s->spent[tr[2]]));
            for (int c = 0; c < 3; c++)
                s->reach[tr[c]] = fmax(s->reach[tr[c]], w);
        }
    }
out:
    slide_free(sl);
    mesh_topo_free(tp);
    return st;
}

qdc_status spend_set_bound(spend *s, const mesh_t *m, double bound, qdc_error *err)
{
    s->bound = bound > 0 ? bound : 0.0;
    return s->bound > 0 ? classify(s, m, err) : QDC_OK;
}

/* What vertex v (kind 1) has left of the bound: a vertex on an operation's
 * triangle by the largest spent around it, one on the input's triangles only by
 * its own distance from its input position. */
static double left(const spend *s, int32_t v)
{
    return s->bound - (s->op[v] ? s->reach[v] : s->spent[v]);
}

qdc_status spend_begin(spend *s, mesh_t *m, opt_options *o, qdc_error *err)
{
    double share = 0.0, best = -1.0;
    uint8_t *held = NULL;
    qdc_status st;

    s->lent = 0;
    if (!(s->bound > 0))
        return QDC_OK;
    st = classify(s, m, err);
    if (st != QDC_OK)
        return st;
    /* the first smoothing spent the whole bound where it was needed, little
     * elsewhere: the round moves most bounded vertices a share of the bound
     * (the largest that most of them still have, halved until then) and
     * holds the rest where they are */
    for (int k = 0; k < 6; k++) {
        double r = s->bound * ldexp(1.0, -k);
        int64_t n = 0;
        for (int32_t v = 0; v < m->nv; v++)
            n += s->kind[v] == 1 && left(s, v) >= r;
        if ((double)n * r > best) {
            best = (double)n * r;
            share = r;
        }
    }
    for (int32_t v = 0; v < m->nv; v++) {
        if (s->kind[v] != 1 || left(s, v) >= share)
            continue;
        if (!held) {
            held = qdc_calloc((size_t)m->nv + 1, 1);
            if (!held)
                return qdc_fail(err, QDC_ENOMEM, "out of memory");
            if (m->fixed)
                memcpy(held, m->fixed, (size_t)m->nv);
        }
        held[v] = 1;
    }
    if (held) {
        s->fixed = m->fixed;
        m->fixed = held;
        s->lent = 1;
    }
    memcpy(s->xin, m->xyz, 3 * (size_t)m->nv * sizeof *s->xin);
    o->hausd = share;
    o->hausd_rel = 0.0;
    return QDC_OK;
}

void spend_end(spend *s, mesh_t *m)
{
    if (s->lent) {
        qdc_free(m->fixed);
        m->fixed = s->fixed;
        s->fixed = NULL;
        s->lent = 0;
    }
    if (!(s->bound > 0))
        return;
    for (int32_t v = 0; v < m->nv; v++) {
        const double *x = m->xyz + 3 * (size_t)v;
        if (s->kind[v] == 0)
            continue;
        if (!s->op[v]) {
            if (s->kind[v] == 1)
                s->spent[v] = dist(x, s->x0 + 3 * (size_t)v);
        } else /* each triangle at v moved by at most v's move more */
            s->spent[v] =
                s->reach[v] + (s->kind[v] == 1 ? dist(x, s->xin + 3 * (size_t)v) : 0.0);
    }
}

qdc_status spend_remap(spend *s, const double *xyz, const int32_t *vmap, int32_t nv,
                       qdc_error *err)
{
    spend b;

    if (spend_copy(&b, s, err) != QDC_OK)
        return QDC_ENOMEM;
    if (!alloc(s, nv)) {
        spend_free(s);
        *s = b;
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    }
    memcpy(s->x0, xyz, 3 * (size_t)nv * sizeof *s->x0);
    for (int32_t v = 0; v < b.nv; v++)
        if (vmap[v] >= 0) {
            memcpy(s->x0 + 3 * (size_t)vmap[v], b.x0 + 3 * (size_t)v, 3 * sizeof *s->x0);
            s->spent[vmap[v]] = b.spent[v];
            s->op[vmap[v]] = b.op[v];
        }
    spend_free(&b);
    return QDC_OK;
}
