/* format.h - what a mesh format module gives meshio.c: one descriptor
 * (meshio_fmt) per format, registered by one line of formats.h. Internal to
 * lib/io. */
#ifndef QDC_FORMAT_H
#define QDC_FORMAT_H

#include "io/meshio.h"
#include "io/meshio_scan.h"

/* Sniffing: buf[0, len) is the start of a file, i the first byte after
 * blanks and '#' comment lines. Return the format (the variant, for a
 * family: the version and encoding the content says), or MESHIO_AUTO.
 * Formats with magic set are asked first, in table order, then the others. */
typedef meshio_format (*meshio_sniff_fn)(const char *buf, size_t len, size_t i);
/* Reading one plain buffer; rec NULL, or to be filled for a spliced write
 * (rec->fmt set to the variant read; left MESHIO_AUTO: no splicing). */
typedef qdc_status (*meshio_read_fn)(const char *buf, size_t len, const meshio_options *o,
                                     srcrec *rec, mesh_t **out, qdc_error *err);
/* Writing m as fmt (the descriptor's own format) through w; part 1 is
 * TetGen's .ele (0 for every other format). */
typedef qdc_status (*meshio_write_fn)(const mesh_t *m, meshio_format fmt, int part,
                                      wbuf *w, qdc_error *err);

typedef struct {
    const char *name;      /* the format's name: --format, ?format=, /v1/formats */
    const char *aliases;   /* other names, space-separated; each also names the
                              format as a file extension ("msh msh41") */
    const char *about;     /* one line for people: "Gmsh MSH 4.1 ASCII" */
    const char *ext;       /* the extension written, without the dot ("msh") */
    const char *input;     /* the file name qdcd stores an upload under, or NULL
                              (not uploaded: TetGen is two files) */
    meshio_format family;  /* the format an extension names (.msh: GMSH41);
                              MESHIO_AUTO: itself */
    const char *media;     /* the media type written, with the parameter that
                              selects this variant ("model/vnd.gmsh;version=2.2"),
                              or NULL */
    const char *media_alt; /* other media types read as this one, space-separated */
    int magic;             /* sniff looks at the first bytes, not after blanks */
    meshio_sniff_fn sniff; /* NULL: another variant of the family sniffs */
    meshio_read_fn read;
    meshio_write_fn write; /* NULL: written only spliced, over its own source */
    int splices;           /* written back as its source with new coordinates */
    int p2;                /* write writes second-order tets (mesh_t.mid) with their
                              ten nodes; 0: such a mesh is written only spliced */
    int pdata;             /* write writes point data (mesh_t.pdata) */
} meshio_fmt;

#define MESHIO_FORMAT(id, desc) extern const meshio_fmt desc;
#include "io/formats.h"
#undef MESHIO_FORMAT

/* The framed form qdc-h5 prints (meshio_med.c says what it is), read by MED
 * and by XDMF with its heavy data in HDF5. */
typedef struct {
    uint64_t at, n; /* byte offset of the first value; value count ('b': bytes) */
    int type;       /* 'f' float64, 'i' int64, 'b' bytes; 0: absent */
} h5_frame;
extern const char h5_magic[8];
/* The frames of buf[0..len) (h5_magic first): fr[k] (count of them) gets
 * the one named names[k], which must be of type types[k] ('?': 'f' or 'i',
 * whichever the dataset holds); others are skipped. QDC_EPARSE, the message starting with
 * what ("MED"). */
qdc_status h5_frames(const char *buf, size_t len, const char *what,
                     const char *const *names, const char *types, int count, h5_frame *fr,
                     qdc_error *err);

/* The descriptor of f, or NULL (MESHIO_AUTO, out of range). */
const meshio_fmt *meshio_fmt_of(meshio_format f);

/* The number a group or set name of qdc's writers holds: prefix, then the
 * decimal digits, "M" before a negative number's ("REGION_12", "SURFACE_M3");
 * 1 and *n if [v, ve) is such a name, else 0 (meshio_fe.c). */
int meshio_name_number(const char *v, const char *ve, const char *prefix, int32_t *n);
/* The mid-edge nodes of second-order m's triangles (edges 01, 12, 20 of
 * each, 3 ntri into mid), from a tet each is a face of; *all 0 if some
 * triangle is the face of no tet (mid then partly filled). QDC_ENOMEM with
 * err (meshio_fe.c). */
qdc_status meshio_tri_mids(const mesh_t *m, int32_t *mid, int *all, qdc_error *err);

/* TetGen's two buffers, rec NULL or filled (meshio.c loads the pair). */
qdc_status meshio_tetgen_read2(const char *node, size_t node_len, const char *ele,
                               size_t ele_len, srcrec *rec, mesh_t **out, qdc_error *err);

#endif
