/* handlers.h - what api.c's dispatch and the per-resource files (progress.c)
 * share: internal to the endpoints, not seen by http.c. */
#ifndef QDCD_HANDLERS_H
#define QDCD_HANDLERS_H

#include "http.h"
#include "store.h"

/* The job of the route, if it exists and belongs to the caller: 1 and *j;
 * else 0 with the 404 (or 503) answered in *ret. */
int load_job(struct MHD_Connection *c, req *r, job_rec *j, enum MHD_Result *ret);

/* 503 with Retry-After: the store did not answer (what: the detail). */
enum MHD_Result store_unavailable(struct MHD_Connection *c, req *r, const char *what);
/* A job's JSON representation (the caller's view of the row). */
void job_json(req *r, const job_rec *j, sbuf *b);
/* Answer with job_json of j. */
enum MHD_Result reply_job(struct MHD_Connection *c, req *r, unsigned status,
                          const job_rec *j, const char *const *headers);

/* POST /v1/jobs/{id}:cancel, DELETE /v1/jobs/{id}, GET /v1/jobs (jobs.c). */
enum MHD_Result do_cancel(struct MHD_Connection *c, req *r);
enum MHD_Result do_delete(struct MHD_Connection *c, req *r);
enum MHD_Result do_list(struct MHD_Connection *c, req *r);

/* GET /v1/jobs/{id}/progress: records after ?after=, long-polled with ?wait=. */
enum MHD_Result do_progress(struct MHD_Connection *c, req *r);
/* GET /v1/jobs/{id}/events: the records as Server-Sent Events. */
enum MHD_Result do_events(struct MHD_Connection *c, req *r);

#endif
