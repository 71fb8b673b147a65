/* store_pg.c - job_store backed by PostgreSQL (libpq), for several qdcd nodes
 * on one database. The rows are the same as the SQLite backend's; what
 * PostgreSQL adds is what many nodes need:
 * - claims with FOR UPDATE SKIP LOCKED, so two nodes never take the same job
 *   and never wait for each other's claim;
 * - the Idempotency-Key as a unique index that INSERT ... ON CONFLICT checks
 *   in the same statement (two nodes receiving the same request at the same
 *   moment make one job, not two);
 * - a versioned schema that qdcd creates or migrates itself, under an advisory
 *   lock so that nodes starting together do not race.
 * - the job files too (schema 2): input meshes, results and reports are
 *   blobs cut into 1 MiB bytea chunks (streamed both ways: never a whole body
 *   in memory), progress records are rows, so nodes share nothing but the
 *   database and each node's --data is a cache;
 * - LISTEN/NOTIFY: triggers announce new jobs, state changes, cancellations,
 *   deletions and progress records; one listening connection per node hears
 *   them (listen) and wakes that node's parked readers and idle workers.
 * Row operations go through one connection serialized by a mutex; blob
 * transfers take a connection from a small pool (a 1 GB upload does not hold
 * up the claims), the progress writer and the listener have their own. A
 * broken connection is reset and the statement (or transaction) tried once
 * more, so a restarted database costs one failed call, not a dead node.
 * Every call is a single statement (autocommit) unless it says otherwise.
 * Here: the rows, the blobs, the schema; the progress writer and the
 * listener are store_pg_feed.c, the statement runners store_pg_sql.c
 * (store_pg_int.h: what the three share). */
#define _GNU_SOURCE
#include "problem.h"
#include "store_pg_int.h"
#include "util.h"

#include <errno.h>
#include <fcntl.h>
#include <libpq-fe.h>
#include <poll.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* The schema, one entry per version; each runs once, in order, in one
 * transaction that also records the version. Append; never edit a version
 * that has shipped. */
static const char *const migrations[] = {
    /* 1 */
    "CREATE TABLE jobs("
    " seq BIGSERIAL PRIMARY KEY, id TEXT UNIQUE NOT NULL,"
    " owner TEXT NOT NULL, state INTEGER NOT NULL, cancel_requested INTEGER NOT NULL"
    " DEFAULT 0, idem_key TEXT NOT NULL, body_hash TEXT NOT NULL, format TEXT NOT NULL,"
    " nv BIGINT NOT NULL DEFAULT 0, nt BIGINT NOT NULL DEFAULT 0,"
    " in_bytes BIGINT NOT NULL DEFAULT 0, options TEXT NOT NULL,"
    " attempts INTEGER NOT NULL DEFAULT 0, lease_owner TEXT NOT NULL DEFAULT '',"
    " lease_until DOUBLE PRECISION NOT NULL DEFAULT 0,"
    " created DOUBLE PRECISION NOT NULL DEFAULT 0,"
    " started DOUBLE PRECISION NOT NULL DEFAULT 0,"
    " finished DOUBLE PRECISION NOT NULL DEFAULT 0,"
    " expires DOUBLE PRECISION NOT NULL DEFAULT 0,"
    " purged INTEGER NOT NULL DEFAULT 0, iterations INTEGER NOT NULL DEFAULT 0,"
    " last_progress TEXT NOT NULL DEFAULT '', error TEXT NOT NULL DEFAULT '',"
    " stop_reason TEXT NOT NULL DEFAULT '', etag_qmesh TEXT NOT NULL DEFAULT '',"
    " etag_json TEXT NOT NULL DEFAULT '', etag_medit TEXT NOT NULL DEFAULT '',"
    " notes TEXT NOT NULL DEFAULT '');"
    "CREATE UNIQUE INDEX jobs_idem ON jobs(owner, idem_key) WHERE idem_key <> '';"
    "CREATE INDEX jobs_state ON jobs(state, seq);"
    "CREATE INDEX jobs_expiry ON jobs(purged, expires);",
    /* 2: the job files in the database (nodes share nothing else), and
     * notifications for the other nodes */
    "CREATE TABLE blobs(job_id TEXT NOT NULL REFERENCES jobs(id) ON DELETE CASCADE,"
    " name TEXT NOT NULL, size BIGINT NOT NULL, sha256 TEXT NOT NULL,"
    " nchunks INTEGER NOT NULL, PRIMARY KEY(job_id, name));"
    "CREATE TABLE blob_chunks(job_id TEXT NOT NULL, name TEXT NOT NULL,"
    " k INTEGER NOT NULL, data BYTEA NOT NULL, PRIMARY KEY(job_id, name, k),"
    " FOREIGN KEY(job_id, name) REFERENCES blobs(job_id, name) ON DELETE CASCADE);"
    /* meshes compress poorly and pglz costs more than it saves */
    "ALTER TABLE blob_chunks ALTER COLUMN data SET STORAGE EXTERNAL;"
    "CREATE TABLE progress(job_id TEXT NOT NULL, seq INTEGER NOT NULL,"
    " rec TEXT NOT NULL, PRIMARY KEY(job_id, seq));"
    "CREATE FUNCTION qdc_job_notify() RETURNS trigger LANGUAGE plpgsql AS $$ BEGIN"
    " IF TG_OP = 'DELETE' THEN PERFORM pg_notify('qdc_job', OLD.id || ' -1 1');"
    " ELSIF TG_OP = 'INSERT' THEN"
    "  PERFORM pg_notify('qdc_job', NEW.id || ' ' || NEW.state || ' ' || "
    "NEW.cancel_requested);"
    " ELSIF NEW.state <> OLD.state OR NEW.cancel_requested <> OLD.cancel_requested THEN"
    "  PERFORM pg_notify('qdc_job', NEW.id || ' ' || NEW.state || ' ' || "
    "NEW.cancel_requested);"
    " END IF; RETURN NULL; END $$;"
    "CREATE TRIGGER jobs_notify AFTER INSERT OR UPDATE OR DELETE ON jobs"
    " FOR EACH ROW EXECUTE PROCEDURE qdc_job_notify();"
    "CREATE FUNCTION qdc_progress_notify() RETURNS trigger LANGUAGE plpgsql AS $$ BEGIN"
    " PERFORM pg_notify('qdc_progress', job_id || ' ' || MAX(seq)) FROM new_rows"
    " GROUP BY job_id; RETURN NULL; END $$;"
    "CREATE TRIGGER progress_notify AFTER INSERT ON progress"
    " REFERENCING NEW TABLE AS new_rows FOR EACH STATEMENT"
    " EXECUTE PROCEDURE qdc_progress_notify();",
    /* 3: the upload's file name and the submitter's label */
    "ALTER TABLE jobs ADD COLUMN file_name TEXT NOT NULL DEFAULT '',"
    " ADD COLUMN label TEXT NOT NULL DEFAULT '';",
    /* 4: an XDMF job's .h5 stored with it (blob input.h5) */
    "ALTER TABLE jobs ADD COLUMN input_h5 INTEGER NOT NULL DEFAULT 0;",
};
#define N_MIGRATIONS ((int)(sizeof migrations / sizeof migrations[0]))

#define COLS                                                                             \
    "seq, id, owner, state, cancel_requested, idem_key, body_hash, format, nv, nt,"      \
    " in_bytes, options, attempts, lease_owner, lease_until, created, started,"          \
    " finished, expires, purged, iterations, last_progress, error, stop_reason,"         \
    " etag_qmesh, etag_json, etag_medit, notes, file_name, label, input_h5"

static void row_to_rec(const PGresult *r, int row, job_rec *j)
{
    memset(j, 0, sizeof *j);
    j->seq = col_i64(r, row, 0);
    col_text(r, row, 1, j->id, sizeof j->id);
    col_text(r, row, 2, j->owner, sizeof j->owner);
    j->state = (job_state)col_i64(r, row, 3);
    j->cancel_requested = (int)col_i64(r, row, 4);
    col_text(r, row, 5, j->idem_key, sizeof j->idem_key);
    col_text(r, row, 6, j->body_hash, sizeof j->body_hash);
    col_text(r, row, 7, j->format, sizeof j->format);
    j->nv = col_i64(r, row, 8);
    j->nt = col_i64(r, row, 9);
    j->in_bytes = col_i64(r, row, 10);
    col_text(r, row, 11, j->options, sizeof j->options);
    j->attempts = (int)col_i64(r, row, 12);
    col_text(r, row, 13, j->lease_owner, sizeof j->lease_owner);
    j->lease_until = col_dbl(r, row, 14);
    j->created = col_dbl(r, row, 15);
    j->started = col_dbl(r, row, 16);
    j->finished = col_dbl(r, row, 17);
    j->expires = col_dbl(r, row, 18);
    j->purged = (int)col_i64(r, row, 19);
    j->iterations = (int)col_i64(r, row, 20);
    col_text(r, row, 21, j->last_progress, sizeof j->last_progress);
    col_text(r, row, 22, j->error, sizeof j->error);
    col_text(r, row, 23, j->stop_reason, sizeof j->stop_reason);
    col_text(r, row, 24, j->etag_qmesh, sizeof j->etag_qmesh);
    col_text(r, row, 25, j->etag_json, sizeof j->etag_json);
    col_text(r, row, 26, j->etag_medit, sizeof j->etag_medit);
    col_text(r, row, 27, j->notes, sizeof j->notes);
    col_text(r, row, 28, j->file_name, sizeof j->file_name);
    col_text(r, row, 29, j->label, sizeof j->label);
    j->input_h5 = (int)col_i64(r, row, 30);
}

/* One statement that returns at most one job row into out (if not NULL).
 * *rows gets the number of rows returned (or affected, for statements without
 * RETURNING). */
static qdc_status one(pg_store *s, const char *sql, const params *p, job_rec *out,
                      int *rows)
{
    PGresult *r;
    qdc_status st = QDC_EIO;

    pthread_mutex_lock(&s->lock);
    r = pg_run(s, sql, p);
    if (r) {
        int n =
            PQresultStatus(r) == PGRES_TUPLES_OK ? PQntuples(r) : atoi(PQcmdTuples(r));
        if (out && PQresultStatus(r) == PGRES_TUPLES_OK && n > 0)
            row_to_rec(r, 0, out);
        if (rows)
            *rows = n;
        st = QDC_OK;
        PQclear(r);
    }
    pthread_mutex_unlock(&s->lock);
    return st;
}

#define INSERT_JOB                                                                       \
    "INSERT INTO jobs(id, owner, state, idem_key, body_hash, format, nv, nt,"            \
    " in_bytes, options, created, notes, file_name, label, input_h5)"                    \
    " VALUES($1,$2,0,$3,$4,$5,$6,$7,$8,$9,$10,$11,$12,$13,$14)"                          \
    " ON CONFLICT (owner, idem_key) WHERE idem_key <> '' DO NOTHING"                     \
    " RETURNING seq"

static void create_params(const job_rec *j, params *p)
{
    p->n = 0;
    p_text(p, j->id);
    p_text(p, j->owner);
    p_text(p, j->idem_key);
    p_text(p, j->body_hash);
    p_text(p, j->format);
    p_i64(p, j->nv);
    p_i64(p, j->nt);
    p_i64(p, j->in_bytes);
    p_text(p, j->options);
    p_dbl(p, j->created);
    p_text(p, j->notes);
    p_text(p, j->file_name);
    p_text(p, j->label);
    p_i64(p, j->input_h5);
}

/* The job that holds j's Idempotency-Key (an insert found it taken). */
static qdc_status existing_idem(pg_store *s, const job_rec *j, int *dup,
                                job_rec *existing)
{
    params p = {.n = 0};
    int n = 0;
    qdc_status st;

    p_text(&p, j->owner);
    p_text(&p, j->idem_key);
    st = one(s, "SELECT " COLS " FROM jobs WHERE owner = $1 AND idem_key = $2", &p,
             existing, &n);
    if (st == QDC_OK && n == 1)
        *dup = 1;
    return st == QDC_OK && n == 1 ? QDC_OK : QDC_EIO;
}

static qdc_status pg_create(job_store *s_, const job_rec *j, int *dup, job_rec *existing)
{
    pg_store *s = (pg_store *)s_;
    params p;
    int n = 0;
    qdc_status st;

    *dup = 0;
    create_params(j, &p);
    /* The unique index decides a duplicate key in this statement, whichever
     * node gets there first. */
    st = one(s, INSERT_JOB, &p, NULL, &n);
    if (st != QDC_OK || n == 1)
        return st;
    return existing_idem(s, j, dup, existing);
}

static qdc_status pg_get(job_store *s_, const char *id, job_rec *out)
{
    params p = {.n = 0};
    int n = 0;
    qdc_status st;

    p_text(&p, id);
    st = one((pg_store *)s_, "SELECT " COLS " FROM jobs WHERE id = $1", &p, out, &n);
    return st != QDC_OK ? st : n ? QDC_OK : QDC_EINVAL;
}

static qdc_status pg_find_idem(job_store *s_, const char *owner, const char *key,
                               job_rec *out)
{
    params p = {.n = 0};
    int n = 0;
    qdc_status st;

    p_text(&p, owner);
    p_text(&p, key);
    st = one((pg_store *)s_,
             "SELECT " COLS " FROM jobs WHERE owner = $1 AND idem_key = $2", &p, out, &n);
    return st != QDC_OK ? st : n ? QDC_OK : QDC_EINVAL;
}

static qdc_status pg_list(job_store *s_, const char *owner, int64_t after_seq, int max,
                          job_rec *out, int *n)
{
    pg_store *s = (pg_store *)s_;
    params p = {.n = 0};
    PGresult *r;
    qdc_status st = QDC_EIO;

    *n = 0;
    p_text(&p, owner);
    p_i64(&p, after_seq);
    p_i64(&p, max);
    pthread_mutex_lock(&s->lock);
    r = pg_run(s,
               "SELECT " COLS
               " FROM jobs WHERE owner = $1 AND seq > $2 ORDER BY seq LIMIT $3",
               &p);
    if (r) {
        for (int i = 0; i < PQntuples(r) && *n < max; i++)
            row_to_rec(r, i, &out[(*n)++]);
        PQclear(r);
        st = QDC_OK;
    }
    pthread_mutex_unlock(&s->lock);
    return st;
}

/* The oldest queued job, or a running one whose lease expired on another
 * instance (a node that died), in one statement: SKIP LOCKED lets concurrent
 * claims from other nodes pass over the row being claimed here. A job leased
 * by this instance is never taken over (a slow iteration is not a dead
 * worker; the worker renews its lease). */
static qdc_status pg_claim(job_store *s_, const char *worker, double lease_s,
                           job_rec *out, int *found)
{
    params p = {.n = 0};
    char inst[80];
    const char *slash = strchr(worker, '/');
    double now = wall_now();
    int n = 0;
    qdc_status st;

    snprintf(inst, sizeof inst, "%.*s/%%", slash ? (int)(slash - worker) : 0, worker);
    p_text(&p, worker);
    p_dbl(&p, now + lease_s);
    p_dbl(&p, now);
    p_text(&p, inst);
    p_i64(&p, ((pg_store *)s_)->max_attempts);
    /* the records of an earlier run (a node that died) are not this run's */
    st = one((pg_store *)s_,
             "WITH c AS (UPDATE jobs SET state = 1, attempts = attempts + 1,"
             " lease_owner = $1, lease_until = $2, started = $3, iterations = 0,"
             " last_progress = ''"
             " WHERE seq = (SELECT seq FROM jobs WHERE state = 0"
             " OR (state = 1 AND lease_until < $3 AND lease_owner NOT LIKE $4"
             " AND attempts < $5)"
             " ORDER BY seq LIMIT 1 FOR UPDATE SKIP LOCKED)"
             " RETURNING " COLS "),"
             " d AS (DELETE FROM progress WHERE job_id IN (SELECT id FROM c))"
             " SELECT * FROM c",
             &p, out, &n);
    *found = st == QDC_OK && n == 1;
    return st;
}

static qdc_status pg_renew(job_store *s_, const char *id, const char *worker,
                           double lease_s)
{
    params p = {.n = 0};

    p_dbl(&p, wall_now() + lease_s);
    p_text(&p, id);
    p_text(&p, worker);
    return one((pg_store *)s_,
               "UPDATE jobs SET lease_until = $1 WHERE id = $2 AND lease_owner = $3", &p,
               NULL, NULL);
}

static qdc_status pg_finish(job_store *s_, const job_rec *j)
{
    params p = {.n = 0};

    p_i64(&p, j->state);
    p_dbl(&p, j->finished);
    p_dbl(&p, j->expires);
    p_i64(&p, j->iterations);
    p_text(&p, j->last_progress);
    p_text(&p, j->error);
    p_text(&p, j->stop_reason);
    p_text(&p, j->etag_qmesh);
    p_text(&p, j->etag_json);
    p_text(&p, j->etag_medit);
    p_i64(&p, j->nv);
    p_i64(&p, j->nt);
    p_text(&p, j->id);
    p_text(&p, j->lease_owner);
    /* Only the run that holds the lease ends the job: a node whose lease
     * expired (the database was away too long) and was taken over by another
     * node must not write a second outcome. */
    return one((pg_store *)s_,
               "UPDATE jobs SET state = $1, finished = $2, expires = $3, iterations = $4,"
               " last_progress = $5, error = $6, stop_reason = $7, etag_qmesh = $8,"
               " etag_json = $9, etag_medit = $10, nv = $11, nt = $12, lease_owner = '',"
               " lease_until = 0 WHERE id = $13 AND state = 1 AND lease_owner = $14",
               &p, NULL, NULL);
}

static qdc_status pg_release(job_store *s_, const char *id, const char *worker)
{
    params p = {.n = 0};

    p_text(&p, id);
    p_text(&p, worker);
    return one((pg_store *)s_,
               "UPDATE jobs SET state = 0, attempts = GREATEST(attempts - 1, 0),"
               " lease_owner = '', lease_until = 0"
               " WHERE id = $1 AND lease_owner = $2 AND state = 1",
               &p, NULL, NULL);
}

/* Queued: cancelled at once. Running: flagged for its worker. One statement,
 * so a claim that commits in between cannot make the cancel miss the job. */
static qdc_status pg_cancel(job_store *s_, const char *id, int *now_done)
{
    params p = {.n = 0};
    job_rec r;
    int n = 0;
    double now = wall_now();
    qdc_status st;

    p_dbl(&p, now);
    p_text(&p, id);
    st = one((pg_store *)s_,
             "UPDATE jobs SET cancel_requested = 1,"
             " state = CASE WHEN state = 0 THEN 4 ELSE state END,"
             " finished = CASE WHEN state = 0 THEN $1 ELSE finished END,"
             " expires = CASE WHEN state = 0 THEN $1 ELSE expires END"
             " WHERE id = $2 AND state IN (0, 1) RETURNING " COLS,
             &p, &r, &n);
    *now_done = st == QDC_OK && n == 1 && r.state == JOB_CANCELLED;
    return st;
}

static qdc_status pg_remove(job_store *s_, const char *id)
{
    params p = {.n = 0};

    p_text(&p, id);
    /* blobs go with the row (ON DELETE CASCADE), records here */
    return one((pg_store *)s_,
               "WITH d AS (DELETE FROM progress WHERE job_id = $1)"
               " DELETE FROM jobs WHERE id = $1",
               &p, NULL, NULL);
}

/* Jobs whose lease expired (their node died) go back to the queue, or fail
 * when they used all their attempts (a job that keeps killing nodes). Run at
 * a node's start-up and then every few seconds by every node; jobs that
 * other, live nodes are running keep their leases. */
static qdc_status pg_recover(job_store *s_, int max_attempts, double retention,
                             int *requeued, int *failed)
{
    pg_store *s = (pg_store *)s_;
    params p = {.n = 0};
    char err[512];
    double now = wall_now();
    qdc_status st;

    problem_attempts(err, sizeof err, max_attempts, "a daemon");
    s->max_attempts = max_attempts;
    p_dbl(&p, now);
    p_dbl(&p, now + retention);
    p_text(&p, err);
    p_i64(&p, max_attempts);
    st = one(s,
             "UPDATE jobs SET state = 3, finished = $1, expires = $2, error = $3,"
             " lease_owner = '', lease_until = 0"
             " WHERE state = 1 AND lease_until < $1 AND attempts >= $4",
             &p, NULL, failed);
    if (st != QDC_OK)
        return st;
    p.n = 0;
    p_dbl(&p, now);
    return one(s,
               "UPDATE jobs SET state = 0, lease_owner = '', lease_until = 0"
               " WHERE state = 1 AND lease_until < $1",
               &p, NULL, requeued);
}

static qdc_status pg_counts(job_store *s_, job_counts *c)
{
    pg_store *s = (pg_store *)s_;
    PGresult *r;
    qdc_status st = QDC_EIO;

    memset(c, 0, sizeof *c);
    pthread_mutex_lock(&s->lock);
    r = pg_run(s, "SELECT state, COUNT(*) FROM jobs GROUP BY state", NULL);
    if (r) {
        for (int i = 0; i < PQntuples(r); i++) {
            int64_t k = col_i64(r, i, 0);
            if (k >= 0 && k < JOB_STATE_COUNT)
                c->by_state[k] = col_i64(r, i, 1);
        }
        PQclear(r);
        st = QDC_OK;
    }
    pthread_mutex_unlock(&s->lock);
    return st;
}

static qdc_status pg_expired(job_store *s_, double now, char (*out)[JOB_ID_LEN + 1],
                             int max, int *n)
{
    pg_store *s = (pg_store *)s_;
    params p = {.n = 0};
    PGresult *r;
    qdc_status st = QDC_EIO;

    *n = 0;
    p_dbl(&p, now);
    p_i64(&p, max);
    pthread_mutex_lock(&s->lock);
    r = pg_run(
        s,
        "SELECT id FROM jobs WHERE state >= 2 AND purged = 0 AND expires < $1 LIMIT $2",
        &p);
    if (r) {
        for (int i = 0; i < PQntuples(r) && *n < max; i++)
            col_text(r, i, 0, out[(*n)++], JOB_ID_LEN + 1);
        PQclear(r);
        st = QDC_OK;
    }
    pthread_mutex_unlock(&s->lock);
    return st;
}

static qdc_status pg_mark_purged(job_store *s_, const char *id)
{
    params p = {.n = 0};

    p_text(&p, id);
    /* the files of an expired job: its blobs and records (the row stays) */
    return one((pg_store *)s_,
               "WITH b AS (DELETE FROM blobs WHERE job_id = $1),"
               " r AS (DELETE FROM progress WHERE job_id = $1)"
               " UPDATE jobs SET purged = 1 WHERE id = $1",
               &p, NULL, NULL);
}

/* ------------------------------------------------------------------ blobs -- */

/* A pooled connection for one transfer; waits while all are in use. The
 * slot, or -1 when no connection can be made (the database is away). */
static int pool_take(pg_store *s)
{
    int i;

    pthread_mutex_lock(&s->pool_lock);
    for (;;) {
        for (i = 0; i < POOL_MAX && s->pool_busy[i]; i++)
            ;
        if (i < POOL_MAX)
            break;
        pthread_cond_wait(&s->pool_cond, &s->pool_lock);
    }
    s->pool_busy[i] = 1;
    pthread_mutex_unlock(&s->pool_lock);
    if (!s->pool[i])
        s->pool[i] = pg_connect(s->uri);
    else if (PQstatus(s->pool[i]) != CONNECTION_OK)
        PQreset(s->pool[i]);
    if (s->pool[i] && PQstatus(s->pool[i]) == CONNECTION_OK)
        return i;
    pthread_mutex_lock(&s->pool_lock);
    s->pool_busy[i] = 0;
    pthread_cond_signal(&s->pool_cond);
    pthread_mutex_unlock(&s->pool_lock);
    return -1;
}

static void pool_give(pg_store *s, int i)
{
    PGconn *c = s->pool[i];

    if (PQstatus(c) == CONNECTION_OK && PQtransactionStatus(c) != PQTRANS_IDLE)
        PQclear(PQexec(c, "ROLLBACK"));
    pthread_mutex_lock(&s->pool_lock);
    s->pool_busy[i] = 0;
    pthread_cond_signal(&s->pool_cond);
    pthread_mutex_unlock(&s->pool_lock);
}

/* The file at path as blob `name` of id, inside the caller's transaction on
 * c: one row of metadata, then CHUNK-sized rows sent as binary parameters,
 * one buffer at a time. QDC_EINVAL when the job row is gone. */
static qdc_status put_chunks(PGconn *c, const char *id, const char *name,
                             const char *path, const char *sha)
{
    params p = {.n = 0};
    struct stat sb;
    char state[6] = "", kb[24];
    char *buf = NULL;
    qdc_status st = QDC_EIO;
    PGresult *r;
    int fd = open(path, O_RDONLY | O_CLOEXEC);

    if (fd < 0)
        return QDC_EIO;
    if (fstat(fd, &sb))
        goto out;
    int64_t size = (int64_t)sb.st_size;
    int64_t nch = (size + (int64_t)CHUNK - 1) / (int64_t)CHUNK;
    p_text(&p, id);
    p_text(&p, name);
    p_i64(&p, size);
    p_text(&p, sha ? sha : "");
    p_i64(&p, nch);
    r = pg_cx(c,
              "INSERT INTO blobs(job_id, name, size, sha256, nchunks)"
              " VALUES($1, $2, $3, $4, $5)",
              &p, state);
    if (!r) {
        st = !strcmp(state, "23503") ? QDC_EINVAL : QDC_EIO;
        goto out;
    }
    PQclear(r);
    buf = malloc(CHUNK);
    if (!buf) {
        st = QDC_ENOMEM;
        goto out;
    }
    for (int64_t k = 0; k < nch; k++) {
        size_t want = k == nch - 1 ? (size_t)(size - k * (int64_t)CHUNK) : CHUNK, got = 0;
        while (got < want) {
            ssize_t n = read(fd, buf + got, want - got);
            if (n < 0 && errno == EINTR)
                continue;
            if (n <= 0)
                goto out;
            got += (size_t)n;
        }
        snprintf(kb, sizeof kb, "%lld", (long long)k);
        const char *v[4] = {id, name, kb, buf};
        const int len[4] = {0, 0, 0, (int)want}, fmt[4] = {0, 0, 0, 1};
        r = PQexecParams(c,
                         "INSERT INTO blob_chunks(job_id, name, k, data)"
                         " VALUES($1, $2, $3, $4)",
                         4, NULL, v, len, fmt, 0);
        if (!r || !result_ok(r)) {
            fprintf(stderr, "qdcd: postgresql: %s",
                    r ? PQresultErrorMessage(r) : PQerrorMessage(c));
            PQclear(r);
            goto out;
        }
        PQclear(r);
    }
    st = QDC_OK;
out:
    free(buf);
    close(fd);
    return st;
}

static qdc_status put_tx(PGconn *c, const char *id, const char *name, const char *path,
                         const char *sha, const char *worker)
{
    params p = {.n = 0};
    char state[6];
    qdc_status st = QDC_EIO;
    PGresult *r = pg_cx(c, "BEGIN", NULL, state);

    if (!r)
        return QDC_EIO;
    PQclear(r);
    p_text(&p, id);
    if (worker) {
        /* KEY SHARE: a claim by another node (FOR UPDATE SKIP LOCKED) passes
         * this row by until the results are in, progress updates do not wait */
        p_text(&p, worker);
        r = pg_cx(c,
                  "SELECT 1 FROM jobs WHERE id = $1 AND lease_owner = $2 AND state = 1"
                  " FOR KEY SHARE",
                  &p, state);
        if (!r)
            return QDC_EIO;
        int n = PQntuples(r);
        PQclear(r);
        if (!n)
            return QDC_EINVAL;
        p.n = 1;
    }
    p_text(&p, name);
    r = pg_cx(c, "DELETE FROM blobs WHERE job_id = $1 AND name = $2", &p, state);
    if (!r)
        return QDC_EIO;
    PQclear(r);
    st = put_chunks(c, id, name, path, sha);
    if (st != QDC_OK)
        return st;
    r = pg_cx(c, "COMMIT", NULL, state);
    if (!r)
        return QDC_EIO;
    PQclear(r);
    return QDC_OK;
}

static qdc_status pg_blob_put(job_store *s_, const char *id, const char *name,
                              const char *path, const char *sha, const char *worker)
{
    pg_store *s = (pg_store *)s_;
    qdc_status st = QDC_EIO;

    /* a connection found broken: once more on a fresh one */
    for (int attempt = 0; attempt < 2; attempt++) {
        int i = pool_take(s);
        if (i < 0)
            return QDC_EIO;
        st = put_tx(s->pool[i], id, name, path, sha, worker);
        int bad = PQstatus(s->pool[i]) != CONNECTION_OK;
        pool_give(s, i);
        if (st != QDC_EIO || !bad)
            break;
    }
    return st;
}

static qdc_status get_tx(PGconn *c, const char *id, const char *name, const char *path,
                         char *sha)
{
    params p = {.n = 0};
    char state[6], tmp[4400];
    qdc_status st = QDC_EIO;
    int64_t size, nch, total = 0, rows = 0;
    int fd, bad = 0;
    PGresult *r;

    /* one snapshot: a blob replaced meanwhile is read whole, old or new */
    r = pg_cx(c, "BEGIN ISOLATION LEVEL REPEATABLE READ READ ONLY", NULL, state);
    if (!r)
        return QDC_EIO;
    PQclear(r);
    p_text(&p, id);
    p_text(&p, name);
    r = pg_cx(c,
              "SELECT size, sha256, nchunks FROM blobs WHERE job_id = $1 AND name = $2",
              &p, state);
    if (!r)
        return QDC_EIO;
    if (!PQntuples(r)) {
        PQclear(r);
        return QDC_EINVAL;
    }
    size = col_i64(r, 0, 0);
    if (sha)
        col_text(r, 0, 1, sha, 65);
    nch = col_i64(r, 0, 2);
    PQclear(r);
    snprintf(tmp, sizeof tmp, "%s.XXXXXX", path);
    fd = mkostemp(tmp, O_CLOEXEC);
    if (fd < 0)
        return QDC_EIO;
    /* single-row mode: one chunk in memory at a time */
    if (!PQsendQueryParams(c,
                           "SELECT data FROM blob_chunks WHERE job_id = $1 AND name = $2"
                           " ORDER BY k",
                           2, NULL, p.v, NULL, NULL, 1) ||
        !PQsetSingleRowMode(c))
        bad = 1;
    while ((r = PQgetResult(c)) != NULL) {
        ExecStatusType es = PQresultStatus(r);
        if (es == PGRES_SINGLE_TUPLE && !bad) {
            const char *d = PQgetvalue(r, 0, 0);
            size_t n = (size_t)PQgetlength(r, 0, 0);
            rows++;
            total += (int64_t)n;
            while (n) {
                ssize_t w = write(fd, d, n);
                if (w < 0 && errno == EINTR)
                    continue;
                if (w <= 0) {
                    bad = 1;
                    break;
                }
                d += w;
                n -= (size_t)w;
            }
        } else if (es != PGRES_TUPLES_OK && es != PGRES_SINGLE_TUPLE) {
            fprintf(stderr, "qdcd: postgresql: %s", PQresultErrorMessage(r));
            bad = 1;
        }
        PQclear(r);
    }
    r = pg_cx(c, "COMMIT", NULL, state);
    PQclear(r);
    if (close(fd))
        bad = 1;
    if (!bad && rows == nch && total == size && rename(tmp, path) == 0)
        st = QDC_OK;
    else
        unlink(tmp);
    return st;
}

static qdc_status pg_blob_get(job_store *s_, const char *id, const char *name,
                              const char *path, char *sha)
{
    pg_store *s = (pg_store *)s_;
    qdc_status st = QDC_EIO;

    for (int attempt = 0; attempt < 2; attempt++) {
        int i = pool_take(s);
        if (i < 0)
            return QDC_EIO;
        st = get_tx(s->pool[i], id, name, path, sha);
        int bad = PQstatus(s->pool[i]) != CONNECTION_OK;
        pool_give(s, i);
        if (st != QDC_EIO || !bad)
            break;
    }
    return st;
}

/* The row and its input (name from path; name2 from path2 too unless NULL)
 * in one transaction: other nodes see (and claim) the job only once its
 * input is there; a duplicate Idempotency-Key stores nothing. */
static qdc_status create_tx(PGconn *c, const job_rec *j, const char *name,
                            const char *path, const char *name2, const char *path2,
                            int *inserted)
{
    params p = {.n = 0};
    char state[6];
    qdc_status st;
    PGresult *r = pg_cx(c, "BEGIN", NULL, state);

    *inserted = 0;
    if (!r)
        return QDC_EIO;
    PQclear(r);
    create_params(j, &p);
    r = pg_cx(c, INSERT_JOB, &p, state);
    if (!r)
        return QDC_EIO;
    *inserted = PQntuples(r) == 1;
    PQclear(r);
    if (!*inserted)
        return QDC_OK; /* the key was taken: the caller rolls back */
    st = put_chunks(c, j->id, name, path, "");
    if (st == QDC_OK && name2)
        st = put_chunks(c, j->id, name2, path2, "");
    if (st != QDC_OK)
        return st;
    r = pg_cx(c, "COMMIT", NULL, state);
    if (!r) {
        *inserted = 0;
        return QDC_EIO;
    }
    PQclear(r);
    return QDC_OK;
}

static qdc_status pg_create_with_input(job_store *s_, const job_rec *j, const char *name,
                                       const char *path, const char *name2,
                                       const char *path2, int *dup, job_rec *existing)
{
    pg_store *s = (pg_store *)s_;
    qdc_status st = QDC_EIO;
    int inserted = 0;

    *dup = 0;
    for (int attempt = 0; attempt < 2; attempt++) {
        int i = pool_take(s);
        if (i < 0)
            return QDC_EIO;
        st = create_tx(s->pool[i], j, name, path, name2, path2, &inserted);
        int bad = PQstatus(s->pool[i]) != CONNECTION_OK;
        pool_give(s, i); /* rolls back what was not committed */
        if (st != QDC_EIO || !bad)
            break;
    }
    if (st != QDC_OK || inserted)
        return st;
    return existing_idem(s, j, dup, existing);
}

static void pg_close(job_store *s_)
{
    pg_store *s = (pg_store *)s_;

    if (!s)
        return;
    pg_listen(s_, NULL, NULL);
    if (s->wq_running) {
        pthread_mutex_lock(&s->wq_lock);
        s->wq_stop = 1;
        pthread_cond_signal(&s->wq_cond);
        pthread_mutex_unlock(&s->wq_lock);
        pthread_join(s->wq_th, NULL);
    }
    while (s->wq_head) {
        prec *nx = s->wq_head->next;
        free(s->wq_head);
        s->wq_head = nx;
    }
    for (int i = 0; i < POOL_MAX; i++)
        PQfinish(s->pool[i]);
    PQfinish(s->conn);
    pthread_mutex_destroy(&s->lock);
    pthread_mutex_destroy(&s->pool_lock);
    pthread_cond_destroy(&s->pool_cond);
    pthread_mutex_destroy(&s->wq_lock);
    pthread_cond_destroy(&s->wq_cond);
    pthread_cond_destroy(&s->wq_done);
    free(s);
}

static const job_store_ops pg_ops = {
    pg_create,        pg_get,         pg_find_idem,    pg_list,
    pg_claim,         pg_renew,       pg_finish,       pg_release,
    pg_cancel,        pg_remove,      pg_recover,      pg_counts,
    pg_expired,       pg_mark_purged, pg_close,        pg_create_with_input,
    pg_blob_put,      pg_blob_get,    pg_progress_add, pg_progress_sync,
    pg_progress_read, pg_listen,
};

/* Bring the schema to the newest version, in one transaction under an
 * advisory lock: nodes that start together migrate once, one after the other. */
static qdc_status migrate(pg_store *s, qdc_error *err)
{
    PGresult *r;
    int have = 0;
    qdc_status st = QDC_OK;

    r = pg_run(s, "BEGIN", NULL);
    if (!r)
        return qdc_fail(err, QDC_EIO, "postgresql: cannot begin the schema migration");
    PQclear(r);
    /* 0x716463 = "qdc": one lock id for every qdcd on this database */
    r = pg_run(s, "SELECT pg_advisory_xact_lock(7431267)", NULL);
    if (r) {
        PQclear(r);
        r = pg_run(s, "CREATE TABLE IF NOT EXISTS qdc_schema(version INTEGER NOT NULL)",
                   NULL);
    }
    if (r) {
        PQclear(r);
        r = pg_run(s, "SELECT COALESCE(MAX(version), 0) FROM qdc_schema", NULL);
    }
    if (!r) {
        st = qdc_fail(err, QDC_EIO, "postgresql: cannot read the schema version");
        goto out;
    }
    have = (int)col_i64(r, 0, 0);
    PQclear(r);
    if (have > N_MIGRATIONS) {
        st = qdc_fail(err, QDC_EINVAL,
                      "postgresql: the database has schema version %d, newer than this "
                      "qdcd knows (%d): upgrade qdcd",
                      have, N_MIGRATIONS);
        goto out;
    }
    for (int v = have; v < N_MIGRATIONS; v++) {
        params p = {.n = 0};
        r = pg_run(s, migrations[v], NULL);
        if (!r) {
            st = qdc_fail(err, QDC_EIO,
                          "postgresql: schema migration to version %d failed", v + 1);
            goto out;
        }
        PQclear(r);
        p_i64(&p, v + 1);
        r = pg_run(s, "INSERT INTO qdc_schema(version) VALUES($1)", &p);
        if (!r) {
            st = qdc_fail(err, QDC_EIO, "postgresql: cannot record schema version %d",
                          v + 1);
            goto out;
        }
        PQclear(r);
    }
out:
    r = pg_run(s, st == QDC_OK ? "COMMIT" : "ROLLBACK", NULL);
    if (!r && st == QDC_OK)
        st = qdc_fail(err, QDC_EIO, "postgresql: cannot commit the schema migration");
    PQclear(r);
    return st;
}

int store_pg_uri(const char *uri)
{
    return !strncmp(uri, "postgresql://", 13) || !strncmp(uri, "postgres://", 11);
}

qdc_status store_pg_open(const char *uri, job_store **out, qdc_error *err)
{
    pg_store *s;
    qdc_status st;

    *out = NULL;
    if (!store_pg_uri(uri))
        return qdc_fail(err, QDC_EINVAL, "not a postgresql:// URI: %s", uri);
    s = calloc(1, sizeof *s);
    if (!s)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    s->base.ops = &pg_ops;
    pthread_mutex_init(&s->lock, NULL);
    pthread_mutex_init(&s->pool_lock, NULL);
    pthread_cond_init(&s->pool_cond, NULL);
    pthread_mutex_init(&s->wq_lock, NULL);
    pthread_cond_init(&s->wq_cond, NULL);
    pthread_cond_init(&s->wq_done, NULL);
    snprintf(s->uri, sizeof s->uri, "%s", uri);
    s->max_attempts = 1000;
    s->conn = pg_connect(uri);
    if (!s->conn || PQstatus(s->conn) != CONNECTION_OK) {
        /* libpq's message names the host and the reason; never the password */
        st = qdc_fail(err, QDC_EIO, "postgresql: cannot connect: %s",
                      s->conn ? PQerrorMessage(s->conn) : "out of memory");
        pg_close(&s->base);
        return st;
    }
    st = migrate(s, err);
    if (st != QDC_OK) {
        pg_close(&s->base);
        return st;
    }
    if (pthread_create(&s->wq_th, NULL, pg_writer_main, s)) {
        pg_close(&s->base);
        return qdc_fail(err, QDC_ENOMEM, "cannot start the progress writer");
    }
    s->wq_running = 1;
    *out = &s->base;
    return QDC_OK;
}
