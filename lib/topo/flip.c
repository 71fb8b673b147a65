/* flip.c - edge removal (Klincsek's dynamic programming over the edge's ring)
 * and the 2-3 face flip, evaluated on a tmesh without changing it. */
#include "topo/flip.h"

#include "core/tet.h"
#include "geom/bderr_int.h"
#include "geom/vec3.h"

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

/* Klincsek's dynamic programming over the polygon ring[0..n) (n >= 3) seen from
 * the edge ab, (a, b, ring[x], ring[x+1]) positive: the triangulation whose
 * worst tet is best, each triangle (x, z, y) making (ring x, z, y, b) and
 * (ring x, y, z, a); every new tet above qneed. Fills c->newt, c->nnew,
 * c->qmin_new and *qsum; 0 when there is none. */
static int ring_dp(const tmesh *tm, int32_t a, int32_t b, const int32_t *ring, int n,
                   double qneed, double floor4, flip_cand *c, double *qsum)
{
    /* best[x][y]: the best triangulation of ring[x..y]: its worst quality, its
     * sum, its apex (-1: none valid); x + 1 == y is an edge of the polygon */
    double bmin[FLIP_MAXRING + 1][FLIP_MAXRING + 1],
        bsum[FLIP_MAXRING + 1][FLIP_MAXRING + 1];
    int8_t bk[FLIP_MAXRING + 1][FLIP_MAXRING + 1];
    int stk[FLIP_MAXRING + 1][2], ns = 0;

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
                q1 = tmesh_quality_above(tm, up, floor4, qneed);
                if (q1 < -1.0 || !(q1 > qneed))
                    continue;
                q2 = tmesh_quality_above(tm, dn, floor4, qneed);
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
    *qsum = bsum[0][n - 1];
    return 1;
}

/* The other two local vertices of tet t than i and j, ordered so that
 * (v[i], v[j], v[k], v[l]) is positive. */
static void edge_ring_start(const int32_t *tt, int i, int j, int32_t *r0, int32_t *r1)
{
    int k = -1, l = -1;

    for (int s = 0; s < 4; s++)
        if (s != i && s != j) {
            if (k < 0)
                k = s;
            else
                l = s;
        }
    if (even_perm(i, j, k, l)) {
        *r0 = tt[k];
        *r1 = tt[l];
    } else {
        *r0 = tt[l];
        *r1 = tt[k];
    }
}

/* The candidate of an edge ab's removal completed: its key and totals. */
static void edge_done(const tmesh *tm, flip_cand *c, int32_t a, int32_t b, double qsum)
{
    c->key[0] = a < b ? a : b;
    c->key[1] = a < b ? b : a;
    c->key[2] = -1;
    finish_cand(tm, c, qsum);
}

int flip_edge_eval(const tmesh *tm, int32_t t, int e, int maxring, double floor4,
                   double margin, flip_cand *c)
{
    const int32_t *tt = tm->tv + 4 * (size_t)t;
    int i = tmesh_edge[e][0], j = tmesh_edge[e][1], n = 1;
    int32_t a, b, ring[FLIP_MAXRING + 1], cur = t, prev, pc;
    double qsum = 0.0;

    if (maxring > FLIP_MAXRING)
        maxring = FLIP_MAXRING;
    if (tm->econs[t] >> e & 1 || tm->q[t] < -1.0)
        return 0;
    a = tt[i];
    b = tt[j];
    /* (a, b, ring[x], ring[x+1]) are the ring's tets, positive */
    edge_ring_start(tt, i, j, &ring[0], &ring[1]);
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
    c->dev = 0.0;
    c->qmin_old = cavity_min(tm, c->old, n);
    if (!ring_dp(tm, a, b, ring, n, c->qmin_old + margin, floor4, c, &qsum))
        return 0;
    edge_done(tm, c, a, b, qsum);
    return 1;
}

/* The distance from p to the triangle (a, b, c). */
static double point_tri(const double *p, const double *a, const double *b,
                        const double *c)
{
    double cp[3];

    return bderr_point_triangle(p, a, b, c, cp);
}

/* The surface moved from the boundary triangles (a, b, c) and (b, a, d) to
 * (c, d, a) and (d, c, b), the four faces of the tet abcd: a bound on the
 * Hausdorff distance, or -1 when not allowed: the smaller of two. Below, the
 * slab of a convex quad. Else: the distance to a triangle is
 * convex, so over a triangle with two corners on another it is largest at the
 * third: a point of acd is within min(|d, abc|, |c, abd|) of the old surface,
 * and so on for each of the four. Not allowed: the triangles' normals more
 * than the feature angle apart (acos cos_feature) and, when convex is set, a
 * quad acbd that is not convex seen along ab x cd (a flip needs one; peeling
 * does not). */
static double quad_dev(const tmesh *tm, int32_t a, int32_t b, int32_t c, int32_t d,
                       double cos_feature, int convex)
{
    const double *pa = tm->xyz + 3 * (size_t)a, *pb = tm->xyz + 3 * (size_t)b;
    const double *pc = tm->xyz + 3 * (size_t)c, *pd = tm->xyz + 3 * (size_t)d;
    double ab[3], cd[3], ac[3], ad[3], ca[3], cb[3], n[3], w[3], n1[3], n2[3], ba[3],
        bd[3], s1, s2, s3, s4, l1, l2, hn, ho, slab;

    vec3_sub(pb, pa, ab);
    vec3_sub(pd, pc, cd);
    vec3_sub(pc, pa, ac);
    vec3_sub(pd, pa, ad);
    vec3_sub(pa, pc, ca);
    vec3_sub(pb, pc, cb);
    /* ab and cd crossing seen along n = ab x cd (a convex quad): each surface
     * is a graph over the quad along n, so each point of one is within the
     * slab width |ac . n| / |n| = 6V / |ab x cd| of the other */
    vec3_cross(ab, cd, n);
    vec3_cross(ab, ac, w);
    s1 = vec3_dot(w, n);
    vec3_cross(ab, ad, w);
    s2 = vec3_dot(w, n);
    vec3_cross(cd, ca, w);
    s3 = vec3_dot(w, n);
    vec3_cross(cd, cb, w);
    s4 = vec3_dot(w, n);
    slab = s1 * s2 < 0.0 && s3 * s4 < 0.0 && vec3_dot(n, n) > 0.0
               ? fabs(vec3_dot(ac, n)) / sqrt(vec3_dot(n, n))
               : INFINITY;
    if (convex && slab == INFINITY)
        return -1.0;
    vec3_sub(pa, pb, ba);
    vec3_sub(pd, pb, bd);
    vec3_cross(ab, ac, n1);
    vec3_cross(ba, bd, n2);
    l1 = sqrt(vec3_dot(n1, n1));
    l2 = sqrt(vec3_dot(n2, n2));
    if (!(l1 > 0.0 && l2 > 0.0) || vec3_dot(n1, n2) < cos_feature * l1 * l2)
        return -1.0;
    /* new to old (acd and bcd alike), old to new (abc and abd alike) */
    hn = fmin(point_tri(pd, pa, pb, pc), point_tri(pc, pa, pb, pd));
    ho = fmin(point_tri(pb, pa, pc, pd), point_tri(pa, pb, pc, pd));
    return fmin(slab, fmax(hn, ho));
}

/* 1 when the boundary faces fa (of ta) and fb (of tb) carry the same ref and
 * orientation rule, with *dev their larger deviation so far. */
static int same_surface(const tmesh *tm, int32_t ta, int fa, int32_t tb, int fb,
                        double *dev)
{
    int32_t sa = 4 * ta + fa, sb = 4 * tb + fb;

    if (!tm->fref || tm->fref[sa] != tm->fref[sb] ||
        (tm->fsurf[ta] >> (4 + fa) & 1) != (tm->fsurf[tb] >> (4 + fb) & 1))
        return 0;
    *dev = fmax(tm->fdev[sa], tm->fdev[sb]);
    return 1;
}

/* 1 when vertex d is in the star of vertex c, which tet t0 is in: an edge cd
 * exists (or the star is too large, or not one piece through its faces, to
 * tell: a pinched vertex, whose other piece may hold d). A search over the
 * tets around c through the faces that contain c. */
static int edge_exists(const tmesh *tm, int32_t t0, int32_t c, int32_t d)
{
    int32_t star[256];
    int n = tmesh_star(tm, t0, c, star, 256);

    if (n < 0 || (tm->vdeg && n != tm->vdeg[c]))
        return 1;
    for (int k = 0; k < n; k++)
        if (tmesh_local(tm, star[k], d) >= 0)
            return 1;
    return 0;
}

int flip_bedge_eval(const tmesh *tm, int32_t t, int e, int maxring, double floor4,
                    double margin, const flip_bound *bd, flip_cand *c)
{
    const int32_t *tt = tm->tv + 4 * (size_t)t;
    int i = tmesh_edge[e][0], j = tmesh_edge[e][1], n;
    int32_t a = tt[i], b = tt[j], ring[FLIP_MAXRING + 1], x0, x1, cur = t, first, tag;
    double qsum = 0.0, dev0, w;

    if (maxring > FLIP_MAXRING)
        maxring = FLIP_MAXRING;
    if (!(tm->econs[t] >> e & 1) || tm->q[t] < -1.0 || !tm->fref || !(bd->hausd > 0))
        return 0;
    tag = tm->tag[t];
    edge_ring_start(tt, i, j, &x0, &x1);
    /* back to the fan's first tet, whose face (a, b, x0) is on the boundary */
    for (n = 1;; n++) {
        int l = tmesh_local(tm, cur, x1);
        int32_t nb = tm->adj[4 * (size_t)cur + l], u, wv = -1;
        const int32_t *tu;
        if (nb < 0)
            break;
        u = nb / 4;
        if (u == t || n >= maxring || tm->fcons[cur] >> l & 1 || tm->tag[u] != tag ||
            tm->q[u] < -1.0)
            return 0; /* a closed ring (interior edge), too long, an interface */
        tu = tm->tv + 4 * (size_t)u;
        for (int s = 0; s < 4; s++)
            if (tu[s] != a && tu[s] != b && tu[s] != x0)
                wv = tu[s];
        x1 = x0;
        x0 = wv;
        cur = u;
    }
    first = cur;
    ring[0] = x0;
    ring[1] = x1;
    c->old[0] = cur;
    /* forward to the last, whose face (a, b, ring[n - 1]) is on the boundary */
    for (n = 1;; n++) {
        int l = tmesh_local(tm, cur, ring[n - 1]);
        int32_t nb = tm->adj[4 * (size_t)cur + l], u, pn = -1;
        const int32_t *tu;
        if (nb < 0)
            break;
        u = nb / 4;
        if (n >= maxring || tm->fcons[cur] >> l & 1 || tm->tag[u] != tag ||
            tm->q[u] < -1.0)
            return 0;
        tu = tm->tv + 4 * (size_t)u;
        for (int s = 0; s < 4; s++)
            if (tu[s] != a && tu[s] != b && tu[s] != ring[n])
                pn = tu[s];
        c->old[n] = u;
        ring[n + 1] = pn;
        cur = u;
    }
    /* n tets, n + 1 ring vertices; one tet is peeling (flip_peel_eval) */
    if (n < 2 || !same_surface(tm, first, tmesh_local(tm, first, ring[1]), cur,
                               tmesh_local(tm, cur, ring[n - 1]), &dev0))
        return 0;
    /* an edge cd elsewhere (across a thin wall) would be doubled, its faces
     * shared by three tets */
    if (edge_exists(tm, first, ring[0], ring[n]))
        return 0;
    w = quad_dev(tm, a, b, ring[0], ring[n], bd->cos_feature, 1);
    if (w < 0.0 || w + dev0 > bd->hausd)
        return 0;
    c->kind = FLIP_BEDGE;
    c->nold = n;
    c->dev = w;
    c->qmin_old = cavity_min(tm, c->old, n);
    if (!ring_dp(tm, a, b, ring, n + 1, c->qmin_old + margin, floor4, c, &qsum))
        return 0;
    edge_done(tm, c, a, b, qsum);
    return 1;
}

int flip_peel_eval(const tmesh *tm, int32_t t, double margin, const flip_bound *bd,
                   flip_cand *c)
{
    const int32_t *tt = tm->tv + 4 * (size_t)t;
    int fb[4], nfb = 0, fi[4], nfi = 0;
    double dev0, w, qn = INFINITY;

    if (!tm->fref || !(bd->hausd > 0) || tm->q[t] < -1.0)
        return 0;
    for (int f = 0; f < 4; f++) {
        int32_t nb = tm->adj[4 * (size_t)t + f];
        if (nb < 0)
            fb[nfb++] = f;
        else if (tm->fcons[t] >> f & 1 || tm->q[nb / 4] < -1.0)
            return 0; /* an interface: the other region's tets would be exposed */
        else
            fi[nfi++] = f;
    }
    if (nfb != 2 || !same_surface(tm, t, fb[0], t, fb[1], &dev0))
        return 0;
    /* the boundary faces are (a, b, d) and (a, b, c), opposite c = tt[fb[0]] and
     * d = tt[fb[1]]; (a, b) in the order that makes (a, b, c, d) positive */
    {
        int i = fi[0], j = fi[1];
        int32_t a = tt[i], b = tt[j], c0, d0;
        /* cd on the boundary already would be left with four boundary faces */
        for (int e = 0; e < 6; e++)
            if (((tmesh_edge[e][0] == fb[0] && tmesh_edge[e][1] == fb[1]) ||
                 (tmesh_edge[e][0] == fb[1] && tmesh_edge[e][1] == fb[0])) &&
                (tm->econs[t] >> e & 1))
                return 0;
        edge_ring_start(tt, i, j, &c0, &d0);
        w = quad_dev(tm, a, b, c0, d0, bd->cos_feature, 0);
    }
    if (w < 0.0 || w + dev0 > bd->hausd)
        return 0;
    for (int k = 0; k < nfi; k++) {
        double q = tm->q[tm->adj[4 * (size_t)t + fi[k]] / 4];
        if (q < qn)
            qn = q;
    }
    c->kind = FLIP_PEEL;
    c->nold = 1;
    c->old[0] = t;
    c->nnew = 0;
    c->dev = w;
    c->qmin_old = tm->q[t];
    /* the tets across the two faces that become boundary are unchanged: the
     * cavity's new minimum is theirs */
    c->qmin_new = qn;
    if (!(qn > c->qmin_old + margin))
        return 0;
    tet_sort3(tt[fb[0]], tt[fb[1]], tt[fi[0]] < tt[fi[1]] ? tt[fi[0]] : tt[fi[1]],
              c->key);
    finish_cand(tm, c, 0.0);
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
    c->dev = 0.0;
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
            double q = tmesh_quality_above(tm, nt[s], floor4, qneed);
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
 * allowed), and their sum; with have, a value below beat as soon as one tet is
 * (the ring cannot be picked then, whatever its sum). */
static double ring_quality(const tmesh *tm, int32_t a, int32_t b, const int32_t *ring,
                           int n, double floor4, int have, double beat, double *sum)
{
    double m = INFINITY;

    *sum = 0.0;
    for (int k = 0; k < n; k++) {
        int32_t v[4] = {a, b, ring[k], ring[(k + 1) % n]};
        double q = have && beat > 0.0 ? tmesh_quality_above(tm, v, floor4, beat)
                                      : tmesh_quality(tm, v, floor4);
        if (q < -1.0)
            return q;
        if (have && q < beat)
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
                q = ring_quality(tm, a, b, ring, len, floor4, have, pick_q, &sum);
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
    c->dev = 0.0;
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
