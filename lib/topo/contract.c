/* contract.c - interior edge contraction: u's star re-pointed at w, checked by
 * the link condition and the exact predicate. */
#include "topo/contract.h"

#include "core/tet.h"
#include "geom/bderr_int.h"

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

/* The stars of an edge's two ends (tmesh_star from a tet of the edge; n -1
 * when over STAR_W tets), found once for both directions of a contraction. */
typedef struct {
    int32_t s[2][STAR_W];
    int n[2];
} edge_stars;

static void find_stars(const tmesh *tm, int32_t t0, int32_t a, int32_t b, edge_stars *st)
{
    st->n[0] = tmesh_star(tm, t0, a, st->s[0], STAR_W);
    st->n[1] = tmesh_star(tm, t0, b, st->s[1], STAR_W);
}

/* The link condition of contracting u onto w (su, nu: u's star, on[k] set for
 * its tets of the edge; sw, nw: w's star; ring, nr: the vertices around the
 * edge): 1 when it holds. */
static int link_ok(const tmesh *tm, int32_t u, int32_t w, const int32_t *su, int nu,
                   const uint8_t *on, const int32_t *sw, int nw, const int32_t *ring,
                   int nr)
{
    int32_t vw[4 * STAR_W];
    int nvw = 0;

    /* edges: two ring vertices of a tet that stays must be a ring edge (then
     * that tet meets a tet of the edge across their face) */
    for (int k = 0; k < nu; k++) {
        const int32_t *tt = tm->tv + 4 * (size_t)su[k];
        if (on[k])
            continue;
        for (int s = 0; s < 4; s++)
            for (int r = s + 1; r < 4; r++) {
                int ok = 0;
                if (!has(ring, nr, tt[s]) || !has(ring, nr, tt[r]))
                    continue;
                for (int j = 0; j < nu && !ok; j++)
                    ok = on[j] && tmesh_local(tm, su[j], tt[s]) >= 0 &&
                         tmesh_local(tm, su[j], tt[r]) >= 0;
                if (!ok)
                    return 0;
            }
    }
    /* vertices: next to u and to w only through the ring */
    for (int k = 0; k < nw; k++)
        for (int s = 0; s < 4; s++) {
            int32_t x = tm->tv[4 * (size_t)sw[k] + s];
            if (x != u && x != w && !has(vw, nvw, x))
                vw[nvw++] = x;
        }
    for (int k = 0; k < nu; k++)
        for (int s = 0; s < 4; s++) {
            int32_t x = tm->tv[4 * (size_t)su[k] + s];
            if (x != u && x != w && has(vw, nvw, x) && !has(ring, nr, x))
                return 0;
        }
    return 1;
}

/* Contract u onto w, t0 a tet of the edge, su (nu tets) and sw (nw) their
 * stars: 1 with *c filled when legal and improving (qfloor: contract_eval's).
 * The new tets first (the cheaper refusals), then the link condition. */
static int one_way(const tmesh *tm, int32_t t0, int32_t u, int32_t w, const int32_t *su,
                   int nu, const int32_t *sw, int nw, double floor4, double margin,
                   double qfloor, contract_cand *c)
{
    int32_t ring[2 * CONTRACT_MAX];
    uint8_t on[CONTRACT_MAX]; /* su[k] is a tet of the edge: gone */
    int nr = 0, nnew;
    double sold = 0.0, snew = 0.0, need;

    if (nu < 0 || nu > CONTRACT_MAX || nw < 0)
        return 0;
    c->qmin_old = INFINITY;
    nnew = nu;
    for (int k = 0; k < nu; k++) {
        const int32_t *tt = tm->tv + 4 * (size_t)su[k];
        if (tm->q[su[k]] < -1.0 || tm->tag[su[k]] != tm->tag[t0])
            return 0;
        c->qmin_old = fmin(c->qmin_old, tm->q[su[k]]);
        sold += tm->q[su[k]];
        on[k] = tmesh_local(tm, su[k], w) >= 0;
        if (on[k]) {
            nnew--;
            for (int s = 0; s < 4; s++)
                if (tt[s] != u && tt[s] != w && !has(ring, nr, tt[s]))
                    ring[nr++] = tt[s];
        }
    }
    need = qfloor > 0.0 ? qfloor : c->qmin_old + margin;
    c->nold = 0;
    c->nnew = 0;
    c->qmin_new = INFINITY;
    for (int k = 0; k < nu; k++) {
        const int32_t *tt = tm->tv + 4 * (size_t)su[k];
        int32_t *nt;
        double q;
        c->old[c->nold++] = su[k];
        if (on[k])
            continue;
        /* by gain: out once the gain cannot be positive with every tet
         * left at mean ratio 1 (the same candidates, fewer evaluated) */
        if (qfloor > 0.0 && !((double)(nu - nnew) - sold + snew + (nnew - c->nnew) > 0.0))
            return 0;
        nt = c->newt[c->nnew++];
        memcpy(nt, tt, 4 * sizeof *tt);
        nt[tmesh_local(tm, su[k], u)] = w;
        /* (below the bound by more than roundings: refused before the exact
         * predicate) */
        q = tmesh_quality_above(tm, nt, floor4, need);
        if (q < -1.0 || !(q > need))
            return 0;
        c->qmin_new = fmin(c->qmin_new, q);
        snew += q;
    }
    c->gain = (double)(c->nold - c->nnew) + snew - sold;
    if (c->nnew == 0 || (qfloor > 0.0 && !(c->gain > 0.0)) ||
        !link_ok(tm, u, w, su, nu, on, sw, nw, ring, nr))
        return 0;
    c->gone = u;
    c->keep = w;
    c->bnd = 0;
    c->dev = 0.0;
    return 1;
}

/* x better than c: the larger new minimum, then gain, then the smaller vertex
 * going. */
static int better(const contract_cand *x, const contract_cand *c)
{
    if (x->qmin_new != c->qmin_new)
        return x->qmin_new > c->qmin_new;
    if (x->gain != c->gain)
        return x->gain > c->gain;
    return x->gone < c->gone;
}

int contract_eval(const tmesh *tm, int32_t t, int e, double floor4, double margin,
                  double qfloor, contract_cand *c)
{
    const int32_t *tt = tm->tv + 4 * (size_t)t;
    int32_t a = tt[tmesh_edge[e][0]], b = tt[tmesh_edge[e][1]];
    contract_cand x;
    edge_stars st;
    int have = 0;

    if (tm->vcons[a] || tm->vcons[b] || tm->q[t] < -1.0)
        return 0;
    find_stars(tm, t, a, b, &st);
    for (int dir = 0; dir < 2; dir++) {
        int32_t u = dir ? b : a, w = dir ? a : b;
        if (!one_way(tm, t, u, w, st.s[dir], st.n[dir], st.s[!dir], st.n[!dir], floor4,
                     margin, qfloor, &x))
            continue;
        if (!have || better(&x, c)) {
            *c = x;
            have = 1;
        }
    }
    return have;
}

/* The normal (not unit) of the triangle a, b, c. */
static void tri_normal(const tmesh *tm, int32_t a, int32_t b, int32_t c, double n[3])
{
    const double *pa = tm->xyz + 3 * (size_t)a, *pb = tm->xyz + 3 * (size_t)b,
                 *pc = tm->xyz + 3 * (size_t)c;
    double u[3], v[3];

    for (int d = 0; d < 3; d++) {
        u[d] = pb[d] - pa[d];
        v[d] = pc[d] - pa[d];
    }
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
}

/* 1 when the normals n and m are within the angle whose cosine is cf. */
static int within(const double n[3], const double m[3], double cf)
{
    double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2],
           mm = m[0] * m[0] + m[1] * m[1] + m[2] * m[2];

    return nn > 0.0 && mm > 0.0 &&
           n[0] * m[0] + n[1] * m[1] + n[2] * m[2] >= cf * sqrt(nn * mm);
}

/* 1 when x and w are joined by a constrained edge of a tet of ws (n tets). */
static int cons_edge(const tmesh *tm, const int32_t *ws, int n, int32_t w, int32_t x)
{
    for (int k = 0; k < n; k++) {
        int i = tmesh_local(tm, ws[k], w), j = tmesh_local(tm, ws[k], x);
        if (j < 0)
            continue;
        for (int e = 0; e < 6; e++)
            if (((tmesh_edge[e][0] == i && tmesh_edge[e][1] == j) ||
                 (tmesh_edge[e][0] == j && tmesh_edge[e][1] == i)) &&
                (tm->econs[ws[k]] >> e & 1))
                return 1;
    }
    return 0;
}

/* The surface checks of contracting boundary vertex u onto w (c's cavity
 * filled by one_way): *dev the move (contract.h), or -1 when not allowed. */
static double surface_move(const tmesh *tm, int32_t u, int32_t w, const contract_cand *c,
                           const flip_bound *bd)
{
    int32_t ws[STAR_W], apex[2] = {-1, -1}, vx[6 * CONTRACT_MAX];
    const double *pu = tm->xyz + 3 * (size_t)u, *pw = tm->xyz + 3 * (size_t)w;
    double dev = 0.0, dev0 = 0.0, cp[3];
    int nwf = 0, nvx = 0, nw;

    for (int k = 0; k < c->nold; k++) {
        int32_t t = c->old[k];
        const int32_t *tt = tm->tv + 4 * (size_t)t;
        for (int i = 0; i < 4; i++) {
            int32_t v[3] = {tt[tet_face_of[i][0]], tt[tet_face_of[i][1]],
                            tt[tet_face_of[i][2]]},
                    x = -1, y = -1;
            double n[3], m[3];
            int hasw = v[0] == w || v[1] == w || v[2] == w;
            if (tt[i] == u || !(tm->fcons[t] >> i & 1))
                continue;
            if (tm->adj[4 * (size_t)t + i] >= 0)
                return -1.0; /* an interface at u */
            tri_normal(tm, v[0], v[1], v[2], n);
            dev0 = fmax(dev0, tm->fdev[4 * (size_t)t + i]);
            for (int s = 0; s < 3; s++)
                if (v[s] != u && v[s] != w) {
                    if (x < 0)
                        x = v[s];
                    else
                        y = v[s];
                }
            if (hasw) {
                if (nwf == 2)
                    return -1.0;
                apex[nwf++] = x;
                continue;
            }
            vx[nvx++] = x;
            vx[nvx++] = y;
            for (int s = 0; s < 3; s++)
                if (v[s] == u)
                    v[s] = w;
            tri_normal(tm, v[0], v[1], v[2], m);
            if (!within(m, n, bd->cos_feature))
                return -1.0; /* a fold */
            dev = fmax(dev, bderr_point_triangle(pw, pu, tm->xyz + 3 * (size_t)x,
                                                 tm->xyz + 3 * (size_t)y, cp));
            dev = fmax(dev, bderr_point_triangle(pu, pw, tm->xyz + 3 * (size_t)x,
                                                 tm->xyz + 3 * (size_t)y, cp));
        }
    }
    if (nwf != 2 || dev + dev0 > bd->hausd)
        return -1.0;
    nw = tmesh_star(tm, c->old[0], w, ws, STAR_W);
    if (nw < 0 || (tm->vdeg && nw != tm->vdeg[w]))
        return -1.0; /* or a pinched star: its other piece may hold wx */
    for (int k = 0; k < nvx; k++)
        if (vx[k] != apex[0] && vx[k] != apex[1] && cons_edge(tm, ws, nw, w, vx[k]))
            return -1.0; /* the surface would be pinched along wx */
    return dev;
}

int contract_bedge_eval(const tmesh *tm, int32_t t, int e, double floor4, double margin,
                        const flip_bound *bd, contract_cand *c)
{
    const int32_t *tt = tm->tv + 4 * (size_t)t;
    int32_t a = tt[tmesh_edge[e][0]], b = tt[tmesh_edge[e][1]];
    contract_cand x;
    edge_stars st;
    int have = 0;

    if (!tm->fref || !(bd->hausd > 0) || !(tm->econs[t] >> e & 1) || !tm->vcons[a] ||
        !tm->vcons[b] || tm->q[t] < -1.0)
        return 0;
    find_stars(tm, t, a, b, &st);
    for (int dir = 0; dir < 2; dir++) {
        int32_t u = dir ? b : a, w = dir ? a : b;
        double dev;
        if (!one_way(tm, t, u, w, st.s[dir], st.n[dir], st.s[!dir], st.n[!dir], floor4,
                     margin, 0.0, &x))
            continue;
        dev = surface_move(tm, u, w, &x, bd);
        if (dev < 0.0)
            continue;
        x.bnd = 1;
        x.dev = dev;
        if (!have || better(&x, c)) {
            *c = x;
            have = 1;
        }
    }
    return have;
}
