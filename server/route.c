/* route.c - the router: paths and methods against the route table (route.h). */
#include "route.h"

#include "parse.h"
#include "store.h"

#include <stdio.h>
#include <string.h>

#define ROW(route, method, pattern, handler, begin, auth, flags)                         \
    {route, method, pattern, auth, flags},
const route_desc route_table[] = {ROUTE_LIST(ROW)};
#undef ROW
const size_t route_count = sizeof route_table / sizeof route_table[0];

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
    if (!strncmp(open, "{type}", 6)) {
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
    for (size_t i = 0; i < route_count; i++) {
        if (route_table[i].flags & RF_UI)
            continue;
        int m = match_one(route_table[i].pattern, url, id);
        if (m > 0)
            return route_table[i].route;
        if (m < 0)
            return R_BAD_ID;
    }
    return R_NONE;
}

const route_desc *route_desc_of(int route)
{
    for (size_t i = 0; i < route_count; i++)
        if (route_table[i].route == route)
            return &route_table[i];
    return NULL;
}

int route_row(int route, const char *method)
{
    unsigned bit = route_method_bit(method);
    int get = -1;

    if (bit == M_OTHER)
        return -1;
    for (size_t i = 0; i < route_count; i++) {
        if (route_table[i].route != route)
            continue;
        if (route_table[i].method == bit)
            return (int)i;
        if (bit == M_HEAD && route_table[i].method == M_GET && get < 0)
            get = (int)i;
    }
    return get;
}

int route_method_ok(int route, const char *method)
{
    return route_row(route, method) >= 0;
}

unsigned route_methods(int route)
{
    unsigned bits = 0;
    for (size_t i = 0; i < route_count; i++)
        if (route_table[i].route == route)
            bits |= route_table[i].method;
    return bits & M_GET ? bits | M_HEAD : bits;
}

int route_always_closes(int route)
{
    int n = 0;
    for (size_t i = 0; i < route_count; i++) {
        if (route_table[i].route != route)
            continue;
        if (!(route_table[i].flags & RF_CLOSE))
            return 0;
        n++;
    }
    return n > 0;
}

void route_allow(int route, char *out, size_t cap)
{
    static const struct {
        unsigned bit;
        const char *name;
    } order[] = {{M_GET, "GET"}, {M_POST, "POST"}, {M_DELETE, "DELETE"}};
    unsigned bits = route_methods(route);
    size_t len = 0;

    if (cap)
        out[0] = 0;
    for (size_t k = 0; k < sizeof order / sizeof order[0]; k++) {
        if (!(bits & order[k].bit) || len >= cap)
            continue;
        int n = snprintf(out + len, cap - len, "%s%s", len ? ", " : "", order[k].name);
        len += n > 0 ? (size_t)n : 0;
    }
}

void route_print(FILE *f)
{
    static const char *const names[] = {"OTHER", "GET", "HEAD", "",      "POST",
                                        "",      "",    "",     "DELETE"};
    for (size_t i = 0; i < route_count; i++)
        if (!(route_table[i].flags & RF_ALIAS))
            fprintf(f, "%s %s\n", names[route_table[i].method], route_table[i].pattern);
}
