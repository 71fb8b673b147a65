/* tmesh.h - a mutable tetrahedral mesh for topological operations: tets made and
 * removed through free lists, face adjacency kept up to date, a region tag per
 * tet, constrained faces and edges as per-tet bits, and a journal that undoes the
 * last operation.
 * Indices are 0-based int32; xyz holds 3 doubles per vertex. Every live tet is
 * positive: det[b-a, c-a, d-a] > 0 (core/tet.h), checked exactly (topo/exact.h).
 * Face i of a tet is the face opposite its local vertex i, ordered as tet_face_of
 * orders it (core/tet.h). Edge e of a tet joins local vertices tmesh_edge[e]
 * (01 02 03 12 13 23, the order of metric_dihedrals).
 * Constrained: a boundary face (of one tet), a face between tets of different
 * tags, a face the caller keeps (tmesh_keep_tris), and every edge of such a face.
 * Operations never remove a constrained face or edge, so the boundary triangles and the
 * interfaces stay as they are; the one exception is tmesh_replace_surface (boundary flips
 * and peeling under a Hausdorff bound), which needs the surface given by
 * tmesh_set_surface. Thread safety: a tmesh is used by one thread at a time. */
#ifndef QDC_TMESH_H
#define QDC_TMESH_H

#include "core/base.h"

#include <stdint.h>

extern const int tmesh_edge[6][2];

typedef struct tmesh_jent tmesh_jent; /* a journal entry (tmesh.c) */

/* The surface ref of a boundary face that no input triangle carries. */
#define TMESH_NOREF INT32_MIN

typedef struct tmesh {
    int32_t nv;      /* vertices */
    int32_t vcap;    /* vertices allocated (xyz, vcons) */
    double *xyz;     /* 3*nv, the mesh's own copy */
    uint8_t *vcons;  /* nv: 1 on a constrained face */
    int32_t cap;     /* tet slots allocated */
    int32_t hi;      /* slots [0, hi) have been used */
    int32_t nlive;   /* live tets */
    int32_t *tv;     /* 4*cap vertices; tv[4t] < 0 for a free slot */
    int32_t *adj;    /* 4*cap: across face i of t, 4*u + j (face j of u), or -1 */
    int32_t *tag;    /* cap region tags */
    uint8_t *rev;    /* cap: 1 when the caller writes the tet with its first two
                      * vertices swapped (tmesh_new's rev; new tets take the
                      * cavity's), so that tmesh_export gives the caller's order */
    uint8_t *fcons;  /* cap: bit i set when face i is constrained */
    uint8_t *econs;  /* cap: bit e set when edge e is constrained */
    double *q;       /* cap: mean ratio of the tet (geom/metric.h) */
    uint32_t *stamp; /* cap: bumped each time a slot gets a new tet */
    int32_t *freel;  /* free slots below hi, a stack */
    int32_t nfree;
    uint8_t *mark; /* cap scratch flags, all 0 between calls */
    /* The surface (tmesh_set_surface; NULL until then), per tet face i: */
    int32_t *fref;      /* 4*cap: the ref of boundary face i's triangle, TMESH_NOREF */
    double *fdev;       /* 4*cap: a bound on boundary face i's distance from the
                         * surface tmesh_set_surface saw (0 for its own faces) */
    uint8_t *fsurf;     /* cap: bit i: boundary face i was made by a boundary
                         * operation; bit 4 + i: its triangle is written with the
                         * orientation opposite to tet_face_of's (the input's) */
    int32_t *vdeg;      /* vcap: the live tets around each vertex (to tell a
                         * star that is not one piece through its faces) */
    int32_t (*gone)[3]; /* sorted vertices of the boundary faces removed */
    int32_t ngone, capgone, ngone_op; /* ..., at the operation's start */
    tmesh_jent *jr;                   /* the journal of the operation under way */
    int32_t njr, capjr;
} tmesh;

/* Build from nt positive tets (4 indices each; the caller orients them, e.g.
 * with mesh_orient) over nv vertices; region may be NULL (one tag, 0); rev may be
 * NULL (all 0), else 1 for each tet the caller writes with its first two
 * vertices swapped. Copies everything. QDC_EMESH for a face of three tets or a
 * bad index (err->index a tet), QDC_ENOMEM. Free with tmesh_free. */
qdc_status tmesh_new(int32_t nv, const double *xyz, int32_t nt, const int32_t *tets,
                     const int32_t *region, const uint8_t *rev, tmesh **out,
                     qdc_error *err);
void tmesh_free(tmesh *tm);

/* Constrain the faces of tm that are among the ntri triangles tris (3 each, in
 * any order; a triangle that is no face of tm, or is already constrained, is
 * passed over), on both sides, with their edges and vertices, as the boundary
 * is: a surface the user gave inside a region (an embedded surface, facet tags
 * between tets of one tag) then stays face for face. Call before any operation.
 * QDC_ENOMEM. */
qdc_status tmesh_keep_tris(tmesh *tm, int32_t ntri, const int32_t *tris);

/* The live tets in slot order, each in the caller's vertex order (rev): *tets
 * (4 each) and *region (may be NULL, then not written) allocated with qdc_malloc
 * for the caller; *nt their count. */
qdc_status tmesh_export(const tmesh *tm, int32_t *nt, int32_t **tets, int32_t **region);

/* Mean ratio of the tet (a,b,c,d), or a value below -1 when it is not positive
 * by the exact predicate or when its four corners are all on constrained faces
 * and its mean ratio is below floor4 (no new sliver held by the surface:
 * Stellar's MIN4BOUNDQUAL). */
double tmesh_quality(const tmesh *tm, const int32_t v[4], double floor4);

/* As tmesh_quality when that is above qneed (> 0); else a value at most qneed
 * (found without the exact predicate or the cube root when floating point
 * shows the mean ratio is clearly below qneed). A caller that wants only tets
 * above qneed gets the same answers as from tmesh_quality, sooner. */
double tmesh_quality_above(const tmesh *tm, const int32_t v[4], double floor4,
                           double qneed);

/* Replace the live tets old[0..nold) (one tag, a connected cavity) by the nnew
 * tets newt (positive, the same outer faces), which take that tag; new_ids (may
 * be NULL) receives their slots. The change is journaled: tmesh_commit keeps it,
 * tmesh_rollback undoes it. *applied is 0 (nothing changed, no journal) when a
 * new tet is not positive, an old one is not (an inverted input tet), the tags
 * differ, or the new tets do not close the
 * cavity's outer faces face for face. QDC_ENOMEM. */
qdc_status tmesh_replace(tmesh *tm, const int32_t *old, int nold,
                         const int32_t (*newt)[4], int nnew, int32_t *new_ids,
                         int *applied);
void tmesh_commit(tmesh *tm);

/* Attach the surface: ntri triangles (3 each, 0-based) with refs (may be NULL:
 * 0). Each boundary face takes the ref of the triangle with its vertices
 * (TMESH_NOREF when none has) and its orientation; other triangles (of
 * interfaces, inside) are ignored. QDC_ENOMEM. */
qdc_status tmesh_set_surface(tmesh *tm, int32_t ntri, const int32_t *tris,
                             const int32_t *refs);

/* As tmesh_replace, for an operation that changes the boundary (a surface
 * attached): outer faces of the cavity that the new tets do not close must be
 * boundary faces (removed: listed in tm->gone) or unconstrained faces to tets of
 * the cavity's tag (they become boundary faces of those tets); new faces that
 * close nothing become boundary faces. Every new boundary face takes the ref and
 * orientation of the removed ones (which must agree), fdev = dev, its fsurf bit
 * set, and its edges become constrained in every tet around them. nnew may be 0
 * (a tet peeled off). *applied 0 when these do not hold or no boundary face is
 * removed. QDC_ENOMEM. */
qdc_status tmesh_replace_surface(tmesh *tm, const int32_t *old, int nold,
                                 const int32_t (*newt)[4], int nnew, double dev,
                                 int32_t *new_ids, int *applied);
/* Undo the journaled operation: slots, vertices, adjacency, tags, bits, the free
 * list and hi exactly as they were. */
void tmesh_rollback(tmesh *tm);

/* Consistency check for tests: adjacency symmetric with matching vertices, face
 * bits as the definition above, the live count. *ninv receives the live tets
 * that are not positive (exactly; only an input's inverted tets can be: their
 * quality is below -1 and no operation touches them). 0 when consistent, else
 * -1 with a reason in why (n bytes). */
int tmesh_check(const tmesh *tm, int32_t *ninv, char *why, size_t n);

/* The tets around vertex v, from tet t0 (which has v) across the faces that
 * have v, into out (room for cap), in search order: their count, or -1 when
 * there are more than cap. A star that is not one piece through its faces
 * (a pinched vertex) gives the piece of t0 only. */
int tmesh_star(const tmesh *tm, int32_t t0, int32_t v, int32_t *out, int cap);

/* Local index of vertex v in tet t, or -1. */
static inline int tmesh_local(const tmesh *tm, int32_t t, int32_t v)
{
    const int32_t *tt = tm->tv + 4 * (int64_t)t;
    return tt[0] == v ? 0 : tt[1] == v ? 1 : tt[2] == v ? 2 : tt[3] == v ? 3 : -1;
}

#endif
