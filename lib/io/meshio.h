/* meshio.h - mesh file formats. Parsers take (buf, len): they check every size
 * against the buffer, every index against bounds, reject NaN/Inf, and say
 * where (err->line/col for text, err->offset for binary). Indices in files are
 * converted to 0-based here and nowhere else. Writers stream through a
 * qdc_write_fn, never building the output in memory.
 * Thread-safe: no global state. */
#ifndef QDC_MESHIO_H
#define QDC_MESHIO_H

#include "core/base.h"
#include "core/mesh.h"

#include <stddef.h>

/* Formats: one per line of io/formats.h, in its order (the format table);
 * each format's file (io/meshio_*.c) says what it reads and writes.
 * Gmsh .msh: tetrahedra (type 4) with their physical tag as region, triangles
 * (type 2) kept with theirs as tri_ref; physical tag 0 means none, and a file
 * without physical groups but with several volume entities gets the entity
 * tags as regions. Other element types are skipped with a note. Both
 * vertices of every $Periodic node pair are held (m->fixed, with a note),
 * so a pair never moves apart; tags of no node are ignored. Higher-order
 * tetrahedra (types 11, 29-31) are refused (QDC_EFORMAT), as are VTK
 * types 24 and 71, Medit TetrahedraP2 and 10-node TetGen tets. Reading
 * accepts 4.1 ASCII/binary, 4.0 ASCII and 2.x ASCII/binary whichever Gmsh
 * variant is named.
 * VTK: cells of type 10 (tets) and 5 (triangles); region from the cell
 * array "region", "gmsh:physical" or "medit:ref" (written as "region"),
 * vref from the point array "medit:ref", the other point arrays as point
 * data (mesh.h; VTK, VTU and Gmsh $NodeData, written back by their writers:
 * meshio_writes_pdata). Reading accepts either encoding.
 * Formats without a media type are named by ?format= in the daemon. Every
 * format has a writer of qdc's own (MED's writes the frames qdc-h5 med-new
 * makes a MED file of); a format without one would be written only as the
 * input with new coordinates (spliced), meshio_write refusing it for a mesh
 * without such a source. */
typedef enum {
    MESHIO_AUTO = 0, /* by extension, else by sniffing the content */
#define MESHIO_FORMAT(id, desc) MESHIO_##id,
#include "io/formats.h"
#undef MESHIO_FORMAT
    MESHIO_FORMAT_COUNT
} meshio_format;

/* The format's name in the table ("medit", "gmsh", "vtu-ascii"...; "auto"
 * for MESHIO_AUTO); NULL for out-of-range values. */
const char *meshio_format_name(meshio_format f);
/* What the table says of a format (the strings are static). */
typedef struct {
    const char *name;     /* as meshio_format_name */
    const char *aliases;  /* other names, space-separated, each also an extension */
    const char *about;    /* one line for people */
    const char *ext;      /* the extension written, without the dot */
    const char *input;    /* the file name qdcd keeps an upload under; NULL: none */
    const char *media;    /* as meshio_media_type; NULL: none */
    meshio_format family; /* the format its extension names (.msh: gmsh) */
    int writes;           /* as meshio_has_writer */
    int splices;          /* written back as its input with new coordinates */
} meshio_format_info;
/* 1 and *info filled for a format of the table, else 0 (AUTO, out of range). */
int meshio_format_info_of(meshio_format f, meshio_format_info *info);
/* The table as JSON: {"formats":[{"name", "aliases":[...], "about",
 * "extension", "family", "media_type" (or null), "upload" (qdcd takes it as
 * a job's input: one file), "result" (and writes a result in it), "splice"
 * (written back as its input with new coordinates)}, ...], "surfaces":
 * [{"name", "extension", "media_type"}, ...]} in the table's order, one entry
 * a line. What GET /v1/formats serves and `qdc formats` prints. */
qdc_status meshio_formats_json(qdc_write_fn fn, void *ctx, qdc_error *err);
/* Accepts a format name (the above, and "mesh", "binary", "msh", "msh41",
 * "msh22"...), a file name or extension (".mesh", "x.node", "a.msh", ".vtu");
 * MESHIO_AUTO if unknown. */
meshio_format meshio_format_from_name(const char *s);
/* Guess from the first bytes: QDCMESH magic, '{', "MeshVersionFormatted",
 * "$MeshFormat" (the version and encoding of its header line), "# vtk DataFile"
 * (ASCII or BINARY), "<?xml"/"<VTKFile"...; MESHIO_AUTO if unknown.
 * "$NOD" (MSH 1) and "$MeshFormat" of any version are Gmsh: reading says
 * which versions are supported. "<dolfin" in the first kB of an XML
 * document, "mesh3d" (Netgen), a first line starting with '*' (Abaqus),
 * the int32 words 1, 1..4, 3 in either byte order (Medit binary). */
meshio_format meshio_sniff(const char *buf, size_t len);

/* HTTP media types, for the daemon's Content-Type / Accept / 415 lists:
 * qmesh application/vnd.qdc.mesh, json application/json, medit model/x-medit,
 * gmsh model/vnd.gmsh (";version=2.2", ";encoding=binary" pick the variants),
 * vtk application/vnd.vtk (";encoding=ascii"), vtu application/vnd.vtk.vtu+xml
 * (";encoding=ascii"). TetGen (two files) and the formats after VTU_ASCII
 * have none: NULL, as for AUTO and out-of-range values. The string is static. */
const char *meshio_media_type(meshio_format f);
/* 1 if meshio_write writes f for any mesh (qdc has a writer of its own; MED:
 * the frames of qdc-h5 med-new), 0 for a format written only over its own
 * source (spliced: none today), AUTO and out-of-range values. TetGen counts:
 * meshio_save writes its two files. */
int meshio_has_writer(meshio_format f);
/* 1 if qdc's writer of f writes second-order tets (mesh_t.mid) with their ten
 * nodes; 0 for the writers of linear tets (DOLFIN, MSH 1...), which write such
 * a mesh only spliced over its source, and for formats without a writer. */
int meshio_writes_p2(meshio_format f);
/* 1 if qdc's writer of f writes point data (mesh_t.pdata: VTK POINT_DATA
 * FIELD arrays, VTU <PointData>, Gmsh $NodeData), 0 for the writers that
 * drop it and for formats without a writer. */
int meshio_writes_pdata(meshio_format f);
/* The format of a Content-Type or Accept entry: case-insensitive, parameters
 * after ';' honoured as above, others (charset, q) ignored; also accepts
 * application/x-gmsh, model/x-gmsh, application/x-vtk, application/x-vtu,
 * text/x-medit. MESHIO_AUTO if unknown or NULL (surfaces: see surface.h). */
meshio_format meshio_format_from_media_type(const char *content_type);

/* Optional reading options: notes (skipped element types...) go to log.
 * source: keep the input for a spliced write (below): 0 the default
 * (meshio_load*: yes, meshio_read*: no), 1 yes, -1 no.
 * max_bytes, max_ratio: what compressed input may inflate to (a gzip file,
 * the zlib arrays of a VTU file), checked while inflating (QDC_ETOOBIG):
 * at most max_bytes (0: GZ_MAX_OUT, 4 GiB) and, with max_ratio > 0, at most
 * max_ratio times the compressed size (gz_budget). A gzip file holding
 * another is refused (QDC_EPARSE). */
typedef struct {
    qdc_log_fn log;
    void *log_ctx;
    int source;
    size_t max_bytes;
    unsigned max_ratio;
} meshio_options;

/* The gzip stream buf[0..len) inflated as a gzip input file is when read:
 * within o's max_bytes and max_ratio (o may be NULL: GZ_MAX_OUT), a gzip
 * file inside refused. *plain: a new NUL-terminated buffer (qdc_free) of
 * *plen bytes, NULL on failure. QDC_EPARSE (corrupt, truncated, compressed
 * twice), QDC_ETOOBIG (over the limit), QDC_ENOMEM. */
qdc_status meshio_gunzip(const char *buf, size_t len, const meshio_options *o,
                         char **plain, size_t *plen, qdc_error *err);

/* Parse one buffer (not TETGEN: it needs two). fmt MESHIO_AUTO sniffs.
 * On success *out is a new mesh (free with mesh_free); on failure *out is NULL
 * and err says what and where. Does not call mesh_validate beyond bounds and
 * finiteness: callers validate. */
qdc_status meshio_read(const char *buf, size_t len, meshio_format fmt, mesh_t **out,
                       qdc_error *err);
/* meshio_read with options (o may be NULL). */
qdc_status meshio_read_ex(const char *buf, size_t len, meshio_format fmt,
                          const meshio_options *o, mesh_t **out, qdc_error *err);
/* TetGen's pair from memory: node[0..node_len) (.node) and ele[0..ele_len)
 * (.ele), read only. On QDC_OK *out is a new mesh the caller frees with
 * mesh_free; on any other status *out is untouched and err says why. */
qdc_status meshio_read_tetgen(const char *node, size_t node_len, const char *ele,
                              size_t ele_len, mesh_t **out, qdc_error *err);

/* Stream m in format fmt (not TETGEN: see meshio_save); spliced when fmt is
 * its source's (below). MESHIO_AUTO: the source's format (QDC_EINVAL if m
 * has no source). */
qdc_status meshio_write(const mesh_t *m, meshio_format fmt, qdc_write_fn fn, void *ctx,
                        qdc_error *err);

/* Files: format from fmt, else from the extension, else by sniffing.
 * TetGen: path may be "base", "base.node" or "base.ele".
 * meshio_load reads path (gunzipped if compressed) into a new mesh *out, which
 * the caller frees with mesh_free; on failure *out is untouched and err says
 * why (QDC_EIO for the file, QDC_EPARSE/QDC_EMESH for its contents). */
qdc_status meshio_load(const char *path, meshio_format fmt, mesh_t **out, qdc_error *err);
/* meshio_load with reading options o (may be NULL; only read). */
qdc_status meshio_load_ex(const char *path, meshio_format fmt, const meshio_options *o,
                          mesh_t **out, qdc_error *err);
/* Write m (only read) to path in fmt: a temporary file beside it, fsynced and
 * renamed over path, so path holds the old file or the whole new one, never
 * a part; compressed when path ends in .gz. QDC_EIO with err on failure. */
qdc_status meshio_save(const char *path, meshio_format fmt, const mesh_t *m,
                       qdc_error *err);
/* len bytes saved to path as meshio_save saves a mesh: a file through a
 * temporary file and a rename (its permissions kept; a symbolic link stays
 * one, the file it names replaced), a pipe or device (/dev/stdout) straight
 * into; gzip-compressed when path ends in .gz. */
qdc_status meshio_save_bytes(const char *path, const void *buf, size_t len,
                             qdc_error *err);

/* 1 if buf[0..len) starts with the HDF5 signature (a MED file, an XDMF's .h5). */
int meshio_is_hdf5(const void *buf, size_t len);

/* XDMF whose heavy data is in HDF5 (Format="HDF", "file.h5:/dataset"):
 * libqdc never calls HDF5; the qdc command has the qdc-h5 program read the
 * datasets (meshio_xdmf.c says how). meshio_xdmf_h5_refs: the datasets the
 * mesh takes from the HDF5 file (n = 0: none, the data is inline), from the
 * XML buf[0..len); every reference must name one file, relative and inside
 * the .xdmf's folder (QDC_EFORMAT otherwise). */
typedef struct {
    char file[1024]; /* the HDF5 file as the XML names it ("mesh.h5") */
    int n;
    struct {
        char name[16];   /* the frame qdc-h5 gives it as: "geometry", "topology",
                            "region"; a dolfinx MeshTags grid's "tagtopo",
                            "tagvals" (tets), "tritopo", "trivals" (facets) */
        char type;       /* 'f' float64, 'i' int64, 'a' either, as the dataset
                            holds (an attribute with no NumberType; qdc-h5
                            frames it 'i' or 'f', so it reports the class) */
        char path[1024]; /* the dataset ("/data0") */
        int ndims;       /* the shape the XML gives it */
        int64_t dims[4];
    } set[7];
} meshio_xdmf_h5;
qdc_status meshio_xdmf_h5_refs(const char *buf, size_t len, meshio_xdmf_h5 *h,
                               qdc_error *err);
/* The input meshio_read takes as MESHIO_XDMF: the XML and the frames qdc-h5
 * printed for the datasets above, in a new buffer *out (qdc_free). Such a
 * mesh is written back spliced as this same form, the geometry's values
 * replaced. */
qdc_status meshio_xdmf_h5_input(const char *xml, size_t xml_len, const char *frames,
                                size_t frames_len, char **out, size_t *out_len,
                                qdc_error *err);
/* The same in place, without a copy of the frames: buf[0..len) holds
 * meshio_xdmf_h5_room(xml_len) bytes of room, then the frames; the room is
 * filled with the XML and what the form needs around it. */
size_t meshio_xdmf_h5_room(size_t xml_len);
qdc_status meshio_xdmf_h5_fill(char *buf, size_t len, const char *xml, size_t xml_len,
                               qdc_error *err);
/* The XML buf[0..len) through fn with every HDF reference naming file
 * instead (the only change): the .xdmf of a copy of its .h5. QDC_EINVAL for
 * a name XML or XDMF cannot hold (&<>"': in it), QDC_EIO if fn fails. */
qdc_status meshio_xdmf_h5_rename(const char *buf, size_t len, const char *file,
                                 qdc_write_fn fn, void *ctx, qdc_error *err);

/* Spliced writing. qdc never changes connectivity, so a mesh can be written
 * back as the very file it was read from with only the coordinates
 * replaced: every tag, name, boundary or point element, $Periodic, data
 * array, comment, the numbering and the version stay byte for byte.
 * A mesh read with its source kept (m->source: the decompressed file and one
 * uint64 offset per vertex, 8 bytes/vertex beyond the file itself; three for
 * DOLFIN and Abaqus, whose coordinates are separate fields) is written
 * that way when the format asked for is the file's own variant (same
 * version and encoding; meshio_save with MESHIO_AUTO picks it when the
 * extension names the same family: .msh, .vtk, .vtu, .mesh, .meshb, .node,
 * .xml, .inp, .vol) and its
 * connectivity, regions, triangles and refs are unchanged since reading
 * (checked by a hash; the fixed flags are not part of it). Text numbers are
 * printed with %.17g (an unmoved coordinate keeps its original text), in a
 * float32 field (VTK `float`, VTU Float32 ascii) as the float32 value with
 * %.9g; binary values are overwritten in their own width and byte order:
 * float32 stays float32. Values derived from the coordinates are recomputed: Gmsh 4.x
 * $Entities bounding boxes (each bound shifted by how far the bound of the
 * entity's nodes, closure included, moved) and VTU Points RangeMin/RangeMax
 * (the range of the point norms); unchanged ones keep their bytes. VTU Points under zlib
 * or base64 are re-encoded the same way (zlib blocks of the same size), and the offset=""
 * of the appended arrays after them shifted by the change in size. Spliced: Medit .mesh,
 * TetGen .node/.ele, Gmsh MSH 2.x ASCII/binary, 4.0 ASCII and 4.1 ASCII/binary, legacy
 * VTK ASCII and binary, VTU ascii, base64, appended raw/base64, zlib-compressed or not.
 */

/* The format of the file m's source holds, or MESHIO_AUTO if none is kept. */
meshio_format meshio_source_format(const mesh_t *m);
/* 1 if writing m in fmt splices its source (see above); 0 with *why (static
 * text, may be NULL) otherwise. */
int meshio_splices(const mesh_t *m, meshio_format fmt, const char **why);
/* The format meshio_save(path, fmt, m) writes: fmt, else the source's own
 * variant if the extension names its family, else by extension; AUTO if none. */
meshio_format meshio_save_format(const char *path, meshio_format fmt, const mesh_t *m);
/* src if named is of src's family (an extension names a family: .msh is every
 * Gmsh variant), else named. */
meshio_format meshio_format_variant(meshio_format named, meshio_format src);
/* Bytes held by m's source in memory (0 if none); *float32 set if its coordinates are
 * stored as float32 (may be NULL). */
size_t meshio_source_bytes(const mesh_t *m, int *float32);
/* Forget m's source (frees it). */
void meshio_drop_source(mesh_t *m);
/* A source read from a file by meshio_load* (not TetGen's two files) can be
 * parked while the mesh is optimized: its bytes are freed (a hash kept) and
 * meshio_unpark_source reads the file again, gunzipped if it is compressed,
 * and takes it back only if it is byte for byte the same (QDC_EIO "changed
 * since it was read" otherwise; the mesh then does not splice). Parking
 * returns 1 if it freed the bytes, 0 if there was nothing to park. While
 * parked, the mesh does not splice. */
int meshio_park_source(mesh_t *m);
/* Take a parked source of m back (see above): QDC_OK with m splicing again,
 * or QDC_EIO (file gone or changed) with m kept as it is, not splicing. */
qdc_status meshio_unpark_source(mesh_t *m, qdc_error *err);

/* Read a whole file into a new buffer (free with qdc_free). */
qdc_status meshio_slurp(const char *path, char **buf, size_t *len, qdc_error *err);
/* meshio_slurp, and the contents decompressed if the file is gzip. */
qdc_status meshio_slurp_plain(const char *path, char **buf, size_t *len, qdc_error *err);

#endif
