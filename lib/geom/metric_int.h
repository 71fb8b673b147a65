/* metric_int.h - per-tet quality metrics (paper Sec. 3.1, docs/method.md §2-§3):
 * the internal part of metric.h, used by the optimizer and the reports.
 * A tet is given by its 4 corner points; it is positive when
 * det[p1-p0, p2-p0, p3-p0] > 0. Thread-safe: pure functions. */
#ifndef QDC_METRIC_INT_H
#define QDC_METRIC_INT_H

#include "core/base.h"
#include "geom/metric.h"

/* Ingredients every metric needs. With S = A W^-1 (W: unit regular tet):
 * sigma = det S = 6 sqrt2 vol, ||S||_F^2 = l2sum / 2, ||adj S||_F^2 = adj2. */
typedef struct {
    double vol;   /* signed volume */
    double l2sum; /* sum of the 6 squared edge lengths */
    double adj2;  /* 4 * sum of the squared face areas */
} metric_parts;

void metric_parts_of(const double *p0, const double *p1, const double *p2,
                     const double *p3, metric_parts *out);
/* The same, computing adj2 only for MICN (the other metrics never read it;
 * adj2 is then 0). For hot loops. */
void metric_parts_for(opt_metric m, const double *p0, const double *p1, const double *p2,
                      const double *p3, metric_parts *out);

/* Escobar's regularization h(s) = (s + sqrt(s^2 + 4 delta^2)) / 2 and its derivative. */
double metric_h(double s, double delta);
double metric_hprime(double s, double delta);

/* The quantity that goes through h(): vol for MIVL, sigma for MIMR/MICN. */
double metric_arg(opt_metric m, const metric_parts *p);
/* Escobar epsilon: eps_rel times metric_arg of a regular tet with edge lbar. */
double metric_eps(opt_metric m, double lbar, double eps_rel);
/* delta = sqrt(eps (eps - smin)) if smin < eps, else 0 (one value per iteration). */
double metric_delta(double smin, double eps);

/* Modified inverse quality q~ (MIMR, MICN, MIVL): 1 on a regular tet, larger is
 * worse; +inf for a non-positive tet when delta == 0. */
double metric_qt(opt_metric m, const metric_parts *p, double delta);

/* q~ of the tet (p12: 4 corners, 3 doubles each) and its gradient with respect
 * to corner a. If pt is not NULL it receives the tet's parts. */
double metric_qt_grad(opt_metric m, const double *p12, int a, double delta, double g[3],
                      metric_parts *pt);

/* q~, its gradient and its Hessian (upper triangle xx xy xz yy yz zz) with
 * respect to corner a, for MIVL and MIMR (NAN for MICN: no Hessian). */
double metric_qt_hess(opt_metric m, const double *p12, int a, double delta, double g[3],
                      double H[6], metric_parts *pt);
/* The same with corner a at pa and the opposite face (f0, f1, f2) ordered as
 * tet_face_of (core/tet.h) orders it for a (so that the tet is positive
 * when pa is on the inner side); vl receives the signed volume and the sum of
 * the squared edge lengths. g NULL: the value only (H unused). Without
 * copying the tet: for the finishing pass's inner loop. */
double metric_qt_hess_face(opt_metric m, const double *pa, const double *f0,
                           const double *f1, const double *f2, double delta, double g[3],
                           double H[6], double vl[2]);

/* What metric_qt_hess_face finds of the face alone, for a vertex that is
 * tried at several points against the same faces (the finishing pass: its
 * trial steps). */
typedef struct {
    const double *f[3]; /* the face's corners, as given */
    double dV[3]; /* -(e1 x e2) / 6, e1 = f1 - f0, e2 = f2 - f0: V = dV . (pa - f0) */
    double ee[5]; /* e1.e1, e2.e2, (e2 - e1)_k^2 (k = 0, 1, 2) */
} metric_face;

void metric_face_set(const double *f0, const double *f1, const double *f2,
                     metric_face *mf);
/* metric_qt_hess_face against a face set by metric_face_set: the same bits. */
double metric_qt_hess_at(opt_metric m, const double *pa, const metric_face *mf,
                         double delta, double g[3], double H[6], double vl[2]);

/* Smallest and largest of the 6 dihedral angles (degrees), as metric_dihedrals
 * but with 2 acos instead of 6. */
void metric_dihedral_range(const double *p0, const double *p1, const double *p2,
                           const double *p3, double *amin, double *amax);
/* The same as cosines (cmin of the largest angle, cmax of the smallest; -1
 * and 1 for a degenerate face): no acos, for whole-mesh scans. */
void metric_dihedral_cos_range(const double *p0, const double *p1, const double *p2,
                               const double *p3, double *cmin, double *cmax);

/* Signed mean ratio 12 (3|V|)^(2/3) / l2sum in [-1, 1]. */
double metric_mean_ratio(const metric_parts *p);
/* The cube of the signed mean ratio, 15552 V|V| / l2sum^3: the same order as
 * metric_mean_ratio (the cube is increasing), for comparisons without a cube
 * root (q < f exactly when q^3 < f^3). */
double metric_mean_ratio_cubed(const metric_parts *p);
/* Volume-length 6 sqrt2 V / l_rms^3 (signed). */
double metric_vol_length(const metric_parts *p);

/* The 6 dihedral angles in degrees (edges 01 02 03 12 13 23); a degenerate face
 * gives 0 and 180 for its angles. Returns 0, or 1 if a face is degenerate. */
int metric_dihedrals(const double *p0, const double *p1, const double *p2,
                     const double *p3, double ang[6]);
/* Their cosines, clamped to [-1, 1] (acos(c[e]) * 180 / pi is metric_dihedrals'
 * angle); returns a mask of the edges whose angle a degenerate face sets (bit
 * e: c[e] is then 1 or -1 and the angle exactly 0 or 180). */
unsigned metric_dihedral_cosines(const double *p0, const double *p1, const double *p2,
                                 const double *p3, double c[6]);

/* Signed sines of the 6 dihedral angles (edges 01 02 03 12 13 23),
 * 3 V l_ij / (2 A_k A_l) (no acos needed), negative on an inverted
 * tet, 0 when a face is degenerate. min over the tet is Stellar's and
 * Freitag's worst-angle measure (small and large angles both score low). */
void metric_dihedral_sines(const double *p0, const double *p1, const double *p2,
                           const double *p3, double s[6]);
/* The same, returning the cube of the signed mean ratio (as
 * metric_mean_ratio_cubed) from the volume and edges the sines need. */
double metric_dihedral_sines_eta3(const double *p0, const double *p1, const double *p2,
                                  const double *p3, double s[6]);

/* Eq. 8 in closed form (docs/method.md §3): the distance alpha* along the unit inward
 * normal from the barycentre of face (f0, f1, f2) that minimizes q~ (delta = 0). */
double metric_alpha_opt(opt_metric m, const double *f0, const double *f1,
                        const double *f2);

#endif
