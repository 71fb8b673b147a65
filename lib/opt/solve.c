/* solve.c - sparse SPD solves for the QDC step (docs/method.md §5, §7). */
#include "opt/solve.h"

#include "opt/encode.h"

#include <cholmod.h>
#include <math.h>
#include <string.h>

/* Above this many unknowns the direct path is not even analysed: METIS and the
 * supernodal factorization of the 2-ring pattern cost seconds to minutes
 * (docs/method.md §7: 22k vertices 1.6 s, 99k 26 s per factorization) while CG needs
 * 10-40 matrix-free products; measured on the dev corpus, the analysis alone
 * (METIS) costs more than all CG solves of a run above ~10k unknowns. */
#define SOLVE_ANALYSE_MAX 10000
/* Direct wins while its factorization is cheaper than ~40 CG iterations on
 * 3 right-hand sides; flop counts from cholmod_analyze (c.fl). */
#define SOLVE_FLOPS_PER_CG_NNZ 2000.0

struct solve_ctx {
    const mesh_topo *tp;
    opt_solver kind;
    int32_t nv, nfree;
    const uint8_t *locked; /* borrowed from the caller for the job's lifetime */
    int32_t *fidx;         /* vertex -> free index or -1 */
    int32_t *fvert;        /* free index -> vertex */
    int32_t *tslot;        /* slot (i, j) -> slot (j, i) */
    double *qtv;           /* PCG: the transposed values, qtv[k] = qval[tslot[k]] */
    double flops;
    /* CHOLMOD */
    cholmod_common c;
    int c_started;
    cholmod_sparse *A;
    cholmod_factor *L;
    int64_t *pairslot; /* per (row i, entry pair) the slot in A->x, -1 if unused */
    int64_t npairs;
    int64_t *diagslot; /* per free column, its diagonal slot */
    /* CG work */
    double *r, *z, *p, *ap, *u, *dinv;
};

opt_solver solve_kind(const solve_ctx *s)
{
    return s->kind;
}

double solve_flops(const solve_ctx *s)
{
    return s->flops;
}

/* y = Q v, each row i times scale[i] if scale (the CG's W Q v in one pass). */
static void q_mul_scaled(const mesh_topo *tp, const double *qval, const double *v,
                         const double *scale, double *y)
{
#pragma omp parallel for schedule(static)
    for (int32_t i = 0; i < tp->nv; i++) {
        double a0 = 0, a1 = 0, a2 = 0, w = scale ? scale[i] : 1.0;
        for (int32_t s = tp->adj_ptr[i]; s < tp->adj_ptr[i + 1]; s++) {
            const double *vj = v + 3 * (size_t)tp->adj_idx[s];
            a0 += qval[s] * vj[0];
            a1 += qval[s] * vj[1];
            a2 += qval[s] * vj[2];
        }
        y[3 * (size_t)i] = a0 * w;
        y[3 * (size_t)i + 1] = a1 * w;
        y[3 * (size_t)i + 2] = a2 * w;
    }
}

void solve_q_mul(const mesh_topo *tp, const double *qval, const double *v, double *y)
{
    q_mul_scaled(tp, qval, v, NULL, y);
}

/* (Q^T u)_j = sum_i Q_ij u_i; the pattern is symmetric, so row j's slots name
 * the i's and qt[k] is Q_ij of slot k of row j: qval gathered through tslot,
 * or the PCG's copy of it gathered once per solve (qtv; the gather in each
 * product took 60% of its time at 4M tets). A gather, safe to run in parallel.
 * With dg (the CG's A v in the same pass): y_j = (Q^T u)_j + dg_j v_j on free
 * vertices, 0 on locked ones. */
static void qt_mul_plus(const solve_ctx *s, const double *qval, const int32_t *tslot,
                        const double *u, const double *dg, const double *v, double *y)
{
    const mesh_topo *tp = s->tp;

#pragma omp parallel for schedule(static)
    for (int32_t j = 0; j < tp->nv; j++) {
        double a[3] = {0, 0, 0};
        for (int32_t k = tp->adj_ptr[j]; k < tp->adj_ptr[j + 1]; k++) {
            const double *ui = u + 3 * (size_t)tp->adj_idx[k];
            double q = qval[tslot ? tslot[k] : k];
            a[0] += q * ui[0];
            a[1] += q * ui[1];
            a[2] += q * ui[2];
        }
        for (int c = 0; c < 3; c++)
            y[3 * (size_t)j + c] = !dg            ? a[c]
                                   : s->locked[j] ? 0.0
                                                  : a[c] + dg[j] * v[3 * (size_t)j + c];
    }
}

void solve_qt_mul(const solve_ctx *s, const double *qval, const double *u, double *y)
{
    qt_mul_plus(s, qval, s->tslot, u, NULL, NULL, y);
}

static int cmp_i64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* Upper-triangular CSC pattern of Q_F^T Q_F (2-ring among free vertices). */
static qdc_status build_pattern(solve_ctx *s, qdc_error *err)
{
    const mesh_topo *tp = s->tp;
    int32_t nf = s->nfree;
    int64_t *colptr = NULL, *rows = NULL, nnz = 0, cap;
    int32_t *mark = NULL;
    int64_t *buf = NULL;
    int32_t maxbuf = 0;
    qdc_status st = QDC_OK;

    for (int32_t i = 0; i < tp->nv; i++) {
        int32_t tot = 0;
        for (int32_t k = tp->adj_ptr[i]; k < tp->adj_ptr[i + 1]; k++) {
            int32_t j = tp->adj_idx[k];
            tot += tp->adj_ptr[j + 1] - tp->adj_ptr[j];
        }
        if (tot > maxbuf)
            maxbuf = tot;
    }
    colptr = qdc_calloc((size_t)nf + 1, sizeof(int64_t));
    mark = qdc_mallocn((size_t)nf + 1, sizeof(int32_t));
    buf = qdc_mallocn((size_t)maxbuf + 1, sizeof(int64_t));
    cap = (int64_t)nf * 16 + 16;
    rows = qdc_mallocn((size_t)cap, sizeof(int64_t));
    if (!colptr || !mark || !buf || !rows) {
        st = QDC_ENOMEM;
        goto out;
    }
    for (int32_t f = 0; f < nf; f++)
        mark[f] = -1;
    for (int32_t c = 0; c < nf; c++) {
        int32_t vk = s->fvert[c], n = 0;
        for (int32_t k = tp->adj_ptr[vk]; k < tp->adj_ptr[vk + 1]; k++) {
            int32_t i = tp->adj_idx[k];
            for (int32_t l = tp->adj_ptr[i]; l < tp->adj_ptr[i + 1]; l++) {
                int32_t r = s->fidx[tp->adj_idx[l]];
                if (r < 0 || r > c || mark[r] == c)
                    continue;
                mark[r] = c;
                buf[n++] = r;
            }
        }
        qsort(buf, (size_t)n, sizeof(int64_t), cmp_i64);
        if (nnz + n > cap) {
            int64_t ncap = (nnz + n) * 2;
            int64_t *nr = qdc_realloc(rows, (size_t)ncap * sizeof(int64_t));
            if (!nr) {
                st = QDC_ENOMEM;
                goto out;
            }
            rows = nr;
            cap = ncap;
        }
        memcpy(rows + nnz, buf, (size_t)n * sizeof(int64_t));
        nnz += n;
        colptr[c + 1] = nnz;
    }
    s->A = cholmod_l_allocate_sparse((size_t)nf, (size_t)nf, (size_t)nnz, 1, 1, 1,
                                     CHOLMOD_REAL, &s->c);
    if (!s->A) {
        st = qdc_fail(err, QDC_ENOMEM, "CHOLMOD could not allocate the %lld-entry matrix",
                      (long long)nnz);
        goto out;
    }
    memcpy(s->A->p, colptr, ((size_t)nf + 1) * sizeof(int64_t));
    memcpy(s->A->i, rows, (size_t)nnz * sizeof(int64_t));
out:
    qdc_free(colptr);
    qdc_free(rows);
    qdc_free(mark);
    qdc_free(buf);
    return st;
}

static int64_t find_in_col(const cholmod_sparse *A, int64_t col, int64_t row)
{
    const int64_t *p = A->p, *ri = A->i;
    int64_t lo = p[col], hi = p[col + 1] - 1;

    while (lo <= hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (ri[mid] == row)
            return mid;
        if (ri[mid] < row)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return -1;
}

/* For every row i of Q and every pair of its free entries (s1 <= s2), the slot of
 * A that Q_i,s1 * Q_i,s2 adds to. Computed once: assembly is then a stream. */
static qdc_status build_pairslots(solve_ctx *s)
{
    const mesh_topo *tp = s->tp;
    int64_t n = 0;

    for (int32_t i = 0; i < tp->nv; i++) {
        int64_t d = tp->adj_ptr[i + 1] - tp->adj_ptr[i];
        n += d * (d + 1) / 2;
    }
    s->npairs = n;
    s->pairslot = qdc_mallocn((size_t)n + 1, sizeof(int64_t));
    s->diagslot = qdc_mallocn((size_t)s->nfree + 1, sizeof(int64_t));
    if (!s->pairslot || !s->diagslot)
        return QDC_ENOMEM;
    n = 0;
    for (int32_t i = 0; i < tp->nv; i++)
        for (int32_t a = tp->adj_ptr[i]; a < tp->adj_ptr[i + 1]; a++)
            for (int32_t b = a; b < tp->adj_ptr[i + 1]; b++) {
                int32_t fa = s->fidx[tp->adj_idx[a]], fb = s->fidx[tp->adj_idx[b]];
                if (fa < 0 || fb < 0)
                    s->pairslot[n++] = -1;
                else
                    s->pairslot[n++] =
                        find_in_col(s->A, fa > fb ? fa : fb, fa < fb ? fa : fb);
            }
    for (int32_t f = 0; f < s->nfree; f++)
        s->diagslot[f] = find_in_col(s->A, f, f);
    return QDC_OK;
}

static qdc_status setup_cholmod(solve_ctx *s, opt_solver want, qdc_error *err)
{
    qdc_status st;

    cholmod_l_start(&s->c);
    s->c_started = 1;
    s->c.supernodal = CHOLMOD_SUPERNODAL;
    s->c.print = 0;
    s->c.error_handler = NULL;
    if (want == OPT_SOLVER_AUTO) {
        /* the choice from AMD's ordering alone: CHOLMOD's default also tries
         * METIS, which cost 0.1-0.3 s on the dev meshes of 2k-10k vertices
         * before CG was chosen anyway (same choice on all 21) */
        s->c.nmethods = 1;
        s->c.method[0].ordering = CHOLMOD_AMD;
    }
    st = build_pattern(s, err);
    if (st != QDC_OK)
        return st;
    /* The matrix of Eq. (15) changes every iteration but its pattern does not
     * (connectivity is fixed), so the symbolic factorization is kept. */
    s->L = cholmod_l_analyze(s->A, &s->c);
    if (!s->L || s->c.status < CHOLMOD_OK)
        return qdc_fail(err,
                        s->c.status == CHOLMOD_OUT_OF_MEMORY ? QDC_ENOMEM : QDC_ESOLVE,
                        "cholmod_analyze failed (status %d)", s->c.status);
    s->flops = s->c.fl;
    if (want == OPT_SOLVER_AUTO) {
        double nnzq = (double)s->tp->adj_ptr[s->tp->nv];
        if (s->flops > SOLVE_FLOPS_PER_CG_NNZ * nnzq)
            return QDC_OK; /* caller switches to CG */
    }
    s->kind = OPT_SOLVER_CHOLMOD;
    return build_pairslots(s);
}

static void free_cholmod(solve_ctx *s)
{
    if (!s->c_started)
        return;
    cholmod_l_free_factor(&s->L, &s->c);
    cholmod_l_free_sparse(&s->A, &s->c);
    cholmod_l_finish(&s->c);
    s->c_started = 0;
    qdc_free(s->pairslot);
    qdc_free(s->diagslot);
    s->pairslot = s->diagslot = NULL;
}

qdc_status solve_new(const mesh_topo *tp, const uint8_t *locked, opt_solver want,
                     solve_ctx **out, qdc_error *err)
{
    solve_ctx *s;
    qdc_status st = QDC_OK;
    size_t n3 = 3 * (size_t)tp->nv;

    *out = NULL;
    s = qdc_calloc(1, sizeof *s);
    if (!s)
        return QDC_ENOMEM;
    s->tp = tp;
    s->nv = tp->nv;
    s->locked = locked;
    s->fidx = qdc_mallocn((size_t)tp->nv, sizeof(int32_t));
    s->fvert = qdc_mallocn((size_t)tp->nv, sizeof(int32_t));
    s->tslot = qdc_mallocn((size_t)tp->adj_ptr[tp->nv] + 1, sizeof(int32_t));
    if (!s->fidx || !s->fvert || !s->tslot) {
        st = QDC_ENOMEM;
        goto fail;
    }
    /* the pattern is symmetric with ascending columns: taking the rows in
     * order, row j's entries are met in order too, so a cursor per row finds
     * each (j, i) (a binary search per entry took 0.25 s at 4M tets); fidx
     * serves as the cursors and is set after */
    for (int32_t v = 0; v < tp->nv; v++)
        s->fidx[v] = tp->adj_ptr[v];
    for (int32_t i = 0; i < tp->nv; i++)
        for (int32_t k = tp->adj_ptr[i]; k < tp->adj_ptr[i + 1]; k++) {
            int32_t j = tp->adj_idx[k], c = s->fidx[j];
            s->tslot[k] = c < tp->adj_ptr[j + 1] && tp->adj_idx[c] == i
                              ? s->fidx[j]++
                              : encode_slot(tp, j, i);
        }
    for (int32_t v = 0; v < tp->nv; v++) {
        s->fidx[v] = locked[v] ? -1 : s->nfree;
        if (!locked[v])
            s->fvert[s->nfree++] = v;
    }
    s->kind = OPT_SOLVER_PCG;
    if (s->nfree > 0 && (want == OPT_SOLVER_CHOLMOD ||
                         (want == OPT_SOLVER_AUTO && s->nfree <= SOLVE_ANALYSE_MAX))) {
        st = setup_cholmod(s, want, err);
        if (st != QDC_OK)
            goto fail;
        if (s->kind != OPT_SOLVER_CHOLMOD)
            free_cholmod(s);
    }
    if (s->kind == OPT_SOLVER_PCG) {
        s->r = qdc_mallocn(n3, sizeof(double));
        s->z = qdc_mallocn(n3, sizeof(double));
        s->p = qdc_calloc(n3, sizeof(double));
        s->ap = qdc_mallocn(n3, sizeof(double));
        s->u = qdc_mallocn(n3, sizeof(double));
        s->dinv = qdc_mallocn((size_t)tp->nv, sizeof(double));
        s->qtv = qdc_mallocn((size_t)tp->adj_ptr[tp->nv] + 1, sizeof(double));
        if (!s->r || !s->z || !s->p || !s->ap || !s->u || !s->dinv || !s->qtv) {
            st = QDC_ENOMEM;
            goto fail;
        }
    }
    *out = s;
    return QDC_OK;
fail:
    solve_free(s);
    return st;
}

void solve_free(solve_ctx *s)
{
    if (!s)
        return;
    free_cholmod(s);
    qdc_free(s->fidx);
    qdc_free(s->fvert);
    qdc_free(s->tslot);
    qdc_free(s->r);
    qdc_free(s->z);
    qdc_free(s->p);
    qdc_free(s->ap);
    qdc_free(s->u);
    qdc_free(s->dinv);
    qdc_free(s->qtv);
    qdc_free(s);
}

static qdc_status solve_direct(solve_ctx *s, const double *qval, const double *w2,
                               const double *dg, const double *b, double *x,
                               qdc_error *err)
{
    const mesh_topo *tp = s->tp;
    double *ax = s->A->x;
    int64_t n = 0;
    cholmod_dense *B, *X;
    qdc_status st = QDC_OK;

    memset(ax, 0, (size_t)((int64_t *)s->A->p)[s->nfree] * sizeof(double));
    for (int32_t i = 0; i < tp->nv; i++) {
        double w = w2[i];
        for (int32_t a = tp->adj_ptr[i]; a < tp->adj_ptr[i + 1]; a++)
            for (int32_t c = a; c < tp->adj_ptr[i + 1]; c++) {
                int64_t slot = s->pairslot[n++];
                if (slot < 0)
                    continue;
                /* a pair a != c is one entry of the stored upper triangle */
                ax[slot] += w * qval[a] * qval[c];
            }
    }
    for (int32_t f = 0; f < s->nfree; f++)
        ax[s->diagslot[f]] += dg[s->fvert[f]];
    if (!cholmod_l_factorize(s->A, s->L, &s->c) || s->c.status < CHOLMOD_OK)
        return qdc_fail(err, QDC_ESOLVE, "cholmod_factorize failed (status %d)",
                        s->c.status);
    /* factorize returns TRUE for a matrix that is not positive definite:
     * the column where it stopped is in L->minor */
    if (s->L->minor < s->L->n)
        return qdc_fail(err, QDC_ESOLVE, "matrix not positive definite at column %lld",
                        (long long)s->L->minor);
    B = cholmod_l_allocate_dense((size_t)s->nfree, 3, (size_t)s->nfree, CHOLMOD_REAL,
                                 &s->c);
    if (!B)
        return QDC_ENOMEM;
    for (int32_t f = 0; f < s->nfree; f++)
        for (int k = 0; k < 3; k++)
            ((double *)B->x)[(size_t)k * s->nfree + f] = b[3 * (size_t)s->fvert[f] + k];
    X = cholmod_l_solve(CHOLMOD_A, s->L, B, &s->c);
    if (!X || s->c.status < CHOLMOD_OK) {
        st = qdc_fail(err, QDC_ESOLVE, "cholmod_solve failed (status %d)", s->c.status);
    } else {
        for (int32_t f = 0; f < s->nfree; f++)
            for (int k = 0; k < 3; k++)
                x[3 * (size_t)s->fvert[f] + k] =
                    ((double *)X->x)[(size_t)k * s->nfree + f];
    }
    cholmod_l_free_dense(&B, &s->c);
    cholmod_l_free_dense(&X, &s->c);
    return st;
}

/* y = (Q^T W Q + diag dg) v on free entries; v must be 0 on locked vertices.
 * The products with Q and Q^T each take the scaling that follows them in
 * the same pass (the same operations as separate passes, in the same order). */
static void apply_a(solve_ctx *s, const double *qval, const double *w2, const double *dg,
                    const double *v, double *y)
{
    q_mul_scaled(s->tp, qval, v, w2, s->u);
    qt_mul_plus(s, s->qtv, NULL, s->u, dg, v, y);
}

/* The CG's vector loops run in parallel over fixed vertex ranges whose
 * partial sums are added in range order: the result does not depend on the
 * thread count. (Serial, they took about a third of each CG iteration at 4M
 * tets, the matrix products being parallel.) */
#define CG_CHUNKS 64

static void cg_range(int32_t nv, int ch, int32_t *i0, int32_t *i1)
{
    *i0 = qdc_part(nv, ch, CG_CHUNKS);
    *i1 = qdc_part(nv, ch + 1, CG_CHUNKS);
}

/* sums[k] = the per-range partials part[.][k] added in range order */
static void cg_sum(double part[][3], double sums[3])
{
    for (int k = 0; k < 3; k++)
        sums[k] = 0.0;
    for (int ch = 0; ch < CG_CHUNKS; ch++)
        for (int k = 0; k < 3; k++)
            sums[k] += part[ch][k];
}

/* Jacobi preconditioner: diag(A)_j = sum_i w_i Q_ij^2 + dg_j, inverted into
 * s->dinv; first the transposed values into s->qtv, for it and the products. */
static void cg_jacobi(solve_ctx *s, const double *qval, const double *w2,
                      const double *dg)
{
    const mesh_topo *tp = s->tp;

#pragma omp parallel for schedule(static)
    for (int32_t j = 0; j < tp->nv; j++)
        for (int32_t k = tp->adj_ptr[j]; k < tp->adj_ptr[j + 1]; k++)
            s->qtv[k] = qval[s->tslot[k]];
#pragma omp parallel for schedule(static)
    for (int32_t j = 0; j < tp->nv; j++) {
        double a = dg[j];
        for (int32_t k = tp->adj_ptr[j]; k < tp->adj_ptr[j + 1]; k++) {
            double q = s->qtv[k];
            a += w2[tp->adj_idx[k]] * q * q;
        }
        s->dinv[j] = a > 0.0 ? 1.0 / a : 1.0;
    }
}

/* The start of CG from x (locked entries 0) into xs: residual, preconditioned
 * residual and direction, r.z, |b|^2 and |r|^2 per coordinate. */
static void cg_start(solve_ctx *s, const double *qval, const double *w2, const double *dg,
                     const double *b, const double *x, double *xs, double rz[3],
                     double bnorm[3], double rnorm[3])
{
    int32_t nv = s->tp->nv;
    double part_a[CG_CHUNKS][3], part_b[CG_CHUNKS][3], part_c[CG_CHUNKS][3];

#pragma omp parallel for schedule(static)
    for (int32_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++)
            xs[3 * (size_t)i + k] = s->locked[i] ? 0.0 : x[3 * (size_t)i + k];
    apply_a(s, qval, w2, dg, xs, s->ap);
#pragma omp parallel for schedule(static)
    for (int ch = 0; ch < CG_CHUNKS; ch++) {
        int32_t i0, i1;
        double a[3] = {0, 0, 0}, bb[3] = {0, 0, 0}, c[3] = {0, 0, 0};
        cg_range(nv, ch, &i0, &i1);
        for (int32_t i = i0; i < i1; i++)
            for (int k = 0; k < 3; k++) {
                size_t q = 3 * (size_t)i + k;
                double bi = s->locked[i] ? 0.0 : b[q];
                s->r[q] = bi - s->ap[q];
                s->z[q] = s->dinv[i] * s->r[q];
                s->p[q] = s->z[q];
                a[k] += s->r[q] * s->z[q];
                bb[k] += bi * bi;
                c[k] += s->r[q] * s->r[q];
            }
        memcpy(part_a[ch], a, sizeof a);
        memcpy(part_b[ch], bb, sizeof bb);
        memcpy(part_c[ch], c, sizeof c);
    }
    cg_sum(part_a, rz);
    cg_sum(part_b, bnorm);
    cg_sum(part_c, rnorm);
}

/* p.Ap per coordinate (fixed chunks summed in order). */
static void cg_pap(const solve_ctx *s, double pap[3])
{
    int32_t nv = s->tp->nv;
    double part_a[CG_CHUNKS][3];

#pragma omp parallel for schedule(static)
    for (int ch = 0; ch < CG_CHUNKS; ch++) {
        int32_t i0, i1;
        double a[3] = {0, 0, 0};
        cg_range(nv, ch, &i0, &i1);
        for (int32_t i = i0; i < i1; i++)
            for (int k = 0; k < 3; k++)
                a[k] += s->p[3 * (size_t)i + k] * s->ap[3 * (size_t)i + k];
        memcpy(part_a[ch], a, sizeof a);
    }
    cg_sum(part_a, pap);
}

/* xs += alpha p, r -= alpha Ap, z = M^-1 r; the new r.z and |r|^2. */
static void cg_advance(solve_ctx *s, double *xs, const double alpha[3], double rz1[3],
                       double rnorm[3])
{
    int32_t nv = s->tp->nv;
    double part_a[CG_CHUNKS][3], part_c[CG_CHUNKS][3];

#pragma omp parallel for schedule(static)
    for (int ch = 0; ch < CG_CHUNKS; ch++) {
        int32_t i0, i1;
        double a[3] = {0, 0, 0}, c[3] = {0, 0, 0};
        cg_range(nv, ch, &i0, &i1);
        for (int32_t i = i0; i < i1; i++)
            for (int k = 0; k < 3; k++) {
                size_t q = 3 * (size_t)i + k;
                xs[q] += alpha[k] * s->p[q];
                s->r[q] -= alpha[k] * s->ap[q];
                s->z[q] = s->dinv[i] * s->r[q];
                a[k] += s->r[q] * s->z[q];
                c[k] += s->r[q] * s->r[q];
            }
        memcpy(part_a[ch], a, sizeof a);
        memcpy(part_c[ch], c, sizeof c);
    }
    cg_sum(part_a, rz1);
    cg_sum(part_c, rnorm);
}

static qdc_status solve_pcg(solve_ctx *s, const double *qval, const double *w2,
                            const double *dg, const double *b, double *x, int *iters,
                            qdc_error *err)
{
    int32_t nv = s->tp->nv;
    double rz[3], bnorm[3], rnorm[3];
    int done[3] = {0, 0, 0}, it;
    const double rtol = 1e-10;
    const int max_it = 2000;
    double *xs = qdc_mallocn(3 * (size_t)nv, sizeof(double));

    if (!xs)
        return QDC_ENOMEM;
    cg_jacobi(s, qval, w2, dg);
    cg_start(s, qval, w2, dg, b, x, xs, rz, bnorm, rnorm);
    for (int k = 0; k < 3; k++) {
        bnorm[k] = sqrt(bnorm[k]);
        done[k] = sqrt(rnorm[k]) <= rtol * (bnorm[k] > 0 ? bnorm[k] : 1.0);
    }
    for (it = 0; it < max_it && !(done[0] && done[1] && done[2]); it++) {
        double pap[3], alpha[3], rz1[3], beta[3];
        apply_a(s, qval, w2, dg, s->p, s->ap);
        cg_pap(s, pap);
        for (int k = 0; k < 3; k++)
            alpha[k] = done[k] || !(pap[k] > 0) ? 0.0 : rz[k] / pap[k];
        cg_advance(s, xs, alpha, rz1, rnorm);
        for (int k = 0; k < 3; k++) {
            beta[k] = done[k] || !(rz[k] > 0) ? 0.0 : rz1[k] / rz[k];
            if (!done[k])
                done[k] = sqrt(rnorm[k]) <= rtol * (bnorm[k] > 0 ? bnorm[k] : 1.0);
            rz[k] = rz1[k];
            if (done[k])
                beta[k] = 0.0;
        }
#pragma omp parallel for schedule(static)
        for (int32_t i = 0; i < nv; i++)
            for (int k = 0; k < 3; k++) {
                size_t q = 3 * (size_t)i + k;
                s->p[q] = done[k] ? 0.0 : s->z[q] + beta[k] * s->p[q];
            }
    }
    *iters = it;
#pragma omp parallel for schedule(static)
    for (int32_t i = 0; i < nv; i++)
        if (!s->locked[i])
            for (int k = 0; k < 3; k++)
                x[3 * (size_t)i + k] = xs[3 * (size_t)i + k];
    qdc_free(xs);
    if (!(done[0] && done[1] && done[2])) {
        /* Loose but finite solutions are still usable: the line search decides.
         * Only non-finite residuals are a failure. */
        for (int k = 0; k < 3; k++)
            if (!isfinite(rnorm[k]))
                return qdc_fail(err, QDC_ESOLVE, "CG diverged after %d iterations", it);
    }
    return QDC_OK;
}

qdc_status solve_system(solve_ctx *s, const double *qval, const double *w2,
                        const double *dg, const double *b, double *x, int *iters,
                        qdc_error *err)
{
    *iters = 0;
    if (s->nfree == 0)
        return QDC_OK;
    if (s->kind == OPT_SOLVER_CHOLMOD)
        return solve_direct(s, qval, w2, dg, b, x, err);
    return solve_pcg(s, qval, w2, dg, b, x, iters, err);
}

/* y = A v for a 1-ring-pattern matrix restricted to unlocked vertices; returns v.y */
static double pattern_mul(const mesh_topo *tp, const uint8_t *locked, const double *aval,
                          const double *v, double *y)
{
    double vy = 0.0;

    for (int32_t i = 0; i < tp->nv; i++) {
        double a = 0;
        if (!locked[i])
            for (int32_t k = tp->adj_ptr[i]; k < tp->adj_ptr[i + 1]; k++)
                if (!locked[tp->adj_idx[k]])
                    a += aval[k] * v[tp->adj_idx[k]];
        y[i] = a;
        vy += v[i] * a;
    }
    return vy;
}

qdc_status solve_cg_pattern(const mesh_topo *tp, const uint8_t *locked,
                            const double *aval, const double *b, double *x, double rtol,
                            int max_iter, int *iters, qdc_error *err)
{
    int32_t nv = tp->nv;
    double *r = qdc_mallocn((size_t)nv, sizeof(double));
    double *z = qdc_mallocn((size_t)nv, sizeof(double));
    double *p = qdc_calloc((size_t)nv, sizeof(double));
    double *ap = qdc_mallocn((size_t)nv, sizeof(double));
    double *dinv = qdc_mallocn((size_t)nv, sizeof(double));
    double rz = 0, bn = 0, rn = 0;
    int it = 0;
    qdc_status st = QDC_OK;

    if (!r || !z || !p || !ap || !dinv) {
        st = QDC_ENOMEM;
        goto out;
    }
    for (int32_t i = 0; i < nv; i++) {
        int32_t d = encode_slot(tp, i, i);
        dinv[i] = d >= 0 && aval[d] > 0 ? 1.0 / aval[d] : 1.0;
    }
    pattern_mul(tp, locked, aval, x, ap);
    for (int32_t i = 0; i < nv; i++) {
        double bi = locked[i] ? 0.0 : b[i];
        r[i] = bi - ap[i];
        z[i] = dinv[i] * r[i];
        p[i] = z[i];
        rz += r[i] * z[i];
        bn += bi * bi;
        rn += r[i] * r[i];
    }
    bn = sqrt(bn);
    for (it = 0; it < max_iter && sqrt(rn) > rtol * (bn > 0 ? bn : 1.0); it++) {
        double pap = pattern_mul(tp, locked, aval, p, ap), alpha, rz1 = 0;
        if (!(pap > 0))
            break;
        alpha = rz / pap;
        rn = 0;
        for (int32_t i = 0; i < nv; i++) {
            x[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
            z[i] = dinv[i] * r[i];
            rz1 += r[i] * z[i];
            rn += r[i] * r[i];
        }
        for (int32_t i = 0; i < nv; i++)
            p[i] = z[i] + (rz1 / rz) * p[i];
        rz = rz1;
    }
    if (!isfinite(rn))
        st = qdc_fail(err, QDC_ESOLVE, "CG diverged");
out:
    if (iters)
        *iters = it;
    qdc_free(r);
    qdc_free(z);
    qdc_free(p);
    qdc_free(ap);
    qdc_free(dinv);
    return st;
}
