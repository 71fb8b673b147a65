/* harm.c - harmonic guidance field (paper Sec. 5.1, docs/method.md §6). */
#include "opt/harm.h"

#include "geom/bderr_int.h"
#include "opt/solve.h"

#include <math.h>
#include <string.h>

/* Medial vertices: interior vertices that are local maxima of the distance to
 * the boundary over their 1-ring, or the farther endpoint of an interior edge
 * whose closest-point directions differ by more than 60 degrees. */
static qdc_status medial(const mesh_topo *tp, const double *x, uint8_t *med,
                         int32_t *count, qdc_error *err)
{
    bderr_bvh *bvh = NULL;
    double *dist = qdc_calloc((size_t)tp->nv, sizeof(double));
    double *dir = qdc_calloc(3 * (size_t)tp->nv, sizeof(double));
    const double cos60 = 0.5;
    int32_t n = 0, far = -1;
    qdc_status st;

    if (!dist || !dir) {
        st = QDC_ENOMEM;
        goto out;
    }
    st = bderr_bvh_build(x, tp->nv, tp->bfaces, tp->nbf, &bvh, err);
    if (st != QDC_OK)
        goto out;
#pragma omp parallel for schedule(dynamic, 512)
    for (int32_t v = 0; v < tp->nv; v++) {
        double cp[3], d;
        if (tp->vflag[v] & (MESH_V_BOUNDARY | MESH_V_UNUSED))
            continue;
        d = bderr_bvh_closest(bvh, x + 3 * (size_t)v, cp, NULL);
        dist[v] = d;
        if (d > 0)
            for (int k = 0; k < 3; k++)
                dir[3 * (size_t)v + k] = (cp[k] - x[3 * (size_t)v + k]) / d;
    }
    memset(med, 0, (size_t)tp->nv);
    for (int32_t v = 0; v < tp->nv; v++) {
        int is_max = 1;
        if (tp->vflag[v] & (MESH_V_BOUNDARY | MESH_V_UNUSED))
            continue;
        if (far < 0 || dist[v] > dist[far])
            far = v;
        for (int32_t k = tp->adj_ptr[v]; k < tp->adj_ptr[v + 1]; k++) {
            int32_t u = tp->adj_idx[k];
            const double *a = dir + 3 * (size_t)v, *b = dir + 3 * (size_t)u;
            if (u == v)
                continue;
            if (dist[u] > dist[v])
                is_max = 0;
            if (u > v && !(tp->vflag[u] & MESH_V_BOUNDARY) &&
                a[0] * b[0] + a[1] * b[1] + a[2] * b[2] < cos60)
                med[dist[u] > dist[v] ? u : v] = 1;
        }
        if (is_max && dist[v] > 0)
            med[v] = 1;
    }
    for (int32_t v = 0; v < tp->nv; v++)
        n += med[v];
    if (n == 0 && far >= 0) {
        med[far] = 1;
        n = 1;
    }
    *count = n;
out:
    bderr_bvh_free(bvh);
    qdc_free(dist);
    qdc_free(dir);
    return st;
}

qdc_status harm_field(const mesh_topo *tp, const double *x, double *h, int32_t *n_medial,
                      qdc_error *err)
{
    uint8_t *med = qdc_mallocn((size_t)tp->nv, 1);
    uint8_t *fixed = qdc_mallocn((size_t)tp->nv, 1);
    double *lap = qdc_mallocn((size_t)tp->adj_ptr[tp->nv] + 1, sizeof(double));
    double *b = qdc_calloc((size_t)tp->nv, sizeof(double));
    int32_t nmed = 0;
    int iters = 0;
    qdc_status st;

    if (!med || !fixed || !lap || !b) {
        st = QDC_ENOMEM;
        goto out;
    }
    st = medial(tp, x, med, &nmed, err);
    if (st != QDC_OK)
        goto out;
    for (int32_t v = 0; v < tp->nv; v++) {
        int on_b = (tp->vflag[v] & MESH_V_BOUNDARY) != 0;
        fixed[v] = on_b || med[v] || (tp->vflag[v] & MESH_V_UNUSED);
        h[v] = on_b ? 1.0 : 0.0;
    }
    /* uniform graph Laplacian L = D - A; Dirichlet values move to b */
    for (int32_t i = 0; i < tp->nv; i++) {
        int32_t deg = tp->adj_ptr[i + 1] - tp->adj_ptr[i] - 1;
        for (int32_t k = tp->adj_ptr[i]; k < tp->adj_ptr[i + 1]; k++) {
            int32_t j = tp->adj_idx[k];
            lap[k] = j == i ? (double)deg : -1.0;
            if (j != i && fixed[j])
                b[i] += h[j];
        }
    }
    st = solve_cg_pattern(tp, fixed, lap, b, h, 1e-10, 5000, &iters, err);
    for (int32_t v = 0; v < tp->nv; v++)
        h[v] = h[v] < 0 ? 0 : (h[v] > 1 ? 1 : h[v]);
    if (n_medial)
        *n_medial = nmed;
out:
    qdc_free(med);
    qdc_free(fixed);
    qdc_free(lap);
    qdc_free(b);
    return st;
}
