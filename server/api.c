/* api.c - the endpoints. Routing happens at the first call (headers only), so
 * a request that is refused (401, 404, 413, 415, 429) is answered before its
 * body is read. Mesh bodies are streamed to a temporary file in DATA/tmp and
 * parsed by libqdc (never by jansson) once complete; the job row is committed
 * and the input file fsynced and renamed into DATA/jobs/ID before the 202. */
#define _GNU_SOURCE
#include "api.h"

#include "job.h"
#include "mesh.h"
#include "meshio.h"

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

enum {
    R_NONE = 0,
    R_JOBS,
    R_JOB,
    R_PROGRESS,
    R_EVENTS,
    R_RESULT,
    R_REPORT,
    R_CANCEL,
    R_LIVEZ,
    R_READYZ,
    R_METRICS,
};

#define MEDIA_QMESH "application/vnd.qdc.mesh"
#define SSE_KEEPALIVE 15.0

static const char *const no_headers[] = {NULL};

/* ------------------------------------------------------------------ routing -- */

static int is_job_id(const char *s, size_t n)
{
    if (n != JOB_ID_LEN)
        return 0;
    for (size_t i = 0; i < n; i++)
        if (!isxdigit((unsigned char)s[i]) || isupper((unsigned char)s[i]))
            return 0;
    return 1;
}

/* Route of url; id copied for job routes. -1: a job route with an id that
 * cannot exist (answered 404 like an unknown id). */
static int route_of(const char *url, char *id)
{
    static const struct {
        const char *path;
        int route;
    } fixed[] = {{"/livez", R_LIVEZ},
                 {"/readyz", R_READYZ},
                 {"/metrics", R_METRICS},
                 {"/v1/jobs", R_JOBS},
                 {"/v1/jobs/", R_JOBS}};
    static const struct {
        const char *suffix;
        int route;
    } sub[] = {{"", R_JOB},           {"/progress", R_PROGRESS}, {"/events", R_EVENTS},
               {"/result", R_RESULT}, {"/report", R_REPORT},     {":cancel", R_CANCEL}};

    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        if (!strcmp(url, fixed[i].path))
            return fixed[i].route;
    if (strncmp(url, "/v1/jobs/", 9))
        return R_NONE;
    const char *p = url + 9;
    size_t n = strcspn(p, "/:");
    for (size_t i = 0; i < sizeof sub / sizeof sub[0]; i++) {
        if (!strcmp(p + n, sub[i].suffix)) {
            if (!is_job_id(p, n))
                return -1;
            memcpy(id, p, n);
            id[n] = 0;
            return sub[i].route;
        }
    }
    return R_NONE;
}

static const char *allowed(int route)
{
    switch (route) {
    case R_JOBS:
        return "GET, POST";
    case R_JOB:
        return "GET, DELETE";
    case R_CANCEL:
        return "POST";
    default:
        return "GET";
    }
}

static int method_ok(int route, const char *m)
{
    const char *a = allowed(route);
    size_t n = strlen(m);
    for (const char *p = a; (p = strstr(p, m)); p += n)
        if ((p == a || p[-1] == ' ') && (p[n] == 0 || p[n] == ','))
            return 1;
    return !strcmp(m, "HEAD") && strstr(a, "GET");
}

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
static int load_job(struct MHD_Connection *c, req *r, job_rec *j, enum MHD_Result *ret)
{
    qdc_status st = r->q->store->ops->get(r->q->store, r->id, j);
    if (st == QDC_OK && !strcmp(j->owner, r->owner))
        return 1;
    if (st == QDC_OK || st == QDC_EINVAL) {
        char d[128];
        snprintf(d, sizeof d, "there is no job '%s'", r->id);
        *ret = http_problem(c, r, 404, "not-found", "no such job", d, NULL, NULL);
    } else {
        *ret = http_problem(c, r, 500, "store", "job store error",
                            "the job store could not be read", NULL, NULL);
    }
    return 0;
}

/* ------------------------------------------------------------------ job JSON -- */

static void job_json(req *r, const job_rec *j, sbuf *b)
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
        b, ",\"mesh\":{\"format\":\"%s\",\"vertices\":%lld,\"tets\":%lld,\"bytes\":%lld}",
        j->format, (long long)j->nv, (long long)j->nt, (long long)j->in_bytes);
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

static enum MHD_Result reply_job(struct MHD_Connection *c, req *r, unsigned status,
                                 const job_rec *j, const char *const *headers)
{
    sbuf b = {0};
    job_json(r, j, &b);
    sb_puts(&b, "\n");
    enum MHD_Result ret = http_reply_json(c, r, status, &b, headers);
    sb_free(&b);
    return ret;
}

/* ------------------------------------------------------------------- upload -- */

typedef struct {
    opt_options o;
    double cap;
    char why[200];
    int bad;
} opt_scan;

static enum MHD_Result scan_option(void *cls, enum MHD_ValueKind kind, const char *key,
                                   const char *val)
{
    opt_scan *s = cls;
    (void)kind;
    if (s->bad)
        return MHD_NO;
    if (job_opt_set(&s->o, key, val ? val : "", s->cap, s->why, sizeof s->why))
        s->bad = 1;
    return s->bad ? MHD_NO : MHD_YES;
}

static enum MHD_Result begin_upload(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    const char *ct, *cl, *ik;
    char ctype[128], tmpl[4200];
    opt_scan s;
    job_counts cnt;
    int64_t limit;

    r->upload = 1;
    /* Options are checked before any byte of the body is read. */
    memset(&s, 0, sizeof s);
    opt_defaults(&s.o);
    s.cap = q->cfg.job_time_limit;
    s.o.time_limit = s.cap;
    MHD_get_connection_values(c, MHD_GET_ARGUMENT_KIND, scan_option, &s);
    if (s.bad)
        return http_problem(c, r, 400, "invalid-option", "invalid option", s.why, NULL,
                            NULL);
    sbuf oj = {0};
    job_opt_json(&s.o, &oj);
    snprintf(r->options, sizeof r->options, "%s", oj.buf ? oj.buf : "{}");
    sb_free(&oj);

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
    }

    /* A replay of an accepted request is answered even when the queue is full. */
    job_rec prev;
    if (!r->idem[0] ||
        q->store->ops->find_idem(q->store, r->owner, r->idem, &prev) != QDC_OK) {
        if (q->store->ops->counts(q->store, &cnt) == QDC_OK &&
            cnt.by_state[JOB_QUEUED] >= q->cfg.max_queued) {
            static const char *const h[] = {MHD_HTTP_HEADER_RETRY_AFTER, "5", NULL};
            char extra[96];
            snprintf(extra, sizeof extra, "\"queued\":%lld,\"max_queued\":%d",
                     (long long)cnt.by_state[JOB_QUEUED], q->cfg.max_queued);
            return http_problem(c, r, 429, "queue-full", "too many queued jobs",
                                "the queue is full; retry later", extra, h);
        }
    }

    ct = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_TYPE);
    snprintf(ctype, sizeof ctype, "%s", ct ? ct : "");
    ctype[strcspn(ctype, "; \t")] = 0;
    if (!strcasecmp(ctype, MEDIA_QMESH)) {
        r->fmt = MESHIO_QMESH;
    } else if (!strcasecmp(ctype, "application/json")) {
        r->fmt = MESHIO_JSON;
    } else if (!strcasecmp(ctype, "model/x-medit")) {
        r->fmt = MESHIO_MEDIT;
    } else if (!ctype[0] || !strcasecmp(ctype, "text/plain") ||
               !strcasecmp(ctype, "application/octet-stream") ||
               !strcasecmp(ctype, "application/x-www-form-urlencoded")) {
        /* curl --data-binary without -H sends form-urlencoded: sniff it too. */
        r->fmt = MESHIO_AUTO;
        r->sniff = 1;
    } else {
        char d[256];
        snprintf(d, sizeof d, "media type '%.100s' is not a mesh type this server reads",
                 ctype);
        return http_problem(c, r, 415, "unsupported-media-type", "unsupported media type",
                            d,
                            "\"accepted\":[\"" MEDIA_QMESH "\",\"application/json\","
                            "\"model/x-medit\",\"text/plain\"]",
                            NULL);
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
    sb_printf(&x, "\"format\":\"%s\"",
              meshio_format_name(r->fmt) ? meshio_format_name(r->fmt) : "unknown");
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
    ret = http_problem(c, r, status, status_slug(st), qdc_status_str(st),
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

/* Make the upload the job's input: fsync, rename into DATA/jobs/ID, fsync dirs. */
static int commit_input(req *r, const char *id, const char *format)
{
    char dir[4200], path[4300];

    job_path(r->q, id, NULL, dir, sizeof dir);
    job_path(r->q, id, job_input_name(format), path, sizeof path);
    if (dir_ensure(dir) || fsync(r->fd) || rename(r->tmp, path)) {
        dir_remove(dir);
        return -1;
    }
    r->tmp[0] = 0;
    if (fsync_parent(path) || fsync_parent(dir))
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

/* Runs on the intake thread; the connection is suspended meanwhile, and
 * MHD_queue_response is allowed on a suspended connection. */
static enum MHD_Result process_upload(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    char d[400], extra[200];
    char *buf = NULL;
    mesh_t *m = NULL;
    mesh_check info;
    qdc_error e;
    qdc_status st;
    enum MHD_Result ret;
    job_rec j, old;
    int dup = 0;

    qdc_error_clear(&e);
    memset(&j, 0, sizeof j);
    if (r->hashing) {
        uint8_t dig[32];
        sha256_final(&r->hash, dig);
        sha256_to_hex(dig, j.body_hash);
        if (q->store->ops->find_idem(q->store, r->owner, r->idem, &old) == QDC_OK)
            return idem_replay(c, r, &old, j.body_hash);
    }
    buf = mmap(NULL, (size_t)r->body_len, PROT_READ, MAP_PRIVATE, r->fd, 0);
    if (buf == MAP_FAILED)
        return http_problem(c, r, 500, "io", "i/o error", "cannot map the upload", NULL,
                            NULL);
    if (r->sniff) {
        r->fmt = meshio_sniff(buf, (size_t)r->body_len);
        if (r->fmt == MESHIO_AUTO) {
            munmap(buf, (size_t)r->body_len);
            return http_problem(
                c, r, 415, "unsupported-media-type", "unsupported media type",
                "the body is not a mesh this server recognises; set "
                "Content-Type to " MEDIA_QMESH ", application/json or model/x-medit",
                NULL, NULL);
        }
    }
    double t_parse = mono_now();
    st = meshio_read(buf, (size_t)r->body_len, r->fmt, &m, &e);
    munmap(buf, (size_t)r->body_len);
    if (st != QDC_OK) {
        return mesh_problem(c, r, st, &e);
    }
    if (m->nv > q->cfg.max_vertices || m->nt > q->cfg.max_tets) {
        snprintf(d, sizeof d,
                 "the mesh has %d vertices and %d tets; this server accepts %lld "
                 "and %lld at most",
                 m->nv, m->nt, (long long)q->cfg.max_vertices,
                 (long long)q->cfg.max_tets);
        snprintf(extra, sizeof extra,
                 "\"vertices\":%d,\"tets\":%d,\"max_vertices\":%lld,"
                 "\"max_tets\":%lld",
                 m->nv, m->nt, (long long)q->cfg.max_vertices,
                 (long long)q->cfg.max_tets);
        mesh_free(m);
        return http_problem(c, r, 413, "too-big", "mesh exceeds server limits", d, extra,
                            NULL);
    }
    double t_valid = mono_now();
    st = mesh_validate(m, &info, &e);
    if (st != QDC_OK) {
        mesh_free(m);
        return mesh_problem(c, r, st, &e);
    }

    new_id(j.id);
    snprintf(j.owner, sizeof j.owner, "%s", r->owner);
    snprintf(j.idem_key, sizeof j.idem_key, "%s", r->idem);
    snprintf(j.format, sizeof j.format, "%s", meshio_format_name(r->fmt));
    j.nv = m->nv;
    j.nt = m->nt;
    j.in_bytes = r->body_len;
    snprintf(j.options, sizeof j.options, "%s", r->options);
    j.created = wall_now();
    mesh_free(m);

    double t_commit = mono_now();
    if (commit_input(r, j.id, j.format))
        return http_problem(c, r, 507, "io", "insufficient storage",
                            "the mesh could not be stored durably", NULL, NULL);
    if (q->store->ops->create(q->store, &j, &dup, &old) != QDC_OK) {
        job_path(q, j.id, NULL, d, sizeof d);
        dir_remove(d);
        return http_problem(c, r, 500, "store", "job store error",
                            "the job could not be recorded", NULL, NULL);
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

static struct {
    pthread_mutex_t lock;
    pthread_cond_t cond;
    req *head, *tail;
    int stop, running;
    pthread_t th;
} intake = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, NULL, NULL, 0, 0, 0};

static void *intake_main(void *arg)
{
    (void)arg;
    pthread_mutex_lock(&intake.lock);
    for (;;) {
        while (!intake.head && !intake.stop)
            pthread_cond_wait(&intake.cond, &intake.lock);
        req *r = intake.head;
        if (!r)
            break; /* stopping and drained */
        intake.head = r->intake_next;
        if (!intake.head)
            intake.tail = NULL;
        pthread_mutex_unlock(&intake.lock);
        process_upload(r->conn, r);
        r->intake_done = 1;
        MHD_resume_connection(r->conn);
        pthread_mutex_lock(&intake.lock);
    }
    pthread_mutex_unlock(&intake.lock);
    return NULL;
}

int api_start(qdcd *q)
{
    (void)q;
    if (pthread_create(&intake.th, NULL, intake_main, NULL))
        return -1;
    intake.running = 1;
    return 0;
}

void api_stop(void)
{
    if (!intake.running)
        return;
    pthread_mutex_lock(&intake.lock);
    intake.stop = 1;
    pthread_cond_signal(&intake.cond);
    pthread_mutex_unlock(&intake.lock);
    pthread_join(intake.th, NULL);
    intake.running = 0;
}

/* Body complete (HTTP thread): refuse what needs no parsing, hand the rest
 * to the intake thread with the connection suspended. */
static enum MHD_Result finish_upload(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    char d[400], extra[200];

    if (r->intake_done) /* resumed without a reply: queueing it failed */
        return MHD_NO;
    if (r->too_big) {
        int json = r->fmt == MESHIO_JSON && q->cfg.max_json < q->cfg.max_body;
        int64_t lim = json ? q->cfg.max_json : q->cfg.max_body;
        if (json)
            snprintf(d, sizeof d,
                     "JSON mesh bodies are limited to %lld bytes; send larger meshes as "
                     "%s (proto/mesh-binary.md)",
                     (long long)lim, MEDIA_QMESH);
        else
            snprintf(d, sizeof d, "request bodies are limited to %lld bytes",
                     (long long)lim);
        snprintf(extra, sizeof extra, "\"max_bytes\":%lld%s", (long long)lim,
                 json ? ",\"use\":\"" MEDIA_QMESH "\"" : "");
        return http_problem(c, r, 413, "too-big", "request body too large", d, extra,
                            NULL);
    }
    if (r->io_err || r->fd < 0)
        return http_problem(c, r, 507, "io", "insufficient storage",
                            "the upload could not be stored", NULL, NULL);
    if (r->body_len == 0)
        return http_problem(c, r, 400, "empty-body", "empty request body",
                            "POST /v1/jobs needs a mesh in the body", NULL, NULL);

    pthread_mutex_lock(&intake.lock);
    if (intake.stop) {
        pthread_mutex_unlock(&intake.lock);
        static const char *const h[] = {MHD_HTTP_HEADER_RETRY_AFTER, "5", NULL};
        return http_problem(c, r, 503, "shutting-down", "shutting down",
                            "the server is stopping; retry later", NULL, h);
    }
    r->intake_next = NULL;
    if (intake.tail)
        intake.tail->intake_next = r;
    else
        intake.head = r;
    intake.tail = r;
    /* Suspended before the intake thread can see it, so its resume always
     * follows this suspend. */
    MHD_suspend_connection(c);
    pthread_cond_signal(&intake.cond);
    pthread_mutex_unlock(&intake.lock);
    return MHD_YES;
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

/* Records after `after` from memory, else (finished run) from the file. */
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
    if (*done)
        file_records(r, j->id, after, sse, out, count, last);
}

static int parse_long(const char *s, long lo, long hi, long *out)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (!*s || *end || errno || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

static enum MHD_Result do_progress(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    job_rec j;
    enum MHD_Result ret;
    sbuf recs = {0}, b = {0};
    int count, done;
    long last;

    if (!load_job(c, r, &j, &ret))
        return ret;
    if (!r->wait_set) {
        const char *a = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "after");
        const char *w = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "wait");
        double wait = 0;
        if (a && parse_long(a, -1, LONG_MAX - 1, &r->after))
            return http_problem(c, r, 400, "invalid-parameter", "invalid parameter",
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
                return http_problem(c, r, 400, "invalid-parameter", "invalid parameter",
                                    d, "\"parameter\":\"wait\"", NULL);
            }
        }
        if (wait > q->cfg.wait_cap)
            wait = q->cfg.wait_cap;
        r->deadline = r->t0 + wait;
        r->wait_set = 1;
    }
    for (int tries = 0;; tries++) {
        recs.len = 0;
        collect(r, &j, r->after, 0, &recs, &count, &last, &done);
        if (count || done || tries || mono_now() >= r->deadline ||
            poll_shutting_down(q->hub))
            break;
        if (poll_park(q->hub, j.id, r->after, &r->w, c, r->deadline)) {
            r->parked_ever = 1;
            sb_free(&recs);
            return MHD_YES;
        }
        /* Something arrived between the read and the park: read again. */
        if (q->store->ops->get(q->store, j.id, &j) != QDC_OK)
            break;
    }
    sb_printf(&b,
              "{\"id\":\"%s\",\"state\":\"%s\",\"done\":%s,\"after\":%ld,"
              "\"next_after\":%ld,\"count\":%d,\"records\":[",
              j.id, job_state_name(j.state), done ? "true" : "false", r->after,
              count ? last : r->after, count);
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
    qdcd *q = r->q;
    job_rec j;
    int count, done;
    long last;

    (void)pos;
    for (;;) {
        if (r->sse_off < r->sse.len) {
            size_t n = r->sse.len - r->sse_off;
            if (n > max)
                n = max;
            memcpy(buf, r->sse.buf + r->sse_off, n);
            r->sse_off += n;
            return (ssize_t)n;
        }
        r->sse.len = 0;
        r->sse_off = 0;
        if (r->sse_end)
            return MHD_CONTENT_READER_END_OF_STREAM;
        if (q->store->ops->get(q->store, r->id, &j) != QDC_OK) {
            sb_puts(&r->sse, "event: end\ndata: {\"state\":\"deleted\"}\n\n");
            r->sse_end = 1;
            continue;
        }
        collect(r, &j, r->after, 1, &r->sse, &count, &last, &done);
        if (r->sse.oom)
            return MHD_CONTENT_READER_END_WITH_ERROR;
        if (count) {
            r->after = last;
            continue;
        }
        if (done || poll_shutting_down(q->hub)) {
            sb_printf(
                &r->sse,
                "event: end\ndata: {\"id\":\"%s\",\"state\":\"%s\",\"done\":%s}\n\n",
                j.id, job_state_name(j.state), done ? "true" : "false");
            r->sse_end = 1;
            continue;
        }
        if (r->deadline > 0 && mono_now() >= r->deadline) {
            sb_puts(&r->sse, ": keep-alive\n\n");
            r->deadline = 0;
            continue;
        }
        r->deadline = mono_now() + SSE_KEEPALIVE;
        if (poll_park(q->hub, j.id, r->after, &r->w, r->conn, r->deadline))
            return 0; /* resumed by a record, the end, the keep-alive or shutdown */
    }
}

static enum MHD_Result do_events(struct MHD_Connection *c, req *r)
{
    job_rec j;
    enum MHD_Result ret;
    const char *a;
    struct MHD_Response *resp;

    if (!load_job(c, r, &j, &ret))
        return ret;
    a = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Last-Event-ID");
    if (!a)
        a = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "after");
    if (a && parse_long(a, -1, LONG_MAX - 1, &r->after))
        return http_problem(c, r, 400, "invalid-parameter", "invalid parameter",
                            "Last-Event-ID / 'after' must be an integer >= -1",
                            "\"parameter\":\"after\"", NULL);
    r->parked_ever = 1; /* a stream: its duration is not a latency */
    resp =
        MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 16384, sse_reader, r, NULL);
    static const char *const h[] = {MHD_HTTP_HEADER_CONTENT_TYPE, "text/event-stream",
                                    MHD_HTTP_HEADER_CACHE_CONTROL, "no-store", NULL};
    return http_reply_response(c, r, 200, resp, h);
}

/* ------------------------------------------------------------ result/report -- */

/* 409 / 410 for a job without a result to give; 0 if it has one. */
static int not_servable(struct MHD_Connection *c, req *r, const job_rec *j,
                        enum MHD_Result *ret)
{
    char d[200], extra[1200];

    if (!job_state_done(j->state)) {
        static const char *const h[] = {MHD_HTTP_HEADER_RETRY_AFTER, "2", NULL};
        snprintf(d, sizeof d, "job %s is %s; poll /v1/jobs/%s/progress", j->id,
                 job_state_name(j->state), j->id);
        snprintf(extra, sizeof extra, "\"state\":\"%s\"", job_state_name(j->state));
        *ret =
            http_problem(c, r, 409, "not-ready", "the job has not finished", d, extra, h);
        return 1;
    }
    if (j->state != JOB_SUCCEEDED) {
        snprintf(d, sizeof d, "job %s %s and has no result", j->id,
                 job_state_name(j->state));
        snprintf(extra, sizeof extra, "\"state\":\"%s\"%s%s", job_state_name(j->state),
                 j->error[0] ? ",\"error\":" : "", j->error);
        *ret =
            http_problem(c, r, 409, "no-result", "the job has no result", d, extra, NULL);
        return 1;
    }
    if (j->purged || j->expires < wall_now()) {
        snprintf(d, sizeof d, "the result of job %s expired and was deleted", j->id);
        snprintf(extra, sizeof extra, "\"expired\":%.3f", j->expires);
        *ret = http_problem(c, r, 410, "gone", "result expired", d, extra, NULL);
        return 1;
    }
    return 0;
}

/* Does If-None-Match match etag (quoted)? Weak comparison (RFC 9110 13.1.2). */
static int etag_matches(const char *inm, const char *etag)
{
    size_t n = strlen(etag);
    if (!inm)
        return 0;
    while (*inm) {
        while (*inm == ' ' || *inm == ',')
            inm++;
        if (*inm == '*')
            return 1;
        if (!strncmp(inm, "W/", 2))
            inm += 2;
        if (!strncmp(inm, etag, n) && (inm[n] == 0 || inm[n] == ',' || inm[n] == ' '))
            return 1;
        inm += strcspn(inm, ",");
    }
    return 0;
}

static enum MHD_Result do_result(struct MHD_Connection *c, req *r)
{
    static const struct {
        const char *names[4];
        const char *file;
        const char *ctype;
        size_t etag_off;
    } fmts[] = {
        {{"binary", "qmesh", MEDIA_QMESH, NULL},
         "result.qmesh",
         MEDIA_QMESH,
         offsetof(job_rec, etag_qmesh)},
        {{"json", "application/json", NULL, NULL},
         "result.json",
         "application/json",
         offsetof(job_rec, etag_json)},
        {{"medit", "mesh", "model/x-medit", "text/plain"},
         "result.mesh",
         "model/x-medit",
         offsetof(job_rec, etag_medit)},
    };
    job_rec j;
    enum MHD_Result ret;
    int k = -1;
    const char *f, *acc;
    char etag[80], path[4300];

    if (!load_job(c, r, &j, &ret))
        return ret;
    f = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "format");
    acc = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_ACCEPT);
    if (f) {
        for (int i = 0; i < 3 && k < 0; i++)
            for (int t = 0; t < 4 && fmts[i].names[t]; t++)
                if (!strcasecmp(f, fmts[i].names[t]))
                    k = i;
        if (k < 0)
            return http_problem(c, r, 400, "invalid-parameter", "invalid parameter",
                                "'format' must be binary, json or medit",
                                "\"parameter\":\"format\"", NULL);
    } else if (acc && *acc) {
        /* The first acceptable type in the client's order wins. */
        const char *p = acc;
        while (*p && k < 0) {
            char t[96];
            size_t n = strcspn(p, ",");
            snprintf(t, sizeof t, "%.*s", (int)(n < 95 ? n : 95), p);
            char *s = t + strspn(t, " ");
            s[strcspn(s, "; ")] = 0;
            if (!strcmp(s, "*/*") || !strcasecmp(s, "application/*"))
                k = 0;
            for (int i = 0; i < 3 && k < 0; i++)
                for (int u = 1; u < 4 && fmts[i].names[u]; u++)
                    if (strchr(fmts[i].names[u], '/') && !strcasecmp(s, fmts[i].names[u]))
                        k = i;
            p += n;
            if (*p == ',')
                p++;
        }
        if (k < 0)
            return http_problem(c, r, 406, "not-acceptable", "not acceptable",
                                "results are " MEDIA_QMESH ", application/json or "
                                "model/x-medit (or use ?format=)",
                                NULL, NULL);
    } else {
        k = 0;
    }
    if (not_servable(c, r, &j, &ret))
        return ret;
    snprintf(etag, sizeof etag, "\"%s\"", (const char *)&j + fmts[k].etag_off);
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
    job_path(r->q, j.id, fmts[k].file, path, sizeof path);
    return http_reply_file(c, r, 200, path, fmts[k].ctype, h);
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
    return http_reply_file(c, r, 200, path, "application/json", no_headers);
}

/* ------------------------------------------------------ cancel/delete/list -- */

static enum MHD_Result do_cancel(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    job_rec j;
    enum MHD_Result ret;
    int now_done = 0;

    if (!load_job(c, r, &j, &ret))
        return ret;
    if (!job_state_done(j.state)) {
        if (q->store->ops->cancel(q->store, j.id, &now_done) != QDC_OK)
            return http_problem(c, r, 500, "store", "job store error",
                                "the cancellation could not be recorded", NULL, NULL);
        if (now_done) {
            atomic_fetch_add(&q->m.finished[JOB_CANCELLED], 1);
            poll_end(q->hub, j.id);
        } else {
            job_pool_cancel(q->pool, j.id);
        }
        if (q->store->ops->get(q->store, j.id, &j) != QDC_OK)
            return http_problem(c, r, 404, "not-found", "no such job",
                                "the job was deleted", NULL, NULL);
    }
    return reply_job(c, r, 200, &j, no_headers);
}

static enum MHD_Result do_delete(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    job_rec j;
    enum MHD_Result ret;
    char dir[4200];
    int now_done;

    if (!load_job(c, r, &j, &ret))
        return ret;
    int running_here = 0;
    if (j.state == JOB_RUNNING) {
        q->store->ops->cancel(q->store, j.id, &now_done);
        running_here = job_pool_cancel(q->pool, j.id);
    }
    if (q->store->ops->remove(q->store, j.id) != QDC_OK)
        return http_problem(c, r, 500, "store", "job store error",
                            "the job could not be deleted", NULL, NULL);
    poll_drop(q->hub, j.id);
    /* A running job's worker removes the directory when it stops (and also
     * when it finished just before the row went away). */
    if (!running_here) {
        job_path(q, j.id, NULL, dir, sizeof dir);
        dir_remove(dir);
    }
    return http_reply(c, r, 204, NULL, "", 0, no_headers);
}

static enum MHD_Result do_list(struct MHD_Connection *c, req *r)
{
    const char *ps = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "page_size");
    const char *pt = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "page_token");
    long size = 50, after = 0;
    job_rec *rows;
    int n = 0;
    sbuf b = {0};
    enum MHD_Result ret;

    if (ps && parse_long(ps, 1, 1000, &size))
        return http_problem(c, r, 400, "invalid-parameter", "invalid parameter",
                            "'page_size' must be an integer in [1, 1000]",
                            "\"parameter\":\"page_size\"", NULL);
    if (pt && *pt && parse_long(pt, 0, LONG_MAX, &after))
        return http_problem(c, r, 400, "invalid-parameter", "invalid parameter",
                            "'page_token' is not a token this server issued",
                            "\"parameter\":\"page_token\"", NULL);
    rows = malloc((size_t)size * sizeof *rows);
    if (!rows)
        return http_problem(c, r, 503, "out-of-memory", "out of memory",
                            "try a smaller page", NULL, NULL);
    if (r->q->store->ops->list(r->q->store, r->owner, after, (int)size, rows, &n) !=
        QDC_OK) {
        free(rows);
        return http_problem(c, r, 500, "store", "job store error", "cannot list jobs",
                            NULL, NULL);
    }
    sb_puts(&b, "{\"jobs\":[");
    for (int i = 0; i < n; i++) {
        if (i)
            sb_puts(&b, ",");
        job_json(r, &rows[i], &b);
    }
    sb_puts(&b, "]");
    if (n == size)
        sb_printf(&b, ",\"next_page_token\":\"%lld\"", (long long)rows[n - 1].seq);
    sb_puts(&b, "}\n");
    free(rows);
    ret = http_reply_json(c, r, 200, &b, no_headers);
    sb_free(&b);
    return ret;
}

/* ------------------------------------------------------------ health, metrics -- */

static enum MHD_Result do_metrics(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    job_counts cnt;
    sbuf b = {0};
    enum MHD_Result ret;
    long long cum = 0;

    memset(&cnt, 0, sizeof cnt);
    q->store->ops->counts(q->store, &cnt);
    sb_puts(&b, "# HELP qdcd_jobs Jobs in the store by state.\n# TYPE qdcd_jobs gauge\n");
    for (int s = 0; s < JOB_STATE_COUNT; s++)
        sb_printf(&b, "qdcd_jobs{state=\"%s\"} %lld\n", job_state_name((job_state)s),
                  (long long)cnt.by_state[s]);
    sb_printf(&b,
              "# HELP qdcd_queue_depth Jobs waiting for a worker.\n"
              "# TYPE qdcd_queue_depth gauge\nqdcd_queue_depth %lld\n",
              (long long)cnt.by_state[JOB_QUEUED]);
    sb_printf(&b,
              "# HELP qdcd_workers Worker threads.\n# TYPE qdcd_workers gauge\n"
              "qdcd_workers %d\n",
              q->cfg.workers);
    sb_printf(&b,
              "# HELP qdcd_workers_busy Workers running a job.\n"
              "# TYPE qdcd_workers_busy gauge\nqdcd_workers_busy %d\n",
              job_pool_busy(q->pool));
    sb_printf(&b,
              "# HELP qdcd_parked_connections Long-polls and event streams waiting.\n"
              "# TYPE qdcd_parked_connections gauge\nqdcd_parked_connections %d\n",
              poll_parked_count(q->hub));
    sb_printf(&b,
              "# HELP qdcd_iterations_total Progress records published.\n"
              "# TYPE qdcd_iterations_total counter\nqdcd_iterations_total %lld\n",
              (long long)atomic_load(&q->m.iterations));
    sb_printf(&b,
              "# HELP qdcd_upload_bytes_total Request body bytes received on uploads.\n"
              "# TYPE qdcd_upload_bytes_total counter\nqdcd_upload_bytes_total %lld\n",
              (long long)atomic_load(&q->m.upload_bytes));
    sb_printf(
        &b,
        "# HELP qdcd_jobs_submitted_total Jobs accepted.\n"
        "# TYPE qdcd_jobs_submitted_total counter\nqdcd_jobs_submitted_total %lld\n",
        (long long)atomic_load(&q->m.submitted));
    sb_printf(&b,
              "# HELP qdcd_jobs_rejected_total Submissions refused (4xx).\n"
              "# TYPE qdcd_jobs_rejected_total counter\nqdcd_jobs_rejected_total %lld\n",
              (long long)atomic_load(&q->m.rejected));
    sb_puts(&b, "# HELP qdcd_jobs_finished_total Runs ended by this process, by state.\n"
                "# TYPE qdcd_jobs_finished_total counter\n");
    for (int s = JOB_SUCCEEDED; s < JOB_STATE_COUNT; s++)
        sb_printf(&b, "qdcd_jobs_finished_total{state=\"%s\"} %lld\n",
                  job_state_name((job_state)s),
                  (long long)atomic_load(&q->m.finished[s]));
    sb_puts(&b, "# HELP qdcd_http_responses_total Responses by status class.\n"
                "# TYPE qdcd_http_responses_total counter\n");
    for (int k = 1; k < 6; k++)
        sb_printf(&b, "qdcd_http_responses_total{code=\"%dxx\"} %lld\n", k,
                  (long long)atomic_load(&q->m.http_by_class[k]));
    sb_puts(&b, "# HELP qdcd_http_request_duration_seconds Time from request to response "
                "(long-polls and streams excluded).\n"
                "# TYPE qdcd_http_request_duration_seconds histogram\n");
    for (int k = 0; k <= LAT_BUCKETS; k++) {
        cum += atomic_load(&q->m.lat_count[k]);
        if (k < LAT_BUCKETS)
            sb_printf(&b, "qdcd_http_request_duration_seconds_bucket{le=\"%g\"} %lld\n",
                      lat_bounds[k], cum);
        else
            sb_printf(&b, "qdcd_http_request_duration_seconds_bucket{le=\"+Inf\"} %lld\n",
                      cum);
    }
    sb_printf(&b,
              "qdcd_http_request_duration_seconds_sum %.6f\n"
              "qdcd_http_request_duration_seconds_count %lld\n",
              (double)atomic_load(&q->m.lat_sum_us) * 1e-6, cum);
    ret = http_reply(c, r, 200, "text/plain; version=0.0.4", b.buf ? b.buf : "",
                     b.buf ? b.len : 0, no_headers);
    sb_free(&b);
    return ret;
}

static enum MHD_Result do_readyz(struct MHD_Connection *c, req *r)
{
    job_counts cnt;
    char body[160];

    if (poll_shutting_down(r->q->hub) || r->q->stop)
        return http_reply(c, r, 503, "application/json", "{\"status\":\"stopping\"}\n",
                          22, no_headers);
    if (r->q->store->ops->counts(r->q->store, &cnt) != QDC_OK)
        return http_reply(c, r, 503, "application/json", "{\"status\":\"store\"}\n", 19,
                          no_headers);
    snprintf(body, sizeof body, "{\"status\":\"ready\",\"queued\":%lld,\"workers\":%d}\n",
             (long long)cnt.by_state[JOB_QUEUED], r->q->cfg.workers);
    return http_reply(c, r, 200, "application/json", body, strlen(body), no_headers);
}

/* ---------------------------------------------------------------- dispatch -- */

enum MHD_Result api_begin(struct MHD_Connection *c, req *r, const char *url,
                          const char *method)
{
    r->conn = c;
    r->route = route_of(url, r->id);
    if (r->route == -1)
        return http_problem(c, r, 404, "not-found", "no such job",
                            "job ids are 32 lower-case hex digits", NULL, NULL);
    if (r->route == R_NONE) {
        char d[300];
        snprintf(d, sizeof d, "no resource at '%.200s'", url);
        return http_problem(c, r, 404, "not-found", "not found", d, NULL, NULL);
    }
    if (!method_ok(r->route, method)) {
        const char *const h[] = {MHD_HTTP_HEADER_ALLOW, allowed(r->route), NULL};
        return http_problem(c, r, 405, "method-not-allowed", "method not allowed",
                            "see the Allow header", NULL, h);
    }
    if (r->route >= R_JOBS && r->route <= R_CANCEL && !authenticate(c, r)) {
        static const char *const h[] = {MHD_HTTP_HEADER_WWW_AUTHENTICATE,
                                        "Bearer realm=\"qdcd\"", NULL};
        return http_problem(c, r, 401, "unauthorized", "unauthorized",
                            "send Authorization: Bearer <token>", NULL, h);
    }
    if (r->route == R_JOBS && !strcmp(method, "POST"))
        return begin_upload(c, r);
    return MHD_YES;
}

enum MHD_Result api_dispatch(struct MHD_Connection *c, req *r, const char *url,
                             const char *method)
{
    (void)url;
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
        return do_events(c, r);
    case R_RESULT:
        return do_result(c, r);
    case R_REPORT:
        return do_report(c, r);
    case R_CANCEL:
        return do_cancel(c, r);
    case R_LIVEZ:
        return http_reply(c, r, 200, "application/json", "{\"status\":\"ok\"}\n", 16,
                          no_headers);
    case R_READYZ:
        return do_readyz(c, r);
    case R_METRICS:
        return do_metrics(c, r);
    default:
        return http_problem(c, r, 404, "not-found", "not found", "no such resource", NULL,
                            NULL);
    }
}
