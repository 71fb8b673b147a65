/* solve.h - the linear system of one semi-implicit step (paper Eq. 15, docs/method.md §5,
 * §7): (Q_F^T W Q_F + diag(dg)) X = B over the free vertices F (locked vertices are
 * eliminated by the caller, which moves their contribution into B). Q lives on the 1-ring
 * pattern of the mesh (see encode.h), W = diag(w2) weights the rows. Three right-hand
 * sides (x, y, z) share one matrix: one factorization, one solve. Two paths: CHOLMOD
 * supernodal Cholesky (pattern analysed once, factorized per step) and matrix-free
 * Jacobi-preconditioned CG, chosen per job from the analysis. Vectors are full length, 3
 * per vertex (xyz interleaved); entries of locked vertices are ignored on input and left
 * untouched on output. Only this module includes CHOLMOD. Thread-safe: one context per
 * job. */
#ifndef QDC_SOLVE_H
#define QDC_SOLVE_H

#include "core/mesh_int.h"
#include "opt/opt.h"

typedef struct solve_ctx solve_ctx;

/* locked: nv flags (non-zero = not an unknown). want: AUTO analyses the pattern
 * (when small enough) and picks the cheaper path. */
qdc_status solve_new(const mesh_topo *tp, const uint8_t *locked, opt_solver want,
                     solve_ctx **out, qdc_error *err);
void solve_free(solve_ctx *s);

opt_solver solve_kind(const solve_ctx *s);
double solve_flops(const solve_ctx *s); /* CHOLMOD's flop estimate, 0 if not analysed */

/* Solve; x holds the warm start (used by CG) and receives the solution.
 * *iters: CG iterations (max over the 3 right-hand sides), 0 for CHOLMOD.
 * QDC_ESOLVE if the matrix is not positive definite or CG does not converge. */
qdc_status solve_system(solve_ctx *s, const double *qval, const double *w2,
                        const double *dg, const double *b, double *x, int *iters,
                        qdc_error *err);

/* y = Q v and y = Q^T u on full-length 3-per-vertex vectors. */
void solve_q_mul(const mesh_topo *tp, const double *qval, const double *v, double *y);
void solve_qt_mul(const solve_ctx *s, const double *qval, const double *u, double *y);

/* The same CG, standalone, for a symmetric positive definite system given by
 * the 1-ring-pattern matrix aval (used for the harmonic field's Laplacian):
 * solves aval * x = b on the unlocked vertices, 1 right-hand side; locked entries
 * of x are neither read nor written (move their contribution into b). */
qdc_status solve_cg_pattern(const mesh_topo *tp, const uint8_t *locked,
                            const double *aval, const double *b, double *x, double rtol,
                            int max_iter, int *iters, qdc_error *err);

#endif
