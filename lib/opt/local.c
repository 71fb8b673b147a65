/* local.c - local repair of the tets the finishing pass left inverted
 * (docs/method.md §5a): the tets within a few vertex rings of them become a
 * mesh of their own, whose vertices on the cut to the rest of the mesh (and
 * the run's locked ones) are held where the run has them, and whose other
 * vertices start where the run has them; that small mesh is optimized
 * (untangled and smoothed, under the run's bound and then, with the default
 * bound, OPT_HAUSD_STUCK, the boundary corners of the inverted tets free to
 * leave their surface) by the run's repair hook and put back, kept by the
 * best-iterate rule. What a rerun of the whole mesh from the input did for a
 * handful of tets, for the cost of their neighbourhood; the angle polish
 * then runs on the whole mesh. */
#include "opt/local.h"

#include "core/tet.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Rings of each round; rounds run while tets stay inverted and the region
 * stays local: at most LOCAL_MAX_TETS tets or 2% of the mesh's. */
static const int local_rings[] = {3, 6, 12};
#define LOCAL_MAX_TETS 30000

/* The region of a round: lev[v] the ring of v around the tets unusable at x
 * (0 their corners, -1 beyond rings), region[t] the tets with a corner inside
 * the last ring, hold[v] their corners that are also corners of a tet outside
 * (the cut). The rings are a breadth-first walk over the vertices' tets from
 * the unusable tets' corners (a scan of every tet per ring was 15 passes over
 * the 4M-tet cube's tets for a region of a few thousand). Returns the number
 * of region tets, -1 if out of memory. */
static int32_t local_region(const mesh_topo *tp, const double *x, int rings, int8_t *lev,
                            uint8_t *region, uint8_t *hold)
{
    const int32_t *tets = tp->tets;
    int32_t *list = qdc_mallocn((size_t)tp->nv + 1, sizeof(int32_t));
    int32_t nl = 0, inner = 0, n = 0;

    if (!list)
        return -1;
    memset(lev, -1, (size_t)tp->nv);
    /* the unusable tets' corners, found in parallel and listed in vertex
     * order: each ring is a set, so the order of the list changes nothing
     * (the serial scan was 0.33 s of main-thread-only time over the local
     * rounds of a tangled 4M-tet run) */
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < tp->nt; t++)
        if (geom_tet_bad(x, tets + 4 * (size_t)t))
            for (int k = 0; k < 4; k++)
                __atomic_store_n(&lev[tets[4 * (size_t)t + k]], 0, __ATOMIC_RELAXED);
    for (int32_t v = 0; v < tp->nv; v++)
        if (lev[v] == 0)
            list[nl++] = v;
    /* list[inner, end) is ring `ring`: its neighbours not reached yet are the next */
    for (int ring = 0; ring < rings; ring++) {
        int32_t end = nl;
        for (int32_t i = inner; i < end; i++)
            for (int32_t k = tp->vt_ptr[list[i]]; k < tp->vt_ptr[list[i] + 1]; k++) {
                const int32_t *tt = tets + 4 * (size_t)(tp->vt_idx[k] >> 2);
                for (int a = 0; a < 4; a++)
                    if (lev[tt[a]] < 0) {
                        lev[tt[a]] = (int8_t)(ring + 1);
                        list[nl++] = tt[a];
                    }
            }
        inner = end;
    }
    memset(region, 0, (size_t)tp->nt);
    for (int32_t i = 0; i < inner; i++) /* the rings before the last */
        for (int32_t k = tp->vt_ptr[list[i]]; k < tp->vt_ptr[list[i] + 1]; k++) {
            int32_t t = tp->vt_idx[k] >> 2;
            n += !region[t];
            region[t] = 1;
        }
    /* a region corner on a tet outside is on the cut */
    memset(hold, 0, (size_t)tp->nv);
    for (int32_t i = 0; i < nl; i++)
        for (int32_t k = tp->vt_ptr[list[i]]; k < tp->vt_ptr[list[i] + 1]; k++)
            if (!region[tp->vt_idx[k] >> 2]) {
                hold[list[i]] = 1;
                break;
            }
    qdc_free(list);
    return n;
}

/* Whether v is a surface or interface vertex sliding on a planar patch or a
 * straight line. */
static int flat(const ctx_t *c, int32_t v)
{
    return (c->tp->vflag[v] & (MESH_V_BOUNDARY | MESH_V_INTERFACE)) && c->sl &&
           slide_flat(c->sl, v);
}

/* Whether v is a surface or interface vertex that the run's bound holds
 * (not one sliding on a planar patch or a straight line, which keeps the
 * shape wherever it goes). */
static int bounded(const ctx_t *c, int32_t v)
{
    return (c->tp->vflag[v] & (MESH_V_BOUNDARY | MESH_V_INTERFACE)) && !flat(c, v);
}

/* The region's mesh (normalized units): its vertices numbered in order
 * (map[v], -1 outside), all at xbest (a start of the free ones from the
 * input made regions of the tangled 4M-tet cube with hundreds of tets
 * inverted that no region run undid), held ones (the cut, locked, and with
 * hold_surface the bounded surface ones) fixed. NULL on allocation failure. */
static mesh_t *local_mesh(const ctx_t *c, const uint8_t *region, const uint8_t *hold,
                          const int8_t *lev, int hold_surface, int32_t nt, int32_t *map)
{
    const int32_t *tets = c->tp->tets;
    int32_t nv = 0, t2 = 0;
    mesh_t *s;

#pragma omp parallel for schedule(static)
    for (int32_t v = 0; v < c->nv; v++)
        map[v] = -1;
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < c->nt; t++)
        for (int k = 0; region[t] && k < 4; k++)
            __atomic_store_n(&map[tets[4 * (size_t)t + k]], 0, __ATOMIC_RELAXED);
    for (int32_t v = 0; v < c->nv; v++)
        map[v] = map[v] == 0 ? nv++ : -1;
    s = mesh_new(nv, nt, MESH_WITH_FIXED | (c->region ? MESH_WITH_REGION : 0));
    if (!s)
        return NULL;
    for (int32_t v = 0; v < c->nv; v++) {
        int32_t w = map[v];
        int held =
            w >= 0 && (hold[v] || c->locked[v] || (hold_surface && bounded(c, v)) ||
                       (c->hold_flat && lev[v] != 0 && flat(c, v)));
        if (w < 0)
            continue;
        memcpy(s->xyz + 3 * (size_t)w, c->xbest + 3 * (size_t)v, 3 * sizeof(double));
        s->fixed[w] = (uint8_t)held;
    }
    for (int32_t t = 0; t < c->nt; t++) {
        if (!region[t])
            continue;
        for (int k = 0; k < 4; k++)
            s->tets[4 * (size_t)t2 + k] = map[tets[4 * (size_t)t + k]];
        if (c->region)
            s->region[t2] = c->region[t];
        t2++;
    }
    return s;
}

/* The boundary corners of the unusable tets (lev 0) that the region moves
 * (not held): loose in the region's numbering (run_once's loose), so that
 * they may leave their surface within the round's bound. A face shared by two
 * tets whose three corners slide on one plane, with both apexes on the same
 * side of it (measured on the tangled cubes of scripts/corpus.py: one such
 * pair at 1M tets), leaves one of the two inverted wherever the corners
 * slide; lifting a corner off the plane by a little opens both. Returns how
 * many. */
static int32_t local_loose(const ctx_t *c, const int8_t *lev, const uint8_t *hold,
                           const int32_t *map, const mesh_t *s, uint8_t *loose)
{
    int32_t n = 0;

    for (int32_t v = 0; v < c->nv; v++) {
        int32_t w = map[v];
        if (w < 0 || lev[v] != 0 || hold[v] || s->fixed[w] ||
            !(c->tp->vflag[v] & (MESH_V_BOUNDARY | MESH_V_INTERFACE)))
            continue;
        /* a corner on an interface only, free of the bound: where the
         * input's interface is folded (a tangle pushed its vertices through
         * it), no place on it or near it opens the tets around (a 13k-tet
         * two-region box of scripts/corpus.py, seed 31, --tangle-frac 0.08:
         * 5 tets left inverted, whose interface corners the tangle had
         * moved 1.4-1.6 edges) */
        loose[w] =
            c->tp->vflag[v] & MESH_V_BOUNDARY ? SLIDE_LOOSE : SLIDE_LOOSE_UNBOUNDED;
        n++;
    }
    return n;
}

/* The region's free interior corners of the unusable tets (lev 0) moved to
 * the mean of their neighbours, by Jacobi sweeps (neighbours among them at
 * their last sweep's place): where a tangle pushed neighbouring vertices past
 * each other, the untangling from where they are ends in a local minimum (a
 * graded box of scripts/corpus.py, seed 47, --tangle-frac 0.12, with the
 * boundary fixed: 5 interior tets left inverted around two vertices pushed
 * 1.4 edges, through every ring and rerun), from their neighbours' mean it
 * does not. Returns how many moved; -1 if out of memory. */
static int32_t local_restart(const ctx_t *c, const int8_t *lev, const int32_t *map,
                             mesh_t *s)
{
    const mesh_topo *tp = c->tp;
    int32_t n = 0, *ids = qdc_mallocn((size_t)c->nv + 1, sizeof(int32_t));
    double *nx;

    if (!ids)
        return -1;
    for (int32_t v = 0; v < c->nv; v++)
        if (lev[v] == 0 && map[v] >= 0 && !s->fixed[map[v]] &&
            !(tp->vflag[v] & (MESH_V_BOUNDARY | MESH_V_INTERFACE)))
            ids[n++] = v;
    nx = qdc_mallocn(3 * (size_t)n + 1, sizeof(double));
    if (!nx) {
        qdc_free(ids);
        return -1;
    }
    for (int sweep = 0; sweep < 20 && n > 0; sweep++) {
        for (int32_t i = 0; i < n; i++) {
            int32_t v = ids[i], cnt = 0;
            double acc[3] = {0, 0, 0};
            for (int32_t k = tp->adj_ptr[v]; k < tp->adj_ptr[v + 1]; k++) {
                int32_t u = tp->adj_idx[k];
                if (u == v || map[u] < 0)
                    continue;
                for (int d = 0; d < 3; d++)
                    acc[d] += s->xyz[3 * (size_t)map[u] + d];
                cnt++;
            }
            for (int d = 0; d < 3; d++)
                nx[3 * (size_t)i + d] =
                    cnt ? acc[d] / cnt : s->xyz[3 * (size_t)map[v] + d];
        }
        for (int32_t i = 0; i < n; i++)
            memcpy(s->xyz + 3 * (size_t)map[ids[i]], nx + 3 * (size_t)i,
                   3 * sizeof(double));
    }
    qdc_free(nx);
    qdc_free(ids);
    return n;
}

/* The region's run: the run's options without progress records or log lines
 * (its figures are the region's), the bound in normalized units. A failed
 * region run (say, out of memory) leaves *ok 0 and the mesh as it was. */
static void local_run(const ctx_t *c, mesh_t *s, const uint8_t *loose, double bound,
                      int *ok)
{
    opt_options o = *c->o;
    opt_result r;
    qdc_error e;

    o.progress = NULL;
    o.progress_ctx = NULL;
    o.log = NULL;
    o.time_limit = ctx_time_left(o.time_limit, qdc_now() - c->t0); /* the run's rest */
    o.hausd = bound;
    o.hausd_rel = 0;
    memset(&e, 0, sizeof e);
    *ok = c->repair(s, &o, c->keep_surface, loose, &r, &e) == QDC_OK &&
          r.outcome != OPT_FAILED;
}

/* The farthest move so far (xbest from the input) of a bounded vertex the
 * region frees: the region's bound is what the run's bound has left. */
static double bound_used(const ctx_t *c, const int8_t *lev, const uint8_t *hold)
{
    double used = 0.0;

    for (size_t v = 0; v < (size_t)c->nv; v++)
        if (lev[v] >= 0 && !hold[v] && bounded(c, (int32_t)v)) {
            double d = 0;
            for (int k = 0; k < 3; k++)
                d += (c->xbest[3 * v + k] - c->x0[3 * v + k]) *
                     (c->xbest[3 * v + k] - c->x0[3 * v + k]);
            used = sqrt(d) > used ? sqrt(d) : used;
        }
    return used;
}

/* One round at `rings` with the bound `bound` (normalized units): the region
 * optimized and put into c->trial, recorded (phase "local") and considered. */
static qdc_status local_round(ctx_t *c, opt_result *res, opt_progress *r, int *next,
                              int rings, double bound, int free_corners, int restart,
                              int *big)
{
    size_t nv = (size_t)c->nv, n3 = 3 * nv;
    int8_t *lev = qdc_malloc(nv + 1);
    uint8_t *hold = qdc_malloc(nv + 1), *region = qdc_malloc((size_t)c->nt + 1);
    int32_t *map = qdc_mallocn(nv + 1, sizeof(int32_t)), nt, was = c->best.n_inverted;
    int32_t nloose = 0;
    uint8_t *loose = NULL;
    mesh_t *s = NULL;
    qdc_status st = QDC_ENOMEM;
    double used = 0.0;
    int ok = 0;

    if (!lev || !hold || !region || !map)
        goto out;
    nt = local_region(c->tp, c->xbest, rings, lev, region, hold);
    if (nt < 0)
        goto out;
    if (nt > LOCAL_MAX_TETS && nt > c->nt / 50) {
        st = QDC_OK; /* not local any more: the reruns' business */
        *big = 1;
        ctx_log(c, 0,
                "local repair: %d tets within %d rings of the %d inverted: not local",
                (int)nt, rings, (int)was);
        goto out;
    }
    used = bound_used(c, lev, hold);
    s = local_mesh(c, region, hold, lev, bound > 0 && used >= 0.9 * bound, nt, map);
    if (!s)
        goto out;
    if (restart && local_restart(c, lev, map, s) <= 0) {
        st = QDC_OK; /* none to restart, or out of memory: no round */
        goto out;
    }
    if (free_corners) {
        loose = qdc_calloc((size_t)s->nv + 1, 1);
        if (!loose)
            goto out;
        nloose = local_loose(c, lev, hold, map, s, loose);
    }
    st = QDC_OK;
    local_run(c, s, loose, bound > 0 && used < 0.9 * bound ? bound - used : bound, &ok);
    if (!ok) {
        ctx_log(c, 0, "local repair: %d tets within %d rings of the %d inverted: failed",
                (int)nt, rings, (int)was);
        goto out;
    }
    memcpy(c->trial, c->xbest, n3 * sizeof(double));
    for (size_t v = 0; v < nv; v++)
        if (map[v] >= 0 && !s->fixed[map[v]])
            memcpy(c->trial + 3 * v, s->xyz + 3 * (size_t)map[v], 3 * sizeof(double));
    ctx_pass_record(c, r, next, "local");
    r->step = 0;
    ctx_consider(c, c->x, r);
    if (c->best_it == r->iteration && bound * c->scale > res->hausd_bound)
        res->hausd_bound = bound * c->scale;
    ctx_log(c, 0,
            "local repair: %d tets within %d rings of the %d inverted, %d vertices "
            "(%d off their surface%s): %s",
            (int)nt, rings, (int)was, (int)s->nv, (int)nloose,
            restart ? ", their free corners from their neighbours' mean" : "",
            c->best_it == r->iteration ? "kept" : "not better");
    if (ctx_report(c, r))
        ctx_set_stop(res, OPT_STOP_CANCELLED);
out:
    mesh_free(s);
    qdc_free(loose);
    qdc_free(map);
    qdc_free(region);
    qdc_free(hold);
    qdc_free(lev);
    return st;
}

/* The rounds at `rings`: sliding within the run's bound, then with the bad
 * tets' boundary corners free to leave their surface within the bound (the
 * default's: OPT_HAUSD_STUCK). *big if the region is not local. */
static qdc_status local_rings_round(ctx_t *c, opt_result *res, opt_progress *r, int *next,
                                    int rings, int *big)
{
    double wide = c->autob && OPT_HAUSD_STUCK > c->hbound ? OPT_HAUSD_STUCK : c->hbound;
    qdc_status st = QDC_OK;

    if (c->best.n_inverted > 0 && !ctx_should_stop(c, res))
        st = local_round(c, res, r, next, rings, c->hbound, 0, 0, big);
    if (st == QDC_OK && wide > 0 && (c->sl || wide > c->hbound) && !*big &&
        c->best.n_inverted > 0 && !ctx_should_stop(c, res))
        st = local_round(c, res, r, next, rings, wide, c->sl != NULL, 0, big);
    return st;
}

qdc_status local_pass(ctx_t *c, opt_result *res, opt_progress *r, int *next)
{
    qdc_status st = QDC_OK;
    int big = 0;

    if (!c->repair)
        return QDC_OK;
    for (size_t i = 0; i < sizeof local_rings / sizeof local_rings[0] && !big; i++) {
        int32_t was = c->best.n_inverted;
        st = local_rings_round(c, res, r, next, local_rings[i], &big);
        /* no tet untangled at this ring count: the next, twice as wide, did
         * not untangle any either on the tangled meshes tried (a 13k-tet
         * two-region box of scripts/corpus.py, seed 31, --tangle-frac 0.08:
         * 42 rounds of up to the whole mesh, 5 tets left inverted all the
         * same); the reruns from the input take over */
        if (st == QDC_OK && !big && c->best.n_inverted > 0 && c->best.n_inverted >= was)
            break;
        /* too many tets at this ring count (at 4M tets of a cube of
         * scripts/corpus.py, 137k within 6 rings of 2 tets, where 3 rings
         * had 10k): the largest count between the last and this one that is
         * still local, before the reruns from the input */
        for (int k = local_rings[i] - 1, done = 0;
             st == QDC_OK && big && !done && i > 0 && k > local_rings[i - 1]; k--) {
            int over = 0;
            st = local_rings_round(c, res, r, next, k, &over);
            done = !over; /* the last round this pass makes (big stays set) */
        }
    }
    /* still inverted: once more at the first ring count, the free interior
     * corners of the inverted tets started from their neighbours' mean */
    if (st == QDC_OK && c->best.n_inverted > 0 && !ctx_should_stop(c, res)) {
        big = 0;
        st = local_round(c, res, r, next, local_rings[0], c->hbound, 0, 1, &big);
    }
    return st;
}
