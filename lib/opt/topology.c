/* topology.c - the rounds of --topology (run.h, opt_topology_rounds; opt_run of entry.c
 * calls them): for flips, the smoother (rerun.c) alternated with the flips of lib/topo
 * (edge removal, 2-3 flips, multi-face removal), after Stellar's schedule (Klingner and
 * Shewchuk 2007): smooth; then flips, worst tets first; then smooth again where the flips
 * opened room, a few rounds while the quality rises; for full, a round with edge
 * contraction and vertex insertion, then one with contraction by gain, each kept when
 * better (the first round splits the long interior edges, with --boundary fixed or
 * where many). With flips the vertex set never changes (point data stays valid);
 * boundary triangles and region tags come back as sets exactly as they went in, unless
 * the user gave --hausd (boundary flips and peeling within it); new tets are written in
 * the vertex order convention of the tets they replace. m's coordinates, tets, regions
 * and tet count are replaced by the result; res->tets_in/out and the topo_* counts
 * filled, res->before the input's record, res->after the result's. */
#include "opt/run.h"

#include "core/base_int.h"
#include "core/mesh.h"
#include "core/tet.h"
#include "geom/metric_int.h"
#include "opt/opt_int.h"
#include "opt/spend.h"
#include "topo/topo.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Rounds of flips, each followed by smoothing: Stellar stops after three rounds
 * without gain; here a round without a flip, or whose smoothing gains less than
 * TOPO_GAIN in mean ratio with no rise of the minimum, ends the run. Measured
 * on the 100k-tet bone-lowq of scripts/corpus.py (one thread): after rounds 1-4
 * mean ratio 0.7071, 0.7180, 0.7211, 0.7222 at 3.6, 4.8, 6.0, 7.1 CPU s (the
 * smoother alone: 0.5811 in 1.6 s); the fourth is not worth its second.
 * The third is worth keeping even when the second's flips were few: on the
 * 100k-tet meshes of scripts/corpus.py --seed 1 (flips), the third round took
 * the mean ratio / smallest dihedral from 0.8176 / 20.73 to 0.8207 / 20.73 on
 * ball-scan (second round's flips: 251 tets fewer, 0.3%), 0.8057 / 15.87 to
 * 0.8100 / 15.95 on ball-lowq (0.4%), 0.7266 to 0.7310 on bone-lowq (0.9%),
 * 0.9028 / 38.83 to 0.9031 / 39.16 on part-cad (0.06%): a stop on a small
 * second round would have cost each mesh either mean ratio or its angle. */
enum { TOPO_ROUNDS = 3 };
#define TOPO_GAIN 1e-3

/* Tets below this mean ratio are given flips (topo.h's qgoal; its default 0.6
 * is for a first pass). Between smoothing rounds the flips that raise the
 * cavity's minimum above 0.6 still lift the mean: on the 20k-tet meshes of
 * scripts/corpus.py --seed 1, --topology flips, mean ratio / smallest dihedral
 * / CPU s at 0.6 and 0.8: part-cad --boundary fixed 0.864 / 29.2 / 0.9 and
 * 0.885 / 29.7 / 1.2; part-cad 0.868 / 31.0 / 0.9 and 0.892 / 38.6 / 1.7;
 * ball-scan --boundary fixed 0.799 / 12.7 / 0.8 and 0.814 / 14.0 / 1.3;
 * bone-lowq 0.678 / 0.87 / 2.3 and 0.692 / 0.87 / 3.0. 1.0 gave ball-scan
 * the same as 0.8 in more time. */
#define TOPO_QGOAL 0.8

/* A flip must also leave the smallest dihedral angle of its tets at least
 * this (degrees) or at least what it was (topo.h's akeep): accepted on the
 * cavity's smallest mean ratio alone, flips lowered the smallest angle that
 * the smoothing had raised (ball-scan at 100k: 17.4 -> 14.2 degrees in the
 * third round). --topology flips on the 100k-tet meshes of scripts/corpus.py
 * --seed 1, mean ratio / smallest dihedral without and with 20: ball-scan
 * 0.8224 / 16.23 and 0.8207 / 20.73; ball-lowq 0.8124 / 10.82 and 0.8101 /
 * 15.95 (full: 0.8158 / 13.28 and 0.8132 / 17.54); bone-lowq 0.7295 / 0.13
 * and 0.7312 / 0.13; part-cad 0.9037 / 39.22 both. 30 took ball-scan to
 * 0.8183 / 19.99, 15 left it as without. */
#define TOPO_AKEEP 20.0

/* full's round: tets below this mean ratio are given a vertex insertion, kept
 * only when the cavity's smallest mean ratio rises by topo.h's imargin and its
 * smallest dihedral angle does not fall (topo.h's iangle), the new vertex
 * placed for the star's smallest mean ratio first. Measured with
 * --boundary fixed on the 20k-tet meshes of scripts/corpus.py --seed 1, mean
 * ratio / smallest dihedral / CPU s (one run each, machine loaded) at 0.15
 * (before) and 0.6: ball-scan 0.8143 / 14.00 / 2.0 and 0.8221 / 14.00 / 2.9
 * (mmg3d -optim -nosurf: 0.8217); ball-lowq 0.7853 / 1.34 / 2.2 and 0.7882 /
 * 1.34 / 5.4; bone-lowq 0.6561 / 0.14 / 3.4 and 0.6574 / 0.14 / 10.3 (tets
 * under 1 degree 28 -> 11). Insertion at 0.6 accepted on the mean ratio alone
 * lifted ball-scan to 0.8246 but took its smallest angle from 14.0 to 10.8. */
#define TOPO_QINSERT 0.5

/* Under a bound the user gave, the first smoothing spends this share of it and
 * the rounds after the flips the rest (spend.h: the whole run keeps the one
 * bound). Measured at --hausd rel:1e-3 with flips on the 20k-tet meshes of
 * scripts/corpus.py --seed 1: bone-lowq mean ratio 0.6753 / 0.34 deg with the
 * whole bound first, 0.6995 / 0.43 with half, 0.7148 / 0.49 with a quarter;
 * ball-scan and part-cad within 0.001 of each other. (The default bound keeps
 * its first run whole: its reruns widen it where tets stay inverted.) */
#define TOPO_FIRST_SHARE 0.25

/* --topology full: the first round of flips starts with interior edge splits
 * (split.h), the unconstrained edges longer than this times the mean size of
 * their ends split at their midpoints; the smoothing and flips of every round
 * place and connect the new vertices. With the boundary fixed (as mmg3d -nosurf
 * keeps it) a scanned shape's fine surface stays against a coarse interior
 * (the 100k-tet ball-scan of scripts/corpus.py --seed 1: the tets with 3
 * boundary corners at mean ratio 0.720 against mmg3d -optim -nosurf's 0.756,
 * which splits such edges). --boundary fixed, mean ratio / smallest dihedral /
 * CPU s at load 5-7: without splits ball-scan 0.8099 / 14.63 / 7.8, ball-lowq
 * 0.7843 / 0.83 / 14.2; splits in full's round only (1.3) 0.8158 / 20.75 / 8.9
 * and 0.7904 / 0.85 / 14.3; in the first round at 1.3 0.8284 / 23.07 / 21.3
 * and 0.8061 / 0.86 / 23.1; 1.45 0.8277 / 19.07 / 13.5 and 0.7999 / 0.82 /
 * 17.4; 1.6 0.8207 / 21.97 / 9.4 and 0.7940 / 0.87 / 12.3 (mmg 0.816 / 11.37 /
 * 8.7 and 0.793 / 0.34 / 13.4). Under the default boundary only when at least
 * TOPO_SSHARE of the edges are that long as the round starts (an interior far
 * coarser than its surface): the dev bunny low 10k (3.7%) 0.7974 / 17.18 ->
 * 0.8277 / 21.30 (mmg 0.8154 / 12.80). Split anyway, the 100k ball-scan (1.0%)
 * gained 0.008 in 8% more CPU, bone-lowq (2.2%) lost 0.003 in 29% more. */
#define TOPO_LSPLIT 1.6
#define TOPO_SSHARE 0.03

/* What flip_round does besides flips (its insert argument): insertion and
 * contraction (each raising its tets' smallest), edge splits before the
 * flips, or contraction by gain (full's last round). */
enum { ROUND_INSERT = 1, ROUND_SPLIT = 2, ROUND_COARSEN = 4 };

/* The contractions of full's last round (ROUND_COARSEN: contract.h's qfloor, topo.h's
 * cfloor): the interior edges of the tets below TOPO_CQUEUE, an edge going when the sum
 * of (1 - mean ratio) over its vertex's tets falls and every new tet stays above
 * TOPO_CFLOOR, the mesh's worst tet and its smallest dihedral angle; a round contracting
 * fewer than TOPO_CMIN of the vertices (Gmsh's, TetGen's meshes) is dropped before its
 * smoothing. Figures (17-32% of random interior points go) and what was tried:
 * docs/method.md 10. */
#define TOPO_CQUEUE 0.85
#define TOPO_CFLOOR 0.5
#define TOPO_CMIN 0.01

/* The first round's operations besides flips for the run of opts. */
static int first_ops(const opt_options *opts)
{
    return opts->topology == OPT_TOPOLOGY_FULL ? ROUND_SPLIT : 0;
}

/* *act grown to nv + 1 entries (a round added vertices). QDC_ENOMEM. */
static qdc_status grow_marks(uint8_t **act, int32_t nv, qdc_error *err)
{
    uint8_t *a = qdc_realloc(*act, (size_t)nv + 1);

    if (!a)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    *act = a;
    return QDC_OK;
}

/* The operations of a round of topology. */
static int64_t round_ops(const topo_stats *ts)
{
    return ts->edge_removals + ts->flips23 + ts->multiface + ts->insertions + ts->bflips +
           ts->peels + ts->contractions;
}

/* m's vertices replaced by nv with the coordinates xyz (taken over): input
 * vertex v is vmap[v] (-1: contracted away), new ones follow the input's
 * kept ones, inside the volume: their flags and refs 0 (free, no ref). The
 * triangles renumbered (a contracted vertex is interior: on none). */
static qdc_status remap_vertices(mesh_t *m, int32_t nv, double *xyz, const int32_t *vmap,
                                 qdc_error *err)
{
    uint8_t *f = m->fixed ? qdc_calloc((size_t)nv + 1, 1) : NULL;
    int32_t *r = m->vref ? qdc_calloc((size_t)nv + 1, sizeof *r) : NULL;
    mesh_pdata *pd = NULL;
    qdc_status st = QDC_OK;

    if ((m->fixed && !f) || (m->vref && !r))
        st = qdc_fail(err, QDC_ENOMEM, "out of memory");
    else /* before m's coordinates and tets change: they interpolate */
        st = mesh_pdata_remap(m, nv, xyz, vmap, &pd, err);
    if (st != QDC_OK) {
        qdc_free(f);
        qdc_free(r);
        return st;
    }
    if (m->pdata) {
        mesh_pdata_free(m->pdata);
        m->pdata = pd;
    }
    for (int32_t v = 0; v < m->nv; v++)
        if (vmap[v] >= 0) {
            if (f)
                f[vmap[v]] = m->fixed[v];
            if (r)
                r[vmap[v]] = m->vref[v];
        }
    for (int64_t k = 0; k < 3 * (int64_t)m->ntri; k++)
        m->tris[k] = vmap[m->tris[k]] >= 0 ? vmap[m->tris[k]] : 0;
    if (f) {
        qdc_free(m->fixed);
        m->fixed = f;
    }
    if (r) {
        qdc_free(m->vref);
        m->vref = r;
    }
    qdc_free(m->xyz);
    m->xyz = xyz;
    m->nv = nv;
    return QDC_OK;
}

/* m's triangles replaced by those of sf after a round with boundary operations
 * (sf's arrays taken over or freed). */
static qdc_status take_surface(mesh_t *m, topo_surface *sf, qdc_error *err)
{
    qdc_status st = QDC_OK;

    if (sf->removed > 0 || sf->added > 0) {
        st = mesh_set_tris(m, sf->ntri_out, m->tri_ref != NULL);
        if (st == QDC_OK) {
            memcpy(m->tris, sf->tris_out, 3 * (size_t)sf->ntri_out * sizeof *m->tris);
            if (m->tri_ref)
                memcpy(m->tri_ref, sf->refs_out,
                       (size_t)sf->ntri_out * sizeof *m->tri_ref);
        } else {
            st = qdc_fail(err, st, "out of memory");
        }
    }
    qdc_free(sf->tris_out);
    qdc_free(sf->refs_out);
    sf->tris_out = sf->refs_out = NULL;
    return st;
}

/* A tet's key: its vertices sorted, mixed into 64 bits. */
static uint64_t tet_hash(const int32_t *t)
{
    int32_t k[4] = {t[0], t[1], t[2], t[3]};
    uint64_t h = 0x243F6A8885A308D3ull;

    for (int x = 1; x < 4; x++)
        for (int y = x; y > 0 && k[y - 1] > k[y]; y--) {
            int32_t w = k[y];
            k[y] = k[y - 1];
            k[y - 1] = w;
        }
    for (int i = 0; i < 4; i++) {
        h ^= (uint64_t)(uint32_t)k[i];
        h *= 0x9E3779B97F4A7C15ull;
        h ^= h >> 29;
    }
    return h;
}

/* act[v] (nv entries) = 1 for each vertex whose tets a round of flips
 * changed (the sum of its tets' keys before and after differ) and for the
 * vertices of the tets around those; else 0. QDC_ENOMEM. */
static qdc_status mark_active(int32_t nv, const int32_t *old, int32_t nold,
                              const int32_t *tets, int32_t nt, uint8_t *act,
                              qdc_error *err)
{
    uint64_t *h = qdc_calloc((size_t)nv + 1, sizeof *h);

    if (!h)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    for (int32_t t = 0; t < nold; t++)
        for (int i = 0; i < 4; i++)
            h[old[4 * (size_t)t + i]] += tet_hash(old + 4 * (size_t)t);
    for (int32_t t = 0; t < nt; t++)
        for (int i = 0; i < 4; i++)
            h[tets[4 * (size_t)t + i]] -= tet_hash(tets + 4 * (size_t)t);
    for (int32_t v = 0; v < nv; v++)
        act[v] = h[v] != 0;
    for (int32_t t = 0; t < nt; t++) {
        const int32_t *tt = tets + 4 * (size_t)t;
        if ((act[tt[0]] | act[tt[1]] | act[tt[2]] | act[tt[3]]) & 1)
            for (int i = 0; i < 4; i++)
                act[tt[i]] |= 2;
    }
    qdc_free(h);
    return QDC_OK;
}

/* mark_active of m's tets against the nt new tets of nv vertices; with vmap
 * (contractions) m's tets renumbered by it first (a vertex gone: nv, in no
 * new tet). act has nv + 1 entries. QDC_ENOMEM. */
static qdc_status mark_active_mapped(const mesh_t *m, const int32_t *vmap, int32_t nv,
                                     const int32_t *tets, int32_t nt, uint8_t *act,
                                     qdc_error *err)
{
    int32_t *old = vmap ? qdc_mallocn(4 * (size_t)m->nt, sizeof *old) : NULL;
    qdc_status st;

    if (!vmap)
        return mark_active(m->nv, m->tets, m->nt, tets, nt, act, err);
    if (!old)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    for (int64_t k = 0; k < 4 * (int64_t)m->nt; k++)
        old[k] = vmap[m->tets[k]] >= 0 ? vmap[m->tets[k]] : nv;
    st = mark_active(nv + 1, old, m->nt, tets, nt, act, err);
    qdc_free(old);
    return st;
}

/* mesh_orient's flip of m's tets, kept from one call to the next while m's
 * tets stay those it was found for (nt < 0: none kept). */
typedef struct {
    uint8_t *flip;
    int32_t nt;
    int pos; /* every tet positive under flip at the last orient_memo_get */
} orient_memo;

/* 1 when every tet of m is positive under flip (none inverted or flat). */
static int orient_positive(const mesh_t *m, const uint8_t *flip)
{
    int32_t bad = 0;

#pragma omp parallel for reduction(+ : bad) schedule(static)
    for (int32_t t = 0; t < m->nt; t++) {
        double d = geom_tet_vol6(m->xyz, m->tets + 4 * (size_t)t);
        bad += flip[t] ? !(d < 0) : !(d > 0);
    }
    return bad == 0;
}

/* flip (m->nt bytes) = mesh_orient's for m (its statuses): om's when every
 * tet is positive under it (the smoothing since moved the vertices, not the
 * tets), for then mesh_orient finds it again (it is an orientation of these
 * tets' connectivity, and every component, all positive under it, keeps it
 * by the majority rule); else mesh_orient's, kept in om. Each round of flips
 * after the first orients the tets its record oriented: on the 1M-tet
 * ball-scan of scripts/corpus.py mesh_orient was 0.5-0.7 CPU s of each. */
static qdc_status orient_memo_get(const mesh_t *m, orient_memo *om, uint8_t *flip,
                                  qdc_error *err)
{
    mesh_orientation mo;
    qdc_status st;

    if (om->nt == m->nt && orient_positive(m, om->flip)) {
        memcpy(flip, om->flip, (size_t)m->nt);
        om->pos = 1;
        return QDC_OK;
    }
    st = mesh_orient(m, flip, &mo, err);
    om->pos = st == QDC_OK && orient_positive(m, flip);
    if (st == QDC_OK) {
        uint8_t *f = qdc_realloc(om->flip, (size_t)m->nt + 1);
        if (!f)
            return qdc_fail(err, QDC_ENOMEM, "out of memory");
        memcpy(f, flip, (size_t)m->nt);
        om->flip = f;
        om->nt = m->nt;
    }
    return st;
}

/* After a round of flips that replaced m's tets: om holds the orientation of
 * the new tets when the round's input had every tet positive under its own
 * (om->pos), else nothing. The new tets are positive under the orientation they
 * inherit (the exact predicate), the others as they were, so every tet is
 * positive: the flip is each tet's sign, and mesh_orient would find the same
 * (orient_memo_get checks it, and calls mesh_orient where a sign is 0). On the
 * 1M-tet ball-scan of scripts/corpus.py mesh_orient after each round was
 * 0.5 s; this pass is parallel and a fraction of it. */
static void orient_carry(const mesh_t *m, orient_memo *om)
{
    uint8_t *f = om->pos ? qdc_realloc(om->flip, (size_t)m->nt + 1) : NULL;

    om->nt = -1;
    if (!f)
        return; /* mesh_orient the next time (out of memory: om as it was) */
    om->flip = f;
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < m->nt; t++)
        f[t] = geom_tet_vol6(m->xyz, m->tets + 4 * (size_t)t) < 0;
    om->nt = m->nt;
}

/* --boundary fixed: no floor4 (topo.h; Stellar's MIN4BOUNDQUAL keeps the
 * tets of four surface corners, out of the smoother's reach, above 0.1). With
 * the surface fixed the tets an operation replaces are as much out of reach,
 * so the floor only kept the worst (docs/method.md). 100k-tet bones of
 * scripts/corpus.py --seed 1, flips --boundary fixed at 0.1 and 0, mean ratio
 * / smallest dihedral: bone-scan 0.7131 / 0.0018 and 0.7137 / 0.0209 (mmg3d
 * -optim -nosurf -noinsert 0.6615 / 0.0114), bone-lowq 0.6898 / 0.0010 and
 * 0.6902 / 0.0035; full --boundary fixed bone-scan 0.7222 and 0.7235, the
 * other meshes the same. With the default boundary 0 changed no angle. */
#define TOPO_FLOOR4_FIXED 0.0

/* The flips' parameters for a round of o (insert: ROUND_INSERT for full's
 * round, ROUND_SPLIT for edge splits before the flips). */
static void round_params(const opt_options *o, int insert, double hausd, topo_params *p)
{
    topo_params_default(p);
    p->qgoal = TOPO_QGOAL;
    p->insert = (insert & ROUND_INSERT) != 0;
    p->contract = p->insert;
    p->split = (insert & ROUND_SPLIT) != 0;
    p->lsplit = TOPO_LSPLIT;
    p->sshare = o->boundary == OPT_BOUNDARY_FIXED ? 0.0 : TOPO_SSHARE;
    p->qinsert = TOPO_QINSERT;
    if (insert & ROUND_COARSEN) {
        p->contract = 1;
        p->qcontract = TOPO_CQUEUE;
        p->cfloor = TOPO_CFLOOR;
    }
    p->akeep = TOPO_AKEEP;
    if (o->boundary == OPT_BOUNDARY_FIXED)
        p->floor4 = TOPO_FLOOR4_FIXED;
    p->bound.hausd = hausd;
    p->bound.cos_feature = cos(o->feature_angle * (3.14159265358979323846 / 180.0));
}

/* One round of flips on m: the tets oriented from the connectivity (mesh_orient:
 * tets written in the other order are flipped for lib/topo and written back so),
 * improved, and m's tets and regions replaced when a flip was made. hausd > 0:
 * boundary flips and peeling within it too, m's triangles brought up to date. */
static qdc_status flip_round(mesh_t *m, const opt_options *o, int insert, double hausd,
                             spend *sp, uint8_t *act, orient_memo *om, topo_stats *ts,
                             topo_surface *sf, qdc_error *err)
{
    uint8_t *flip = qdc_malloc((size_t)m->nt);
    int32_t *tv = qdc_mallocn(4 * (size_t)m->nt, sizeof *tv), *tets = NULL,
            *region = NULL, *vmap = NULL;
    int32_t nt = 0, nv = 0;
    double *xyz = NULL;
    topo_params p;
    qdc_status st;

    memset(ts, 0, sizeof *ts);
    if (!flip || !tv) {
        st = qdc_fail(err, QDC_ENOMEM, "out of memory");
        goto out;
    }
    st = orient_memo_get(m, om, flip, err);
    if (st != QDC_OK)
        goto out;
    memcpy(tv, m->tets, 4 * (size_t)m->nt * sizeof *tv);
    for (int32_t t = 0; t < m->nt; t++)
        if (flip[t]) {
            tv[4 * (size_t)t] = m->tets[4 * (size_t)t + 1];
            tv[4 * (size_t)t + 1] = m->tets[4 * (size_t)t];
        }
    round_params(o, insert, hausd, &p);
    p.nkeep = m->ntri; /* triangles inside the mesh too: a user's inner surface */
    p.keep = m->tris;
    sf->ntri = m->ntri;
    sf->tris = m->tris;
    sf->refs = m->tri_ref;
    sf->vdev = sp->bound > 0 ? sp->spent : NULL; /* the run's bound, not the round's */
    sf->vop = sp->op;
    st = topo_full_arrays(m->nv, m->xyz, m->nt, tv, m->region, flip, &p, o->cancel, &nv,
                          &xyz, &nt, &tets, m->region ? &region : NULL, &vmap,
                          hausd > 0 ? sf : NULL, ts, err);
    if (st == QDC_ECANCEL)
        st = QDC_OK; /* the mesh as the flips left it is valid */
    if (st != QDC_OK || round_ops(ts) == 0)
        goto out;
    if (hausd > 0) {
        st = take_surface(m, sf, err);
        if (st != QDC_OK)
            goto out;
    }
    if (act && ts->insertions == 0) {
        st =
            mark_active_mapped(m, ts->contractions ? vmap : NULL, nv, tets, nt, act, err);
        if (st != QDC_OK)
            goto out;
    }
    if (ts->insertions + ts->contractions > 0) {
        st = spend_remap(sp, xyz, vmap, nv, err);
        if (st != QDC_OK)
            goto out;
        st = remap_vertices(m, nv, xyz, vmap, err);
        if (st != QDC_OK)
            goto out;
        xyz = NULL;
    }
    qdc_free(m->tets);
    m->tets = tets;
    tets = NULL;
    if (m->region) {
        qdc_free(m->region);
        m->region = region;
        region = NULL;
    }
    m->nt = nt;
    orient_carry(m, om); /* other tets */
out:
    qdc_free(flip);
    qdc_free(tv);
    qdc_free(tets);
    qdc_free(region);
    qdc_free(xyz);
    qdc_free(vmap);
    qdc_free(sf->tris_out);
    qdc_free(sf->refs_out);
    sf->tris_out = sf->refs_out = NULL;
    return st;
}

/* Tet t's mean ratio signed under flip, into q[t], and its smallest and
 * largest dihedral angles (NAN for an inverted tet) into a[2t], a[2t + 1]. */
static void tet_record(const mesh_t *m, const uint8_t *flip, int32_t t, double *q,
                       double *a)
{
    const int32_t *tt = m->tets + 4 * (size_t)t;
    int s0 = flip[t] ? 1 : 0, s1 = 1 - s0;
    const double *p0 = m->xyz + 3 * (size_t)tt[s0], *p1 = m->xyz + 3 * (size_t)tt[s1];
    const double *p2 = m->xyz + 3 * (size_t)tt[2], *p3 = m->xyz + 3 * (size_t)tt[3];
    metric_parts pt;

    metric_parts_for(OPT_METRIC_MIMR, p0, p1, p2, p3, &pt);
    q[t] = metric_mean_ratio(&pt);
    if (geom_tet_inverted(pt.vol))
        a[2 * (size_t)t] = a[2 * (size_t)t + 1] = NAN;
    else
        metric_dihedral_range(p0, p1, p2, p3, &a[2 * (size_t)t], &a[2 * (size_t)t + 1]);
}

/* The record of the mesh after a round of flips (phase "topology"), each tet
 * signed under the connectivity's orientation: the tets measured in parallel,
 * summed in their order (the same figures whatever the thread count). */
static qdc_status flip_record(const mesh_t *m, orient_memo *om, int iteration, double t0,
                              opt_progress *r, qdc_error *err)
{
    double sum = 0.0, sq = 0.0;
    uint8_t *flip = qdc_malloc((size_t)m->nt);
    double *q = qdc_mallocn((size_t)m->nt + 1, sizeof *q),
           *a = qdc_mallocn(2 * (size_t)m->nt + 1, sizeof *a);
    qdc_status st;

    memset(r, 0, sizeof *r);
    st = flip && q && a ? orient_memo_get(m, om, flip, err)
                        : qdc_fail(err, QDC_ENOMEM, "out of memory");
    if (st != QDC_OK)
        goto out;
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < m->nt; t++)
        tet_record(m, flip, t, q, a);
    r->iteration = iteration;
    r->phase = "topology";
    r->n_tets = m->nt;
    r->q_min = INFINITY;
    r->dih_min = 180.0;
    r->dih_max = 0.0;
    for (int32_t t = 0; t < m->nt; t++) {
        sum += q[t];
        sq += q[t] * q[t];
        if (q[t] < r->q_min)
            r->q_min = q[t];
        if (isnan(a[2 * (size_t)t])) {
            r->n_inverted++;
            continue;
        }
        if (a[2 * (size_t)t] < r->dih_min)
            r->dih_min = a[2 * (size_t)t];
        if (a[2 * (size_t)t + 1] > r->dih_max)
            r->dih_max = a[2 * (size_t)t + 1];
    }
    r->q_mean = sum / m->nt;
    r->q_std = sqrt(fmax(0.0, sq / m->nt - r->q_mean * r->q_mean));
    r->elapsed = qdc_now() - t0;
out:
    qdc_free(flip);
    qdc_free(q);
    qdc_free(a);
    return st;
}

static void add_run(opt_result *acc, const opt_result *r)
{
    acc->iterations += r->iterations;
    acc->t_setup += r->t_setup;
    acc->t_weights += r->t_weights;
    acc->t_assembly += r->t_assembly;
    acc->t_solve += r->t_solve;
    acc->t_linesearch += r->t_linesearch;
    acc->t_harmonic += r->t_harmonic;
    acc->t_finish += r->t_finish;
}

/* Progress of a round's smoothing: numbered after the records so far; its
 * input record is left out (the "topology" record just sent holds it). */
typedef struct {
    opt_progress_fn fn;
    void *ctx;
    int offset;
    double t_offset;
} round_progress;

static int round_report(void *ctx, const opt_progress *p)
{
    const round_progress *rp = ctx;
    opt_progress q = *p;

    if (p->iteration == 0)
        return 0;
    q.iteration += rp->offset;
    q.elapsed += rp->t_offset;
    return rp->fn(rp->ctx, &q);
}

/* The operations of one round of flips and the boundary triangles it
 * removed and added (sf), added to the run's counts. */
static void count_round(opt_result *acc, const topo_stats *ts, const topo_surface *sf)
{
    acc->topo_rounds++;
    acc->topo_tris_removed += sf->removed;
    acc->topo_tris_added += sf->added;
    acc->topo_edge_removals += ts->edge_removals;
    acc->topo_flips23 += ts->flips23;
    acc->topo_multiface += ts->multiface;
    acc->topo_insertions += ts->insertions;
    acc->topo_bflips += ts->bflips;
    acc->topo_peels += ts->peels;
    acc->topo_contractions += ts->contractions;
    acc->topo_bcontractions += ts->bcontractions;
    for (int n = 3; n <= FLIP_MAXRING; n++)
        acc->topo_by_ring[n] += ts->by_ring[n];
}

static void log_round_failed(const opt_options *opts, qdc_status st, const qdc_error *err)
{
    char msg[400];

    if (!opts->log)
        return;
    snprintf(msg, sizeof msg,
             "topology: a round failed (%s%s%.200s): the mesh of "
             "the round before is returned",
             qdc_status_str(st), err && err->msg[0] ? ": " : "", err ? err->msg : "");
    opts->log(opts->log_ctx, 1, msg);
}

/* The whole run's result: the last round's records and outcome, the first
 * run's input record, the counts and times summed over the rounds. */
static void merge_result(opt_result *last, const opt_result *first, int32_t nt_out,
                         int32_t nv_out, int record, double t_total)
{
    last->before = first->before;
    last->tets_in = first->tets_in;
    last->tets_out = nt_out;
    last->topo_rounds = first->topo_rounds;
    last->topo_edge_removals = first->topo_edge_removals;
    last->topo_flips23 = first->topo_flips23;
    last->topo_multiface = first->topo_multiface;
    last->topo_insertions = first->topo_insertions;
    last->topo_bflips = first->topo_bflips;
    last->topo_peels = first->topo_peels;
    last->topo_contractions = first->topo_contractions;
    last->topo_bcontractions = first->topo_bcontractions;
    last->topo_tris_removed = first->topo_tris_removed;
    last->topo_tris_added = first->topo_tris_added;
    last->verts_in = first->verts_in;
    last->verts_out = nv_out;
    memcpy(last->topo_by_ring, first->topo_by_ring, sizeof last->topo_by_ring);
    last->iterations = first->iterations;
    last->t_setup = first->t_setup;
    last->t_weights = first->t_weights;
    last->t_assembly = first->t_assembly;
    last->t_solve = first->t_solve;
    last->t_linesearch = first->t_linesearch;
    last->t_harmonic = first->t_harmonic;
    last->t_finish = first->t_finish;
    last->hausd_bound = first->hausd_bound; /* the run's, which every round kept */
    last->last_record = record;
    last->t_total = t_total;
    snprintf(last->stop_reason, sizeof last->stop_reason, "%s",
             opt_stop_name(last->stop));
}

/* The model's arrays of a and b exchanged (not their sources). */
static void swap_model(mesh_t *a, mesh_t *b)
{
    mesh_t t = *a;

    a->nv = b->nv;
    a->nt = b->nt;
    a->xyz = b->xyz;
    a->tets = b->tets;
    a->region = b->region;
    a->fixed = b->fixed;
    a->vref = b->vref;
    a->pdata = b->pdata;
    a->ntri = b->ntri;
    a->tris = b->tris;
    a->tri_ref = b->tri_ref;
    b->nv = t.nv;
    b->nt = t.nt;
    b->xyz = t.xyz;
    b->tets = t.tets;
    b->region = t.region;
    b->fixed = t.fixed;
    b->vref = t.vref;
    b->pdata = t.pdata;
    b->ntri = t.ntri;
    b->tris = t.tris;
    b->tri_ref = t.tri_ref;
}

/* 1 when a >= b up to the roundings of one tet's figure (relative 1e-9): the
 * worst tet is often one the surface holds in every round (full's round on
 * the 100k bone-lowq, mean ratio 0.73116 -> 0.73326, was dropped for its
 * smallest angle 2e-11 relative lower). */
static int not_below(double a, double b)
{
    return a >= b - 1e-9 * fabs(b);
}

/* full_round's test of a round's record a against b before it: the worst tet
 * not lower (not_below); the smallest dihedral at most 5% lower (a round that
 * raises the mean ratio by 0.02 moves it a few tenths of a degree); the mean
 * ratio not lower, or by at most 0.01 when the worst tet's at least doubled
 * (20k-tet bone-scans of scripts/corpus.py, --boundary fixed: insertion rounds
 * took the smallest angle from 0.015 and 0.056 to 3.41 and 2.31 degrees). */
static int round_kept(const opt_progress *a, const opt_progress *b)
{
    return not_below(a->q_min, b->q_min) && a->dih_min >= 0.95 * b->dih_min &&
           (a->q_mean >= b->q_mean ||
            (a->q_min >= 2.0 * b->q_min && a->q_mean >= b->q_mean - 1e-2));
}

/* --topology flips: a round's smoothing with the vertices away from the flips
 * held runs this many global iterations at most. After the second the global
 * phase ended there (it stops at its third when that gains little) or its
 * third step was rejected, after a line search through every halving: on the
 * 100k-tet part-cad and two-region of scripts/corpus.py --seed 1 the same
 * bytes with 2, about 0.3 s of wall time less per round; mean ratio /
 * smallest dihedral with 10 and 2 the same on the five meshes of the bench
 * (part-cad, two-region, ball-scan, ball-lowq, bone-lowq), default and
 * --boundary fixed, but bone-lowq's mean 0.7310 -> 0.7309. With 0
 * (finishing passes only) part-cad's smallest dihedral fell to 38.92
 * (39.16), with 1 to 38.65. Not for full: its last round starts from the
 * mesh these rounds leave, and ball-lowq's smallest dihedral fell from
 * 16.10 to 15.95. But in every held round (full's too) the global phase may
 * stop at its second iteration when that one gained little (opt.h's
 * stall_early), not only at its third: the third was a line search through
 * every halving that found no step on part-cad and two-region. --topology
 * full on the 100k-tet meshes of scripts/corpus.py --seed 1, default and
 * --boundary fixed: the same bytes on part-cad, two-region, ball-scan and
 * ball-lowq fixed; ball-lowq 0.8139 / 16.10 -> 0.8141 / 15.95, bone-lowq
 * 0.7333 -> 0.7332 and fixed 0.6932 -> 0.6927 (mean ratio / smallest
 * dihedral); instructions of a single-thread run (callgrind) on the 20k-tet
 * part-cad and two-region 8.7% and 9.1% fewer. */
enum { TOPO_HELD_ITERS = 2 };

/* A round's smoothing (within the run's bound, spend.h); with act, only the
 * vertices act marks move (the others held: m->fixed lent meanwhile), and
 * with cap in at most TOPO_HELD_ITERS global iterations. */
static qdc_status round_smooth(mesh_t *m, opt_options *o, spend *sp, const uint8_t *act,
                               int cap, opt_result *r, qdc_error *err)
{
    uint8_t *keep = m->fixed, *held = NULL;
    int iters = o->max_iter;
    qdc_status st;

    if (act) {
        held = qdc_malloc((size_t)m->nv + 1);
        if (!held)
            return qdc_fail(err, QDC_ENOMEM, "out of memory");
        for (int32_t v = 0; v < m->nv; v++)
            held[v] = (uint8_t)((keep && keep[v]) || !act[v]);
        m->fixed = held;
    }
    if (act && cap && o->max_iter > TOPO_HELD_ITERS)
        o->max_iter = TOPO_HELD_ITERS;
    o->stall_early = act != NULL;
    st = spend_begin(sp, m, o, err);
    if (st == QDC_OK) {
        st = opt_run_smooth_round(m, o, r, err);
        spend_end(sp, m);
    }
    o->max_iter = iters;
    o->stall_early = 0;
    if (act) {
        m->fixed = keep;
        qdc_free(held);
    }
    return st;
}

/* --topology full, after the rounds of flips: a round with edge contraction and
 * vertex insertion too (ROUND_INSERT), then one with contraction by gain
 * (ROUND_COARSEN), each smoothed and kept when round_kept says (else m as it
 * was). Both inside every round: the 100k-tet bone-lowq of scripts/corpus.py
 * ended at mean ratio 0.7238 (flips: 0.7289); contraction by gain in the
 * insertion round took bone-scan's from 0.7501 to 0.7484. */
static qdc_status full_round(mesh_t *m, opt_options *o, int ops, double hausd, spend *sp,
                             orient_memo *om, topo_surface *sf, opt_result *first,
                             opt_result *last, int *record, qdc_error *err)
{
    mesh_t *keep;
    opt_result r, acc = *first;
    opt_progress pr;
    topo_params p;
    topo_stats ts;
    spend was;
    int32_t nv = m->nv;
    int64_t least;
    uint8_t *act = NULL; /* ROUND_COARSEN: the vertices its smoothing moves */
    qdc_status st;

    /* No tet below the mean ratio insertion or contraction start at: the
     * round's flips keep it so (each raises its cavity's smallest), so it
     * would insert and contract nothing and be dropped, after a round of
     * flips and the copies (on the 100k-tet part-cad and two-region of
     * scripts/corpus.py --seed 1, about a tenth of full's CPU). */
    round_params(o, ops, hausd, &p);
    st = hausd > 0 ? QDC_OK : flip_record(m, om, 0, 0.0, &pr, err);
    if (st != QDC_OK)
        return st;
    if (hausd <= 0 && pr.n_inverted == 0 && pr.q_min >= fmax(p.qinsert, p.qcontract))
        return QDC_OK;
    keep = mesh_dup(m);
    if (!keep)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    st = spend_copy(&was, sp, err);
    if (st != QDC_OK) {
        mesh_free(keep);
        return st;
    }
    if (ops & ROUND_COARSEN) {
        act = qdc_malloc((size_t)nv + 1);
        if (!act)
            st = qdc_fail(err, QDC_ENOMEM, "out of memory");
    }
    if (st == QDC_OK)
        st = flip_round(m, o, ops, hausd, sp, act, om, &ts, sf, err);
    least = ops & ROUND_COARSEN ? (int64_t)ceil(TOPO_CMIN * nv) : 1;
    if (st == QDC_OK && ts.insertions + ts.contractions >= least) {
        count_round(&acc, &ts, sf);
        o->progress = NULL; /* a trial: its records would not be the result's */
        st = round_smooth(m, o, sp, act, act != NULL, &r, err);
        if (st == QDC_OK && r.outcome != OPT_STOPPED &&
            round_kept(&r.after, &last->after)) {
            add_run(&acc, &r);
            *first = acc;
            *last = r;
            *record += r.last_record;
            mesh_free(keep);
            spend_free(&was);
            qdc_free(act);
            return QDC_OK;
        }
    }
    /* not better, too little, or the trial failed: m as it was, valid */
    qdc_free(act);
    swap_model(m, keep);
    om->nt = -1;
    mesh_free(keep);
    spend_free(sp);
    *sp = was;
    qdc_error_clear(err);
    return QDC_OK;
}

/* A round's start, after its flips: their record (number `record`) sent,
 * and o's time limit and progress set for the round's smoothing. Returns 1
 * when the run stops here: *st says why if it failed, else last's outcome
 * (cancelled, out of time). */
static int round_begin(const mesh_t *m, const opt_options *opts, opt_options *o,
                       orient_memo *om, const topo_stats *ts, int record, double t0,
                       round_progress *rp, opt_result *last, qdc_status *st,
                       qdc_error *err)
{
    opt_progress pr;

    *st = flip_record(m, om, record, t0, &pr, err);
    if (*st != QDC_OK)
        return 1;
    pr.operations =
        ts->edge_removals + ts->flips23 + ts->multiface + ts->bflips + ts->peels;
    if (opts->progress && opts->progress(opts->progress_ctx, &pr)) {
        last->outcome = OPT_STOPPED;
        last->stop = OPT_STOP_CANCELLED;
        return 1;
    }
    if (opts->time_limit > 0) {
        double left = opts->time_limit - (qdc_now() - t0);
        if (left <= 0) {
            last->outcome = OPT_STOPPED;
            last->stop = OPT_STOP_TIME_LIMIT;
            return 1;
        }
        o->time_limit = left;
    }
    if (opts->progress) {
        rp->offset = record;
        rp->t_offset = qdc_now() - t0;
        o->progress = round_report;
        o->progress_ctx = rp;
    }
    return 0;
}

/* The first smoothing, whose bound is the run's: under a bound the user gave
 * it spends only a share of it; every round after spends what it has left
 * (spend.h). *hausd: the bound the boundary operations may use (0: none). */
static qdc_status first_round(mesh_t *m, const opt_options *opts, opt_options *o,
                              spend *sp, opt_result *first, double *hausd, int *moved,
                              qdc_error *err)
{
    /* the boundary changes only under a bound the user asked for (not the
     * default's) and when it may move at all (issue #31: triangle for
     * triangle otherwise) */
    int given =
        opts->boundary != OPT_BOUNDARY_FIXED &&
        (opts->hausd > 0 || (opts->hausd_rel > 0 && opts->hausd_rel != OPT_HAUSD_AUTO));
    qdc_status st;

    if (given) {
        o->hausd *= TOPO_FIRST_SHARE;
        o->hausd_rel *= TOPO_FIRST_SHARE;
    }
    st = opt_run_smooth(m, o, first, err);
    if (given)
        first->hausd_bound /= TOPO_FIRST_SHARE; /* the run's bound */
    if (st != QDC_OK)
        return st; /* m unchanged */
    *moved = 1;
    if (opts->boundary != OPT_BOUNDARY_FIXED && first->outcome != OPT_FAILED) {
        st = spend_set_bound(sp, m, first->hausd_bound, err);
        if (st != QDC_OK)
            return st;
    }
    if (given)
        *hausd = first->hausd_bound;
    return QDC_OK;
}

qdc_status opt_topology_rounds(mesh_t *m, const opt_options *opts, opt_result *res,
                               qdc_error *err)
{
    opt_options o = *opts;
    opt_result first, last;
    double t0 = qdc_now(), hausd = 0.0;
    int record = 0, stopped = 0, moved = 0;
    round_progress rp = {opts->progress, opts->progress_ctx, 0, 0.0};
    topo_surface sf = {0};
    uint8_t *act;
    orient_memo om = {NULL, -1, 0};
    spend sp;
    qdc_status st;

    o.topology = OPT_TOPOLOGY_NONE;
    o.free_fins = 1;
    st = spend_new(m, opts, &sp, err);
    if (st != QDC_OK)
        return st;
    st = first_round(m, opts, &o, &sp, &first, &hausd, &moved, err);
    if (st != QDC_OK && !moved) {
        if (res)
            *res = first;
        spend_free(&sp);
        return st;
    }
    act = qdc_malloc((size_t)m->nv + 1);
    if (st == QDC_OK && !act)
        st = qdc_fail(err, QDC_ENOMEM, "out of memory");
    last = first;
    first.tets_in = m->nt;
    first.verts_in = m->nv;
    record = first.last_record;
    /* (stopped: cancelled, out of time or the solver in trouble; st not
     * QDC_OK: the smoothing moved m, what came after failed: a stopped run) */
    for (int round = 0;
         round < TOPO_ROUNDS && st == QDC_OK && !stopped && last.outcome != OPT_STOPPED;
         round++) {
        topo_stats ts;
        opt_result r;
        st = flip_round(m, &o, round == 0 ? first_ops(opts) : 0, hausd, &sp, act, &om,
                        &ts, &sf, err);
        if (st == QDC_OK && ts.insertions > 0)
            st = grow_marks(&act, m->nv, err);
        if (st != QDC_OK || round_ops(&ts) == 0)
            break;
        count_round(&first, &ts, &sf);
        if (round_begin(m, opts, &o, &om, &ts, ++record, t0, &rp, &last, &st, err))
            break;
        st = round_smooth(m, &o, &sp, round > 0 ? act : NULL,
                          opts->topology == OPT_TOPOLOGY_FLIPS, &r, err);
        if (st != QDC_OK)
            break; /* m is the flipped mesh, valid */
        /* its records numbered on from the topology record (its input's) */
        r.best_iteration += record;
        record += r.last_record;
        add_run(&first, &r);
        stopped = r.after.q_min <= last.after.q_min &&
                  r.after.q_mean < last.after.q_mean + TOPO_GAIN;
        last = r;
    }
    for (int k = 0; k < 2 && st == QDC_OK && opts->topology == OPT_TOPOLOGY_FULL &&
                    last.outcome != OPT_STOPPED;
         k++)
        st = full_round(m, &o, k ? ROUND_COARSEN : ROUND_INSERT, hausd, &sp, &om, &sf,
                        &first, &last, &record, err);
    if (st != QDC_OK) {
        /* m is the valid mesh of the round before (flip_round replaces the
         * tets only when it succeeds, a failed smoothing leaves m as it was):
         * returned as a stopped run, as opt_run does for solver trouble */
        log_round_failed(opts, st, err);
        last.outcome = OPT_STOPPED;
        st = QDC_OK;
    }
    merge_result(&last, &first, m->nt, m->nv, record, qdc_now() - t0);
    spend_free(&sp);
    qdc_free(act);
    qdc_free(om.flip);
    if (res)
        *res = last;
    return st;
}
