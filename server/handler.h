/* handler.h - what the endpoint handlers (upload.c, jobs.c, progress.c,
 * result.c, ops.c) share: the job of a route, the job's JSON and the replies
 * several of them give (handler.c). Internal to the endpoints, not seen by
 * http.c; it includes no handler's header. */
#ifndef QDCD_HANDLER_H
#define QDCD_HANDLER_H

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

#endif
