/* encode.c - quality differential coordinates (paper Eqs. 3-8, docs/method.md §3-§4). */
#include "opt/encode.h"

#include "core/tet.h"

#include "geom/metric_int.h"

#include <math.h>
#include <omp.h>
#include <string.h>

static void tet_points(const mesh_topo *tp, const double *x, int32_t t, double p[4][3])
{
    for (int a = 0; a < 4; a++)
        memcpy(p[a], x + 3 * (size_t)tp->tets[4 * (size_t)t + a], 3 * sizeof(double));
}

/* Sums over tets are formed per fixed chunk and added in chunk order, so the
 * result (and every line-search decision taken on it) does not depend on the
 * number of threads or their timing. */
#define ENCODE_CHUNKS 256

/* The objective's pass, with sc (may be NULL) filled too. */
static double objective_pass(const mesh_topo *tp, const double *x, opt_metric m,
                             double delta, double *qt, int32_t *n_nonpos, encode_scan *sc)
{
    double part[ENCODE_CHUNKS], emin[ENCODE_CHUNKS], sum = 0.0;
    int32_t badc[ENCODE_CHUNKS], unus[ENCODE_CHUNKS], bad = 0;

#pragma omp parallel for schedule(static)
    for (int c = 0; c < ENCODE_CHUNKS; c++) {
        int32_t t0 = qdc_part(tp->nt, c, ENCODE_CHUNKS);
        int32_t t1 = qdc_part(tp->nt, c + 1, ENCODE_CHUNKS);
        double s = 0.0, e3 = INFINITY;
        int32_t b = 0, u = 0;
        for (int32_t t = t0; t < t1; t++) {
            double p[4][3], q;
            metric_parts pt;
            tet_points(tp, x, t, p);
            metric_parts_for(m, p[0], p[1], p[2], p[3], &pt);
            b += !(metric_arg(m, &pt) > 0.0);
            q = metric_qt(m, &pt, delta);
            if (qt)
                qt[t] = q;
            s += q;
            if (sc) { /* every metric's parts hold MIVL's vol and l2sum */
                double e = metric_mean_ratio_cubed(&pt);
                e3 = e < e3 ? e : e3;
                u += geom_tet_bad(x, tp->tets + 4 * (size_t)t);
            }
        }
        part[c] = s;
        badc[c] = b;
        emin[c] = e3;
        unus[c] = u;
    }
    if (sc) {
        sc->eta3_min = INFINITY;
        sc->n_bad = 0;
    }
    for (int c = 0; c < ENCODE_CHUNKS; c++) {
        sum += part[c];
        bad += badc[c];
        if (sc) {
            sc->eta3_min = emin[c] < sc->eta3_min ? emin[c] : sc->eta3_min;
            sc->n_bad += unus[c];
        }
    }
    if (n_nonpos)
        *n_nonpos = bad;
    return sum;
}

double encode_objective(const mesh_topo *tp, const double *x, opt_metric m, double delta,
                        double *qt, int32_t *n_nonpos)
{
    return objective_pass(tp, x, m, delta, qt, n_nonpos, NULL);
}

double encode_objective_scan(const mesh_topo *tp, const double *x, opt_metric m,
                             double delta, double *qt, encode_scan *sc)
{
    return objective_pass(tp, x, m, delta, qt, NULL, sc);
}

int32_t encode_slot(const mesh_topo *tp, int32_t i, int32_t j)
{
    int32_t lo = tp->adj_ptr[i], hi = tp->adj_ptr[i + 1] - 1;

    while (lo <= hi) {
        int32_t mid = lo + (hi - lo) / 2;
        if (tp->adj_idx[mid] == j)
            return mid;
        if (tp->adj_idx[mid] < j)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return -1;
}

/* Face opposite local vertex a of tet t: its 3 vertex ids, barycentre, unit
 * inward normal (docs/method.md §1: from the connectivity's orientation, never from the
 * current side of the free vertex) and alpha* (Eq. 8, closed form). */
static void face_target(const mesh_topo *tp, const double *x, opt_metric m, int32_t t,
                        int a, int32_t fv[3], double pc[3], double n[3], double *alpha)
{
    const double *f[3];
    double e1[3], e2[3], len;

    for (int k = 0; k < 3; k++) {
        fv[k] = tp->tets[4 * (size_t)t + tet_face_of[a][k]];
        f[k] = x + 3 * (size_t)fv[k];
    }
    for (int k = 0; k < 3; k++) {
        pc[k] = (f[0][k] + f[1][k] + f[2][k]) / 3.0;
        e1[k] = f[1][k] - f[0][k];
        e2[k] = f[2][k] - f[0][k];
    }
    n[0] = -(e1[1] * e2[2] - e1[2] * e2[1]);
    n[1] = -(e1[2] * e2[0] - e1[0] * e2[2]);
    n[2] = -(e1[0] * e2[1] - e1[1] * e2[0]);
    len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len > 0.0) {
        n[0] /= len;
        n[1] /= len;
        n[2] /= len;
        *alpha = metric_alpha_opt(m, f[0], f[1], f[2]);
    } else {
        n[0] = n[1] = n[2] = 0.0; /* degenerate face: target its barycentre */
        *alpha = 0.0;
    }
}

uint8_t *encode_face_slots(const mesh_topo *tp)
{
    int nth = qdc_threads_upto(8);
    uint8_t *fs = qdc_mallocn(12 * (size_t)tp->nt + 1, 1);
    /* per thread, each vertex's offset in the row being filled (a row's
     * entries are written before they are read, so no clearing) */
    uint8_t *pos = qdc_mallocn((size_t)nth * ((size_t)tp->nv + 1), 1);

    if (!fs || !pos) {
        qdc_free(fs);
        qdc_free(pos);
        return NULL;
    }
#pragma omp parallel num_threads(nth)
    {
        uint8_t *ps = pos + (size_t)omp_get_thread_num() * ((size_t)tp->nv + 1);
#pragma omp for schedule(static)
        for (int32_t i = 0; i < tp->nv; i++) {
            int32_t r0 = tp->adj_ptr[i];
            for (int32_t s = r0; s < tp->adj_ptr[i + 1]; s++)
                ps[tp->adj_idx[s]] = (uint8_t)(s - r0 < 255 ? s - r0 : 255);
            for (int32_t k = tp->vt_ptr[i]; k < tp->vt_ptr[i + 1]; k++) {
                int32_t t = tp->vt_idx[k] >> 2, a = tp->vt_idx[k] & 3;
                for (int f = 0; f < 3; f++)
                    fs[3 * (size_t)k + f] =
                        ps[tp->tets[4 * (size_t)t + tet_face_of[a][f]]];
            }
        }
    }
    qdc_free(pos);
    return fs;
}

/* (the search for each face vertex's slot was 3% of a 4M-tet run) */
void encode_optavg(const mesh_topo *tp, const double *x, opt_metric m, const double *qt,
                   const uint8_t *fslot, double *qval, double *d)
{
#pragma omp parallel for schedule(dynamic, 256)
    for (int32_t i = 0; i < tp->nv; i++) {
        double sum = 0.0, di[3] = {0, 0, 0};
        int32_t r0 = tp->adj_ptr[i], r1 = tp->adj_ptr[i + 1];

        for (int32_t s = r0; s < r1; s++)
            qval[s] = tp->adj_idx[s] == i ? 1.0 : 0.0;
        for (int32_t k = tp->vt_ptr[i]; k < tp->vt_ptr[i + 1]; k++)
            sum += qt[tp->vt_idx[k] >> 2];
        if (!(sum > 0.0) || !isfinite(sum)) {
            /* unused vertex, or a star with infinite q~ (only with delta = 0 on
             * an invalid mesh): identity row, target = current position */
            memcpy(d + 3 * (size_t)i, x + 3 * (size_t)i, 3 * sizeof(double));
            continue;
        }
        for (int32_t k = tp->vt_ptr[i]; k < tp->vt_ptr[i + 1]; k++) {
            int32_t t = tp->vt_idx[k] >> 2, a = tp->vt_idx[k] & 3, fv[3];
            double pc[3], n[3], alpha, c = qt[t] / sum;
            face_target(tp, x, m, t, a, fv, pc, n, &alpha);
            for (int j = 0; j < 3; j++) {
                int fo = fslot ? fslot[3 * (size_t)k + j] : 255;
                int32_t s = fo < 255 ? r0 + fo : encode_slot(tp, i, fv[j]);
                qval[s] -= c / 3.0;
                di[j] += c * alpha * n[j];
            }
        }
        memcpy(d + 3 * (size_t)i, di, sizeof di);
    }
}

void encode_paper(const mesh_topo *tp, const double *x, opt_metric m, const double *qt,
                  double *qval, double *d)
{
    const double floor2 = 1e-12; /* normalized units (bbox diagonal 1) */

#pragma omp parallel for schedule(dynamic, 256)
    for (int32_t i = 0; i < tp->nv; i++) {
        int32_t r0 = tp->adj_ptr[i], r1 = tp->adj_ptr[i + 1];
        double rowsum = 0.0;

        memset(d + 3 * (size_t)i, 0, 3 * sizeof(double));
        for (int32_t s = r0; s < r1; s++)
            qval[s] = 0.0;
        /* Eq. 6, 'all' reading: every tet of T(i) contributes to every 1-ring
         * neighbour j (docs/method.md §4: the per-tet reading flattens the worst tet). */
        for (int32_t k = tp->vt_ptr[i]; k < tp->vt_ptr[i + 1]; k++) {
            int32_t t = tp->vt_idx[k] >> 2, a = tp->vt_idx[k] & 3, fv[3];
            double pc[3], n[3], alpha, p[3], q2 = qt[t] * qt[t];
            if (!isfinite(q2))
                continue;
            face_target(tp, x, m, t, a, fv, pc, n, &alpha);
            for (int c = 0; c < 3; c++)
                p[c] = pc[c] + alpha * n[c];
            for (int32_t s = r0; s < r1; s++) {
                const double *xj = x + 3 * (size_t)tp->adj_idx[s];
                double dx = xj[0] - p[0], dy = xj[1] - p[1], dz = xj[2] - p[2];
                double dd = dx * dx + dy * dy + dz * dz;
                if (tp->adj_idx[s] == i)
                    continue;
                qval[s] += q2 / (dd > floor2 ? dd : floor2);
            }
        }
        for (int32_t s = r0; s < r1; s++)
            rowsum += qval[s];
        for (int32_t s = r0; s < r1; s++) {
            if (tp->adj_idx[s] == i)
                qval[s] = 1.0;
            else
                qval[s] = rowsum > 0.0 ? -qval[s] / rowsum : 0.0;
        }
    }
}
