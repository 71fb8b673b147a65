/* tet.h - the tetrahedron, defined once: its faces, its signed volume, and
 * what "inverted" and "degenerate" (flat) mean. Every scan of the library counts
 * tets with these, so a count means the same thing in a progress record, the
 * report and the CLI.
 * A tet (a,b,c,d) is positive when det[b-a, c-a, d-a] > 0 (Shewchuk's
 * orient3d(a,b,c,d) has the opposite sign); x holds 3 doubles per vertex. */
#ifndef QDC_TET_H
#define QDC_TET_H

#include <stddef.h>
#include <stdint.h>

/* Face opposite local vertex a, ordered so that its normal points out of a
 * positive tet (defined in mesh.c; the one face table of the library). */
extern const int tet_face_of[4][3];

/* 6 x the signed volume of tet tt (4 vertex indices into x). */
static inline double geom_tet_vol6(const double *x, const int32_t *tt)
{
    const double *a = x + 3 * (size_t)tt[0], *b = x + 3 * (size_t)tt[1];
    const double *c = x + 3 * (size_t)tt[2], *d = x + 3 * (size_t)tt[3];
    double u0 = b[0] - a[0], u1 = b[1] - a[1], u2 = b[2] - a[2];
    double v0 = c[0] - a[0], v1 = c[1] - a[1], v2 = c[2] - a[2];
    double w0 = d[0] - a[0], w1 = d[1] - a[1], w2 = d[2] - a[2];

    return u0 * (v1 * w2 - v2 * w1) - u1 * (v0 * w2 - v2 * w0) + u2 * (v0 * w1 - v1 * w0);
}

/* A face's three vertex indices in ascending order into s: the key under
 * which faces are matched (the one 3-integer sort of the library). */
static inline void tet_sort3(int32_t a, int32_t b, int32_t c, int32_t s[3])
{
    int32_t x;

    if (a > b) {
        x = a;
        a = b;
        b = x;
    }
    if (b > c) {
        x = b;
        b = c;
        c = x;
    }
    if (a > b) {
        x = a;
        a = b;
        b = x;
    }
    s[0] = a;
    s[1] = b;
    s[2] = c;
}

/* Degenerate (flat): 6V <= GEOM_FLAT_EPS * l_rms^3, l_rms the root mean
 * square of the six edge lengths (so it does not depend on units). The
 * regular tet has 6V = l^3 / sqrt2; a tet at the floor has mean ratio
 * 2 (GEOM_FLAT_EPS / 2)^(2/3) = 1.26e-6 and a smallest dihedral angle of
 * about 1e-7 degrees. 1e-9 sits far above rounding (6V computed from
 * coordinates |x| <= R carries an error of about 10 u (R / l_rms) l_rms^3,
 * u = 1.1e-16: 2e-13 of l_rms^3 for the tets of a 4M-tet mesh in the
 * optimizer's unit frame) and far below what meshers write (the flattest
 * valid tets of tests/data and of scripts/corpus.py have mean ratio 2.4e-5
 * and smallest dihedral 2.3e-5 degrees). docs/method.md §1. */
#define GEOM_FLAT_EPS 1e-9
/* The same floor on the mean ratio cubed (15552 V^2 / l2sum^3, what the
 * passes compare): a tet is degenerate exactly when that is <= 2 eps^2. */
#define GEOM_FLAT_ETA3 (2.0 * GEOM_FLAT_EPS * GEOM_FLAT_EPS)

/* Sum of the six squared edge lengths of tet tt. */
static inline double geom_tet_l2sum(const double *x, const int32_t *tt)
{
    double s = 0.0;

    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++)
            for (int c = 0; c < 3; c++) {
                double e = x[3 * (size_t)tt[j] + c] - x[3 * (size_t)tt[i] + c];
                s += e * e;
            }
    return s;
}

/* Inverted: negative under the orientation its vertex order gives. */
static inline int geom_tet_inverted(double vol6)
{
    return vol6 < 0.0;
}

/* Degenerate: not inverted, and 6V <= GEOM_FLAT_EPS l_rms^3 (zero volume
 * included), from 6V and the sum of squared edge lengths l2sum (no root). */
static inline int geom_tet_degenerate(double vol6, double l2sum)
{
    double r = l2sum / 6.0;

    return !geom_tet_inverted(vol6) &&
           !(vol6 * vol6 > GEOM_FLAT_EPS * GEOM_FLAT_EPS * r * r * r);
}

/* Unusable: inverted or degenerate, the one test behind every count of
 * "inverted or flat" tets, the never-worse check and every pass's acceptance
 * test (no move may make a tet unusable that was not). NaN is unusable. */
static inline int geom_tet_bad_vl(double vol6, double l2sum)
{
    double r = l2sum / 6.0;

    return !(vol6 > 0.0) || !(vol6 * vol6 > GEOM_FLAT_EPS * GEOM_FLAT_EPS * r * r * r);
}

static inline int geom_tet_bad(const double *x, const int32_t *tt)
{
    double v = geom_tet_vol6(x, tt);

    return !(v > 0.0) || geom_tet_bad_vl(v, geom_tet_l2sum(x, tt));
}

#endif
