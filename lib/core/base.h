/* base.h - status codes, error details, allocation and the output and log
 * callbacks shared by every libqdc module (public: included by qdc.h; the
 * internal helpers are in base_int.h). Thread-safe: no global mutable state
 * (the test builds' allocation fault counter is thread-local). */
#ifndef QDC_BASE_H
#define QDC_BASE_H

#include <stddef.h>
#include <stdint.h>

/* One list of errors (libuv style). Append; never renumber. The third column is
 * the HTTP status the daemon answers with when the error is the request's fault
 * (5xx otherwise). */
#define QDC_STATUS_LIST(X)                                                               \
    X(QDC_OK, "ok", 200)                                                                 \
    X(QDC_ENOMEM, "out of memory", 503)                                                  \
    X(QDC_EINVAL, "invalid argument", 400)                                               \
    X(QDC_EPARSE, "malformed mesh input", 400)                                           \
    X(QDC_ETOOBIG, "mesh exceeds limits", 413)                                           \
    X(QDC_EMESH, "mesh failed validation", 422)                                          \
    X(QDC_ESOLVE, "linear solve failed", 500)                                            \
    X(QDC_EIO, "i/o error", 500)                                                         \
    X(QDC_ECANCEL, "cancelled", 409)                                                     \
    X(QDC_EFORMAT, "unsupported format", 415)                                            \
    X(QDC_ETETGEN, "surface could not be tetrahedralized", 422)                          \
    X(QDC_EINTERNAL, "internal error", 500)

typedef enum {
#define QDC_X_ENUM(name, text, http) name,
    QDC_STATUS_LIST(QDC_X_ENUM)
#undef QDC_X_ENUM
        QDC_STATUS_COUNT
} qdc_status;

/* Detail of a failure. Every field is optional: -1 / empty when unknown.
 * `line`/`col` are 1-based positions in a text input, `offset` a byte offset
 * in a binary one; `index` the offending vertex or tet (0-based) and `kind`
 * says which ("vertex", "tet", "region"...). */
typedef struct {
    qdc_status status;
    char msg[256];
    int64_t line;
    int64_t col;
    int64_t offset;
    int64_t index;
    char kind[16];
} qdc_error;

/* The message of st ("out of memory"); a static string, never NULL (an
 * unknown st gives a generic one). */
const char *qdc_status_str(qdc_status st);
/* The enumerator's name of st ("QDC_ENOMEM"); a static string, never NULL. */
const char *qdc_status_name(qdc_status st);
/* The HTTP status the daemon answers st with (200, 400, 413...; 500 when
 * unknown). */
int qdc_status_http(qdc_status st);

/* Reset *err before a call: status QDC_OK, empty texts, -1 positions.
 * err may be NULL. */
void qdc_error_clear(qdc_error *err);

/* Set err's status to st and its message to the printf-style fmt (cut to fit
 * msg); its other fields are left as they are. err may be NULL. Returns st,
 * so that callers can write
 * `return qdc_fail(err, QDC_EMESH, "...")`. */
qdc_status qdc_fail(qdc_error *err, qdc_status st, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* All allocation in lib/ goes through these, so that tests can fail the Nth
 * allocation (build with -DQDC_FAULT_INJECTION). Memory the library hands to
 * the caller as a plain buffer (meshio_slurp...) is freed with qdc_free; an
 * array a caller puts into a mesh_t (m->region after mesh_new...) comes from
 * them, since mesh_free releases it with qdc_free. */

/* size bytes, uninitialized; NULL on failure. */
void *qdc_malloc(size_t size);
/* n*size bytes, zeroed; NULL on failure or if n*size overflows. */
void *qdc_calloc(size_t n, size_t size);
/* n*size bytes, uninitialized; NULL on failure or if n*size overflows. */
void *qdc_mallocn(size_t n, size_t size);
/* p (from these, or NULL) resized to size bytes, its contents kept; NULL on
 * failure, p then still allocated and the caller's. */
void *qdc_realloc(void *p, size_t size);
/* Free p (from these); p may be NULL. */
void qdc_free(void *p);

#ifdef QDC_FAULT_INJECTION
/* Test builds only: the fail_after-th allocation from now (1 = the next one)
 * and every later one return NULL; 0 disables. Thread-local. */
void qdc_fault_set(long fail_after);
/* Allocations made by this thread since the last qdc_fault_set. */
long qdc_fault_count(void);
#endif

/* Streaming output used by every writer (mesh formats, reports): called with
 * consecutive pieces of the output (data is the writer's, valid only during
 * the call); returns 0 on success, non-zero to abort the write (the writer
 * then returns QDC_EIO). */
typedef int (*qdc_write_fn)(void *ctx, const void *data, size_t len);

/* Logging callback (the library never prints): level 0 = info, 1 = warning;
 * msg is one line without a newline, valid only during the call. */
typedef void (*qdc_log_fn)(void *ctx, int level, const char *msg);

#endif
