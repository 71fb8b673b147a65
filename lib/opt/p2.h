/* p2.h - second-order (10-node) tets after a run on their corners (p2.c):
 * the Jacobian of the quadratic element, the mid-edge nodes moved with their
 * edges, boundary ones put back on the input's curved surface, and elements
 * whose Jacobian turned non-positive at a node straightened until it is not.
 * A 10-node element here is x[10][3]: corners 0-3, then the mid-edge nodes of
 * mesh_p2_edges (01, 12, 02, 03, 13, 23). Thread-safe: no global state. */
#ifndef QDC_P2_H
#define QDC_P2_H

#include "core/mesh.h"
#include "opt/opt.h"

/* The Jacobian determinant of the element x at barycentric point (r, s, t)
 * of the reference tet (corner 0 at the origin, corners 1, 2, 3 on the
 * axes); for straight edges it is 6 times the signed volume everywhere. */
double p2_jacobian(const double x[10][3], double r, double s, double t);
/* The smallest Jacobian determinant at the 10 nodes and the centroid,
 * divided by that of the straight tet of the same corners (so 1 for a
 * straight element, <= 0 for one a solver refuses); -1 if the straight tet
 * is flat. */
double p2_scaled_jacobian(const double x[10][3]);
/* The closest point cp to p on the quadratic triangle x (corners 0, 1, 2,
 * then the mid-edge nodes of 01, 12, 02), by Gauss-Newton from the
 * barycentric (uv[0], uv[1]) of corners 1 and 2, kept in the triangle; uv
 * receives where it ended. Returns the distance. */
double p2_tri_closest(const double x[6][3], const double p[3], double uv[2],
                      double cp[3]);

/* After a run moved m's corners from xyz_in (3*m->nv, the input's
 * coordinates, the mid-edge nodes where they were): each mid-edge node whose
 * edge moved goes to the new midpoint plus its input offset from the old one
 * mapped by the affine map of the corners of each tet around the edge (the
 * average of those maps: exact when the corners moved by one affine map);
 * one on a boundary edge is then projected to the input's curved boundary
 * (its quadratic triangles); then every element whose scaled Jacobian fell
 * below both its input's and 0.2 (where the input's was > 0) has its
 * mid-edge nodes pulled toward the straight midpoints until it is not
 * (interior ones first). m->mid must
 * be set; m->xyz changes at the mid-edge nodes only. res receives the counts
 * (opt_result's p2_* fields). QDC_ENOMEM. */
qdc_status p2_finish(mesh_t *m, const double *xyz_in, opt_result *res, qdc_error *err);

#endif
