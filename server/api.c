/* api.c - the router. Routing happens at the first call (headers only), so a
 * request that is refused (400, 401, 403, 404, 405, 413, 415, 429) is answered before
 * its body is read; then the request's row of the route table (route.h) names
 * its handler, in the file of its resource: upload.c (POST /v1/jobs), jobs.c
 * (a job, list, cancel, delete), progress.c (long-poll, SSE), result.c
 * (result, input, report), ops.c (metrics, readiness, options, problem
 * pages), ui.c (the web console). Here: framing, the checks of guard.c
 * (query values, Host, Origin), authentication and dispatch;
 * what the handlers share is handler.c, below them. */
#define _GNU_SOURCE
#include "api.h"

#include "endpoints.h"
#include "guard.h"
#include "ops.h"
#include "route.h"
#include "ui.h"

#include <stdio.h>
#include <string.h>
#include <strings.h>

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

/* The handlers of each row of the route table, in its order. */
typedef enum MHD_Result (*route_fn)(struct MHD_Connection *c, req *r);
#define ROW(route, method, pattern, handler, begin, auth, flags) {handler, begin},
static const struct {
    route_fn handler, begin;
} route_fns[] = {ROUTE_LIST(ROW)};
#undef ROW

/* Route the request (r->route, *row: its row of the table, or -1); refuse it
 * when framing, path, method or token say so: 1 with the answer in *ret. */
static int refused(struct MHD_Connection *c, req *r, const char *url, const char *method,
                   int *row, enum MHD_Result *ret)
{
    int framing[2] = {0, 0};

    r->conn = c;
    r->url = url;
    r->route = ui_asset_of(url) ? R_UI : route_match(url, r->id);
    *row = route_row(r->route, method);
    /* Two Content-Lengths, or one with a Transfer-Encoding, can frame the
     * body two ways (request smuggling behind a proxy): refuse, and close. */
    MHD_get_connection_values(c, MHD_HEADER_KIND, count_framing, framing);
    if (framing[0] > 1 || (framing[0] && framing[1])) {
        r->close_after = r->no_hold = 1; /* its body is not read: no framing to trust */
        *ret = http_problem(c, r, 400, "ambiguous-framing", NULL,
                            "send one Content-Length, or Transfer-Encoding without it",
                            NULL, NULL);
        return 1;
    }
    /* query values, Host, Origin: before anything of the route is done */
    if (guard_request(c, r, method, ret))
        return 1;
    /* libmicrohttpd 0.9.75 zeroes a keep-alive connection's whole memory pool
     * (MHD_OPTION_CONNECTION_MEMORY_LIMIT, 128 KiB) when it goes on to its
     * next request (MHD_pool_reset), so a long-poll parked on a reused
     * connection holds ~135 KB of touched memory instead of ~14 KB on a fresh
     * one. What follows a long-poll, a stream or an upload is usually a
     * long-poll: those replies close the connection (RF_CLOSE), so clients
     * park on fresh ones. */
    r->close_after = *row >= 0 ? (route_table[*row].flags & RF_CLOSE) != 0
                               : route_always_closes(r->route);
    if (r->route == R_BAD_ID) {
        *ret = http_problem(c, r, 404, "not-found", "no such job",
                            "job ids are 32 lower-case hex digits", NULL, NULL);
        return 1;
    }
    if (r->route == R_NONE) {
        char d[300];
        snprintf(d, sizeof d, "no resource at '%.200s'", url);
        *ret = http_problem(c, r, 404, "not-found", NULL, d, NULL, NULL);
        return 1;
    }
    if (*row < 0) {
        char allow[32];
        route_allow(r->route, allow, sizeof allow);
        const char *const h[] = {MHD_HTTP_HEADER_ALLOW, allow, NULL};
        *ret = http_problem(c, r, 405, "method-not-allowed", NULL, "see the Allow header",
                            NULL, h);
        return 1;
    }
    int auth = route_table[*row].auth;
    if ((auth == AUTH_TOKEN || (auth == AUTH_OPS && !r->q->cfg.public_metrics)) &&
        !authenticate(c, r)) {
        static const char *const h[] = {MHD_HTTP_HEADER_WWW_AUTHENTICATE,
                                        "Bearer realm=\"qdcd\"", NULL};
        *ret = http_problem(c, r, 401, "unauthorized", NULL,
                            "send Authorization: Bearer <token>", NULL, h);
        return 1;
    }
    return 0;
}

enum MHD_Result api_begin(struct MHD_Connection *c, req *r, const char *url,
                          const char *method)
{
    int row;
    enum MHD_Result ret = MHD_YES;

    if (refused(c, r, url, method, &row, &ret) || !route_fns[row].begin)
        return ret;
    return route_fns[row].begin(c, r);
}

enum MHD_Result api_dispatch(struct MHD_Connection *c, req *r, const char *url,
                             const char *method)
{
    int row = route_row(r->route, method);
    (void)url;
    if (row < 0)
        return http_problem(c, r, 404, "not-found", NULL, "no such resource", NULL, NULL);
    return route_fns[row].handler(c, r);
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
