/* exact.c - exact orientation of four points: a filter with a proven error bound,
 * then exact expansion arithmetic (Shewchuk, "Adaptive precision floating-point
 * arithmetic and fast robust geometric predicates", DCG 18, 1997). */
#include "topo/exact.h"

#include <math.h>

/* a + b = *s + *e exactly (Knuth's two-sum, the paper's Theorem 7). */
static void two_sum(double a, double b, double *s, double *e)
{
    double x = a + b;
    double bv = x - a;
    double av = x - bv;

    *s = x;
    *e = (a - av) + (b - bv);
}

/* Dekker's split: a = *hi + *lo with 26 significant bits each (paper Thm 17). */
static void split(double a, double *hi, double *lo)
{
    double c = 134217729.0 * a; /* 2^27 + 1 */
    double big = c - a;

    *hi = c - big;
    *lo = a - *hi;
}

/* a * b = *p + *e exactly (Dekker's product, paper Thm 18). */
static void two_product(double a, double b, double *p, double *e)
{
    double x = a * b, ah, al, bh, bl, err;

    split(a, &ah, &al);
    split(b, &bh, &bl);
    err = x - ah * bh;
    err -= al * bh;
    err -= ah * bl;
    *p = x;
    *e = al * bl - err;
}

/* Add b to the expansion e[0..m) (non-overlapping, increasing magnitude) in
 * place, dropping zero components (the paper's Grow-Expansion with zero
 * elimination): the result keeps both properties. Returns its length. */
static int grow(double *e, int m, double b)
{
    double q = b;
    int k = 0;

    for (int i = 0; i < m; i++) {
        double s, err;
        two_sum(q, e[i], &s, &err);
        q = s;
        if (err != 0.0)
            e[k++] = err;
    }
    if (q != 0.0 || k == 0)
        e[k++] = q;
    return k;
}

/* e += sign * x * y * z exactly: the product is the sum of four doubles. */
static int add_triple(double *e, int m, double sign, double x, double y, double z)
{
    double p, pe, r[4];

    two_product(x, y, &p, &pe);
    two_product(p, z, &r[0], &r[1]);
    two_product(pe, z, &r[2], &r[3]);
    for (int i = 0; i < 4; i++)
        if (r[i] != 0.0)
            m = grow(e, m, sign * r[i]);
    return m;
}

/* e += sign * det[p; q; r] (3x3, rows the points) exactly: six triple products. */
static int add_det3(double *e, int m, double sign, const double *p, const double *q,
                    const double *r)
{
    m = add_triple(e, m, sign, p[0], q[1], r[2]);
    m = add_triple(e, m, -sign, p[0], q[2], r[1]);
    m = add_triple(e, m, -sign, p[1], q[0], r[2]);
    m = add_triple(e, m, sign, p[1], q[2], r[0]);
    m = add_triple(e, m, sign, p[2], q[0], r[1]);
    m = add_triple(e, m, -sign, p[2], q[1], r[0]);
    return m;
}

/* det[b-a, c-a, d-a] = -det[[a 1];[b 1];[c 1];[d 1]], expanded along the column
 * of ones into the four 3x3 determinants of the points themselves: every term
 * is a product of three stored coordinates, so no difference is ever rounded. */
static int exact_sign(const double *a, const double *b, const double *c, const double *d)
{
    double e[97]; /* 24 triple products of at most 4 components each, plus one */
    int m = 0;

    m = add_det3(e, m, 1.0, b, c, d);
    m = add_det3(e, m, -1.0, a, c, d);
    m = add_det3(e, m, 1.0, a, b, d);
    m = add_det3(e, m, -1.0, a, b, c);
    /* the largest component (the last one) carries the sign */
    for (int i = m - 1; i >= 0; i--)
        if (e[i] != 0.0)
            return e[i] > 0.0 ? 1 : -1;
    return 0;
}

int exact_orient3d(const double *a, const double *b, const double *c, const double *d)
{
    /* The paper's bound for this evaluation order (its o3derrboundA): the
     * rounded determinant is within (7 + 56 eps) eps times the permanent. */
    static const double eps = 1.1102230246251565e-16; /* 2^-53 */
    double u0 = b[0] - a[0], u1 = b[1] - a[1], u2 = b[2] - a[2];
    double v0 = c[0] - a[0], v1 = c[1] - a[1], v2 = c[2] - a[2];
    double w0 = d[0] - a[0], w1 = d[1] - a[1], w2 = d[2] - a[2];
    double m0a = v1 * w2, m0b = v2 * w1, m1a = v0 * w2, m1b = v2 * w0;
    double m2a = v0 * w1, m2b = v1 * w0;
    double det = u0 * (m0a - m0b) - u1 * (m1a - m1b) + u2 * (m2a - m2b);
    double perm = fabs(u0) * (fabs(m0a) + fabs(m0b)) +
                  fabs(u1) * (fabs(m1a) + fabs(m1b)) + fabs(u2) * (fabs(m2a) + fabs(m2b));
    double bound = (7.0 + 56.0 * eps) * eps * perm;

    if (det > bound)
        return 1;
    if (-det > bound)
        return -1;
    return exact_sign(a, b, c, d);
}
