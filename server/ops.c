/* ops.c - the operations endpoints: GET /metrics (Prometheus text) and
 * GET /readyz. /livez is a constant reply in api.c's dispatch. */
#include "ops.h"

#include "job.h"

#include <stdio.h>
#include <string.h>

static const char *const no_headers[] = {NULL};

enum MHD_Result ops_metrics(struct MHD_Connection *c, req *r)
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
              "# HELP qdcd_parked_hangups_total Parked connections dropped because "
              "their client had closed them.\n"
              "# TYPE qdcd_parked_hangups_total counter\nqdcd_parked_hangups_total %ld\n",
              poll_gone_count(q->hub));
    sb_printf(&b,
              "# HELP qdcd_iterations_total Progress records published.\n"
              "# TYPE qdcd_iterations_total counter\nqdcd_iterations_total %lld\n",
              (long long)atomic_load(&q->m.iterations));
    sb_printf(&b,
              "# HELP qdcd_upload_bytes_total Request body bytes received on uploads.\n"
              "# TYPE qdcd_upload_bytes_total counter\nqdcd_upload_bytes_total %lld\n",
              (long long)atomic_load(&q->m.upload_bytes));
    if (q->cfg.cache_max)
        sb_printf(
            &b,
            "# HELP qdcd_cache_bytes Bytes of job files in this node's cache at "
            "its last scan (--cache-max %lld).\n"
            "# TYPE qdcd_cache_bytes gauge\nqdcd_cache_bytes %lld\n"
            "# HELP qdcd_cache_evicted_total Cached files evicted, least recently "
            "used first.\n"
            "# TYPE qdcd_cache_evicted_total counter\nqdcd_cache_evicted_total %lld\n",
            (long long)q->cfg.cache_max, (long long)atomic_load(&q->m.cache_bytes),
            (long long)atomic_load(&q->m.cache_evicted));
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
