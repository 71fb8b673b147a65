/* hold.c - the vertices a finished run holds or frees: hold_back (do no
 * harm, docs/method.md §5), and the masks the reruns read (rerun.c): the
 * squashed ears and the stuck boundary. */
#include "opt/hold.h"

#include "core/tet.h"
#include "geom/metric_int.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Mean ratio of tet t at coordinates x. */
static double tet_mean_ratio(const mesh_topo *tp, const double *x, int32_t t)
{
    const int32_t *tt = tp->tets + 4 * (size_t)t;
    metric_parts pt;
    metric_parts_of(x + 3 * (size_t)tt[0], x + 3 * (size_t)tt[1], x + 3 * (size_t)tt[2],
                    x + 3 * (size_t)tt[3], &pt);
    return metric_mean_ratio(&pt);
}

/* Slide mode: the corners of the smooth ears (slide.h) that the run squashed
 * to less than half their input mean ratio and to among the worst tets of its
 * result (under twice its worst mean ratio, or inverted), as an nv mask (NULL
 * if none). An ear squashed but still far above the worst tet costs nothing
 * that holding it would buy back: measured on a tangled thin bone
 * (scripts/corpus.py --tets 100000, bone-scan-tangled), three reruns for such
 * ears, each worse than the first run (worst mean ratio 0.0032 -> 0.0026 and
 * below), took 4.7x the time. */
qdc_status opt_squashed_ears(const ctx_t *c, uint8_t **out)
{
    const mesh_topo *tp = c->tp;
    uint8_t *ear = qdc_mallocn((size_t)tp->nt + 1, 1), *pins = NULL;
    const double worst = 2.0 * fmax(c->best.q_min, 0.0);
    int32_t n;

    *out = NULL;
    if (!ear)
        return QDC_ENOMEM;
    n = slide_smooth_ears(c->sl, tp, ear);
    if (n < 0) {
        qdc_free(ear);
        return QDC_ENOMEM;
    }
    for (int32_t t = 0; n > 0 && t < tp->nt; t++) {
        double q;
        if (!ear[t])
            continue;
        q = tet_mean_ratio(tp, c->xbest, t);
        if (!(q < 0.5 * tet_mean_ratio(tp, c->x0, t)) || !(q < worst || q <= 0.0))
            continue;
        if (!pins && !(pins = qdc_calloc((size_t)c->nv, 1))) {
            qdc_free(ear);
            return QDC_ENOMEM;
        }
        for (int a = 0; a < 4; a++)
            pins[tp->tets[4 * (size_t)t + a]] = 1;
    }
    qdc_free(ear);
    *out = pins;
    return QDC_OK;
}

/* Do no harm on a valid input (docs/method.md §5): no tet of the returned mesh
 * may be inverted, below the input's worst mean ratio or below its smallest
 * dihedral angle. The best iterate already keeps the first two over the whole
 * mesh; the finishing and angle passes can still trade the smallest angle
 * for the mean (a structured cube: 45 -> 39 degrees). The corners of every
 * tet that breaks a rule go back to their input positions, and again while
 * the tets around them break one; with all corners back the mesh is the
 * input, so the rounds end. Returns how many vertices went back. */
int32_t opt_hold_back(ctx_t *c)
{
    const mesh_topo *tp = c->tp;
    double cmax0 = -2.0, qmin0 = c->input.q_min;
    int32_t back = 0;

    if (c->input.n_inverted > 0 || c->best_it == 0)
        return 0;
#pragma omp parallel for reduction(max : cmax0) schedule(static)
    for (int32_t t = 0; t < tp->nt; t++) {
        const int32_t *tt = tp->tets + 4 * (size_t)t;
        double lo, hi;
        metric_dihedral_cos_range(c->x0 + 3 * (size_t)tt[0], c->x0 + 3 * (size_t)tt[1],
                                  c->x0 + 3 * (size_t)tt[2], c->x0 + 3 * (size_t)tt[3],
                                  &lo, &hi);
        cmax0 = hi > cmax0 ? hi : cmax0;
    }
    memset(c->vmark, 0, (size_t)c->nv);
    for (;;) {
        int32_t n = 0;
#pragma omp parallel for schedule(static)
        for (int32_t t = 0; t < tp->nt; t++) {
            const int32_t *tt = tp->tets + 4 * (size_t)t;
            const double *y = c->xbest;
            double lo, hi;
            if (geom_tet_bad(y, tt)) {
                ctx_mark_corners(c, tt);
                continue;
            }
            metric_dihedral_cos_range(y + 3 * (size_t)tt[0], y + 3 * (size_t)tt[1],
                                      y + 3 * (size_t)tt[2], y + 3 * (size_t)tt[3], &lo,
                                      &hi);
            if (hi > cmax0 || ctx_tet_eta3(y, tt) < qmin0 * qmin0 * qmin0)
                ctx_mark_corners(c, tt);
        }
        for (int32_t v = 0; v < c->nv; v++) {
            double *y = c->xbest + 3 * (size_t)v;
            const double *o = c->x0 + 3 * (size_t)v;
            if (!c->vmark[v])
                continue;
            c->vmark[v] = 0;
            if (y[0] != o[0] || y[1] != o[1] || y[2] != o[2]) {
                memcpy(y, o, 3 * sizeof(double));
                n++;
            }
        }
        if (!n)
            return back;
        back += n;
    }
}

/* The default slide mode, on a tangled input, when the best iterate still
 * has inverted tets: the boundary and interface vertices of those tets, of the
 * tets inverted in the input and of the tets around them, as an nv mask (NULL
 * if none). Where the tangle
 * reaches the boundary, sliding on the input surface may not undo it
 * (torus_h0.1_tangled: 15 tets left inverted; lsq: none); opt_run then runs
 * again with these vertices free. */
qdc_status opt_stuck_boundary(const ctx_t *c, uint8_t **out)
{
    const mesh_topo *tp = c->tp;
    uint8_t *core = qdc_calloc((size_t)c->nv + 1, 1), *mask = NULL;
    int32_t n = 0;

    *out = NULL;
    if (!core)
        return QDC_ENOMEM;
    for (int32_t t = 0; t < tp->nt; t++) {
        const int32_t *tt = tp->tets + 4 * (size_t)t;
        if (geom_tet_bad(c->xbest, tt) || geom_tet_bad(c->x0, tt))
            for (int a = 0; a < 4; a++)
                core[tt[a]] = 1;
    }
    mask = qdc_calloc((size_t)c->nv + 1, 1);
    if (!mask) {
        qdc_free(core);
        return QDC_ENOMEM;
    }
    for (int32_t t = 0; t < tp->nt; t++) {
        const int32_t *tt = tp->tets + 4 * (size_t)t;
        if (!(core[tt[0]] | core[tt[1]] | core[tt[2]] | core[tt[3]]))
            continue;
        for (int a = 0; a < 4; a++)
            if ((tp->vflag[tt[a]] & (MESH_V_BOUNDARY | MESH_V_INTERFACE)) &&
                !mask[tt[a]]) {
                mask[tt[a]] = 1;
                n++;
            }
    }
    qdc_free(core);
    if (!n) {
        qdc_free(mask);
        mask = NULL;
    }
    *out = mask;
    return QDC_OK;
}
