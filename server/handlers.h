/* handlers.h - what api.c's dispatch and the per-resource files (upload.c,
 * jobs.c, progress.c, result.c) share: internal to the endpoints, not seen by
 * http.c. */
#ifndef QDCD_HANDLERS_H
#define QDCD_HANDLERS_H

#include "http.h"
#include "store.h"

/* The job of the route, if it exists and belongs to the caller: 1 and *j;
 * else 0 with the 404 (or 503) answered in *ret. */
int load_job(struct MHD_Connection *c, req *r, job_rec *j, enum MHD_Result *ret);

/* 503 with Retry-After: the store did not answer (what: the detail). */
enum MHD_Result store_unavailable(struct MHD_Connection *c, req *r, const char *what);
/* 507 with Retry-After: the disk is full (what: what could not be stored). */
enum MHD_Result storage_full(struct MHD_Connection *c, req *r, const char *what);
/* errno e says the disk (or the quota) is full. */
int disk_full(int e);
/* The media types this server reads and writes as JSON strings joined by
 * commas (with surfaces: those of the surfaces it tetrahedralizes too), and
 * the same as ?format= names. */
void media_list(sbuf *b, int surfaces);
void format_names(sbuf *b, int surfaces);

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
