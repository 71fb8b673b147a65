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
enum { FLIP_EDGE = 1, FLIP_23 = 2, FLIP_MULTIFACE = 3 };

typedef struct {
    int kind; /* FLIP_EDGE or FLIP_23 */
    int nold; /* tets removed (the ring, or the two tets of the face) */
    int nnew; /* tets made */
    int32_t old[2 * FLIP_MAXRING];
    int32_t newt[2 * FLIP_MAXRING][4];
    double qmin_old, qmin_new; /* smallest mean ratio in the cavity before, after */
    double gain;               /* sum of (1 - q) over the old tets less over the new */
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

#endif
