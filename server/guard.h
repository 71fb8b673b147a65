/* guard.h - checks every request passes before it is routed: query values
 * without NUL or control bytes (400), a Host this daemon serves (403: DNS
 * rebinding), and for state-changing methods an allowed Origin and no
 * Sec-Fetch-Site: cross-site (403: cross-site request forgery; a browser
 * sends a text/plain POST to any address without asking). Options:
 * --allowed-hosts, --allowed-origins (server.h). Called by api.c's router
 * once the framing is checked, on the HTTP thread. */
#ifndef QDCD_GUARD_H
#define QDCD_GUARD_H

#include "http.h"

/* 0 when the request may go on; 1 when it was answered (*ret). */
int guard_request(struct MHD_Connection *c, req *r, const char *method,
                  enum MHD_Result *ret);

#endif
