/* insert.c - interior vertex insertion: the star of a new vertex placed by a
 * small search inside the cavity of a bad tet and its face-neighbours. */
#include "topo/insert.h"

#include "core/tet.h"
#include "geom/metric_int.h"
#include "geom/vec3.h"

#include <math.h>
#include <string.h>

enum { INS_OLD = 12, INS_NEW = 32 };

qdc_status tmesh_add_vertex(tmesh *tm, const double p[3])
{
    if (tm->nv == INT32_MAX)
        return QDC_ENOMEM;
    if (tm->nv == tm->vcap) {
        int32_t cap = tm->vcap < INT32_MAX / 2 ? tm->vcap + tm->vcap / 4 + 64 : INT32_MAX;
        double *x = qdc_realloc(tm->xyz, 3 * (size_t)cap * sizeof *x);
        uint8_t *c;
        if (!x)
            return QDC_ENOMEM;
        tm->xyz = x;
        c = qdc_realloc(tm->vcons, (size_t)cap);
        if (!c)
            return QDC_ENOMEM;
        tm->vcons = c;
        if (tm->vdeg) {
            int32_t *d = qdc_realloc(tm->vdeg, (size_t)cap * sizeof *d);
            if (!d)
                return QDC_ENOMEM;
            tm->vdeg = d;
        }
        tm->vcap = cap;
    }
    memcpy(tm->xyz + 3 * (size_t)tm->nv, p, 3 * sizeof *p);
    if (tm->vdeg)
        tm->vdeg[tm->nv] = 0;
    tm->vcons[tm->nv++] = 0;
    return QDC_OK;
}

/* The cavity of t: t and the live tets across its unconstrained faces (one tag,
 * none inverted). Returns its size. */
static int cavity(const tmesh *tm, int32_t t, int32_t old[INS_OLD])
{
    int n = 0;

    old[n++] = t;
    for (int i = 0; i < 4; i++) {
        int32_t a = tm->adj[4 * (size_t)t + i];
        if (a < 0 || (tm->fcons[t] >> i & 1) || tm->q[a / 4] < -1.0 ||
            tm->tag[a / 4] != tm->tag[t])
            continue;
        old[n++] = a / 4;
    }
    return n;
}

/* The star of vertex v over the outer faces of the cavity old (each tet with
 * the vertex opposite an outer face replaced by v). Returns the tet count, or
 * -1 when there are more than INS_NEW or when a constrained face lies between
 * two tets of the cavity (a kept inner surface it wrapped round: the star
 * would remove it). */
static int star(const tmesh *tm, const int32_t *old, int nold, int32_t v,
                int32_t newt[INS_NEW][4], int32_t from[INS_NEW])
{
    int n = 0;

    for (int o = 0; o < nold; o++)
        for (int i = 0; i < 4; i++) {
            int32_t a = tm->adj[4 * (size_t)old[o] + i], in = 0;
            for (int k = 0; k < nold && a >= 0; k++)
                in |= old[k] == a / 4;
            if (in && (tm->fcons[old[o]] >> i & 1))
                return -1;
            if (in)
                continue;
            if (n == INS_NEW)
                return -1;
            memcpy(newt[n], tm->tv + 4 * (size_t)old[o], 4 * sizeof(int32_t));
            from[n] = 4 * old[o] + i;
            newt[n++][i] = v;
        }
    return n;
}

/* The smallest quality of the star with its vertex (the last) at p when that
 * is above thr; else a value at most thr. The search only asks whether a place
 * beats the best so far: on the 100k-tet ball-scan of scripts/corpus.py
 * --seed 1, --topology full --boundary fixed with insertion below mean ratio
 * 0.7, the star's qualities were 65% of the CPU. So the cubes of the mean
 * ratios are computed first (no exact predicate, no cube root): with thr
 * positive, one under thr's cube by more than its roundings ends the scan;
 * else only the tets within roundings of the smallest cube, and those whose
 * cube is under 1e-9 (mean ratio 1e-3: only there can the sign in floating
 * point differ from the exact one), are evaluated as tmesh_quality does: the
 * same value as evaluating every tet, since the cube root keeps the order up
 * to those roundings and a tet farther above zero is positive exactly. (Until
 * the star's quality passed 1e-3 every tet was evaluated in full: on the
 * 100k-tet ball-lowq, --topology full --boundary fixed, the placement search
 * was a quarter of the CPU.) */
static double star_min(tmesh *tm, const double p[3], int32_t (*newt)[4], int nnew,
                       double thr)
{
    double q = INFINITY, q3[INS_NEW], lo = INFINITY, t3 = -INFINITY, lim;

    memcpy(tm->xyz + 3 * (size_t)(tm->nv - 1), p, 3 * sizeof *p);
    if (thr > 0.0)
        t3 = thr * thr * thr * (1.0 - 1e-9);
    for (int j = 0; j < nnew; j++) {
        metric_parts pt;
        metric_parts_for(OPT_METRIC_MIMR, tm->xyz + 3 * (size_t)newt[j][0],
                         tm->xyz + 3 * (size_t)newt[j][1],
                         tm->xyz + 3 * (size_t)newt[j][2],
                         tm->xyz + 3 * (size_t)newt[j][3], &pt);
        q3[j] = metric_mean_ratio_cubed(&pt);
        if (q3[j] < t3)
            return -4.0;
        lo = fmin(lo, q3[j]);
    }
    lim = fmax(lo * (1.0 + 1e-9), 1e-9);
    for (int j = 0; j < nnew; j++)
        if (q3[j] <= lim)
            q = fmin(q, tmesh_quality(tm, newt[j], -INFINITY));
    return q;
}

/* The cosine of the smallest dihedral angle of tet v (the largest of its six;
 * 1 for a degenerate face): the smaller, the better. */
static double cos_smallest(const tmesh *tm, const int32_t v[4])
{
    double cmin, cmax;

    metric_dihedral_cos_range(tm->xyz + 3 * (size_t)v[0], tm->xyz + 3 * (size_t)v[1],
                              tm->xyz + 3 * (size_t)v[2], tm->xyz + 3 * (size_t)v[3],
                              &cmin, &cmax);
    return cmax;
}

/* The best place found for the new vertex: the centroids of t and of the
 * cavity's vertices, then a compass search (6 directions, step halved when
 * none improves) from the better. Returns its smallest quality, p set. */
static double place(tmesh *tm, int32_t t, const int32_t *old, int nold,
                    int32_t (*newt)[4], int nnew, double p[3])
{
    double c0[3] = {0, 0, 0}, c1[3] = {0, 0, 0}, h = 0.0, best, q;
    int nc = 0;

    for (int k = 0; k < 4; k++)
        for (int d = 0; d < 3; d++)
            c0[d] += 0.25 * tm->xyz[3 * (size_t)tm->tv[4 * (size_t)t + k] + d];
    for (int o = 0; o < nold; o++)
        for (int k = 0; k < 4; k++, nc++) {
            const double *x = tm->xyz + 3 * (size_t)tm->tv[4 * (size_t)old[o] + k];
            for (int d = 0; d < 3; d++) {
                c1[d] += x[d];
                h = fmax(h, fabs(x[d] - c0[d]));
            }
        }
    for (int d = 0; d < 3; d++)
        c1[d] /= nc;
    best = star_min(tm, c0, newt, nnew, -INFINITY);
    memcpy(p, c0, sizeof c0);
    q = star_min(tm, c1, newt, nnew, best);
    if (q > best) {
        best = q;
        memcpy(p, c1, sizeof c1);
    }
    h *= 0.25;
    for (int it = 0; it < 24 && h > 0.0; it++) {
        int moved = 0;
        for (int dir = 0; dir < 6; dir++) {
            double x[3] = {p[0], p[1], p[2]};
            x[dir / 2] += dir % 2 ? -h : h;
            q = star_min(tm, x, newt, nnew, best);
            if (q > best) {
                best = q;
                memcpy(p, x, sizeof x);
                moved = 1;
            }
        }
        if (!moved)
            h *= 0.5;
    }
    memcpy(tm->xyz + 3 * (size_t)(tm->nv - 1), p, 3 * sizeof *p);
    return best;
}

/* With area A and squared edges summing to L, the apex at height h over the
 * centroid is best (the sum of its squared distances to the corners is least
 * there for that volume), its six squared edges summing to 4L/3 + 3h^2, and
 * 12 (A h)^(2/3) / (4L/3 + 3h^2) is largest at h^2 = 2L/9:
 * 8 (A^2 / (6 (4L/3)^2))^(1/3). */
double insert_face_cap(const double *a, const double *b, const double *c)
{
    double u[3], w[3], e[3], n[3], a2, l;

    vec3_sub(b, a, u);
    vec3_sub(c, a, w);
    vec3_sub(c, b, e);
    vec3_cross(u, w, n);
    a2 = 0.25 * vec3_dot(n, n);
    l = 4.0 / 3.0 * (vec3_dot(u, u) + vec3_dot(w, w) + vec3_dot(e, e));
    return l > 0.0 ? 8.0 * cbrt(a2 / (6.0 * l * l)) : 0.0;
}

/* The tet across the outer face slot f (4 * tet + face) when the cavity old
 * may take it (interior, unconstrained, one tag, not inverted, not in it), or -1. */
static int32_t across(const tmesh *tm, const int32_t *old, int nold, int32_t f)
{
    int32_t a = tm->adj[f];

    if (a < 0 || (tm->fcons[f / 4] >> (f % 4) & 1) || tm->q[a / 4] < -1.0 ||
        tm->tag[a / 4] != tm->tag[f / 4] || nold >= INS_OLD)
        return -1;
    for (int o = 0; o < nold; o++)
        if (old[o] == a / 4)
            return -1;
    return a / 4;
}

/* 1 when every vertex of the cavity old is a vertex of the star newt (none would
 * be left without a tet). */
static int keeps_vertices(const tmesh *tm, const int32_t *old, int nold,
                          int32_t (*newt)[4], int nn)
{
    for (int o = 0; o < nold; o++)
        for (int k = 0; k < 4; k++) {
            int32_t v = tm->tv[4 * (size_t)old[o] + k], found = 0;
            for (int j = 0; j < nn && !found; j++)
                found = newt[j][0] == v || newt[j][1] == v || newt[j][2] == v ||
                        newt[j][3] == v;
            if (!found)
                return 0;
        }
    return 1;
}

/* 1 when the smallest dihedral angle of the star (its vertex at p) is at least
 * the one whose cosine is cold (the cavity's). */
static int keeps_angle(tmesh *tm, const double p[3], int32_t (*newt)[4], int nn,
                       double cold)
{
    memcpy(tm->xyz + 3 * (size_t)(tm->nv - 1), p, 3 * sizeof *p);
    for (int j = 0; j < nn; j++)
        if (cos_smallest(tm, newt[j]) > cold)
            return 0;
    return 1;
}

/* The cavity grown from t and its face-neighbours, each time by the tet across
 * the outer face of the worst new tet that the cavity may cross (Stellar's
 * cavity growth, greedy), up to INS_OLD tets; the one whose star, its vertex
 * placed by place(), has the best smallest quality relative to the cavity's,
 * among those that raise it by margin, or double it when it is below margin
 * (with angle, only among the stars whose smallest dihedral angle is at least
 * the cavity's): old/nold and p set, *nold 0 when none does.
 *
 * The growth passes over a new tet on a constrained face (the cavity cannot
 * take what is across it) for the worst it can grow from; it stopped there
 * before, and a sliver whose four corners are on a fixed surface (a flat tet
 * on two boundary faces, one of them a cap triangle) never got past its first
 * neighbours. The doubling lets the worst tets (mean ratio 0.004 to 0.02 in
 * the cavity) take a star five times better, which the absolute margin
 * refused. On the 100k-tet bone-scan and bone-lowq of scripts/corpus.py --seed
 * 1, after --topology full --boundary fixed, the tets with four boundary
 * corners under mean ratio 0.05 that an insertion could take: 1 of 54 and 1 of
 * 64 before, 33 and 18 after. */
static void grow(tmesh *tm, int32_t t, double margin, int angle, int32_t *old, int *nold,
                 double p[3])
{
    double best_gain = -INFINITY;
    int32_t cav[INS_OLD], newt[INS_NEW][4], from[INS_NEW];
    int n = cavity(tm, t, cav);
    double qold = INFINITY, cold = -1.0;

    *nold = 0;
    for (int o = 0; o < n; o++) {
        qold = fmin(qold, tm->q[cav[o]]);
        if (angle)
            cold = fmax(cold, cos_smallest(tm, tm->tv + 4 * (size_t)cav[o]));
    }
    for (;;) {
        double x[3], qn, cap = INFINITY, capj[INS_NEW], worst = INFINITY;
        int nn = star(tm, cav, n, tm->nv - 1, newt, from), skip;
        int32_t a = -1;
        if (nn < 0)
            break;
        /* no place of the vertex makes a tet on an outer face better than
         * that face's cap: when the smallest cap cannot win, the star is not
         * placed (it could not be taken), and the cavity grows across the
         * crossable face of the smallest cap. On the 100k-tet bone-scan of
         * scripts/corpus.py --seed 1, --topology full: 14.5 CPU s without
         * this, 8.9 with it, 6.3 before the growth went past the surface. */
        for (int j = 0; j < nn; j++) {
            const int32_t *f = tm->tv + 4 * (size_t)(from[j] / 4);
            const int *fi = tet_face_of[from[j] % 4];
            capj[j] = insert_face_cap(tm->xyz + 3 * (size_t)f[fi[0]],
                                      tm->xyz + 3 * (size_t)f[fi[1]],
                                      tm->xyz + 3 * (size_t)f[fi[2]]);
            cap = fmin(cap, capj[j]);
        }
        cap *= 1.0 + 1e-6; /* its roundings */
        skip = cap - qold < fmin(margin, qold) || cap - qold <= best_gain;
        if (!skip) {
            qn = place(tm, t, cav, n, newt, nn, x);
            if (qn - qold > best_gain && qn - qold >= fmin(margin, qold) &&
                keeps_vertices(tm, cav, n, newt, nn) &&
                (!angle || keeps_angle(tm, x, newt, nn, cold))) {
                best_gain = qn - qold;
                memcpy(old, cav, (size_t)n * sizeof *cav);
                *nold = n;
                memcpy(p, x, sizeof x);
            }
        }
        for (int j = 0; j < nn; j++) {
            int32_t aj = across(tm, cav, n, from[j]);
            double q;
            if (aj < 0)
                continue;
            q = skip ? capj[j] : tmesh_quality(tm, newt[j], -INFINITY);
            if (q < worst) {
                worst = q;
                a = aj;
            }
        }
        if (a < 0)
            break;
        cav[n++] = a;
        qold = fmin(qold, tm->q[a]);
        if (angle)
            cold = fmax(cold, cos_smallest(tm, tm->tv + 4 * (size_t)a));
    }
}

qdc_status insert_in_tet(tmesh *tm, int32_t t, double margin, int angle, int *done,
                         int32_t *new_ids, int *nnew)
{
    int32_t old[INS_OLD], newt[INS_NEW][4], from[INS_NEW];
    double p[3] = {0, 0, 0};
    int nold = 0, nn, applied = 0;
    qdc_status st;

    *done = 0;
    *nnew = 0;
    if (tm->tv[4 * (size_t)t] < 0 || tm->q[t] < -1.0)
        return QDC_OK;
    st = tmesh_add_vertex(tm, p);
    if (st != QDC_OK)
        return st;
    grow(tm, t, margin, angle, old, &nold, p);
    if (nold == 0) {
        tm->nv--;
        return QDC_OK;
    }
    memcpy(tm->xyz + 3 * (size_t)(tm->nv - 1), p, sizeof p);
    nn = star(tm, old, nold, tm->nv - 1, newt, from);
    st = tmesh_replace(tm, old, nold, (const int32_t(*)[4])newt, nn, new_ids, &applied);
    if (st != QDC_OK || !applied) {
        tm->nv--;
        return st;
    }
    *done = 1;
    *nnew = nn;
    return QDC_OK;
}

void insert_undo(tmesh *tm)
{
    tmesh_rollback(tm);
    tm->nv--;
}
