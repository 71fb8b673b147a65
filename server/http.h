/* http.h - libmicrohttpd glue: the daemon (one internal epoll thread with
 * suspend/resume), the per-request state, and the reply helpers every handler
 * answers through. */
#ifndef QDCD_HTTP_H
#define QDCD_HTTP_H

#include "poll.h"
#include "qdc.h"
#include "server.h"
#include "sha256.h"

#include <microhttpd.h>

/* Per-request state, created at the first call of the access handler and
 * freed in the completion hook. */
typedef struct req {
    qdcd *q;
    struct MHD_Connection *conn;
    double t0;
    int status;  /* status queued, for metrics (0 = none yet) */
    int replied; /* a response is queued: ignore the rest */
    int parked_ever;
    int upload;      /* POST /v1/jobs: a 4xx counts as a rejected submission */
    int close_after; /* the reply says Connection: close (http_reply_response) */
    int route;
    char id[JOB_ID_LEN + 1];
    char owner[65];
    /* POST /v1/jobs upload */
    int fd;
    char tmp[4200];
    int64_t body_len;
    int too_big, io_err, hashing;
    sha256_ctx hash;
    meshio_format fmt;   /* a mesh upload's format, or MESHIO_AUTO */
    surface_format sfmt; /* a surface upload's format (tetrahedralized), or AUTO */
    int sniff;           /* format from the content (text/plain, octet-stream, none) */
    int tetgen_opts;     /* tetgen_quality or max_volume given: surfaces only */
    char idem[129];
    char options[1024];
    struct req *intake_next; /* queued for the intake or the convert thread */
    int intake_done;         /* that thread has handled this request */
    /* GET /result */
    meshio_format res_fmt;
    /* long-poll and SSE */
    poll_waiter w;
    double deadline;
    long after;
    int wait_set;
    sbuf sse;
    size_t sse_off;
    int sse_end; /* 1: end event queued, 2: stream over */
} req;

/* What the layer above answers requests with (api.c's api_handlers): http.c
 * calls these and knows nothing else of the endpoints. */
typedef struct http_handlers {
    /* First call (headers only): may answer at once. */
    enum MHD_Result (*begin)(struct MHD_Connection *c, req *r, const char *url,
                             const char *method);
    /* One chunk of the request body. */
    void (*body)(req *r, const char *data, size_t len);
    /* Body complete (or resumed after parking): answer or park. */
    enum MHD_Result (*dispatch)(struct MHD_Connection *c, req *r, const char *url,
                                const char *method);
    /* The request is over: release what it still holds. */
    void (*done)(req *r);
} http_handlers;

qdc_status http_start(qdcd *q, const http_handlers *h, qdc_error *err);
/* Stop accepting new connections (shutdown, step 1). */
void http_quiesce(qdcd *q);
void http_stop(qdcd *q);

/* Headers are given as name, value, name, value, ..., NULL. Each helper
 * destroys the response it built on every path and records the status. */
enum MHD_Result http_reply(struct MHD_Connection *c, req *r, unsigned status,
                           const char *ctype, const void *data, size_t len,
                           const char *const *headers);
enum MHD_Result http_reply_json(struct MHD_Connection *c, req *r, unsigned status,
                                const sbuf *body, const char *const *headers);
/* RFC 9457 problem+json. extra: further members as JSON text without braces
 * ("\"index\": 3"), or NULL. */
enum MHD_Result http_problem(struct MHD_Connection *c, req *r, unsigned status,
                             const char *slug, const char *title, const char *detail,
                             const char *extra, const char *const *headers);
/* Serve a regular file (takes no ownership of path). 404-style failure returns
 * a 500 problem, since callers only pass files the store says exist. */
enum MHD_Result http_reply_file(struct MHD_Connection *c, req *r, unsigned status,
                                const char *path, const char *ctype,
                                const char *const *headers);
enum MHD_Result http_reply_response(struct MHD_Connection *c, req *r, unsigned status,
                                    struct MHD_Response *resp,
                                    const char *const *headers);

#endif
