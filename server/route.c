/* route.c - the route table and the router (route.h). */
#include "route.h"

#include "parse.h"
#include "store.h"

#include <stdio.h>
#include <string.h>

#define GET_HEAD (M_GET | M_HEAD)

/* Matched in order: the fixed paths first, so "/v1/jobs/" is the collection. */
static const route_desc table[] = {
    {"/livez", R_LIVEZ, GET_HEAD, "GET", AUTH_NONE},
    {"/readyz", R_READYZ, GET_HEAD, "GET", AUTH_OPS},
    {"/metrics", R_METRICS, GET_HEAD, "GET", AUTH_OPS},
    {"/v1/jobs", R_JOBS, GET_HEAD | M_POST, "GET, POST", AUTH_TOKEN},
    {"/v1/jobs/", R_JOBS, GET_HEAD | M_POST, "GET, POST", AUTH_TOKEN},
    {"/v1/options", R_OPTIONS, GET_HEAD, "GET", AUTH_TOKEN},
    {"/v1/formats", R_FORMATS, GET_HEAD, "GET", AUTH_TOKEN},
    {"/problems/{slug}", R_PROBLEM, GET_HEAD, "GET", AUTH_NONE},
    {"/v1/jobs/{id}", R_JOB, GET_HEAD | M_DELETE, "GET, DELETE", AUTH_TOKEN},
    {"/v1/jobs/{id}/progress", R_PROGRESS, GET_HEAD, "GET", AUTH_TOKEN},
    {"/v1/jobs/{id}/events", R_EVENTS, GET_HEAD, "GET", AUTH_TOKEN},
    {"/v1/jobs/{id}/result", R_RESULT, GET_HEAD, "GET", AUTH_TOKEN},
    {"/v1/jobs/{id}/report", R_REPORT, GET_HEAD, "GET", AUTH_TOKEN},
    {"/v1/jobs/{id}:cancel", R_CANCEL, M_POST, "POST", AUTH_TOKEN},
    {"/v1/jobs/{id}/input", R_INPUT, GET_HEAD, "GET", AUTH_TOKEN},
    {NULL, R_UI, GET_HEAD, "GET", AUTH_NONE},
};
#define NROUTES (sizeof table / sizeof table[0])

unsigned route_method_bit(const char *m)
{
    static const struct {
        const char *name;
        unsigned bit;
    } names[] = {
        {"GET", M_GET}, {"HEAD", M_HEAD}, {"POST", M_POST}, {"DELETE", M_DELETE}};
    for (size_t i = 0; m && i < sizeof names / sizeof names[0]; i++)
        if (!strcmp(m, names[i].name))
            return names[i].bit;
    return M_OTHER;
}

/* A problem slug: 1..JOB_ID_LEN of [a-z-]. */
static int is_slug(const char *s, size_t n)
{
    size_t k = 0;
    while (k < n && ((s[k] >= 'a' && s[k] <= 'z') || s[k] == '-'))
        k++;
    return n && n <= JOB_ID_LEN && k == n;
}

/* url against one pattern: 1 match, 0 no match, -1 the shape matches but the
 * id cannot exist. */
static int match_one(const char *pat, const char *url, char *id)
{
    const char *open = strchr(pat, '{');
    if (!open)
        return !strcmp(pat, url);
    size_t pre = (size_t)(open - pat);
    if (strncmp(url, pat, pre))
        return 0;
    const char *close = strchr(open, '}');
    const char *seg = url + pre;
    size_t n = strcspn(seg, "/:");
    if (strcmp(seg + n, close + 1))
        return 0;
    if (!strncmp(open, "{slug}", 6)) {
        if (!is_slug(seg, n))
            return 0;
    } else if (!parse_is_job_id(seg, n)) {
        return -1;
    }
    memcpy(id, seg, n);
    id[n] = 0;
    return 1;
}

int route_match(const char *url, char *id)
{
    for (size_t i = 0; i < NROUTES; i++) {
        if (!table[i].pattern)
            continue;
        int m = match_one(table[i].pattern, url, id);
        if (m > 0)
            return table[i].route;
        if (m < 0)
            return R_BAD_ID;
    }
    return R_NONE;
}

const route_desc *route_desc_of(int route)
{
    for (size_t i = 0; i < NROUTES; i++)
        if (table[i].route == route)
            return &table[i];
    return NULL;
}

int route_method_ok(int route, const char *method)
{
    const route_desc *d = route_desc_of(route);
    return d && (d->methods & route_method_bit(method)) != 0;
}
