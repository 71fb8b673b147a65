/* cli.h - pieces shared by the qdc subcommands. */
#ifndef QDC_CLI_H
#define QDC_CLI_H

#include "qdc.h"

#include <stdio.h>

/* Exit codes (documented in README.md and `qdc --help`). */
enum {
    CLI_OK = 0,
    CLI_EUSAGE = 1,     /* bad command line */
    CLI_EINPUT = 2,     /* input file unreadable, malformed or invalid */
    CLI_EOPT = 3,       /* optimization failed */
    CLI_EOUTPUT = 4,    /* output could not be written */
    CLI_EINTR = 5,      /* interrupted (SIGINT/SIGTERM): best mesh so far was written */
    CLI_EREJECTED = 10, /* remote: the server rejected the request (4xx) */
    CLI_EJOB = 11,      /* remote: the job failed or was cancelled */
    CLI_ENETWORK = 12   /* remote: server unreachable or 5xx after retries */
};

/* A tet mesh from path, in any format qdc reads (fin, else by the name, else
 * by the contents); "-" is standard input, and a pipe or device is read once. */
qdc_status cli_load_mesh(const char *path, meshio_format fin, const meshio_options *mo,
                         mesh_t **m, qdc_error *err);

/* The file's bytes, decompressed if gzip; "-" is standard input. */
qdc_status cli_slurp(const char *path, char **buf, size_t *len, qdc_error *err);

/* A closed surface's format, by path's name, else (a name of no mesh format
 * either) by its contents, then left in *buf (decompressed, qdc_free; NULL if
 * not read); SURFACE_AUTO for a mesh. */
surface_format cli_input_surface(const char *path, char **buf, size_t *len);

/* cli_load_mesh, and the file's bytes (decompressed) in *raw (qdc_free), or
 * NULL for TetGen's two files. */
qdc_status cli_read_mesh(const char *path, meshio_format fin, const meshio_options *mo,
                         mesh_t **m, char **raw, size_t *rawlen, qdc_error *err);

/* m written to out: a file (meshio_save), or standard output for "-", in
 * fout, else the input's format, else Medit. */
qdc_status cli_save_mesh(const char *out, meshio_format fout, const mesh_t *m,
                         qdc_error *err);

/* With --topology (its name: topology) the tets change, and OUT in a format
 * qdc writes only over its source (meshio_has_writer: none today; MED was
 * until qdc-h5 med-new) cannot hold them: said on stderr, ending "nothing
 * was <what>", and 1; else 0. m: the input, read. */
int cli_topology_out_refused(const char *out, meshio_format fout, const mesh_t *m,
                             const char *topology, const char *what);

/* MED (HDF5) through the qdc-h5 child (h5.c). cli_h5_wanted: 1 if path is
 * to be read that way (fin MESHIO_MED, or a file that starts as HDF5 does).
 * cli_h5_read: the mesh (its source kept as mo says); cli_h5_write: m
 * written to out: the MED file cli_h5_read read it from with the new
 * coordinates, or, for a mesh that does not splice, a MED file of its own. */
/* A .gz file or standard input is inflated into a private temporary file
 * first (cli_h5_bytes: 1 if buf is such an HDF5 file; cli_h5_read_bytes: read
 * it, shown as name). */
int cli_h5_wanted(const char *path, meshio_format fin);
int cli_h5_bytes(const char *buf, size_t len);
qdc_status cli_h5_read(const char *path, const meshio_options *mo, mesh_t **m,
                       qdc_error *err);
qdc_status cli_h5_read_bytes(const char *name, const char *buf, size_t len,
                             const meshio_options *mo, mesh_t **m, qdc_error *err);
qdc_status cli_h5_write(const char *out, const mesh_t *m, qdc_error *err);

/* XDMF whose heavy data is in HDF5 (h5.c): the datasets read by qdc-h5 from
 * the .h5 file the XML names, in the .xdmf file's folder.
 * cli_xdmf_h5_retry: after a read of path failed with st, the mesh read
 * that way if path is such an XDMF file, else st (err as it was).
 * cli_xdmf_h5_source: 1 if m is to be written so (read that way, splicing);
 * cli_xdmf_h5_write: out (.xdmf) written with a copy of the .h5 file beside
 * it, named as out with .h5 for its extension, only the coordinates
 * changed. */
qdc_status cli_xdmf_h5_retry(const char *path, qdc_status st, const meshio_options *mo,
                             mesh_t **m, qdc_error *err);
int cli_xdmf_h5_source(const mesh_t *m);
qdc_status cli_xdmf_h5_write(const char *out, const mesh_t *m, qdc_error *err);
/* The XDMF file that cli_xdmf_h5_retry read, named name, and its .h5 file as
 * a multipart/form-data body with the boundary b (parts "xdmf" and "h5",
 * what `qdc submit` sends qdcd) into fn. */
qdc_status cli_xdmf_h5_form(const char *name, const char *b, qdc_write_fn fn, void *ctx,
                            qdc_error *err);

/* One-line error in the form "qdc: FILE:LINE:COL: message". */
void cli_error(const char *path, const qdc_error *err, qdc_status st);

/* The candidate nearest to word by edit distance (insertions, deletions,
 * substitutions, swaps of neighbours; '-' and '_' alike), or a candidate word
 * is the start of; NULL when none is within about a third of word's length. */
const char *cli_suggest(const char *word, const char *const *cands, size_t n);

/* `qdc optimize --help` (help.c): the options in groups, each word explained. */
void cli_optimize_usage(FILE *f);
/* The option of `qdc optimize` nearest to a mistyped flag ("--bondary") into
 * buf ("--boundary"): 1, or 0 when none is near. */
int cli_optimize_suggest(const char *flag, char *buf, size_t len);

int cli_optimize(int argc, char **argv);
int cli_quality(int argc, char **argv);
/* qdc convert IN OUT: read and write (spliced when OUT is in IN's format). */
int cli_convert(int argc, char **argv);
/* qdc options: the library's option table as JSON on stdout. */
int cli_options(int argc, char **argv);
/* qdc formats: the library's format table as JSON (as GET /v1/formats). */
int cli_formats(int argc, char **argv);
/* qdc tetra IN OUT: tetrahedralize a surface (also run by qdcd, in a child). */
int cli_tetra(int argc, char **argv);
/* submit, status, watch, fetch, cancel, jobs (remote.c); argv[0] is the command. */
int cli_remote(int argc, char **argv);

#endif
