/* metric.c - per-tet quality metrics (paper Sec. 3.1, docs/method.md §2-§3). */
#include "core/tet.h"
#include "geom/metric_int.h"
#include "geom/vec3.h"

#include <math.h>
#include <string.h>

#define SQRT2 1.4142135623730951

/* Volume and squared edge lengths: all that MIMR and MIVL need. */
static void parts_basic(const double *p0, const double *p1, const double *p2,
                        const double *p3, metric_parts *out)
{
    double e01[3], e02[3], e03[3], e12[3], e13[3], e23[3], n1[3];

    vec3_sub(p1, p0, e01);
    vec3_sub(p2, p0, e02);
    vec3_sub(p3, p0, e03);
    vec3_sub(p2, p1, e12);
    vec3_sub(p3, p1, e13);
    vec3_sub(p3, p2, e23);
    vec3_cross(e02, e03, n1); /* face 0 2 3 */
    out->vol = vec3_dot(e01, n1) / 6.0;
    out->l2sum = vec3_dot(e01, e01) + vec3_dot(e02, e02) + vec3_dot(e03, e03) +
                 vec3_dot(e12, e12) + vec3_dot(e13, e13) + vec3_dot(e23, e23);
    out->adj2 = 0.0;
}

void metric_parts_of(const double *p0, const double *p1, const double *p2,
                     const double *p3, metric_parts *out)
{
    double e01[3], e02[3], e03[3], e12[3], e13[3], n[4][3];

    parts_basic(p0, p1, p2, p3, out);
    vec3_sub(p1, p0, e01);
    vec3_sub(p2, p0, e02);
    vec3_sub(p3, p0, e03);
    vec3_sub(p2, p1, e12);
    vec3_sub(p3, p1, e13);
    vec3_cross(e12, e13, n[0]);
    vec3_cross(e02, e03, n[1]);
    vec3_cross(e01, e03, n[2]);
    vec3_cross(e01, e02, n[3]);
    /* |n|^2 = 4 area^2, so 4 * sum area^2 = sum |n|^2 */
    for (int f = 0; f < 4; f++)
        out->adj2 += vec3_dot(n[f], n[f]);
}

void metric_parts_for(opt_metric m, const double *p0, const double *p1, const double *p2,
                      const double *p3, metric_parts *out)
{
    if (m == OPT_METRIC_MICN)
        metric_parts_of(p0, p1, p2, p3, out);
    else
        parts_basic(p0, p1, p2, p3, out);
}

double metric_h(double s, double delta)
{
    if (delta == 0.0)
        return s;
    return 0.5 * (s + sqrt(s * s + 4.0 * delta * delta));
}

double metric_hprime(double s, double delta)
{
    if (delta == 0.0)
        return 1.0;
    return 0.5 * (1.0 + s / sqrt(s * s + 4.0 * delta * delta));
}

double metric_arg(opt_metric m, const metric_parts *p)
{
    return m == OPT_METRIC_MIVL ? p->vol : 6.0 * SQRT2 * p->vol;
}

double metric_eps(opt_metric m, double lbar, double eps_rel)
{
    double l3 = lbar * lbar * lbar;
    return eps_rel * (m == OPT_METRIC_MIVL ? l3 * SQRT2 / 12.0 : l3);
}

double metric_delta(double smin, double eps)
{
    return smin < eps ? sqrt(eps * (eps - smin)) : 0.0;
}

double metric_qt(opt_metric m, const metric_parts *p, double delta)
{
    double s = metric_arg(m, p);
    double h = metric_h(s, delta);

    if (!(h > 0.0))
        return INFINITY;
    switch (m) {
    case OPT_METRIC_MIMR:
        return 0.5 * p->l2sum / (3.0 * cbrt(h * h));
    case OPT_METRIC_MICN:
        return sqrt(0.5 * p->l2sum * p->adj2) / (3.0 * h);
    case OPT_METRIC_MIVL:
    default: {
        double l = p->l2sum / 6.0;
        return SQRT2 * l * sqrt(l) / (12.0 * h);
    }
    }
}

double metric_qt_grad(opt_metric m, const double *p12, int a, double delta, double g[3],
                      metric_parts *pt_out)
{
    metric_parts pt;
    double p[4][3];
    const double *f0, *f1, *f2;
    double dl2[3], dvol[3], e1[3], e2[3], nf[3], q, s, h, hp, cs;
    int fi[3];

    memcpy(p, p12, sizeof p);
    metric_parts_for(m, p[0], p[1], p[2], p[3], &pt);
    if (pt_out)
        *pt_out = pt;
    q = metric_qt(m, &pt, delta);
    g[0] = g[1] = g[2] = 0.0;
    if (!isfinite(q))
        return q;
    /* d l2sum / d p_a = 2 * sum_{b != a} (p_a - p_b) */
    for (int k = 0; k < 3; k++)
        dl2[k] = 2.0 * (3.0 * p[a][k] - p[(a + 1) & 3][k] - p[(a + 2) & 3][k] -
                        p[(a + 3) & 3][k]);
    /* d vol / d p_a = (inward face normal * area) / 3 = -(outward cross) / 6 */
    {
        for (int k = 0; k < 3; k++)
            fi[k] = tet_face_of[a][k];
        f0 = p[fi[0]];
        f1 = p[fi[1]];
        f2 = p[fi[2]];
        vec3_sub(f1, f0, e1);
        vec3_sub(f2, f0, e2);
        vec3_cross(e1, e2, nf);
        for (int k = 0; k < 3; k++)
            dvol[k] = -nf[k] / 6.0;
    }
    s = metric_arg(m, &pt);
    h = metric_h(s, delta);
    hp = metric_hprime(s, delta);
    cs = m == OPT_METRIC_MIVL ? 1.0 : 6.0 * SQRT2; /* ds/dvol */
    switch (m) {
    case OPT_METRIC_MIMR:
        /* q = (l2/2) / (3 h^(2/3)) */
        for (int k = 0; k < 3; k++)
            g[k] = q * (dl2[k] / pt.l2sum - (2.0 / 3.0) * hp * cs * dvol[k] / h);
        break;
    case OPT_METRIC_MICN: {
        /* q = sqrt(l2/2 * adj2) / (3h); adj2 = sum |n_f|^2 over faces; for a face
         * (a, b, c) containing p_a, d|n|^2/dp_a = 2 (b - c) x n. */
        double dadj[3] = {0, 0, 0};
        for (int f = 0; f < 4; f++) {
            int v0 = tet_face_of[f][0], v1 = tet_face_of[f][1], v2 = tet_face_of[f][2];
            int b, c;
            double n[3], bc[3], t[3];
            if (f == a)
                continue;
            /* rotate so that the face reads (a, b, c) */
            if (v0 == a) {
                b = v1;
                c = v2;
            } else if (v1 == a) {
                b = v2;
                c = v0;
            } else {
                b = v0;
                c = v1;
            }
            vec3_sub(p[b], p[a], e1);
            vec3_sub(p[c], p[a], e2);
            vec3_cross(e1, e2, n);
            vec3_sub(p[b], p[c], bc);
            vec3_cross(bc, n, t);
            for (int k = 0; k < 3; k++)
                dadj[k] += 2.0 * t[k];
        }
        for (int k = 0; k < 3; k++)
            g[k] = q * (0.5 * dl2[k] / pt.l2sum + 0.5 * dadj[k] / pt.adj2 -
                        hp * cs * dvol[k] / h);
        break;
    }
    case OPT_METRIC_MIVL:
    default:
        /* q = sqrt2 (l2/6)^(3/2) / (12 h(V)) */
        for (int k = 0; k < 3; k++)
            g[k] = q * (1.5 * dl2[k] / pt.l2sum - hp * dvol[k] / h);
        break;
    }
    return q;
}

void metric_face_set(const double *f0, const double *f1, const double *f2,
                     metric_face *mf)
{
    double e1[3], e2[3];

    mf->f[0] = f0;
    mf->f[1] = f1;
    mf->f[2] = f2;
    vec3_sub(f1, f0, e1);
    vec3_sub(f2, f0, e2);
    vec3_cross(e1, e2, mf->dV);
    for (int k = 0; k < 3; k++)
        mf->dV[k] *= -1.0 / 6.0;
    mf->ee[0] = vec3_dot(e1, e1);
    mf->ee[1] = vec3_dot(e2, e2);
    for (int k = 0; k < 3; k++)
        mf->ee[2 + k] = (e2[k] - e1[k]) * (e2[k] - e1[k]);
}

double metric_qt_hess_face(opt_metric m, const double *pa, const double *f0,
                           const double *f1, const double *f2, double delta, double g[3],
                           double H[6], double vl[2])
{
    metric_face mf;

    metric_face_set(f0, f1, f2, &mf);
    return metric_qt_hess_at(m, pa, &mf, delta, g, H, vl);
}

double metric_qt_hess_at(opt_metric m, const double *pa, const metric_face *mf,
                         double delta, double g[3], double H[6], double vl[2])
{
    /* q = c A^al h(s)^-be with A = l2sum, s = cv V; ln q is a sum of simple
     * terms: grad q = q u, u = al dA/A - be h' cv dV/h, and
     * hess q = q (u u^T + al (6 I/A - dA dA^T/A^2) - be cv^2 (h''/h - h'^2/h^2) dV dV^T)
     * (d2A/dp_a2 = 6 I; V is linear in p_a: V = dV . (p_a - f0)). A's terms
     * are added in the order of the sum over the edges d0, d1, d2, e1, e2,
     * e2 - e1, as before the face's part was set apart (the same bits). */
    const double *dV = mf->dV;
    double d0[3], d1[3], d2[3], dA[3], u[3], A, V, sarg, h, hp, hpp, q;
    double al, be, cv, iA, ih, cvv;

    vec3_sub(pa, mf->f[0], d0);
    vec3_sub(pa, mf->f[1], d1);
    vec3_sub(pa, mf->f[2], d2);
    for (int k = 0; k < 3; k++)
        dA[k] = 2.0 * (d0[k] + d1[k] + d2[k]);
    V = vec3_dot(dV, d0);
    A = vec3_dot(d0, d0) + vec3_dot(d1, d1) + vec3_dot(d2, d2) + mf->ee[0] + mf->ee[1] +
        mf->ee[2] + mf->ee[3] + mf->ee[4];
    vl[0] = V;
    vl[1] = A;
    if (m == OPT_METRIC_MIVL) {
        al = 1.5;
        be = 1.0;
        cv = 1.0;
    } else if (m == OPT_METRIC_MIMR) {
        al = 1.0;
        be = 2.0 / 3.0;
        cv = 6.0 * SQRT2;
    } else {
        return NAN;
    }
    sarg = cv * V;
    if (delta == 0.0) {
        h = sarg;
        hp = 1.0;
        hpp = 0.0;
    } else {
        double r = sqrt(sarg * sarg + 4.0 * delta * delta);
        h = 0.5 * (sarg + r);
        hp = 0.5 * (1.0 + sarg / r);
        hpp = 2.0 * delta * delta / (r * r * r);
    }
    if (!(h > 0.0) || !(A > 0.0)) {
        if (g) {
            memset(H, 0, 6 * sizeof(double));
            g[0] = g[1] = g[2] = 0.0;
        }
        return INFINITY;
    }
    if (m == OPT_METRIC_MIVL) {
        double l = A / 6.0;
        q = SQRT2 * l * sqrt(l) / (12.0 * h);
    } else {
        q = 0.5 * A / (3.0 * cbrt(h * h));
    }
    if (!g)
        return q;
    iA = 1.0 / A;
    ih = 1.0 / h;
    cvv = be * cv * cv * (hpp * ih - hp * hp * ih * ih);
    {
        double c1 = al * iA, c2 = be * hp * cv * ih;
        double wa = -q * al * iA * iA, wv = -q * cvv, dg = 6.0 * q * al * iA;
        for (int k = 0; k < 3; k++) {
            u[k] = c1 * dA[k] - c2 * dV[k];
            g[k] = q * u[k];
        }
        /* H = q u u^T + wa dA dA^T + wv dV dV^T + dg I, upper triangle */
        H[0] = g[0] * u[0] + wa * dA[0] * dA[0] + wv * dV[0] * dV[0] + dg;
        H[1] = g[0] * u[1] + wa * dA[0] * dA[1] + wv * dV[0] * dV[1];
        H[2] = g[0] * u[2] + wa * dA[0] * dA[2] + wv * dV[0] * dV[2];
        H[3] = g[1] * u[1] + wa * dA[1] * dA[1] + wv * dV[1] * dV[1] + dg;
        H[4] = g[1] * u[2] + wa * dA[1] * dA[2] + wv * dV[1] * dV[2];
        H[5] = g[2] * u[2] + wa * dA[2] * dA[2] + wv * dV[2] * dV[2] + dg;
    }
    return q;
}

double metric_qt_hess(opt_metric m, const double *p12, int a, double delta, double g[3],
                      double H[6], metric_parts *pt_out)
{
    const double *p = p12;
    double vl[2], q;

    if (m == OPT_METRIC_MICN)
        return NAN;
    q = metric_qt_hess_face(m, p + 3 * a, p + 3 * tet_face_of[a][0],
                            p + 3 * tet_face_of[a][1], p + 3 * tet_face_of[a][2], delta,
                            g, H, vl);
    if (pt_out)
        metric_parts_for(m, p12, p12 + 3, p12 + 6, p12 + 9, pt_out);
    return q;
}

double metric_mean_ratio(const metric_parts *p)
{
    double v = fabs(p->vol), r;

    if (!(p->l2sum > 0.0))
        return 0.0;
    r = 12.0 * cbrt(9.0 * v * v) / p->l2sum;
    return p->vol < 0 ? -r : (p->vol > 0 ? r : 0.0);
}

double metric_mean_ratio_cubed(const metric_parts *p)
{
    double a = p->l2sum;

    if (!(a > 0.0))
        return 0.0;
    return 15552.0 * p->vol * fabs(p->vol) / (a * a * a);
}

double metric_vol_length(const metric_parts *p)
{
    double l = sqrt(p->l2sum / 6.0);

    if (!(l > 0.0))
        return 0.0;
    return 6.0 * SQRT2 * p->vol / (l * l * l);
}

/* Area vectors g_k of the faces opposite each corner k (as tools/quality.py
 * builds them) and their lengths; returns 1 if a face is degenerate. The
 * dihedral at edge (i, j) is acos(-u_k . u_l), {k, l} the other two corners. */
static const int dihedral_opp[6][2] = {{2, 3}, {1, 3}, {1, 2}, {0, 3}, {0, 2}, {0, 1}};

static int face_area_vectors(const double *p0, const double *p1, const double *p2,
                             const double *p3, double g[4][3], double len[4])
{
    double ab[3], ac[3], ad[3];
    int degenerate = 0;

    vec3_sub(p1, p0, ab);
    vec3_sub(p2, p0, ac);
    vec3_sub(p3, p0, ad);
    vec3_cross(ac, ad, g[1]);
    vec3_cross(ad, ab, g[2]);
    vec3_cross(ab, ac, g[3]);
    for (int k = 0; k < 3; k++)
        g[0][k] = -(g[1][k] + g[2][k] + g[3][k]);
    for (int f = 0; f < 4; f++) {
        len[f] = sqrt(vec3_dot(g[f], g[f]));
        degenerate |= !(len[f] > 0.0);
    }
    return degenerate;
}

static double dihedral_cos(double g[4][3], const double len[4], int e)
{
    int k = dihedral_opp[e][0], l = dihedral_opp[e][1];
    double c = -vec3_dot(g[k], g[l]) / (len[k] * len[l]);
    return c > 1.0 ? 1.0 : (c < -1.0 ? -1.0 : c);
}

#define RAD2DEG (180.0 / 3.14159265358979323846)

void metric_dihedral_cos_range(const double *p0, const double *p1, const double *p2,
                               const double *p3, double *cmin, double *cmax)
{
    double g[4][3], len[4], il[4], lo = 2, hi = -2;

    if (face_area_vectors(p0, p1, p2, p3, g, len)) {
        *cmin = -1.0;
        *cmax = 1.0;
        return;
    }
    for (int f = 0; f < 4; f++)
        il[f] = 1.0 / len[f];
    for (int e = 0; e < 6; e++) {
        int k = dihedral_opp[e][0], l = dihedral_opp[e][1];
        double c = -vec3_dot(g[k], g[l]) * il[k] * il[l];
        lo = c < lo ? c : lo;
        hi = c > hi ? c : hi;
    }
    *cmin = lo < -1.0 ? -1.0 : lo;
    *cmax = hi > 1.0 ? 1.0 : hi;
}

void metric_dihedral_range(const double *p0, const double *p1, const double *p2,
                           const double *p3, double *amin, double *amax)
{
    double cmin, cmax;

    metric_dihedral_cos_range(p0, p1, p2, p3, &cmin, &cmax);
    /* acos is decreasing: the largest cosine is the smallest angle */
    *amin = acos(cmax) * RAD2DEG;
    *amax = acos(cmin) * RAD2DEG;
}

unsigned metric_dihedral_cosines(const double *p0, const double *p1, const double *p2,
                                 const double *p3, double c[6])
{
    double g[4][3], len[4];
    unsigned flat = 0;

    face_area_vectors(p0, p1, p2, p3, g, len);
    for (int e = 0; e < 6; e++) {
        int k = dihedral_opp[e][0], l = dihedral_opp[e][1];
        if (!(len[k] > 0.0) || !(len[l] > 0.0)) {
            flat |= 1u << e;
            c[e] = e & 1 ? -1.0 : 1.0;
        } else {
            c[e] = dihedral_cos(g, len, e);
        }
    }
    return flat;
}

int metric_dihedrals(const double *p0, const double *p1, const double *p2,
                     const double *p3, double ang[6])
{
    double c[6];
    unsigned flat = metric_dihedral_cosines(p0, p1, p2, p3, c);

    for (int e = 0; e < 6; e++)
        ang[e] = flat >> e & 1 ? (e & 1 ? 180.0 : 0.0) : acos(c[e]) * RAD2DEG;
    return flat != 0;
}

double metric_dihedral_sines_eta3(const double *p0, const double *p1, const double *p2,
                                  const double *p3, double s[6])
{
    static const int ends[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    const double *p[4] = {p0, p1, p2, p3};
    double g[4][3], len[4], il[4], ad[3], det, l2sum = 0.0;

    face_area_vectors(p0, p1, p2, p3, g, len);
    vec3_sub(p3, p0, ad);
    det = vec3_dot(g[3], ad); /* 6 V */
    for (int f = 0; f < 4; f++)
        il[f] = len[f] > 0.0 ? 1.0 / len[f] : 0.0;
    for (int e = 0; e < 6; e++) {
        int k = dihedral_opp[e][0], l = dihedral_opp[e][1];
        double d[3];
        double l2;
        vec3_sub(p[ends[e][1]], p[ends[e][0]], d);
        l2 = vec3_dot(d, d);
        l2sum += l2;
        /* sin = 3 V l / (2 A_k A_l) with |g| = 2 A; 0 on a degenerate face */
        s[e] = det * sqrt(l2) * il[k] * il[l];
    }
    {
        metric_parts pt = {.vol = det / 6.0, .l2sum = l2sum};
        return metric_mean_ratio_cubed(&pt);
    }
}

void metric_dihedral_sines(const double *p0, const double *p1, const double *p2,
                           const double *p3, double s[6])
{
    (void)metric_dihedral_sines_eta3(p0, p1, p2, p3, s);
}

double metric_alpha_opt(opt_metric m, const double *f0, const double *f1,
                        const double *f2)
{
    double e01[3], e02[3], e12[3], F;

    vec3_sub(f1, f0, e01);
    vec3_sub(f2, f0, e02);
    vec3_sub(f2, f1, e12);
    F = vec3_dot(e01, e01) + vec3_dot(e02, e02) + vec3_dot(e12, e12);
    if (m != OPT_METRIC_MICN)
        return sqrt(2.0 * F / 9.0); /* MIMR, MIVL: alpha^2 = N0 / (2 N2) */
    {
        /* MICN: ||S||^2 = N0 + N2 a^2, ||adj S||^2 = C0 + C2 a^2, a*^4 = N0 C0 / (N2 C2).
         * Put the free vertex at the barycentre plus a * unit inward normal and
         * evaluate at a = 0 and a = 1. */
        double pc[3], n[3], len, p[3];
        metric_parts a0, a1;
        double N0, N2, C0, C2;
        vec3_cross(e01, e02,
                   n); /* this face ordering: normal points away from the free vertex */
        len = sqrt(vec3_dot(n, n));
        if (!(len > 0.0))
            return 0.0;
        for (int k = 0; k < 3; k++) {
            pc[k] = (f0[k] + f1[k] + f2[k]) / 3.0;
            n[k] = -n[k] / len;
            p[k] = pc[k] + n[k];
        }
        metric_parts_of(pc, f0, f2, f1, &a0);
        metric_parts_of(p, f0, f2, f1, &a1);
        N0 = a0.l2sum;
        N2 = a1.l2sum - a0.l2sum;
        C0 = a0.adj2;
        C2 = a1.adj2 - a0.adj2;
        if (!(N2 * C2 > 0.0))
            return sqrt(2.0 * F / 9.0);
        return sqrt(sqrt(N0 * C0 / (N2 * C2)));
    }
}
