/* tet.h - the tetrahedron, defined once: its faces, its signed volume, and
 * what "inverted" and "degenerate" mean. Every scan of the library counts
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

/* Inverted: not positive under the orientation its vertex order gives
 * (zero volume included: a flat tet is as unusable as a folded one).
 * Degenerate: exactly zero volume (reported apart, counted as inverted). */
static inline int geom_tet_inverted(double vol6)
{
    return !(vol6 > 0.0);
}

static inline int geom_tet_degenerate(double vol6)
{
    return vol6 == 0.0;
}

#endif
