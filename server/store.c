/* store.c - job_store backed by SQLite in WAL mode (DIR/qdcd.db).
 * Two connections: one writer shared by workers and handlers (serialized by a
 * mutex; synchronous=FULL, so a commit is on disk before the call returns and a
 * 202 never promises a job that a crash could lose), and one reader for the
 * HTTP thread, which under WAL never waits for the writer's fsync. */
#define _GNU_SOURCE
#include "store.h"
#include "problem.h"
#include "util.h"

#include <pthread.h>
#include <sqlite3.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    job_store base;
    sqlite3 *wr, *rd;
    pthread_mutex_t wr_lock, rd_lock;
} sq_store;

static const char *const state_names[JOB_STATE_COUNT] = {"queued", "running", "succeeded",
                                                         "failed", "cancelled"};

const char *job_state_name(job_state s)
{
    return (unsigned)s < JOB_STATE_COUNT ? state_names[s] : "unknown";
}

int job_state_done(job_state s)
{
    return s == JOB_SUCCEEDED || s == JOB_FAILED || s == JOB_CANCELLED;
}

int job_has_result(const job_rec *j)
{
    return j->state == JOB_SUCCEEDED || (j->state == JOB_CANCELLED && j->etag_qmesh[0]);
}

static const char schema[] =
    "CREATE TABLE IF NOT EXISTS jobs("
    " seq INTEGER PRIMARY KEY AUTOINCREMENT, id TEXT UNIQUE NOT NULL,"
    " owner TEXT NOT NULL, state INTEGER NOT NULL, cancel_requested INTEGER DEFAULT 0,"
    " idem_key TEXT NOT NULL, body_hash TEXT NOT NULL, format TEXT NOT NULL,"
    " nv INTEGER, nt INTEGER, in_bytes INTEGER, options TEXT NOT NULL,"
    " attempts INTEGER DEFAULT 0, lease_owner TEXT DEFAULT '', lease_until REAL DEFAULT "
    "0,"
    " created REAL, started REAL DEFAULT 0, finished REAL DEFAULT 0, expires REAL "
    "DEFAULT 0,"
    " purged INTEGER DEFAULT 0, iterations INTEGER DEFAULT 0, last_progress TEXT DEFAULT "
    "'',"
    " error TEXT DEFAULT '', stop_reason TEXT DEFAULT '', etag_qmesh TEXT DEFAULT '',"
    " etag_json TEXT DEFAULT '', etag_medit TEXT DEFAULT '', notes TEXT DEFAULT '',"
    " file_name TEXT DEFAULT '', label TEXT DEFAULT '', input_h5 INTEGER DEFAULT 0);"
    "CREATE UNIQUE INDEX IF NOT EXISTS jobs_idem ON jobs(owner, idem_key) WHERE idem_key "
    "!= '';"
    "CREATE INDEX IF NOT EXISTS jobs_state ON jobs(state, seq);"
    "CREATE INDEX IF NOT EXISTS jobs_expiry ON jobs(purged, expires);";

#define COLS                                                                             \
    "seq, id, owner, state, cancel_requested, idem_key, body_hash, format, nv, nt,"      \
    " in_bytes, options, attempts, lease_owner, lease_until, created, started, "         \
    "finished,"                                                                          \
    " expires, purged, iterations, last_progress, error, stop_reason, etag_qmesh,"       \
    " etag_json, etag_medit, notes, file_name, label, input_h5"

static void col_text(sqlite3_stmt *st, int i, char *dst, size_t cap)
{
    const unsigned char *t = sqlite3_column_text(st, i);
    snprintf(dst, cap, "%s", t ? (const char *)t : "");
}

static void row_to_rec(sqlite3_stmt *st, job_rec *j)
{
    memset(j, 0, sizeof *j);
    j->seq = sqlite3_column_int64(st, 0);
    col_text(st, 1, j->id, sizeof j->id);
    col_text(st, 2, j->owner, sizeof j->owner);
    j->state = (job_state)sqlite3_column_int(st, 3);
    j->cancel_requested = sqlite3_column_int(st, 4);
    col_text(st, 5, j->idem_key, sizeof j->idem_key);
    col_text(st, 6, j->body_hash, sizeof j->body_hash);
    col_text(st, 7, j->format, sizeof j->format);
    j->nv = sqlite3_column_int64(st, 8);
    j->nt = sqlite3_column_int64(st, 9);
    j->in_bytes = sqlite3_column_int64(st, 10);
    col_text(st, 11, j->options, sizeof j->options);
    j->attempts = sqlite3_column_int(st, 12);
    col_text(st, 13, j->lease_owner, sizeof j->lease_owner);
    j->lease_until = sqlite3_column_double(st, 14);
    j->created = sqlite3_column_double(st, 15);
    j->started = sqlite3_column_double(st, 16);
    j->finished = sqlite3_column_double(st, 17);
    j->expires = sqlite3_column_double(st, 18);
    j->purged = sqlite3_column_int(st, 19);
    j->iterations = sqlite3_column_int(st, 20);
    col_text(st, 21, j->last_progress, sizeof j->last_progress);
    col_text(st, 22, j->error, sizeof j->error);
    col_text(st, 23, j->stop_reason, sizeof j->stop_reason);
    col_text(st, 24, j->etag_qmesh, sizeof j->etag_qmesh);
    col_text(st, 25, j->etag_json, sizeof j->etag_json);
    col_text(st, 26, j->etag_medit, sizeof j->etag_medit);
    col_text(st, 27, j->notes, sizeof j->notes);
    col_text(st, 28, j->file_name, sizeof j->file_name);
    col_text(st, 29, j->label, sizeof j->label);
    j->input_h5 = sqlite3_column_int(st, 30);
}

/* Prepare sql on db; binds are done by the caller. NULL on failure. */
static sqlite3_stmt *prep(sqlite3 *db, const char *sql)
{
    sqlite3_stmt *st = NULL;
    if (sqlite3_prepare_v2(db, sql, -1, &st, NULL) != SQLITE_OK) {
        fprintf(stderr, "qdcd: sqlite: %s: %s\n", sqlite3_errmsg(db), sql);
        return NULL;
    }
    return st;
}

static qdc_status exec(sqlite3 *db, const char *sql)
{
    char *msg = NULL;
    if (sqlite3_exec(db, sql, NULL, NULL, &msg) != SQLITE_OK) {
        fprintf(stderr, "qdcd: sqlite: %s: %s\n", msg ? msg : "?", sql);
        sqlite3_free(msg);
        return QDC_EIO;
    }
    return QDC_OK;
}

/* End a transaction begun with BEGIN IMMEDIATE: commit if rc is QDC_OK and
 * commit_ok, else roll back. Finalizes st. Returns the outcome. */
static qdc_status end_tx(sqlite3 *db, sqlite3_stmt *st, qdc_status rc, int commit_ok)
{
    sqlite3_finalize(st);
    if (rc == QDC_OK && commit_ok) {
        rc = exec(db, "COMMIT");
        if (rc == QDC_OK)
            return rc;
    }
    exec(db, "ROLLBACK");
    return rc;
}

static void bind_text(sqlite3_stmt *st, int i, const char *s)
{
    sqlite3_bind_text(st, i, s, -1, SQLITE_TRANSIENT);
}

/* Fetch one row by id on db into out; QDC_EINVAL if absent. */
static qdc_status fetch(sqlite3 *db, const char *id, job_rec *out)
{
    qdc_status rc = QDC_EIO;
    sqlite3_stmt *st = prep(db, "SELECT " COLS " FROM jobs WHERE id = ?");

    if (!st)
        return QDC_EIO;
    bind_text(st, 1, id);
    switch (sqlite3_step(st)) {
    case SQLITE_ROW:
        row_to_rec(st, out);
        rc = QDC_OK;
        break;
    case SQLITE_DONE:
        rc = QDC_EINVAL;
        break;
    default:
        break;
    }
    sqlite3_finalize(st);
    return rc;
}

static qdc_status sq_create(job_store *s_, const job_rec *j, int *dup, job_rec *existing)
{
    sq_store *s = (sq_store *)s_;
    qdc_status rc = QDC_EIO;
    sqlite3_stmt *st = NULL;
    int ok = 0;

    *dup = 0;
    pthread_mutex_lock(&s->wr_lock);
    if (exec(s->wr, "BEGIN IMMEDIATE") != QDC_OK)
        goto out;
    if (j->idem_key[0]) {
        st = prep(s->wr, "SELECT " COLS " FROM jobs WHERE owner = ? AND idem_key = ?");
        if (!st)
            goto end;
        bind_text(st, 1, j->owner);
        bind_text(st, 2, j->idem_key);
        if (sqlite3_step(st) == SQLITE_ROW) {
            row_to_rec(st, existing);
            *dup = 1;
            rc = QDC_OK; /* nothing to commit */
            goto end;
        }
        sqlite3_finalize(st);
    }
    st = prep(s->wr,
              "INSERT INTO jobs(id, owner, state, idem_key, body_hash, format, nv, nt,"
              " in_bytes, options, created, notes, file_name, label, input_h5)"
              " VALUES(?,?,0,?,?,?,?,?,?,?,?,?,?,?,?)");
    if (!st)
        goto end;
    bind_text(st, 1, j->id);
    bind_text(st, 2, j->owner);
    bind_text(st, 3, j->idem_key);
    bind_text(st, 4, j->body_hash);
    bind_text(st, 5, j->format);
    sqlite3_bind_int64(st, 6, j->nv);
    sqlite3_bind_int64(st, 7, j->nt);
    sqlite3_bind_int64(st, 8, j->in_bytes);
    bind_text(st, 9, j->options);
    sqlite3_bind_double(st, 10, j->created);
    bind_text(st, 11, j->notes);
    bind_text(st, 12, j->file_name);
    bind_text(st, 13, j->label);
    sqlite3_bind_int(st, 14, j->input_h5);
    ok = sqlite3_step(st) == SQLITE_DONE;
    rc = ok ? QDC_OK : QDC_EIO;
end:
    rc = end_tx(s->wr, st, rc, ok);
out:
    pthread_mutex_unlock(&s->wr_lock);
    return rc;
}

static qdc_status sq_get(job_store *s_, const char *id, job_rec *out)
{
    sq_store *s = (sq_store *)s_;
    qdc_status rc;

    pthread_mutex_lock(&s->rd_lock);
    rc = fetch(s->rd, id, out);
    pthread_mutex_unlock(&s->rd_lock);
    return rc;
}

static qdc_status sq_find_idem(job_store *s_, const char *owner, const char *key,
                               job_rec *out)
{
    sq_store *s = (sq_store *)s_;
    qdc_status rc = QDC_EIO;
    sqlite3_stmt *st;

    pthread_mutex_lock(&s->rd_lock);
    st = prep(s->rd, "SELECT " COLS " FROM jobs WHERE owner = ? AND idem_key = ?");
    if (st) {
        bind_text(st, 1, owner);
        bind_text(st, 2, key);
        int r = sqlite3_step(st);
        if (r == SQLITE_ROW)
            row_to_rec(st, out);
        rc = r == SQLITE_ROW ? QDC_OK : r == SQLITE_DONE ? QDC_EINVAL : QDC_EIO;
        sqlite3_finalize(st);
    }
    pthread_mutex_unlock(&s->rd_lock);
    return rc;
}

static qdc_status sq_list(job_store *s_, const char *owner, int64_t after_seq, int max,
                          job_rec *out, int *n)
{
    sq_store *s = (sq_store *)s_;
    qdc_status rc = QDC_OK;
    sqlite3_stmt *st;
    int r;

    *n = 0;
    pthread_mutex_lock(&s->rd_lock);
    st = prep(s->rd, "SELECT " COLS " FROM jobs WHERE owner = ? AND seq > ?"
                     " ORDER BY seq LIMIT ?");
    if (!st) {
        rc = QDC_EIO;
        goto out;
    }
    bind_text(st, 1, owner);
    sqlite3_bind_int64(st, 2, after_seq);
    sqlite3_bind_int(st, 3, max);
    while ((r = sqlite3_step(st)) == SQLITE_ROW && *n < max)
        row_to_rec(st, &out[(*n)++]);
    if (r != SQLITE_ROW && r != SQLITE_DONE)
        rc = QDC_EIO;
    sqlite3_finalize(st);
out:
    pthread_mutex_unlock(&s->rd_lock);
    return rc;
}

/* The worker name is "<instance>/w<N>"; jobs leased by this instance are never
 * taken over, whatever their lease says (a slow iteration is not a dead worker). */
static qdc_status sq_claim(job_store *s_, const char *worker, double lease_s,
                           job_rec *out, int *found)
{
    sq_store *s = (sq_store *)s_;
    qdc_status rc = QDC_EIO;
    sqlite3_stmt *st = NULL;
    char inst[64], id[JOB_ID_LEN + 1];
    double now = wall_now();
    const char *slash = strchr(worker, '/');
    int r;

    snprintf(inst, sizeof inst, "%.*s/%%", slash ? (int)(slash - worker) : 0, worker);
    *found = 0;
    pthread_mutex_lock(&s->wr_lock);
    if (exec(s->wr, "BEGIN IMMEDIATE") != QDC_OK)
        goto out;
    st = prep(s->wr,
              "SELECT id FROM jobs WHERE state = 0 OR (state = 1 AND lease_until < ?"
              " AND lease_owner NOT LIKE ?) ORDER BY seq LIMIT 1");
    if (!st)
        goto end;
    sqlite3_bind_double(st, 1, now);
    bind_text(st, 2, inst);
    r = sqlite3_step(st);
    if (r != SQLITE_ROW) {
        rc = r == SQLITE_DONE ? QDC_OK : QDC_EIO; /* DONE: nothing to claim */
        goto end;
    }
    col_text(st, 0, id, sizeof id);
    sqlite3_finalize(st);
    st =
        prep(s->wr, "UPDATE jobs SET state = 1, attempts = attempts + 1, lease_owner = ?,"
                    " lease_until = ?, started = ?, iterations = 0, last_progress = ''"
                    " WHERE id = ?");
    if (!st)
        goto end;
    bind_text(st, 1, worker);
    sqlite3_bind_double(st, 2, now + lease_s);
    sqlite3_bind_double(st, 3, now);
    bind_text(st, 4, id);
    if (sqlite3_step(st) == SQLITE_DONE && fetch(s->wr, id, out) == QDC_OK) {
        *found = 1;
        rc = QDC_OK;
    }
end:
    rc = end_tx(s->wr, st, rc, *found);
    if (rc != QDC_OK)
        *found = 0;
out:
    pthread_mutex_unlock(&s->wr_lock);
    return rc;
}

/* Run one UPDATE/DELETE with text/double binds described by fmt ('t' text,
 * 'd' double, 'i' int64) on the writer; *changes gets the row count. */
static qdc_status write1(sq_store *s, int *changes, const char *sql, const char *fmt, ...)
{
    qdc_status rc = QDC_EIO;
    va_list ap;
    sqlite3_stmt *st;

    pthread_mutex_lock(&s->wr_lock);
    st = prep(s->wr, sql);
    if (!st)
        goto out;
    va_start(ap, fmt);
    for (int i = 0; fmt[i]; i++) {
        if (fmt[i] == 't')
            bind_text(st, i + 1, va_arg(ap, const char *));
        else if (fmt[i] == 'd')
            sqlite3_bind_double(st, i + 1, va_arg(ap, double));
        else
            sqlite3_bind_int64(st, i + 1, va_arg(ap, int64_t));
    }
    va_end(ap);
    if (sqlite3_step(st) == SQLITE_DONE) {
        rc = QDC_OK;
        if (changes)
            *changes = sqlite3_changes(s->wr);
    } else {
        fprintf(stderr, "qdcd: sqlite: %s\n", sqlite3_errmsg(s->wr));
    }
    sqlite3_finalize(st);
out:
    pthread_mutex_unlock(&s->wr_lock);
    return rc;
}

static qdc_status sq_renew(job_store *s_, const char *id, const char *worker,
                           double lease_s)
{
    return write1((sq_store *)s_, NULL,
                  "UPDATE jobs SET lease_until = ? WHERE id = ? AND lease_owner = ?",
                  "dtt", wall_now() + lease_s, id, worker);
}

static qdc_status sq_finish(job_store *s_, const job_rec *j)
{
    return write1((sq_store *)s_, NULL,
                  "UPDATE jobs SET state = ?, finished = ?, expires = ?, iterations = ?,"
                  " last_progress = ?, error = ?, stop_reason = ?, etag_qmesh = ?,"
                  " etag_json = ?, etag_medit = ?, nv = ?, nt = ?, lease_owner = '',"
                  " lease_until = 0"
                  " WHERE id = ?",
                  "iddittttttiit", (int64_t)j->state, j->finished, j->expires,
                  (int64_t)j->iterations, j->last_progress, j->error, j->stop_reason,
                  j->etag_qmesh, j->etag_json, j->etag_medit, j->nv, j->nt, j->id);
}

static qdc_status sq_release(job_store *s_, const char *id, const char *worker)
{
    return write1((sq_store *)s_, NULL,
                  "UPDATE jobs SET state = 0, attempts = MAX(attempts - 1, 0),"
                  " lease_owner = '', lease_until = 0 WHERE id = ? AND lease_owner = ?"
                  " AND state = 1",
                  "tt", id, worker);
}

static qdc_status sq_cancel(job_store *s_, const char *id, int *now_done)
{
    sq_store *s = (sq_store *)s_;
    int n = 0;
    double now = wall_now();
    qdc_status rc =
        write1(s, &n,
               "UPDATE jobs SET state = 4, cancel_requested = 1, finished = ?,"
               " expires = ? WHERE id = ? AND state = 0",
               "ddt", now, now, id);

    *now_done = n > 0;
    if (rc != QDC_OK || n > 0)
        return rc;
    return write1(s, NULL,
                  "UPDATE jobs SET cancel_requested = 1 WHERE id = ? AND state = 1", "t",
                  id);
}

static qdc_status sq_remove(job_store *s_, const char *id)
{
    return write1((sq_store *)s_, NULL, "DELETE FROM jobs WHERE id = ?", "t", id);
}

static qdc_status sq_recover(job_store *s_, int max_attempts, double retention,
                             int *requeued, int *failed)
{
    sq_store *s = (sq_store *)s_;
    char err[512];
    qdc_status rc;

    problem_attempts(err, sizeof err, max_attempts, "the daemon");
    rc = write1(s, failed,
                "UPDATE jobs SET state = 3, finished = ?, expires = ?, error = ?,"
                " lease_owner = '', lease_until = 0 WHERE state = 1 AND attempts >= ?",
                "ddti", wall_now(), wall_now() + retention, err, (int64_t)max_attempts);
    if (rc != QDC_OK)
        return rc;
    return write1(s, requeued,
                  "UPDATE jobs SET state = 0, lease_owner = '', lease_until = 0"
                  " WHERE state = 1",
                  "");
}

static qdc_status sq_counts(job_store *s_, job_counts *c)
{
    sq_store *s = (sq_store *)s_;
    qdc_status rc = QDC_OK;
    sqlite3_stmt *st;

    memset(c, 0, sizeof *c);
    pthread_mutex_lock(&s->rd_lock);
    st = prep(s->rd, "SELECT state, COUNT(*) FROM jobs GROUP BY state");
    if (!st) {
        rc = QDC_EIO;
        goto out;
    }
    while (sqlite3_step(st) == SQLITE_ROW) {
        int k = sqlite3_column_int(st, 0);
        if (k >= 0 && k < JOB_STATE_COUNT)
            c->by_state[k] = sqlite3_column_int64(st, 1);
    }
    sqlite3_finalize(st);
out:
    pthread_mutex_unlock(&s->rd_lock);
    return rc;
}

static qdc_status sq_expired(job_store *s_, double now, char (*out)[JOB_ID_LEN + 1],
                             int max, int *n)
{
    sq_store *s = (sq_store *)s_;
    sqlite3_stmt *st;

    *n = 0;
    pthread_mutex_lock(&s->rd_lock);
    st = prep(s->rd, "SELECT id FROM jobs WHERE state >= 2 AND purged = 0 AND expires < ?"
                     " LIMIT ?");
    if (st) {
        sqlite3_bind_double(st, 1, now);
        sqlite3_bind_int(st, 2, max);
        while (sqlite3_step(st) == SQLITE_ROW && *n < max)
            col_text(st, 0, out[(*n)++], JOB_ID_LEN + 1);
        sqlite3_finalize(st);
    }
    pthread_mutex_unlock(&s->rd_lock);
    return st ? QDC_OK : QDC_EIO;
}

static qdc_status sq_mark_purged(job_store *s_, const char *id)
{
    return write1((sq_store *)s_, NULL, "UPDATE jobs SET purged = 1 WHERE id = ?", "t",
                  id);
}

static void sq_close(job_store *s_)
{
    sq_store *s = (sq_store *)s_;
    if (!s)
        return;
    sqlite3_close(s->rd);
    sqlite3_close(s->wr);
    pthread_mutex_destroy(&s->rd_lock);
    pthread_mutex_destroy(&s->wr_lock);
    free(s);
}

static const job_store_ops sq_ops = {
    sq_create,
    sq_get,
    sq_find_idem,
    sq_list,
    sq_claim,
    sq_renew,
    sq_finish,
    sq_release,
    sq_cancel,
    sq_remove,
    sq_recover,
    sq_counts,
    sq_expired,
    sq_mark_purged,
    sq_close,
    /* the job files are in the data directory: no blob or progress ops */
    NULL,
    NULL,
    NULL,
    NULL,
    NULL,
    NULL,
    NULL,
};

static qdc_status open_db(const char *path, sqlite3 **db, qdc_error *err)
{
    if (sqlite3_open_v2(path, db,
                        SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX,
                        NULL) != SQLITE_OK)
        return qdc_fail(err, QDC_EIO, "cannot open %s: %s", path,
                        *db ? sqlite3_errmsg(*db) : "out of memory");
    sqlite3_busy_timeout(*db, 10000);
    if (exec(*db, "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL;"
                  " PRAGMA foreign_keys=ON;") != QDC_OK)
        return qdc_fail(err, QDC_EIO, "cannot configure %s", path);
    return QDC_OK;
}

qdc_status store_sqlite_open(const char *dir, job_store **out, qdc_error *err)
{
    char path[4096];
    qdc_status st;
    sq_store *s = calloc(1, sizeof *s);

    *out = NULL;
    if (!s)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    s->base.ops = &sq_ops;
    pthread_mutex_init(&s->wr_lock, NULL);
    pthread_mutex_init(&s->rd_lock, NULL);
    snprintf(path, sizeof path, "%s/qdcd.db", dir);
    st = open_db(path, &s->wr, err);
    if (st == QDC_OK && exec(s->wr, schema) != QDC_OK)
        st = qdc_fail(err, QDC_EIO, "cannot create the schema in %s", path);
    /* A store made before the notes, file_name, label or input_h5 column: add
     * it (an error only means it is there already). */
    for (int i = 0; st == QDC_OK && i < 4; i++) {
        static const char *const added[] = {
            "ALTER TABLE jobs ADD COLUMN notes TEXT DEFAULT ''",
            "ALTER TABLE jobs ADD COLUMN file_name TEXT DEFAULT ''",
            "ALTER TABLE jobs ADD COLUMN label TEXT DEFAULT ''",
            "ALTER TABLE jobs ADD COLUMN input_h5 INTEGER DEFAULT 0"};
        sqlite3_exec(s->wr, added[i], NULL, NULL, NULL);
    }
    if (st == QDC_OK)
        st = open_db(path, &s->rd, err);
    if (st != QDC_OK) {
        sq_close(&s->base);
        return st;
    }
    *out = &s->base;
    return QDC_OK;
}
