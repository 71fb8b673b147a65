/* upload.c - POST /v1/jobs. Options, format, Idempotency-Key, the queue limit
 * and the size cap are checked at the first call (headers only), so a refused
 * body is not read. The body is streamed to a temporary file in DATA/tmp;
 * once complete, an intake thread maps it, parses and validates it with
 * libqdc (never with jansson), keeps the parsed mesh for the worker
 * (JOB_INTAKE_QMESH, when it holds all the worker needs), fsyncs and renames
 * the upload into DATA/jobs/ID and commits the row before the 202. With a PostgreSQL
 * store (shared.h) the input is stored in the database in the transaction that inserts
 * the row. The upload's state is this file's (struct upload, r->up): other requests do
 * not carry it. */
#define _GNU_SOURCE
#include "endpoints.h"
#include "handler.h"

#include "h5job.h"
#include "h5upload.h"
#include "job.h"
#include "multipart.h"
#include "offq.h"
#include "qdc.h"
#include "shared.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/mman.h>
#include <sys/random.h>
#include <unistd.h>

#define MEDIA_QMESH "application/vnd.qdc.mesh"

struct upload {
    int fd;          /* the body's temporary file in DATA/tmp, or -1 */
    char tmp[4200];  /* its path; "" once renamed or removed */
    char mtmp[4300]; /* the parsed mesh (JOB_INTAKE_QMESH) beside it, or "" */
    double keep_s;   /* seconds spent writing it */
    int64_t body_len;
    int too_big;
    int io_err;          /* errno of a failed write of the body, or 0 */
    int hashing;         /* an Idempotency-Key was given: fingerprint the request */
    sha256_ctx hash;     /* options, ?format=, body */
    meshio_format fmt;   /* a mesh upload's format, or MESHIO_AUTO */
    surface_format sfmt; /* a surface upload's format (tetrahedralized), or AUTO */
    int sniff;           /* format from the content (text/plain, octet-stream, none) */
    int tetgen_opts;     /* tetgen_quality or max_volume given: surfaces only */
    char idem[129];
    char options[1024];  /* canonical options JSON */
    char file_name[256]; /* ?name=: the uploaded file's name (its last path part) */
    char label[128];     /* ?label= */
    /* multipart/form-data: an XDMF file and its .h5 (multipart_upload) */
    int multipart;
    char boundary[MP_BOUNDARY_MAX + 1];
    char xtmp[4300], htmp[4300]; /* the two files cut from the body, or "" */
};

static enum MHD_Result process_upload(struct MHD_Connection *c, req *r);

/* The intake threads: uploads are inflated, parsed and checked side by side,
 * so a large one (or a compressed bomb, until its limit stops it) does not
 * hold up the small ones that arrive behind it; each may take up to the
 * body limit of memory while it is parsed. They are committed one at a time
 * (commit_lock), which keeps the queue limit exact. */
#define INTAKE_THREADS 4
static offq intake = OFFQ_INIT(process_upload);
static pthread_mutex_t commit_lock = PTHREAD_MUTEX_INITIALIZER;

int upload_start(void)
{
    return offq_start(&intake, INTAKE_THREADS);
}

void upload_stop(void)
{
    offq_stop(&intake);
}

typedef struct {
    opt_options o;
    double cap;
    double tq, tv; /* tetgen_quality, max_volume; -1 when not given */
    char file_name[256], label[128];
    char why[200];
    int bad;
} opt_scan;

/* ?name= (the uploaded file's name: its last path part is kept) or ?label=:
 * text of at most 255 / 127 bytes, no control characters. */
static enum MHD_Result scan_name(opt_scan *s, const char *key, const char *val)
{
    int name = !strcmp(key, "name");
    char *dst = name ? s->file_name : s->label;
    size_t cap = name ? sizeof s->file_name : sizeof s->label;
    const char *p = val;

    if (name)
        for (const char *q = val; *q; q++)
            if (*q == '/' || *q == '\\')
                p = q + 1;
    for (const char *q = p; *q; q++)
        if ((unsigned char)*q < 32 || *q == 127) {
            snprintf(s->why, sizeof s->why, "%s: a control character in the text", key);
            s->bad = 1;
            return MHD_NO;
        }
    if (strlen(p) >= cap) {
        snprintf(s->why, sizeof s->why, "%s: longer than %zu bytes", key, cap - 1);
        s->bad = 1;
        return MHD_NO;
    }
    memcpy(dst, p, strlen(p) + 1);
    return MHD_YES;
}

static enum MHD_Result scan_option(void *cls, enum MHD_ValueKind kind, const char *key,
                                   size_t key_size, const char *val, size_t val_size)
{
    opt_scan *s = cls;
    (void)kind;
    if (s->bad)
        return MHD_NO;
    (void)key_size;
    (void)val_size; /* no NUL inside: guard.c refused those */
    if (!val)
        val = "";
    if (!strcmp(key, "format"))
        return MHD_YES; /* the body's format: upload_format */
    if (!strcmp(key, "name") || !strcmp(key, "label"))
        return scan_name(s, key, val);
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
    ret = http_problem(c, r, 415, "unsupported-media-type", NULL, detail,
                       x.oom ? NULL : x.buf, NULL);
    sb_free(&x);
    return ret;
}

/* Name of the upload's format ("gmsh-bin", "stl"), "unknown" before sniffing. */
static const char *upload_format_name(const upload *u)
{
    if (u->sfmt != SURFACE_AUTO)
        return surface_format_name(u->sfmt);
    return u->fmt != MESHIO_AUTO ? meshio_format_name(u->fmt) : "unknown";
}

/* The body's format: ?format= (a name), else Content-Type; sniffed from the
 * content later when neither says (no type, octet-stream, text/plain, or
 * form-urlencoded, which curl --data-binary sends without -H). 0, or -1 when
 * the request gets a 415 (detail in why). */
static int upload_format(struct MHD_Connection *c, upload *u, char *why, size_t cap)
{
    const char *fq = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "format");
    const char *ct =
        MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_TYPE);
    char ctype[128];

    u->fmt = MESHIO_AUTO;
    u->sfmt = SURFACE_AUTO;
    int form = h5up_form(ct, fq, u->boundary, why, cap); /* an .xdmf and its .h5 */
    if (form) {
        u->multipart = form > 0;
        u->fmt = MESHIO_XDMF;
        return form > 0 ? 0 : -1;
    }
    if (fq) {
        u->fmt = strchr(fq, '/') ? meshio_format_from_media_type(fq)
                                 : meshio_format_from_name(fq);
        if (u->fmt == MESHIO_AUTO)
            u->sfmt = strchr(fq, '/') ? surface_format_from_media_type(fq)
                                      : surface_format_from_name(fq);
        if (u->fmt == MESHIO_TETGEN) {
            snprintf(why, cap,
                     "TetGen .node/.ele is two files; upload one of the "
                     "accepted formats instead");
            return -1;
        }
        if (u->fmt == MESHIO_AUTO && u->sfmt == SURFACE_AUTO) {
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
        u->sniff = 1;
        return 0;
    }
    u->fmt = meshio_format_from_media_type(ct);
    if (u->fmt == MESHIO_AUTO)
        u->sfmt = surface_format_from_media_type(ct);
    if (u->fmt == MESHIO_AUTO && u->sfmt == SURFACE_AUTO) {
        snprintf(why, cap,
                 "media type '%.100s' is not a mesh or surface type this "
                 "server reads",
                 ctype);
        return -1;
    }
    return 0;
}

/* The byte limit of an upload in format fmt: JSON meshes have their own
 * (--max-json), which applies when it is the smaller. */
static int64_t body_limit(const qdcd *q, meshio_format fmt, int *json)
{
    *json = fmt == MESHIO_JSON && q->cfg.max_json < q->cfg.max_body;
    return *json ? q->cfg.max_json : q->cfg.max_body;
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
    return http_problem(c, r, 429, "queue-full", NULL, "the queue is full; retry later",
                        extra, h);
}

/* The query's options checked against the library's table (and TetGen's two)
 * into u->options, the canonical JSON; 0, or -1 with the 400 reason in why. */
static int upload_options(struct MHD_Connection *c, qdcd *q, upload *u, char *why,
                          size_t cap)
{
    opt_scan s;
    sbuf oj = {0};

    memset(&s, 0, sizeof s);
    opt_defaults(&s.o);
    s.cap = q->cfg.job_time_limit;
    s.o.time_limit = s.cap;
    s.tq = s.tv = -1;
    MHD_get_connection_values_n(c, MHD_GET_ARGUMENT_KIND, scan_option, &s);
    if (s.bad) {
        snprintf(why, cap, "%s", s.why);
        return -1;
    }
    job_opt_json(&s.o, &oj);
    if (oj.len && (s.tq >= 0 || s.tv >= 0)) {
        oj.len--; /* the closing brace */
        if (s.tq >= 0)
            sb_printf(&oj, ",\"tetgen_quality\":%.17g", s.tq);
        if (s.tv >= 0)
            sb_printf(&oj, ",\"max_volume\":%.17g", s.tv);
        sb_puts(&oj, "}");
        u->tetgen_opts = 1;
    }
    snprintf(u->options, sizeof u->options, "%s", oj.buf && !oj.oom ? oj.buf : "{}");
    sb_free(&oj);
    memcpy(u->file_name, s.file_name, sizeof u->file_name);
    memcpy(u->label, s.label, sizeof u->label);
    return 0;
}

/* An Idempotency-Key: kept, and the request's fingerprint begun (options,
 * ?format=; the body follows). 0, or -1 when the key is not valid. */
static int upload_idem(struct MHD_Connection *c, upload *u)
{
    const char *ik = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Idempotency-Key");
    size_t n;
    int ok;

    if (!ik)
        return 0;
    n = strlen(ik);
    ok = n > 0 && n < sizeof u->idem;
    for (size_t i = 0; ok && i < n; i++)
        ok = ik[i] > 32 && ik[i] < 127;
    if (!ok)
        return -1;
    memcpy(u->idem, ik, n + 1);
    u->hashing = 1;
    sha256_init(&u->hash);
    sha256_update(&u->hash, u->options, strlen(u->options));
    if (MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "format")) {
        /* ?format= changes what the body means; a Content-Type does not count
         * (a retry may send the same bytes under another type). */
        const char *fn = upload_format_name(u);
        sha256_update(&u->hash, "\nformat=", 8);
        sha256_update(&u->hash, fn, strlen(fn));
    }
    return 0;
}

enum MHD_Result upload_begin(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    char tmpl[4200], why[200];
    job_counts cnt;
    job_rec prev;
    int64_t limit;
    int json;
    upload *u;

    r->upload = 1;
    u = r->up = calloc(1, sizeof *u);
    if (!u)
        return http_problem(c, r, 503, "out-of-memory", NULL,
                            "the upload could not be started", NULL, NULL);
    u->fd = -1;
    /* Options are checked before any byte of the body is read. */
    if (upload_options(c, q, u, why, sizeof why))
        return http_problem(c, r, 400, "invalid-option", NULL, why, NULL, NULL);
    if (upload_format(c, u, why, sizeof why))
        return unsupported(c, r, why);
    if (u->tetgen_opts && u->fmt != MESHIO_AUTO)
        return http_problem(c, r, 400, "invalid-option", NULL,
                            "tetgen_quality and max_volume apply to surface uploads only",
                            NULL, NULL);
    if (upload_idem(c, u))
        return http_problem(c, r, 400, "invalid-idempotency-key", NULL,
                            "the key must be 1 to 128 visible ASCII characters", NULL,
                            NULL);
    /* A replay of an accepted request is answered even when the queue is full.
     * Checked here so that a refused body is not uploaded, and again at commit
     * (uploads that were in flight together). */
    if ((!u->idem[0] ||
         q->store->ops->find_idem(q->store, r->owner, u->idem, &prev) != QDC_OK) &&
        queue_full(q, &cnt))
        return queue_full_reply(c, r, &cnt);

    limit = body_limit(q, u->fmt, &json);
    if (r->body_len > limit) { /* the declared Content-Length (http.c) */
        u->too_big = 1;
        u->body_len = r->body_len;
        return upload_finish(c, r);
    }
    snprintf(tmpl, sizeof tmpl, "%s/tmp/upload-XXXXXX", q->cfg.data);
    u->fd = mkostemp(tmpl, O_CLOEXEC);
    if (u->fd < 0 && disk_full(errno))
        return storage_full(c, r, "the upload could not be stored");
    if (u->fd < 0)
        return http_problem(c, r, 500, "io", NULL, "cannot create an upload file", NULL,
                            NULL);
    snprintf(u->tmp, sizeof u->tmp, "%s", tmpl);
    return MHD_YES;
}

void upload_body(req *r, const char *data, size_t len)
{
    qdcd *q = r->q;
    upload *u = r->up;
    int json;
    int64_t limit = body_limit(q, u->fmt, &json);

    u->body_len += (int64_t)len;
    if (u->fd < 0 || u->too_big || u->io_err)
        return;
    if (u->body_len > limit) {
        u->too_big = 1; /* keep reading (and dropping) so the 413 can be sent */
        return;
    }
    if (u->hashing)
        sha256_update(&u->hash, data, len);
    while (len) {
        ssize_t n = write(u->fd, data, len);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            u->io_err = n < 0 ? errno : EIO;
            return;
        }
        data += n;
        len -= (size_t)n;
    }
}

void upload_done(req *r)
{
    upload *u = r->up;

    if (!u)
        return;
    if (u->fd >= 0)
        close(u->fd);
    if (u->tmp[0])
        unlink(u->tmp);
    if (u->mtmp[0])
        unlink(u->mtmp);
    if (u->xtmp[0])
        unlink(u->xtmp);
    if (u->htmp[0])
        unlink(u->htmp);
    free(u);
    r->up = NULL;
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
    upload *u = r->up;
    sbuf x = {0};
    unsigned status = (unsigned)qdc_status_http(st);
    enum MHD_Result ret;

    /* The request is at fault for any parse or validation error, whatever
     * the library's table says for unexpected codes. */
    if (status >= 500 && st != QDC_ENOMEM)
        status = 422;
    sb_printf(&x, "\"format\":\"%s\"", upload_format_name(u));
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
        st == QDC_EMESH && u->sfmt != SURFACE_AUTO ? "invalid-surface" : status_slug(st),
        st == QDC_EMESH && u->sfmt != SURFACE_AUTO ? "the surface cannot bound a volume"
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
 * Shared (PostgreSQL): the database keeps it durably; here it is a cache.
 * 0, or the errno of what failed (the job's directory is then removed). */
static int commit_input(req *r, const char *id, const char *format)
{
    upload *u = r->up;
    char dir[4200], path[4300];
    int durable = !shared_on(r->q);

    job_path(r->q, id, NULL, dir, sizeof dir);
    job_path(r->q, id, job_input_name(format), path, sizeof path);
    if (u->multipart) {
        char h5[4300];
        job_path(r->q, id, JOB_INPUT_H5, h5, sizeof h5);
        return h5up_commit(u->xtmp, u->htmp, dir, path, h5);
    }
    if (dir_ensure(dir) || (durable && fsync(u->fd)) || rename(u->tmp, path) ||
        (u->tmp[0] = 0, durable && (fsync_parent(path) || fsync_parent(dir)))) {
        int e = errno ? errno : EIO;
        dir_remove(dir);
        return e;
    }
    if (!durable) /* the cache's clock: used now, not when the upload began */
        (void)shared_use(r->q, path);
    /* The parsed mesh for the worker: an optimization, not the job's record
     * (the worker parses the input without it), so it is not fsynced into the
     * directory; meshio_save synced its content before naming it. */
    if (u->mtmp[0]) {
        job_path(r->q, id, JOB_INTAKE_QMESH, path, sizeof path);
        if (rename(u->mtmp, path))
            unlink(u->mtmp);
        u->mtmp[0] = 0;
    }
    return 0;
}

/* The upload could not be stored (errno e): 507 when the disk is full, a
 * passing condition; else 500. */
static enum MHD_Result store_failed(struct MHD_Connection *c, req *r, int e,
                                    const char *what)
{
    if (disk_full(e))
        return storage_full(c, r, what);
    return http_problem(c, r, 500, "io", NULL, what, NULL, NULL);
}

/* Answer a request whose Idempotency-Key was used before: the same job when
 * the fingerprint (options + body) matches, else 422. */
static enum MHD_Result idem_replay(struct MHD_Connection *c, req *r, const job_rec *old,
                                   const char *body_hash)
{
    char loc[80], extra[80];

    if (strcmp(old->body_hash, body_hash)) {
        snprintf(extra, sizeof extra, "\"job\":\"%s\"", old->id);
        return http_problem(c, r, 422, "idempotency-key-reused", NULL,
                            "this key was already used for a different body or options",
                            extra, NULL);
    }
    snprintf(loc, sizeof loc, "/v1/jobs/%s", old->id);
    const char *const h[] = {MHD_HTTP_HEADER_LOCATION, loc, "Idempotent-Replayed", "true",
                             NULL};
    return reply_job(c, r, 202, old, h);
}

/* 413 for a body over its cap, as sent or as it inflates (gz: a gzip body;
 * ratio: stopped by --max-ratio, not the cap). The problem names the limit
 * ("limit": the option's name). */
static enum MHD_Result too_big(struct MHD_Connection *c, req *r, meshio_format fmt,
                               int gz, int ratio)
{
    qdcd *q = r->q;
    char d[400], extra[300];
    int json;
    int64_t lim = body_limit(q, fmt, &json);
    const char *name = ratio ? "max-ratio" : json ? "max-json" : "max-body";

    if (ratio)
        snprintf(d, sizeof d,
                 "the gzip body inflates to more than %d times its %lld bytes "
                 "(--max-ratio); send it uncompressed",
                 q->cfg.max_ratio, (long long)r->up->body_len);
    else if (json)
        snprintf(d, sizeof d,
                 "JSON mesh bodies are limited to %lld bytes%s; send larger meshes as "
                 "%s (proto/mesh-binary.md)",
                 (long long)lim, gz ? " once inflated" : "", MEDIA_QMESH);
    else
        snprintf(d, sizeof d, "request bodies are limited to %lld bytes%s",
                 (long long)lim, gz ? " once inflated" : "");
    snprintf(extra, sizeof extra, "\"limit\":\"%s\",\"max_bytes\":%lld%s", name,
             (long long)lim, json ? ",\"use\":\"" MEDIA_QMESH "\"" : "");
    if (ratio)
        snprintf(extra + strlen(extra), sizeof extra - strlen(extra), ",\"max_ratio\":%d",
                 q->cfg.max_ratio);
    return http_problem(c, r, 413, "too-big", NULL, d, extra, NULL);
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
    upload *u = r->up;
    qdcd *q = r->q;
    char d[400], extra[200];

    snprintf(d, sizeof d,
             "the %s has %lld vertices and %lld tets; this server accepts %lld and %lld "
             "at most",
             u->sfmt != SURFACE_AUTO ? "surface" : "mesh", (long long)nv, (long long)nt,
             (long long)q->cfg.max_vertices, (long long)q->cfg.max_tets);
    snprintf(extra, sizeof extra,
             "\"vertices\":%lld,\"tets\":%lld,\"max_vertices\":%lld,\"max_tets\":%lld",
             (long long)nv, (long long)nt, (long long)q->cfg.max_vertices,
             (long long)q->cfg.max_tets);
    return http_problem(c, r, 413, "too-big", "mesh exceeds server limits", d, extra,
                        NULL);
}

/* The validated mesh kept for the worker as the binary format beside the
 * upload's temporary file (commit_input moves it into the job's directory),
 * when it holds all the worker uses of the input (job_intake_keeps). A
 * failure only costs the worker a parse. */
static void keep_mesh(req *r, const mesh_t *m)
{
    upload *u = r->up;
    qdc_error e;

    double t0 = mono_now();

    if (!job_intake_keeps(m, u->fmt) || job_parses_upload(u->fmt, u->options))
        return;
    snprintf(u->mtmp, sizeof u->mtmp, "%s.qmesh", u->tmp);
    qdc_error_clear(&e);
    if (meshio_save(u->mtmp, MESHIO_QMESH, m, &e) != QDC_OK) {
        if (r->q->cfg.verbose)
            fprintf(stderr, "qdcd: the parsed upload was not kept: %s\n", e.msg);
        unlink(u->mtmp);
        u->mtmp[0] = 0;
    }
    u->keep_s = mono_now() - t0;
}

/* Parse and validate the upload (buf, len) into j's sizes and notes, or
 * answer with the problem (returns 1 then, *ret set). A surface is checked
 * (closed, manifold, oriented) but tetrahedralized later, by the worker. */
static int check_upload(struct MHD_Connection *c, req *r, const char *buf, size_t len,
                        job_rec *j, enum MHD_Result *ret, double *t_valid)
{
    upload *u = r->up;
    qdcd *q = r->q;
    qdc_error e;
    qdc_status st;

    qdc_error_clear(&e);
    *t_valid = mono_now();
    if (u->sfmt != SURFACE_AUTO) {
        surface_t *sf = NULL;
        st = surface_read(buf, len, u->sfmt, &sf, &e);
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

    /* HDF5 is read by the worker's qdc-h5 child (h5job.h), never here */
    if (h5up_check(buf, len, u->fmt, j, &st, &e)) {
        if (st != QDC_OK)
            *ret = mesh_problem(c, r, st, &e);
        return st != QDC_OK;
    }
    mesh_t *m = NULL;
    sbuf notes = {0};
    meshio_options mo = {.log = collect_note, .log_ctx = &notes};
    /* zlib arrays inside a VTU body: no more than a gzip body may inflate to */
    mo.max_bytes = gz_budget((size_t)u->body_len, (size_t)q->cfg.max_body,
                             (unsigned)q->cfg.max_ratio);
    st = meshio_read_ex(buf, len, u->fmt, &mo, &m, &e);
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
        keep_mesh(r, m);
    }
    mesh_free(m);
    sb_free(&notes);
    if (st != QDC_OK) {
        *ret = mesh_problem(c, r, st, &e);
        return 1;
    }
    return 0;
}

/* A gzip body (any mesh format may come compressed) inflated into *plain
 * (qdc_free), stopped as soon as it passes the limit of its format (sniffed
 * from its first bytes when nothing named it) or --max-ratio times its size:
 * the limits apply to what is parsed, not to what was sent. 0, or 1 with
 * the answer (413, 400) in *ret. */
static int inflate_upload(struct MHD_Connection *c, req *r, const char *buf, size_t len,
                          char **plain, size_t *plen, enum MHD_Result *ret)
{
    upload *u = r->up;
    qdcd *q = r->q;
    char head[4096];
    size_t hn = gz_head(buf, len, head, sizeof head);
    meshio_format f = u->sniff ? meshio_sniff(head, hn) : u->fmt;
    int json;
    int64_t lim = body_limit(q, f, &json);
    size_t budget = gz_budget(len, (size_t)lim, (unsigned)q->cfg.max_ratio);
    qdc_error e;
    qdc_status st;

    qdc_error_clear(&e);
    st = gz_inflate_max(buf, len, budget, plain, plen, &e);
    if (st == QDC_OK && gz_is_gzip(*plain, *plen))
        st = qdc_fail(&e, QDC_EPARSE, "gzip: compressed twice");
    if (st == QDC_ETOOBIG)
        *ret = too_big(c, r, f, 1, budget < (size_t)lim);
    else if (st != QDC_OK)
        *ret = mesh_problem(c, r, st, &e);
    if (st != QDC_OK) {
        qdc_free(*plain);
        *plain = NULL;
        return 1;
    }
    return 0;
}

/* 1 if the table gives f a file name for uploads (TetGen and MED have none). */
static int job_uploadable(meshio_format f)
{
    meshio_format_info fi;

    return meshio_format_info_of(f, &fi) && fi.input;
}

/* A multipart/form-data upload (buf[0..len), the body as sent): an XDMF
 * file and its .h5 file (h5upload.h), written beside the body (u->xtmp,
 * u->htmp), which commit_input moves into the job's directory. 0, or 1 with
 * the answer (400) in *ret. */
static int multipart_upload(struct MHD_Connection *c, req *r, const char *buf, size_t len,
                            job_rec *j, enum MHD_Result *ret)
{
    upload *u = r->up;
    char why[400], extra[200];
    qdc_error e;
    int n = 0;

    qdc_error_clear(&e);
    qdc_status st = h5up_multipart(buf, len, u->boundary, u->tmp, u->xtmp, u->htmp,
                                   sizeof u->xtmp, j, why, sizeof why, &n, &e);
    if (why[0]) {
        snprintf(extra, sizeof extra, "\"format\":\"xdmf\",\"parts\":%d", n);
        *ret = http_problem(c, r, 400, "malformed-mesh", NULL, why, extra, NULL);
        return 1;
    }
    if (st == QDC_EIO) {
        *ret = store_failed(c, r, errno, "the upload could not be stored");
        return 1;
    }
    if (st != QDC_OK) {
        *ret = mesh_problem(c, r, st, &e);
        return 1;
    }
    return 0;
}

/* Map the body, inflate it if it is gzip, settle its format (sniffed when
 * nothing named it), parse and validate it (check_upload): 0, or 1 with the
 * answer in *ret. */
static int inspect_upload(struct MHD_Connection *c, req *r, job_rec *j,
                          enum MHD_Result *ret, double *t_parse, double *t_valid)
{
    upload *u = r->up;
    size_t mlen = (size_t)u->body_len, len = mlen;
    char *map = mmap(NULL, mlen, PROT_READ, MAP_PRIVATE, u->fd, 0), *plain = NULL;
    const char *buf = map;
    int bad = 1;

    if (map == MAP_FAILED) {
        *ret = http_problem(c, r, 500, "io", NULL, "cannot map the upload", NULL, NULL);
        return 1;
    }
    if (u->multipart) {
        *t_parse = *t_valid = mono_now();
        bad = multipart_upload(c, r, map, mlen, j, ret);
        munmap(map, mlen);
        return bad;
    }
    if (gz_is_gzip(map, mlen)) {
        if (inflate_upload(c, r, map, mlen, &plain, &len, ret)) {
            munmap(map, mlen);
            return 1;
        }
        buf = plain;
    }
    if (u->sniff) {
        u->fmt = meshio_sniff(buf, len);
        if (u->fmt == MESHIO_AUTO)
            u->sfmt = surface_sniff(buf, len);
    } else if (u->fmt != MESHIO_AUTO) {
        /* a Gmsh or VTK body named by its family ("model/vnd.gmsh" for a
         * binary MSH 4.1 or 2.2 file, or MSH 4.0) is recorded as the variant
         * its header says, so that a result asked for in it is the upload
         * written back (the readers take every variant; the writers write
         * the one named) */
        meshio_format v = meshio_sniff(buf, len);
        if (v != MESHIO_AUTO && meshio_format_variant(u->fmt, v) == v)
            u->fmt = v;
    }
    if (u->fmt == MESHIO_AUTO && u->sfmt == SURFACE_AUTO)
        *ret = unsupported(c, r,
                           "the body is not a mesh or surface this server recognises; "
                           "set Content-Type to one of the accepted types");
    else if (u->fmt != MESHIO_AUTO && !job_uploadable(u->fmt))
        *ret = unsupported(c, r, "this format is not taken as an upload");
    else if (plain && u->fmt == MESHIO_MED)
        /* the worker's qdc-h5 child reads the stored upload as it is */
        *ret = unsupported(c, r, "MED is read uncompressed; send it without gzip");
    else if (u->fmt == MESHIO_JSON && (int64_t)len > r->q->cfg.max_json)
        *ret = too_big(c, r, MESHIO_JSON, plain != NULL, 0);
    else if (plain && u->sfmt != SURFACE_AUTO)
        /* the worker hands the stored upload to `qdc tetra`, which reads
         * surfaces uncompressed */
        *ret = unsupported(c, r, "surfaces are read uncompressed; send it without gzip");
    else if (u->tetgen_opts && u->sfmt == SURFACE_AUTO)
        *ret = http_problem(c, r, 400, "invalid-option", NULL,
                            "tetgen_quality and max_volume apply to surface uploads only",
                            NULL, NULL);
    else
        bad = 0;
    if (!bad) {
        *t_parse = mono_now();
        bad = check_upload(c, r, buf, len, j, ret, t_valid);
    }
    qdc_free(plain);
    munmap(map, mlen);
    return bad;
}

/* The job recorded: the queue checked again (exactly: the intake threads
 * commit one upload at a time), the input committed, the row inserted
 * (with the input, in a shared store). 0, or 1 with the answer in *ret:
 * 429, 507, 503, or the replay of a concurrent request with the same key. */
static int create_job(struct MHD_Connection *c, req *r, job_rec *j, enum MHD_Result *ret)
{
    qdcd *q = r->q;
    char d[400];
    job_rec old;
    job_counts cnt;
    int dup = 0;
    qdc_status st;

    if (queue_full(q, &cnt)) {
        *ret = queue_full_reply(c, r, &cnt);
        return 1;
    }
    int e = commit_input(r, j->id, j->format);
    if (e) {
        *ret = store_failed(c, r, e, "the mesh could not be stored durably");
        return 1;
    }
    if (shared_on(q)) { /* an XDMF file's .h5 too, in the same transaction */
        char h5[4300];
        job_path(q, j->id, job_input_name(j->format), d, sizeof d);
        job_path(q, j->id, JOB_INPUT_H5, h5, sizeof h5);
        st = q->store->ops->create_with_input(q->store, j, job_input_name(j->format), d,
                                              j->input_h5 ? JOB_INPUT_H5 : NULL, h5, &dup,
                                              &old);
    } else {
        st = q->store->ops->create(q->store, j, &dup, &old);
    }
    if (st != QDC_OK || dup) {
        job_path(q, j->id, NULL, d, sizeof d);
        dir_remove(d);
        /* dup: a concurrent request with the same key won */
        *ret = st != QDC_OK ? store_unavailable(c, r, "the job could not be recorded")
                            : idem_replay(c, r, &old, j->body_hash);
        return 1;
    }
    return 0;
}

/* Runs on an intake thread; the connection is suspended meanwhile, and
 * MHD_queue_response is allowed on a suspended connection. */
static enum MHD_Result process_upload(struct MHD_Connection *c, req *r)
{
    upload *u = r->up;
    qdcd *q = r->q;
    enum MHD_Result ret = MHD_NO;
    job_rec j, old;
    double t_parse = 0, t_valid = 0, t_commit;

    memset(&j, 0, sizeof j);
    if (u->hashing) {
        uint8_t dig[32];
        sha256_final(&u->hash, dig);
        sha256_to_hex(dig, j.body_hash);
        if (q->store->ops->find_idem(q->store, r->owner, u->idem, &old) == QDC_OK)
            return idem_replay(c, r, &old, j.body_hash);
    }
    if (inspect_upload(c, r, &j, &ret, &t_parse, &t_valid))
        return ret;
    new_id(j.id);
    snprintf(j.owner, sizeof j.owner, "%s", r->owner);
    snprintf(j.idem_key, sizeof j.idem_key, "%s", u->idem);
    snprintf(j.format, sizeof j.format, "%s", upload_format_name(u));
    j.in_bytes = u->body_len;
    snprintf(j.options, sizeof j.options, "%s", u->options);
    memcpy(j.file_name, u->file_name, sizeof j.file_name);
    memcpy(j.label, u->label, sizeof j.label);
    j.created = wall_now();
    t_commit = mono_now();
    pthread_mutex_lock(&commit_lock);
    int refused = create_job(c, r, &j, &ret);
    pthread_mutex_unlock(&commit_lock);
    if (refused)
        return ret;
    atomic_fetch_add(&q->m.submitted, 1);
    job_pool_notify(q->pool);
    if (q->cfg.verbose)
        fprintf(stderr,
                "qdcd: job %s queued (%s, %lld tets; body %.3f s after the headers, "
                "parse %.3f s, validate %.3f s, keep %.3f s, commit %.3f s)\n",
                j.id, j.format, (long long)j.nt, t_parse - r->t0, t_valid - t_parse,
                t_commit - t_valid - u->keep_s, u->keep_s, mono_now() - t_commit);
    char loc[80];
    snprintf(loc, sizeof loc, "/v1/jobs/%s", j.id);
    const char *const h[] = {MHD_HTTP_HEADER_LOCATION, loc, NULL};
    job_rec now;
    if (q->store->ops->get(q->store, j.id, &now) != QDC_OK)
        now = j;
    return reply_job(c, r, 202, &now, h);
}

/* Body complete (HTTP thread): refuse what needs no parsing, hand the rest
 * to an intake thread with the connection suspended. */
enum MHD_Result upload_finish(struct MHD_Connection *c, req *r)
{
    upload *u = r->up;

    if (r->off_done || !u) /* resumed without a reply: queueing it failed */
        return MHD_NO;
    if (u->too_big)
        return too_big(c, r, u->fmt, 0, 0);
    if (u->io_err || u->fd < 0)
        return store_failed(c, r, u->fd < 0 ? ENOSPC : u->io_err,
                            "the upload could not be stored");
    if (u->body_len == 0)
        return http_problem(c, r, 400, "empty-body", NULL,
                            "POST /v1/jobs needs a mesh in the body", NULL, NULL);

    return offq_push(&intake, c, r);
}
