/* report.c - mesh quality evaluation and the JSON report (docs/method.md §9). */
#include "eval/report.h"

#include "eval/outcome.h"

#include "core/mesh_int.h"
#include "core/tet.h"
#include "core/tri_edges.h"
#include "geom/metric_int.h"
#include "geom/vec3.h"
#include "opt/opt_int.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const int report_dmin_thresholds[4] = {5, 15, 30, 40};
const int report_dmax_thresholds[4] = {175, 165, 150, 140};

/* Tets measured at once by report_quality_faces, then added up in order. */
#define SCAN_BLOCK 65536
#define SCAN_RANGES 16 /* of a block, counted each by one thread */

/* What the scan takes from one tet. */
typedef struct {
    double eta, vl, cn; /* cn: NAN unless valid and finite */
    double amin, amax;  /* its smallest and largest dihedral angle, degrees */
    uint8_t kind;       /* 0 valid, 1 inverted, 2 degenerate */
    uint8_t bin[6];     /* each angle's histogram bin */
} tet_measure;

typedef struct {
    double sum, sum2, vsum, cnsum;
    int32_t nvalid;
    int worst; /* a q_min was found (worst_tet set) */
} scan_sums;

#define RAD2DEG (180.0 / 3.14159265358979323846)
#define BIN_CELLS 2048 /* cells of the cosine per unit, for the first guess */

/* A dihedral angle's histogram bin from its cosine c, without acos: the bin
 * (int)(acos(c) * RAD2DEG), clamped to the bins, falls as c rises (acos is
 * decreasing), so bin >= k exactly when c <= lim[k], the largest such cosine
 * (found once by bisection over the doubles, with acos itself: the same bins
 * as that formula). guess[i]: the bin at the lower end of cell i of [-1, 1].
 * acos was 6 of a tet's measures and a tenth of a 1M-tet report's time. */
typedef struct {
    double lim[REPORT_HIST_BINS]; /* lim[0] unused */
    uint8_t guess[2 * BIN_CELLS + 1];
} bin_table;

static int bin_of_angle(double a)
{
    return !(a >= 0) ? 0 : a >= REPORT_HIST_BINS ? REPORT_HIST_BINS - 1 : (int)a;
}

/* An order-keeping map of the doubles onto the integers, and back. */
static int64_t dkey(double d)
{
    int64_t b;

    memcpy(&b, &d, sizeof b);
    return b >= 0 ? b : -(b & INT64_MAX);
}

static double dval(int64_t k)
{
    int64_t b = k >= 0 ? k : (-k) | INT64_MIN;
    double d;

    memcpy(&d, &b, sizeof d);
    return d;
}

static void bin_table_init(bin_table *bt)
{
    bt->lim[0] = 1.0;
    for (int k = 1; k < REPORT_HIST_BINS; k++) {
        int64_t lo = dkey(-1.0), hi = dkey(1.0); /* bin(lo) >= k > bin(hi) */
        while (hi - lo > 1) {
            int64_t mid = lo + (hi - lo) / 2;
            if (bin_of_angle(acos(dval(mid)) * RAD2DEG) >= k)
                lo = mid;
            else
                hi = mid;
        }
        bt->lim[k] = dval(lo);
    }
    for (int i = 0; i <= 2 * BIN_CELLS; i++)
        bt->guess[i] = (uint8_t)bin_of_angle(acos((double)i / BIN_CELLS - 1.0) * RAD2DEG);
}

/* The bin of cosine c in [-1, 1] (0 for a NaN, as the formula's cast gives
 * none). */
static int bin_of_cos(const bin_table *bt, double c)
{
    int b;

    if (!(c >= -1.0 && c <= 1.0))
        return 0;
    b = bt->guess[(int)((c + 1.0) * BIN_CELLS)];
    while (b + 1 < REPORT_HIST_BINS && c <= bt->lim[b + 1])
        b++;
    while (b > 0 && c > bt->lim[b])
        b--;
    return b;
}

/* Tet t of m in its positive vertex order (flip) into *o. */
static void measure_tet(const mesh_t *m, const uint8_t *flip, const bin_table *bt,
                        int32_t t, tet_measure *o)
{
    const int32_t *tt = m->tets + 4 * (size_t)t;
    int a = flip[t] ? 1 : 0, b = flip[t] ? 0 : 1; /* positive vertex order */
    const double *p0 = m->xyz + 3 * (size_t)tt[a], *p1 = m->xyz + 3 * (size_t)tt[b];
    const double *p2 = m->xyz + 3 * (size_t)tt[2], *p3 = m->xyz + 3 * (size_t)tt[3];
    metric_parts pt;
    double c[6], amin = 180, amax = 0, cmin = 2, cmax = -2;
    unsigned flat;

    metric_parts_of(p0, p1, p2, p3, &pt);
    o->eta = metric_mean_ratio(&pt);
    o->vl = metric_vol_length(&pt);
    o->cn = NAN;
    o->kind = pt.vol < 0 ? 1 : geom_tet_degenerate(6.0 * pt.vol, pt.l2sum) ? 2 : 0;
    if (!o->kind) /* condition number ||S|| ||S^-1|| / 3 = ||S|| ||adj S|| / (3 sigma) =
                     MICN */
        o->cn = metric_qt(OPT_METRIC_MICN, &pt, 0.0);
    flat = metric_dihedral_cosines(p0, p1, p2, p3, c);
    for (int e = 0; e < 6; e++) {
        if (flat >> e & 1) { /* exactly 0 or 180 degrees */
            double ang = e & 1 ? 180.0 : 0.0;
            amin = ang < amin ? ang : amin;
            amax = ang > amax ? ang : amax;
            o->bin[e] = (uint8_t)bin_of_angle(ang);
            continue;
        }
        cmin = c[e] < cmin ? c[e] : cmin;
        cmax = c[e] > cmax ? c[e] : cmax;
        o->bin[e] = (uint8_t)bin_of_cos(bt, c[e]);
    }
    if (cmax >= -1.0) { /* the extreme angles: acos is decreasing */
        double lo = acos(cmax) * RAD2DEG, hi = acos(cmin) * RAD2DEG;
        amin = lo < amin ? lo : amin;
        amax = hi > amax ? hi : amax;
    }
    o->amin = amin;
    o->amax = amax;
}

/* What a range of tets adds up to in the order-free parts of a scan: counts,
 * minima and maxima (the first tet of the smallest mean ratio), the
 * histogram. Ranges are scanned in parallel and merged in tet order. */
typedef struct {
    double q_min, vl_min, cn_max, dih_min, dih_max;
    int32_t worst_tet, n_inverted, n_degenerate;
    int32_t n_dmin_lt[4], n_dmax_gt[4];
    int64_t hist[REPORT_HIST_BINS];
} scan_part;

static void part_clear(scan_part *p)
{
    memset(p, 0, sizeof *p);
    p->q_min = p->vl_min = p->dih_min = INFINITY;
    p->dih_max = -INFINITY;
    p->worst_tet = -1;
}

/* Tet t's measures o added to p. */
static void part_add(scan_part *p, const tet_measure *o, int32_t t)
{
    if (o->eta < p->q_min) {
        p->q_min = o->eta;
        p->worst_tet = t;
    }
    if (o->vl < p->vl_min)
        p->vl_min = o->vl;
    p->n_inverted += o->kind == 1;
    p->n_degenerate += o->kind == 2;
    if (isfinite(o->cn) && o->cn > p->cn_max)
        p->cn_max = o->cn;
    for (int e = 0; e < 6; e++)
        p->hist[o->bin[e]]++;
    if (o->amin < p->dih_min)
        p->dih_min = o->amin;
    if (o->amax > p->dih_max)
        p->dih_max = o->amax;
    for (int k = 0; k < 4; k++) {
        p->n_dmin_lt[k] += o->amin < report_dmin_thresholds[k];
        p->n_dmax_gt[k] += o->amax > report_dmax_thresholds[k];
    }
}

/* Range p (after the ranges already merged) into q and acc: the comparisons
 * of one serial pass in tet order. */
static void part_merge(report_quality *q, const scan_part *p, scan_sums *acc)
{
    if (p->q_min < q->q_min) {
        q->q_min = p->q_min;
        q->worst_tet = p->worst_tet;
        acc->worst = 1;
    }
    if (p->vl_min < q->vl_min)
        q->vl_min = p->vl_min;
    q->n_inverted += p->n_inverted;
    q->n_degenerate += p->n_degenerate;
    if (p->cn_max > q->cn_max)
        q->cn_max = p->cn_max;
    for (int b = 0; b < REPORT_HIST_BINS; b++)
        q->hist[b] += p->hist[b];
    if (p->dih_min < q->dih_min)
        q->dih_min = p->dih_min;
    if (p->dih_max > q->dih_max)
        q->dih_max = p->dih_max;
    for (int k = 0; k < 4; k++) {
        q->n_dmin_lt[k] += p->n_dmin_lt[k];
        q->n_dmax_gt[k] += p->n_dmax_gt[k];
    }
}

/* Every tet of m (in the vertex order flip gives it) measured into q and acc,
 * block by block: measured, counted and compared per range in parallel, the
 * ranges merged in tet order, the sums in one pass in tet order, so the same
 * bits at any thread count (the serial adding up was 0.1 s of a 1M-tet
 * report). 0 if out of memory. */
static int scan_tets(const mesh_t *m, const uint8_t *flip, report_quality *q,
                     scan_sums *acc)
{
    tet_measure *ms = qdc_mallocn(SCAN_BLOCK, sizeof *ms);
    scan_part *parts = qdc_mallocn(SCAN_RANGES, sizeof *parts);
    bin_table *bt = qdc_mallocn(1, sizeof *bt);

    if (!ms || !parts || !bt) {
        qdc_free(ms);
        qdc_free(parts);
        qdc_free(bt);
        return 0;
    }
    bin_table_init(bt);
    for (int32_t t0 = 0; t0 < m->nt; t0 += SCAN_BLOCK) {
        int32_t nb = m->nt - t0 < SCAN_BLOCK ? m->nt - t0 : SCAN_BLOCK;
#pragma omp parallel for schedule(static)
        for (int r = 0; r < SCAN_RANGES; r++) {
            part_clear(&parts[r]);
            for (int32_t i = qdc_part(nb, r, SCAN_RANGES);
                 i < qdc_part(nb, r + 1, SCAN_RANGES); i++) {
                measure_tet(m, flip, bt, t0 + i, &ms[i]);
                part_add(&parts[r], &ms[i], t0 + i);
            }
        }
        for (int r = 0; r < SCAN_RANGES; r++)
            part_merge(q, &parts[r], acc);
        for (int32_t i = 0; i < nb; i++) {
            acc->sum += ms[i].eta;
            acc->sum2 += ms[i].eta * ms[i].eta;
            acc->vsum += ms[i].vl;
            if (isfinite(ms[i].cn)) {
                acc->cnsum += ms[i].cn;
                acc->nvalid++;
            }
        }
    }
    qdc_free(ms);
    qdc_free(parts);
    qdc_free(bt);
    return 1;
}

/* The solid's angle in degrees at edge (a, b) of triangles (a, b, c) and
 * (b, a, d), both oriented outward when out > 0 (inward when out < 0), or -1
 * when either is degenerate. */
static double edge_angle(const double *xyz, int32_t a, int32_t b, int32_t c, int32_t d,
                         double out)
{
    const double *pa = xyz + 3 * (size_t)a, *pb = xyz + 3 * (size_t)b;
    double ab[3], ac[3], ad[3], ba[3], bd[3], n1[3], n2[3], l1, l2, cs, phi;

    vec3_sub(pb, pa, ab);
    vec3_sub(xyz + 3 * (size_t)c, pa, ac);
    vec3_sub(xyz + 3 * (size_t)d, pa, ad);
    vec3_sub(pa, pb, ba);
    vec3_sub(xyz + 3 * (size_t)d, pb, bd);
    vec3_cross(ab, ac, n1);
    vec3_cross(ba, bd, n2);
    l1 = sqrt(vec3_dot(n1, n1));
    l2 = sqrt(vec3_dot(n2, n2));
    if (!(l1 > 0.0 && l2 > 0.0))
        return -1.0;
    cs = vec3_dot(n1, n2) / (l1 * l2);
    phi = acos(cs < -1.0 ? -1.0 : cs > 1.0 ? 1.0 : cs) * (180.0 / 3.14159265358979323846);
    /* convex at the edge when d is on the inner side of (a, b, c)'s plane */
    return vec3_dot(ad, n1) * out < 0.0 ? 180.0 - phi : 180.0 + phi;
}

static int32_t find_root(int32_t *up, int32_t i)
{
    while (up[i] != i)
        i = up[i] = up[up[i]];
    return i;
}

/* q->surf_angle_min and q->n_surf_lt5 from f's boundary triangles: each edge
 * that two of them share (an edge of more is not a manifold's: passed over).
 * The triangles are in their tets' vertex order: within one closed surface
 * all outward or all inward, as the sign of the volume it encloses tells
 * (the pieces of a mesh may be oriented each its own way). QDC_ENOMEM. */
static qdc_status surface_angles(const mesh_t *m, const mesh_faces *f, report_quality *q)
{
    const int32_t *tr = f->tris;
    const double *o = m->xyz + 3 * (size_t)tr[0];
    size_t n = 3 * (size_t)f->ntri;
    tri_edge *he = NULL;
    int32_t *up = qdc_mallocn((size_t)f->ntri, sizeof *up);
    double *vol = qdc_calloc((size_t)f->ntri, sizeof *vol), amin = 360.0;
    int32_t nlt5 = 0;

    q->surf_angle_min = 360.0;
    q->n_surf_lt5 = 0;
    if (tri_edges_sorted(tr, f->ntri, m->nv, &he) != QDC_OK || !up || !vol) {
        qdc_free(he);
        qdc_free(up);
        qdc_free(vol);
        return QDC_ENOMEM;
    }
    for (int32_t i = 0; i < f->ntri; i++)
        up[i] = i;
    for (size_t i = 0; i + 1 < n; i++) /* the pieces of the surface */
        if (he[i].lo == he[i + 1].lo && he[i].hi == he[i + 1].hi)
            up[find_root(up, he[i].tri)] = find_root(up, he[i + 1].tri);
    for (int32_t i = 0; i < f->ntri; i++) {
        double u[3], v[3], w[3], x[3];
        vec3_sub(m->xyz + 3 * (size_t)tr[3 * i], o, u);
        vec3_sub(m->xyz + 3 * (size_t)tr[3 * i + 1], o, v);
        vec3_sub(m->xyz + 3 * (size_t)tr[3 * i + 2], o, w);
        vec3_cross(v, w, x);
        up[i] = find_root(up, i); /* its piece's root from here on */
        vol[up[i]] += vec3_dot(u, x);
    }
    /* each edge where its run of equal (lo, hi) starts; a minimum and a count:
     * the same at any thread count */
#pragma omp parallel for reduction(min : amin) reduction(+ : nlt5) schedule(static)
    for (size_t i = 0; i < n; i++) {
        size_t j;
        if (i > 0 && he[i - 1].lo == he[i].lo && he[i - 1].hi == he[i].hi)
            continue;
        j = tri_edges_run(he, n, i);
        if (j - i == 2) {
            const int32_t *t1 = tr + 3 * (size_t)he[i].tri,
                          *t2 = tr + 3 * (size_t)he[i + 1].tri;
            int k1 = he[i].k, k2 = he[i + 1].k;
            double ang = edge_angle(m->xyz, t1[k1], t1[(k1 + 1) % 3], t1[(k1 + 2) % 3],
                                    t2[(k2 + 2) % 3], vol[up[he[i].tri]]);
            if (ang >= 0.0 && ang < amin)
                amin = ang;
            nlt5 += ang >= 0.0 && ang < 5.0;
        }
    }
    q->surf_angle_min = amin;
    q->n_surf_lt5 = nlt5;
    qdc_free(he);
    qdc_free(up);
    qdc_free(vol);
    return QDC_OK;
}

/* surface_angles of f's triangles, or of m's boundary found here when f is
 * NULL (a run that changed the tets, or no run); -1 when m's faces cannot be
 * found (a face of three tets). QDC_ENOMEM. */
static qdc_status surface_of(const mesh_t *m, const mesh_faces *f, report_quality *q)
{
    mesh_topo *tp = NULL;
    mesh_faces *own = NULL;
    qdc_status st;

    q->surf_angle_min = -1.0;
    q->n_surf_lt5 = -1;
    if (!f) {
        st = mesh_topo_build(m, &tp, NULL);
        if (st == QDC_OK)
            st = mesh_faces_of_topo(tp, m->tets, NULL, NULL, &own);
        mesh_topo_free(tp);
        if (st != QDC_OK)
            return st == QDC_ENOMEM ? st : QDC_OK;
        f = own;
    }
    if (f->ntri == 0) {
        q->surf_angle_min = 360.0;
        q->n_surf_lt5 = 0;
        st = QDC_OK;
    } else {
        st = surface_angles(m, f, q);
    }
    mesh_faces_free(own);
    return st;
}

qdc_status report_quality_compute(const mesh_t *m, report_quality *q, qdc_error *err)
{
    return report_quality_faces(m, NULL, q, err);
}

qdc_status report_quality_faces(const mesh_t *m, const mesh_faces *f, report_quality *q,
                                qdc_error *err)
{
    int32_t npos = 0, nneg = 0;
    scan_sums acc = {0, 0, 0, 0, 0, 0};
    uint8_t *flip;
    mesh_orientation orient;

    memset(q, 0, sizeof *q);
    if (!m || m->nt <= 0 || m->nv <= 0)
        return qdc_fail(err, QDC_EMESH, "empty mesh");
    {
        int32_t bad = m->nt; /* the first tet with an index out of range */
#pragma omp parallel for reduction(min : bad) schedule(static)
        for (int32_t t = 0; t < m->nt; t++)
            for (int a = 0; a < 4; a++)
                if ((m->tets[4 * (size_t)t + a] < 0 ||
                     m->tets[4 * (size_t)t + a] >= m->nv) &&
                    t < bad)
                    bad = t;
        if (bad < m->nt)
            return qdc_fail(err, QDC_EMESH, "tet %d: vertex index out of range",
                            (int)bad);
    }
    q->nv = m->nv;
    q->nt = m->nt;
    {
        /* Metrics are scale-free, but sums of squared edges of a mesh of size
         * 1e200 overflow (1e-200: underflow): measure such a mesh in units of
         * its diagonal. */
        double lo[3], hi[3], diag = mesh_bbox(m, lo, hi);
        if (isfinite(diag) && diag > 0 && (diag < 1e-50 || diag > 1e50)) {
            mesh_t *n = mesh_dup(m);
            qdc_status st;
            if (!n)
                return QDC_ENOMEM;
            for (size_t i = 0; i < 3 * (size_t)n->nv; i++)
                n->xyz[i] = (m->xyz[i] - lo[i % 3]) / diag;
            st = report_quality_faces(n, f, q, err);
            for (int k = 0; k < 3; k++)
                q->worst_centroid[k] = lo[k] + q->worst_centroid[k] * diag;
            q->diag = diag;
            mesh_free(n);
            return st;
        }
        q->diag = diag;
    }
    /* docs/method.md §1: each tet is measured in the vertex order its
     * component's orientation gives it (mesh_orient); a connectivity that
     * cannot be oriented (reported, never optimized) falls back to the
     * majority sign of the whole mesh. */
    if (f && f->nt != m->nt)
        return qdc_fail(err, QDC_EINVAL, "report: faces of %d tets for a mesh of %d",
                        (int)f->nt, (int)m->nt);
    flip = f ? f->flip : qdc_calloc((size_t)m->nt, 1);
    if (!flip)
        return QDC_ENOMEM;
    if (!f && mesh_orient(m, flip, &orient, NULL) != QDC_OK) {
        for (int32_t t = 0; t < m->nt; t++) {
            const int32_t *tt = m->tets + 4 * (size_t)t;
            metric_parts pt;
            metric_parts_of(m->xyz + 3 * (size_t)tt[0], m->xyz + 3 * (size_t)tt[1],
                            m->xyz + 3 * (size_t)tt[2], m->xyz + 3 * (size_t)tt[3], &pt);
            npos += pt.vol > 0;
            nneg += pt.vol < 0;
        }
        memset(flip, nneg > npos, (size_t)m->nt);
    }
    q->q_min = q->vl_min = INFINITY;
    q->dih_min = INFINITY;
    q->dih_max = -INFINITY;
    if (!scan_tets(m, flip, q, &acc)) {
        if (!f)
            qdc_free(flip);
        return QDC_ENOMEM;
    }
    if (acc.worst) {
        const int32_t *tt = m->tets + 4 * (size_t)q->worst_tet;
        for (int k = 0; k < 3; k++)
            q->worst_centroid[k] =
                (m->xyz[3 * (size_t)tt[0] + k] + m->xyz[3 * (size_t)tt[1] + k] +
                 m->xyz[3 * (size_t)tt[2] + k] + m->xyz[3 * (size_t)tt[3] + k]) /
                4;
    }
    q->q_mean = acc.sum / m->nt;
    q->q_std = sqrt(fmax(0.0, acc.sum2 / m->nt - q->q_mean * q->q_mean));
    q->vl_mean = acc.vsum / m->nt;
    q->cn_mean = acc.nvalid ? acc.cnsum / acc.nvalid : 0.0;
    if (!f)
        qdc_free(flip);
    return surface_of(m, f, q);
}

/* ---- a small buffered JSON writer ------------------------------------------ */

typedef struct {
    qdc_write_fn fn;
    void *ctx;
    char buf[8192];
    size_t len;
    int failed;
    int need_comma;
} jw;

static void jw_flush(jw *w)
{
    if (w->len && !w->failed && w->fn(w->ctx, w->buf, w->len))
        w->failed = 1;
    w->len = 0;
}

static void jw_raw(jw *w, const char *s, size_t n)
{
    while (n) {
        size_t room = sizeof w->buf - w->len, k = n < room ? n : room;
        memcpy(w->buf + w->len, s, k);
        w->len += k;
        s += k;
        n -= k;
        if (w->len == sizeof w->buf)
            jw_flush(w);
    }
}

static void jw_printf(jw *w, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void jw_printf(jw *w, const char *fmt, ...)
{
    char tmp[128];
    va_list ap;
    int n;

    va_start(ap, fmt);
    n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (n > 0)
        jw_raw(w, tmp, (size_t)n < sizeof tmp ? (size_t)n : sizeof tmp - 1);
}

static void jw_key(jw *w, const char *k)
{
    if (w->need_comma)
        jw_raw(w, ",", 1);
    jw_printf(w, "\"%s\":", k);
    w->need_comma = 1;
}

static void jw_open(jw *w, const char *k, char brace)
{
    if (k)
        jw_key(w, k);
    else if (w->need_comma)
        jw_raw(w, ",", 1);
    jw_raw(w, &brace, 1);
    w->need_comma = 0;
}

static void jw_close(jw *w, char brace)
{
    jw_raw(w, &brace, 1);
    w->need_comma = 1;
}

static void jw_num(jw *w, const char *k, double v)
{
    jw_key(w, k);
    if (isfinite(v))
        jw_printf(w, "%.10g", v);
    else
        jw_raw(w, "null", 4);
}

static void jw_int(jw *w, const char *k, long long v)
{
    jw_key(w, k);
    jw_printf(w, "%lld", v);
}

/* a JSON string of s */
static void jw_text(jw *w, const char *s)
{
    jw_raw(w, "\"", 1);
    for (; s && *s; s++) {
        unsigned char ch = (unsigned char)*s;
        if (ch == '"' || ch == '\\')
            jw_printf(w, "\\%c", ch);
        else if (ch < 0x20)
            jw_printf(w, "\\u%04x", ch);
        else
            jw_raw(w, (const char *)&ch, 1);
    }
    jw_raw(w, "\"", 1);
}

static void jw_str(jw *w, const char *k, const char *s)
{
    jw_key(w, k);
    jw_text(w, s);
}

static void write_quality(jw *w, const char *k, const report_quality *q)
{
    char key[32];

    jw_open(w, k, '{');
    jw_int(w, "n_vertices", q->nv);
    jw_int(w, "n_tets", q->nt);
    jw_int(w, "n_inverted", q->n_inverted);
    jw_int(w, "n_degenerate", q->n_degenerate);
    jw_num(w, "mean_ratio_mean", q->q_mean);
    jw_num(w, "mean_ratio_std", q->q_std);
    jw_num(w, "mean_ratio_min", q->q_min);
    jw_num(w, "volume_length_mean", q->vl_mean);
    jw_num(w, "volume_length_min", q->vl_min);
    jw_num(w, "condition_number_mean", q->cn_mean);
    jw_num(w, "condition_number_max", q->cn_max);
    jw_num(w, "dihedral_min", q->dih_min);
    jw_num(w, "dihedral_max", q->dih_max);
    if (q->n_surf_lt5 >= 0) {
        jw_num(w, "surface_angle_min", q->surf_angle_min);
        jw_int(w, "n_surface_edges_lt_5", q->n_surf_lt5);
    }
    for (int i = 0; i < 4; i++) {
        snprintf(key, sizeof key, "n_dmin_lt_%d", report_dmin_thresholds[i]);
        jw_int(w, key, q->n_dmin_lt[i]);
    }
    for (int i = 0; i < 4; i++) {
        snprintf(key, sizeof key, "n_dmax_gt_%d", report_dmax_thresholds[i]);
        jw_int(w, key, q->n_dmax_gt[i]);
    }
    jw_open(w, "dihedral_histogram", '[');
    for (int i = 0; i < REPORT_HIST_BINS; i++)
        jw_printf(w, i ? ",%lld" : "%lld", (long long)q->hist[i]);
    jw_close(w, ']');
    jw_close(w, '}');
}

static void write_progress_fields(jw *w, const opt_progress *p)
{
    jw_int(w, "iteration", p->iteration);
    jw_str(w, "phase", p->phase ? p->phase : "");
    jw_num(w, "objective", p->objective);
    jw_num(w, "step", p->step);
    jw_num(w, "mean_ratio_mean", p->q_mean);
    jw_num(w, "mean_ratio_std", p->q_std);
    jw_num(w, "mean_ratio_min", p->q_min);
    jw_num(w, "dihedral_min", p->dih_min);
    jw_num(w, "dihedral_max", p->dih_max);
    jw_int(w, "n_inverted", p->n_inverted - p->n_degenerate);
    jw_int(w, "n_degenerate", p->n_degenerate);
    jw_int(w, "n_folded", p->n_folded);
    jw_num(w, "max_move", p->max_move);
    jw_num(w, "elapsed", p->elapsed);
    jw_int(w, "cg_iterations", p->cg_iters);
    if (p->phase && !strcmp(p->phase, "topology")) {
        jw_int(w, "n_tets", p->n_tets);
        jw_int(w, "operations", p->operations);
    }
}

qdc_status report_progress_json(const opt_progress *p, qdc_write_fn fn, void *ctx)
{
    jw w = {.fn = fn, .ctx = ctx};

    jw_open(&w, NULL, '{');
    write_progress_fields(&w, p);
    jw_close(&w, '}');
    jw_flush(&w);
    return w.failed ? QDC_EIO : QDC_OK;
}

static void write_texts(jw *w, const char *k, const char (*list)[OUTCOME_TEXT], int n)
{
    jw_open(w, k, '[');
    for (int i = 0; i < n; i++) {
        if (i)
            jw_raw(w, ",", 1);
        jw_text(w, list[i]);
    }
    jw_close(w, ']');
}

/* The outcome in words (outcome.h) of a report with an "after". */
static void write_outcome(jw *w, const outcome_t *o)
{
    jw_open(w, "outcome", '{');
    jw_str(w, "summary", o->summary);
    jw_str(w, "improved", o->improved);
    jw_open(w, "left_bad", '{');
    jw_str(w, "text", o->left_bad);
    jw_int(w, "n_tets", o->n_tets);
    jw_int(w, "n_dihedral_lt_5", o->n_small);
    jw_int(w, "n_dihedral_gt_175", o->n_large);
    jw_int(w, "n_inverted", o->n_inverted);
    jw_int(w, "worst_tet", o->worst_tet);
    jw_num(w, "worst_mean_ratio", o->worst_q);
    jw_open(w, "worst_centroid", '[');
    jw_printf(w, "%.10g,%.10g,%.10g", o->worst_centroid[0], o->worst_centroid[1],
              o->worst_centroid[2]);
    jw_close(w, ']');
    jw_close(w, '}');
    jw_open(w, "boundary", '{');
    jw_str(w, "text", o->boundary);
    if (o->moved_rel >= 0)
        jw_num(w, "moved_rel", o->moved_rel);
    jw_num(w, "bound_rel", o->bound_rel);
    jw_close(w, '}');
    write_texts(w, "warnings", o->warnings, o->n_warnings);
    write_texts(w, "suggestions", o->suggestions, o->n_suggestions);
    jw_close(w, '}');
}

qdc_status report_write_json(const report_t *r, qdc_write_fn fn, void *ctx,
                             qdc_error *err)
{
    jw w = {.fn = fn, .ctx = ctx};

    jw_open(&w, NULL, '{');
    if (r->options) {
        const opt_options *o = r->options;
        jw_open(&w, "options", '{');
        jw_str(&w, "metric", opt_metric_name(o->metric));
        jw_str(&w, "boundary", opt_boundary_name(o->boundary));
        jw_str(&w, "mode", opt_mode_name(o->mode));
        jw_str(&w, "weights", opt_weights_name(o->weights));
        jw_str(&w, "solver", opt_solver_name(o->solver));
        jw_int(&w, "harmonic", o->harmonic);
        jw_int(&w, "finish", o->finish);
        jw_int(&w, "max_iter", o->max_iter);
        jw_num(&w, "mu", o->mu);
        if (o->topology != OPT_TOPOLOGY_NONE) /* absent: the report of before */
            jw_str(&w, "topology", opt_topology_name(o->topology));
        jw_close(&w, '}');
    }
    if (r->run) {
        const opt_result *s = r->run;
        static const char *const outcomes[] = {"converged", "stopped", "failed"};
        jw_open(&w, "run", '{');
        jw_str(&w, "outcome", (unsigned)s->outcome < 3 ? outcomes[s->outcome] : "?");
        jw_str(&w, "stop_reason", s->stop_reason);
        /* one count (docs/defaults.md): the records after the input's */
        jw_int(&w, "iterations", s->last_record);
        jw_int(&w, "best_iteration", s->best_iteration);
        jw_int(&w, "global_iterations", s->iterations);
        jw_int(&w, "max_inverted_global", s->max_inverted_global);
        jw_int(&w, "folded_global", s->folded_global);
        jw_num(&w, "hausd_bound", s->hausd_bound);
        jw_int(&w, "held_back", s->held_back);
        jw_str(&w, "solver", opt_solver_name(s->solver));
        jw_num(&w, "solver_flops", s->solver_flops);
        jw_open(&w, "seconds", '{');
        jw_num(&w, "setup", s->t_setup);
        jw_num(&w, "weights", s->t_weights);
        jw_num(&w, "assembly", s->t_assembly);
        jw_num(&w, "solve", s->t_solve);
        jw_num(&w, "linesearch", s->t_linesearch);
        jw_num(&w, "harmonic", s->t_harmonic);
        jw_num(&w, "finish", s->t_finish);
        jw_num(&w, "total", s->t_total);
        jw_close(&w, '}');
        if (s->p2_tets > 0) { /* second-order tets (opt/p2.c) */
            jw_open(&w, "second_order", '{');
            jw_int(&w, "tets", s->p2_tets);
            jw_int(&w, "mid_nodes", s->p2_mid);
            jw_int(&w, "mid_moved", s->p2_mid_moved);
            jw_int(&w, "boundary_mid", s->p2_boundary_mid);
            jw_int(&w, "pulled_straighter", s->p2_pulled);
            jw_int(&w, "jacobian_nonpositive_before", s->p2_bad_in);
            jw_int(&w, "jacobian_nonpositive_after", s->p2_bad_out);
            jw_num(&w, "scaled_jacobian_min_before", s->p2_jac_min_in);
            jw_num(&w, "scaled_jacobian_min_after", s->p2_jac_min_out);
            jw_num(&w, "boundary_mid_distance", s->p2_bd_mid_dist);
            jw_num(&w, "boundary_corner_distance", s->p2_bd_corner_dist);
            jw_close(&w, '}');
        }
        if (s->tets_in > 0) {
            jw_open(&w, "topology", '{');
            jw_int(&w, "tets_in", s->tets_in);
            jw_int(&w, "tets_out", s->tets_out);
            jw_int(&w, "edge_removals", s->topo_edge_removals);
            jw_open(&w, "edge_removals_by_ring", '{');
            for (int n = 3; n <= 10; n++) {
                char k[8];
                snprintf(k, sizeof k, "%d", n);
                jw_int(&w, k, s->topo_by_ring[n]);
            }
            jw_close(&w, '}');
            jw_int(&w, "flips23", s->topo_flips23);
            jw_int(&w, "multiface_removals", s->topo_multiface);
            jw_int(&w, "rounds", s->topo_rounds);
            if (s->topo_bflips + s->topo_peels + s->topo_bcontractions >
                0) { /* --hausd */
                jw_int(&w, "boundary_flips", s->topo_bflips);
                jw_int(&w, "peeled", s->topo_peels);
                jw_int(&w, "boundary_contractions", s->topo_bcontractions);
                jw_int(&w, "boundary_triangles_removed", s->topo_tris_removed);
                jw_int(&w, "boundary_triangles_added", s->topo_tris_added);
            }
            if (s->topo_insertions + s->topo_contractions > 0) { /* --topology full */
                jw_int(&w, "insertions", s->topo_insertions);
                jw_int(&w, "contractions", s->topo_contractions);
                jw_int(&w, "vertices_in", s->verts_in);
                jw_int(&w, "vertices_out", s->verts_out);
            }
            jw_close(&w, '}');
        }
        jw_open(&w, "before_finish", '{');
        write_progress_fields(&w, &s->before_finish);
        jw_close(&w, '}');
        jw_close(&w, '}');
    }
    if (r->before)
        write_quality(&w, "before", r->before);
    if (r->after)
        write_quality(&w, "after", r->after);
    if (r->boundary) {
        const bderr_result *b = r->boundary;
        jw_open(&w, "boundary_error", '{');
        jw_num(&w, "hausdorff", b->hausdorff);
        jw_num(&w, "hausdorff_rel", b->hausdorff_rel);
        jw_num(&w, "hausdorff_out_to_in", b->h_a_to_b);
        jw_num(&w, "hausdorff_in_to_out", b->h_b_to_a);
        jw_num(&w, "vertex_max", b->vertex_max);
        jw_num(&w, "vertex_max_rel", b->vertex_max_rel);
        jw_num(&w, "mean", b->mean);
        jw_num(&w, "mean_rel", b->mean_rel);
        jw_num(&w, "rms", b->rms);
        jw_num(&w, "rms_rel", b->rms_rel);
        jw_num(&w, "bbox_diagonal", b->diag);
        jw_int(&w, "n_samples", b->n_samples);
        jw_close(&w, '}');
    }
    if (r->after) {
        outcome_t o;
        if (outcome_compute(r, &o) == QDC_OK)
            write_outcome(&w, &o);
    }
    jw_close(&w, '}');
    jw_raw(&w, "\n", 1);
    jw_flush(&w);
    if (w.failed)
        return qdc_fail(err, QDC_EIO, "report: write failed");
    return QDC_OK;
}

int report_file_writer(void *ctx, const void *data, size_t len)
{
    return fwrite(data, 1, len, (FILE *)ctx) != len;
}
