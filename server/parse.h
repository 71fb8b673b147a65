/* parse.h - pure parsers of the HTTP layer (no libmicrohttpd, no state):
 * job ids, query integers, If-None-Match, Accept. Unit-tested in
 * tests/unit/test_http.c. */
#ifndef QDCD_PARSE_H
#define QDCD_PARSE_H

#include "qdc.h"

#include <stddef.h>

/* s[0..n) is a job id: JOB_ID_LEN lower-case hex digits. */
int parse_is_job_id(const char *s, size_t n);
/* A whole decimal integer in [lo, hi] (no sign junk, no trailing text): 0 and
 * *out set, else -1 and *out untouched. */
int parse_long(const char *s, long lo, long hi, long *out);
/* Does an If-None-Match header value match etag (quoted, strong)? Weak
 * comparison (RFC 9110 13.1.2): "W/" prefixes ignored, "*" matches; NULL
 * matches nothing. */
int etag_matches(const char *inm, const char *etag);
/* The result format an Accept value asks for: its first entry that names an
 * offered format (parameters like ";encoding=binary" pick variants; q=0
 * entries are skipped, other q values ignored: the client's order decides;
 * * / * and application/ * pick the binary, model/ * and text/plain Medit).
 * 0 and *out set, or -1 when no entry is offered. */
int parse_accept(const char *acc, meshio_format *out);

#endif
