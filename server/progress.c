/* progress.c - GET /v1/jobs/{id}/progress (long-poll) and /events (SSE):
 * records of a running job from the poll hub, of a finished one from
 * DATA/jobs/ID/progress.jsonl (or the shared store); a waiting client is a
 * suspended connection parked on the job's channel. */
#define _GNU_SOURCE
#include "endpoints.h"
#include "handler.h"

#include "job.h"
#include "parse.h"
#include "shared.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const no_headers[] = {NULL};

/* A reader's state, made at its first call and freed with the request. */
struct watch {
    poll_waiter w; /* linked to the job's channel while parked */
    double deadline;
    long after;   /* the last record seq the client has */
    int wait_set; /* ?after= and ?wait= read (a resumed long-poll) */
    long from;    /* ?attempt=: the run the client's records are of, or 0 */
    sbuf sse;     /* SSE: events not yet sent */
    size_t sse_off;
    int sse_end; /* 1: end event queued, 2: stream over */
};

/* r's watch, made on first use; NULL (503 answered in *ret) without memory. */
static watch *watch_of(struct MHD_Connection *c, req *r, enum MHD_Result *ret)
{
    if (r->watch)
        return r->watch;
    r->watch = calloc(1, sizeof *r->watch);
    if (!r->watch) {
        *ret = http_problem(c, r, 503, "out-of-memory", NULL,
                            "the request could not be served", NULL, NULL);
        return NULL;
    }
    r->watch->after = -1;
    return r->watch;
}

void watch_done(req *r)
{
    if (!r->watch)
        return;
    sb_free(&r->watch->sse);
    free(r->watch);
    r->watch = NULL;
}

/* ----------------------------------------------------------------- progress -- */

/* Records of a finished run from DATA/jobs/ID/progress.jsonl (line k = seq k),
 * as a JSON list body (sse = 0) or as SSE events (sse = 1). */
static void file_records(req *r, const char *id, long after, int sse, sbuf *out,
                         int *count, long *last)
{
    char path[4300];
    size_t len = 0;
    char *buf;
    long seq = 0;

    *count = 0;
    *last = -1;
    job_path(r->q, id, "progress.jsonl", path, sizeof path);
    buf = file_read_all(path, &len);
    if (!buf)
        return;
    for (char *p = buf; p < buf + len; seq++) {
        char *nl = memchr(p, '\n', (size_t)(buf + len - p));
        size_t n = nl ? (size_t)(nl - p) : (size_t)(buf + len - p);
        if (!nl && n == 0)
            break;
        if (!nl) /* torn last line of a crashed run: not a record */
            break;
        if (seq > after) {
            if (sse) {
                sb_printf(out, "id: %ld\nevent: progress\ndata: ", seq);
                sb_add(out, p, n);
                sb_puts(out, "\n\n");
            } else {
                if (*count)
                    sb_puts(out, ",");
                sb_add(out, p, n);
            }
            (*count)++;
        }
        *last = seq;
        p += n + 1;
    }
    free(buf);
}

/* store_record_fn target: frames records like file_records. */
typedef struct {
    sbuf *out;
    int sse, *count;
    long *last;
} rec_sink;

static void sink_record(void *ctx, long seq, const char *json, size_t len)
{
    rec_sink *k = ctx;
    if (k->sse) {
        sb_printf(k->out, "id: %ld\nevent: progress\ndata: ", seq);
        sb_add(k->out, json, len);
        sb_puts(k->out, "\n\n");
    } else {
        if (*k->count)
            sb_puts(k->out, ",");
        sb_add(k->out, json, len);
    }
    (*k->count)++;
    *k->last = seq;
}

/* Records after `after` from memory (a run of this process), else from the
 * store (shared: any state, the run may be on another node) or, for a
 * finished run, from the file. */
static void collect(req *r, const job_rec *j, long after, int sse, sbuf *out, int *count,
                    long *last, int *done)
{
    int chan_done = 0;
    if (!sse) {
        if (poll_read(r->q->hub, j->id, after, out, count, last, &chan_done)) {
            *done = chan_done || job_state_done(j->state);
            return;
        }
    } else {
        sbuf tmp = {0};
        /* SSE needs one event per record: read the list, then frame it. */
        if (poll_read(r->q->hub, j->id, after, &tmp, count, last, &chan_done)) {
            long seq = *last - *count + 1;
            char *p = tmp.buf;
            for (int i = 0; i < *count; i++, seq++) {
                /* records are objects joined by ',' at depth 0 */
                int depth = 0, instr = 0;
                char *q = p;
                for (; *q; q++) {
                    if (instr) {
                        if (*q == '\\' && q[1])
                            q++;
                        else if (*q == '"')
                            instr = 0;
                    } else if (*q == '"') {
                        instr = 1;
                    } else if (*q == '{') {
                        depth++;
                    } else if (*q == '}' && --depth == 0) {
                        q++;
                        break;
                    }
                }
                sb_printf(out, "id: %ld\nevent: progress\ndata: ", seq);
                sb_add(out, p, (size_t)(q - p));
                sb_puts(out, "\n\n");
                p = *q == ',' ? q + 1 : q;
            }
            sb_free(&tmp);
            *done = chan_done || job_state_done(j->state);
            return;
        }
        sb_free(&tmp);
    }
    *count = 0;
    *last = -1;
    *done = job_state_done(j->state);
    if (shared_on(r->q)) {
        rec_sink k = {out, sse, count, last};
        r->q->store->ops->progress_read(r->q->store, j->id, after, sink_record, &k);
        if (!*count)
            *last = after;
    } else if (*done) {
        file_records(r, j->id, after, sse, out, count, last);
    }
}

/* ?attempt=N: the run the client's records (up to ?after=) belong to. When
 * the job has been run again since (a node died, the daemon restarted), those
 * records are another run's: the reader gets this run's from the start
 * (after -1) and is told (wt->from). 0, or 1 with a 400 in *ret. */
static int read_attempt(struct MHD_Connection *c, req *r, watch *wt, const job_rec *j,
                        enum MHD_Result *ret)
{
    const char *a = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "attempt");
    long n;

    if (!a)
        return 0;
    if (parse_long(a, 1, INT_MAX, &n)) {
        *ret = http_problem(c, r, 400, "invalid-parameter", NULL,
                            "'attempt' must be an integer >= 1 (a run's attempt)",
                            "\"parameter\":\"attempt\"", NULL);
        return 1;
    }
    if (j->attempts > 0 && n != j->attempts) {
        wt->from = n;
        wt->after = -1;
    }
    return 0;
}

enum MHD_Result do_progress(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    job_rec j;
    enum MHD_Result ret;
    sbuf recs = {0}, b = {0};
    int count, done;
    long last;
    watch *wt = watch_of(c, r, &ret);

    if (!wt)
        return ret;
    if (wt->w.gone) /* resumed because the client hung up: close, answer nothing */
        return MHD_NO;
    if (!load_job(c, r, &j, &ret))
        return ret;
    if (!wt->wait_set) {
        const char *a = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "after");
        const char *w = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "wait");
        double wait = 0;
        if (a && parse_long(a, -1, LONG_MAX - 1, &wt->after))
            return http_problem(c, r, 400, "invalid-parameter", NULL,
                                "'after' must be an integer >= -1 (a record seq)",
                                "\"parameter\":\"after\"", NULL);
        if (w) {
            char *end;
            wait = strtod(w, &end);
            if (!*w || *end || !(wait >= 0 && wait <= 3600)) {
                char d[160];
                snprintf(d, sizeof d,
                         "'wait' must be a number of seconds in [0, 3600] (the server "
                         "waits at most %g)",
                         q->cfg.wait_cap);
                return http_problem(c, r, 400, "invalid-parameter", NULL, d,
                                    "\"parameter\":\"wait\"", NULL);
            }
        }
        if (wait > q->cfg.wait_cap)
            wait = q->cfg.wait_cap;
        wt->deadline = r->t0 + wait;
        wt->wait_set = 1;
        if (read_attempt(c, r, wt, &j, &ret))
            return ret;
    }
    for (int tries = 0;; tries++) {
        /* before the read: a kick from another node after it refuses the park */
        unsigned long gen = poll_kick_gen(q->hub);
        recs.len = 0;
        collect(r, &j, wt->after, 0, &recs, &count, &last, &done);
        if (count || done || tries || mono_now() >= wt->deadline ||
            poll_shutting_down(q->hub))
            break;
        if (poll_park_since(q->hub, j.id, wt->after, &wt->w, c, wt->deadline, gen)) {
            r->parked_ever = 1;
            sb_free(&recs);
            return MHD_YES;
        }
        /* Something arrived between the read and the park: read again. */
        if (q->store->ops->get(q->store, j.id, &j) != QDC_OK)
            break;
    }
    sb_printf(&b, "{\"id\":\"%s\",\"state\":\"%s\",\"done\":%s,\"attempt\":%d,", j.id,
              job_state_name(j.state), done ? "true" : "false", j.attempts);
    if (wt->from)
        sb_printf(&b, "\"restarted\":{\"from_attempt\":%ld,\"attempt\":%d},", wt->from,
                  j.attempts);
    sb_printf(&b, "\"after\":%ld,\"next_after\":%ld,\"count\":%d,\"records\":[",
              wt->after, count ? last : wt->after, count);
    if (recs.len)
        sb_add(&b, recs.buf, recs.len);
    sb_puts(&b, "]}\n");
    ret = http_reply_json(c, r, 200, &b, no_headers);
    sb_free(&b);
    sb_free(&recs);
    return ret;
}

/* SSE body: MHD pulls; with nothing to send the connection parks from here. */
static ssize_t sse_reader(void *cls, uint64_t pos, char *buf, size_t max)
{
    req *r = cls;
    watch *wt = r->watch;
    qdcd *q = r->q;
    job_rec j;
    int count, done;
    long last;

    (void)pos;
    if (wt->w.gone) /* resumed because the client hung up */
        return MHD_CONTENT_READER_END_WITH_ERROR;
    for (;;) {
        if (wt->sse_off < wt->sse.len) {
            size_t n = wt->sse.len - wt->sse_off;
            if (n > max)
                n = max;
            memcpy(buf, wt->sse.buf + wt->sse_off, n);
            wt->sse_off += n;
            return (ssize_t)n;
        }
        wt->sse.len = 0;
        wt->sse_off = 0;
        if (wt->sse_end)
            return MHD_CONTENT_READER_END_OF_STREAM;
        unsigned long gen = poll_kick_gen(q->hub); /* before the reads, as do_progress */
        if (q->store->ops->get(q->store, r->id, &j) != QDC_OK) {
            sb_puts(&wt->sse, "event: end\ndata: {\"state\":\"deleted\"}\n\n");
            wt->sse_end = 1;
            continue;
        }
        collect(r, &j, wt->after, 1, &wt->sse, &count, &last, &done);
        if (wt->sse.oom)
            return MHD_CONTENT_READER_END_WITH_ERROR;
        if (count) {
            wt->after = last;
            continue;
        }
        if (done || poll_shutting_down(q->hub)) {
            sb_printf(
                &wt->sse,
                "event: end\ndata: {\"id\":\"%s\",\"state\":\"%s\",\"done\":%s}\n\n",
                j.id, job_state_name(j.state), done ? "true" : "false");
            wt->sse_end = 1;
            continue;
        }
        if (wt->deadline > 0 && mono_now() >= wt->deadline) {
            sb_puts(&wt->sse, ": keep-alive\n\n");
            wt->deadline = 0;
            continue;
        }
        wt->deadline = mono_now() + q->cfg.sse_keepalive;
        if (poll_park_since(q->hub, j.id, wt->after, &wt->w, r->conn, wt->deadline, gen))
            return 0; /* resumed by a record, the end, the keep-alive or shutdown */
    }
}

/* HEAD of the stream: its headers, no stream. */
enum MHD_Result do_events_head(struct MHD_Connection *c, req *r)
{
    job_rec j;
    enum MHD_Result ret;
    if (!load_job(c, r, &j, &ret))
        return ret;
    return http_reply(c, r, 200, "text/event-stream", "", 0, no_headers);
}

enum MHD_Result do_events(struct MHD_Connection *c, req *r)
{
    job_rec j;
    enum MHD_Result ret;
    const char *a;
    struct MHD_Response *resp;
    watch *wt = watch_of(c, r, &ret);

    if (!wt || !load_job(c, r, &j, &ret))
        return ret;
    a = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Last-Event-ID");
    if (!a)
        a = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "after");
    if (a && parse_long(a, -1, LONG_MAX - 1, &wt->after))
        return http_problem(c, r, 400, "invalid-parameter", NULL,
                            "Last-Event-ID / 'after' must be an integer >= -1",
                            "\"parameter\":\"after\"", NULL);
    if (read_attempt(c, r, wt, &j, &ret))
        return ret;
    if (wt->from) /* the stream starts over: say so first */
        sb_printf(&wt->sse,
                  "event: restart\ndata: {\"from_attempt\":%ld,\"attempt\":%d}\n\n",
                  wt->from, j.attempts);
    r->parked_ever = 1; /* a stream: its duration is not a latency */
    resp =
        MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 16384, sse_reader, r, NULL);
    static const char *const h[] = {MHD_HTTP_HEADER_CONTENT_TYPE, "text/event-stream",
                                    MHD_HTTP_HEADER_CACHE_CONTROL, "no-store", NULL};
    return http_reply_response(c, r, 200, resp, h);
}
