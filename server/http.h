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

struct upload;
struct watch;

/* Per-request state, created at the first call of the access handler and
 * freed in the completion hook: what every request needs; a handler that
 * keeps more (an upload, a long-poll or stream) hangs its own struct here
 * and frees it in its done hook. */
typedef struct req {
    qdcd *q;
    struct MHD_Connection *conn;
    double t0;
    int status;          /* status queued, for metrics (0 = none yet) */
    int replied;         /* a response is queued: ignore the rest */
    int parked_ever;     /* suspended at some point: not counted as a latency */
    int upload;          /* POST /v1/jobs: a 4xx counts as a rejected submission */
    int close_after;     /* the reply says Connection: close (http_reply_response) */
    int in_begin;        /* inside the first call (headers only) */
    long long body_len;  /* Content-Length, or -1 (none, or chunked) */
    long long body_seen; /* body bytes received so far */
    int no_hold;         /* a refusal at the first call is sent at once (see http.c) */
    /* A refusal decided at the first call, held until the body is read */
    struct MHD_Response *held;
    unsigned held_status;
    int route;
    const char *url; /* the request's path (libmicrohttpd's, valid until done) */
    char id[JOB_ID_LEN + 1];
    char owner[65];
    /* handed to a thread of its own (offq.h) with the connection suspended */
    struct req *off_next;
    int off_done;          /* that thread has handled this request */
    meshio_format res_fmt; /* the format a conversion is to write (result.c) */
    int res_h5;            /* ... or an XDMF+HDF5 job's .h5 file (res_fmt XDMF) */
    struct upload *up;     /* POST /v1/jobs (upload.c) */
    struct watch *watch;   /* /progress, /events (progress.c) */
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

/* Bind and listen on --listen (q->listen_fd; q->cfg.port set to the port
 * bound): first thing at start-up, so a daemon that cannot have its port
 * stops before it opens the store or claims a job. QDC_EIO names the
 * address, the port and why. */
qdc_status http_bind(qdcd *q, qdc_error *err);
/* Serve the bound socket with h (the libmicrohttpd daemon and its thread). */
qdc_status http_start(qdcd *q, const http_handlers *h, qdc_error *err);
/* Stop accepting new connections (shutdown, step 1). */
void http_quiesce(qdcd *q);
/* Stop serving; closes the socket (also one bound and never served). */
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
