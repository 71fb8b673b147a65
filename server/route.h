/* route.h - the route table, one row per method and path: the route, the
 * method, the path pattern, the handler that answers when the body is in, the
 * hook that may answer at the headers, who may call it and its flags. api.c
 * dispatches from it (with the handlers, endpoints.h); route.c matches paths
 * and methods against it without them, so route_match is pure (no
 * libmicrohttpd): unit-tested in tests/unit/test_http.c. `qdcd --print-routes`
 * prints it and tests/server/openapi.sh checks proto/openapi.yaml against it.
 * HEAD is allowed wherever GET is and answered by the GET row's handler
 * unless a HEAD row comes first. */
#ifndef QDCD_ROUTE_H
#define QDCD_ROUTE_H

#include <stddef.h>
#include <stdio.h>

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

/* Row flags. */
enum {
    RF_CLOSE = 1, /* the reply closes the connection (api.c says why) */
    RF_ALIAS = 2, /* another spelling of a documented path: not in the API */
    RF_UI = 4,    /* matched by ui_asset_of (the pattern is for the API docs) */
};

/* Matched in order: the fixed paths first, so "/v1/jobs/" is the collection.
 * X(route, method, pattern, handler, begin, auth, flags): "{id}" in a pattern
 * is a job id segment, "{type}" a problem slug; begin (or NULL) is called at
 * the headers and may answer at once (an upload's limits). To add an
 * endpoint: a row here, its handler in the file of its resource (declared in
 * endpoints.h), its path in proto/openapi.yaml (docs/architecture.md). */
#define ROUTE_LIST(X)                                                                    \
    X(R_LIVEZ, M_GET, "/livez", ops_livez, NULL, AUTH_NONE, 0)                           \
    X(R_READYZ, M_GET, "/readyz", ops_readyz, NULL, AUTH_OPS, 0)                         \
    X(R_METRICS, M_GET, "/metrics", ops_metrics, NULL, AUTH_OPS, 0)                      \
    X(R_JOBS, M_GET, "/v1/jobs", do_list, NULL, AUTH_TOKEN, 0)                           \
    X(R_JOBS, M_POST, "/v1/jobs", upload_finish, upload_begin, AUTH_TOKEN, RF_CLOSE)     \
    X(R_JOBS, M_GET, "/v1/jobs/", do_list, NULL, AUTH_TOKEN, RF_ALIAS)                   \
    X(R_JOBS, M_POST, "/v1/jobs/", upload_finish, upload_begin, AUTH_TOKEN,              \
      RF_CLOSE | RF_ALIAS)                                                               \
    X(R_OPTIONS, M_GET, "/v1/options", ops_options, NULL, AUTH_TOKEN, 0)                 \
    X(R_FORMATS, M_GET, "/v1/formats", ops_formats, NULL, AUTH_TOKEN, 0)                 \
    X(R_PROBLEM, M_GET, "/problems/{type}", ops_problem_page, NULL, AUTH_NONE, 0)        \
    X(R_JOB, M_GET, "/v1/jobs/{id}", do_get, NULL, AUTH_TOKEN, 0)                        \
    X(R_JOB, M_DELETE, "/v1/jobs/{id}", do_delete, NULL, AUTH_TOKEN, 0)                  \
    X(R_PROGRESS, M_GET, "/v1/jobs/{id}/progress", do_progress, NULL, AUTH_TOKEN,        \
      RF_CLOSE)                                                                          \
    X(R_EVENTS, M_HEAD, "/v1/jobs/{id}/events", do_events_head, NULL, AUTH_TOKEN,        \
      RF_CLOSE)                                                                          \
    X(R_EVENTS, M_GET, "/v1/jobs/{id}/events", do_events, NULL, AUTH_TOKEN, RF_CLOSE)    \
    X(R_RESULT, M_GET, "/v1/jobs/{id}/result", do_result, NULL, AUTH_TOKEN, 0)           \
    X(R_REPORT, M_GET, "/v1/jobs/{id}/report", do_report, NULL, AUTH_TOKEN, 0)           \
    X(R_CANCEL, M_POST, "/v1/jobs/{id}:cancel", do_cancel, NULL, AUTH_TOKEN, 0)          \
    X(R_INPUT, M_GET, "/v1/jobs/{id}/input", do_result, NULL, AUTH_TOKEN, 0)             \
    X(R_UI, M_GET, "/", ui_serve, NULL, AUTH_NONE, RF_UI)                                \
    X(R_UI, M_GET, "/ui/{file}", ui_serve, NULL, AUTH_NONE, RF_UI)                       \
    X(R_UI, M_GET, "/ui/jobs/{id}", ui_serve, NULL, AUTH_NONE, RF_UI)

/* A row of the table, without its handlers. */
typedef struct route_desc {
    int route;
    unsigned method; /* one M_* bit */
    const char *pattern;
    int auth;
    unsigned flags; /* RF_* bits */
} route_desc;

/* The rows, in table order. */
extern const route_desc route_table[];
extern const size_t route_count;

/* The method's bit: exact, case-sensitive comparison (RFC 9110 9.1). */
unsigned route_method_bit(const char *method);
/* The route of a path; the job id (or problem slug) is copied to id
 * (JOB_ID_LEN + 1 bytes). R_NONE or R_BAD_ID when nothing matches. */
int route_match(const char *url, char *id);
/* The first row of a route (R_JOBS..R_UI), else NULL. */
const route_desc *route_desc_of(int route);
/* The row that answers method on route: its own, or for HEAD the GET row;
 * its index in the table, or -1 when the method is not allowed. */
int route_row(int route, const char *method);
/* Is method allowed on route (a route_match result > R_NONE)? */
int route_method_ok(int route, const char *method);
/* The methods allowed on route: M_* bits, HEAD wherever GET is. */
unsigned route_methods(int route);
/* Does every row of route close the connection (RF_CLOSE)? */
int route_always_closes(int route);
/* The Allow header of a 405 on route ("GET, POST"): its methods but HEAD. */
void route_allow(int route, char *out, size_t cap);
/* The table as "METHOD PATTERN" lines, the documented rows only (not
 * RF_ALIAS; HEAD rows as HEAD): `qdcd --print-routes`. */
void route_print(FILE *f);

#endif
