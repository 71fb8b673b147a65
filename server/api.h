/* api.h - the endpoints : routing, JSON <-> library. */
#ifndef QDCD_API_H
#define QDCD_API_H

#include "http.h"

/* First call (headers only): route, authenticate, check limits; may answer
 * at once (401, 404, 413, 415, 429). */
enum MHD_Result api_begin(struct MHD_Connection *c, req *r, const char *url,
                          const char *method);
/* One chunk of the request body. */
void api_body(req *r, const char *data, size_t len);
/* Body complete (or resumed after parking): answer or park. */
enum MHD_Result api_dispatch(struct MHD_Connection *c, req *r, const char *url,
                             const char *method);
/* Release what the request still holds (temp upload file). */
void api_req_done(req *r);
/* The four above, for http_start. */
extern const http_handlers api_handlers;

/* The intake thread: parses, validates and commits complete uploads while
 * their connections are suspended, so the HTTP thread never waits on a parse
 * or an fsync. api_stop finishes what is queued (answering each) first. */
int api_start(qdcd *q);
void api_stop(void);

#endif
