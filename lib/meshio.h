/* meshio.h - mesh file formats. Parsers take (buf, len): they check every size
 * against the buffer, every index against bounds, reject NaN/Inf, and say
 * where (err->line/col for text, err->offset for binary). Indices in files are
 * converted to 0-based here and nowhere else. Writers stream through a
 * qdc_write_fn, never building the output in memory.
 * Thread-safe: no global state. */
#ifndef QDC_MESHIO_H
#define QDC_MESHIO_H

#include "base.h"
#include "mesh.h"

#include <stddef.h>

typedef enum {
    MESHIO_AUTO = 0, /* by extension, else by sniffing the content */
    MESHIO_MEDIT,    /* .mesh ASCII (Vertices, Tetrahedra with refs = regions, Triangles kept) */
    MESHIO_TETGEN,   /* .node + .ele (+ attributes as regions) */
    MESHIO_QMESH,    /* proto/mesh-binary.md, application/vnd.qdc.mesh, .qmesh */
    MESHIO_JSON,     /* {"vertices":[[x,y,z],...],"tets":[[a,b,c,d],...],"regions":[...]} 0-based */
    MESHIO_FORMAT_COUNT
} meshio_format;

/* "medit", "tetgen", "qmesh", "json"; NULL for out-of-range values. */
const char *meshio_format_name(meshio_format f);
/* Accepts a format name ("medit", "mesh", "qmesh", "binary", "json", "tetgen"),
 * a file name or extension (".mesh", "x.node"); MESHIO_AUTO if unknown. */
meshio_format meshio_format_from_name(const char *s);
/* Guess from the first bytes: QDCMESH magic, '{', "MeshVersionFormatted"...;
 * MESHIO_AUTO if unknown. */
meshio_format meshio_sniff(const char *buf, size_t len);

/* Parse one buffer (not TETGEN: it needs two). fmt MESHIO_AUTO sniffs.
 * On success *out is a new mesh (free with mesh_free); on failure *out is NULL
 * and err says what and where. Does not call mesh_validate beyond bounds and
 * finiteness: callers validate. */
qdc_status meshio_read(const char *buf, size_t len, meshio_format fmt, mesh_t **out,
                       qdc_error *err);
qdc_status meshio_read_tetgen(const char *node, size_t node_len, const char *ele,
                              size_t ele_len, mesh_t **out, qdc_error *err);

/* Stream m in format fmt (not TETGEN: see meshio_save). */
qdc_status meshio_write(const mesh_t *m, meshio_format fmt, qdc_write_fn fn, void *ctx,
                        qdc_error *err);

/* Files: format from fmt, else from the extension, else by sniffing.
 * TetGen: path may be "base", "base.node" or "base.ele".
 * meshio_save writes a temporary file, fsyncs and renames it over path. */
qdc_status meshio_load(const char *path, meshio_format fmt, mesh_t **out, qdc_error *err);
qdc_status meshio_save(const char *path, meshio_format fmt, const mesh_t *m, qdc_error *err);

/* Read a whole file into a new buffer (free with qdc_free). */
qdc_status meshio_slurp(const char *path, char **buf, size_t *len, qdc_error *err);

#endif
