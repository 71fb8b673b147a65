/* store.h - the durable job store behind the daemon.
 * Handlers and workers talk to a job_store through its ops table only, so a
 * PostgreSQL backend can be added beside the SQLite one without touching them.
 * Every call is thread-safe (backends lock internally). Times are Unix seconds.
 * SQLite: mesh bodies, results, reports and progress logs are files in the
 * data directory (job_path), never rows. PostgreSQL (nodes that share nothing
 * but the database): they are stored in the database too, in chunks (the
 * blob_* and progress_* ops, NULL in the SQLite backend), and DATA/jobs is
 * each node's cache. */
#ifndef QDCD_STORE_H
#define QDCD_STORE_H

#include "qdc.h"

#include <stdint.h>

typedef enum {
    JOB_QUEUED = 0,
    JOB_RUNNING,
    JOB_SUCCEEDED,
    JOB_FAILED,
    JOB_CANCELLED,
    JOB_STATE_COUNT
} job_state;

const char *job_state_name(job_state s); /* "queued"... */
int job_state_done(job_state s);         /* succeeded, failed or cancelled */

#define JOB_ID_LEN 32 /* hex characters */

/* One job row. Fixed-size fields so records copy by value between threads. */
typedef struct {
    char id[JOB_ID_LEN + 1];
    int64_t seq;    /* insertion order, for paging */
    char owner[65]; /* SHA-256 hex of the creating token, "" without tokens */
    job_state state;
    int cancel_requested;
    char idem_key[129]; /* Idempotency-Key, "" if none */
    char body_hash[65]; /* SHA-256 of query + body when idem_key is set */
    char format[16];    /* input format name: meshio's ("qmesh", "gmsh-bin"...) or
                           a surface's ("stl"...: tetrahedralized by the worker) */
    int64_t nv, nt;
    int64_t in_bytes;
    char options[1024]; /* canonical options JSON */
    int attempts;
    char lease_owner[64];
    double lease_until;
    double created, started, finished, expires;
    int purged;              /* files removed after retention (result: 410) */
    int iterations;          /* the last run's last record number (its seq) */
    char last_progress[768]; /* latest progress record JSON, "" if none */
    char error[1024];        /* problem+json object of a failed job, "" otherwise */
    char stop_reason[64];
    char etag_qmesh[65], etag_json[65], etag_medit[65];
    char notes[512];     /* reader notes (skipped element types...), lines, "" if none */
    char file_name[256]; /* the upload's file name (?name=), "" if not given */
    char label[128];     /* the submitter's label (?label=), "" if none */
    int input_h5;        /* an XDMF job whose heavy data is its second input file,
                            the .h5 sent with it (h5job.h: JOB_INPUT_H5) */
} job_rec;

/* j has a result and a report: it succeeded, or it was cancelled while the
 * optimizer ran and the best mesh so far was kept (its etags are set). */
int job_has_result(const job_rec *j);

typedef struct {
    int64_t by_state[JOB_STATE_COUNT];
} job_counts;

typedef struct job_store job_store;

/* What another node changed, as heard by listen (LISTEN/NOTIFY). */
typedef enum {
    STORE_EV_JOB,      /* a job row was inserted, changed state or was flagged
                          for cancellation (state, cancel), or deleted (state -1) */
    STORE_EV_PROGRESS, /* records up to seq were written for id */
    STORE_EV_RESYNC    /* the connection was lost and is back: anything may
                          have happened meanwhile (id "") */
} store_ev_kind;

typedef struct {
    store_ev_kind kind;
    char id[JOB_ID_LEN + 1];
    int state, cancel;
    long seq;
} store_event;

typedef void (*store_event_fn)(void *ctx, const store_event *ev);
/* progress_read's callback: one record (JSON object with its "seq"). */
typedef void (*store_record_fn)(void *ctx, long seq, const char *json, size_t len);

typedef struct {
    /* Insert j (id, owner, idem_key, body_hash, format, sizes, options, created,
     * notes filled by the caller). If j->idem_key is set and the owner already has a
     * job with that key, nothing is inserted, *existing receives that job and
     * *dup is set to 1. The row is durable when this returns QDC_OK. */
    qdc_status (*create)(job_store *s, const job_rec *j, int *dup, job_rec *existing);
    /* QDC_EINVAL when there is no such job. */
    qdc_status (*get)(job_store *s, const char *id, job_rec *out);
    /* The owner's job created with Idempotency-Key key; QDC_EINVAL if none. */
    qdc_status (*find_idem)(job_store *s, const char *owner, const char *key,
                            job_rec *out);
    /* Up to max jobs of owner with seq > after_seq, oldest first; *n set. */
    qdc_status (*list)(job_store *s, const char *owner, int64_t after_seq, int max,
                       job_rec *out, int *n);
    /* Claim the oldest queued job (or a running one whose lease expired):
     * state running, attempts + 1, lease owner/until. *found 0 if none. */
    qdc_status (*claim)(job_store *s, const char *worker, double lease_s, job_rec *out,
                        int *found);
    qdc_status (*renew)(job_store *s, const char *id, const char *worker, double lease_s);
    /* Terminal state from a worker: writes state, finished, expires, iterations,
     * last_progress, error, stop_reason, etags, nv and nt of j (a surface job
     * learns its tet count from TetGen). */
    qdc_status (*finish)(job_store *s, const job_rec *j);
    /* Give a running job back to the queue (graceful shutdown): attempts - 1. */
    qdc_status (*release)(job_store *s, const char *id, const char *worker);
    /* Queued: cancelled at once (*now_done = 1). Running: cancel_requested = 1. */
    qdc_status (*cancel)(job_store *s, const char *id, int *now_done);
    qdc_status (*remove)(job_store *s, const char *id);
    /* Start-up after a crash: running jobs go back to queued, or to failed when
     * they already used max_attempts (kept for retention seconds, as any
     * finished job). *requeued / *failed counted. */
    qdc_status (*recover)(job_store *s, int max_attempts, double retention, int *requeued,
                          int *failed);
    qdc_status (*counts)(job_store *s, job_counts *c);
    /* Done jobs whose expires < now and not yet purged: ids into out (max). */
    qdc_status (*expired)(job_store *s, double now, char (*out)[JOB_ID_LEN + 1], int max,
                          int *n);
    qdc_status (*mark_purged)(job_store *s, const char *id);
    void (*close)(job_store *s);

    /* ---- Node-shared job files (PostgreSQL); NULL in the SQLite backend. ---- */
    /* create, with the job's input: the file at path, stored as blob `name` in
     * the same transaction as the row (streamed in chunks), and the file at
     * path2 as blob name2 unless name2 is NULL (an XDMF file's .h5). */
    qdc_status (*create_with_input)(job_store *s, const job_rec *j, const char *name,
                                    const char *path, const char *name2,
                                    const char *path2, int *dup, job_rec *existing);
    /* Store the file at path as job id's blob `name` (replacing an older one),
     * with its SHA-256 hex (sha, or "" if none), streamed in chunks. worker:
     * only while that worker holds the job's lease (NULL: any time). QDC_EINVAL
     * when the job is gone or the lease is lost. */
    qdc_status (*blob_put)(job_store *s, const char *id, const char *name,
                           const char *path, const char *sha, const char *worker);
    /* Blob `name` of job id into path (via path.tmp, renamed), streamed; its
     * SHA-256 hex into sha (65 bytes) if not NULL. QDC_EINVAL if there is none. */
    qdc_status (*blob_get)(job_store *s, const char *id, const char *name,
                           const char *path, char *sha);
    /* Record seq of worker's run of id (a JSON object with its "seq"): queued
     * and written by a background thread with the job row's latest progress,
     * so the optimizer never waits on the database. Dropped if the worker
     * no longer holds the lease. */
    void (*progress_add)(job_store *s, const char *id, const char *worker, long seq,
                         const char *json, size_t len);
    /* Wait up to timeout seconds until every record queued so far is written
     * (or dropped). QDC_OK, or QDC_EIO if the database did not take them. */
    qdc_status (*progress_sync)(job_store *s, double timeout);
    /* The stored records of id with seq > after, in order, to fn. */
    qdc_status (*progress_read)(job_store *s, const char *id, long after,
                                store_record_fn fn, void *ctx);
    /* Start a thread (own connection) that hears other nodes' changes and
     * calls fn from it; reconnects with a growing pause (then STORE_EV_RESYNC).
     * fn NULL: stop that thread and wait for it. */
    qdc_status (*listen)(job_store *s, store_event_fn fn, void *ctx);
} job_store_ops;

struct job_store {
    const job_store_ops *ops;
};

/* SQLite (WAL) backend: DIR/qdcd.db. */
qdc_status store_sqlite_open(const char *dir, job_store **out, qdc_error *err);

/* PostgreSQL backend (store_pg.c): uri is a libpq connection URI
 * (postgresql://USER@HOST:PORT/DB). The schema is created or migrated on open. */
qdc_status store_pg_open(const char *uri, job_store **out, qdc_error *err);
/* 1 if uri names a PostgreSQL database (postgresql:// or postgres://). */
int store_pg_uri(const char *uri);

#endif
