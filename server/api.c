/* api.c - dispatch and what the endpoints share. Routing happens at the first
 * call (headers only), so a request that is refused (401, 404, 405, 413, 415,
 * 429) is answered before its body is read; then each route goes to the file
 * of its resource: upload.c (POST /v1/jobs), jobs.c (list, cancel, delete),
 * progress.c (long-poll, SSE), result.c (result, input, report), ops.c
 * (metrics, readiness), ui.c (the web console). Here: authentication, the
 * job's JSON, and the replies several of them give. */
#define _GNU_SOURCE
#include "api.h"

#include "handlers.h"
#include "job.h"
#include "ops.h"
#include "parse.h"
#include "problem.h"
#include "qdc.h"
#include "route.h"
#include "shared.h"
#include "ui.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define MEDIA_QMESH "application/vnd.qdc.mesh"

static const char *const no_headers[] = {NULL};

/* ------------------------------------------------------------------- access -- */

/* Owner of the request: "" without tokens, else the token's SHA-256. */
static int authenticate(struct MHD_Connection *c, req *r)
{
    const char *h;
    char hex[65];

    r->owner[0] = 0;
    if (!r->q->ntokens)
        return 1;
    h = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_AUTHORIZATION);
    if (!h || strncasecmp(h, "Bearer ", 7))
        return 0;
    h += 7;
    while (*h == ' ')
        h++;
    sha256_hex(h, strlen(h), hex);
    for (int i = 0; i < r->q->ntokens; i++) {
        unsigned diff = 0;
        for (int k = 0; k < 64; k++)
            diff |= (unsigned)(hex[k] ^ r->q->tokens[i][k]);
        if (!diff) {
            memcpy(r->owner, hex, sizeof hex);
            return 1;
        }
    }
    return 0;
}

/* The job store did not answer (a database that went away, SQLite busy or
 * out of space): a passing condition, 503 with a Retry-After. */
enum MHD_Result store_unavailable(struct MHD_Connection *c, req *r, const char *what)
{
    static const char *const h[] = {MHD_HTTP_HEADER_RETRY_AFTER, "5", NULL};
    return http_problem(c, r, 503, "store-unavailable", NULL, what, NULL, h);
}

int load_job(struct MHD_Connection *c, req *r, job_rec *j, enum MHD_Result *ret)
{
    qdc_status st = r->q->store->ops->get(r->q->store, r->id, j);
    if (st == QDC_OK && !strcmp(j->owner, r->owner))
        return 1;
    if (st == QDC_OK || st == QDC_EINVAL) {
        char d[128];
        snprintf(d, sizeof d, "there is no job '%s'", r->id);
        *ret = http_problem(c, r, 404, "not-found", "no such job", d, NULL, NULL);
    } else {
        *ret = store_unavailable(c, r, "the job store could not be read");
    }
    return 0;
}

/* ------------------------------------------------------------------ job JSON -- */

void job_json(req *r, const job_rec *j, sbuf *b)
{
    sbuf last = {0};
    int cnt = 0, done;
    long lastseq;

    sb_printf(b, "{\"id\":\"%s\",\"name\":\"jobs/%s\",\"state\":\"%s\",\"done\":%s",
              j->id, j->id, job_state_name(j->state),
              job_state_done(j->state) ? "true" : "false");
    sb_printf(b, ",\"created\":%.3f", j->created);
    if (j->started > 0)
        sb_printf(b, ",\"started\":%.3f", j->started);
    if (j->finished > 0)
        sb_printf(b, ",\"finished\":%.3f", j->finished);
    if (job_state_done(j->state) && j->state != JOB_CANCELLED)
        sb_printf(b, ",\"expires\":%.3f,\"expired\":%s", j->expires,
                  j->purged || j->expires < wall_now() ? "true" : "false");
    sb_printf(b, ",\"attempts\":%d,\"cancel_requested\":%s", j->attempts,
              j->cancel_requested ? "true" : "false");
    sb_printf(
        b,
        ",\"mesh\":{\"format\":\"%s\",\"vertices\":%lld,\"tets\":%lld,\"bytes\":%lld%s}",
        j->format, (long long)j->nv, (long long)j->nt, (long long)j->in_bytes,
        job_is_surface(j->format) ? ",\"surface\":true" : "");
    if (j->notes[0]) {
        /* one string per line */
        sb_puts(b, ",\"notes\":[");
        for (const char *p = j->notes; *p;) {
            size_t n = strcspn(p, "\n");
            char line[sizeof j->notes];
            snprintf(line, sizeof line, "%.*s", (int)n, p);
            sb_puts(b, p == j->notes ? "" : ",");
            sb_json_str(b, line);
            p += n + (p[n] == '\n');
        }
        sb_puts(b, "]");
    }
    sb_printf(b, ",\"options\":%s", j->options[0] ? j->options : "{}");
    /* Latest metrics: from memory while the run is live, else from the row. */
    if (j->state == JOB_RUNNING &&
        poll_read(r->q->hub, j->id, LONG_MAX, &last, &cnt, &lastseq, &done) &&
        lastseq >= 0) {
        last.len = 0;
        poll_read(r->q->hub, j->id, lastseq - 1, &last, &cnt, &lastseq, &done);
        sb_printf(b, ",\"iterations\":%ld,\"progress\":%s", lastseq + 1,
                  last.len ? last.buf : "null");
    } else {
        sb_printf(b, ",\"iterations\":%d,\"progress\":%s", j->iterations,
                  j->last_progress[0] ? j->last_progress : "null");
    }
    sb_free(&last);
    if (j->stop_reason[0]) {
        sb_puts(b, ",\"stop_reason\":");
        sb_json_str(b, j->stop_reason);
    }
    if (j->error[0])
        sb_printf(b, ",\"error\":%s", j->error);
    sb_printf(
        b,
        ",\"links\":{\"self\":\"/v1/jobs/%s\",\"progress\":\"/v1/jobs/%s/progress\","
        "\"events\":\"/v1/jobs/%s/events\"",
        j->id, j->id, j->id);
    if (j->state == JOB_SUCCEEDED && !j->purged && j->expires >= wall_now())
        sb_printf(b,
                  ",\"result\":\"/v1/jobs/%s/result\",\"report\":\"/v1/jobs/%s/report\"",
                  j->id, j->id);
    sb_puts(b, "}}");
}

enum MHD_Result reply_job(struct MHD_Connection *c, req *r, unsigned status,
                          const job_rec *j, const char *const *headers)
{
    sbuf b = {0};
    job_json(r, j, &b);
    sb_puts(&b, "\n");
    enum MHD_Result ret = http_reply_json(c, r, status, &b, headers);
    sb_free(&b);
    return ret;
}

/* Disk full (or quota): 507 and a Retry-After, since space is usually freed;
 * the detail says what could not be stored, never where. */
enum MHD_Result storage_full(struct MHD_Connection *c, req *r, const char *what)
{
    static const char *const h[] = {MHD_HTTP_HEADER_RETRY_AFTER, "30", NULL};
    char d[600];

    snprintf(d, sizeof d, "%.400s: the server's disk is full; try again later", what);
    return http_problem(c, r, 507, "io", "insufficient storage", d, NULL, h);
}

int disk_full(int e)
{
    return e == ENOSPC || e == EDQUOT;
}

/* ------------------------------------------------------------ media types -- */

/* Every mesh media type this server reads and writes (TetGen, two files, has
 * none), then with surfaces those of the surfaces it tetrahedralizes: JSON
 * strings joined by commas. */
void media_list(sbuf *b, int surfaces)
{
    int n = 0;
    for (int f = 1; f < MESHIO_FORMAT_COUNT; f++) {
        const char *t = meshio_media_type((meshio_format)f);
        if (!t)
            continue;
        sb_puts(b, n++ ? "," : "");
        sb_json_str(b, t);
    }
    for (int f = 1; surfaces && f < SURFACE_FORMAT_COUNT; f++) {
        const char *t = surface_media_type((surface_format)f);
        if (!t)
            continue;
        sb_puts(b, n++ ? "," : "");
        sb_json_str(b, t);
    }
}

/* The ?format= names: of every mesh format read, then with surfaces (an
 * upload) of the surfaces; without (a result), of every mesh format written
 * (Abaqus and Netgen only for a job uploaded in them: not listed). TetGen is
 * two files. */
void format_names(sbuf *b, int surfaces)
{
    int n = 0;
    for (int f = 1; f < MESHIO_FORMAT_COUNT; f++) {
        if (f == MESHIO_TETGEN || (!surfaces && !meshio_has_writer((meshio_format)f)))
            continue;
        sb_puts(b, n++ ? "," : "");
        sb_json_str(b, meshio_format_name((meshio_format)f));
    }
    for (int f = 1; surfaces && f < SURFACE_FORMAT_COUNT; f++) {
        sb_puts(b, n++ ? "," : "");
        sb_json_str(b, surface_format_name((surface_format)f));
    }
}

/* GET /v1/formats: the library's format table (meshio_formats_json), which
 * the console, the Python client and the batch script read instead of a copy. */
static enum MHD_Result do_formats(struct MHD_Connection *c, req *r)
{
    sbuf b = {0};
    qdc_error e;
    enum MHD_Result ret;

    if (meshio_formats_json(sb_writer, &b, &e) != QDC_OK) {
        sb_free(&b);
        return http_problem(c, r, 500, "internal", NULL, e.msg, NULL, NULL);
    }
    ret = http_reply_json(c, r, 200, &b, no_headers);
    sb_free(&b);
    return ret;
}

/* ---------------------------------------------------------------- dispatch -- */

/* Content-Length and Transfer-Encoding headers of a request, counted. */
static enum MHD_Result count_framing(void *cls, enum MHD_ValueKind kind, const char *key,
                                     const char *val)
{
    int *n = cls;
    (void)kind;
    (void)val;
    if (!strcasecmp(key, MHD_HTTP_HEADER_CONTENT_LENGTH))
        n[0]++;
    else if (!strcasecmp(key, MHD_HTTP_HEADER_TRANSFER_ENCODING))
        n[1]++;
    return MHD_YES;
}

enum MHD_Result api_begin(struct MHD_Connection *c, req *r, const char *url,
                          const char *method)
{
    int framing[2] = {0, 0};

    r->conn = c;
    r->route = ui_asset_of(url) ? R_UI : route_match(url, r->id);
    /* Two Content-Lengths, or one with a Transfer-Encoding, can frame the
     * body two ways (request smuggling behind a proxy): refuse, and close. */
    MHD_get_connection_values(c, MHD_HEADER_KIND, count_framing, framing);
    if (framing[0] > 1 || (framing[0] && framing[1])) {
        r->close_after = r->no_hold = 1; /* its body is not read: no framing to trust */
        return http_problem(c, r, 400, "ambiguous-framing", NULL,
                            "send one Content-Length, or Transfer-Encoding without it",
                            NULL, NULL);
    }
    /* libmicrohttpd 0.9.75 zeroes a keep-alive connection's whole memory pool
     * (MHD_OPTION_CONNECTION_MEMORY_LIMIT, 128 KiB) when it goes on to its
     * next request (MHD_pool_reset), so a long-poll parked on a reused
     * connection holds ~135 KB of touched memory instead of ~14 KB on a fresh
     * one. What follows a long-poll, a stream or an upload is usually a
     * long-poll: those replies close the connection, so clients park on fresh
     * ones. */
    r->close_after = r->route == R_PROGRESS || r->route == R_EVENTS ||
                     (r->route == R_JOBS && !strcmp(method, "POST"));
    if (r->route == R_BAD_ID)
        return http_problem(c, r, 404, "not-found", "no such job",
                            "job ids are 32 lower-case hex digits", NULL, NULL);
    if (r->route == R_NONE) {
        char d[300];
        snprintf(d, sizeof d, "no resource at '%.200s'", url);
        return http_problem(c, r, 404, "not-found", NULL, d, NULL, NULL);
    }
    const route_desc *rd = route_desc_of(r->route);
    if (!route_method_ok(r->route, method)) {
        const char *const h[] = {MHD_HTTP_HEADER_ALLOW, rd->allow, NULL};
        return http_problem(c, r, 405, "method-not-allowed", NULL, "see the Allow header",
                            NULL, h);
    }
    if ((rd->auth == AUTH_TOKEN || (rd->auth == AUTH_OPS && !r->q->cfg.public_metrics)) &&
        !authenticate(c, r)) {
        static const char *const h[] = {MHD_HTTP_HEADER_WWW_AUTHENTICATE,
                                        "Bearer realm=\"qdcd\"", NULL};
        return http_problem(c, r, 401, "unauthorized", NULL,
                            "send Authorization: Bearer <token>", NULL, h);
    }
    if (r->route == R_JOBS && !strcmp(method, "POST"))
        return upload_begin(c, r);
    return MHD_YES;
}

/* The page of a problem type: problem+json bodies name their type as
 * /problems/<slug>, a URI this daemon serves. */
static enum MHD_Result do_problem_page(struct MHD_Connection *c, req *r, const char *url)
{
    const char *slug = url + 10;
    sbuf b = {0};
    enum MHD_Result ret;
    const char *text = "A problem qdcd reports; the response's title and detail describe "
                       "the occurrence.";

    const problem_type *t = problem_type_of(slug);
    if (t && t->page)
        text = t->page;
    sb_printf(&b,
              "qdcd problem type: %s\n\n%s\n\nSee proto/openapi.yaml of the qdc "
              "repository for the whole API.\n",
              slug, text);
    ret = http_reply(c, r, 200, "text/plain; charset=utf-8", b.buf ? b.buf : "", b.len,
                     no_headers);
    sb_free(&b);
    return ret;
}

enum MHD_Result api_dispatch(struct MHD_Connection *c, req *r, const char *url,
                             const char *method)
{
    switch (r->route) {
    case R_JOBS:
        return strcmp(method, "POST") ? do_list(c, r) : upload_finish(c, r);
    case R_JOB: {
        job_rec j;
        enum MHD_Result ret;
        if (!strcmp(method, "DELETE"))
            return do_delete(c, r);
        if (!load_job(c, r, &j, &ret))
            return ret;
        return reply_job(c, r, 200, &j, no_headers);
    }
    case R_PROGRESS:
        return do_progress(c, r);
    case R_EVENTS:
        if (!strcmp(method, "HEAD")) { /* the stream's headers, no stream */
            job_rec j;
            enum MHD_Result ret;
            if (!load_job(c, r, &j, &ret))
                return ret;
            return http_reply(c, r, 200, "text/event-stream", "", 0, no_headers);
        }
        return do_events(c, r);
    case R_RESULT:
    case R_INPUT:
        return do_result(c, r);
    case R_OPTIONS: {
        sbuf b = {0};
        job_opt_table_json(&b);
        enum MHD_Result ret = http_reply_json(c, r, 200, &b, no_headers);
        sb_free(&b);
        return ret;
    }
    case R_FORMATS:
        return do_formats(c, r);
    case R_REPORT:
        return do_report(c, r);
    case R_CANCEL:
        return do_cancel(c, r);
    case R_LIVEZ:
        return http_reply(c, r, 200, "application/json", "{\"status\":\"ok\"}\n", 16,
                          no_headers);
    case R_READYZ:
        return ops_readyz(c, r);
    case R_METRICS:
        return ops_metrics(c, r);
    case R_PROBLEM:
        return do_problem_page(c, r, url);
    case R_UI:
        return ui_serve(c, r, url);
    default:
        return http_problem(c, r, 404, "not-found", NULL, "no such resource", NULL, NULL);
    }
}

/* A body chunk: only uploads keep theirs (other bodies are dropped). */
void api_body(req *r, const char *data, size_t len)
{
    atomic_fetch_add(&r->q->m.upload_bytes, (long long)len);
    if (r->up)
        upload_body(r, data, len);
}

/* The request is over: each handler releases its own state. */
void api_req_done(req *r)
{
    upload_done(r);
    watch_done(r);
}

int api_start(qdcd *q)
{
    (void)q;
    if (upload_start())
        return -1;
    if (result_start()) {
        upload_stop();
        return -1;
    }
    return 0;
}

void api_stop(void)
{
    upload_stop();
    result_stop();
}

const http_handlers api_handlers = {api_begin, api_body, api_dispatch, api_req_done};
