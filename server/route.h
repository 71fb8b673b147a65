/* route.h - the route table: path pattern, allowed methods (and the Allow
 * header a 405 sends), who may call it. route_match is pure (no
 * libmicrohttpd): unit-tested in tests/unit/test_http.c. */
#ifndef QDCD_ROUTE_H
#define QDCD_ROUTE_H

#include <stddef.h>

enum {
    R_BAD_ID = -1, /* a job route with an id that cannot exist: 404 */
    R_NONE = 0,    /* no resource: 404 */
    R_JOBS,
    R_JOB,
    R_PROGRESS,
    R_EVENTS,
    R_RESULT,
    R_REPORT,
    R_INPUT,   /* the job's input mesh: served like R_RESULT */
    R_OPTIONS, /* the option table */
    R_FORMATS, /* the format table */
    R_CANCEL,
    R_LIVEZ,
    R_READYZ,
    R_METRICS,
    R_PROBLEM,
    R_UI, /* the web console (ui.c); matched by ui_asset_of, not by pattern */
    R_COUNT
};

/* Methods, one bit each; M_OTHER for any other (never allowed). */
enum { M_OTHER = 0, M_GET = 1, M_HEAD = 2, M_POST = 4, M_DELETE = 8 };

/* Who may call a route. */
enum {
    AUTH_NONE,  /* anyone */
    AUTH_TOKEN, /* a bearer token when the daemon has tokens */
    AUTH_OPS,   /* like AUTH_TOKEN unless --public-metrics */
};

typedef struct route_desc {
    const char *pattern; /* "{id}": a job id segment; "{slug}": a problem slug */
    int route;
    unsigned methods;  /* M_* bits (HEAD wherever GET is) */
    const char *allow; /* the Allow header of a 405 */
    int auth;
} route_desc;

/* The method's bit: exact, case-sensitive comparison (RFC 9110 9.1). */
unsigned route_method_bit(const char *method);
/* The route of a path; the job id (or problem slug) is copied to id
 * (JOB_ID_LEN + 1 bytes). R_NONE or R_BAD_ID when nothing matches. */
int route_match(const char *url, char *id);
/* The table entry of a route (R_JOBS..R_UI), else NULL. */
const route_desc *route_desc_of(int route);
/* Is method allowed on route (a route_match result > R_NONE)? */
int route_method_ok(int route, const char *method);

#endif
