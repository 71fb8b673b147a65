/* split.h - interior edge split of the topology layer (mmg's split of a long
 * edge at its midpoint, Stellar's edge insertion in its simplest form): the
 * tets around an unconstrained edge ab are each cut in two by a new vertex m at
 * the midpoint, (.. a .. b ..) -> (.. m .. b ..) and (.. a .. m ..); the outer
 * faces of the ring stay as they are, so no constrained face or edge is touched
 * and the new vertex is interior (vcons 0). Meant for a mesh whose interior is
 * coarse against its boundary (a fine surface kept with --boundary fixed): the
 * edges much longer than the sizes at their ends are split, and the smoother
 * and the flips after place and connect the new vertices.
 * Thread safety: as tmesh. */
#ifndef QDC_SPLIT_H
#define QDC_SPLIT_H

#include "topo/tmesh.h"

#include <stdatomic.h>

enum { SPLIT_MAXRING = 16 }; /* tets around a split edge, at most */

/* Split edge e (tmesh_edge) of live tet t at its midpoint when the edge is
 * unconstrained, its ring has at most SPLIT_MAXRING tets (none inverted), every
 * new tet is positive by the exact predicate and the smallest mean ratio of
 * the new tets is at least qfrac times the ring's: *done 1 with the new tets'
 * slots in new_ids (room for 2 * SPLIT_MAXRING) and their count in *nnew,
 * journaled (tmesh_commit keeps it, split_undo undoes it); else *done 0 and tm
 * exactly as it was. QDC_ENOMEM. */
qdc_status split_edge(tmesh *tm, int32_t t, int e, double qfrac, int *done,
                      int32_t *new_ids, int *nnew);

/* Undo a split not yet committed: the journal rolled back, its vertex removed. */
void split_undo(tmesh *tm);

/* One pass of splits: each vertex's size is the mean length of its edges (of
 * its constrained edges for a vertex on a constrained face: the surface's
 * size); the unconstrained edges longer than lratio times the mean size of
 * their ends are split (split_edge with qfrac), the relatively longest first
 * (ties by vertex ids), each edge of the mesh as the pass began at most once;
 * none when they are fewer than share times the mesh's edges (share 0: no
 * such condition; the edges counted by Euler's formula for a solid with one
 * closed boundary, nv + nt + (boundary faces) / 2 - 1).
 * *nsplit receives the count. cancel (may be NULL) is polled between splits:
 * QDC_ECANCEL, the mesh valid. QDC_ENOMEM. */
qdc_status split_long_edges(tmesh *tm, double lratio, double qfrac, double share,
                            int64_t *nsplit, const atomic_int *cancel);

#endif
