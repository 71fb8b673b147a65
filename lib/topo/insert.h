/* insert.h - interior vertex insertion of the topology layer (Stellar's
 * insertion, Klingner and Shewchuk 2007, in its simplest cavity): a bad tet and
 * the tets across its unconstrained faces (one tag) are replaced by the star of
 * a new vertex placed inside them, when every cavity face is visible from it
 * (exact orient3d) and the cavity's smallest mean ratio rises (and, when
 * asked, its smallest dihedral angle does not fall).
 * No constrained face or edge is removed (the faces removed are the bad tet's
 * own unconstrained faces; every edge of the cavity stays on its outer faces);
 * the new vertex is interior (vcons 0). Thread safety: as tmesh. */
#ifndef QDC_INSERT_H
#define QDC_INSERT_H

#include "topo/tmesh.h"

/* Append a vertex at p (vcons 0); its index is tm->nv - 1. QDC_ENOMEM. */
qdc_status tmesh_add_vertex(tmesh *tm, const double p[3]);

/* Insert a vertex into the cavity of live tet t (above) when the cavity's
 * smallest mean ratio rises by at least margin (at least doubles, when it is
 * below margin) and, with angle 1, its smallest
 * dihedral angle does not fall (the vertex placed for the mean ratio first,
 * then the angle checked: a star that lifts the mean ratio with a thinner
 * angle is refused): *done 1 with the new tets'
 * slots in new_ids (room for 32) and their count in *nnew, the change journaled
 * (tmesh_commit keeps it, insert_undo undoes it, vertex included); else *done 0
 * and tm exactly as it was. QDC_ENOMEM. */
qdc_status insert_in_tet(tmesh *tm, int32_t t, double margin, int angle, int *done,
                         int32_t *new_ids, int *nnew);

/* The largest mean ratio of a tet on the face (a, b, c), whatever its fourth
 * corner (1 for an equilateral face, 0 for a degenerate one); reached with
 * the fourth corner over the centroid at a height of sqrt(2/9) times the root
 * of the sum of the face's squared edges. */
double insert_face_cap(const double *a, const double *b, const double *c);

/* Undo an insertion not yet committed: the journal rolled back and the vertex
 * it added removed. */
void insert_undo(tmesh *tm);

#endif
