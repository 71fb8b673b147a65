/* angle.c - the angle polish: max-min of dihedral sines one vertex at a
 * time, and joint moves of the worst tets' corners (docs/method.md §5a). */
#include "opt/angle.h"
#include "core/tet.h"
#include "geom/metric_int.h"
#include "opt/select.h"
#include "opt/star.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* ---- worst-angle polish: max-min of dihedral sines (Freitag's non-smooth
 * smoothing, as in Stellar) ---- */

#define DIH_ACTIVE 1e-3 /* functions within this of the minimum are active */
#define DIH_MAXACT 8
#define DIH_INNER 10
/* A move may lower the star's smallest mean ratio (down to the floor) where
 * the star holds one of the mesh's worst angles, its smallest sine within 10%
 * of the mesh's: measured on the 21 dev meshes and the 100k corpus (28 runs),
 * the smallest dihedral +0.95 degrees on average (up to +4.5), the mean ratio
 * -0.0005; elsewhere the star's smallest mean ratio may not drop (relaxed
 * everywhere: the same angles, -0.0006). */
#define DIH_RELAX 1.1
/* a sweep lifts the tets below min(1% quantile, 1.25 x the smallest sine):
 * raising the floor step by step costs the neighbours little (measured on the
 * good dev meshes: -0.0006 mean against -0.002 when every star of the worst
 * 1% goes to its own optimum, same smallest angle) */
#define LEVEL_MULT 1.25
/* ... but at least up to sin 3 degrees: from a near-zero floor, steps of 1.25x
 * never get anywhere (measured on bone-lowq at 100k tets: 6e-5 degrees became
 * 1.3e-3 with this floor, 6e-5 without) */
#define DIH_LEVEL_MIN 0.0523

typedef struct {
    int32_t k; /* position in v's star (vt_idx) */
    int e;     /* edge 0..5 */
} dih_fn;

/* Function (k, e) of value f into the active list act[0..*n) (values av[],
 * sorted, at most cap: a larger value than the last of a full list stays out). */
static void act_insert(dih_fn *act, double *av, int *n, int cap, double f, int32_t k,
                       int e)
{
    int i;

    if (*n == cap && f >= av[*n - 1])
        return;
    i = *n < cap ? (*n)++ : *n - 1;
    while (i > 0 && av[i - 1] > f) {
        av[i] = av[i - 1];
        act[i] = act[i - 1];
        i--;
    }
    av[i] = f;
    act[i].k = k;
    act[i].e = e;
}

/* Corners of star tet k of v with v placed at y; returns v's corner index. */
static int star_tet(const mesh_topo *tp, const double *x, int32_t k, const double *y,
                    double p[4][3])
{
    int32_t t = tp->vt_idx[k] >> 2;
    int a = tp->vt_idx[k] & 3;

    for (int b = 0; b < 4; b++)
        memcpy(p[b], b == a ? y : x + 3 * (size_t)tp->tets[4 * (size_t)t + b],
               sizeof p[b]);
    return a;
}

/* The dihedral sines s[] of star tet k of v with v placed at y, their
 * smallest (returned) and the tet's mean ratio cubed (*q3). */
static double star_tet_sines(const mesh_topo *tp, const double *x, int32_t k,
                             const double *y, double s[6], double *q3)
{
    double p[4][3], tmin = INFINITY;

    star_tet(tp, x, k, y, p);
    *q3 = metric_dihedral_sines_eta3(p[0], p[1], p[2], p[3], s);
    for (int e = 0; e < 6; e++)
        tmin = fmin(tmin, s[e]);
    return tmin;
}

/* Tets of a star whose sines are kept between the reads of a vertex's ascent
 * (a larger star's are computed again where they are needed). */
#define STAR_KEEP 96

/* Smallest dihedral sine of v's star with v at y, the tets under level
 * (*nbelow) and the cube of the smallest mean ratio (*qmin); the sines of the
 * first STAR_KEEP tets into keep[] if not NULL. */
static double star_scan(const mesh_topo *tp, const double *x, int32_t v, const double *y,
                        double level, double (*keep)[6], int *nbelow, double *qmin)
{
    double smin = INFINITY, q = INFINITY;
    int32_t k0 = tp->vt_ptr[v], n_star = tp->vt_ptr[v + 1] - k0;
    int below = 0;

    for (int32_t i = 0; i < n_star; i++) {
        double st[6], q3,
            tmin = star_tet_sines(tp, x, k0 + i, y, keep && i < STAR_KEEP ? keep[i] : st,
                                  &q3);
        q = fmin(q, q3);
        smin = fmin(smin, tmin);
        below += tmin < level;
    }
    *nbelow = below;
    *qmin = q;
    return smin;
}

/* The active functions of v's star at y (at most DIH_MAXACT, the smallest)
 * into act, their count returned: smin its smallest sine, keep[] the sines
 * star_scan kept. */
static int star_active(const mesh_topo *tp, const double *x, int32_t v, const double *y,
                       double (*keep)[6], double smin, dih_fn *act)
{
    double av[DIH_MAXACT];
    int32_t k0 = tp->vt_ptr[v], n_star = tp->vt_ptr[v + 1] - k0;
    int n = 0;

    for (int32_t i = 0; i < n_star; i++) {
        double st[6], q3, *s = i < STAR_KEEP ? keep[i] : st;
        if (i >= STAR_KEEP)
            (void)star_tet_sines(tp, x, k0 + i, y, st, &q3);
        for (int e = 0; e < 6; e++)
            if (s[e] <= smin + DIH_ACTIVE)
                act_insert(act, av, &n, DIH_MAXACT, s[e], k0 + i, e);
    }
    return n;
}

/* A trial position y of v, tested against move_ok's rules on the way:
 * 1 with star_scan's figures in *f1, *nb1, *q1 when its smallest sine stays
 * above fneed, no more than nbmax tets fall under level and its smallest mean
 * ratio cubed is at least qneed (and the sines in keep[] as star_scan keeps
 * them, if not NULL); 0 at the first tet that breaks one. Each of
 * the three only gets worse as the star is read, so the answer is the one
 * star_scan's whole figures would give: most trials fail, and early (on the
 * 20k-tet part-cad of scripts/corpus.py, --topology full, 6.6% of the run's
 * instructions saved; reading the active functions' tets first saved none). */
static int star_trial(const mesh_topo *tp, const double *x, int32_t v, const double *y,
                      double level, double fneed, int nbmax, double qneed,
                      double (*keep)[6], double *f1, int *nb1, double *q1)
{
    double smin = INFINITY, q = INFINITY;
    int32_t k0 = tp->vt_ptr[v];
    int below = 0;

    for (int32_t k = k0; k < tp->vt_ptr[v + 1]; k++) {
        double st[6], q3,
            tmin = star_tet_sines(tp, x, k, y,
                                  keep && k - k0 < STAR_KEEP ? keep[k - k0] : st, &q3);
        q = fmin(q, q3);
        smin = fmin(smin, tmin);
        below += tmin < level;
        if (!(smin > fneed) || below > nbmax || !(q >= qneed))
            return 0;
    }
    *f1 = smin;
    *nb1 = below;
    *q1 = q;
    return 1;
}

/* Gradient of one dihedral sine with respect to v's position (central
 * differences; h in x's units). */
static void sine_grad(const mesh_topo *tp, const double *x, const double *y, dih_fn f,
                      double h, double g[3])
{
    for (int c = 0; c < 3; c++) {
        double yp[3], p[4][3], sp[6], sm[6];
        memcpy(yp, y, sizeof yp);
        yp[c] = y[c] + h;
        star_tet(tp, x, f.k, yp, p);
        metric_dihedral_sines(p[0], p[1], p[2], p[3], sp);
        yp[c] = y[c] - h;
        star_tet(tp, x, f.k, yp, p);
        metric_dihedral_sines(p[0], p[1], p[2], p[3], sm);
        g[c] = (sp[f.e] - sm[f.e]) / (2.0 * h);
    }
}

/* The cubed floor of a move's star: the mean ratio floor qfloor cubed, and
 * never a degenerate tet (core/tet.h), even where no floor is set (a tangled
 * mesh): a sine can stay up while a tet flattens (a collapsing edge). */
static double floor_cubed(double qfloor)
{
    double q3 = qfloor * qfloor * qfloor;

    return q3 > GEOM_FLAT_ETA3 ? q3 : GEOM_FLAT_ETA3;
}

/* The rules of an angle move from a star at (f0 smallest sine, nb0 tets
 * under the level, q0 smallest mean ratio cubed) to (f1, nb1, q1): the
 * smallest sine rises, no more tets under the level (a stricter rule, no tet
 * of the set getting worse, stalls: sphere_h0.1_good 13.1 against 16.0
 * degrees), no tet under the floor, and the star's smallest mean ratio does
 * not drop unless the star's smallest sine is under relax. 1 if v at y
 * passes, with the star's figures there in *f1, *nb1, *q1; the smallest sine
 * must also rise above fneed (>= f0); keep: as star_trial's. */
static int move_ok(const mesh_topo *tp, const double *x, int32_t v, const double *y,
                   double level, double fneed, double f0, int nb0, double q0,
                   double relax, double qf3, double (*keep)[6], double *f1, int *nb1,
                   double *q1)
{
    return star_trial(tp, x, v, y, level, fneed, nb0, f0 < relax ? qf3 : fmax(q0, qf3),
                      keep, f1, nb1, q1);
}

/* Pattern moves (pattern_move): PATTERN_RAND hashed directions besides the
 * axes (measured on bone-scan, scripts/corpus.py at 100k tets, with stars
 * deep under 3 degrees and free to lower their smallest mean ratio: 8 such
 * directions lifted its smallest angle to 0.21 degrees, 2 to 0.18, none
 * 0.12; the run 1.02, 0.95 and 0.89 s) */
#define PATTERN_RAND 2
/* ... for the stars whose smallest sine is within PATTERN_BAND of the mesh's
 * (and deep): all deep stars gave the same smallest angles on the thin bones
 * at twice the time of the run (bone-scan, 100k tets: 1.9 against 0.9 s).
 * Deep was first under 3 degrees: on the 5M-tet ball (scripts/corpus.py),
 * whose worst angles sit near 3 degrees, that ended at 2.38 against 2.78
 * degrees and 46 s against 39 s (docs/method.md, section 5a) */
#define PATTERN_BAND 2.0
static uint64_t mix64(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static void pattern_dir(int32_t v, int it, int k, double d[3])
{
    if (k < 6) {
        d[0] = d[1] = d[2] = 0.0;
        d[k >> 1] = (k & 1) ? -1.0 : 1.0;
        return;
    }
    uint64_t z = mix64(((uint64_t)(uint32_t)v << 16) ^ ((uint64_t)it << 8) ^ (uint64_t)k);
    for (int c = 0; c < 3; c++) /* 21 bits each, in [-0.5, 0.5] */
        d[c] = (double)((z >> (21 * c)) & 0x1fffff) / 0x1fffff - 0.5;
}

/* Pattern moves of a deep star's vertex, tried where the ascent stops: at
 * flat tets with four corners on a curved surface (a thin bone's Delaunay
 * shells, scripts/corpus.py) the active sines balance each other (no ascent
 * direction) while a longer move still lifts them all. Directions: the 3
 * axes both ways and PATTERN_RAND more from a hash of the vertex and the
 * ascent step (runs repeat); steps 0.2, 0.05, 0.0125 mean edge, the largest
 * that lifts the star first, the best direction of it. f0, nb0, q0: the
 * star at v's position, as the ascent found it (star_scan). 1 if v moved. */
static int pattern_move(const mesh_topo *tp, const slide_ctx *sl, double *x, int32_t v,
                        int sliding, double lbar, double target, double relax, double qf3,
                        int it, double f0, int nb0, double q0)
{
    double *xv = x + 3 * (size_t)v, best[3], fb = f0;
    int found = 0;

    for (double sc = 0.2 * lbar; sc > 0.01 * lbar && !found; sc *= 0.25)
        for (int k = 0; k < 6 + PATTERN_RAND; k++) {
            double d[3], y[3], q1, f1, dn;
            int nb1;
            pattern_dir(v, it, k, d);
            dn = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (!(dn > 0.0))
                continue;
            star_trial_point(sliding ? sl : NULL, v, xv, d, sc / dn, y);
            if (move_ok(tp, x, v, y, target, fb, f0, nb0, q0, relax, qf3, NULL, &f1, &nb1,
                        &q1)) {
                fb = f1;
                memcpy(best, y, sizeof best);
                found = 1;
            }
        }
    if (found)
        memcpy(xv, best, sizeof best);
    return found;
}

/* Max-min ascent of one vertex: raise the smallest dihedral sine of its star
 * under move_ok's rules; where the ascent stops, a star whose smallest
 * sine is under pattern tries pattern moves. */
static int32_t dihedral_vertex(const mesh_topo *tp, const slide_ctx *sl, double *x,
                               int32_t v, double lbar, double qfloor, double target,
                               double relax, double pattern)
{
    int sliding = sl && slide_kind(sl, v) != SLIDE_INTERIOR;
    double *xv = x + 3 * (size_t)v, s = 0.02 * lbar, h = 1e-6 * lbar;
    const double qf3 = floor_cubed(qfloor); /* star_scan gives cubes */
    /* the star's sines at v's position, and at the trial position; after a
     * move by the ascent, the trial's are the star's (read once) */
    double keep[2][STAR_KEEP][6], (*cur)[6] = keep[0], (*tried)[6] = keep[1], fc = 0.0,
                                  qc = 0.0;
    int32_t moves = 0;
    int nbc = 0, known = 0;

    for (int it = 0; it < DIH_INNER; it++) {
        dih_fn act[DIH_MAXACT];
        double g[DIH_MAXACT][3], d[3], dn, y[3], q0 = qc, q1, f0 = fc, f1, (*t)[6];
        int nact = 0, ok = 0, nb0 = nbc, nb1;
        if (!known)
            f0 = star_scan(tp, x, v, xv, target, cur, &nb0, &q0);
        if (!(f0 > 0.0) || f0 >= target ||
            (nact = star_active(tp, x, v, xv, cur, f0, act)) == 0)
            break; /* inverted stars are the smooth pass's job */
        for (int i = 0; i < nact; i++) {
            sine_grad(tp, x, xv, act[i], h, g[i]);
            if (sliding) {
                double gt[3];
                slide_tangent(sl, v, g[i], gt);
                memcpy(g[i], gt, sizeof gt);
            }
        }
        if (star_min_norm_point(g, nact, d)) {
            dn = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (int hv = 0; hv < FINISH_HALVINGS; hv++) {
                star_trial_point(sliding ? sl : NULL, v, xv, d, s / dn, y);
                if (move_ok(tp, x, v, y, target, f0, f0, nb0, q0, relax, qf3, tried, &f1,
                            &nb1, &q1)) {
                    ok = 1;
                    break;
                }
                s *= 0.5;
            }
        }
        if (!ok) {
            if (f0 < pattern && pattern_move(tp, sl, x, v, sliding, lbar, target, relax,
                                             qf3, it, f0, nb0, q0)) {
                moves++;
                s = 0.02 * lbar;
                known = 0;
                continue;
            }
            break;
        }
        memcpy(xv, y, sizeof y);
        t = cur;
        cur = tried;
        tried = t;
        known = 1;
        fc = f1;
        nbc = nb1;
        qc = q1;
        moves++;
        s = fmin(s * 1.6, 0.1 * lbar);
        if (f1 - f0 < 1e-5)
            break;
    }
    return moves;
}

/* The smallest dihedral sine of tet t at x. */
static double tet_min_sine(const mesh_topo *tp, const double *x, int32_t t)
{
    const int32_t *tt = tp->tets + 4 * (size_t)t;
    double s[6], m = INFINITY;

    metric_dihedral_sines(x + 3 * (size_t)tt[0], x + 3 * (size_t)tt[1],
                          x + 3 * (size_t)tt[2], x + 3 * (size_t)tt[3], s);
    for (int e = 0; e < 6; e++)
        m = fmin(m, s[e]);
    return m;
}

static void fresh_sines(const mesh_topo *tp, const double *x, double *smin)
{
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < tp->nt; t++)
        smin[t] = tet_min_sine(tp, x, t);
}

/* Smallest dihedral sine of every tet into smin[] (if fresh; else smin[] is
 * up to date); *mean: the mean of the k smallest (the sweep's score), *kth:
 * the k-th smallest, *lo: the smallest. QDC_ENOMEM if out of memory. */
static qdc_status tet_sines(const mesh_topo *tp, const double *x, double *smin, int fresh,
                            int32_t k, double *kth, double *lo, double *mean)
{
    double low = INFINITY, hi = -INFINITY, sum = 0.0;
    qdc_status st;

    if (fresh)
        fresh_sines(tp, x, smin);
#pragma omp parallel for schedule(static) reduction(min : low) reduction(max : hi)
    for (int32_t t = 0; t < tp->nt; t++) {
        low = smin[t] < low ? smin[t] : low;
        hi = smin[t] > hi ? smin[t] : hi;
    }
    *lo = low;
    st = select_kth(smin, tp->nt, k - 1, low, hi, kth, &sum);
    *mean = sum / k;
    return st;
}

/* Each vertex's smallest sine among the tets at or under thresh, 2.0 if none. */
static void dihedral_vworst(const mesh_topo *tp, const double *smin, double thresh,
                            double *vworst)
{
    for (int32_t v = 0; v < tp->nv; v++)
        vworst[v] = 2.0;
    for (int32_t t = 0; t < tp->nt; t++)
        if (smin[t] <= thresh)
            for (int a = 0; a < 4; a++) {
                int32_t v = tp->tets[4 * (size_t)t + a];
                vworst[v] = fmin(vworst[v], smin[t]);
            }
}

/* Only the stars of the moved vertices (list[i].q == -INFINITY) changed:
 * their tets' smallest sines into smin. */
static void moved_sines(const mesh_topo *tp, const double *x, const vq_pair *list,
                        int32_t n, double *smin)
{
    for (int32_t i = 0; i < n; i++) {
        int32_t v = list[i].v;
        if (list[i].q != -INFINITY)
            continue;
        for (int32_t kk = tp->vt_ptr[v]; kk < tp->vt_ptr[v + 1]; kk++)
            smin[tp->vt_idx[kk] >> 2] = tet_min_sine(tp, x, tp->vt_idx[kk] >> 2);
    }
}

qdc_status finish_dihedral_sweep(const mesh_topo *tp, const uint8_t *movable,
                                 const slide_ctx *sl, double *x, double lbar, double frac,
                                 double qfloor, double *smin, int smin_valid,
                                 finish_stats *st)
{
    double *vworst = qdc_mallocn((size_t)tp->nv, sizeof(double));
    int32_t *start = NULL, n = 0, k, ncol;
    vq_pair *list = NULL;
    double thresh, dummy, pattern;
    qdc_status st_ = QDC_ENOMEM;

    memset(st, 0, sizeof *st);
    if (!vworst)
        goto out;
    k = (int32_t)(frac * tp->nt);
    k = k < 1 ? 1 : (k > tp->nt ? tp->nt : k);
    if (tet_sines(tp, x, smin, !smin_valid, k, &thresh, &st->floor_before,
                  &st->score_before) != QDC_OK)
        goto out;
    if (st->floor_before > 0.0)
        thresh = fmin(thresh, fmax(LEVEL_MULT * st->floor_before, DIH_LEVEL_MIN));
    dihedral_vworst(tp, smin, thresh, vworst);
    ncol = select_vertices(tp, movable, vworst, &list, &n, &start);
    if (ncol < 0)
        goto out;
    /* pattern moves for the deep stars near the mesh's smallest sine
     * (PATTERN_BAND) */
    pattern = fmin(FINISH_DEEP_SINE, PATTERN_BAND * st->floor_before);
    /* a vertex stops once its star leaves the worst set (measured: moving it
     * further, to its own max-min optimum, costs the neighbours' mean ratio:
     * -0.005 against -0.002 mean on the good dev meshes, same smallest angle) */
    for (int32_t c = 0; c < ncol; c++) {
        int32_t moves = 0;
#pragma omp parallel for reduction(+ : moves) schedule(dynamic, 4) if (c < COLOUR_SHARED)
        for (int32_t i = start[c]; i < start[c + 1]; i++) {
            int32_t mv = dihedral_vertex(tp, sl, x, list[i].v, lbar, qfloor, thresh,
                                         DIH_RELAX * st->floor_before, pattern);
            list[i].q =
                mv > 0 ? -INFINITY : list[i].q; /* mark the moved (sines are >= -1) */
            moves += mv;
        }
        st->n_moves += moves;
    }
    st->n_verts = n;
    moved_sines(tp, x, list, n, smin);
    st_ = tet_sines(tp, x, smin, 0, k, &dummy, &st->floor_after, &st->score_after);
out:
    qdc_free(start);
    qdc_free(list);
    qdc_free(vworst);
    return st_;
}

/* ---- joint moves of the worst tets' corners ----
 * One vertex at a time, the max-min ascent stops where the smallest sines of
 * a few neighbouring tets balance each other (measured on a 1M-tet ball: the
 * three worst tets, around one short boundary edge, at 5.1-5.2 degrees after
 * the sweeps). Moving the corners of a worst tet together is the same ascent
 * in up to 12 dimensions over the union of their stars. */
#define PATCH_TETS SELECT_WORST_TETS /* the worst tets tried in a round */
#define PATCH_MAXT 384               /* tets of the corners' stars (larger: skipped) */
#define PATCH_ACT 16                 /* active functions */
#define PATCH_INNER 8                /* ascent steps per tet */
#define PATCH_HALVINGS 12

typedef struct {
    int eta; /* the functions: 0 the tets' dihedral sines, 1 their mean ratios cubed */
    int nv;  /* movable corners */
    int32_t v[4];
    double y[4][3]; /* their positions */
    int32_t nt;     /* tets of their stars */
    int32_t t[PATCH_MAXT];
} patch_t;

static void patch_tet(const mesh_topo *tp, const double *x, const patch_t *pc,
                      const double (*y)[3], int32_t t, double p[4][3])
{
    const int32_t *tt = tp->tets + 4 * (size_t)t;

    for (int b = 0; b < 4; b++) {
        const double *src = x + 3 * (size_t)tt[b];
        for (int j = 0; j < pc->nv; j++)
            if (tt[b] == pc->v[j])
                src = y[j];
        memcpy(p[b], src, sizeof p[b]);
    }
}

/* The functions of tet i of the patch with its corners at y into f[] (6
 * sines, or the mean ratio cubed once); returns how many, and its mean ratio
 * cubed in *q3. */
static int patch_fns(const mesh_topo *tp, const double *x, const patch_t *pc,
                     const double (*y)[3], int32_t i, double f[6], double *q3)
{
    double p[4][3];

    patch_tet(tp, x, pc, y, pc->t[i], p);
    *q3 = metric_dihedral_sines_eta3(p[0], p[1], p[2], p[3], f);
    if (!pc->eta)
        return 6;
    f[0] = *q3;
    return 1;
}

/* Smallest function value over the patch's tets with its corners at y; the
 * tets with a value below level (*nbelow) and the active functions (within
 * DIH_ACTIVE of the smallest, or 1% of it for mean ratios; k: position in
 * pc->t). The functions of tet i in fv[i]: computed, or known there already
 * (patch_trial_ok's, at the same y). */
static double patch_values(const mesh_topo *tp, const double *x, const patch_t *pc,
                           const double (*y)[3], double level, double (*fv)[6], int known,
                           int *nbelow, dih_fn *act, int *nact)
{
    double fmin_ = INFINITY, av[PATCH_ACT], tol;
    int below = 0, n = 0, nf = pc->eta ? 1 : 6;

    for (int32_t i = 0; i < pc->nt; i++) {
        double tmin = INFINITY, q3;
        if (!known)
            (void)patch_fns(tp, x, pc, y, i, fv[i], &q3);
        for (int e = 0; e < nf; e++)
            tmin = fmin(tmin, fv[i][e]);
        fmin_ = fmin(fmin_, tmin);
        below += tmin < level;
    }
    tol = pc->eta ? 0.01 * fabs(fmin_) : DIH_ACTIVE;
    /* the smallest PATCH_ACT active functions, sorted */
    for (int32_t i = 0; i < pc->nt; i++)
        for (int e = 0; e < nf; e++)
            if (fv[i][e] <= fmin_ + tol)
                act_insert(act, av, &n, PATCH_ACT, fv[i][e], i, e);
    *nact = n;
    *nbelow = below;
    return fmin_;
}

/* 1 if the patch with its corners at y keeps the ascent's rules: every tet's
 * smallest value above f0 (into *f1, the smallest), no more of them below level
 * than nb0, no mean ratio cubed under qcap. The active functions' tets are
 * tried first and the scan stops at the first tet that breaks a rule: most
 * trials fail there (a full scan per trial was most of the angle pass on 20k-tet
 * meshes). The second pass reads every tet: a trial that passes leaves the
 * functions of each tet in fv[] (patch_values'). */
static int patch_trial_ok(const mesh_topo *tp, const double *x, const patch_t *pc,
                          const double (*y)[3], double f0, int nb0, double qcap,
                          double level, const dih_fn *act, int nact, double (*fv)[6],
                          double *f1)
{
    double lo = INFINITY;
    int below = 0;

    for (int pass = 0; pass < 2; pass++)
        for (int32_t i = 0; i < (pass ? pc->nt : nact); i++) {
            int32_t k = pass ? i : act[i].k;
            double fo[6], *f = pass ? fv[k] : fo, q3, tmin = INFINITY;
            int nf, first = 1;
            for (int a = 0; a < i && !pass && first; a++)
                first = act[a].k != k;
            if (!first)
                continue; /* that tet was tried already */
            nf = patch_fns(tp, x, pc, y, k, f, &q3);
            for (int e = 0; e < nf; e++)
                tmin = fmin(tmin, f[e]);
            if (!(tmin > f0) || q3 < qcap)
                return 0;
            if (pass) {
                below += tmin < level;
                if (below > nb0)
                    return 0;
                lo = fmin(lo, tmin);
            }
        }
    *f1 = lo;
    return 1;
}

/* Euclidean projection of l[0..m) onto the unit simplex. */
static void simplex_project(double *l, int m)
{
    double u[PATCH_ACT], run = 0.0, theta = 0.0;

    memcpy(u, l, (size_t)m * sizeof *u);
    for (int i = 1; i < m; i++) /* descending */
        for (int j = i; j > 0 && u[j] > u[j - 1]; j--) {
            double t = u[j];
            u[j] = u[j - 1];
            u[j - 1] = t;
        }
    for (int i = 0; i < m; i++) {
        run += u[i];
        if (u[i] - (run - 1.0) / (i + 1) > 0.0)
            theta = (run - 1.0) / (i + 1);
    }
    for (int i = 0; i < m; i++)
        l[i] = fmax(l[i] - theta, 0.0);
}

/* An ascent direction d (dim entries) for min_i f_i from the gradients g[0..m):
 * the minimum-norm point of their convex hull, by projected gradient on the
 * simplex of weights (m <= 16: a few hundred cheap steps). 0 if no direction
 * raises every active function. */
static int patch_direction(double g[][12], int m, int dim, double d[12])
{
    double G[PATCH_ACT][PATCH_ACT], l[PATCH_ACT], L = 0.0, dd = 0.0;

    for (int i = 0; i < m; i++) {
        double row = 0.0;
        for (int j = 0; j < m; j++) {
            G[i][j] = 0.0;
            for (int c = 0; c < dim; c++)
                G[i][j] += g[i][c] * g[j][c];
            row += fabs(G[i][j]);
        }
        L = fmax(L, row);
        l[i] = 1.0 / m;
    }
    if (!(L > 0.0) || !isfinite(L))
        return 0;
    for (int it = 0; it < 100 && m > 1; it++) {
        double gl[PATCH_ACT], prev[PATCH_ACT], change = 0.0;
        memcpy(prev, l, (size_t)m * sizeof *l);
        for (int i = 0; i < m; i++) {
            gl[i] = 0.0;
            for (int j = 0; j < m; j++)
                gl[i] += G[i][j] * l[j];
        }
        for (int i = 0; i < m; i++)
            l[i] -= gl[i] / L;
        simplex_project(l, m);
        for (int i = 0; i < m; i++)
            change = fmax(change, fabs(l[i] - prev[i]));
        if (change < 1e-6) /* the weights have settled */
            break;
    }
    for (int c = 0; c < dim; c++) {
        d[c] = 0.0;
        for (int i = 0; i < m; i++)
            d[c] += l[i] * g[i][c];
        dd += d[c] * d[c];
    }
    if (!(dd > 0.0) || !isfinite(dd))
        return 0;
    for (int i = 0; i < m; i++) {
        double gd = 0.0;
        for (int c = 0; c < dim; c++)
            gd += g[i][c] * d[c];
        if (!(gd > 0.0))
            return 0;
    }
    return 1;
}

/* The patch of tet t: its movable corners and the tets of their stars; 0 if
 * none moves or the stars are too many. */
static int patch_of(const mesh_topo *tp, const uint8_t *movable, const double *x,
                    int32_t t, patch_t *pc)
{
    pc->nv = pc->nt = 0;
    for (int b = 0; b < 4; b++) {
        int32_t v = tp->tets[4 * (size_t)t + b];
        if (!movable[v])
            continue;
        pc->v[pc->nv] = v;
        memcpy(pc->y[pc->nv++], x + 3 * (size_t)v, 3 * sizeof(double));
        for (int32_t k = tp->vt_ptr[v]; k < tp->vt_ptr[v + 1]; k++) {
            int32_t s = tp->vt_idx[k] >> 2, dup = 0;
            for (int32_t i = 0; i < pc->nt && !dup; i++)
                dup = pc->t[i] == s;
            if (dup)
                continue;
            if (pc->nt == PATCH_MAXT)
                return 0;
            pc->t[pc->nt++] = s;
        }
    }
    return pc->nv > 0;
}

/* Max-min ascent of a patch's corners together (dihedral_vertex's rules over
 * the union of their stars; for mean ratios, without the floor); the moves are
 * written to x. */
static int32_t patch_ascent(const mesh_topo *tp, const slide_ctx *sl, double *x,
                            patch_t *pc, double lbar, double qfloor, double level)
{
    const double qf3 = floor_cubed(qfloor), h = 1e-6 * lbar;
    double s = 0.02 * lbar;
    int32_t moves = 0;
    int dim = 3 * pc->nv;

    /* the tets' functions at the corners' positions, and at a trial's: after a
     * move, the trial's are the patch's (read once) */
    double fvs[2][PATCH_MAXT][6], (*cur)[6] = fvs[0], (*tried)[6] = fvs[1], (*sw)[6];
    int known = 0;

    for (int it = 0; it < PATCH_INNER; it++) {
        dih_fn act[PATCH_ACT];
        double g[PATCH_ACT][12], d[12], dn = 0.0, y[4][3], f0, f1 = 0.0;
        int nact = 0, ok = 0, nb0;
        f0 = patch_values(tp, x, pc, (const double(*)[3])pc->y, level, cur, known, &nb0,
                          act, &nact);
        if (!(f0 > 0.0) || nact == 0)
            break;
        for (int i = 0; i < nact; i++) {
            int32_t t = pc->t[act[i].k];
            for (int j = 0; j < pc->nv; j++) {
                double *gj = g[i] + 3 * j;
                int in = 0;
                for (int b = 0; b < 4; b++)
                    in |= tp->tets[4 * (size_t)t + b] == pc->v[j];
                gj[0] = gj[1] = gj[2] = 0.0;
                if (!in)
                    continue;
                for (int c = 0; c < 3; c++) {
                    double yy[4][3], fp[6], fm[6], q3;
                    memcpy(yy, pc->y, sizeof yy);
                    yy[j][c] += h;
                    patch_fns(tp, x, pc, (const double(*)[3])yy, act[i].k, fp, &q3);
                    yy[j][c] -= 2.0 * h;
                    patch_fns(tp, x, pc, (const double(*)[3])yy, act[i].k, fm, &q3);
                    gj[c] = (fp[act[i].e] - fm[act[i].e]) / (2.0 * h);
                }
                if (sl && slide_kind(sl, pc->v[j]) != SLIDE_INTERIOR) {
                    double gt[3];
                    slide_tangent(sl, pc->v[j], gj, gt);
                    memcpy(gj, gt, sizeof gt);
                }
            }
        }
        if (!patch_direction(g, nact, dim, d))
            break;
        for (int c = 0; c < dim; c++)
            dn += d[c] * d[c];
        dn = sqrt(dn);
        for (int hv = 0; hv < PATCH_HALVINGS; hv++) {
            for (int j = 0; j < pc->nv; j++) {
                int sliding = sl && slide_kind(sl, pc->v[j]) != SLIDE_INTERIOR;
                star_trial_point(sliding ? sl : NULL, pc->v[j], pc->y[j], d + 3 * j,
                                 s / dn, y[j]);
            }
            if (patch_trial_ok(tp, x, pc, (const double(*)[3])y, f0, nb0,
                               pc->eta ? GEOM_FLAT_ETA3 : qf3, level, act, nact, tried,
                               &f1)) {
                ok = 1;
                break;
            }
            s *= 0.5;
        }
        if (!ok)
            break;
        memcpy(pc->y, y, sizeof y);
        sw = cur;
        cur = tried;
        tried = sw;
        known = 1;
        moves++;
        s = fmin(s * 1.6, 0.1 * lbar);
        if (f1 - f0 < (pc->eta ? 1e-5 * f0 : 1e-6))
            break;
    }
    for (int j = 0; moves && j < pc->nv; j++)
        memcpy(x + 3 * (size_t)pc->v[j], pc->y[j], 3 * sizeof(double));
    return moves;
}

static double mean_q(const vq_pair *p, int32_t n)
{
    double s = 0.0;

    for (int32_t i = 0; i < n; i++)
        s += p[i].q;
    return n > 0 ? s / n : 0.0;
}

/* The mean ratio of tet t at x, as the driver's scans compute it. */
static double tet_eta(const mesh_topo *tp, const double *x, int32_t t)
{
    const int32_t *tt = tp->tets + 4 * (size_t)t;
    metric_parts pt;

    metric_parts_for(OPT_METRIC_MIVL, x + 3 * (size_t)tt[0], x + 3 * (size_t)tt[1],
                     x + 3 * (size_t)tt[2], x + 3 * (size_t)tt[3], &pt);
    return metric_mean_ratio(&pt);
}

qdc_status finish_patches(const mesh_topo *tp, const uint8_t *movable,
                          const slide_ctx *sl, double *x, double lbar,
                          finish_patch_kind kind, double qfloor, double *val,
                          int val_valid, finish_stats *st)
{
    vq_pair worst[PATCH_TETS];
    patch_t *pc = qdc_malloc(sizeof *pc);
    int eta = kind == FINISH_PATCH_MEAN_RATIO;
    double level;
    int32_t n;

    memset(st, 0, sizeof *st);
    if (!pc)
        return QDC_ENOMEM;
    if (!val_valid && eta) {
#pragma omp parallel for schedule(static)
        for (int32_t t = 0; t < tp->nt; t++)
            val[t] = tet_eta(tp, x, t);
    } else if (!val_valid) {
        fresh_sines(tp, x, val);
    }
    n = select_worst_tets(val, tp->nt, worst);
    st->floor_before = n > 0 ? worst[0].q : INFINITY;
    st->score_before = mean_q(worst, n);
    level = n > 0 ? worst[n - 1].q : 0.0;
    if (eta) /* the ascent compares mean ratios cubed */
        level = level * level * level;
    /* worst first, one patch after the other (they share vertices); the
     * values of a moved patch's tets are brought up to date */
    for (int32_t i = 0; i < n; i++) {
        int32_t moves;
        if (!patch_of(tp, movable, x, worst[i].v, pc))
            continue;
        pc->eta = eta;
        st->n_verts += pc->nv;
        moves = patch_ascent(tp, sl, x, pc, lbar, qfloor, level);
        st->n_moves += moves;
        for (int32_t j = 0; moves && j < pc->nt; j++)
            val[pc->t[j]] =
                eta ? tet_eta(tp, x, pc->t[j]) : tet_min_sine(tp, x, pc->t[j]);
    }
    n = select_worst_tets(val, tp->nt, worst);
    st->floor_after = n > 0 ? worst[0].q : INFINITY;
    st->score_after = mean_q(worst, n);
    qdc_free(pc);
    return QDC_OK;
}
