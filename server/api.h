/* api.h - the endpoints as http.c sees them: four handlers (api.c routes
 * each request to the file of its resource) and their threads. */
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
/* Release what the request still holds (each handler's own state: an
 * upload's temporary file, a reader's watch). */
void api_req_done(req *r);
/* The four above, for http_start. */
extern const http_handlers api_handlers;

/* The intake thread (upload.c: parses, validates and commits complete
 * uploads) and the conversion thread (result.c), serving requests whose
 * connections are suspended, so the HTTP thread never waits on a parse, a
 * conversion or an fsync. api_stop finishes what is queued (answering each)
 * first. */
int api_start(qdcd *q);
void api_stop(void);

#endif
