/* store_pg_int.h - what the files of the PostgreSQL store share: the store's
 * state, query parameters and the column readers (inline), the statement
 * runners (store_pg_sql.c) and the progress writer and listener
 * (store_pg_feed.c) that store_pg.c's job_store_ops name. Not for the rest
 * of the daemon, which sees store.h. */
#ifndef QDCD_STORE_PG_INT_H
#define QDCD_STORE_PG_INT_H

#include "store.h"

#include <libpq-fe.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#define CHUNK ((size_t)1 << 20)  /* bytes per blob row */
#define POOL_MAX 4               /* connections for blob transfers */
#define PROGRESS_QUEUE_MAX 20000 /* records waiting for the database */

/* A progress record waiting for the writer thread. */
typedef struct prec {
    struct prec *next;
    char id[JOB_ID_LEN + 1];
    char worker[64];
    long seq;
    unsigned long ticket;
    size_t len;
    char json[]; /* len bytes + NUL */
} prec;

typedef struct {
    job_store base;
    PGconn *conn;
    pthread_mutex_t lock;
    char uri[1024];
    int max_attempts; /* from recover: claims leave exhausted jobs to it */
    /* blob transfers */
    pthread_mutex_t pool_lock;
    pthread_cond_t pool_cond;
    PGconn *pool[POOL_MAX];
    int pool_busy[POOL_MAX];
    /* progress writer */
    pthread_mutex_t wq_lock;
    pthread_cond_t wq_cond, wq_done;
    prec *wq_head, *wq_tail;
    long wq_n, wq_dropped;
    unsigned long wq_next, wq_written; /* tickets: issued, all written up to */
    int wq_stop, wq_running;
    pthread_t wq_th;
    /* listener */
    pthread_t ln_th;
    int ln_running;
    volatile int ln_stop;
    store_event_fn ln_fn;
    void *ln_ctx;
} pg_store;

static inline void col_text(const PGresult *r, int row, int i, char *dst, size_t cap)
{
    snprintf(dst, cap, "%s", PQgetisnull(r, row, i) ? "" : PQgetvalue(r, row, i));
}

static inline int64_t col_i64(const PGresult *r, int row, int i)
{
    return PQgetisnull(r, row, i) ? 0 : strtoll(PQgetvalue(r, row, i), NULL, 10);
}

static inline double col_dbl(const PGresult *r, int row, int i)
{
    return PQgetisnull(r, row, i) ? 0.0 : strtod(PQgetvalue(r, row, i), NULL);
}

/* Parameters are passed as text; numbers are formatted into small buffers. */
typedef struct {
    const char *v[16];
    char num[16][32];
    int n;
} params; /* a NULL value is SQL NULL */

static inline void p_text(params *p, const char *s)
{
    p->v[p->n++] = s;
}

static inline void p_i64(params *p, int64_t x)
{
    snprintf(p->num[p->n], sizeof p->num[0], "%lld", (long long)x);
    p->v[p->n] = p->num[p->n];
    p->n++;
}

static inline void p_dbl(params *p, double x)
{
    snprintf(p->num[p->n], sizeof p->num[0], "%.17g", x);
    p->v[p->n] = p->num[p->n];
    p->n++;
}

static inline int result_ok(const PGresult *r)
{
    ExecStatusType st = PQresultStatus(r);
    return st == PGRES_COMMAND_OK || st == PGRES_TUPLES_OK;
}

/* A connection with a bounded connect time and quiet NOTICEs (store_pg_sql.c). */
PGconn *pg_connect(const char *uri);
/* Run sql with p on the store's row connection (lock held); a broken
 * connection is reset and the statement retried once. NULL (logged) if it
 * still fails. The caller PQclear()s the result. */
PGresult *pg_run(pg_store *s, const char *sql, const params *p);
/* sql with p on c (any connection); NULL if it failed, with the SQLSTATE in
 * state ("" when the connection broke). */
PGresult *pg_cx(PGconn *c, const char *sql, const params *p, char state[6]);

/* The progress writer thread (arg: the pg_store) and the job_store_ops of
 * the progress records and the listener (store_pg_feed.c; store.h says what
 * each does). */
void *pg_writer_main(void *arg);
void pg_progress_add(job_store *s_, const char *id, const char *worker, long seq,
                     const char *json, size_t len);
qdc_status pg_progress_sync(job_store *s_, double timeout);
qdc_status pg_progress_read(job_store *s_, const char *id, long after, store_record_fn fn,
                            void *ctx);
qdc_status pg_listen(job_store *s_, store_event_fn fn, void *ctx);

#endif
