/* store_pg_feed.c - the PostgreSQL store's progress records and listener
 * (store_pg_int.h): a writer thread that batches the records into rows, their
 * reading back, and the LISTEN connection that hears the other nodes. */
#define _GNU_SOURCE
#include "store_pg_int.h"
#include "util.h"

#include <errno.h>
#include <poll.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* --------------------------------------------------------------- progress -- */

/* A PostgreSQL array literal element: "..." with " and \ escaped. */
static void arr_str(sbuf *b, const char *s, size_t n)
{
    sb_puts(b, b->len > 1 ? ",\"" : "\"");
    for (size_t i = 0; i < n; i++) {
        if (s[i] == '"' || s[i] == '\\')
            sb_add(b, "\\", 1);
        sb_add(b, s + i, 1);
    }
    sb_puts(b, "\"");
}

/* One job's consecutive records (first .. last, same worker) in one
 * statement: stored only while that worker holds the lease, and the row's
 * latest progress moves with them (any node's GET shows it). 0 when done
 * (written or refused for good), -1 when the connection failed. */
static int write_group(PGconn *c, prec *first, prec *last)
{
    sbuf seqs = {0}, recs = {0};
    params p = {.n = 0};
    char state[6];
    PGresult *r;
    int rc = 0;

    sb_puts(&seqs, "{");
    sb_puts(&recs, "{");
    for (prec *e = first;; e = e->next) {
        sb_printf(&seqs, "%s%ld", seqs.len > 1 ? "," : "", e->seq);
        arr_str(&recs, e->json, e->len);
        if (e == last)
            break;
    }
    sb_puts(&seqs, "}");
    sb_puts(&recs, "}");
    if (seqs.oom || recs.oom)
        goto out; /* dropped */
    p_text(&p, first->id);
    p_text(&p, first->worker);
    p_i64(&p, last->seq); /* the job's iterations: its last record's number */
    /* the row keeps the last record when it fits (job_rec.last_progress) */
    p_text(&p, last->len < sizeof((job_rec *)0)->last_progress ? last->json : NULL);
    p_text(&p, seqs.buf);
    p_text(&p, recs.buf);
    r = pg_cx(
        c,
        "WITH j AS (UPDATE jobs SET iterations = $3,"
        " last_progress = COALESCE($4, last_progress)"
        " WHERE id = $1 AND lease_owner = $2 AND state = 1 RETURNING id)"
        " INSERT INTO progress(job_id, seq, rec)"
        " SELECT j.id, u.seq, u.rec FROM j, unnest($5::int[], $6::text[]) AS u(seq, rec)"
        " ON CONFLICT DO NOTHING",
        &p, state);
    if (r)
        PQclear(r);
    else if (PQstatus(c) != CONNECTION_OK)
        rc = -1;
out:
    sb_free(&seqs);
    sb_free(&recs);
    return rc;
}

void *pg_writer_main(void *arg)
{
    pg_store *s = arg;
    PGconn *c = NULL;
    double pause = 0.1;
    int failures = 0;

    pthread_mutex_lock(&s->wq_lock);
    for (;;) {
        while (!s->wq_head && !s->wq_stop)
            pthread_cond_wait(&s->wq_cond, &s->wq_lock);
        if (!s->wq_head)
            break; /* stopping, nothing left */
        /* a batch of up to 256 records, left in the queue until written */
        prec *head = s->wq_head, *end = head;
        for (int k = 1; k < 256 && end->next; k++)
            end = end->next;
        pthread_mutex_unlock(&s->wq_lock);

        int ok = 1;
        if (!c)
            c = pg_connect(s->uri);
        else if (PQstatus(c) != CONNECTION_OK)
            PQreset(c);
        if (!c || PQstatus(c) != CONNECTION_OK)
            ok = 0;
        for (prec *g = head; ok;) {
            prec *e = g;
            while (e != end && e->next && !strcmp(e->next->id, g->id) &&
                   !strcmp(e->next->worker, g->worker))
                e = e->next;
            if (write_group(c, g, e)) {
                ok = 0;
                break;
            }
            if (e == end)
                break;
            g = e->next;
        }

        pthread_mutex_lock(&s->wq_lock);
        if (!ok && !(s->wq_stop && failures >= 3)) {
            /* the database is away: keep the records, try again later */
            if (!failures++)
                fprintf(stderr, "qdcd: postgresql: progress records wait for the "
                                "database\n");
            struct timespec ts;
            clock_gettime(CLOCK_REALTIME, &ts);
            double t = (double)ts.tv_sec + ts.tv_nsec * 1e-9 + pause;
            ts.tv_sec = (time_t)t;
            ts.tv_nsec = (long)((t - (double)ts.tv_sec) * 1e9);
            pthread_cond_timedwait(&s->wq_cond, &s->wq_lock, &ts);
            pause = pause * 2 > 5 ? 5 : pause * 2;
            continue;
        }
        if (!ok)
            fprintf(stderr, "qdcd: postgresql: progress records dropped at shutdown\n");
        failures = 0;
        pause = 0.1;
        s->wq_head = end->next;
        if (!s->wq_head)
            s->wq_tail = NULL;
        end->next = NULL;
        s->wq_written = end->ticket;
        while (head) {
            prec *nx = head->next;
            free(head);
            s->wq_n--;
            head = nx;
        }
        pthread_cond_broadcast(&s->wq_done);
    }
    pthread_mutex_unlock(&s->wq_lock);
    PQfinish(c);
    return NULL;
}

void pg_progress_add(job_store *s_, const char *id, const char *worker, long seq,
                     const char *json, size_t len)
{
    pg_store *s = (pg_store *)s_;
    prec *e = malloc(sizeof *e + len + 1);

    if (!e)
        return;
    e->next = NULL;
    snprintf(e->id, sizeof e->id, "%s", id);
    snprintf(e->worker, sizeof e->worker, "%s", worker);
    e->seq = seq;
    e->len = len;
    memcpy(e->json, json, len);
    e->json[len] = 0;
    pthread_mutex_lock(&s->wq_lock);
    if (s->wq_n >= PROGRESS_QUEUE_MAX || s->wq_stop || !s->wq_running) {
        if (!s->wq_dropped++)
            fprintf(stderr, "qdcd: postgresql: too many progress records waiting for the "
                            "database: new ones are dropped\n");
        pthread_mutex_unlock(&s->wq_lock);
        free(e);
        return;
    }
    e->ticket = ++s->wq_next;
    if (s->wq_tail)
        s->wq_tail->next = e;
    else
        s->wq_head = e;
    s->wq_tail = e;
    s->wq_n++;
    pthread_cond_signal(&s->wq_cond);
    pthread_mutex_unlock(&s->wq_lock);
}

qdc_status pg_progress_sync(job_store *s_, double timeout)
{
    pg_store *s = (pg_store *)s_;
    struct timespec ts;
    int ok;

    clock_gettime(CLOCK_REALTIME, &ts);
    double t = (double)ts.tv_sec + ts.tv_nsec * 1e-9 + timeout;
    ts.tv_sec = (time_t)t;
    ts.tv_nsec = (long)((t - (double)ts.tv_sec) * 1e9);
    pthread_mutex_lock(&s->wq_lock);
    unsigned long target = s->wq_next;
    while (s->wq_written < target &&
           pthread_cond_timedwait(&s->wq_done, &s->wq_lock, &ts) == 0)
        ;
    ok = s->wq_written >= target;
    pthread_mutex_unlock(&s->wq_lock);
    return ok ? QDC_OK : QDC_EIO;
}

qdc_status pg_progress_read(job_store *s_, const char *id, long after, store_record_fn fn,
                            void *ctx)
{
    pg_store *s = (pg_store *)s_;
    params p = {.n = 0};
    PGresult *r;
    qdc_status st = QDC_EIO;

    p_text(&p, id);
    p_i64(&p, after);
    pthread_mutex_lock(&s->lock);
    r = pg_run(
        s, "SELECT seq, rec FROM progress WHERE job_id = $1 AND seq > $2 ORDER BY seq",
        &p);
    pthread_mutex_unlock(&s->lock);
    if (r) {
        for (int i = 0; i < PQntuples(r); i++)
            fn(ctx, (long)col_i64(r, i, 0), PQgetvalue(r, i, 1),
               (size_t)PQgetlength(r, i, 1));
        PQclear(r);
        st = QDC_OK;
    }
    return st;
}

/* --------------------------------------------------------------- listener -- */

static void nap(pg_store *s, double seconds)
{
    for (double t = 0; t < seconds && !s->ln_stop; t += 0.05) {
        struct timespec ts = {0, 50 * 1000 * 1000};
        nanosleep(&ts, NULL);
    }
}

static void *listen_main(void *arg)
{
    pg_store *s = arg;
    PGconn *c = NULL;
    double pause = 0.1;

    while (!s->ln_stop) {
        if (!c || PQstatus(c) != CONNECTION_OK) {
            char state[6];
            PGresult *r = NULL;
            if (!c)
                c = pg_connect(s->uri);
            else
                PQreset(c);
            if (c && PQstatus(c) == CONNECTION_OK)
                r = pg_cx(c, "LISTEN qdc_job; LISTEN qdc_progress", NULL, state);
            if (!r) {
                nap(s, pause);
                pause = pause * 2 > 5 ? 5 : pause * 2;
                continue;
            }
            PQclear(r);
            pause = 0.1;
            /* whatever was announced while nobody listened */
            store_event ev = {.kind = STORE_EV_RESYNC};
            s->ln_fn(s->ln_ctx, &ev);
        }
        struct pollfd pf = {.fd = PQsocket(c), .events = POLLIN};
        int n = poll(&pf, 1, 200);
        if (n < 0 && errno != EINTR) {
            PQfinish(c);
            c = NULL;
            continue;
        }
        if (n > 0 && !PQconsumeInput(c)) {
            PQfinish(c); /* the server went away: connect again */
            c = NULL;
            continue;
        }
        PGnotify *nt;
        while ((nt = PQnotifies(c)) != NULL) {
            store_event ev;
            memset(&ev, 0, sizeof ev);
            if (!strcmp(nt->relname, "qdc_job") &&
                sscanf(nt->extra, "%32s %d %d", ev.id, &ev.state, &ev.cancel) == 3) {
                ev.kind = STORE_EV_JOB;
                s->ln_fn(s->ln_ctx, &ev);
            } else if (!strcmp(nt->relname, "qdc_progress") &&
                       sscanf(nt->extra, "%32s %ld", ev.id, &ev.seq) == 2) {
                ev.kind = STORE_EV_PROGRESS;
                s->ln_fn(s->ln_ctx, &ev);
            }
            PQfreemem(nt);
        }
    }
    PQfinish(c);
    return NULL;
}

qdc_status pg_listen(job_store *s_, store_event_fn fn, void *ctx)
{
    pg_store *s = (pg_store *)s_;

    if (!fn) {
        if (s->ln_running) {
            s->ln_stop = 1;
            pthread_join(s->ln_th, NULL);
            s->ln_running = 0;
        }
        return QDC_OK;
    }
    if (s->ln_running)
        return QDC_OK;
    s->ln_fn = fn;
    s->ln_ctx = ctx;
    s->ln_stop = 0;
    if (pthread_create(&s->ln_th, NULL, listen_main, s))
        return QDC_EIO;
    s->ln_running = 1;
    return QDC_OK;
}
