/* slide.c - sliding boundary constraints. */
#include "opt/slide.h"

#include "core/tet.h"
#include "core/tri_edges.h"
#include "geom/bderr_int.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct slide_ctx {
    int32_t nv;
    uint8_t *kind;
    uint8_t *on_iface; /* surface vertex of an interface (not of the outer boundary) */
    uint8_t *flat; /* surface vertex on a planar patch, line vertex on a straight line */
    int32_t *near; /* per surface vertex: one of its input faces (projection start) */
    int32_t *sf_ptr; /* per vertex: its input faces (CSR), as vertex triples */
    int32_t *sf_tri;
    double *x0;      /* copy of the input coordinates */
    double *normal;  /* per surface vertex: unit normal of the input surface */
    double *tangent; /* per line vertex: unit direction of the feature line */
    int32_t *fe_ptr; /* per vertex: feature edges around it (CSR), as vertex pairs */
    int32_t *fe_nbr;
    int32_t nfe;
    bderr_bvh *outer;   /* input boundary triangles */
    bderr_bvh *inter;   /* input interface triangles (NULL if none) */
    double bound;       /* > 0: no vertex farther than this from its input position */
    uint8_t *loose;     /* per vertex: freed by slide_release */
    double loose_bound; /* > bound: the bound of the freed vertices instead */
    double lift; /* > 0: curved-surface vertices slide, within this of the surface */
};

static void face_normal(const double *x, const int32_t *f, double n[3])
{
    const double *a = x + 3 * (size_t)f[0], *b = x + 3 * (size_t)f[1],
                 *c = x + 3 * (size_t)f[2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
}

static void normalize(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0) {
        v[0] /= l;
        v[1] /= l;
        v[2] /= l;
    }
}

/* Feature edges: boundary edges whose two boundary faces' normals differ by more
 * than the feature angle, plus boundary edges with other than 2 boundary faces. */
static qdc_status find_features(slide_ctx *s, const mesh_topo *tp, const double *x0,
                                double feature_angle, int32_t *deg)
{
    size_t ne = 3 * (size_t)tp->nbf;
    tri_edge *e = NULL;
    int32_t *pairs = NULL, np = 0;
    double cosmax = cos(feature_angle * 3.14159265358979323846 / 180.0);

    if (tri_edges_sorted(tp->bfaces, tp->nbf, tp->nv, &e) != QDC_OK)
        return QDC_ENOMEM;
    pairs = qdc_mallocn(ne + 1, 2 * sizeof(int32_t));
    if (!pairs) {
        qdc_free(e);
        return QDC_ENOMEM;
    }
    for (size_t i = 0; i < ne;) {
        size_t j = tri_edges_run(e, ne, i);
        int feature;
        if (j - i == 2) {
            double n1[3], n2[3];
            face_normal(x0, tp->bfaces + 3 * (size_t)e[i].tri, n1);
            face_normal(x0, tp->bfaces + 3 * (size_t)e[i + 1].tri, n2);
            normalize(n1);
            normalize(n2);
            feature = n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2] < cosmax;
        } else {
            feature = 1; /* non-manifold surface edge: keep it as a feature */
        }
        if (feature) {
            pairs[2 * np] = e[i].lo;
            pairs[2 * np + 1] = e[i].hi;
            np++;
            deg[e[i].lo]++;
            deg[e[i].hi]++;
        }
        i = j;
    }
    qdc_free(e);
    s->nfe = np;
    s->fe_ptr = qdc_calloc((size_t)tp->nv + 1, sizeof(int32_t));
    s->fe_nbr = qdc_mallocn(2 * (size_t)np + 1, sizeof(int32_t));
    if (!s->fe_ptr || !s->fe_nbr) {
        qdc_free(pairs);
        return QDC_ENOMEM;
    }
    for (int32_t v = 0; v < tp->nv; v++)
        s->fe_ptr[v + 1] = s->fe_ptr[v] + deg[v];
    {
        int32_t *pos = qdc_mallocn((size_t)tp->nv + 1, sizeof(int32_t));
        if (!pos) {
            qdc_free(pairs);
            return QDC_ENOMEM;
        }
        memcpy(pos, s->fe_ptr, ((size_t)tp->nv + 1) * sizeof(int32_t));
        for (int32_t i = 0; i < np; i++) {
            s->fe_nbr[pos[pairs[2 * i]]++] = pairs[2 * i + 1];
            s->fe_nbr[pos[pairs[2 * i + 1]]++] = pairs[2 * i];
        }
        qdc_free(pos);
    }
    qdc_free(pairs);
    return QDC_OK;
}

typedef struct {
    int32_t v[3]; /* sorted */
} tri_key;

static int tri_cmp(const void *x, const void *y)
{
    const tri_key *p = x, *q = y;
    for (int k = 0; k < 3; k++)
        if (p->v[k] != q->v[k])
            return p->v[k] < q->v[k] ? -1 : 1;
    return 0;
}

static tri_key make_key(int32_t a, int32_t b, int32_t c)
{
    tri_key k;

    tet_sort3(a, b, c, k.v);
    return k;
}

static int is_feature_edge(const slide_ctx *s, int32_t a, int32_t b)
{
    for (int32_t k = s->fe_ptr[a]; k < s->fe_ptr[a + 1]; k++)
        if (s->fe_nbr[k] == b)
            return 1;
    return 0;
}

int32_t slide_smooth_ears(const slide_ctx *s, const mesh_topo *tp, uint8_t *ear)
{
    static const int omit_pair[4][4][2] = {{{-1, -1}, {2, 3}, {1, 3}, {1, 2}},
                                           {{2, 3}, {-1, -1}, {0, 3}, {0, 2}},
                                           {{1, 3}, {0, 3}, {-1, -1}, {0, 1}},
                                           {{1, 2}, {0, 2}, {0, 1}, {-1, -1}}};
    tri_key *keys = qdc_mallocn((size_t)tp->nbf + 1, sizeof *keys);
    int32_t count = 0;

    if (!keys)
        return -1;
    for (int32_t f = 0; f < tp->nbf; f++)
        keys[f] = make_key(tp->bfaces[3 * (size_t)f], tp->bfaces[3 * (size_t)f + 1],
                           tp->bfaces[3 * (size_t)f + 2]);
    qsort(keys, (size_t)tp->nbf, sizeof *keys, tri_cmp);
    for (int32_t t = 0; t < tp->nt; t++) {
        const int32_t *tt = tp->tets + 4 * (size_t)t;
        int onb[4], nb = 0, first = -1, pin = 0;
        for (int a = 0; a < 4; a++)
            if (!(tp->vflag[tt[a]] & MESH_V_BOUNDARY))
                goto next;
        for (int a = 0; a < 4; a++) { /* face a: the one without corner a */
            tri_key k = make_key(tt[(a + 1) & 3], tt[(a + 2) & 3], tt[(a + 3) & 3]);
            onb[a] = bsearch(&k, keys, (size_t)tp->nbf, sizeof *keys, tri_cmp) != NULL;
            if (onb[a]) {
                if (nb == 1) {
                    const int *e = omit_pair[first][a];
                    pin = !is_feature_edge(s, tt[e[0]], tt[e[1]]);
                }
                if (nb == 0)
                    first = a;
                nb++;
            }
        }
        if (nb >= 3)
            pin = 1;
        ear[t] = (uint8_t)pin;
        count += pin;
        continue;
    next:
        ear[t] = 0;
    }
    qdc_free(keys);
    return count;
}

/* Whether the faces f (n of them, 3 vertices each) around surface vertex v
 * all lie in one plane with it: every face normal within FLAT_COS of v's
 * normal (either sign on an interface, whose faces come in both orientations). */
#define FLAT_COS (1.0 - 1e-10) /* 1.4e-5 radians */

static void flat_faces(slide_ctx *s, const double *x0, const int32_t *f, int32_t n,
                       uint8_t *bad, int iface)
{
    for (int32_t i = 0; i < n; i++) {
        double nf[3];
        face_normal(x0, f + 3 * (size_t)i, nf);
        normalize(nf);
        for (int k = 0; k < 3; k++) {
            int32_t v = f[3 * (size_t)i + k];
            const double *nv = s->normal + 3 * (size_t)v;
            double d = nf[0] * nv[0] + nf[1] * nv[1] + nf[2] * nv[2];
            if (s->on_iface[v] != iface)
                continue;
            if ((iface ? fabs(d) : d) < FLAT_COS)
                bad[v] = 1;
        }
    }
}

/* s->flat: surface vertices whose input star is planar, and line vertices
 * whose two feature edges are collinear. Sliding such a vertex keeps the
 * shape exactly, however far it goes, so the --hausd bound does not hold
 * it back (slide_project). */
static void mark_flat(slide_ctx *s, const mesh_topo *tp, const double *x0)
{
    uint8_t *bad = s->flat; /* reused: 1 = not flat, inverted below */

    flat_faces(s, x0, tp->bfaces, tp->nbf, bad, 0);
    flat_faces(s, x0, tp->ifaces, tp->nif, bad, 1);
    for (int32_t v = 0; v < tp->nv; v++) {
        int flat = 0;
        if (s->kind[v] == SLIDE_SURFACE)
            flat = !bad[v];
        else if (s->kind[v] == SLIDE_LINE) {
            const double *o = x0 + 3 * (size_t)v;
            const double *a = x0 + 3 * (size_t)s->fe_nbr[s->fe_ptr[v]];
            const double *b = x0 + 3 * (size_t)s->fe_nbr[s->fe_ptr[v] + 1];
            double da[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]};
            double db[3] = {o[0] - b[0], o[1] - b[1], o[2] - b[2]};
            normalize(da);
            normalize(db);
            flat = da[0] * db[0] + da[1] * db[1] + da[2] * db[2] >= FLAT_COS;
        }
        s->flat[v] = (uint8_t)flat;
    }
}

/* s->sf_*: the input faces around each surface vertex (boundary faces for
 * outer-boundary vertices, interface faces for interface vertices). */
static qdc_status star_faces(slide_ctx *s, const mesh_topo *tp)
{
    int32_t *pos;

    s->sf_ptr = qdc_calloc((size_t)tp->nv + 1, sizeof(int32_t));
    if (!s->sf_ptr)
        return QDC_ENOMEM;
    for (int pass = 0; pass < 2; pass++) {
        for (int which = 0; which < 2; which++) {
            const int32_t *f = which ? tp->ifaces : tp->bfaces;
            int32_t n = which ? tp->nif : tp->nbf;
            for (int32_t i = 0; i < n; i++)
                for (int k = 0; k < 3; k++) {
                    int32_t v = f[3 * (size_t)i + k];
                    if (s->kind[v] != SLIDE_SURFACE || s->on_iface[v] != which)
                        continue;
                    if (!pass)
                        s->sf_ptr[v + 1]++;
                    else
                        memcpy(s->sf_tri + 3 * (size_t)pos[v]++, f + 3 * (size_t)i,
                               3 * sizeof(int32_t));
                }
        }
        if (pass)
            break;
        for (int32_t v = 0; v < tp->nv; v++)
            s->sf_ptr[v + 1] += s->sf_ptr[v];
        s->sf_tri = qdc_mallocn(3 * (size_t)s->sf_ptr[tp->nv] + 1, sizeof(int32_t));
        pos = qdc_mallocn((size_t)tp->nv + 1, sizeof(int32_t));
        if (!s->sf_tri || !pos) {
            qdc_free(pos);
            return QDC_ENOMEM;
        }
        memcpy(pos, s->sf_ptr, (size_t)tp->nv * sizeof(int32_t));
    }
    qdc_free(pos);
    return QDC_OK;
}

/* Closest point out to p on the input faces around surface vertex c; *edge
 * receives 1 when it lies on the star's outer edge (where a face beyond may
 * be closer) and *next the end of that edge nearer to it. 0 if c has no faces. */
static int star_closest(const slide_ctx *s, int32_t c, const double p[3], double out[3],
                        int *edge, int32_t *next)
{
    double best = INFINITY, cp[3];
    int32_t bi = -1;

    for (int32_t k = s->sf_ptr[c]; k < s->sf_ptr[c + 1]; k++) {
        const int32_t *t = s->sf_tri + 3 * (size_t)k;
        double d =
            bderr_point_triangle(p, s->x0 + 3 * (size_t)t[0], s->x0 + 3 * (size_t)t[1],
                                 s->x0 + 3 * (size_t)t[2], cp);
        if (d < best) {
            best = d;
            bi = k;
            memcpy(out, cp, sizeof cp);
        }
    }
    if (bi < 0)
        return 0;
    {
        /* on the edge opposite c (where the next face begins)? */
        const int32_t *t = s->sf_tri + 3 * (size_t)bi;
        const double *a = NULL, *b = NULL;
        int32_t ia = -1, ib = -1;
        double e[3], w[3], ee, tt, dd = 0;
        for (int k = 0; k < 3; k++)
            if (t[k] == c) {
                ia = t[(k + 1) % 3];
                ib = t[(k + 2) % 3];
                a = s->x0 + 3 * (size_t)ia;
                b = s->x0 + 3 * (size_t)ib;
            }
        if (!a)
            return 0;
        for (int k = 0; k < 3; k++) {
            e[k] = b[k] - a[k];
            w[k] = out[k] - a[k];
        }
        ee = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
        tt = ee > 0 ? (w[0] * e[0] + w[1] * e[1] + w[2] * e[2]) / ee : 0;
        tt = tt < 0 ? 0 : tt > 1 ? 1 : tt;
        for (int k = 0; k < 3; k++) {
            double r = w[k] - tt * e[k];
            dd += r * r;
        }
        *edge = !(dd > 1e-24 * ee);
        *next = tt < 0.5 ? ia : ib;
        return 1;
    }
}

/* Steps of the walk in project_star before the whole-surface search. */
#define PROJ_WALK 4

/* Closest point to p on the input faces around surface vertex v, if it lies
 * inside v's star (not on its outer edges, where a face beyond may be
 * closer). That is the closest point of v's own part of the surface; the
 * whole-surface search gives the same point unless another part of the
 * surface (across a thin wall) is closer still, which a vertex sliding on its
 * own side should ignore anyway. A point on the star's outer edge walks on to
 * the star of that edge's nearer end (same surface), up to PROJ_WALK stars:
 * measured on an 800k-tet ball, 4% of the projections left v's star and took
 * the whole-surface search, a third of the projection time. 0 if the search
 * is needed. */
static int project_star(const slide_ctx *s, int32_t v, const double p[3], double out[3])
{
    int32_t c = v;

    for (int step = 0; step < PROJ_WALK; step++) {
        int edge = 0;
        int32_t next = -1;
        if (!star_closest(s, c, p, out, &edge, &next))
            return 0;
        if (!edge)
            return 1;
        if (next < 0 || s->kind[next] != SLIDE_SURFACE ||
            s->on_iface[next] != s->on_iface[v])
            return 0;
        c = next;
    }
    return 0;
}

/* Area-weighted vertex normals of the input boundary surface (and of the
 * interfaces) into s->normal, not yet normalized. */
static void vertex_normals(slide_ctx *s, const mesh_topo *tp, const double *x0)
{
    for (int32_t f = 0; f < tp->nbf; f++) {
        double n[3];
        face_normal(x0, tp->bfaces + 3 * (size_t)f, n);
        for (int k = 0; k < 3; k++)
            for (int c = 0; c < 3; c++)
                s->normal[3 * (size_t)tp->bfaces[3 * (size_t)f + k] + c] += n[c];
    }
    for (int32_t f = 0; f < tp->nif; f++) {
        double n[3];
        face_normal(x0, tp->ifaces + 3 * (size_t)f, n);
        for (int k = 0; k < 3; k++) {
            int32_t v = tp->ifaces[3 * (size_t)f + k];
            double *nv = s->normal + 3 * (size_t)v;
            /* interface faces come with either orientation: align to the sum */
            double sg = nv[0] * n[0] + nv[1] * n[1] + nv[2] * n[2] < 0 ? -1.0 : 1.0;
            if (tp->vflag[v] & MESH_V_BOUNDARY)
                continue;
            for (int c = 0; c < 3; c++)
                nv[c] += sg * n[c];
        }
    }
}

/* Each boundary and interface vertex's kind (surface, line, corner), its
 * unit normal and, on a line, its unit tangent; deg: feature edges at each
 * vertex. */
static void classify(slide_ctx *s, const mesh_topo *tp, const double *x0,
                     const int32_t *deg)
{
    for (int32_t v = 0; v < tp->nv; v++) {
        uint8_t fl = tp->vflag[v];
        if (!(fl & (MESH_V_BOUNDARY | MESH_V_INTERFACE)))
            continue;
        normalize(s->normal + 3 * (size_t)v);
        if ((fl & MESH_V_FIXED) || ((fl & MESH_V_BOUNDARY) && (fl & MESH_V_INTERFACE)))
            s->kind[v] = SLIDE_CORNER;
        else if (deg[v] == 2) {
            int32_t a = s->fe_nbr[s->fe_ptr[v]], b = s->fe_nbr[s->fe_ptr[v] + 1];
            double *t = s->tangent + 3 * (size_t)v;
            for (int c = 0; c < 3; c++)
                t[c] = x0[3 * (size_t)b + c] - x0[3 * (size_t)a + c];
            normalize(t);
            s->kind[v] = SLIDE_LINE;
        } else if (deg[v] > 0)
            s->kind[v] = SLIDE_CORNER; /* 1 (line end) or 3+ feature edges */
        else
            s->kind[v] = SLIDE_SURFACE;
        s->on_iface[v] = !(fl & MESH_V_BOUNDARY);
    }
}

/* slide_new, and with project 0 slide_new_kinds. */
static qdc_status slide_build(const mesh_topo *tp, const double *x0, double feature_angle,
                              int project, slide_ctx **out, qdc_error *err)
{
    slide_ctx *s = qdc_calloc(1, sizeof *s);
    int32_t *deg = qdc_calloc((size_t)tp->nv, sizeof(int32_t));
    qdc_status st = QDC_ENOMEM;

    *out = NULL;
    if (!s || !deg)
        goto fail;
    s->nv = tp->nv;
    s->kind = qdc_calloc((size_t)tp->nv, 1);
    s->on_iface = qdc_calloc((size_t)tp->nv, 1);
    s->x0 = qdc_mallocn(3 * (size_t)tp->nv, sizeof(double));
    s->normal = qdc_calloc(3 * (size_t)tp->nv, sizeof(double));
    s->tangent = qdc_calloc(3 * (size_t)tp->nv, sizeof(double));
    s->flat = qdc_calloc((size_t)tp->nv, 1);
    s->loose = qdc_calloc((size_t)tp->nv, 1);
    s->near = qdc_mallocn((size_t)tp->nv + 1, sizeof(int32_t));
    if (!s->kind || !s->on_iface || !s->x0 || !s->normal || !s->tangent || !s->flat ||
        !s->loose || !s->near)
        goto fail;
    memcpy(s->x0, x0, 3 * (size_t)tp->nv * sizeof(double));
    st = find_features(s, tp, x0, feature_angle, deg);
    if (st != QDC_OK)
        goto fail;
    vertex_normals(s, tp, x0);
    classify(s, tp, x0, deg);
    mark_flat(s, tp, x0);
    if (!project) {
        qdc_free(deg);
        *out = s;
        return QDC_OK;
    }
    for (int32_t v = 0; v < tp->nv; v++)
        s->near[v] = -1;
    for (int32_t f = 0; f < tp->nbf; f++)
        for (int k = 0; k < 3; k++)
            if (!s->on_iface[tp->bfaces[3 * (size_t)f + k]])
                s->near[tp->bfaces[3 * (size_t)f + k]] = f;
    for (int32_t f = 0; f < tp->nif; f++)
        for (int k = 0; k < 3; k++)
            if (s->on_iface[tp->ifaces[3 * (size_t)f + k]])
                s->near[tp->ifaces[3 * (size_t)f + k]] = f;
    st = star_faces(s, tp);
    if (st != QDC_OK)
        goto fail;
    st = bderr_bvh_build(x0, tp->nv, tp->bfaces, tp->nbf, &s->outer, err);
    if (st == QDC_OK && tp->nif > 0)
        st = bderr_bvh_build(x0, tp->nv, tp->ifaces, tp->nif, &s->inter, err);
    if (st != QDC_OK)
        goto fail;
    qdc_free(deg);
    *out = s;
    return QDC_OK;
fail:
    qdc_free(deg);
    slide_free(s);
    return st;
}

qdc_status slide_new(const mesh_topo *tp, const double *x0, double feature_angle,
                     slide_ctx **out, qdc_error *err)
{
    return slide_build(tp, x0, feature_angle, 1, out, err);
}

qdc_status slide_new_kinds(const mesh_topo *tp, const double *x0, double feature_angle,
                           slide_ctx **out, qdc_error *err)
{
    return slide_build(tp, x0, feature_angle, 0, out, err);
}

void slide_free(slide_ctx *s)
{
    if (!s)
        return;
    qdc_free(s->kind);
    qdc_free(s->on_iface);
    qdc_free(s->flat);
    qdc_free(s->loose);
    qdc_free(s->near);
    qdc_free(s->sf_ptr);
    qdc_free(s->sf_tri);
    qdc_free(s->x0);
    qdc_free(s->normal);
    qdc_free(s->tangent);
    qdc_free(s->fe_ptr);
    qdc_free(s->fe_nbr);
    bderr_bvh_free(s->outer);
    bderr_bvh_free(s->inter);
    qdc_free(s);
}

int slide_kind(const slide_ctx *s, int32_t v)
{
    return s->kind[v];
}

int32_t slide_n_feature_edges(const slide_ctx *s)
{
    return s->nfe;
}

/* Closest point on the feature segments around v and around its feature
 * neighbours (a vertex moves at most a fraction of an edge per step). */
static void project_line(const slide_ctx *s, int32_t v, const double p[3], double out[3])
{
    double best = INFINITY;

    memcpy(out, s->x0 + 3 * (size_t)v, 3 * sizeof(double));
    for (int32_t k = s->fe_ptr[v]; k < s->fe_ptr[v + 1]; k++) {
        int32_t u = s->fe_nbr[k];
        for (int32_t l = s->fe_ptr[u]; l < s->fe_ptr[u + 1]; l++) {
            double cp[3];
            int32_t w = s->fe_nbr[l];
            double d =
                bderr_point_segment(p, s->x0 + 3 * (size_t)u, s->x0 + 3 * (size_t)w, cp);
            if (d < best) {
                best = d;
                memcpy(out, cp, sizeof cp);
            }
        }
    }
}

void slide_set_bound(slide_ctx *s, double r)
{
    s->bound = r > 0 ? r : 0.0;
}

void slide_set_lift(slide_ctx *s, double r)
{
    s->lift = r > 0 ? r : 0.0;
}

void slide_clamp(const double *x0, int32_t v, double r, double p[3])
{
    const double *o = x0 + 3 * (size_t)v;
    double d[3] = {p[0] - o[0], p[1] - o[1], p[2] - o[2]};
    double n = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);

    if (n > r)
        for (int k = 0; k < 3; k++)
            p[k] = o[k] + d[k] * (r / n);
}

void slide_release(slide_ctx *s, int32_t v, int unbounded)
{
    if (s->kind[v] == SLIDE_CORNER && s->on_iface[v])
        return;
    s->loose[v] = 1;
    if (s->bound > 0 &&
        !(unbounded &&
          s->on_iface[v])) { /* free in space, within the bound of its input position */
        s->kind[v] = SLIDE_SURFACE;
        s->flat[v] = 0;
    } else {
        s->kind[v] = SLIDE_INTERIOR;
    }
}

int slide_flat(const slide_ctx *s, int32_t v)
{
    return s->flat[v];
}

int slide_lifts(const slide_ctx *s, int32_t v)
{
    return (s->bound > 0 || s->lift > 0) && s->kind[v] == SLIDE_SURFACE && !s->flat[v];
}

void slide_project(const slide_ctx *s, int32_t v, const double p[3], double out[3])
{
    if (s->kind[v] == SLIDE_INTERIOR || !(s->bound > 0 || s->lift > 0)) {
        slide_project_free(s, v, p, out);
        return;
    }
    if (s->flat[v]) { /* on a planar patch or a straight line: the shape holds */
        slide_project_free(s, v, p, out);
        return;
    }
    /* Curved parts. A move off a curved surface is what opens the tets whose
     * four corners are on it. Without a bound a surface vertex slides and
     * leaves the surface by at most s->lift (the default mode: every vertex
     * within s->lift of the input surface); with a bound it moves freely
     * within the bound of its input position (then the Hausdorff distance
     * holds, slide.h). A curved feature line's vertex stays on its line. */
    if (s->kind[v] == SLIDE_SURFACE && !(s->bound > 0)) {
        /* slide on the surface, and off it by at most s->lift */
        double q[3], d[3], n;
        slide_project_free(s, v, p, q);
        for (int k = 0; k < 3; k++)
            d[k] = p[k] - q[k];
        n = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (int k = 0; k < 3; k++)
            out[k] = q[k] + (n > s->lift ? d[k] * (s->lift / n) : d[k]);
        return;
    }
    if (s->kind[v] == SLIDE_SURFACE)
        memcpy(out, p, 3 * sizeof(double));
    else
        slide_project_free(s, v, p, out);
    if (s->bound > 0)
        slide_clamp(s->x0, v,
                    s->loose[v] && s->loose_bound > s->bound ? s->loose_bound : s->bound,
                    out);
}

void slide_set_loose_bound(slide_ctx *s, double r)
{
    s->loose_bound = r > 0 ? r : 0.0;
}

void slide_project_free(const slide_ctx *s, int32_t v, const double p[3], double out[3])
{
    switch (s->kind[v]) {
    case SLIDE_SURFACE:
        /* outer-boundary vertices onto the input boundary, interface vertices
         * onto the input interface */
        if (!project_star(s, v, p, out))
            bderr_bvh_closest_near(s->on_iface[v] ? s->inter : s->outer, p, s->near[v],
                                   out, NULL);
        break;
    case SLIDE_LINE:
        project_line(s, v, p, out);
        break;
    case SLIDE_CORNER:
        memcpy(out, s->x0 + 3 * (size_t)v, 3 * sizeof(double));
        break;
    default:
        memcpy(out, p, 3 * sizeof(double));
    }
}

void slide_tangent(const slide_ctx *s, int32_t v, const double g[3], double out[3])
{
    const double *n = s->normal + 3 * (size_t)v, *t = s->tangent + 3 * (size_t)v;
    double d;

    switch (s->kind[v]) {
    case SLIDE_SURFACE:
        if (slide_lifts(s, v)) {
            memcpy(out, g, 3 * sizeof(double));
            break;
        }
        d = g[0] * n[0] + g[1] * n[1] + g[2] * n[2];
        for (int c = 0; c < 3; c++)
            out[c] = g[c] - d * n[c];
        break;
    case SLIDE_LINE:
        d = g[0] * t[0] + g[1] * t[1] + g[2] * t[2];
        for (int c = 0; c < 3; c++)
            out[c] = d * t[c];
        break;
    case SLIDE_CORNER:
        out[0] = out[1] = out[2] = 0.0;
        break;
    default:
        memcpy(out, g, 3 * sizeof(double));
    }
}
