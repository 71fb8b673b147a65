/* contract.h - interior edge contraction of the topology layer (Stellar's and
 * mmg's collapse, Netgen's 'c'): the edge uw of a bad tet, both ends interior
 * (on no constrained face: so the tets around them share one tag), goes by
 * moving u onto w: the tets around the edge vanish, the others around u take w
 * for u; vertex u is no longer used. Vertices stay where they are, so the
 * volume is kept exactly.
 * Legal when the link condition holds (the vertices next to both u and w are
 * those of the edge's ring, and no two ring vertices that are not a ring edge
 * share a tet with u), every new tet is positive by the exact predicate, none
 * has four constrained corners below floor4, and each beats the smallest mean
 * ratio of u's tets by margin. Thread-safe for concurrent reads of a tmesh. */
#ifndef QDC_CONTRACT_H
#define QDC_CONTRACT_H

#include "topo/flip.h"
#include "topo/tmesh.h"

enum { CONTRACT_MAX = 48 }; /* tets around the vertex that goes, at most */

typedef struct {
    int32_t gone, keep; /* u, w */
    int nold, nnew;
    int32_t old[CONTRACT_MAX];
    int32_t newt[CONTRACT_MAX][4];
    double qmin_old, qmin_new; /* smallest mean ratio of u's tets, of the new */
    double gain;               /* sum of (1 - q) over the old tets less over the new */
    int bnd;                   /* 1: a boundary edge (contract_bedge_eval) */
    double dev;                /* ... its bound on the surface's move */
} contract_cand;

/* The better direction (larger new minimum, then gain, then the smaller
 * vertex going) of contracting edge e (tmesh_edge) of live tet t: 1 with *c
 * filled, 0 when neither is legal (above) or improves. qfloor > 0: improving
 * by the gain instead (Netgen's combine): the sum of (1 - q) over u's tets
 * falls and every new tet's mean ratio is above qfloor, not above the
 * smallest of u's (a vertex among clustered ones goes, though the tets around
 * it were all better than the new ones will be). */
int contract_eval(const tmesh *tm, int32_t t, int e, double floor4, double margin,
                  double qfloor, contract_cand *c);

/* As contract_eval for a boundary edge uw (under a bound, a surface attached:
 * mmg's collapse of a short boundary edge, which removes the needle and cap
 * triangles at it): u's tets re-pointed at w, the two boundary triangles of the
 * edge removed, u's other boundary triangles (u, x, y) become (w, x, y). Legal
 * as above and when u is on the boundary only (no interface face at u), its
 * boundary triangles carry one ref and orientation rule (tmesh_replace_surface
 * checks), each keeps its normal within the feature angle (no fold), no
 * boundary edge wx exists but those of the edge's two triangles (the surface
 * stays a manifold), and the surface moves by at most bd->hausd with what its
 * removed triangles moved before. The move is bounded by the largest, over u's
 * triangles (u, x, y) without w, of the distances of w to (u, x, y) and of u
 * to (w, x, y): the distance to a triangle is convex, and every old and new
 * triangle shares two corners with one of the other side. c->dev is that. */
int contract_bedge_eval(const tmesh *tm, int32_t t, int e, double floor4, double margin,
                        const flip_bound *bd, contract_cand *c);

#endif
