/* flip.c - edge removal (Klincsek's dynamic programming over the edge's ring)
 * and the 2-3 face flip, evaluated on a tmesh without changing it. */
#include "topo/flip.h"

#include "core/tet.h"

#include <math.h>
#include <string.h>

/* Cavity totals of the candidate: old minimum and sum, new sum, gain. */
static void finish_cand(const tmesh *tm, flip_cand *c, double qsum_new)
{
    double sold = 0.0;

    for (int o = 0; o < c->nold; o++)
        sold += tm->q[c->old[o]];
    c->gain = (double)(c->nold - c->nnew) + qsum_new - sold;
}

static double cavity_min(const tmesh *tm, const int32_t *old, int nold)
{
    double m = INFINITY;

    for (int o = 0; o < nold; o++)
        if (tm->q[old[o]] < m)
            m = tm->q[old[o]];
    return m;
}

/* 1 if the permutation (i, j, k, l) of 0..3 is even. */
static int even_perm(int i, int j, int k, int l)
{
    int p[4] = {i, j, k, l}, inv = 0;

    for (int x = 0; x < 4; x++)
        for (int y = x + 1; y < 4; y++)
            inv += p[x] > p[y];
    return !(inv & 1);
}

int flip_edge_eval(const tmesh *tm, int32_t t, int e, int maxring, double floor4,
                   double margin, flip_cand *c)
{
    const int32_t *tt = tm->tv + 4 * (size_t)t;
    int i = tmesh_edge[e][0], j = tmesh_edge[e][1], k = -1, l = -1, n = 1;
    int32_t a, b, ring[FLIP_MAXRING + 1], cur = t, prev, pc;
    /* best[x][y]: the best triangulation of ring[x..y]: its worst quality, its
     * sum, its apex (-1: none valid); x + 1 == y is an edge of the polygon */
    double bmin[FLIP_MAXRING][FLIP_MAXRING], bsum[FLIP_MAXRING][FLIP_MAXRING];
    int8_t bk[FLIP_MAXRING][FLIP_MAXRING];
    int stk[FLIP_MAXRING][2], ns = 0;
    double qneed, qsum = 0.0;

    if (maxring > FLIP_MAXRING)
        maxring = FLIP_MAXRING;
    if (tm->econs[t] >> e & 1 || tm->q[t] < -1.0)
        return 0;
    for (int s = 0; s < 4; s++)
        if (s != i && s != j) {
            if (k < 0)
                k = s;
            else
                l = s;
        }
    a = tt[i];
    b = tt[j];
    /* (a, b, ring[x], ring[x+1]) are the ring's tets, positive */
    if (even_perm(i, j, k, l)) {
        ring[0] = tt[k];
        ring[1] = tt[l];
    } else {
        ring[0] = tt[l];
        ring[1] = tt[k];
    }
    c->old[0] = t;
    prev = ring[0];
    pc = ring[1];
    for (;;) {
        int32_t nb = tm->adj[4 * (size_t)cur + tmesh_local(tm, cur, prev)], u, pn = -1;
        const int32_t *tu;
        if (nb < 0)
            return 0;
        u = nb / 4;
        if (u == t)
            break;
        if (n >= maxring || tm->tag[u] != tm->tag[t] || tm->q[u] < -1.0)
            return 0;
        tu = tm->tv + 4 * (size_t)u;
        for (int s = 0; s < 4; s++)
            if (tu[s] != a && tu[s] != b && tu[s] != pc)
                pn = tu[s];
        c->old[n] = u;
        ring[n + 1] = pn;
        n++;
        prev = pc;
        pc = pn;
        cur = u;
    }
    if (n < 3 || ring[n] != ring[0])
        return 0;
    c->kind = FLIP_EDGE;
    c->nold = n;
    c->qmin_old = cavity_min(tm, c->old, n);
    qneed = c->qmin_old + margin;
    for (int x = 0; x + 1 < n; x++) {
        bmin[x][x + 1] = INFINITY;
        bsum[x][x + 1] = 0.0;
        bk[x][x + 1] = 0;
    }
    for (int len = 2; len < n; len++)
        for (int x = 0; x + len < n; x++) {
            int y = x + len;
            bk[x][y] = -1;
            bmin[x][y] = -INFINITY;
            bsum[x][y] = -INFINITY;
            for (int z = x + 1; z < y; z++) {
                int32_t up[4] = {ring[x], ring[z], ring[y], b};
                int32_t dn[4] = {ring[x], ring[y], ring[z], a};
                double q1, q2, m, s;
                if (bk[x][z] < 0 || bk[z][y] < 0)
                    continue;
                q1 = tmesh_quality(tm, up, floor4);
                if (q1 < -1.0 || !(q1 > qneed))
                    continue;
                q2 = tmesh_quality(tm, dn, floor4);
                if (q2 < -1.0 || !(q2 > qneed))
                    continue;
                m = fmin(fmin(q1, q2), fmin(bmin[x][z], bmin[z][y]));
                s = q1 + q2 + bsum[x][z] + bsum[z][y];
                if (m > bmin[x][y] || (m == bmin[x][y] && s > bsum[x][y])) {
                    bmin[x][y] = m;
                    bsum[x][y] = s;
                    bk[x][y] = (int8_t)z;
                }
            }
        }
    if (bk[0][n - 1] < 0)
        return 0;
    c->qmin_new = bmin[0][n - 1];
    c->nnew = 0;
    stk[ns][0] = 0;
    stk[ns][1] = n - 1;
    ns++;
    while (ns > 0) {
        int x = stk[ns - 1][0], y = stk[ns - 1][1], z;
        ns--;
        if (y - x < 2)
            continue;
        z = bk[x][y];
        int32_t *up = c->newt[c->nnew++], *dn = c->newt[c->nnew++];
        up[0] = ring[x];
        up[1] = ring[z];
        up[2] = ring[y];
        up[3] = b;
        dn[0] = ring[x];
        dn[1] = ring[y];
        dn[2] = ring[z];
        dn[3] = a;
        stk[ns][0] = x;
        stk[ns][1] = z;
        ns++;
        stk[ns][0] = z;
        stk[ns][1] = y;
        ns++;
    }
    qsum = bsum[0][n - 1];
    c->key[0] = a < b ? a : b;
    c->key[1] = a < b ? b : a;
    c->key[2] = -1;
    finish_cand(tm, c, qsum);
    return 1;
}

int flip_23_eval(const tmesh *tm, int32_t t, int f, double floor4, double margin,
                 flip_cand *c)
{
    const int32_t *tt = tm->tv + 4 * (size_t)t;
    int32_t nb = tm->adj[4 * (size_t)t + f], u, d, e, f0, f1, f2;
    double qsum = 0.0, qneed;

    if (nb < 0 || tm->fcons[t] >> f & 1)
        return 0;
    u = nb / 4;
    if (tm->tag[u] != tm->tag[t] || tm->q[t] < -1.0 || tm->q[u] < -1.0)
        return 0;
    d = tt[f];
    e = tm->tv[4 * (size_t)u + nb % 4];
    f0 = tt[tet_face_of[f][0]];
    f1 = tt[tet_face_of[f][1]];
    f2 = tt[tet_face_of[f][2]];
    c->kind = FLIP_23;
    c->nold = 2;
    c->old[0] = t;
    c->old[1] = u;
    c->qmin_old = cavity_min(tm, c->old, 2);
    qneed = c->qmin_old + margin;
    /* (f0, f2, f1, d) is t itself; each new tet trades one face corner for e */
    {
        int32_t nt[3][4] = {{e, f2, f1, d}, {f0, e, f1, d}, {f0, f2, e, d}};
        c->qmin_new = INFINITY;
        for (int s = 0; s < 3; s++) {
            double q = tmesh_quality(tm, nt[s], floor4);
            if (q < -1.0 || !(q > qneed))
                return 0;
            qsum += q;
            if (q < c->qmin_new)
                c->qmin_new = q;
            memcpy(c->newt[s], nt[s], sizeof nt[s]);
        }
    }
    c->nnew = 3;
    c->key[0] = f0;
    c->key[1] = f1;
    c->key[2] = f2;
    tmesh_sort3(c->key);
    finish_cand(tm, c, qsum);
    return 1;
}
