/* tetra.h - tetrahedralize a closed triangle surface with TetGen 1.5
 * (libtet, AGPL-3.0-or-later) through a small C++ bridge (tetra.cpp).
 * The surface is checked first (surface_check) so the usual mistakes get a
 * clear QDC_EMESH; what only TetGen finds (self-intersections, features
 * below its tolerance) comes back as QDC_ETETGEN with TetGen's reason.
 * TetGen never exits or aborts the process here: it is built as a library
 * (TETLIBRARY: errors are thrown) and the bridge catches every exception.
 * TetGen may still print to stdout on errors; 'Q' silences the rest.
 * Thread-safe: no global mutable state of ours (TetGen's predicates set up
 * constants once, the same each time). Public (qdc.h). */
#ifndef QDC_TETRA_H
#define QDC_TETRA_H

#include "core/base.h"
#include "core/mesh.h"
#include "io/surface.h"

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double quality; /* radius-edge ratio bound (TetGen -q), >= 1; 0 = no refinement */
    double min_dihedral; /* minimum dihedral angle in degrees (-q/.. second value); 0 =
                            TetGen's */
    double max_volume;   /* maximum tet volume (-a); 0 = none */
    int32_t max_steiner; /* cap on added points (-S), bounds the work; 0 = none */
} tetra_options;

/* Fill *o with the defaults: quality 2 (TetGen's -q default), no dihedral
 * bound, no volume bound, no cap. */
void tetra_defaults(tetra_options *o);

/* Tetrahedralize the surface (xyz: 3*nv, tris: 3*ntri 0-based). On success
 * *out is a new mesh (mesh_free) whose tets are positively oriented and whose
 * region is the subdomain TetGen numbered (1, 2, ... for nested or separate
 * closed parts). The arrays and o (may be NULL: defaults) are only read.
 * may fail: QDC_EINVAL (an option out of range), QDC_EMESH (surface_check),
 * QDC_ETETGEN, QDC_ENOMEM; *out is then NULL. */
qdc_status tetra_from_surface(const double *xyz, int32_t nv, const int32_t *tris,
                              int32_t ntri, const tetra_options *o, mesh_t **out,
                              qdc_error *err);

/* The same for a surface_t: its facet markers (tri_ref) become the mesh's
 * boundary triangles with refs (m->tris, m->tri_ref), its hole points carve
 * volumes out and its region seeds set the regions (and local max volumes).
 * s and o (may be NULL) are only read; *out and the statuses as
 * tetra_from_surface. */
qdc_status tetra_from_surface_t(const surface_t *s, const tetra_options *o, mesh_t **out,
                                qdc_error *err);

/* One call for a surface in a buffer (the daemon's upload): surface_read of
 * the len bytes at buf (only read), then tetra_from_surface_t; the statuses
 * of both. On success *out is a new mesh the caller owns (mesh_free). */
qdc_status tetra_from_buffer(const char *buf, size_t len, surface_format fmt,
                             const tetra_options *o, mesh_t **out, qdc_error *err);

#ifdef __cplusplus
}
#endif

#endif
