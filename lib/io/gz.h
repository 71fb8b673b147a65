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
/* Below this many decompressed bytes a ratio cap (gz_budget) does not apply:
 * a small file may compress far better than a mesh of real size does. */
#define GZ_RATIO_FLOOR ((size_t)1 << 20)

/* 1 if buf starts a gzip stream. */
int gz_is_gzip(const char *buf, size_t len);

/* The most len compressed bytes may inflate to: max_out (0: GZ_MAX_OUT, and
 * never more), and with max_ratio > 0 at most max_ratio * len bytes, or
 * GZ_RATIO_FLOOR when that is more. Meshes compress 2-3x with gzip, a
 * stream of zeros about 1000x. */
size_t gz_budget(size_t len, size_t max_out, unsigned max_ratio);

/* Inflate the gzip stream buf[0..len) (several members allowed) into a new
 * buffer *out (qdc_free) of *outlen bytes, NUL-terminated. QDC_EPARSE for a
 * corrupt or truncated stream, QDC_ETOOBIG past GZ_MAX_OUT. */
qdc_status gz_inflate(const char *buf, size_t len, char **out, size_t *outlen,
                      qdc_error *err);
/* gz_inflate that stops as soon as the output passes max_out bytes
 * (QDC_ETOOBIG; memory used: max_out plus zlib's window). */
qdc_status gz_inflate_max(const char *buf, size_t len, size_t max_out, char **out,
                          size_t *outlen, qdc_error *err);
/* The first bytes the gzip stream buf[0..len) inflates to, at most cap of
 * them into dst (to sniff a format before deciding a limit): how many, 0 for
 * a stream that is not gzip or is corrupt at its start. */
size_t gz_head(const char *buf, size_t len, char *dst, size_t cap);

/* A writer (qdc_write_fn-compatible through gz_write) that deflates into the
 * caller's sink. */
typedef struct gz_writer gz_writer;
gz_writer *gz_writer_new(qdc_write_fn sink, void *sink_ctx);
int gz_write(void *w, const void *data, size_t len); /* 0 ok, -1 error */
/* Flush the end of the stream; 0 ok. Frees w either way. */
int gz_writer_finish(gz_writer *w);

#endif
