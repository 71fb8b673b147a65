/* slide.h - sliding boundary constraints (issue: boundary mode `slide`).
 * Boundary and interface vertices may move along the INPUT surfaces: a vertex
 * on a smooth part slides on the surface (projected back to the closest point
 * of the input triangles), a vertex on a feature line (boundary edges whose
 * faces meet at a dihedral sharper than the feature angle) slides along that
 * line, and corners (3+ feature edges, or a feature-line end) stay fixed.
 * Vertices where an interface meets the outer boundary stay fixed too.
 * Thread-safe: the context is read-only once built. */
#ifndef QDC_SLIDE_H
#define QDC_SLIDE_H

#include "core/mesh_int.h"

enum { SLIDE_INTERIOR = 0, SLIDE_SURFACE, SLIDE_LINE, SLIDE_CORNER };

typedef struct slide_ctx slide_ctx;

/* x0: input coordinates (3 per vertex) that define the surfaces to keep.
 * feature_angle: degrees between adjacent face normals that makes an edge a feature. */
qdc_status slide_new(const mesh_topo *tp, const double *x0, double feature_angle,
                     slide_ctx **out, qdc_error *err);
/* The same context for slide_kind and slide_flat only (the vertices' kinds
 * and the planar patches): no projection onto the input's triangles, so none
 * of their search trees (a tenth of a --topology round's setup). */
qdc_status slide_new_kinds(const mesh_topo *tp, const double *x0, double feature_angle,
                           slide_ctx **out, qdc_error *err);
void slide_free(slide_ctx *s);

int slide_kind(const slide_ctx *s, int32_t v);
int32_t slide_n_feature_edges(const slide_ctx *s);

/* v moves freely from now on (a run that leaves tets inverted where sliding
 * cannot undo them frees the boundary vertices around them): as an interior
 * vertex without a bound, anywhere within the bound of its input position
 * with one (slide_set_bound first), so the bound still holds. unbounded: an
 * interface vertex (on no boundary face) moves as an interior vertex even
 * under a bound (a corner of a tet inverted where the input's interface is
 * folded: see local.c). */
void slide_release(slide_ctx *s, int32_t v, int unbounded);
/* A loose mask's values (run.h: opt_run_once's loose): released within the
 * bound, or unbounded as above. */
enum { SLIDE_LOOSE = 1, SLIDE_LOOSE_UNBOUNDED = 2 };
/* The freed vertices' bound instead, if larger than the bound. */
void slide_set_loose_bound(slide_ctx *s, double r);

/* Whether v is on a planar patch (surface vertex) or a straight feature line
 * (line vertex) of the input: sliding it changes nothing of the shape. */
int slide_flat(const slide_ctx *s, int32_t v);
/* Whether v may leave the input surface: a surface vertex on a curved part
 * when a bound or a lift is set (slide_set_bound, slide_set_lift). */
int slide_lifts(const slide_ctx *s, int32_t v);

/* Project p (a new position of vertex v) onto v's constraint set. With a
 * bound (slide_set_bound): vertices on planar patches and straight lines slide
 * freely (the shape is kept exactly); a surface vertex on a curved part moves
 * freely in space and a curved line's vertex along its line, both within the
 * bound of the input position. With a lift instead (slide_set_lift), a
 * curved-surface vertex slides and leaves the surface by at most the lift. */
void slide_project(const slide_ctx *s, int32_t v, const double p[3], double out[3]);
/* The same without the bound. */
void slide_project_free(const slide_ctx *s, int32_t v, const double p[3], double out[3]);
/* --hausd: no boundary or interface vertex off a planar patch or a straight
 * line farther than r from its input position (0: no bound). A triangle of a
 * planar patch stays in the patch's plane; any other output boundary triangle
 * lies within r of its input triangle point for point where all its corners
 * are bounded (the same convex combination of corners that moved by at most
 * r), and within r of the patch's plane where some corners slide on it. */
void slide_set_bound(slide_ctx *s, double r);
/* Without a bound: surface vertices on curved parts may leave the input
 * surface by at most r (they slide on it, then move off it by at most r), so
 * every boundary vertex stays within r of the input surface (0: none). */
void slide_set_lift(slide_ctx *s, double r);
/* p pulled back along the segment to within r of x0's vertex v. */
void slide_clamp(const double *x0, int32_t v, double r, double p[3]);
/* Project a direction onto the tangent space of v's constraint (plane or line;
 * unchanged for a vertex that slide_lifts). */
void slide_tangent(const slide_ctx *s, int32_t v, const double g[3], double out[3]);

/* Ears on smooth parts: tets with 4 boundary corners and two boundary faces
 * whose common edge is not a feature (or three boundary faces). Such a tet's
 * shape is pinned by how much the surface bends there, and sliding its
 * corners over a piecewise-flat input surface can squash it flat. Sets
 * ear[t] (nt entries) and returns how many, or -1 if out of memory. */
int32_t slide_smooth_ears(const slide_ctx *s, const mesh_topo *tp, uint8_t *ear);

#endif
