/* handler.c - what the endpoint handlers share (handler.h): the job of a
 * route, the job's JSON, the replies several handlers give (store
 * unavailable, disk full) and the media type lists. Below the handlers: it
 * calls none of them, nor the router. */
#define _GNU_SOURCE
#include "handler.h"

#include "h5job.h"
#include "job.h"
#include "qdc.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <string.h>

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
    if (job_state_done(j->state) && (j->state != JOB_CANCELLED || job_has_result(j)))
        sb_printf(b, ",\"expires\":%.3f,\"expired\":%s", j->expires,
                  j->purged || j->expires < wall_now() ? "true" : "false");
    sb_printf(b, ",\"attempts\":%d,\"cancel_requested\":%s", j->attempts,
              j->cancel_requested ? "true" : "false");
    sb_printf(
        b,
        ",\"mesh\":{\"format\":\"%s\",\"vertices\":%lld,\"tets\":%lld,\"bytes\":%lld%s}",
        j->format, (long long)j->nv, (long long)j->nt, (long long)j->in_bytes,
        job_is_surface(j->format) ? ",\"surface\":true"
        : h5job_is_xdmf(r->q, j)  ? ",\"h5\":true" /* result?format=h5 */
                                  : "");
    if (j->file_name[0]) {
        sb_puts(b, ",\"file_name\":");
        sb_json_str(b, j->file_name);
    }
    if (j->label[0]) {
        sb_puts(b, ",\"label\":");
        sb_json_str(b, j->label);
    }
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
        sb_printf(b, ",\"iterations\":%ld,\"progress\":%s", lastseq,
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
    if (job_has_result(j) && !j->purged && j->expires >= wall_now())
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
