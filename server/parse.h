/* parse.h - pure parsers of the HTTP layer (no libmicrohttpd, no state):
 * job ids, query integers, If-None-Match, Accept, query values, Host and
 * Origin. Unit-tested in tests/unit/test_http.c. */
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

/* s[0..n) is a query value (or name) with no NUL or other control byte
 * (0x00-0x1f, 0x7f) once percent-decoded: 1, else 0. */
int parse_query_ok(const char *s, size_t n);
/* May a request with this Host header be served (DNS rebinding: a page whose
 * name was rebound to this machine sends its own name)? 1 for an IP address
 * (v4, or v6 in brackets), "localhost" and names under ".localhost", the
 * listen address's name, and the names of the comma-separated list allowed
 * ("*" allows any); the port is not checked (a proxy may use another). NULL
 * host (HTTP/1.0) is allowed; an empty one is not. */
int parse_host_allowed(const char *host, const char *listen_host, const char *allowed);
/* May a state-changing request come from this Origin? 1 when it is one of
 * the comma-separated origins in allowed (exact, case-insensitive; "*" any),
 * or http:// or https:// followed by the request's Host (the page was served
 * from the address the request went to: the console, directly or through a
 * proxy that keeps the Host). "null" and other origins: 0. */
int parse_origin_allowed(const char *origin, const char *host, const char *allowed);

#endif
