/* http.c - the MHD daemon and the request life cycle (docs/style.md §7).
 * One internal epoll thread serves every connection; handlers never block on
 * optimization (workers do that) and waiting clients are suspended
 * connections, not threads. */
#define _GNU_SOURCE
#include "http.h"

#include "problem.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

const double lat_bounds[LAT_BUCKETS] = {0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025,
                                        0.05,   0.1,   0.25,   0.5,   1.0,  5.0};

/* Set once by http_start, before the MHD thread starts; read only after. */
static const http_handlers *handlers;

static req *req_new(qdcd *q)
{
    req *r = calloc(1, sizeof *r);
    if (!r)
        return NULL;
    r->q = q;
    r->t0 = mono_now();
    return r;
}

/* The declared Content-Length, or -1. */
static long long content_length(struct MHD_Connection *c)
{
    const char *cl =
        MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH);
    char *end;
    long long n;

    if (!cl)
        return -1;
    errno = 0;
    n = strtoll(cl, &end, 10);
    return errno || end == cl || *end || n < 0 ? -1 : n;
}

/* Has the client closed its side? libmicrohttpd 0.9.75 (epoll, edge-triggered)
 * reads a body until a read returns less than it asked for, then waits for
 * the next edge; a client's FIN that came with its last bytes raises none, so
 * a client gone in the middle of its body (killed, or one that sends part of
 * a body and closes) left the connection in CLOSE-WAIT, its upload file open,
 * until --connection-timeout: 300 such uploads left 277 connections open.
 * Asked after each chunk, once libmicrohttpd holds no unread byte of it. */
static int peer_gone(struct MHD_Connection *c)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(c, MHD_CONNECTION_INFO_CONNECTION_FD);
    char b;
    ssize_t n;

    if (!ci)
        return 0;
    do
        n = recv(ci->connect_fd, &b, 1, MSG_PEEK | MSG_DONTWAIT);
    while (n < 0 && errno == EINTR);
    return n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK);
}

static enum MHD_Result on_request(void *cls, struct MHD_Connection *c, const char *url,
                                  const char *method, const char *ver, const char *data,
                                  size_t *len, void **req_cls)
{
    req *r = *req_cls;

    (void)ver;
    if (!r) { /* first call: headers only */
        enum MHD_Result ret;
        r = req_new(cls);
        if (!r)
            return MHD_NO;
        *req_cls = r; /* freed in the completion hook */
        r->body_len = content_length(c);
        /* closed right after its headers: whatever of the body
         * libmicrohttpd holds comes next; if none does, no edge comes
         * either, so the connection gets 1 s instead of the idle timeout */
        if (r->body_len > 0 && peer_gone(c))
            MHD_set_connection_option(c, MHD_CONNECTION_OPTION_TIMEOUT, 1U);
        r->in_begin = 1;
        ret = handlers->begin(c, r, url, method);
        r->in_begin = 0;
        return ret;
    }
    if (*len) { /* body chunk; capped, 413 at the end */
        if (!r->replied)
            handlers->body(r, data, *len);
        r->body_seen += (long long)*len;
        *len = 0;
        /* a body cut short: the client is gone (a client that closes its
         * side after a whole body still gets its reply) */
        if (r->body_len >= 0 && r->body_seen < r->body_len && peer_gone(c))
            return MHD_NO;
        return MHD_YES;
    }
    if (r->held) { /* the body is read: now the refusal */
        struct MHD_Response *resp = r->held;
        enum MHD_Result ret;
        r->held = NULL;
        ret = MHD_queue_response(c, r->held_status, resp);
        MHD_destroy_response(resp);
        return ret;
    }
    if (r->replied)
        return MHD_YES;
    return handlers->dispatch(c, r, url, method);
}

static void on_completed(void *cls, struct MHD_Connection *c, void **req_cls,
                         enum MHD_RequestTerminationCode toe)
{
    qdcd *q = cls;
    req *r = *req_cls;

    (void)c;
    (void)toe;
    if (!r)
        return;
    if (r->held)
        MHD_destroy_response(r->held);
    if (r->status >= 100 && r->status < 600)
        atomic_fetch_add(&q->m.http_by_class[r->status / 100], 1);
    if (r->upload && r->status >= 400 && r->status < 500)
        atomic_fetch_add(&q->m.rejected, 1);
    if (r->status && !r->parked_ever) {
        double dt = mono_now() - r->t0;
        int b = 0;
        while (b < LAT_BUCKETS && dt > lat_bounds[b])
            b++;
        atomic_fetch_add(&q->m.lat_count[b], 1);
        atomic_fetch_add(&q->m.lat_sum_us, (long long)(dt * 1e6));
    }
    handlers->done(r);
    free(r);
    *req_cls = NULL;
}

/* Is a refusal decided from the headers better sent once the body is read?
 * libmicrohttpd sends an early reply and then closes the connection with the
 * body still arriving; the kernel answers the unread bytes with a reset, which
 * can reach the client before it reads the reply: it then sees "connection
 * reset" instead of the 429 with its Retry-After (and retries at once, body
 * and all), or instead of the 401/415 that says what is wrong. A client that
 * asked "Expect: 100-continue" has sent no body and gets the reply at once;
 * so does one whose declared body is over the upload cap (--max-body), which
 * is not read for a refusal. Any other body is read and dropped first. */
static int hold_reply(struct MHD_Connection *c, req *r)
{
    const char *ex;

    if (!r->in_begin || r->no_hold)
        return 0;
    ex = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_EXPECT);
    if (ex && !strcasecmp(ex, "100-continue"))
        return 0;
    /* chunked: dropped as it comes, as an oversized one is (upload.c) */
    if (r->body_len < 0)
        return MHD_lookup_connection_value(c, MHD_HEADER_KIND,
                                           MHD_HTTP_HEADER_TRANSFER_ENCODING) != NULL;
    return r->body_len > 0 && r->body_len <= r->q->cfg.max_body;
}

enum MHD_Result http_reply_response(struct MHD_Connection *c, req *r, unsigned status,
                                    struct MHD_Response *resp, const char *const *headers)
{
    enum MHD_Result ret = MHD_NO;

    if (!resp)
        return MHD_NO;
    for (int i = 0; headers && headers[i]; i += 2)
        if (MHD_add_response_header(resp, headers[i], headers[i + 1]) != MHD_YES)
            goto out;
    /* no body of this server is to be run as another type than it says */
    if (MHD_add_response_header(resp, "X-Content-Type-Options", "nosniff") != MHD_YES)
        goto out;
    if (r->close_after &&
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CONNECTION, "close") != MHD_YES)
        goto out;
    if (hold_reply(c, r)) {
        r->held = resp;
        r->held_status = status;
        r->status = (int)status;
        r->replied = 1;
        return MHD_YES;
    }
    ret = MHD_queue_response(c, status, resp);
    if (ret == MHD_YES) {
        r->status = (int)status;
        r->replied = 1;
    }
out:
    MHD_destroy_response(resp);
    return ret;
}

enum MHD_Result http_reply(struct MHD_Connection *c, req *r, unsigned status,
                           const char *ctype, const void *data, size_t len,
                           const char *const *headers)
{
    struct MHD_Response *resp =
        MHD_create_response_from_buffer(len, (void *)data, MHD_RESPMEM_MUST_COPY);

    if (!resp)
        return MHD_NO;
    if (ctype &&
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, ctype) != MHD_YES) {
        MHD_destroy_response(resp);
        return MHD_NO;
    }
    return http_reply_response(c, r, status, resp, headers);
}

enum MHD_Result http_reply_json(struct MHD_Connection *c, req *r, unsigned status,
                                const sbuf *body, const char *const *headers)
{
    if (body->oom)
        return http_problem(c, r, 503, "out-of-memory", NULL,
                            "the reply did not fit in memory", NULL, NULL);
    return http_reply(c, r, status, "application/json", body->buf ? body->buf : "{}",
                      body->buf ? body->len : 2, headers);
}

enum MHD_Result http_problem(struct MHD_Connection *c, req *r, unsigned status,
                             const char *slug, const char *title, const char *detail,
                             const char *extra, const char *const *headers)
{
    sbuf b = {0};
    enum MHD_Result ret;

    problem_json(&b, (int)status, slug, title, detail, extra);
    sb_puts(&b, "\n");
    if (b.oom)
        ret = http_reply(c, r, 503, "text/plain", "out of memory\n", 14, NULL);
    else
        ret = http_reply(c, r, status, "application/problem+json", b.buf, b.len, headers);
    sb_free(&b);
    return ret;
}

enum MHD_Result http_reply_file(struct MHD_Connection *c, req *r, unsigned status,
                                const char *path, const char *ctype,
                                const char *const *headers)
{
    struct stat sb;
    struct MHD_Response *resp;
    int fd = open(path, O_RDONLY | O_CLOEXEC);

    if (fd < 0 || fstat(fd, &sb)) {
        if (fd >= 0)
            close(fd);
        return http_problem(c, r, 500, "io", NULL, "a stored file could not be read",
                            NULL, NULL);
    }
    resp = MHD_create_response_from_fd((uint64_t)sb.st_size, fd); /* owns fd */
    if (!resp) {
        close(fd);
        return MHD_NO;
    }
    if (MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, ctype) != MHD_YES) {
        MHD_destroy_response(resp);
        return MHD_NO;
    }
    return http_reply_response(c, r, status, resp, headers);
}

static void log_mhd(void *cls, const char *fmt, va_list ap)
{
    qdcd *q = cls;
    if (!q->cfg.verbose)
        return;
    fputs("qdcd: mhd: ", stderr);
    vfprintf(stderr, fmt, ap);
}

qdc_status http_bind(qdcd *q, qdc_error *err)
{
    struct addrinfo hints = {0}, *ai = NULL;
    char port[16];
    struct sockaddr_storage ss;
    socklen_t sl = sizeof ss;
    int rc, fd, one = 1, e;

    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
    snprintf(port, sizeof port, "%d", q->cfg.port);
    rc = getaddrinfo(q->cfg.host, port, &hints, &ai);
    if (rc)
        return qdc_fail(err, QDC_EINVAL, "cannot resolve %s: %s", q->cfg.host,
                        gai_strerror(rc));
    fd = socket(ai->ai_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    /* as libmicrohttpd binds: a restart finds its port in TIME_WAIT */
    if (fd >= 0 && (setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) ||
                    (ai->ai_family == AF_INET6 &&
                     setsockopt(fd, IPPROTO_IPV6, IPV6_V6ONLY, &one, sizeof one)) ||
                    bind(fd, ai->ai_addr, ai->ai_addrlen) || listen(fd, 1024))) {
        e = errno;
        close(fd);
        fd = -1;
        errno = e;
    }
    q->listen_v6 = ai->ai_family == AF_INET6;
    freeaddrinfo(ai);
    if (fd < 0)
        return qdc_fail(err, QDC_EIO, "cannot listen on %s%s%s:%d: %s",
                        q->listen_v6 ? "[" : "", q->cfg.host, q->listen_v6 ? "]" : "",
                        q->cfg.port, strerror(errno));
    if (!getsockname(fd, (struct sockaddr *)&ss, &sl)) {
        if (ss.ss_family == AF_INET)
            q->cfg.port = ntohs(((struct sockaddr_in *)&ss)->sin_port);
        else if (ss.ss_family == AF_INET6)
            q->cfg.port = ntohs(((struct sockaddr_in6 *)&ss)->sin6_port);
    }
    q->listen_fd = fd;
    return QDC_OK;
}

qdc_status http_start(qdcd *q, const http_handlers *h, qdc_error *err)
{
    handlers = h;
    unsigned flags = MHD_USE_EPOLL_INTERNAL_THREAD | MHD_ALLOW_SUSPEND_RESUME |
                     MHD_USE_ERROR_LOG | MHD_USE_TURBO;
    if (q->listen_v6)
        flags |= MHD_USE_IPv6;
    /* the socket http_bind bound: connections that came meanwhile wait in
     * its backlog */
    q->mhd = MHD_start_daemon(
        flags, 0, NULL, NULL, on_request, q, MHD_OPTION_EXTERNAL_LOGGER, log_mhd, q,
        MHD_OPTION_LISTEN_SOCKET, q->listen_fd, MHD_OPTION_CONNECTION_LIMIT,
        (unsigned)q->cfg.max_connections, MHD_OPTION_CONNECTION_TIMEOUT,
        (unsigned)q->cfg.conn_timeout, MHD_OPTION_CONNECTION_MEMORY_LIMIT,
        (size_t)128 * 1024, MHD_OPTION_LISTEN_BACKLOG_SIZE, 1024U,
        MHD_OPTION_NOTIFY_COMPLETED, on_completed, q, MHD_OPTION_END);
    if (!q->mhd)
        return qdc_fail(err, QDC_EIO, "cannot serve HTTP on port %d", q->cfg.port);
    q->listen_fd = -1; /* libmicrohttpd's now: closed by MHD_stop_daemon */
    return QDC_OK;
}

void http_quiesce(qdcd *q)
{
    if (q->mhd) {
        MHD_socket s = MHD_quiesce_daemon(q->mhd);
        if (s != MHD_INVALID_SOCKET)
            close(s);
    }
}

void http_stop(qdcd *q)
{
    if (q->mhd)
        MHD_stop_daemon(q->mhd);
    q->mhd = NULL;
    if (q->listen_fd >= 0) /* bound, never served */
        close(q->listen_fd);
    q->listen_fd = -1;
}
