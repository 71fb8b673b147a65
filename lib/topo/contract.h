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

#include "topo/tmesh.h"

enum { CONTRACT_MAX = 48 }; /* tets around the vertex that goes, at most */

typedef struct {
    int32_t gone, keep; /* u, w */
    int nold, nnew;
    int32_t old[CONTRACT_MAX];
    int32_t newt[CONTRACT_MAX][4];
    double qmin_old, qmin_new; /* smallest mean ratio of u's tets, of the new */
    double gain;               /* sum of (1 - q) over the old tets less over the new */
} contract_cand;

/* The better direction (larger new minimum, then gain, then the smaller
 * vertex going) of contracting edge e (tmesh_edge) of live tet t: 1 with *c
 * filled, 0 when neither is legal (above) or improves. */
int contract_eval(const tmesh *tm, int32_t t, int e, double floor4, double margin,
                  contract_cand *c);

#endif
