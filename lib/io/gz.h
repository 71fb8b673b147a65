/* gz.h - gzip-compressed mesh files (zlib): any format may come as FILE.gz
 * (.mesh.gz, .msh.gz, .vtk.gz, ...). Reading recognizes the gzip magic
 * whatever the name; writing compresses when the path ends in .gz.
 * Thread-safe: no state beyond the call. */
#ifndef QDC_GZ_H
#define QDC_GZ_H

#include "core/base.h"

#include <stddef.h>

/* Largest decompressed size accepted (a gzip bomb inflates ~1000x). */
#define GZ_MAX_OUT ((size_t)4 << 30)

/* 1 if buf starts a gzip stream. */
int gz_is_gzip(const char *buf, size_t len);

/* Inflate the gzip stream buf[0..len) (several members allowed) into a new
 * buffer *out (qdc_free) of *outlen bytes, NUL-terminated. QDC_EPARSE for a
 * corrupt or truncated stream, QDC_ETOOBIG past GZ_MAX_OUT. */
qdc_status gz_inflate(const char *buf, size_t len, char **out, size_t *outlen,
                      qdc_error *err);

/* A writer (qdc_write_fn-compatible through gz_write) that deflates into the
 * caller's sink. */
typedef struct gz_writer gz_writer;
gz_writer *gz_writer_new(qdc_write_fn sink, void *sink_ctx);
int gz_write(void *w, const void *data, size_t len); /* 0 ok, -1 error */
/* Flush the end of the stream; 0 ok. Frees w either way. */
int gz_writer_finish(gz_writer *w);

#endif
