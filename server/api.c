/* api.c - the endpoints. Routing happens at the first call (headers only), so
 * a request that is refused (401, 404, 413, 415, 429) is answered before its
 * body is read. Mesh bodies are streamed to a temporary file in DATA/tmp and
 * parsed by libqdc (never by jansson) once complete; the job row is committed
 * and the input file fsynced and renamed into DATA/jobs/ID before the 202.
 * With a PostgreSQL store (shared.h) the input is stored in the database in
 * the transaction that inserts the row, and any node serves any job's
 * records, results and report, fetching what its cache lacks. */
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

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/mman.h>
#include <sys/random.h>
#include <unistd.h>

#define MEDIA_QMESH "application/vnd.qdc.mesh"

static const char *const no_headers[] = {NULL};

/* ------------------------------------------------------------------ routing -- */

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

/* The job of the route, if it exists and belongs to the caller; else a 404. */
/* The job store did not answer (a database that went away, SQLite busy or
 * out of space): a passing condition, 503 with a Retry-After. */
enum MHD_Result store_unavailable(struct MHD_Connection *c, req *r, const char *what)
{
    static const char *const h[] = {MHD_HTTP_HEADER_RETRY_AFTER, "5", NULL};
    return http_problem(c, r, 503, "store-unavailable", "job store unavailable", what,
                        NULL, h);
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
static enum MHD_Result storage_full(struct MHD_Connection *c, req *r, const char *what)
{
    static const char *const h[] = {MHD_HTTP_HEADER_RETRY_AFTER, "30", NULL};
    char d[600];

    snprintf(d, sizeof d, "%.400s: the server's disk is full; try again later", what);
    return http_problem(c, r, 507, "io", "insufficient storage", d, NULL, h);
}

static int disk_full(int e)
{
    return e == ENOSPC || e == EDQUOT;
}

/* ------------------------------------------------------------------- upload -- */

typedef struct {
    opt_options o;
    double cap;
    double tq, tv; /* tetgen_quality, max_volume; -1 when not given */
    char why[200];
    int bad;
} opt_scan;

static enum MHD_Result scan_option(void *cls, enum MHD_ValueKind kind, const char *key,
                                   size_t key_size, const char *val, size_t val_size)
{
    opt_scan *s = cls;
    (void)kind;
    if (s->bad)
        return MHD_NO;
    if (!val)
        val = "";
    /* a %00 in the query would cut the value short: max_iter=5%00abc is not 5 */
    if (strlen(key) != key_size || strlen(val) != val_size) {
        snprintf(s->why, sizeof s->why, "option '%.40s': the value has a NUL byte (%%00)",
                 key);
        s->bad = 1;
        return MHD_NO;
    }
    if (!strcmp(key, "format"))
        return MHD_YES; /* the body's format: begin_upload */
    if (!strcmp(key, "tetgen_quality") || !strcmp(key, "max_volume")) {
        /* Surface uploads: TetGen's -q radius-edge bound (>= 1, 0 = no
         * refinement) and -a volume bound (0 = none), as `qdc tetra`. */
        char *end;
        double v = strtod(val, &end);
        int q = !strcmp(key, "tetgen_quality");
        if (!*val || *end || !(v >= 0 && v <= 1e300) || (q && v > 0 && v < 1)) {
            snprintf(s->why, sizeof s->why, "option '%s': '%.40s' is not %s", key, val,
                     q ? "0 or a number >= 1" : "a number >= 0");
            s->bad = 1;
            return MHD_NO;
        }
        *(q ? &s->tq : &s->tv) = v;
        return MHD_YES;
    }
    if (job_opt_set(&s->o, key, val, s->cap, s->why, sizeof s->why))
        s->bad = 1;
    return s->bad ? MHD_NO : MHD_YES;
}

/* ------------------------------------------------------------ media types -- */

/* Every mesh media type this server reads and writes (TetGen, two files, has
 * none), then with surfaces those of the surfaces it tetrahedralizes: JSON
 * strings joined by commas. */
static void media_list(sbuf *b, int surfaces)
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

/* Whether results and inputs are served in format k: the formats with a media
 * type (TetGen is two files; Abaqus and Netgen are written only over their
 * own source file, which a result does not have). */
static int offerable(meshio_format k)
{
    return k != MESHIO_AUTO && k != MESHIO_TETGEN && meshio_media_type(k) != NULL;
}

/* The same as ?format= names. */
static void format_names(sbuf *b, int surfaces)
{
    int n = 0;
    for (int f = 1; f < MESHIO_FORMAT_COUNT; f++) {
        if (!meshio_media_type((meshio_format)f))
            continue;
        sb_puts(b, n++ ? "," : "");
        sb_json_str(b, meshio_format_name((meshio_format)f));
    }
    for (int f = 1; surfaces && f < SURFACE_FORMAT_COUNT; f++) {
        sb_puts(b, n++ ? "," : "");
        sb_json_str(b, surface_format_name((surface_format)f));
    }
}

/* 415 for an upload: what was sent (detail) and everything accepted. */
static enum MHD_Result unsupported(struct MHD_Connection *c, req *r, const char *detail)
{
    sbuf x = {0};
    enum MHD_Result ret;

    sb_puts(&x, "\"accepted\":[");
    media_list(&x, 1);
    sb_puts(&x, "],\"sniffed\":[\"application/octet-stream\",\"text/plain\"],"
                "\"formats\":[");
    format_names(&x, 1);
    sb_puts(&x, "]");
    ret = http_problem(c, r, 415, "unsupported-media-type", "unsupported media type",
                       detail, x.oom ? NULL : x.buf, NULL);
    sb_free(&x);
    return ret;
}

/* Name of the upload's format ("gmsh-bin", "stl"), "unknown" before sniffing. */
static const char *upload_format_name(const req *r)
{
    if (r->sfmt != SURFACE_AUTO)
        return surface_format_name(r->sfmt);
    return r->fmt != MESHIO_AUTO ? meshio_format_name(r->fmt) : "unknown";
}

/* The body's format: ?format= (a name), else Content-Type; sniffed from the
 * content later when neither says (no type, octet-stream, text/plain, or
 * form-urlencoded, which curl --data-binary sends without -H). 0, or -1 when
 * the request gets a 415 (detail in why). */
static int upload_format(struct MHD_Connection *c, req *r, char *why, size_t cap)
{
    const char *fq = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "format");
    const char *ct =
        MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_TYPE);
    char ctype[128];

    r->fmt = MESHIO_AUTO;
    r->sfmt = SURFACE_AUTO;
    if (fq) {
        r->fmt = strchr(fq, '/') ? meshio_format_from_media_type(fq)
                                 : meshio_format_from_name(fq);
        if (r->fmt == MESHIO_AUTO)
            r->sfmt = strchr(fq, '/') ? surface_format_from_media_type(fq)
                                      : surface_format_from_name(fq);
        if (r->fmt == MESHIO_TETGEN) {
            snprintf(why, cap,
                     "TetGen .node/.ele is two files; upload one of the "
                     "accepted formats instead");
            return -1;
        }
        if (r->fmt == MESHIO_AUTO && r->sfmt == SURFACE_AUTO) {
            snprintf(why, cap, "format '%.60s' is not one this server reads", fq);
            return -1;
        }
        return 0;
    }
    snprintf(ctype, sizeof ctype, "%s", ct ? ct : "");
    ctype[strcspn(ctype, "; \t")] = 0;
    if (!ctype[0] || !strcasecmp(ctype, "text/plain") ||
        !strcasecmp(ctype, "application/octet-stream") ||
        !strcasecmp(ctype, "application/x-www-form-urlencoded")) {
        r->sniff = 1;
        return 0;
    }
    r->fmt = meshio_format_from_media_type(ct);
    if (r->fmt == MESHIO_AUTO)
        r->sfmt = surface_format_from_media_type(ct);
    if (r->fmt == MESHIO_AUTO && r->sfmt == SURFACE_AUTO) {
        snprintf(why, cap,
                 "media type '%.100s' is not a mesh or surface type this "
                 "server reads",
                 ctype);
        return -1;
    }
    return 0;
}

/* max_queued reached? (cnt receives the counts) */
static int queue_full(qdcd *q, job_counts *cnt)
{
    return q->store->ops->counts(q->store, cnt) == QDC_OK &&
           cnt->by_state[JOB_QUEUED] >= q->cfg.max_queued;
}

static enum MHD_Result queue_full_reply(struct MHD_Connection *c, req *r,
                                        const job_counts *cnt)
{
    static const char *const h[] = {MHD_HTTP_HEADER_RETRY_AFTER, "5", NULL};
    char extra[96];
    snprintf(extra, sizeof extra, "\"queued\":%lld,\"max_queued\":%d",
             (long long)cnt->by_state[JOB_QUEUED], r->q->cfg.max_queued);
    return http_problem(c, r, 429, "queue-full", "too many queued jobs",
                        "the queue is full; retry later", extra, h);
}

static enum MHD_Result begin_upload(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    const char *cl, *ik;
    char tmpl[4200];
    opt_scan s;
    job_counts cnt;
    int64_t limit;

    r->upload = 1;
    /* Options are checked before any byte of the body is read. */
    memset(&s, 0, sizeof s);
    opt_defaults(&s.o);
    s.cap = q->cfg.job_time_limit;
    s.o.time_limit = s.cap;
    s.tq = s.tv = -1;
    MHD_get_connection_values_n(c, MHD_GET_ARGUMENT_KIND, scan_option, &s);
    if (s.bad)
        return http_problem(c, r, 400, "invalid-option", "invalid option", s.why, NULL,
                            NULL);
    sbuf oj = {0};
    job_opt_json(&s.o, &oj);
    if (oj.len && (s.tq >= 0 || s.tv >= 0)) {
        oj.len--; /* the closing brace */
        if (s.tq >= 0)
            sb_printf(&oj, ",\"tetgen_quality\":%.17g", s.tq);
        if (s.tv >= 0)
            sb_printf(&oj, ",\"max_volume\":%.17g", s.tv);
        sb_puts(&oj, "}");
        r->tetgen_opts = 1;
    }
    snprintf(r->options, sizeof r->options, "%s", oj.buf && !oj.oom ? oj.buf : "{}");
    sb_free(&oj);
    {
        char why[200];
        if (upload_format(c, r, why, sizeof why))
            return unsupported(c, r, why);
    }
    if (r->tetgen_opts && r->fmt != MESHIO_AUTO)
        return http_problem(c, r, 400, "invalid-option", "invalid option",
                            "tetgen_quality and max_volume apply to surface uploads only",
                            NULL, NULL);

    ik = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Idempotency-Key");
    if (ik) {
        size_t n = strlen(ik);
        int ok = n > 0 && n < sizeof r->idem;
        for (size_t i = 0; ok && i < n; i++)
            ok = ik[i] > 32 && ik[i] < 127;
        if (!ok)
            return http_problem(
                c, r, 400, "invalid-idempotency-key", "invalid Idempotency-Key",
                "the key must be 1 to 128 visible ASCII characters", NULL, NULL);
        memcpy(r->idem, ik, n + 1);
        r->hashing = 1;
        sha256_init(&r->hash);
        sha256_update(&r->hash, r->options, strlen(r->options));
        if (MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "format")) {
            /* ?format= changes what the body means; a Content-Type does not
             * count (a retry may send the same bytes under another type). */
            const char *fn = upload_format_name(r);
            sha256_update(&r->hash, "\nformat=", 8);
            sha256_update(&r->hash, fn, strlen(fn));
        }
    }

    /* A replay of an accepted request is answered even when the queue is full.
     * Checked here so that a refused body is not uploaded, and again at commit
     * (uploads that were in flight together). */
    job_rec prev;
    if (!r->idem[0] ||
        q->store->ops->find_idem(q->store, r->owner, r->idem, &prev) != QDC_OK) {
        if (queue_full(q, &cnt))
            return queue_full_reply(c, r, &cnt);
    }

    limit = r->fmt == MESHIO_JSON && q->cfg.max_json < q->cfg.max_body ? q->cfg.max_json
                                                                       : q->cfg.max_body;
    cl = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH);
    if (cl && strtoll(cl, NULL, 10) > limit) {
        r->too_big = 1;
        r->body_len = strtoll(cl, NULL, 10);
        return api_dispatch(c, r, "", "POST");
    }

    snprintf(tmpl, sizeof tmpl, "%s/tmp/upload-XXXXXX", q->cfg.data);
    r->fd = mkostemp(tmpl, O_CLOEXEC);
    if (r->fd < 0 && disk_full(errno))
        return storage_full(c, r, "the upload could not be stored");
    if (r->fd < 0)
        return http_problem(c, r, 500, "io", "i/o error", "cannot create an upload file",
                            NULL, NULL);
    snprintf(r->tmp, sizeof r->tmp, "%s", tmpl);
    return MHD_YES;
}

void api_body(req *r, const char *data, size_t len)
{
    qdcd *q = r->q;
    int64_t limit = r->fmt == MESHIO_JSON && q->cfg.max_json < q->cfg.max_body
                        ? q->cfg.max_json
                        : q->cfg.max_body;

    r->body_len += (int64_t)len;
    atomic_fetch_add(&q->m.upload_bytes, (long long)len);
    if (r->fd < 0 || r->too_big || r->io_err)
        return;
    if (r->body_len > limit) {
        r->too_big = 1; /* keep reading (and dropping) so the 413 can be sent */
        return;
    }
    if (r->hashing)
        sha256_update(&r->hash, data, len);
    while (len) {
        ssize_t n = write(r->fd, data, len);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            r->io_err = 1;
            return;
        }
        data += n;
        len -= (size_t)n;
    }
}

void api_req_done(req *r)
{
    if (r->fd >= 0)
        close(r->fd);
    r->fd = -1;
    if (r->tmp[0])
        unlink(r->tmp);
    r->tmp[0] = 0;
}

static const char *status_slug(qdc_status st)
{
    switch (st) {
    case QDC_EPARSE:
        return "malformed-mesh";
    case QDC_ETOOBIG:
        return "too-big";
    case QDC_EMESH:
        return "invalid-mesh";
    case QDC_EFORMAT:
        return "unsupported-media-type";
    case QDC_ENOMEM:
        return "out-of-memory";
    case QDC_EINVAL:
        return "invalid-argument";
    default:
        return "internal";
    }
}

/* A problem for a mesh the library refused, with where it went wrong. */
static enum MHD_Result mesh_problem(struct MHD_Connection *c, req *r, qdc_status st,
                                    const qdc_error *e)
{
    sbuf x = {0};
    unsigned status = (unsigned)qdc_status_http(st);
    enum MHD_Result ret;

    /* The request is at fault for any parse or validation error, whatever
     * the library's table says for unexpected codes. */
    if (status >= 500 && st != QDC_ENOMEM)
        status = 422;
    sb_printf(&x, "\"format\":\"%s\"", upload_format_name(r));
    if (e->line >= 0)
        sb_printf(&x, ",\"line\":%lld", (long long)e->line);
    if (e->col >= 0)
        sb_printf(&x, ",\"column\":%lld", (long long)e->col);
    if (e->offset >= 0)
        sb_printf(&x, ",\"offset\":%lld", (long long)e->offset);
    if (e->index >= 0)
        sb_printf(&x, ",\"index\":%lld", (long long)e->index);
    if (e->kind[0]) {
        sb_puts(&x, ",\"kind\":");
        sb_json_str(&x, e->kind);
    }
    ret = http_problem(
        c, r, status,
        st == QDC_EMESH && r->sfmt != SURFACE_AUTO ? "invalid-surface" : status_slug(st),
        st == QDC_EMESH && r->sfmt != SURFACE_AUTO ? "the surface cannot bound a volume"
                                                   : qdc_status_str(st),
        e->msg[0] ? e->msg : qdc_status_str(st), x.buf, NULL);
    sb_free(&x);
    return ret;
}

static void new_id(char out[JOB_ID_LEN + 1])
{
    unsigned char b[JOB_ID_LEN / 2];
    static const char hx[] = "0123456789abcdef";
    size_t got = 0;

    while (got < sizeof b) {
        ssize_t n = getrandom(b + got, sizeof b - got, 0);
        if (n > 0)
            got += (size_t)n;
    }
    for (size_t i = 0; i < sizeof b; i++) {
        out[2 * i] = hx[b[i] >> 4];
        out[2 * i + 1] = hx[b[i] & 15];
    }
    out[JOB_ID_LEN] = 0;
}

/* Make the upload the job's input: fsync, rename into DATA/jobs/ID, fsync dirs.
 * Shared (PostgreSQL): the database keeps it durably; here it is a cache. */
static int commit_input(req *r, const char *id, const char *format)
{
    char dir[4200], path[4300];
    int durable = !shared_on(r->q);

    job_path(r->q, id, NULL, dir, sizeof dir);
    job_path(r->q, id, job_input_name(format), path, sizeof path);
    if (dir_ensure(dir) || (durable && fsync(r->fd)) || rename(r->tmp, path)) {
        dir_remove(dir);
        return -1;
    }
    r->tmp[0] = 0;
    if (!durable) /* the cache's clock: used now, not when the upload began */
        (void)shared_use(r->q, path);
    if (durable && (fsync_parent(path) || fsync_parent(dir)))
        return -1;
    return 0;
}

/* Answer a request whose Idempotency-Key was used before: the same job when
 * the fingerprint (options + body) matches, else 422. */
static enum MHD_Result idem_replay(struct MHD_Connection *c, req *r, const job_rec *old,
                                   const char *body_hash)
{
    char loc[80], extra[80];

    if (strcmp(old->body_hash, body_hash)) {
        snprintf(extra, sizeof extra, "\"job\":\"%s\"", old->id);
        return http_problem(c, r, 422, "idempotency-key-reused",
                            "Idempotency-Key reused with a different request",
                            "this key was already used for a different body or options",
                            extra, NULL);
    }
    snprintf(loc, sizeof loc, "/v1/jobs/%s", old->id);
    const char *const h[] = {MHD_HTTP_HEADER_LOCATION, loc, "Idempotent-Replayed", "true",
                             NULL};
    return reply_job(c, r, 202, old, h);
}

/* 413 for a body over its cap: JSON meshes have their own (--max-json). */
static enum MHD_Result too_big(struct MHD_Connection *c, req *r, int json)
{
    qdcd *q = r->q;
    char d[400], extra[200];
    int64_t lim;

    json = json && q->cfg.max_json < q->cfg.max_body;
    lim = json ? q->cfg.max_json : q->cfg.max_body;
    if (json)
        snprintf(d, sizeof d,
                 "JSON mesh bodies are limited to %lld bytes; send larger meshes as "
                 "%s (proto/mesh-binary.md)",
                 (long long)lim, MEDIA_QMESH);
    else
        snprintf(d, sizeof d, "request bodies are limited to %lld bytes", (long long)lim);
    snprintf(extra, sizeof extra, "\"max_bytes\":%lld%s", (long long)lim,
             json ? ",\"use\":\"" MEDIA_QMESH "\"" : "");
    return http_problem(c, r, 413, "too-big", "request body too large", d, extra, NULL);
}

/* meshio_options.log target: notes about the upload (skipped element types),
 * one per line, kept with the job. */
static void collect_note(void *ctx, int level, const char *msg)
{
    sbuf *b = ctx;
    (void)level;
    if (b->len + strlen(msg) + 2 > sizeof((job_rec *)0)->notes)
        return; /* the first few say enough */
    sb_printf(b, "%s%s", b->len ? "\n" : "", msg);
}

/* The sizes of an upload over the server's limits: 413. */
static enum MHD_Result over_limits(struct MHD_Connection *c, req *r, int64_t nv,
                                   int64_t nt)
{
    qdcd *q = r->q;
    char d[400], extra[200];

    snprintf(d, sizeof d,
             "the %s has %lld vertices and %lld tets; this server accepts %lld and %lld "
             "at most",
             r->sfmt != SURFACE_AUTO ? "surface" : "mesh", (long long)nv, (long long)nt,
             (long long)q->cfg.max_vertices, (long long)q->cfg.max_tets);
    snprintf(extra, sizeof extra,
             "\"vertices\":%lld,\"tets\":%lld,\"max_vertices\":%lld,\"max_tets\":%lld",
             (long long)nv, (long long)nt, (long long)q->cfg.max_vertices,
             (long long)q->cfg.max_tets);
    return http_problem(c, r, 413, "too-big", "mesh exceeds server limits", d, extra,
                        NULL);
}

/* Parse and validate the upload (buf, len) into j's sizes and notes, or
 * answer with the problem (returns 1 then, *ret set). A surface is checked
 * (closed, manifold, oriented) but tetrahedralized later, by the worker. */
static int check_upload(struct MHD_Connection *c, req *r, const char *buf, size_t len,
                        job_rec *j, enum MHD_Result *ret, double *t_valid)
{
    qdcd *q = r->q;
    qdc_error e;
    qdc_status st;

    qdc_error_clear(&e);
    *t_valid = mono_now();
    if (r->sfmt != SURFACE_AUTO) {
        surface_t *sf = NULL;
        st = surface_read(buf, len, r->sfmt, &sf, &e);
        if (st == QDC_OK && sf->nv > q->cfg.max_vertices) {
            *ret = over_limits(c, r, sf->nv, 0);
            surface_free(sf);
            return 1;
        }
        *t_valid = mono_now();
        if (st == QDC_OK)
            st = surface_check(sf, &e);
        if (st == QDC_OK) {
            j->nv = sf->nv;
            j->nt = 0; /* known once TetGen ran */
            snprintf(j->notes, sizeof j->notes,
                     "surface of %d triangles: tetrahedralized with TetGen before the "
                     "optimization",
                     sf->ntri);
        }
        surface_free(sf);
        if (st != QDC_OK) {
            *ret = mesh_problem(c, r, st, &e);
            return 1;
        }
        return 0;
    }

    mesh_t *m = NULL;
    sbuf notes = {0};
    meshio_options mo = {collect_note, &notes, 0};
    st = meshio_read_ex(buf, len, r->fmt, &mo, &m, &e);
    if (st == QDC_OK && (m->nv > q->cfg.max_vertices || m->nt > q->cfg.max_tets)) {
        *ret = over_limits(c, r, m->nv, m->nt);
        mesh_free(m);
        sb_free(&notes);
        return 1;
    }
    *t_valid = mono_now();
    if (st == QDC_OK)
        st = mesh_validate(m, NULL, &e);
    if (st == QDC_OK) {
        j->nv = m->nv;
        j->nt = m->nt;
        snprintf(j->notes, sizeof j->notes, "%s",
                 notes.buf && !notes.oom ? notes.buf : "");
    }
    mesh_free(m);
    sb_free(&notes);
    if (st != QDC_OK) {
        *ret = mesh_problem(c, r, st, &e);
        return 1;
    }
    return 0;
}

/* Runs on the intake thread; the connection is suspended meanwhile, and
 * MHD_queue_response is allowed on a suspended connection. */
static enum MHD_Result process_upload(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    char d[400];
    char *buf = NULL;
    size_t len = (size_t)r->body_len;
    enum MHD_Result ret;
    job_rec j, old;
    int dup = 0, bad;
    double t_parse, t_valid;
    qdc_status st_create;

    memset(&j, 0, sizeof j);
    if (r->hashing) {
        uint8_t dig[32];
        sha256_final(&r->hash, dig);
        sha256_to_hex(dig, j.body_hash);
        if (q->store->ops->find_idem(q->store, r->owner, r->idem, &old) == QDC_OK)
            return idem_replay(c, r, &old, j.body_hash);
    }
    buf = mmap(NULL, len, PROT_READ, MAP_PRIVATE, r->fd, 0);
    if (buf == MAP_FAILED)
        return http_problem(c, r, 500, "io", "i/o error", "cannot map the upload", NULL,
                            NULL);
    if (r->sniff) {
        r->fmt = meshio_sniff(buf, len);
        if (r->fmt == MESHIO_AUTO)
            r->sfmt = surface_sniff(buf, len);
        if (r->fmt == MESHIO_AUTO && r->sfmt == SURFACE_AUTO) {
            munmap(buf, len);
            return unsupported(
                c, r,
                "the body is not a mesh or surface this server recognises; "
                "set Content-Type to one of the accepted types");
        }
        if (r->fmt == MESHIO_JSON && r->body_len > q->cfg.max_json) {
            munmap(buf, len);
            return too_big(c, r, 1);
        }
    }
    if (r->tetgen_opts && r->sfmt == SURFACE_AUTO) {
        munmap(buf, len);
        return http_problem(c, r, 400, "invalid-option", "invalid option",
                            "tetgen_quality and max_volume apply to surface uploads only",
                            NULL, NULL);
    }
    t_parse = mono_now();
    bad = check_upload(c, r, buf, len, &j, &ret, &t_valid);
    munmap(buf, len);
    if (bad)
        return ret;

    new_id(j.id);
    snprintf(j.owner, sizeof j.owner, "%s", r->owner);
    snprintf(j.idem_key, sizeof j.idem_key, "%s", r->idem);
    snprintf(j.format, sizeof j.format, "%s", upload_format_name(r));
    j.in_bytes = r->body_len;
    snprintf(j.options, sizeof j.options, "%s", r->options);
    j.created = wall_now();

    /* the intake thread commits one upload at a time, so this check is exact */
    {
        job_counts cnt;
        if (queue_full(q, &cnt))
            return queue_full_reply(c, r, &cnt);
    }
    double t_commit = mono_now();
    if (commit_input(r, j.id, j.format))
        return storage_full(c, r, "the mesh could not be stored durably");
    if (shared_on(q)) {
        job_path(q, j.id, job_input_name(j.format), d, sizeof d);
        st_create = q->store->ops->create_with_input(
            q->store, &j, job_input_name(j.format), d, &dup, &old);
    } else {
        st_create = q->store->ops->create(q->store, &j, &dup, &old);
    }
    if (st_create != QDC_OK) {
        job_path(q, j.id, NULL, d, sizeof d);
        dir_remove(d);
        return store_unavailable(c, r, "the job could not be recorded");
    }
    if (dup) { /* a concurrent request with the same key won */
        job_path(q, j.id, NULL, d, sizeof d);
        dir_remove(d);
        return idem_replay(c, r, &old, j.body_hash);
    }
    atomic_fetch_add(&q->m.submitted, 1);
    job_pool_notify(q->pool);
    if (q->cfg.verbose)
        fprintf(stderr,
                "qdcd: job %s queued (%s, %lld tets; body %.3f s after the headers, "
                "parse %.3f s, validate %.3f s, commit %.3f s)\n",
                j.id, j.format, (long long)j.nt, t_parse - r->t0, t_valid - t_parse,
                t_commit - t_valid, mono_now() - t_commit);
    char loc[80];
    snprintf(loc, sizeof loc, "/v1/jobs/%s", j.id);
    const char *const h[] = {MHD_HTTP_HEADER_LOCATION, loc, NULL};
    job_rec now;
    if (q->store->ops->get(q->store, j.id, &now) != QDC_OK)
        now = j;
    ret = reply_job(c, r, 202, &now, h);
    return ret;
}

/* A thread serving suspended requests one at a time, so the HTTP thread never
 * waits on a parse, a conversion or an fsync: the intake (parse, validate and
 * commit uploads) and the converter (results in the formats the worker did not
 * write). Each answers its request, then resumes it. */
typedef struct {
    pthread_mutex_t lock;
    pthread_cond_t cond;
    req *head, *tail;
    int stop, running;
    pthread_t th;
    enum MHD_Result (*fn)(struct MHD_Connection *c, req *r);
} offq;

static enum MHD_Result process_convert(struct MHD_Connection *c, req *r);

static offq intake = {PTHREAD_MUTEX_INITIALIZER,
                      PTHREAD_COND_INITIALIZER,
                      NULL,
                      NULL,
                      0,
                      0,
                      0,
                      process_upload};
static offq convert = {PTHREAD_MUTEX_INITIALIZER,
                       PTHREAD_COND_INITIALIZER,
                       NULL,
                       NULL,
                       0,
                       0,
                       0,
                       process_convert};

static void *offq_main(void *arg)
{
    offq *o = arg;
    pthread_mutex_lock(&o->lock);
    for (;;) {
        while (!o->head && !o->stop)
            pthread_cond_wait(&o->cond, &o->lock);
        req *r = o->head;
        if (!r)
            break; /* stopping and drained */
        o->head = r->intake_next;
        if (!o->head)
            o->tail = NULL;
        pthread_mutex_unlock(&o->lock);
        o->fn(r->conn, r);
        r->intake_done = 1;
        MHD_resume_connection(r->conn);
        pthread_mutex_lock(&o->lock);
    }
    pthread_mutex_unlock(&o->lock);
    return NULL;
}

static int offq_start(offq *o)
{
    if (pthread_create(&o->th, NULL, offq_main, o))
        return -1;
    o->running = 1;
    return 0;
}

/* Answers what is queued first. */
static void offq_stop(offq *o)
{
    if (!o->running)
        return;
    pthread_mutex_lock(&o->lock);
    o->stop = 1;
    pthread_cond_signal(&o->cond);
    pthread_mutex_unlock(&o->lock);
    pthread_join(o->th, NULL);
    o->running = 0;
}

/* Hand r to o's thread with its connection suspended (HTTP thread). */
static enum MHD_Result offq_push(offq *o, struct MHD_Connection *c, req *r)
{
    pthread_mutex_lock(&o->lock);
    if (o->stop) {
        pthread_mutex_unlock(&o->lock);
        static const char *const h[] = {MHD_HTTP_HEADER_RETRY_AFTER, "5", NULL};
        return http_problem(c, r, 503, "shutting-down", "shutting down",
                            "the server is stopping; retry later", NULL, h);
    }
    r->intake_next = NULL;
    if (o->tail)
        o->tail->intake_next = r;
    else
        o->head = r;
    o->tail = r;
    /* Suspended before the thread can see it, so its resume always follows
     * this suspend. */
    MHD_suspend_connection(c);
    pthread_cond_signal(&o->cond);
    pthread_mutex_unlock(&o->lock);
    return MHD_YES;
}

int api_start(qdcd *q)
{
    (void)q;
    if (offq_start(&intake))
        return -1;
    if (offq_start(&convert)) {
        offq_stop(&intake);
        return -1;
    }
    return 0;
}

void api_stop(void)
{
    offq_stop(&intake);
    offq_stop(&convert);
}

/* Body complete (HTTP thread): refuse what needs no parsing, hand the rest
 * to the intake thread with the connection suspended. */
static enum MHD_Result finish_upload(struct MHD_Connection *c, req *r)
{
    if (r->intake_done) /* resumed without a reply: queueing it failed */
        return MHD_NO;
    if (r->too_big)
        return too_big(c, r, r->fmt == MESHIO_JSON);
    if (r->io_err || r->fd < 0)
        return storage_full(c, r, "the upload could not be stored");
    if (r->body_len == 0)
        return http_problem(c, r, 400, "empty-body", "empty request body",
                            "POST /v1/jobs needs a mesh in the body", NULL, NULL);

    return offq_push(&intake, c, r);
}

/* ------------------------------------------------------------ result/report -- */

/* The input mesh of a job as the optimizer read it: the upload, or TetGen's
 * mesh of a surface once the worker has made it. */
static meshio_format input_source(req *r, const job_rec *j, char *path, size_t cap)
{
    int surf = job_is_surface(j->format);
    job_path(r->q, j->id, surf ? JOB_INPUT_TETS : job_input_name(j->format), path, cap);
    return surf ? MESHIO_QMESH : meshio_format_from_name(j->format);
}

/* 409 / 410 for a job without a result (or, GET /input, an input mesh) to
 * give; 0 if it has one. */
static int not_servable(struct MHD_Connection *c, req *r, const job_rec *j,
                        enum MHD_Result *ret)
{
    char d[200], extra[1200], src[4300];
    int gone = j->purged || j->expires < wall_now();

    if (r->route == R_INPUT && !(job_state_done(j->state) && gone)) {
        input_source(r, j, src, sizeof src);
        if (shared_on(r->q) && !job_is_surface(j->format))
            (void)shared_fetch(r->q, j->id, job_input_name(j->format), NULL); /* or use */
        if (access(src, R_OK) == 0)
            return 0;
        if (job_state_done(j->state)) { /* a surface TetGen could not mesh */
            snprintf(d, sizeof d, "job %s %s before its surface was tetrahedralized",
                     j->id, job_state_name(j->state));
            *ret = http_problem(c, r, 409, "no-result", "the job has no input mesh", d,
                                NULL, NULL);
            return 1;
        }
    }
    if (!job_state_done(j->state)) {
        static const char *const h[] = {MHD_HTTP_HEADER_RETRY_AFTER, "2", NULL};
        snprintf(d, sizeof d, "job %s is %s; poll /v1/jobs/%s/progress", j->id,
                 job_state_name(j->state), j->id);
        snprintf(extra, sizeof extra, "\"state\":\"%s\"", job_state_name(j->state));
        *ret =
            http_problem(c, r, 409, "not-ready", "the job has not finished", d, extra, h);
        return 1;
    }
    if (j->state != JOB_SUCCEEDED && r->route != R_INPUT) {
        snprintf(d, sizeof d, "job %s %s and has no result", j->id,
                 job_state_name(j->state));
        snprintf(extra, sizeof extra, "\"state\":\"%s\"%s%s", job_state_name(j->state),
                 j->error[0] ? ",\"error\":" : "", j->error);
        *ret =
            http_problem(c, r, 409, "no-result", "the job has no result", d, extra, NULL);
        return 1;
    }
    if (gone) {
        snprintf(d, sizeof d, "the %s of job %s expired and was deleted",
                 r->route == R_INPUT ? "input" : "result", j->id);
        snprintf(extra, sizeof extra, "\"expired\":%.3f", j->expires);
        *ret = http_problem(c, r, 410, "gone", "result expired", d, extra, NULL);
        return 1;
    }
    return 0;
}

/* The offered list for a 400/406 about the result's format. */
static void offered(sbuf *x)
{
    sb_puts(x, "\"offered\":[");
    media_list(x, 0);
    sb_puts(x, "],\"formats\":[");
    format_names(x, 0);
    sb_puts(x, "]");
}

/* The format of a result representation a GET asks for: ?format= (a name or a
 * media type), else the first entry of Accept that is offered (parameters
 * like ";encoding=binary" and ";version=2.2" pick variants; entries with q=0
 * are skipped, other q values ignored: the client's order decides), else the
 * binary. 0, or -1 with the 400/406 answered in *ret. */
static int result_format(struct MHD_Connection *c, req *r, meshio_format *out,
                         enum MHD_Result *ret)
{
    const char *f = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "format");
    const char *acc =
        MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_ACCEPT);
    meshio_format k = MESHIO_AUTO;
    sbuf x = {0};
    char d[300];

    if (f) {
        if (!strcasecmp(f, "text/plain"))
            k = MESHIO_MEDIT;
        else
            k = strchr(f, '/') ? meshio_format_from_media_type(f)
                               : meshio_format_from_name(f);
        if (offerable(k)) {
            *out = k;
            return 0;
        }
        sb_puts(&x, "\"parameter\":\"format\",");
        offered(&x);
        snprintf(d, sizeof d,
                 "'format' must name one of the offered formats, not '%.60s'", f);
        *ret = http_problem(c, r, 400, "invalid-parameter", "invalid parameter", d,
                            x.oom ? NULL : x.buf, NULL);
        sb_free(&x);
        return -1;
    }
    if (!acc || !*acc) {
        *out = MESHIO_QMESH;
        return 0;
    }
    if (!parse_accept(acc, out))
        return 0;
    offered(&x);
    snprintf(d, sizeof d,
             "no offered type matches Accept: %.150s (or name one with ?format=)", acc);
    *ret = http_problem(c, r, 406, "not-acceptable", "not acceptable", d,
                        x.oom ? NULL : x.buf, NULL);
    sb_free(&x);
    return -1;
}

/* The file of the result in format f and its SHA-256 (the strong ETag) when
 * the file exists: the worker writes the binary, JSON and Medit results and
 * their hashes are in the row; other formats are written on first request
 * (process_convert) with the hash beside them in FILE.etag, and so is the
 * input mesh (GET /input) in every format, as input-as.FORMAT. */
static void result_file(req *r, const job_rec *j, meshio_format f, char *path, size_t cap,
                        char hex[65])
{
    char name[64], side[4400];
    const char *known = NULL;

    hex[0] = 0;
    switch (r->route == R_INPUT ? MESHIO_AUTO : f) {
    case MESHIO_QMESH:
        snprintf(name, sizeof name, "result.qmesh");
        known = j->etag_qmesh;
        break;
    case MESHIO_JSON:
        snprintf(name, sizeof name, "result.json");
        known = j->etag_json;
        break;
    case MESHIO_MEDIT:
        snprintf(name, sizeof name, "result.mesh");
        known = j->etag_medit;
        break;
    default:
        snprintf(name, sizeof name, "%s.%s", r->route == R_INPUT ? "input-as" : "result",
                 meshio_format_name(f));
        break;
    }
    job_path(r->q, j->id, name, path, cap);
    if (known) {
        snprintf(hex, 65, "%s", known);
        return;
    }
    snprintf(side, sizeof side, "%s.etag", path);
    size_t len = 0;
    char *b = file_read_all(side, &len);
    if (b && len == 64 && access(path, R_OK) == 0)
        snprintf(hex, 65, "%s", b);
    free(b);
}

static enum MHD_Result serve_result(struct MHD_Connection *c, req *r, meshio_format f,
                                    const char *path, const char *hex)
{
    char etag[80];

    snprintf(etag, sizeof etag, "\"%s\"", hex);
    const char *const h[] = {MHD_HTTP_HEADER_ETAG,
                             etag,
                             MHD_HTTP_HEADER_VARY,
                             "Accept",
                             MHD_HTTP_HEADER_CACHE_CONTROL,
                             "private, max-age=3600",
                             NULL};
    if (etag_matches(MHD_lookup_connection_value(c, MHD_HEADER_KIND,
                                                 MHD_HTTP_HEADER_IF_NONE_MATCH),
                     etag))
        return http_reply(c, r, 304, NULL, "", 0, h);
    return http_reply_file(
        c, r, 200, path,
        meshio_media_type(f) ? meshio_media_type(f) : "application/octet-stream", h);
}

/* Converter thread: write the result in r->res_fmt from result.qmesh (or the
 * input from its file), hash it, serve it. One thread, so two requests never
 * write the same file. */
static enum MHD_Result process_convert(struct MHD_Connection *c, req *r)
{
    job_rec j;
    enum MHD_Result ret;
    char path[4300], src[4300], side[4400], hex[65], d[400];
    mesh_t *m = NULL;
    qdc_error e;
    qdc_status st;

    if (!load_job(c, r, &j, &ret) || not_servable(c, r, &j, &ret))
        return ret;
    result_file(r, &j, r->res_fmt, path, sizeof path, hex);
    snprintf(side, sizeof side, "%s.etag", path);
    if (shared_on(r->q) && shared_use(r->q, path) != 0) {
        /* not in this node's cache: the stored file (the worker's formats,
         * or a conversion another node stored), with the same ETag */
        char sha[65] = "";
        qdc_status fs = shared_fetch(r->q, j.id, strrchr(path, '/') + 1, sha);
        if (fs == QDC_EIO)
            return store_unavailable(c, r, "the result could not be read");
        if (fs == QDC_OK && !hex[0] && strlen(sha) == 64 &&
            file_write_atomic(side, sha, 64) == 0)
            snprintf(hex, sizeof hex, "%s", sha);
        if (fs == QDC_OK && hex[0])
            return serve_result(c, r, r->res_fmt, path, hex);
        hex[0] = 0;
        if (shared_fetch(r->q, j.id,
                         r->route == R_INPUT ? job_input_name(j.format) : "result.qmesh",
                         NULL) == QDC_EIO)
            return store_unavailable(c, r, "the result could not be read");
    }
    if (hex[0]) /* written for a request queued before this one */
        return serve_result(c, r, r->res_fmt, path, hex);
    qdc_error_clear(&e);
    meshio_format sf = MESHIO_QMESH;
    if (r->route == R_INPUT)
        sf = input_source(r, &j, src, sizeof src);
    else
        job_path(r->q, j.id, "result.qmesh", src, sizeof src);
    snprintf(side, sizeof side, "%s.etag", path);
    double t0 = mono_now();
    st = meshio_load(src, sf, &m, &e);
    if (st == QDC_OK)
        st = meshio_save(path, r->res_fmt, m, &e);
    mesh_free(m);
    if (st == QDC_OK && sha256_file_hex(path, hex))
        st = qdc_fail(&e, QDC_EIO, "cannot hash the result");
    if (st == QDC_OK && file_write_atomic(side, hex, 64))
        st = qdc_fail(&e, QDC_EIO, "cannot store the result's hash");
    if (st != QDC_OK) {
        int full = disk_full(errno) || strstr(e.msg, strerror(ENOSPC)) != NULL;
        /* Deleted or expired meanwhile: say that rather than an i/o error. */
        if (!load_job(c, r, &j, &ret) || not_servable(c, r, &j, &ret))
            return ret;
        unlink(path);
        snprintf(d, sizeof d, "the %s could not be written as %s",
                 r->route == R_INPUT ? "input" : "result",
                 meshio_format_name(r->res_fmt));
        /* the library's message names our files: it goes to the log, not out */
        if (r->q->cfg.verbose)
            fprintf(stderr, "qdcd: job %s: %s: %s\n", j.id, d, e.msg);
        if (full)
            return storage_full(c, r, d);
        return http_problem(c, r, 500, "io", "i/o error", d, NULL, NULL);
    }
    /* Deleted (or purged) while converting: the directory may have been
     * emptied before our file landed in it; remove what is left. */
    if (r->q->store->ops->get(r->q->store, j.id, &j) == QDC_EINVAL || j.purged) {
        job_path(r->q, j.id, NULL, d, sizeof d);
        dir_remove(d);
        if (!load_job(c, r, &j, &ret) || not_servable(c, r, &j, &ret))
            return ret;
    }
    if (r->q->cfg.verbose)
        fprintf(stderr, "qdcd: job %s: %s written as %s in %.3f s\n", j.id,
                r->route == R_INPUT ? "input" : "result", meshio_format_name(r->res_fmt),
                mono_now() - t0);
    /* the other nodes serve this conversion from the store (best effort:
     * converting again gives the same bytes) */
    if (shared_on(r->q))
        (void)shared_put(r->q, j.id, strrchr(path, '/') + 1, hex, NULL);
    return serve_result(c, r, r->res_fmt, path, hex);
}

static enum MHD_Result do_result(struct MHD_Connection *c, req *r)
{
    job_rec j;
    enum MHD_Result ret;
    meshio_format f;
    char path[4300], hex[65];

    if (r->intake_done) /* resumed without a reply: queueing it failed */
        return MHD_NO;
    if (!load_job(c, r, &j, &ret))
        return ret;
    if (result_format(c, r, &f, &ret))
        return ret;
    if (not_servable(c, r, &j, &ret))
        return ret;
    result_file(r, &j, f, path, sizeof path, hex);
    /* shared: a file missing from this node's cache is fetched off-thread */
    if (hex[0] && (!shared_on(r->q) || shared_use(r->q, path) == 0))
        return serve_result(c, r, f, path, hex);
    r->res_fmt = f;
    return offq_push(&convert, c, r);
}

static enum MHD_Result do_report(struct MHD_Connection *c, req *r)
{
    job_rec j;
    enum MHD_Result ret;
    char path[4300];

    if (!load_job(c, r, &j, &ret))
        return ret;
    if (not_servable(c, r, &j, &ret))
        return ret;
    job_path(r->q, j.id, "report.json", path, sizeof path);
    /* shared: from the store when this node's cache lacks it (a few kB) */
    if (shared_on(r->q) && shared_fetch(r->q, j.id, "report.json", NULL) == QDC_EIO)
        return store_unavailable(c, r, "the report could not be read");
    return http_reply_file(c, r, 200, path, "application/json", no_headers);
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
        r->close_after = 1;
        return http_problem(c, r, 400, "ambiguous-framing", "ambiguous request framing",
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
        return http_problem(c, r, 404, "not-found", "not found", d, NULL, NULL);
    }
    const route_desc *rd = route_desc_of(r->route);
    if (!route_method_ok(r->route, method)) {
        const char *const h[] = {MHD_HTTP_HEADER_ALLOW, rd->allow, NULL};
        return http_problem(c, r, 405, "method-not-allowed", "method not allowed",
                            "see the Allow header", NULL, h);
    }
    if ((rd->auth == AUTH_TOKEN || (rd->auth == AUTH_OPS && !r->q->cfg.public_metrics)) &&
        !authenticate(c, r)) {
        static const char *const h[] = {MHD_HTTP_HEADER_WWW_AUTHENTICATE,
                                        "Bearer realm=\"qdcd\"", NULL};
        return http_problem(c, r, 401, "unauthorized", "unauthorized",
                            "send Authorization: Bearer <token>", NULL, h);
    }
    if (r->route == R_JOBS && !strcmp(method, "POST"))
        return begin_upload(c, r);
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
        return strcmp(method, "POST") ? do_list(c, r) : finish_upload(c, r);
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
        return http_problem(c, r, 404, "not-found", "not found", "no such resource", NULL,
                            NULL);
    }
}

const http_handlers api_handlers = {api_begin, api_body, api_dispatch, api_req_done};
