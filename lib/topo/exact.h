/* exact.h - the exact sign of a tet's orientation (Shewchuk's orient3d, in the
 * library's sign convention): a floating-point filter decides when it can, and
 * exact expansion arithmetic when it cannot, so the answer is the sign of the
 * determinant of the points as stored, never a rounding artefact.
 * A tet (a,b,c,d) is positive when det[b-a, c-a, d-a] > 0 (core/tet.h; Shewchuk's
 * orient3d(a,b,c,d) has the opposite sign). Needs round-to-nearest doubles without
 * fused multiply-add contraction (the build is ISO C11, where GCC does not contract).
 * Thread-safe: pure functions. */
#ifndef QDC_EXACT_H
#define QDC_EXACT_H

/* +1, 0 or -1: the sign of det[b-a, c-a, d-a], exactly. */
int exact_orient3d(const double *a, const double *b, const double *c, const double *d);

#endif
