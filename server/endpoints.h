/* endpoints.h - the handlers the route table (route.h) names, one file per
 * resource (upload.c, jobs.c, progress.c, result.c, ops.c, ui.c), and their
 * threads: what api.c's router calls. A handler file includes handler.h (what
 * they share), never this router's header api.h. */
#ifndef QDCD_ENDPOINTS_H
#define QDCD_ENDPOINTS_H

#include "http.h"
#include "store.h"

/* GET /v1/jobs/{id}, POST /v1/jobs/{id}:cancel, DELETE /v1/jobs/{id},
 * GET /v1/jobs (jobs.c). */
enum MHD_Result do_get(struct MHD_Connection *c, req *r);
enum MHD_Result do_cancel(struct MHD_Connection *c, req *r);
enum MHD_Result do_delete(struct MHD_Connection *c, req *r);
enum MHD_Result do_list(struct MHD_Connection *c, req *r);

/* GET /v1/jobs/{id}/progress: records after ?after=, long-polled with ?wait=. */
enum MHD_Result do_progress(struct MHD_Connection *c, req *r);
/* GET /v1/jobs/{id}/events: the records as Server-Sent Events; HEAD: the
 * stream's headers only. */
enum MHD_Result do_events(struct MHD_Connection *c, req *r);
enum MHD_Result do_events_head(struct MHD_Connection *c, req *r);

/* POST /v1/jobs (upload.c): begin at the headers (options, format, limits:
 * may answer at once), body chunks, finish when the body is complete (the
 * intake thread parses and commits it), done when the request is over. */
typedef struct upload upload;
enum MHD_Result upload_begin(struct MHD_Connection *c, req *r);
void upload_body(req *r, const char *data, size_t len);
enum MHD_Result upload_finish(struct MHD_Connection *c, req *r);
void upload_done(req *r);
/* The intake thread. upload_stop answers what is queued first. */
int upload_start(void);
void upload_stop(void);

/* A reader's long-poll or stream state (progress.c), freed with the request. */
typedef struct watch watch;
void watch_done(req *r);

/* GET /v1/jobs/{id}/result and /input in a negotiated format, /report
 * (result.c), and the conversion thread. */
enum MHD_Result do_result(struct MHD_Connection *c, req *r);
enum MHD_Result do_report(struct MHD_Connection *c, req *r);
int result_start(void);
void result_stop(void);

#endif
