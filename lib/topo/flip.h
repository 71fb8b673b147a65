/* flip.h - the flips of the topology layer, evaluated without changing the mesh:
 * edge removal by the optimal retriangulation of the edge's ring (Klincsek's
 * dynamic programming as Stellar's removeedge uses it: the triangulation of the
 * ring polygon whose worst tet is best; 3-2, 4-4, 5-6, 6-8 ... flips) and the
 * 2-3 face flip. Each returns a candidate that tmesh_replace applies.
 * An operation is legal only when it removes no constrained face or edge and its
 * shell carries one tag (tmesh.h); every new tet is positive by the exact
 * predicate, and none has four corners on constrained faces below floor4.
 * Thread-safe for concurrent reads of one tmesh. */
#ifndef QDC_FLIP_H
#define QDC_FLIP_H

#include "topo/tmesh.h"

enum { FLIP_MAXRING = 10 };
enum { FLIP_EDGE = 1, FLIP_23 = 2, FLIP_MULTIFACE = 3, FLIP_BEDGE = 4, FLIP_PEEL = 5 };

/* What a boundary operation may do (flip_bedge_eval, flip_peel_eval). */
typedef struct {
    double hausd;       /* > 0: a bound on how far the surface may move (mesh units) */
    double cos_feature; /* the two triangles' normals at most this far apart */
} flip_bound;

typedef struct {
    int kind; /* FLIP_EDGE, FLIP_23, ... */
    int nold; /* tets removed (the ring, or the two tets of the face) */
    int nnew; /* tets made */
    int32_t old[2 * FLIP_MAXRING];
    int32_t newt[2 * FLIP_MAXRING][4];
    double qmin_old, qmin_new; /* smallest mean ratio in the cavity before, after */
    double gain;               /* sum of (1 - q) over the old tets less over the new */
    double dev;                /* a boundary operation: how far the surface moves */
    int32_t key[3]; /* the edge's vertices sorted (and -1), or the (first) face's */
} flip_cand;

/* Remove edge e (tmesh_edge) of live tet t: its ring of at most maxring
 * (<= FLIP_MAXRING) tets replaced by the best triangulation whose new tets all
 * have a mean ratio above qmin_old + margin. Returns 1 with *c filled, 0 when the
 * edge is constrained, on the boundary, in a mixed-tag or larger ring, next to an
 * inverted tet, or when no such triangulation exists (a ring that is not
 * convex as seen from the edge has none that is positive). */
int flip_edge_eval(const tmesh *tm, int32_t t, int e, int maxring, double floor4,
                   double margin, flip_cand *c);

/* Flip face f of live tet t and the tet across it into three tets around the
 * new edge joining the two apexes. Returns 1 with *c filled when the face is
 * interior, unconstrained, between tets of one tag, and the three new tets all
 * have a mean ratio above qmin_old + margin; else 0. */
int flip_23_eval(const tmesh *tm, int32_t t, int f, double floor4, double margin,
                 flip_cand *c);

/* Multi-face removal (Stellar's removemultiface, the inverse of edge removal):
 * the faces sandwiched between the apexes a (of t, opposite face f) and b (across
 * f), a disk of F faces whose boundary is a ring of F + 2 vertices, with the 2F
 * tets on them, become the F + 2 tets around the new edge ab. The disk grows
 * from face f one face at a time, each time by the face that makes the worst new
 * tet best, up to a ring of maxring (a single face is the 2-3 flip, left to
 * flip_23_eval). Returns 1 with *c filled for the best disk of two faces or
 * more whose new tets all have a mean ratio above qmin_old + margin; 0 when
 * none has, or f is constrained, on the boundary, between tags. No vertex
 * leaves the mesh: the disk never has a vertex inside it. */
int flip_multiface_eval(const tmesh *tm, int32_t t, int f, int maxring, double floor4,
                        double margin, flip_cand *c);

/* Boundary edge flip (Stellar's 2-2 boundary flip, mmg's boundary swap) under
 * a surface attached (tmesh_set_surface): the boundary edge e = ab of t, whose
 * open fan of n = 2..maxring - 1 tets runs from boundary triangle (a, b, c) to
 * (b, a, d) through unconstrained faces of one tag, becomes edge cd: the fan's
 * polygon c ... d triangulated best (as flip_edge_eval) over the new edge cd,
 * the boundary triangles (c, d, a) and (d, c, b). Allowed when the two
 * triangles carry one ref, quad acbd is convex seen across it, their normals
 * are within the feature angle, and the surface moves by at most bd->hausd
 * together with what the two faces moved before (c->dev: this move).
 * Returns 1 with *c filled when the new tets are above qmin_old + margin. */
int flip_bedge_eval(const tmesh *tm, int32_t t, int e, int maxring, double floor4,
                    double margin, const flip_bound *bd, flip_cand *c);

/* Peeling: t with exactly two boundary faces (a, b, c) and (b, a, d), one
 * ref, and two unconstrained interior faces is removed; (c, d, a) and (d, c,
 * b) become boundary faces of the tets across them. Allowed as for
 * flip_bedge_eval; taken when the tets across (the cavity's new minimum) are
 * above t's quality + margin. c->nnew is 0. */
int flip_peel_eval(const tmesh *tm, int32_t t, double margin, const flip_bound *bd,
                   flip_cand *c);

#endif
