/* handlers.h - what api.c's dispatch and the per-resource files (progress.c)
 * share: internal to the endpoints, not seen by http.c. */
#ifndef QDCD_HANDLERS_H
#define QDCD_HANDLERS_H

#include "http.h"
#include "store.h"

/* The job of the route, if it exists and belongs to the caller: 1 and *j;
 * else 0 with the 404 (or 503) answered in *ret. */
int load_job(struct MHD_Connection *c, req *r, job_rec *j, enum MHD_Result *ret);

/* GET /v1/jobs/{id}/progress: records after ?after=, long-polled with ?wait=. */
enum MHD_Result do_progress(struct MHD_Connection *c, req *r);
/* GET /v1/jobs/{id}/events: the records as Server-Sent Events. */
enum MHD_Result do_events(struct MHD_Connection *c, req *r);

#endif
