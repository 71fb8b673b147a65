/* star.c - what the passes do to one vertex's star (star.h): a trial point,
 * the signed volume of a star tet, the steepest max-min ascent direction. */
#include "opt/star.h"
#include "core/tet.h"

#include <math.h>
#include <string.h>

/* 6 x the signed volume of star tet k of v with v placed at y, and (if g) its
 * gradient with respect to y (constant: the volume is linear in y). */
double star_vol6(const mesh_topo *tp, const double *x, int32_t k, const double *y,
                 double g[3])
{
    static const int32_t corner[4] = {0, 1, 2, 3};
    int32_t t = tp->vt_idx[k] >> 2, a = tp->vt_idx[k] & 3;
    const int32_t *tt = tp->tets + 4 * (size_t)t;
    double p[12], v0;

    for (int b = 0; b < 4; b++)
        memcpy(p + 3 * b, b == a ? y : x + 3 * (size_t)tt[b], 3 * sizeof(double));
    v0 = geom_tet_vol6(p, corner);
    if (g)
        for (int c = 0; c < 3; c++) {
            double s = p[3 * a + c];
            p[3 * a + c] = s + 1.0;
            g[c] = geom_tet_vol6(p, corner) - v0;
            p[3 * a + c] = s;
        }
    return v0;
}

/* y = xv + t dir, put back on v's surface or line if sl (a sliding vertex). */
void star_trial_point(const slide_ctx *sl, int32_t v, const double *xv,
                      const double dir[3], double t, double y[3])
{
    for (int c = 0; c < 3; c++)
        y[c] = xv[c] + t * dir[c];
    if (sl) {
        double yp[3];
        slide_project(sl, v, y, yp);
        memcpy(y, yp, sizeof yp);
    }
}

/* Minimum-norm point d of the convex hull of g[0..n): the steepest ascent
 * direction of min_i f_i (every active f_i rises at rate >= |d|^2 along d).
 * In 3-D it lies on a face spanned by at most 3 points, so the candidates are
 * the points, the segments and the triangles. Returns 0 if the hull contains
 * the origin (no ascent direction). */
int star_min_norm_point(double g[][3], int n, double d[3])
{
    double best = INFINITY, cand[3];

    for (int i = 0; i < n; i++)
        for (int j = i; j < n; j++)
            for (int k = j; k < n; k++) {
                double u[3], w[3], uu, uw, ww, gu, gw, a = 0, b = 0, nn;
                if ((j == i && k != i) || (k == j && j != i))
                    continue; /* subsets {i}, {i,j}, {i,j,k} only */
                for (int c = 0; c < 3; c++) {
                    u[c] = g[j][c] - g[i][c];
                    w[c] = g[k][c] - g[i][c];
                }
                uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
                ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
                uw = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
                gu = g[i][0] * u[0] + g[i][1] * u[1] + g[i][2] * u[2];
                gw = g[i][0] * w[0] + g[i][1] * w[1] + g[i][2] * w[2];
                if (j == i) {
                    a = b = 0;
                } else if (k == j) {
                    if (!(uu > 0))
                        continue;
                    a = -gu / uu;
                    if (!(a > 0 && a < 1))
                        continue;
                } else {
                    double det = uu * ww - uw * uw;
                    if (!(det > 1e-14 * uu * ww))
                        continue;
                    a = (-gu * ww + gw * uw) / det;
                    b = (-gw * uu + gu * uw) / det;
                    if (!(a > 0 && b > 0 && a + b < 1))
                        continue;
                }
                for (int c = 0; c < 3; c++)
                    cand[c] = g[i][c] + a * u[c] + b * w[c];
                nn = cand[0] * cand[0] + cand[1] * cand[1] + cand[2] * cand[2];
                if (nn < best) {
                    best = nn;
                    memcpy(d, cand, sizeof cand);
                }
            }
    if (!(best > 0) || !isfinite(best))
        return 0;
    /* optimality: every point sees d at least as far as d itself; else the
     * origin is inside the hull */
    for (int i = 0; i < n; i++)
        if (g[i][0] * d[0] + g[i][1] * d[1] + g[i][2] * d[2] < best * (1.0 - 1e-9))
            return 0;
    return 1;
}
