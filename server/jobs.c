/* jobs.c - GET /v1/jobs/{id}, POST /v1/jobs/{id}:cancel, DELETE
 * /v1/jobs/{id} and GET /v1/jobs (the caller's jobs, newest first, paged).
 * Submission is upload.c. */
#define _GNU_SOURCE
#include "endpoints.h"
#include "handler.h"

#include "job.h"
#include "parse.h"
#include "shared.h"
#include "trash.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const no_headers[] = {NULL};

/* ------------------------------------------------------ cancel/delete/list -- */

enum MHD_Result do_get(struct MHD_Connection *c, req *r)
{
    job_rec j;
    enum MHD_Result ret;
    if (!load_job(c, r, &j, &ret))
        return ret;
    return reply_job(c, r, 200, &j, no_headers);
}

enum MHD_Result do_cancel(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    job_rec j;
    enum MHD_Result ret;
    int now_done = 0;

    if (!load_job(c, r, &j, &ret))
        return ret;
    if (!job_state_done(j.state)) {
        if (q->store->ops->cancel(q->store, j.id, &now_done) != QDC_OK)
            return store_unavailable(c, r, "the cancellation could not be recorded");
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

enum MHD_Result do_delete(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    job_rec j;
    enum MHD_Result ret;
    char dir[4200];
    int now_done;

    if (!load_job(c, r, &j, &ret))
        return ret;
    int running_here = 0;
    if (j.state == JOB_RUNNING)
        q->store->ops->cancel(q->store, j.id, &now_done);
    if (q->store->ops->remove(q->store, j.id) != QDC_OK)
        return store_unavailable(c, r, "the job could not be deleted");
    /* Whatever state was read above: a worker may have claimed the job since
     * (a DELETE right after the 202). The row is gone first, so a worker that
     * registers after this cancel finds it gone (job.c) and does not run it. */
    running_here = job_pool_cancel(q->pool, j.id);
    poll_drop(q->hub, j.id);
    /* A running job's worker removes the directory when it stops (and also
     * when it finished just before the row went away). */
    if (!running_here) {
        job_path(q, j.id, NULL, dir, sizeof dir);
        trash_put(dir); /* a big job's files take seconds to unlink */
    }
    return http_reply(c, r, 204, NULL, "", 0, no_headers);
}

enum MHD_Result do_list(struct MHD_Connection *c, req *r)
{
    const char *ps = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "page_size");
    const char *pt = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "page_token");
    long size = 50, after = 0;
    job_rec *rows;
    int n = 0;
    sbuf b = {0};
    enum MHD_Result ret;

    if (ps && parse_long(ps, 1, 1000, &size))
        return http_problem(c, r, 400, "invalid-parameter", NULL,
                            "'page_size' must be an integer in [1, 1000]",
                            "\"parameter\":\"page_size\"", NULL);
    if (pt && *pt && parse_long(pt, 0, LONG_MAX, &after))
        return http_problem(c, r, 400, "invalid-parameter", NULL,
                            "'page_token' is not a token this server issued",
                            "\"parameter\":\"page_token\"", NULL);
    rows = malloc((size_t)size * sizeof *rows);
    if (!rows)
        return http_problem(c, r, 503, "out-of-memory", NULL, "try a smaller page", NULL,
                            NULL);
    if (r->q->store->ops->list(r->q->store, r->owner, after, (int)size, rows, &n) !=
        QDC_OK) {
        free(rows);
        return store_unavailable(c, r, "cannot list jobs");
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
