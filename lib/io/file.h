/* file.h - whole files in and out, below the mesh formats: reading a file
 * into memory (meshio_slurp and meshio_slurp_plain, declared in meshio.h, are
 * here) and saving through a temporary file and a rename. No global state. */
#ifndef QDC_FILE_H
#define QDC_FILE_H

#include "io/meshio.h"

/* Writes what is saved through fn(ctx, ...): QDC_EIO when fn failed (the
 * caller names the file), another status with err filled. */
typedef qdc_status (*file_emit_fn)(const void *arg, qdc_write_fn fn, void *ctx,
                                   qdc_error *err);

/* What emit(arg) writes, saved to path: a file through a temporary file,
 * fsync and a rename (its permissions kept; a symbolic link stays one, the
 * file it names replaced), a pipe or device (/dev/stdout) straight into;
 * gzip-compressed when path ends in .gz. */
qdc_status file_save(const char *path, file_emit_fn emit, const void *arg,
                     qdc_error *err);
/* Where file_save writes path: 0 through a temporary file renamed onto
 * *target (qdc_malloc'd, freed by the caller), 1 straight into path (a
 * device, a pipe, a process's descriptor, a link to nothing yet), -1 out of
 * memory. */
int file_save_route(const char *path, char **target);
/* 1 if path ends in ".gz". */
int file_path_gz(const char *path);
/* The extension that names the format: "mesh" for a.mesh, "mesh.gz" for
 * a.mesh.gz (read it up to the next dot); NULL if none. */
const char *file_path_ext(const char *path);
/* 1 if path names something stat() finds. */
int file_exists(const char *path);

#endif
