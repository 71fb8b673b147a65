/* surface.h - closed triangle surfaces to be tetrahedralized (lib/tetra.h):
 * STL (ASCII and binary), OFF, OBJ, TetGen .poly and .smesh.
 * Parsers take (buf, len) like meshio's: every count is checked against the
 * bytes left, NaN/Inf are rejected, errors say err->line/col (text) or
 * err->offset (binary STL). Polygons are split into fans of triangles and
 * vertices with exactly equal coordinates are merged (STL repeats them per
 * triangle), so the result is an indexed triangle surface.
 * Public (qdc.h). Thread-safe: no global state. */
#ifndef QDC_SURFACE_H
#define QDC_SURFACE_H

#include "core/base.h"

#include <stddef.h>
#include <stdint.h>

typedef enum {
    SURFACE_AUTO = 0,
    SURFACE_STL,   /* .stl, model/stl: ASCII "solid ..." or binary */
    SURFACE_OFF,   /* .off, model/x-off */
    SURFACE_OBJ,   /* .obj, model/obj: v and f lines, the rest ignored */
    SURFACE_POLY,  /* TetGen .poly: nodes, facets (markers), holes, regions */
    SURFACE_SMESH, /* TetGen .smesh: as .poly with the nodes inline */
    SURFACE_FORMAT_COUNT
} surface_format;

typedef struct {
    int32_t nv, ntri;
    double *xyz;      /* 3*nv */
    int32_t *tris;    /* 3*ntri, 0-based */
    int32_t *tri_ref; /* ntri facet markers (.poly/.smesh), or NULL */
    int32_t nholes;   /* points inside volume holes (.poly/.smesh) */
    double *holes;    /* 3*nholes */
    int32_t nregions; /* region seeds (.poly/.smesh): x y z attribute maxvol */
    double *regions;  /* 5*nregions; maxvol <= 0 means none */
} surface_t;

/* Free s and its arrays. s may be NULL. */
void surface_free(surface_t *s);

/* The name of f: "stl", "off", "obj", "poly", "smesh" (static); NULL for
 * AUTO or out of range. */
const char *surface_format_name(surface_format f);
/* The format named by s, a name, extension or file name ("stl", ".OFF",
 * "a/b.obj"; only read); AUTO if unknown or NULL. */
surface_format surface_format_from_name(const char *s);
/* The format of the len bytes at buf (only read), from their content: binary
 * STL (84 + 50 n bytes), "solid", "OFF", OBJ "v " lines; AUTO if unknown. */
surface_format surface_sniff(const char *buf, size_t len);
/* model/stl (also application/sla, model/x.stl-binary, model/x.stl-ascii),
 * model/obj (text/plain not accepted), model/x-off, application/vnd.qdc.surface+poly
 * (TetGen .poly), application/vnd.qdc.surface+smesh; parameters ignored;
 * AUTO if unknown or NULL. */
surface_format surface_format_from_media_type(const char *content_type);
/* The media type of f (static), NULL for AUTO or out of range. */
const char *surface_media_type(surface_format f);

/* Parse the len bytes at buf (only read; fmt AUTO sniffs). On success *out
 * is a new surface the caller owns (surface_free);
 * on failure NULL, err says what and where (QDC_EPARSE, QDC_ETOOBIG, QDC_ENOMEM,
 * QDC_EFORMAT when the format is unknown). */
qdc_status surface_read(const char *buf, size_t len, surface_format fmt, surface_t **out,
                        qdc_error *err);
/* Read the file at path and parse it as surface_read: format from fmt, else
 * the extension, else sniffing. *out as surface_read; QDC_EIO when the file
 * cannot be read too. */
qdc_status surface_load(const char *path, surface_format fmt, surface_t **out,
                        qdc_error *err);

/* Can s bound a volume? QDC_EMESH with the first problem found (err->index,
 * err->kind "triangle" or "edge"): no triangles, an index out of range, a
 * degenerate triangle (repeated vertex or zero area), an edge not shared by
 * exactly two triangles (open or non-manifold surface), or two triangles on
 * an edge with the same orientation (inconsistently oriented). Self-
 * intersections are found by TetGen. s is only read; QDC_OK when none. */
qdc_status surface_check(const surface_t *s, qdc_error *err);

#endif
