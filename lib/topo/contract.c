/* contract.c - interior edge contraction: u's star re-pointed at w, checked by
 * the link condition and the exact predicate. */
#include "topo/contract.h"

#include <math.h>
#include <string.h>

enum { STAR_W = 96 };

/* 1 when v is among the n of a. */
static int has(const int32_t *a, int n, int32_t v)
{
    for (int i = 0; i < n; i++)
        if (a[i] == v)
            return 1;
    return 0;
}

/* Contract u onto w, t0 a tet of the edge: 1 with *c filled when legal and
 * improving. */
static int one_way(const tmesh *tm, int32_t t0, int32_t u, int32_t w, double floor4,
                   double margin, contract_cand *c)
{
    int32_t su[CONTRACT_MAX], sw[STAR_W], ring[2 * CONTRACT_MAX], vw[4 * STAR_W];
    int nu = tmesh_star(tm, t0, u, su, CONTRACT_MAX), nw, nr = 0, nvw = 0;
    double sold = 0.0, snew = 0.0;

    if (nu < 0)
        return 0;
    nw = tmesh_star(tm, t0, w, sw, STAR_W);
    if (nw < 0)
        return 0;
    c->qmin_old = INFINITY;
    for (int k = 0; k < nu; k++) {
        const int32_t *tt = tm->tv + 4 * (size_t)su[k];
        if (tm->q[su[k]] < -1.0 || tm->tag[su[k]] != tm->tag[t0])
            return 0;
        c->qmin_old = fmin(c->qmin_old, tm->q[su[k]]);
        sold += tm->q[su[k]];
        if (tmesh_local(tm, su[k], w) >= 0)
            for (int s = 0; s < 4; s++)
                if (tt[s] != u && tt[s] != w && !has(ring, nr, tt[s]))
                    ring[nr++] = tt[s];
    }
    for (int k = 0; k < nw; k++)
        for (int s = 0; s < 4; s++) {
            int32_t x = tm->tv[4 * (size_t)sw[k] + s];
            if (x != u && x != w && !has(vw, nvw, x))
                vw[nvw++] = x;
        }
    /* link condition, vertices: next to u and to w only through the ring */
    for (int k = 0; k < nu; k++)
        for (int s = 0; s < 4; s++) {
            int32_t x = tm->tv[4 * (size_t)su[k] + s];
            if (x != u && x != w && has(vw, nvw, x) && !has(ring, nr, x))
                return 0;
        }
    c->nold = 0;
    c->nnew = 0;
    c->qmin_new = INFINITY;
    for (int k = 0; k < nu; k++) {
        const int32_t *tt = tm->tv + 4 * (size_t)su[k];
        int32_t *nt;
        double q;
        c->old[c->nold++] = su[k];
        if (tmesh_local(tm, su[k], w) >= 0)
            continue; /* a tet of the edge: gone */
        /* link condition, edges: two ring vertices of this tet must be a ring
         * edge (then this tet meets a tet of the edge across their face) */
        for (int s = 0; s < 4; s++)
            for (int r = s + 1; r < 4; r++) {
                int ok = 0;
                if (!has(ring, nr, tt[s]) || !has(ring, nr, tt[r]))
                    continue;
                for (int j = 0; j < nu && !ok; j++)
                    ok = tmesh_local(tm, su[j], w) >= 0 &&
                         tmesh_local(tm, su[j], tt[s]) >= 0 &&
                         tmesh_local(tm, su[j], tt[r]) >= 0;
                if (!ok)
                    return 0;
            }
        nt = c->newt[c->nnew++];
        memcpy(nt, tt, 4 * sizeof *tt);
        nt[tmesh_local(tm, su[k], u)] = w;
        q = tmesh_quality(tm, nt, floor4);
        if (q < -1.0 || !(q > c->qmin_old + margin))
            return 0;
        c->qmin_new = fmin(c->qmin_new, q);
        snew += q;
    }
    if (c->nnew == 0)
        return 0;
    c->gone = u;
    c->keep = w;
    c->gain = (double)(c->nold - c->nnew) + snew - sold;
    return 1;
}

int contract_eval(const tmesh *tm, int32_t t, int e, double floor4, double margin,
                  contract_cand *c)
{
    const int32_t *tt = tm->tv + 4 * (size_t)t;
    int32_t a = tt[tmesh_edge[e][0]], b = tt[tmesh_edge[e][1]];
    contract_cand x;
    int have = 0;

    if (tm->vcons[a] || tm->vcons[b] || tm->q[t] < -1.0)
        return 0;
    for (int dir = 0; dir < 2; dir++) {
        int32_t u = dir ? b : a, w = dir ? a : b;
        if (!one_way(tm, t, u, w, floor4, margin, &x))
            continue;
        if (!have || x.qmin_new > c->qmin_new ||
            (x.qmin_new == c->qmin_new &&
             (x.gain > c->gain || (x.gain == c->gain && x.gone < c->gone)))) {
            *c = x;
            have = 1;
        }
    }
    return have;
}
