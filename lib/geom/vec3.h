/* vec3.h - inline helpers on 3-vectors of doubles (difference, cross and dot
 * products), shared by the quality metrics, the boundary distances and the
 * topology operations. */
#ifndef QDC_GEOM_VEC3_H
#define QDC_GEOM_VEC3_H

/* o = a - b */
static inline void vec3_sub(const double *a, const double *b, double *o)
{
    o[0] = a[0] - b[0];
    o[1] = a[1] - b[1];
    o[2] = a[2] - b[2];
}

/* o = a x b */
static inline void vec3_cross(const double *a, const double *b, double *o)
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

static inline double vec3_dot(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

#endif
