/* ops.c - the operations endpoints: GET /metrics (Prometheus text),
 * GET /readyz and GET /livez; and the constant documents: GET /v1/options
 * (the option table) and GET /problems/{type} (a problem type's page). */
#include "ops.h"

#include "job.h"
#include "problem.h"

#include <stdio.h>
#include <string.h>

static const char *const no_headers[] = {NULL};

/* One metric without labels: its HELP and TYPE lines, then its value. */
static void metric(sbuf *b, const char *name, const char *type, const char *help,
                   long long v)
{
    sb_printf(b, "# HELP %s %s\n# TYPE %s %s\n%s %lld\n", name, help, name, type, name,
              v);
}

/* The request latency histogram (long-polls and streams excluded). */
static void latency_histogram(sbuf *b, qdcd *q)
{
    long long cum = 0;

    sb_puts(b, "# HELP qdcd_http_request_duration_seconds Time from request to response "
               "(long-polls and streams excluded).\n"
               "# TYPE qdcd_http_request_duration_seconds histogram\n");
    for (int k = 0; k <= LAT_BUCKETS; k++) {
        cum += atomic_load(&q->m.lat_count[k]);
        if (k < LAT_BUCKETS)
            sb_printf(b, "qdcd_http_request_duration_seconds_bucket{le=\"%g\"} %lld\n",
                      lat_bounds[k], cum);
        else
            sb_printf(b, "qdcd_http_request_duration_seconds_bucket{le=\"+Inf\"} %lld\n",
                      cum);
    }
    sb_printf(b,
              "qdcd_http_request_duration_seconds_sum %.6f\n"
              "qdcd_http_request_duration_seconds_count %lld\n",
              (double)atomic_load(&q->m.lat_sum_us) * 1e-6, cum);
}

enum MHD_Result ops_metrics(struct MHD_Connection *c, req *r)
{
    qdcd *q = r->q;
    job_counts cnt;
    sbuf b = {0};
    enum MHD_Result ret;

    memset(&cnt, 0, sizeof cnt);
    q->store->ops->counts(q->store, &cnt);
    sb_puts(&b, "# HELP qdcd_jobs Jobs in the store by state.\n# TYPE qdcd_jobs gauge\n");
    for (int s = 0; s < JOB_STATE_COUNT; s++)
        sb_printf(&b, "qdcd_jobs{state=\"%s\"} %lld\n", job_state_name((job_state)s),
                  (long long)cnt.by_state[s]);
    metric(&b, "qdcd_queue_depth", "gauge", "Jobs waiting for a worker.",
           (long long)cnt.by_state[JOB_QUEUED]);
    metric(&b, "qdcd_workers", "gauge", "Worker threads.", q->cfg.workers);
    metric(&b, "qdcd_workers_busy", "gauge", "Workers running a job.",
           job_pool_busy(q->pool));
    metric(&b, "qdcd_parked_connections", "gauge",
           "Long-polls and event streams waiting.", poll_parked_count(q->hub));
    metric(&b, "qdcd_parked_hangups_total", "counter",
           "Parked connections dropped because their client had closed them.",
           poll_gone_count(q->hub));
    metric(&b, "qdcd_records_total", "counter", "Progress records published.",
           (long long)atomic_load(&q->m.iterations));
    metric(&b, "qdcd_upload_bytes_total", "counter",
           "Request body bytes received on uploads.",
           (long long)atomic_load(&q->m.upload_bytes));
    if (q->cfg.cache_max) { /* --cache-max */
        metric(&b, "qdcd_cache_bytes", "gauge",
               "Bytes of job files in this node's cache at its last scan.",
               (long long)atomic_load(&q->m.cache_bytes));
        metric(&b, "qdcd_cache_evicted_total", "counter",
               "Cached files evicted, least recently used first.",
               (long long)atomic_load(&q->m.cache_evicted));
    }
    metric(&b, "qdcd_jobs_submitted_total", "counter", "Jobs accepted.",
           (long long)atomic_load(&q->m.submitted));
    metric(&b, "qdcd_jobs_rejected_total", "counter", "Submissions refused (4xx).",
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
    latency_histogram(&b, q);
    ret = http_reply(c, r, 200, "text/plain; version=0.0.4", b.buf ? b.buf : "",
                     b.buf ? b.len : 0, no_headers);
    sb_free(&b);
    return ret;
}

enum MHD_Result ops_readyz(struct MHD_Connection *c, req *r)
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

enum MHD_Result ops_livez(struct MHD_Connection *c, req *r)
{
    return http_reply(c, r, 200, "application/json", "{\"status\":\"ok\"}\n", 16,
                      no_headers);
}

enum MHD_Result ops_options(struct MHD_Connection *c, req *r)
{
    sbuf b = {0};
    job_opt_table_json(&b);
    enum MHD_Result ret = http_reply_json(c, r, 200, &b, no_headers);
    sb_free(&b);
    return ret;
}

enum MHD_Result ops_formats(struct MHD_Connection *c, req *r)
{
    sbuf b = {0};
    qdc_error e;
    enum MHD_Result ret;

    if (meshio_formats_json(sb_writer, &b, &e) != QDC_OK) {
        sb_free(&b);
        return http_problem(c, r, 500, "internal", NULL, e.msg, NULL, NULL);
    }
    ret = http_reply_json(c, r, 200, &b, no_headers);
    sb_free(&b);
    return ret;
}

/* problem+json bodies name their type as /problems/<slug>, a URI this daemon
 * serves; the router copied the slug to r->id. */
enum MHD_Result ops_problem_page(struct MHD_Connection *c, req *r)
{
    const char *slug = r->id;
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
