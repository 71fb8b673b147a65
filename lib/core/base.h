/* base.h - status codes, error details and allocation shared by every libqdc module.
 * Thread-safe: no global mutable state (the optional allocation fault hook is
 * per call site: see qdc_alloc_hooks). */
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

const char *qdc_status_str(qdc_status st);  /* "out of memory"... never NULL */
const char *qdc_status_name(qdc_status st); /* "QDC_ENOMEM"... never NULL */
int qdc_status_http(qdc_status st);         /* 200, 400, ... */

/* Clear an error record (err may be NULL). */
void qdc_error_clear(qdc_error *err);

/* Fill err (may be NULL) with st and a printf-style message; returns st so
 * callers can write `return qdc_fail(err, QDC_EMESH, "...")`. */
qdc_status qdc_fail(qdc_error *err, qdc_status st, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* All allocation in lib/ goes through these, so tests can fail the Nth
 * allocation (build with -DQDC_FAULT_INJECTION) and jobs can be budgeted.
 * qdc_malloc/qdc_calloc return NULL on overflow of n*size too. */
void *qdc_malloc(size_t size);
void *qdc_calloc(size_t n, size_t size);
void *qdc_mallocn(size_t n, size_t size); /* malloc(n*size) with overflow check */
void *qdc_realloc(void *p, size_t size);
void qdc_free(void *p);

#ifdef QDC_FAULT_INJECTION
/* Test builds only: the fail_after-th allocation from now (1 = the next one)
 * and every later one return NULL; 0 disables. Thread-local. */
void qdc_fault_set(long fail_after);
long qdc_fault_count(void); /* allocations made since the last qdc_fault_set */
#endif

/* A hint to fetch the cache line of p ahead of a read (none where the
 * compiler has no such builtin). */
#if defined(__GNUC__)
#define QDC_PREFETCH(p) __builtin_prefetch(p)
#else
#define QDC_PREFETCH(p) ((void)(p))
#endif

/* The first item of part p of n items cut into parts nearly equal parts (p =
 * parts: n): the fixed ranges that parallel loops give their threads. */
static inline int32_t qdc_part(int32_t n, int p, int parts)
{
    return (int32_t)((int64_t)n * p / parts);
}

/* Monotonic wall clock in seconds. */
double qdc_now(void);

/* The caller's OpenMP thread count, at most cap: the team size of a loop that
 * gives each thread its own scratch array of the mesh's size. */
int qdc_threads_upto(int cap);

/* A counting sort's counts made by nth threads over consecutive ranges of the
 * items (cnt: nth rows of w entries, bucket b of thread i at cnt[i * w + b])
 * into each thread's first place in each of the n buckets: bucket by bucket,
 * thread by thread, so the placed items keep their serial order. start (n + 1
 * entries, may be NULL) receives each bucket's first place and the total. */
void qdc_count_places(int32_t *cnt, int nth, size_t w, int32_t n, int32_t *start);

/* Streaming output used by every writer (mesh formats, reports): returns 0 on
 * success, non-zero to abort the write (the writer then returns QDC_EIO). */
typedef int (*qdc_write_fn)(void *ctx, const void *data, size_t len);

/* Logging callback (the library never prints): level 0 = info, 1 = warning. */
typedef void (*qdc_log_fn)(void *ctx, int level, const char *msg);

#endif
