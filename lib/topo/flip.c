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
    tet_sort3(f0, f1, f2, c->key);
    finish_cand(tm, c, qsum);
    return 1;
}

/* A face of the sandwich: its tets on a's side and on b's, and its corners in
 * the order that makes (x, y, z, b) positive. */
typedef struct {
    int32_t ta, tb;
    int32_t v[3];
} sface;

/* The boundary of the disk of faces s[0..n) as a ring of vertices such that
 * (a, b, ring[k], ring[k+1]) is positive: the directed edges of the faces that
 * appear once, chained. Returns its length, or 0 when the boundary is not one
 * simple cycle of n + 2 vertices (a vertex inside the disk, a pinch). */
static int disk_ring(const sface *s, int n, int32_t *ring)
{
    int32_t from[3 * 2 * FLIP_MAXRING], to[3 * 2 * FLIP_MAXRING];
    int ne = 0, len = 0;

    for (int i = 0; i < n; i++)
        for (int e = 0; e < 3; e++) {
            int32_t x = s[i].v[e], y = s[i].v[(e + 1) % 3];
            int inner = 0;
            for (int j = 0; j < n && !inner; j++)
                for (int g = 0; g < 3; g++)
                    if (j != i && s[j].v[g] == y && s[j].v[(g + 1) % 3] == x)
                        inner = 1;
            if (!inner) {
                from[ne] = x;
                to[ne] = y;
                ne++;
            }
        }
    if (ne != n + 2 || ne > FLIP_MAXRING)
        return 0;
    ring[0] = from[0];
    for (len = 1; len < ne; len++) {
        int k = -1;
        for (int e = 0; e < ne; e++)
            if (from[e] == ring[len - 1])
                k = k < 0 ? e : -2;
        if (k < 0)
            return 0;
        ring[len] = to[k];
        for (int j = 0; j < len; j++)
            if (ring[j] == ring[len])
                return 0;
    }
    /* the chain must close: the last vertex leads back to the first */
    for (int e = 0; e < ne; e++)
        if (from[e] == ring[ne - 1])
            return to[e] == ring[0] ? ne : 0;
    return 0;
}

/* The sandwich face on a's tet ta opposite a, or 0 when the tet across that
 * face is not b's or the face is not free to go. */
static int sandwich(const tmesh *tm, int32_t ta, int32_t a, int32_t b, int32_t tag,
                    sface *out)
{
    int la = tmesh_local(tm, ta, a);
    int32_t nb = la < 0 ? -1 : tm->adj[4 * (size_t)ta + la];

    if (nb < 0 || tm->fcons[ta] >> la & 1 || tm->tag[ta] != tag || tm->q[ta] < -1.0)
        return 0;
    if (tm->tv[nb] != b || tm->tag[nb / 4] != tag || tm->q[nb / 4] < -1.0)
        return 0;
    out->ta = ta;
    out->tb = nb / 4;
    for (int s = 0; s < 3; s++)
        out->v[s] = tm->tv[4 * (size_t)ta + tet_face_of[la][s]];
    return 1;
}

/* 1 when edge (x, y) of tet t is constrained. */
static int edge_constrained(const tmesh *tm, int32_t t, int32_t x, int32_t y)
{
    int lx = tmesh_local(tm, t, x), ly = tmesh_local(tm, t, y);

    for (int e = 0; e < 6; e++)
        if ((tmesh_edge[e][0] == lx && tmesh_edge[e][1] == ly) ||
            (tmesh_edge[e][0] == ly && tmesh_edge[e][1] == lx))
            return tm->econs[t] >> e & 1;
    return 1;
}

/* The smallest quality of the ring's tets around ab (below -1 if one is not
 * allowed), and their sum. */
static double ring_quality(const tmesh *tm, int32_t a, int32_t b, const int32_t *ring,
                           int n, double floor4, double *sum)
{
    double m = INFINITY;

    *sum = 0.0;
    for (int k = 0; k < n; k++) {
        int32_t v[4] = {a, b, ring[k], ring[(k + 1) % n]};
        double q = tmesh_quality(tm, v, floor4);
        if (q < -1.0)
            return q;
        *sum += q;
        if (q < m)
            m = q;
    }
    return m;
}

int flip_multiface_eval(const tmesh *tm, int32_t t, int f, int maxring, double floor4,
                        double margin, flip_cand *c)
{
    sface s[FLIP_MAXRING], best_s[FLIP_MAXRING];
    int32_t a = tm->tv[4 * (size_t)t + f], b, ring[FLIP_MAXRING], tag = tm->tag[t];
    int n = 1, best_n = 0, best_len = 0;
    double best_q = -INFINITY, best_sum = 0.0;
    int32_t best_ring[FLIP_MAXRING];

    if (maxring > FLIP_MAXRING)
        maxring = FLIP_MAXRING;
    if (tm->adj[4 * (size_t)t + f] < 0)
        return 0;
    b = tm->tv[tm->adj[4 * (size_t)t + f]];
    if (!sandwich(tm, t, a, b, tag, &s[0]))
        return 0;
    /* grow: each step adds the neighbouring face that makes the disk's worst
     * new tet best; stop when no step beats the best disk so far */
    while (n + 3 <= maxring) {
        sface cand, pick;
        double pick_q = -INFINITY, pick_sum = 0.0;
        int32_t pick_ring[FLIP_MAXRING];
        int pick_len = 0, have = 0;
        for (int i = 0; i < n; i++)
            for (int e = 0; e < 3; e++) {
                int32_t x = s[i].v[e], y = s[i].v[(e + 1) % 3], z = s[i].v[(e + 2) % 3];
                int32_t na = tm->adj[4 * (size_t)s[i].ta + tmesh_local(tm, s[i].ta, z)];
                int32_t nbb = tm->adj[4 * (size_t)s[i].tb + tmesh_local(tm, s[i].tb, z)];
                int dup = 0, len;
                double q, sum;
                if (na < 0 || nbb < 0 || edge_constrained(tm, s[i].ta, x, y))
                    continue;
                if (!sandwich(tm, na / 4, a, b, tag, &cand) || cand.tb != nbb / 4)
                    continue; /* the ring of (x, y) is not (z, a, w, b) */
                for (int j = 0; j < n; j++)
                    dup |= s[j].ta == cand.ta;
                if (dup)
                    continue;
                s[n] = cand;
                len = disk_ring(s, n + 1, ring);
                if (!len)
                    continue;
                q = ring_quality(tm, a, b, ring, len, floor4, &sum);
                if (!have || q > pick_q || (q == pick_q && sum > pick_sum)) {
                    pick = cand;
                    pick_q = q;
                    pick_sum = sum;
                    pick_len = len;
                    memcpy(pick_ring, ring, sizeof ring);
                    have = 1;
                }
            }
        if (!have || (best_n && !(pick_q > best_q)))
            break;
        s[n++] = pick;
        if (pick_q >= -1.0 && (!best_n || pick_q > best_q)) {
            best_q = pick_q;
            best_sum = pick_sum;
            best_n = n;
            best_len = pick_len;
            memcpy(best_s, s, sizeof s);
            memcpy(best_ring, pick_ring, sizeof best_ring);
        }
    }
    if (!best_n)
        return 0;
    c->kind = FLIP_MULTIFACE;
    c->nold = 2 * best_n;
    for (int i = 0; i < best_n; i++) {
        c->old[2 * i] = best_s[i].ta;
        c->old[2 * i + 1] = best_s[i].tb;
    }
    c->qmin_old = cavity_min(tm, c->old, c->nold);
    if (!(best_q > c->qmin_old + margin))
        return 0;
    c->qmin_new = best_q;
    c->nnew = best_len;
    for (int k = 0; k < best_len; k++) {
        c->newt[k][0] = a;
        c->newt[k][1] = b;
        c->newt[k][2] = best_ring[k];
        c->newt[k][3] = best_ring[(k + 1) % best_len];
    }
    tet_sort3(s[0].v[0], s[0].v[1], s[0].v[2], c->key);
    finish_cand(tm, c, best_sum);
    return 1;
}
