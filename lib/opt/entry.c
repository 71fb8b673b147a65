/* entry.c - opt_run (opt/opt.h), where a run goes: second-order tets to the
 * smoothing of their corners (p2.c), --topology flips and full to the rounds
 * of topology.c on the mesh numbered along a space-filling curve
 * (core/order.h) and given back in the caller's numbering, the rest to the
 * smoothing with its reruns (rerun.c). The top of the run: it calls only the
 * files below it.
 *
 * The numbering: the flips read the tets around each bad tet's edges and
 * faces, and at a million tets those reads miss the cache when neighbours are
 * far apart in memory (the points of a Delaunay mesher come in no spatial
 * order). The smoothing renumbers its own copy (rerun.c); the rounds of flips
 * now run on a renumbered mesh too. Measured on the 834k-tet ball-scan of
 * scripts/corpus.py --tets 1000000, --topology flips, three runs each
 * (median): 17.7 s of wall time against 19.2 s before, 28.5 CPU s against
 * 30.6; the same mean ratio and smallest dihedral angle to four places.
 *
 * The vertices come back in the caller's order (the input's kept ones in
 * their order, full's new ones after them, as opt_topology_rounds numbers
 * them), so that a --topology flips result keeps every vertex's number. The
 * tets stay in the order the run left them, unless it changed none (then the
 * caller's order, so that an unchanged file can be written back as read).
 * Which input vertex each is rides through the run in the refs (m->vref),
 * which the rounds carry to the vertices they keep and set to 0 on the ones
 * they make; the caller's refs are put back after. */
#include "opt/opt.h"

#include "core/mesh.h"
#include "core/order.h"
#include "opt/p2.h"
#include "opt/run.h"

#include <string.h>

/* 1 when the run r changed no tet. */
static int tets_kept(const opt_result *r)
{
    return r->topo_edge_removals == 0 && r->topo_flips23 == 0 && r->topo_multiface == 0 &&
           r->topo_insertions == 0 && r->topo_contractions == 0 && r->topo_bflips == 0 &&
           r->topo_peels == 0 && r->topo_tris_removed == 0 && r->topo_tris_added == 0;
}

/* The scratch of the way back, taken before the run: giving the numbers back
 * then needs no memory unless full's round grew the mesh past cap (a quarter
 * more vertices or tets than it had), and a run whose last allocation fails
 * still ends in the caller's numbering. */
typedef struct {
    int32_t *rank; /* the input's vertex count */
    int32_t *back; /* cap */
    uint8_t *done; /* cap */
    int32_t cap;
} way_back;

static void way_free(way_back *w)
{
    qdc_free(w->rank);
    qdc_free(w->back);
    qdc_free(w->done);
}

/* Room in w for n vertices or tets. QDC_ENOMEM. */
static qdc_status way_room(way_back *w, int32_t n)
{
    int32_t *b;
    uint8_t *d;

    if (n <= w->cap)
        return QDC_OK;
    b = qdc_realloc(w->back, ((size_t)n + 1) * sizeof *b);
    if (b)
        w->back = b;
    d = b ? qdc_realloc(w->done, (size_t)n + 1) : NULL;
    if (!d)
        return QDC_ENOMEM;
    w->done = d;
    w->cap = n;
    return QDC_OK;
}

/* m (its refs: each vertex's input number + 1, 0 for a new one) given back
 * the input's numbering of nv0 vertices and the refs ref (NULL: none); with
 * tto (the run changed no tet: its tet t was the input's tto[t]), the input's
 * tet order too. QDC_ENOMEM: m valid, numbered as the run left it, each
 * vertex with its ref. */
static qdc_status give_back(mesh_t *m, int32_t nv0, int32_t *ref, const int32_t *tto,
                            way_back *w)
{
    int32_t nv = m->nv, *org = m->vref, kept = 0, made = 0;
    qdc_status st = way_room(w, nv > m->nt ? nv : m->nt);

    if (st == QDC_OK) {
        memset(w->rank, 0, (size_t)nv0 * sizeof *w->rank);
        for (int32_t v = 0; v < nv; v++)
            if (org[v] > 0)
                w->rank[org[v] - 1] = 1;
        for (int32_t u = 0; u < nv0; u++) {
            int32_t k = w->rank[u];
            w->rank[u] = kept;
            kept += k;
        }
        for (int32_t v = 0; v < nv; v++)
            w->back[v] = org[v] > 0 ? w->rank[org[v] - 1] : kept + made++;
    }
    if (ref) {
        for (int32_t v = 0; v < nv; v++)
            org[v] = org[v] > 0 ? ref[org[v] - 1] : 0;
        qdc_free(ref);
    } else {
        qdc_free(m->vref);
        m->vref = NULL;
    }
    if (st == QDC_OK)
        mesh_renumber(m, w->back, tto, w->done);
    return st;
}

/* opt_topology_rounds on m numbered along a space-filling curve, given back
 * in m's numbering (above). */
static qdc_status topology_ordered(mesh_t *m, const opt_options *opts, opt_result *res,
                                   qdc_error *err)
{
    mesh_order o;
    opt_result own;
    way_back w = {0};
    int32_t nv0 = m->nv, *ref = m->vref, *org = NULL;
    qdc_status st = mesh_order_build(m, &o), st2;

    if (!res)
        res = &own;
    memset(res, 0, sizeof *res);
    if (st == QDC_EINVAL) /* an index out of range: the run names it */
        return opt_topology_rounds(m, opts, res, err);
    if (st == QDC_OK) {
        int32_t n = nv0 > m->nt ? nv0 : m->nt;
        org = qdc_mallocn((size_t)nv0 + 1, sizeof *org);
        w.rank = qdc_mallocn((size_t)nv0 + 1, sizeof *w.rank);
        st = org && w.rank ? way_room(&w, n + n / 4 + 16) : QDC_ENOMEM;
    }
    if (st != QDC_OK) {
        qdc_free(org);
        way_free(&w);
        mesh_order_free(&o);
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    }
    for (int32_t v = 0; v < nv0; v++)
        org[v] = v + 1;
    m->vref = org;
    for (int32_t t = 0; t < m->nt; t++) /* the input's tet told[t] goes to t */
        w.back[o.told[t]] = t;
    mesh_renumber(m, o.vnew, w.back, w.done);
    st = opt_topology_rounds(m, opts, res, err);
    /* a failed run changed no tet (opt_topology_rounds fails only before
     * its first flip: a round that fails leaves the mesh of the round before,
     * as a stopped run) */
    st2 = give_back(m, nv0, ref, st != QDC_OK || tets_kept(res) ? o.told : NULL, &w);
    way_free(&w);
    mesh_order_free(&o);
    if (st2 != QDC_OK)
        return qdc_fail(err, st2, "out of memory for the vertices' numbers");
    if (st != QDC_OK && err && err->index >= 0) {
        /* a vertex or tet named in the renumbered mesh: again in m's own
         * numbering, for the message */
        qdc_error_clear(err);
        st = opt_topology_rounds(m, opts, res, err);
    }
    return st;
}

/* Second-order tets: the run on the corners (the mid-edge nodes are in no
 * tet: held), then the mid-edge nodes moved with their edges (p2.c). */
static qdc_status p2_run(mesh_t *m, const opt_options *opts, opt_result *res,
                         qdc_error *err)
{
    opt_result own;
    double *x0;
    qdc_status st;

    if (opts && opts->topology != OPT_TOPOLOGY_NONE)
        return qdc_fail(err, QDC_EINVAL,
                        "second-order (10-node) tets: --topology %s would change the "
                        "edges their mid-edge nodes are on; use --topology none",
                        opt_topology_name(opts->topology));
    if (!res)
        res = &own;
    x0 = qdc_mallocn((size_t)m->nv * 3 + 1, sizeof(double));
    if (!x0)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the input's coordinates");
    memcpy(x0, m->xyz, (size_t)m->nv * 3 * sizeof(double));
    st = opt_run_smooth(m, opts, res, err);
    if (st == QDC_OK && res->outcome != OPT_FAILED) {
        st = p2_finish(m, x0, res, err);
        if (st != QDC_OK) /* m unchanged on failure */
            memcpy(m->xyz, x0, (size_t)m->nv * 3 * sizeof(double));
    }
    qdc_free(x0);
    return st;
}

qdc_status opt_run(mesh_t *m, const opt_options *opts, opt_result *res, qdc_error *err)
{
    if (m && m->mid && m->nv > 0 && m->nt > 0 && m->xyz && m->tets) {
        qdc_status st = mesh_validate(m, NULL, err);
        return st != QDC_OK ? st : p2_run(m, opts, res, err);
    }
    if (opts && opts->topology != OPT_TOPOLOGY_NONE && m && m->nv > 0 && m->nt > 0 &&
        m->xyz && m->tets)
        return topology_ordered(m, opts, res, err);
    return opt_run_smooth(m, opts, res, err);
}

qdc_status opt_run_faces(mesh_t *m, const opt_options *opts, opt_result *res,
                         mesh_faces **faces, qdc_error *err)
{
    if (!faces)
        return opt_run(m, opts, res, err);
    *faces = NULL;
    /* second-order tets and a run that changes the tets: the report finds
     * the faces itself */
    if ((opts && opts->topology != OPT_TOPOLOGY_NONE) || (m && m->mid))
        return opt_run(m, opts, res, err);
    return opt_run_smooth_faces(m, opts, res, faces, err);
}
