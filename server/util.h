/* util.h - small helpers shared by the daemon's modules: a growable string
 * buffer (also a qdc_write_fn target), clocks, and durable file writes. */
#ifndef QDCD_UTIL_H
#define QDCD_UTIL_H

#include <stdarg.h>
#include <stddef.h>

typedef struct {
    char *buf;
    size_t len, cap;
    int oom; /* set once an append failed; the content is then truncated */
} sbuf;

void sb_free(sbuf *b);
void sb_add(sbuf *b, const void *data, size_t len);
void sb_puts(sbuf *b, const char *s);
void sb_printf(sbuf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* JSON string literal with quotes and escapes. */
void sb_json_str(sbuf *b, const char *s);
/* qdc_write_fn adaptor: ctx is an sbuf. */
int sb_writer(void *ctx, const void *data, size_t len);

double mono_now(void); /* CLOCK_MONOTONIC seconds */
double wall_now(void); /* Unix seconds */

/* Write len bytes to path via path.tmp, fsync, rename, fsync the directory. 0 or -1. */
int file_write_atomic(const char *path, const void *data, size_t len);
/* fsync the directory holding path. 0 or -1. */
int fsync_parent(const char *path);
/* Whole file into a malloc'd NUL-terminated buffer; NULL on failure. */
char *file_read_all(const char *path, size_t *len);
/* The same after room bytes left for the caller (not set): *len counts them. */
char *file_read_after(const char *path, size_t room, size_t *len);
/* mkdir -p for one level below an existing parent; 0 if it exists. */
int dir_ensure(const char *path);
/* Remove the entries of a directory: files, and subdirectories down to
 * `depth` levels (each emptied the same way, then removed). */
void dir_clear(const char *path, int depth);
/* Remove a directory and the regular files in it (one level). */
void dir_remove(const char *path);

#endif
