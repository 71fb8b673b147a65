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
 * One connection, serialized by a mutex; a broken connection is reset and the
 * statement tried once more, so a restarted database costs one failed call,
 * not a dead node. Every call is a single statement (autocommit) unless it
 * says otherwise. */
#define _GNU_SOURCE
#include "store.h"
#include "util.h"

#include <libpq-fe.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    job_store base;
    PGconn *conn;
    pthread_mutex_t lock;
    char uri[1024];
} pg_store;

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
};
#define N_MIGRATIONS ((int)(sizeof migrations / sizeof migrations[0]))

#define COLS                                                                             \
    "seq, id, owner, state, cancel_requested, idem_key, body_hash, format, nv, nt,"      \
    " in_bytes, options, attempts, lease_owner, lease_until, created, started,"          \
    " finished, expires, purged, iterations, last_progress, error, stop_reason,"         \
    " etag_qmesh, etag_json, etag_medit, notes"

static void col_text(const PGresult *r, int row, int i, char *dst, size_t cap)
{
    snprintf(dst, cap, "%s", PQgetisnull(r, row, i) ? "" : PQgetvalue(r, row, i));
}

static int64_t col_i64(const PGresult *r, int row, int i)
{
    return PQgetisnull(r, row, i) ? 0 : strtoll(PQgetvalue(r, row, i), NULL, 10);
}

static double col_dbl(const PGresult *r, int row, int i)
{
    return PQgetisnull(r, row, i) ? 0.0 : strtod(PQgetvalue(r, row, i), NULL);
}

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
}

/* Parameters are passed as text; numbers are formatted into small buffers. */
typedef struct {
    const char *v[16];
    char num[16][32];
    int n;
} params;

static void p_text(params *p, const char *s)
{
    p->v[p->n++] = s;
}

static void p_i64(params *p, int64_t x)
{
    snprintf(p->num[p->n], sizeof p->num[0], "%lld", (long long)x);
    p->v[p->n] = p->num[p->n];
    p->n++;
}

static void p_dbl(params *p, double x)
{
    snprintf(p->num[p->n], sizeof p->num[0], "%.17g", x);
    p->v[p->n] = p->num[p->n];
    p->n++;
}

static int result_ok(const PGresult *r)
{
    ExecStatusType st = PQresultStatus(r);
    return st == PGRES_COMMAND_OK || st == PGRES_TUPLES_OK;
}

/* Run sql with p on the connection (lock held). A connection found broken is
 * reset once and the statement retried: a statement that failed on a broken
 * connection never reached the server's commit, so running it again is safe.
 * NULL (logged) if it still fails. The caller PQclear()s the result. */
static PGresult *run(pg_store *s, const char *sql, const params *p)
{
    for (int attempt = 0; attempt < 2; attempt++) {
        /* without parameters: the simple protocol, which also takes a script
         * of several statements (the migrations) */
        PGresult *r = p ? PQexecParams(s->conn, sql, p->n, NULL, p->v, NULL, NULL, 0)
                        : PQexec(s->conn, sql);
        if (r && result_ok(r))
            return r;
        if (PQstatus(s->conn) == CONNECTION_BAD && attempt == 0) {
            PQclear(r);
            PQreset(s->conn);
            continue;
        }
        fprintf(stderr, "qdcd: postgresql: %s",
                r ? PQresultErrorMessage(r) : PQerrorMessage(s->conn));
        PQclear(r);
        return NULL;
    }
    return NULL;
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
    r = run(s, sql, p);
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

static qdc_status pg_create(job_store *s_, const job_rec *j, int *dup, job_rec *existing)
{
    pg_store *s = (pg_store *)s_;
    params p = {.n = 0};
    int n = 0;
    qdc_status st;

    *dup = 0;
    p_text(&p, j->id);
    p_text(&p, j->owner);
    p_text(&p, j->idem_key);
    p_text(&p, j->body_hash);
    p_text(&p, j->format);
    p_i64(&p, j->nv);
    p_i64(&p, j->nt);
    p_i64(&p, j->in_bytes);
    p_text(&p, j->options);
    p_dbl(&p, j->created);
    p_text(&p, j->notes);
    /* The unique index decides a duplicate key in this statement, whichever
     * node gets there first. */
    st = one(s,
             "INSERT INTO jobs(id, owner, state, idem_key, body_hash, format, nv, nt,"
             " in_bytes, options, created, notes)"
             " VALUES($1,$2,0,$3,$4,$5,$6,$7,$8,$9,$10,$11)"
             " ON CONFLICT (owner, idem_key) WHERE idem_key <> '' DO NOTHING"
             " RETURNING seq",
             &p, NULL, &n);
    if (st != QDC_OK || n == 1)
        return st;
    /* the key was taken: the job that holds it */
    p.n = 0;
    p_text(&p, j->owner);
    p_text(&p, j->idem_key);
    st = one(s, "SELECT " COLS " FROM jobs WHERE owner = $1 AND idem_key = $2", &p,
             existing, &n);
    if (st == QDC_OK && n == 1)
        *dup = 1;
    return st == QDC_OK && n == 1 ? QDC_OK : QDC_EIO;
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
    r = run(s,
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
    st = one((pg_store *)s_,
             "UPDATE jobs SET state = 1, attempts = attempts + 1, lease_owner = $1,"
             " lease_until = $2, started = $3, iterations = 0, last_progress = ''"
             " WHERE seq = (SELECT seq FROM jobs WHERE state = 0"
             " OR (state = 1 AND lease_until < $3 AND lease_owner NOT LIKE $4)"
             " ORDER BY seq LIMIT 1 FOR UPDATE SKIP LOCKED)"
             " RETURNING " COLS,
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
    return one((pg_store *)s_,
               "UPDATE jobs SET state = $1, finished = $2, expires = $3, iterations = $4,"
               " last_progress = $5, error = $6, stop_reason = $7, etag_qmesh = $8,"
               " etag_json = $9, etag_medit = $10, nv = $11, nt = $12, lease_owner = '',"
               " lease_until = 0 WHERE id = $13",
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
    return one((pg_store *)s_, "DELETE FROM jobs WHERE id = $1", &p, NULL, NULL);
}

/* Start-up of a node: jobs whose lease expired (their node died) go back to
 * the queue, or fail when they used all their attempts. Jobs that other,
 * live nodes are running keep their leases. */
static qdc_status pg_recover(job_store *s_, int max_attempts, double retention,
                             int *requeued, int *failed)
{
    pg_store *s = (pg_store *)s_;
    params p = {.n = 0};
    char err[512];
    double now = wall_now();
    qdc_status st;

    snprintf(
        err, sizeof err,
        "{\"type\":\"/problems/attempts-exhausted\",\"title\":\"job crashed the daemon\","
        "\"status\":500,\"detail\":\"a daemon died while running this job on each of "
        "its %d attempt(s); it is not retried\",\"attempts\":%d}",
        max_attempts, max_attempts);
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
    r = run(s, "SELECT state, COUNT(*) FROM jobs GROUP BY state", NULL);
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
    r = run(
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
    return one((pg_store *)s_, "UPDATE jobs SET purged = 1 WHERE id = $1", &p, NULL,
               NULL);
}

static void pg_close(job_store *s_)
{
    pg_store *s = (pg_store *)s_;

    if (!s)
        return;
    PQfinish(s->conn);
    pthread_mutex_destroy(&s->lock);
    free(s);
}

static const job_store_ops pg_ops = {
    pg_create,  pg_get,    pg_find_idem, pg_list,        pg_claim,
    pg_renew,   pg_finish, pg_release,   pg_cancel,      pg_remove,
    pg_recover, pg_counts, pg_expired,   pg_mark_purged, pg_close,
};

/* Bring the schema to the newest version, in one transaction under an
 * advisory lock: nodes that start together migrate once, one after the other. */
static qdc_status migrate(pg_store *s, qdc_error *err)
{
    PGresult *r;
    int have = 0;
    qdc_status st = QDC_OK;

    r = run(s, "BEGIN", NULL);
    if (!r)
        return qdc_fail(err, QDC_EIO, "postgresql: cannot begin the schema migration");
    PQclear(r);
    /* 0x716463 = "qdc": one lock id for every qdcd on this database */
    r = run(s, "SELECT pg_advisory_xact_lock(7431267)", NULL);
    if (r) {
        PQclear(r);
        r = run(s, "CREATE TABLE IF NOT EXISTS qdc_schema(version INTEGER NOT NULL)",
                NULL);
    }
    if (r) {
        PQclear(r);
        r = run(s, "SELECT COALESCE(MAX(version), 0) FROM qdc_schema", NULL);
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
        r = run(s, migrations[v], NULL);
        if (!r) {
            st = qdc_fail(err, QDC_EIO,
                          "postgresql: schema migration to version %d failed", v + 1);
            goto out;
        }
        PQclear(r);
        p_i64(&p, v + 1);
        r = run(s, "INSERT INTO qdc_schema(version) VALUES($1)", &p);
        if (!r) {
            st = qdc_fail(err, QDC_EIO, "postgresql: cannot record schema version %d",
                          v + 1);
            goto out;
        }
        PQclear(r);
    }
out:
    r = run(s, st == QDC_OK ? "COMMIT" : "ROLLBACK", NULL);
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
    snprintf(s->uri, sizeof s->uri, "%s", uri);
    s->conn = PQconnectdb(uri);
    if (!s->conn || PQstatus(s->conn) != CONNECTION_OK) {
        /* libpq's message names the host and the reason; never the password */
        st = qdc_fail(err, QDC_EIO, "postgresql: cannot connect: %s",
                      s->conn ? PQerrorMessage(s->conn) : "out of memory");
        pg_close(&s->base);
        return st;
    }
    /* quiet NOTICEs (e.g. "relation already exists"), UTC timestamps */
    PQclear(run(s, "SET client_min_messages = warning", NULL));
    st = migrate(s, err);
    if (st != QDC_OK) {
        pg_close(&s->base);
        return st;
    }
    *out = &s->base;
    return QDC_OK;
}
