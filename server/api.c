/* api.c - the router. Routing happens at the first
 * call (headers only), so a request that is refused (401, 404, 405, 413, 415,
 * 429) is answered before its body is read; then each route goes to the file
 * of its resource: upload.c (POST /v1/jobs), jobs.c (list, cancel, delete),
 * progress.c (long-poll, SSE), result.c (result, input, report), ops.c
 * (metrics, readiness), ui.c (the web console). Here: authentication and
 * dispatch; what the handlers share is in handler.c, below them. */
#define _GNU_SOURCE
#include "api.h"

#include "endpoints.h"
#include "handler.h"
#include "job.h"
#include "ops.h"
#include "parse.h"
#include "problem.h"
#include "qdc.h"
#include "route.h"
#include "shared.h"
#include "ui.h"

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
