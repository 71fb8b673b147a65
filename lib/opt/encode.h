/* encode.h - quality differential coordinates (paper Eqs. 3-8, docs/method.md §3-§4).
 * Q lives on the 1-ring pattern of mesh_topo (adj_ptr/adj_idx): qval has one
 * value per pattern slot; rows exist for every vertex and sum to 0 off the
 * diagonal part (Q = I - W with rows of W summing to 1).
 * Thread-safe: pure functions over caller arrays (OpenMP inside). */
#ifndef QDC_ENCODE_H
#define QDC_ENCODE_H

#include "core/mesh_int.h"
#include "opt/opt.h"

/* Per-tet q~ at coordinates x for a given delta, their sum, and the number of
 * tets whose metric argument is <= 0. Returns the sum (+inf if delta == 0 and a
 * tet is not positive). qt may be NULL. */
double encode_objective(const mesh_topo *tp, const double *x, opt_metric m, double delta,
                        double *qt, int32_t *n_nonpos);

/* What encode_objective_scan finds at x besides: the smallest mean ratio
 * cubed (ctx_tet_eta3's value, signed) and the count of unusable tets
 * (geom_tet_bad of core/tet.h). */
typedef struct {
    double eta3_min;
    int32_t n_bad;
} encode_scan;

/* encode_objective (the same sum, bit for bit) and *sc, in the one pass over
 * the tets: the global iteration's line search needs both at x. */
double encode_objective_scan(const mesh_topo *tp, const double *x, opt_metric m,
                             double delta, double *qt, encode_scan *sc);

/* Optimal-position averaging (docs/method.md §4, default): row i of Q is
 * v_i - sum_t c_ti bary(face opposite i in t), c_ti = qt_t / sum_{s in T(i)} qt_s,
 * and d_i = sum_t c_ti alpha*_t n_ti (3 per vertex), so (Qx - d)_i = v_i - u_i.
 * fslot: the slots of each star entry's face vertices from encode_face_slots,
 * or NULL (then each is found by search). */
void encode_optavg(const mesh_topo *tp, const double *x, opt_metric m, const double *qt,
                   const uint8_t *fslot, double *qval, double *d);
/* For star entry k of vertex i (vt_idx[k]) and its face's vertex f (0..2),
 * fslot[3k + f] = slot - adj_ptr[i], or 255 when that is 255 or more (then
 * searched): 12 bytes per tet, the pattern never changes. NULL if out of
 * memory. Free with qdc_free. */
uint8_t *encode_face_slots(const mesh_topo *tp);

/* Paper Eq. 6-7: w_ij = sum_{t in T(i)} qt_t^2 / max(|v_j - p_ti|^2, floor), rows
 * normalized, Q = I - W, d = 0. */
void encode_paper(const mesh_topo *tp, const double *x, opt_metric m, const double *qt,
                  double *qval, double *d);

/* Slot of entry (i, j) in the 1-ring pattern, or -1. */
int32_t encode_slot(const mesh_topo *tp, int32_t i, int32_t j);

#endif
