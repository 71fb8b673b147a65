/* remote.c - `qdc submit|status|watch|fetch|cancel|jobs`: the qdcd HTTP API
 * (proto/openapi.yaml) through libcurl.
 *
 * The local file is read (and checked) first, whatever its format, and goes
 * up as it is, in its own variant (by its media type, or named in the query
 * when it has none): a result asked for in that format is the upload with
 * only the coordinates replaced. TetGen's two files go up as
 * application/vnd.qdc.mesh, and submit -o in their format puts the result's
 * coordinates into the files read here. Either way `qdc submit IN -o OUT`
 * writes what `qdc optimize IN OUT` writes: names, tags, arrays and comments
 * kept. A result in another format is asked for in it (or as the binary
 * mesh, for TetGen's pair) and written as it comes.
 *
 * Every request is retried on 429, 5xx and network failures, waiting what the
 * server's Retry-After says, else an exponential backoff. A submit carries an
 * Idempotency-Key, so a retried POST whose first attempt did reach the server
 * returns the same job instead of making a second one. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "qdc.h"

#include <curl/curl.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

#define DEFAULT_SERVER "http://127.0.0.1:8080"
#define MEDIA_QMESH "application/vnd.qdc.mesh"
#define POLL_WAIT 30     /* seconds asked of the long-poll */
#define MAX_BACKOFF 30.0 /* seconds between two attempts, at most */

static volatile sig_atomic_t interrupted;

static void on_signal(int sig)
{
    (void)sig;
    interrupted = 1;
}

/* ----------------------------------------------------------------- buffers -- */

typedef struct {
    char *buf;
    size_t len, cap;
    int oom;
} rbuf;

static int rb_add(rbuf *b, const void *p, size_t n)
{
    if (b->oom)
        return -1;
    if (b->len + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->len + n + 1)
            cap *= 2;
        char *nb = realloc(b->buf, cap);
        if (!nb) {
            b->oom = 1;
            return -1;
        }
        b->buf = nb;
        b->cap = cap;
    }
    memcpy(b->buf + b->len, p, n);
    b->len += n;
    b->buf[b->len] = 0;
    return 0;
}

static int rb_writer(void *ctx, const void *data, size_t len)
{
    return rb_add(ctx, data, len) ? -1 : 0;
}

static void rb_free(rbuf *b)
{
    free(b->buf);
    memset(b, 0, sizeof *b);
}

/* -------------------------------------------------------------------- JSON -- */

/* Just enough JSON to read the server's replies: find a member, read a string,
 * a number or a boolean, walk an array. Values are (start, end) slices of the
 * reply; nothing is allocated. */

typedef struct {
    const char *p, *end;
} jv;

static const char *ws(const char *p, const char *end)
{
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r'))
        p++;
    return p;
}

/* Past the value at p, or NULL if it is malformed. */
static const char *skip_value(const char *p, const char *end, int depth)
{
    p = ws(p, end);
    if (p >= end || depth > 64)
        return NULL;
    if (*p == '"') {
        for (p++; p < end; p++) {
            if (*p == '\\')
                p++;
            else if (*p == '"')
                return p + 1;
        }
        return NULL;
    }
    if (*p == '{' || *p == '[') {
        char close = *p == '{' ? '}' : ']';
        p = ws(p + 1, end);
        if (p < end && *p == close)
            return p + 1;
        while (p < end) {
            if (close == '}') {
                p = skip_value(p, end, depth + 1); /* key */
                p = p ? ws(p, end) : NULL;
                if (!p || p >= end || *p != ':')
                    return NULL;
                p++;
            }
            p = skip_value(p, end, depth + 1);
            p = p ? ws(p, end) : NULL;
            if (!p || p >= end)
                return NULL;
            if (*p == close)
                return p + 1;
            if (*p != ',')
                return NULL;
            p++;
        }
        return NULL;
    }
    while (p < end && !strchr(",}] \t\r\n", *p))
        p++;
    return p;
}

/* Member `key` of the object v; key may be a dotted path ("progress.seq"). */
static int jget(jv v, const char *key, jv *out)
{
    const char *dot = strchr(key, '.');
    size_t klen = dot ? (size_t)(dot - key) : strlen(key);
    const char *p = ws(v.p, v.end);

    if (p >= v.end || *p != '{')
        return 0;
    p = ws(p + 1, v.end);
    while (p < v.end && *p == '"') {
        const char *k = p + 1, *ke = skip_value(p, v.end, 0);
        if (!ke)
            return 0;
        p = ws(ke, v.end);
        if (p >= v.end || *p != ':')
            return 0;
        const char *val = ws(p + 1, v.end), *ve = skip_value(val, v.end, 0);
        if (!ve)
            return 0;
        if ((size_t)(ke - 1 - k) == klen && !memcmp(k, key, klen)) {
            jv m = {val, ve};
            if (dot)
                return jget(m, dot + 1, out);
            *out = m;
            return 1;
        }
        p = ws(ve, v.end);
        if (p < v.end && *p == ',')
            p = ws(p + 1, v.end);
    }
    return 0;
}

/* The string s (escapes decoded; non-ASCII \u escapes become '?'; UTF-8 kept). */
static int jtext(jv s, char *out, size_t cap)
{
    size_t n = 0;

    if (!cap)
        return 0;
    out[0] = 0;
    if (s.p >= s.end || *s.p != '"')
        return 0;
    for (const char *p = s.p + 1; p < s.end - 1 && n + 1 < cap; p++) {
        char c = *p;
        if (c == '\\' && p + 1 < s.end - 1) {
            c = *++p;
            if (c == 'n')
                c = '\n';
            else if (c == 't')
                c = '\t';
            else if (c == 'u') {
                unsigned u = 0;
                if (p + 4 < s.end && sscanf(p + 1, "%4x", &u) == 1)
                    p += 4;
                c = u < 128 && u >= 32 ? (char)u : '?';
            } else if (c != '"' && c != '\\' && c != '/')
                c = '?';
        }
        out[n++] = c;
    }
    out[n] = 0;
    return 1;
}

/* String member (jtext). */
static int jstr(jv v, const char *key, char *out, size_t cap)
{
    jv s;

    if (cap)
        out[0] = 0;
    return jget(v, key, &s) && jtext(s, out, cap);
}

static int jnum(jv v, const char *key, double *out)
{
    jv s;
    char tmp[64], *end;
    size_t n;

    if (!jget(v, key, &s))
        return 0;
    n = (size_t)(s.end - s.p);
    if (!n || n >= sizeof tmp || !strchr("-0123456789", *s.p))
        return 0;
    memcpy(tmp, s.p, n);
    tmp[n] = 0;
    *out = strtod(tmp, &end);
    return *end == 0;
}

static int jbool(jv v, const char *key)
{
    jv s;
    return jget(v, key, &s) && s.end - s.p == 4 && !memcmp(s.p, "true", 4);
}

/* Next element of the array whose position is *it (start: the array itself). */
static int jnext(jv *it, jv *elem)
{
    const char *p = ws(it->p, it->end);
    if (p < it->end && (*p == '[' || *p == ','))
        p = ws(p + 1, it->end);
    if (p >= it->end || *p == ']')
        return 0;
    const char *e = skip_value(p, it->end, 0);
    if (!e)
        return 0;
    elem->p = p;
    elem->end = e;
    it->p = ws(e, it->end);
    return 1;
}

static jv jbody(const rbuf *b)
{
    jv v = {b->buf ? b->buf : "", b->buf ? b->buf + b->len : ""};
    return v;
}

/* -------------------------------------------------------------------- HTTP -- */

typedef struct {
    char server[1024]; /* base URL, no trailing '/' */
    const char *token;
    int retries; /* further attempts after a 429, 5xx or network failure */
    int quiet;
    CURL *curl;
} remote;

typedef struct {
    long status; /* 0: no HTTP answer */
    rbuf body;
    char ctype[128];
    char location[512];
    double retry_after; /* seconds; < 0 when absent */
    char cerr[CURL_ERROR_SIZE];
} reply;

static size_t on_body(char *p, size_t size, size_t n, void *ctx)
{
    reply *r = ctx;
    return rb_add(&r->body, p, size * n) ? 0 : size * n;
}

static size_t on_header(char *p, size_t size, size_t n, void *ctx)
{
    reply *r = ctx;
    size_t len = size * n, k;
    char line[600];

    k = len < sizeof line - 1 ? len : sizeof line - 1;
    memcpy(line, p, k);
    line[k] = 0;
    line[strcspn(line, "\r\n")] = 0;
    if (!strncmp(line, "HTTP/", 5)) { /* a new response (after a 100 or redirect) */
        r->ctype[0] = r->location[0] = 0;
        r->retry_after = -1;
    }
    char *colon = strchr(line, ':');
    if (!colon)
        return len;
    *colon = 0;
    char *v = colon + 1 + strspn(colon + 1, " \t");
    if (!strcasecmp(line, "content-type"))
        snprintf(r->ctype, sizeof r->ctype, "%s", v);
    else if (!strcasecmp(line, "location"))
        snprintf(r->location, sizeof r->location, "%s", v);
    else if (!strcasecmp(line, "retry-after")) {
        char *end;
        double s = strtod(v, &end);
        if (end != v && s >= 0) {
            r->retry_after = s;
        } else {
            time_t t = curl_getdate(v, NULL); /* an HTTP-date */
            if (t > 0)
                r->retry_after =
                    difftime(t, time(NULL)) > 0 ? difftime(t, time(NULL)) : 0;
        }
    }
    return len;
}

static int on_xfer(void *ctx, curl_off_t dt, curl_off_t dn, curl_off_t ut, curl_off_t un)
{
    (void)ctx;
    (void)dt;
    (void)dn;
    (void)ut;
    (void)un;
    return interrupted; /* non-zero aborts the transfer */
}

static void sleep_s(double s)
{
    struct timespec ts;
    if (s <= 0)
        return;
    ts.tv_sec = (time_t)s;
    ts.tv_nsec = (long)((s - (double)ts.tv_sec) * 1e9);
    while (!interrupted && nanosleep(&ts, &ts) && errno == EINTR)
        ;
}

static double jitter(void)
{
    return 0.75 + 0.5 * ((double)rand() / RAND_MAX);
}

/* The request's header list: hdrs, then the token's Authorization. 0, or -1
 * without memory (nothing left allocated). */
static int http_headers(const remote *rm, const char *const *hdrs,
                        struct curl_slist **out)
{
    struct curl_slist *h = NULL, *t;
    char auth[1100];
    int bad_list = 0;

    for (int i = 0; hdrs && hdrs[i]; i++) {
        t = curl_slist_append(h, hdrs[i]);
        bad_list |= !t;
        h = t ? t : h;
    }
    if (rm->token && *rm->token) {
        snprintf(auth, sizeof auth, "Authorization: Bearer %s", rm->token);
        t = curl_slist_append(h, auth);
        bad_list |= !t;
        h = t ? t : h;
    }
    if (bad_list) {
        curl_slist_free_all(h);
        return -1;
    }
    *out = h;
    return 0;
}

/* The curl handle set up for one attempt. */
static void http_setup(remote *rm, const char *url, const char *method,
                       struct curl_slist *h, const char *body, size_t body_len,
                       long timeout, reply *r)
{
    curl_easy_reset(rm->curl);
    curl_easy_setopt(rm->curl, CURLOPT_URL, url);
    curl_easy_setopt(rm->curl, CURLOPT_NOSIGNAL, 1L);
    curl_easy_setopt(rm->curl, CURLOPT_USERAGENT, "qdc/1");
    curl_easy_setopt(rm->curl, CURLOPT_CONNECTTIMEOUT, 10L);
    /* Fail on silence rather than on total time: uploads may be long. */
    curl_easy_setopt(rm->curl, CURLOPT_LOW_SPEED_LIMIT, 1L);
    curl_easy_setopt(rm->curl, CURLOPT_LOW_SPEED_TIME, timeout);
    curl_easy_setopt(rm->curl, CURLOPT_HTTPHEADER, h);
    curl_easy_setopt(rm->curl, CURLOPT_WRITEFUNCTION, on_body);
    curl_easy_setopt(rm->curl, CURLOPT_WRITEDATA, r);
    curl_easy_setopt(rm->curl, CURLOPT_HEADERFUNCTION, on_header);
    curl_easy_setopt(rm->curl, CURLOPT_HEADERDATA, r);
    curl_easy_setopt(rm->curl, CURLOPT_ERRORBUFFER, r->cerr);
    curl_easy_setopt(rm->curl, CURLOPT_NOPROGRESS, 0L);
    curl_easy_setopt(rm->curl, CURLOPT_XFERINFOFUNCTION, on_xfer);
    if (!strcmp(method, "POST")) {
        curl_easy_setopt(rm->curl, CURLOPT_POST, 1L);
        curl_easy_setopt(rm->curl, CURLOPT_POSTFIELDS, body ? body : "");
        curl_easy_setopt(rm->curl, CURLOPT_POSTFIELDSIZE_LARGE,
                         (curl_off_t)(body ? body_len : 0));
    } else if (strcmp(method, "GET")) {
        curl_easy_setopt(rm->curl, CURLOPT_CUSTOMREQUEST, method);
    }
}

/* One HTTP exchange with retries. body may be NULL (no request body); timeout
 * is the longest silence accepted from the server, in seconds. Returns 0 when
 * an answer that is final for the caller arrived (r->status set), -1 when the
 * server could not be reached or kept answering 429/5xx. */
static int http(remote *rm, const char *method, const char *path, const char *const *hdrs,
                const char *body, size_t body_len, long timeout, reply *r)
{
    char url[4096];
    double backoff = 0.5;

    snprintf(url, sizeof url, "%s%s", rm->server, path);
    for (int attempt = 0;; attempt++) {
        struct curl_slist *h = NULL;
        CURLcode cc;

        rb_free(&r->body);
        r->status = 0;
        r->ctype[0] = r->location[0] = r->cerr[0] = 0;
        r->retry_after = -1;
        if (http_headers(rm, hdrs, &h)) {
            snprintf(r->cerr, sizeof r->cerr, "out of memory");
            return -1;
        }
        http_setup(rm, url, method, h, body, body_len, timeout, r);
        cc = curl_easy_perform(rm->curl);
        curl_slist_free_all(h);
        if (interrupted)
            return -1;
        if (cc == CURLE_OK)
            curl_easy_getinfo(rm->curl, CURLINFO_RESPONSE_CODE, &r->status);
        else if (!r->cerr[0])
            snprintf(r->cerr, sizeof r->cerr, "%s", curl_easy_strerror(cc));
        if (r->body.oom) {
            snprintf(r->cerr, sizeof r->cerr, "out of memory reading the reply");
            return -1;
        }
        int again = cc != CURLE_OK || r->status == 429 || r->status >= 500;
        if (!again)
            return 0;
        if (attempt >= rm->retries)
            return cc == CURLE_OK && r->status < 500 ? 0 : -1;
        double wait = r->retry_after >= 0 ? r->retry_after : backoff * jitter();
        if (wait > MAX_BACKOFF)
            wait = MAX_BACKOFF;
        backoff = backoff * 2 < MAX_BACKOFF ? backoff * 2 : MAX_BACKOFF;
        if (!rm->quiet) {
            if (cc != CURLE_OK)
                fprintf(stderr, "qdc: %s %s: %s; retrying in %.1f s\n", method, url,
                        r->cerr, wait);
            else
                fprintf(stderr, "qdc: %s %s: HTTP %ld%s; retrying in %.1f s\n", method,
                        url, r->status, r->status == 429 ? " (server busy)" : "", wait);
        }
        sleep_s(wait);
        if (interrupted)
            return -1;
    }
}

/* Exit code and one line on stderr for an answer the caller did not expect. */
static int http_fail(const char *what, int rc, const reply *r)
{
    char title[200], detail[600], state[32];
    jv b = jbody(&r->body);

    if (interrupted) {
        fprintf(stderr, "qdc: %s: interrupted\n", what);
        return CLI_EINTR;
    }
    if (rc) {
        if (r->status)
            fprintf(stderr, "qdc: %s: server error (HTTP %ld), giving up\n", what,
                    r->status);
        else
            fprintf(stderr, "qdc: %s: %s\n", what,
                    r->cerr[0] ? r->cerr : "network failure");
        return CLI_ENETWORK;
    }
    jstr(b, "title", title, sizeof title);
    jstr(b, "detail", detail, sizeof detail);
    fprintf(stderr, "qdc: %s: HTTP %ld%s%s%s%s\n", what, r->status, title[0] ? " " : "",
            title, detail[0] ? ": " : "", detail);
    if (r->status >= 500 || r->status == 429)
        return CLI_ENETWORK;
    /* A 409 for a job that ended without a result is the job's failure. */
    if (r->status == 409 && jstr(b, "state", state, sizeof state) &&
        (!strcmp(state, "failed") || !strcmp(state, "cancelled")))
        return CLI_EJOB;
    return CLI_EREJECTED;
}

/* ------------------------------------------------------------ command line -- */

typedef struct {
    remote rm;
    const char *pos[2]; /* positional arguments */
    int npos;
    const char *out, *report, *idem, *out_format, *in_format, *label;
    int wait, json;
    rbuf query; /* optimizer options as a query string */
} args;

static void remote_usage(FILE *f)
{
    fputs(
        "usage: qdc submit IN [--wait] [-o OUT] [--report R.json] [optimizer options]\n"
        "       qdc status JOB [--json]\n"
        "       qdc watch JOB\n"
        "       qdc fetch JOB -o OUT [--report R.json] [--wait]\n"
        "       qdc cancel JOB\n"
        "       qdc jobs [--json]\n"
        "Common options:\n"
        "  --server URL          qdcd address (default $QDC_SERVER, else " DEFAULT_SERVER
        ")\n"
        "  --token T             bearer token (default $QDC_TOKEN)\n"
        "  --retries N           attempts after a 429, 5xx or network failure (default "
        "8)\n"
        "  -q, --quiet           no progress or retry messages\n"
        "submit:\n"
        "  IN ('-': standard input) is read in any format qdc reads and uploaded\n"
        "  as it is (TetGen's .node/.ele as " MEDIA_QMESH "); a closed\n"
        "  surface (.stl .obj .off .poly .smesh) goes as it is, to be tetrahedralized.\n"
        "  -o OUT in IN's format is what qdc optimize IN OUT writes (names, tags\n"
        "  and arrays kept). The job id is printed on stdout (on stderr when -o\n"
        "  or --report is '-', standard output: in IN's format unless --out-format\n"
        "  says another). -o or --report imply --wait.\n"
        "  The job keeps IN's file name (shown by qdc jobs and status, the console\n"
        "  and its download names).\n"
        "  --label L             a label for the job, besides the file's name\n"
        "  --idempotency-key K   key of this submission (default: a random one; reuse\n"
        "                        it to make a re-run return the same job)\n"
        "  --in-format F, --out-format F   a format name, as in qdc optimize (default:\n"
        "                        from the extension)\n"
        "  Optimizer options are those of `qdc optimize` (--max-iter 20,\n"
        "  --boundary fixed, ...): --some-name V is sent as some_name=V.\n"
        "Exit codes: 0 ok, 1 usage, 2 bad input file, 4 output not written,\n"
        "  5 interrupted, 10 request rejected, 11 job failed or cancelled,\n"
        "  12 server unreachable or failing.\n",
        f);
}

static int query_add(rbuf *q, const char *name, const char *val, CURL *c)
{
    char *ev = curl_easy_escape(c, val, 0);
    int rc = 0;

    if (!ev)
        return -1;
    rc |= rb_add(q, q->len ? "&" : "?", 1);
    for (const char *p = name; *p; p++)
        rc |= rb_add(q, *p == '-' ? "_" : p, 1);
    rc |= rb_add(q, "=", 1);
    rc |= rb_add(q, ev, strlen(ev));
    curl_free(ev);
    return rc;
}

/* Parses argv (argv[0] is the subcommand); returns -1 on success, else an exit code. */
static int parse_args(int argc, char **argv, int max_pos, int allow_opt, args *a)
{
    const char *server = getenv("QDC_SERVER");
    const char *retries = NULL;

    a->rm.token = getenv("QDC_TOKEN");
    a->rm.retries = 8;
    for (int i = 1; i < argc; i++) {
        const char *s = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(s, "-h") || !strcmp(s, "--help")) {
            remote_usage(stdout);
            return CLI_OK;
        } else if (!strcmp(s, "-q") || !strcmp(s, "--quiet")) {
            a->rm.quiet = 1;
        } else if (!strcmp(s, "--wait")) {
            a->wait = 1;
        } else if (!strcmp(s, "--json")) {
            a->json = 1;
        } else if (s[0] == '-' && s[1]) {
            if (!v) {
                fprintf(stderr, "qdc: %s needs a value\n", s);
                return CLI_EUSAGE;
            }
            i++;
            if (!strcmp(s, "--server"))
                server = v;
            else if (!strcmp(s, "--token"))
                a->rm.token = v;
            else if (!strcmp(s, "--retries"))
                retries = v;
            else if (!strcmp(s, "-o") || !strcmp(s, "--output"))
                a->out = v;
            else if (!strcmp(s, "--label"))
                a->label = v;
            else if (!strcmp(s, "--report"))
                a->report = v;
            else if (!strcmp(s, "--idempotency-key"))
                a->idem = v;
            else if (!strcmp(s, "--out-format"))
                a->out_format = v;
            else if (!strcmp(s, "--in-format"))
                a->in_format = v;
            else if (allow_opt && s[1] == '-' && s[2]) {
                /* An optimizer option: the server checks name and value. */
                if (query_add(&a->query, s + 2, v, a->rm.curl)) {
                    fprintf(stderr, "qdc: out of memory\n");
                    return CLI_EUSAGE;
                }
            } else {
                fprintf(stderr, "qdc: %s: unknown option %s (qdc %s --help)\n", argv[0],
                        s, argv[0]);
                return CLI_EUSAGE;
            }
        } else if (a->npos < max_pos) {
            a->pos[a->npos++] = s;
        } else {
            fprintf(stderr, "qdc: %s: unexpected argument '%s'\n", argv[0], s);
            return CLI_EUSAGE;
        }
    }
    if (retries) {
        char *end;
        long n = strtol(retries, &end, 10);
        if (!*retries || *end || n < 0 || n > 1000) {
            fprintf(stderr, "qdc: --retries: '%s' is not a count\n", retries);
            return CLI_EUSAGE;
        }
        a->rm.retries = (int)n;
    }
    if (!server || !*server)
        server = DEFAULT_SERVER;
    snprintf(a->rm.server, sizeof a->rm.server, "%s", server);
    for (size_t n = strlen(a->rm.server); n && a->rm.server[n - 1] == '/'; n--)
        a->rm.server[n - 1] = 0;
    if (a->npos < max_pos) {
        fprintf(stderr, "qdc: %s: missing argument\n", argv[0]);
        remote_usage(stderr);
        return CLI_EUSAGE;
    }
    return -1;
}

/* A job id from "ID", "jobs/ID" or a URL ending in /v1/jobs/ID. */
static int job_id(const char *s, char out[33])
{
    const char *slash = strrchr(s, '/');
    size_t n;

    if (slash)
        s = slash + 1;
    n = strlen(s);
    if (n != 32)
        goto bad;
    for (size_t i = 0; i < n; i++)
        if (!strchr("0123456789abcdef", s[i]))
            goto bad;
    memmove(out, s, 33);
    return 0;
bad:
    fprintf(stderr, "qdc: '%s' is not a job id (32 lowercase hex digits)\n", s);
    return -1;
}

/* ---------------------------------------------------------------- progress -- */

typedef struct {
    FILE *f;
    int tty;
    int last_len;
    int quiet;
    char state[32];
} view;

static void view_line(view *v, const char *line)
{
    int n = (int)strlen(line);
    if (v->quiet)
        return;
    if (v->tty) {
        fprintf(v->f, "\r%s%*s", line, v->last_len > n ? v->last_len - n : 0, "");
        v->last_len = n;
    } else {
        fprintf(v->f, "%s\n", line);
    }
    fflush(v->f);
}

static void view_end(view *v)
{
    if (v->tty && v->last_len && !v->quiet) {
        fputc('\n', v->f);
        fflush(v->f);
    }
    v->last_len = 0;
}

/* One record of /progress: the same line as `qdc optimize` draws. */
static void view_record(view *v, jv rec)
{
    char phase[32], line[256];
    double it = 0, qm = 0, qmin = 0, dmin = 0, dmax = 0, inv = 0, step = 0, cg = 0,
           el = 0;

    if (!jstr(rec, "phase", phase, sizeof phase))
        snprintf(phase, sizeof phase, "?");
    jnum(rec, "iteration", &it);
    jnum(rec, "mean_ratio_mean", &qm);
    jnum(rec, "mean_ratio_min", &qmin);
    jnum(rec, "dihedral_min", &dmin);
    jnum(rec, "dihedral_max", &dmax);
    jnum(rec, "n_inverted", &inv);
    jnum(rec, "step", &step);
    jnum(rec, "cg_iterations", &cg);
    jnum(rec, "elapsed", &el);
    snprintf(line, sizeof line,
             "%-6s %3.0f  q mean %.4f min %+.4f  dihedral %6.2f..%6.2f  inverted %.0f  "
             "step %.3g  cg %.0f  %.1fs",
             phase, it, qm, qmin, dmin, dmax, inv, step, cg, el);
    view_line(v, line);
}

/* Follows /progress from the start until the job is done; *state gets the
 * final state. Returns -1 when done, else an exit code. */
static int follow(remote *rm, const char *id, view *v, char *state, size_t cap)
{
    long after = -1, run = 0; /* run: the attempt the records so far are of */
    char path[256], line[160];
    reply r = {0};
    int rc = -1;

    for (;;) {
        snprintf(path, sizeof path, "/v1/jobs/%s/progress?after=%ld&wait=%d", id, after,
                 POLL_WAIT);
        if (run > 0) /* told if the job runs again (a node died): records start over */
            snprintf(path + strlen(path), sizeof path - strlen(path), "&attempt=%ld",
                     run);
        int hr = http(rm, "GET", path, NULL, NULL, 0, POLL_WAIT + 30, &r);
        if (hr || r.status != 200) {
            view_end(v);
            rc = http_fail("progress", hr, &r);
            break;
        }
        jv b = jbody(&r.body), recs, it, rec, rs;
        double na = (double)after, at = (double)run, from = 0;
        int done = jbool(b, "done");
        if (jget(b, "restarted", &rs) && jnum(rs, "from_attempt", &from)) {
            double to = from + 1;
            jnum(rs, "attempt", &to);
            snprintf(
                line, sizeof line,
                "job %s runs again from the start: attempt %.0f (attempt %.0f stopped)",
                id, to, from);
            view_line(v, line);
        }
        if (jnum(b, "attempt", &at))
            run = (long)at;
        if (jget(b, "records", &recs)) {
            it = recs;
            while (jnext(&it, &rec))
                view_record(v, rec);
        }
        jstr(b, "state", state, cap);
        if (strcmp(state, v->state)) {
            /* On a terminal the live line shows "queued" until records come;
             * the final state gets a line of its own below the last record. */
            snprintf(line, sizeof line, "job %s %s", id, state);
            if (done)
                view_end(v);
            if (!v->tty || strcmp(state, "running"))
                view_line(v, line);
            snprintf(v->state, sizeof v->state, "%s", state);
        }
        if (jnum(b, "next_after", &na))
            after = (long)na;
        if (done)
            break;
    }
    view_end(v);
    rb_free(&r.body);
    return rc;
}

/* ------------------------------------------------------------------- files -- */

static meshio_format format_of(const char *path, const char *forced)
{
    return meshio_format_from_name(forced ? forced : path);
}

/* Checked before anything is sent, so a typo does not cost a job. "-"
 * (standard output) takes the job's format unless --out-format names one. */
static int out_format_ok(const args *a)
{
    if (a->out && a->report && !strcmp(a->out, "-") && !strcmp(a->report, "-")) {
        fputs("qdc: -o and --report cannot both be standard output ('-')\n", stderr);
        return 0;
    }
    if (!a->out || format_of(a->out, a->out_format) != MESHIO_AUTO ||
        (!strcmp(a->out, "-") && !a->out_format))
        return 1;
    fprintf(stderr,
            "qdc: %s: not a mesh format qdc writes (use its extension: .mesh, .node, "
            ".qmesh, .json, ..., or --out-format)\n",
            a->out);
    return 0;
}

/* submit -o OUT with --topology flips|full (in the query): OUT checked once
 * the input is read, before the job is sent (it used to run, and the
 * download then fail). 1 if refused. */
static int topology_out_refused(const args *a, const mesh_t *m)
{
    const char *q = a->query.buf;
    const char *topo = !q                            ? NULL
                       : strstr(q, "topology=flips") ? "flips"
                       : strstr(q, "topology=full")  ? "full"
                                                     : NULL;

    return a->out && topo &&
           cli_topology_out_refused(a->out,
                                    a->out_format ? meshio_format_from_name(a->out_format)
                                                  : MESHIO_AUTO,
                                    m, topo, "sent");
}

/* Writes len bytes to path (meshio_save_bytes: a file atomically, a pipe or
 * device straight into); "-" is stdout. */
static int write_file(const char *path, const char *buf, size_t len)
{
    qdc_error err;

    if (!strcmp(path, "-"))
        return fwrite(buf, 1, len, stdout) == len && !fflush(stdout) ? 0 : -1;
    return meshio_save_bytes(path, buf, len, &err) == QDC_OK ? 0 : -1;
}

/* The outcome in words of a finished job (docs/defaults.md): its report's
 * "outcome", the lines `qdc optimize` ends with, each line led by lead. body: the
 * report when already fetched, else NULL (fetched here; nothing printed when the
 * job has no report). */
static void print_outcome(remote *rm, const char *id, const rbuf *body, FILE *f,
                          const char *lead)
{
    char path[128], text[1024];
    reply r = {0};
    jv b, arr, it, e;
    static const char *const lists[2][2] = {{"outcome.warnings", "warning"},
                                            {"outcome.suggestions", "suggestion"}};

    if (!body) {
        snprintf(path, sizeof path, "/v1/jobs/%s/report", id);
        if (http(rm, "GET", path, NULL, NULL, 0, 60, &r) || r.status != 200)
            goto out;
        body = &r.body;
    }
    b = jbody(body);
    if (!jstr(b, "outcome.summary", text, sizeof text))
        goto out;
    fprintf(f, "%soutcome: %s\n", lead, text);
    for (int l = 0; l < 2; l++) {
        if (!jget(b, lists[l][0], &arr))
            continue;
        it = arr;
        while (jnext(&it, &e))
            if (jtext(e, text, sizeof text))
                fprintf(f, "%s%s: %s\n", lead, lists[l][1], text);
    }
out:
    rb_free(&r.body);
}

/* Downloads the result into out, in its extension's format or out_format,
 * and the report into report; either may be NULL. local: the input as read
 * with its source, when it was sent as the binary mesh (TetGen's files): an
 * OUT in its format is then the input with the result's coordinates put in,
 * here. */
static int download(remote *rm, const char *id, const char *out, const char *out_format,
                    const char *report, mesh_t *local)
{
    char path[256];
    reply r = {0};
    mesh_t *m = NULL;
    qdc_error err;
    qdc_status st;
    int rc = CLI_OK, hr;

    qdc_error_clear(&err);
    if (out) {
        /* the format OUT names; its extension names a family (.msh), and
         * then the job's own variant is asked for: in the upload's format the
         * server writes the upload back with only the coordinates replaced
         * (names, tags, arrays kept), as qdc optimize writes OUT. OUT "-"
         * without --out-format: the job's format */
        meshio_format want = format_of(out, out_format), want_named = want;
        meshio_format lsrc = local ? meshio_source_format(local) : MESHIO_AUTO;
        meshio_format job = MESHIO_AUTO;
        int served;
        if (!out_format) {
            char name[40];
            snprintf(path, sizeof path, "/v1/jobs/%s", id);
            hr = http(rm, "GET", path, NULL, NULL, 0, 30, &r);
            if (!hr && r.status == 200 &&
                jstr(jbody(&r.body), "mesh.format", name, sizeof name))
                job = meshio_format_from_name(name);
            want = want == MESHIO_AUTO ? job : meshio_format_variant(want, job);
            /* a local source in OUT's format (or for "-"): put the result's
             * coordinates into it here */
            if (lsrc != MESHIO_AUTO && (want_named == MESHIO_AUTO ||
                                        meshio_format_variant(want_named, lsrc) == lsrc))
                want = MESHIO_AUTO;
        } else if (lsrc != MESHIO_AUTO && want == lsrc) {
            want = MESHIO_AUTO;
        }
        if (want == MESHIO_AUTO && lsrc == MESHIO_AUTO) /* a surface's job: Medit */
            want = MESHIO_MEDIT;
        /* the server writes every format qdc writes (MED: over the upload
         * of a MED job, else a MED file of its own) */
        served = want != MESHIO_TETGEN &&
                 (meshio_has_writer(want) || (want != MESHIO_AUTO && want == job));
        snprintf(path, sizeof path, "/v1/jobs/%s/result?format=%s", id,
                 meshio_format_name(served ? want : MESHIO_QMESH));
        hr = http(rm, "GET", path, NULL, NULL, 0, 120, &r);
        if (hr || r.status != 200) {
            rc = http_fail("result", hr, &r);
            goto out;
        }
        /* a mesh, or the server sent something else (MED: an HDF5 file,
         * which libqdc does not read) */
        if (served && want == MESHIO_MED)
            st = cli_h5_bytes(r.body.buf, r.body.len)
                     ? QDC_OK
                     : qdc_fail(&err, QDC_EPARSE, "MED: the server sent no HDF5 file");
        else
            st = meshio_read(r.body.buf, r.body.len, served ? want : MESHIO_QMESH, &m,
                             &err);
        if (st != QDC_OK) {
            cli_error("result", &err, st);
            rc = CLI_ENETWORK;
            goto out;
        }
        if (want == MESHIO_AUTO) {
            if (m->nv == local->nv && m->nt != local->nt) {
                /* a topology mode changed the tets: the result's tets and
                 * regions in the local mesh, written by qdc's own writer */
                int pd = local->pdata && local->pdata->n > 0;
                meshio_format of = meshio_save_format(out, MESHIO_AUTO, local);
                mesh_swap_tets(local, m);
                meshio_drop_source(local);
                if (!rm->quiet)
                    fprintf(stderr,
                            "qdc: note: %s: written by qdc's own writer (the job "
                            "changed the tets): only vertices, tets, triangles%s\n",
                            out,
                            !pd ? " and their region tags are kept"
                            : meshio_writes_pdata(of)
                                ? ", their region tags and the point data are kept"
                                : " and their region tags are kept; point data dropped");
            } else if (m->nv != local->nv || m->nt != local->nt) {
                fprintf(stderr,
                        "qdc: result: %d vertices, %d tets: not the input's %d, %d\n",
                        (int)m->nv, (int)m->nt, (int)local->nv, (int)local->nt);
                rc = CLI_ENETWORK;
                goto out;
            }
            memcpy(local->xyz, m->xyz, 3 * sizeof(double) * (size_t)m->nv);
            mesh_free(m);
            m = NULL;
        }
        if (served ? write_file(out, r.body.buf, r.body.len) != 0
                   : (st = cli_save_mesh(out, want, want == MESHIO_AUTO ? local : m,
                                         &err)) != QDC_OK) {
            if (served)
                fprintf(stderr, "qdc: %s: cannot write\n", out);
            else
                cli_error(out, &err, st);
            rc = CLI_EOUTPUT;
            goto out;
        }
    }
    if (report) {
        snprintf(path, sizeof path, "/v1/jobs/%s/report", id);
        hr = http(rm, "GET", path, NULL, NULL, 0, 120, &r);
        if (hr || r.status != 200) {
            rc = http_fail("report", hr, &r);
            goto out;
        }
        if (write_file(report, r.body.buf ? r.body.buf : "", r.body.len)) {
            fprintf(stderr, "qdc: %s: cannot write\n", report);
            rc = CLI_EOUTPUT;
        }
    }
    if (!rm->quiet)
        print_outcome(rm, id, report ? &r.body : NULL, stderr, "qdc: ");
out:
    mesh_free(m);
    rb_free(&r.body);
    return rc;
}

/* Prints why a job ended without a result; CLI_EJOB. */
static int job_failed(remote *rm, const char *id, const char *state)
{
    char path[128], msg[600] = "";
    reply r = {0};
    jv b, e;

    snprintf(path, sizeof path, "/v1/jobs/%s", id);
    if (!http(rm, "GET", path, NULL, NULL, 0, 30, &r) && r.status == 200) {
        b = jbody(&r.body);
        if (jget(b, "error", &e) && !jstr(e, "detail", msg, sizeof msg) &&
            !jstr(e, "message", msg, sizeof msg))
            jstr(e, "title", msg, sizeof msg);
        if (!msg[0])
            jstr(b, "stop_reason", msg, sizeof msg);
        if (!strcmp(msg, state))
            msg[0] = 0;
    }
    fprintf(stderr, "qdc: job %s %s%s%s\n", id, state, msg[0] ? ": " : "", msg);
    rb_free(&r.body);
    return CLI_EJOB;
}

/* Follows the job to its end: -1 when it succeeded, else an exit code. */
static int await_job(remote *rm, const char *id, view *v)
{
    char state[32] = "";
    int rc = follow(rm, id, v, state, sizeof state);

    if (rc >= 0)
        return rc;
    return strcmp(state, "succeeded") ? job_failed(rm, id, state) : -1;
}

/* --------------------------------------------------------------- commands -- */

static void random_key(char out[33])
{
    unsigned char b[16];
    int fd = open("/dev/urandom", O_RDONLY | O_CLOEXEC);
    ssize_t n = fd >= 0 ? read(fd, b, sizeof b) : -1;

    if (fd >= 0)
        close(fd);
    if (n != (ssize_t)sizeof b) {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        srand((unsigned)ts.tv_nsec ^ (unsigned)getpid());
        for (size_t i = 0; i < sizeof b; i++)
            b[i] = (unsigned char)rand();
    }
    for (size_t i = 0; i < sizeof b; i++)
        snprintf(out + 2 * i, 3, "%02x", b[i]);
}

static int cmd_submit(args *a)
{
    const char *in = a->pos[0];
    mesh_t *m = NULL;
    rbuf body = {0};
    reply r = {0};
    qdc_error err;
    qdc_status st;
    char key[200], hkey[260], path[4200], id[64] = "";
    int rc = CLI_OK, hr;
    view v = {stderr, isatty(2), 0, a->rm.quiet, ""};
    meshio_options keep = {.log = NULL, .log_ctx = NULL, .source = 1};
    meshio_format src, own; /* sent as; the input's own format (AUTO: none kept) */
    surface_format sf;
    char *raw = NULL, ctype[128];
    size_t rawlen = 0;
    const char *out_format = a->out_format;

    qdc_error_clear(&err);
    if (a->out || a->report)
        a->wait = 1;
    if (!out_format_ok(a))
        return CLI_EUSAGE;
    /* the job keeps the file's name (its last part) and the label: the list,
     * the console and download names show them */
    if (strcmp(in, "-")) {
        const char *base = strrchr(in, '/');
        if (query_add(&a->query, "name", base ? base + 1 : in, a->rm.curl))
            return CLI_EUSAGE;
    }
    if (a->label && query_add(&a->query, "label", a->label, a->rm.curl))
        return CLI_EUSAGE;
    /* a closed surface (qdcd tetrahedralizes it with TetGen): sent as it is,
     * after the checks qdcd makes */
    sf = a->in_format ? surface_format_from_name(a->in_format)
                      : cli_input_surface(in, &raw, &rawlen);
    if (sf != SURFACE_AUTO) {
        surface_t *s = NULL;
        st = raw ? QDC_OK : cli_slurp(in, &raw, &rawlen, &err);
        if (st == QDC_OK)
            st = surface_read(raw, rawlen, sf, &s, &err);
        if (st == QDC_OK)
            st = surface_check(s, &err);
        surface_free(s);
        if (st != QDC_OK) {
            cli_error(in, &err, st);
            qdc_free(raw);
            return CLI_EINPUT;
        }
        body.buf = raw;
        body.len = rawlen;
        raw = NULL;
        snprintf(ctype, sizeof ctype, "Content-Type: %s", surface_media_type(sf));
        goto send;
    }
    /* read (and checked) here, so a bad file costs no job; a mesh told by its
     * contents is read from the bytes already read */
    st = raw ? meshio_read_ex(raw, rawlen, MESHIO_AUTO, &keep, &m, &err)
             : cli_read_mesh(
                   in, a->in_format ? meshio_format_from_name(a->in_format) : MESHIO_AUTO,
                   &keep, &m, &raw, &rawlen, &err);
    /* XDMF whose heavy data is in a .h5 file: the two sent together as
     * multipart/form-data */
    if (st == QDC_EFORMAT && strcmp(in, "-") &&
        cli_xdmf_h5_retry(in, st, &keep, &m, &err) == QDC_OK) {
        char b[64];
        random_key(b);
        st = cli_xdmf_h5_form(in, b, rb_writer, &body, &err);
        snprintf(ctype, sizeof ctype, "Content-Type: multipart/form-data; boundary=%.40s",
                 b);
        if (st == QDC_OK && !body.oom) {
            if (!a->out) { /* else kept: -o is written here as qdc optimize writes it */
                mesh_free(m);
                m = NULL;
            }
            goto send;
        }
        rb_free(&body);
        st = body.oom ? QDC_ENOMEM : st;
    }
    if (st != QDC_OK) {
        cli_error(in, &err, st);
        qdc_free(raw);
        mesh_free(m);
        return CLI_EINPUT;
    }
    if (topology_out_refused(a, m)) {
        qdc_free(raw);
        mesh_free(m);
        return CLI_EUSAGE;
    }
    /* sent as it is (the file's own variant, which the server writes back
     * with only the coordinates replaced: names, tags and arrays come back;
     * by its media type, or named in the query), else (TetGen's two files)
     * as the binary mesh */
    own = src = meshio_source_format(m);
    if (raw && src != MESHIO_AUTO && src != MESHIO_TETGEN) {
        body.buf = raw;
        body.len = rawlen;
        raw = NULL;
        if (!meshio_media_type(src) &&
            query_add(&a->query, "format", meshio_format_name(src), a->rm.curl))
            st = QDC_ENOMEM;
    } else {
        src = MESHIO_QMESH;
        st = meshio_write(m, MESHIO_QMESH, rb_writer, &body, &err);
    }
    qdc_free(raw);
    /* an input with no file of its own to write back (JSON, the binary mesh)
     * goes to standard output as Medit, as qdc optimize writes it there */
    if (!out_format && a->out && !strcmp(a->out, "-") && own == MESHIO_AUTO)
        out_format = "medit";
    /* sent as the binary mesh: kept (with its source) to write -o in its own
     * format as qdc optimize would, the result's coordinates put in */
    if (src != MESHIO_QMESH || !a->out || own == MESHIO_AUTO) {
        mesh_free(m);
        m = NULL;
    }
    snprintf(ctype, sizeof ctype, "Content-Type: %s",
             meshio_media_type(src) ? meshio_media_type(src)
                                    : "application/octet-stream");
    if (st != QDC_OK || body.oom) {
        cli_error(in, &err, st != QDC_OK ? st : QDC_ENOMEM);
        rb_free(&body);
        mesh_free(m);
        return CLI_EINPUT;
    }
send:
    if (a->idem)
        snprintf(key, sizeof key, "%s", a->idem);
    else
        random_key(key);
    snprintf(hkey, sizeof hkey, "Idempotency-Key: %s", key);
    const char *const h[] = {ctype, hkey, NULL};
    snprintf(path, sizeof path, "/v1/jobs%s", a->query.buf ? a->query.buf : "");
    hr = http(&a->rm, "POST", path, h, body.buf, body.len, 120, &r);
    rb_free(&body);
    if (hr || r.status != 202) {
        rc = http_fail("submit", hr, &r);
        goto out;
    }
    if (!jstr(jbody(&r.body), "id", id, sizeof id) || job_id(id, id)) {
        fprintf(stderr, "qdc: submit: the server's answer has no job id\n");
        rc = CLI_ENETWORK;
        goto out;
    }
    if ((a->out && !strcmp(a->out, "-")) || (a->report && !strcmp(a->report, "-")))
        fprintf(stderr, "qdc: job %s\n", id); /* stdout carries the result */
    else
        printf("%s\n", id);
    fflush(stdout);
    if (!a->wait)
        goto out;
    rc = await_job(&a->rm, id, &v);
    if (rc >= 0)
        goto out;
    rc = download(&a->rm, id, a->out, out_format, a->report, m);
out:
    if (interrupted && id[0])
        fprintf(stderr,
                "qdc: job %s goes on on the server (qdc watch %s, qdc cancel %s)\n", id,
                id, id);
    mesh_free(m);
    rb_free(&r.body);
    return rc;
}

/* Summary of a job object on one line. */
static void print_job(jv j, FILE *f)
{
    char id[64], state[32], fmt[16], name[256] = "", label[128] = "";
    double nt = 0, it = 0, qm = 0, qmin = 0, inv = 0;
    int has_q;

    jstr(j, "id", id, sizeof id);
    jstr(j, "state", state, sizeof state);
    jstr(j, "mesh.format", fmt, sizeof fmt);
    jnum(j, "mesh.tets", &nt);
    jnum(j, "iterations", &it);
    has_q = jnum(j, "progress.mean_ratio_mean", &qm);
    jnum(j, "progress.mean_ratio_min", &qmin);
    jnum(j, "progress.n_inverted", &inv);
    jstr(j, "file_name", name, sizeof name);
    jstr(j, "label", label, sizeof label);
    fprintf(f, "%s  %-9s  %-5s %9.0f tets  %3.0f it", id, state, fmt, nt, it);
    if (has_q)
        fprintf(f, "  q mean %.4f min %+.4f  inverted %.0f", qm, qmin, inv);
    /* the names last: the columns before them keep their places */
    if (label[0] || name[0])
        fprintf(f, "  %s%s%s%s", label, label[0] && name[0] ? " (" : "", name,
                label[0] && name[0] ? ")" : "");
    fputc('\n', f);
}

/* GET or POST a job route whose answer is the job; prints it. */
static int job_request(args *a, const char *method, const char *suffix, const char *what)
{
    char id[33], path[128];
    reply r = {0};
    int rc = CLI_OK, hr;

    if (job_id(a->pos[0], id))
        return CLI_EUSAGE;
    snprintf(path, sizeof path, "/v1/jobs/%s%s", id, suffix);
    hr = http(&a->rm, method, path, NULL, NULL, 0, 60, &r);
    if (hr || r.status != 200)
        rc = http_fail(what, hr, &r);
    else if (a->json)
        fwrite(r.body.buf, 1, r.body.len, stdout);
    else {
        jv j = jbody(&r.body), link;
        print_job(j, stdout);
        /* a finished job's outcome in words, under its line */
        if (!strcmp(what, "status") && jget(j, "links.report", &link))
            print_outcome(&a->rm, id, NULL, stdout, "  ");
    }
    rb_free(&r.body);
    return rc;
}

static int cmd_status(args *a)
{
    return job_request(a, "GET", "", "status");
}

static int cmd_watch(args *a)
{
    char id[33];
    view v = {stdout, isatty(1), 0, a->rm.quiet, ""};
    int rc;

    if (job_id(a->pos[0], id))
        return CLI_EUSAGE;
    rc = await_job(&a->rm, id, &v);
    return rc >= 0 ? rc : CLI_OK;
}

/* After a download: a job cancelled while it ran has the best mesh so far as
 * its result (qdcd keeps it, as qdc optimize does on Ctrl-C): written, said,
 * and exit 11 as for any cancelled job. */
static int cancelled_note(remote *rm, const char *id)
{
    char path[128], state[32] = "";
    reply r = {0};

    snprintf(path, sizeof path, "/v1/jobs/%s", id);
    if (!http(rm, "GET", path, NULL, NULL, 0, 30, &r) && r.status == 200)
        jstr(jbody(&r.body), "state", state, sizeof state);
    rb_free(&r.body);
    if (strcmp(state, "cancelled"))
        return CLI_OK;
    fprintf(stderr,
            "qdc: job %s was cancelled: what was written is its best mesh so far\n", id);
    return CLI_EJOB;
}

static int cmd_fetch(args *a)
{
    char id[33];
    view v = {stderr, isatty(2), 0, a->rm.quiet, ""};
    int rc;

    if (job_id(a->pos[0], id))
        return CLI_EUSAGE;
    if (!a->out && !a->report) {
        fprintf(stderr, "qdc: fetch: give -o OUT and/or --report R.json\n");
        return CLI_EUSAGE;
    }
    if (!out_format_ok(a))
        return CLI_EUSAGE;
    if (a->wait) {
        rc = await_job(&a->rm, id, &v);
        if (rc >= 0)
            return rc;
    }
    rc = download(&a->rm, id, a->out, a->out_format, a->report, NULL);
    return rc == CLI_OK ? cancelled_note(&a->rm, id) : rc;
}

static int cmd_cancel(args *a)
{
    return job_request(a, "POST", ":cancel", "cancel");
}

static int cmd_jobs(args *a)
{
    char path[256], token[64] = "";
    reply r = {0};
    int rc = CLI_OK, hr;

    for (;;) {
        snprintf(path, sizeof path, "/v1/jobs?page_size=200%s%s",
                 token[0] ? "&page_token=" : "", token);
        hr = http(&a->rm, "GET", path, NULL, NULL, 0, 60, &r);
        if (hr || r.status != 200) {
            rc = http_fail("jobs", hr, &r);
            break;
        }
        jv b = jbody(&r.body), list, it, j;
        if (jget(b, "jobs", &list)) {
            it = list;
            while (jnext(&it, &j)) {
                if (a->json) {
                    fwrite(j.p, 1, (size_t)(j.end - j.p), stdout);
                    fputc('\n', stdout);
                } else {
                    print_job(j, stdout);
                }
            }
        }
        if (!jstr(b, "next_page_token", token, sizeof token) || !token[0])
            break;
    }
    rb_free(&r.body);
    return rc;
}

int cli_remote(int argc, char **argv)
{
    static const struct {
        const char *name;
        int (*fn)(args *);
        int npos, opts;
    } cmds[] = {{"submit", cmd_submit, 1, 1}, {"status", cmd_status, 1, 0},
                {"watch", cmd_watch, 1, 0},   {"fetch", cmd_fetch, 1, 0},
                {"cancel", cmd_cancel, 1, 0}, {"jobs", cmd_jobs, 0, 0}};
    args a;
    int rc = CLI_EUSAGE;
    size_t k;
    struct sigaction sa;

    for (k = 0; k < sizeof cmds / sizeof cmds[0] && strcmp(cmds[k].name, argv[0]); k++)
        ;
    if (k == sizeof cmds / sizeof cmds[0])
        return CLI_EUSAGE;
    memset(&a, 0, sizeof a);
    if (curl_global_init(CURL_GLOBAL_DEFAULT) != CURLE_OK) {
        fprintf(stderr, "qdc: cannot initialise libcurl\n");
        return CLI_ENETWORK;
    }
    a.rm.curl = curl_easy_init();
    if (!a.rm.curl) {
        fprintf(stderr, "qdc: cannot initialise libcurl\n");
        curl_global_cleanup();
        return CLI_ENETWORK;
    }
    srand((unsigned)time(NULL) ^ (unsigned)getpid());
    rc = parse_args(argc, argv, cmds[k].npos, cmds[k].opts, &a);
    if (rc < 0) {
        /* Ctrl-C ends a wait cleanly; the job itself goes on on the server. */
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_signal;
        sigemptyset(&sa.sa_mask);
        sigaction(SIGINT, &sa, NULL);
        sigaction(SIGTERM, &sa, NULL);
        rc = cmds[k].fn(&a);
        if (interrupted && rc == CLI_OK)
            rc = CLI_EINTR;
    }
    rb_free(&a.query);
    curl_easy_cleanup(a.rm.curl);
    curl_global_cleanup();
    return rc;
}
