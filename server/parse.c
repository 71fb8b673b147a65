/* parse.c - pure parsers of the HTTP layer (parse.h). */
#include "parse.h"

#include "store.h"

#include <arpa/inet.h>
#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

int parse_is_job_id(const char *s, size_t n)
{
    if (n != JOB_ID_LEN)
        return 0;
    for (size_t i = 0; i < n; i++)
        if (!isxdigit((unsigned char)s[i]) || isupper((unsigned char)s[i]))
            return 0;
    return 1;
}

int parse_long(const char *s, long lo, long hi, long *out)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (!*s || *end || errno || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

int etag_matches(const char *inm, const char *etag)
{
    size_t n = strlen(etag);
    if (!inm)
        return 0;
    while (*inm) {
        while (*inm == ' ' || *inm == ',')
            inm++;
        if (*inm == '*')
            return 1;
        if (!strncmp(inm, "W/", 2))
            inm += 2;
        if (!strncmp(inm, etag, n) && (inm[n] == 0 || inm[n] == ',' || inm[n] == ' '))
            return 1;
        inm += strcspn(inm, ",");
    }
    return 0;
}

int parse_accept(const char *acc, meshio_format *out)
{
    for (const char *p = acc; *p;) {
        char t[200], base[100];
        meshio_format k;
        size_t n = strcspn(p, ",");
        snprintf(t, sizeof t, "%.*s", (int)(n < sizeof t - 1 ? n : sizeof t - 1), p);
        p += n + (p[n] == ',');
        const char *e = t + strspn(t, " \t");
        snprintf(base, sizeof base, "%s", e);
        base[strcspn(base, "; \t")] = 0;
        int q0 = 0;
        for (const char *sc = strchr(e, ';'); sc; sc = strchr(sc + 1, ';')) {
            const char *pv = sc + 1 + strspn(sc + 1, " \t");
            if ((pv[0] == 'q' || pv[0] == 'Q') && pv[1] == '=')
                q0 = strtod(pv + 2, NULL) <= 0;
        }
        if (q0)
            continue; /* q=0: "not acceptable" */
        if (!strcmp(base, "*/*") || !strcasecmp(base, "application/*"))
            k = MESHIO_QMESH;
        else if (!strcasecmp(base, "model/*") || !strcasecmp(base, "text/plain"))
            k = MESHIO_MEDIT;
        else
            k = meshio_format_from_media_type(e);
        if (k != MESHIO_AUTO && k != MESHIO_TETGEN && meshio_media_type(k)) {
            *out = k;
            return 0;
        }
    }
    return -1;
}

int parse_query_ok(const char *s, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if ((unsigned char)s[i] < 0x20 || s[i] == 0x7f)
            return 0;
    return 1;
}

/* Is name[0..n) an entry of the comma-separated list (spaces around entries
 * ignored; "*" matches anything)? */
static int in_list(const char *list, const char *name, size_t n)
{
    for (const char *p = list; p && *p;) {
        size_t k = strcspn(p, ",");
        const char *e = p + k;
        while (p < e && (*p == ' ' || *p == '\t'))
            p++;
        size_t m = (size_t)(e - p);
        while (m && (p[m - 1] == ' ' || p[m - 1] == '\t'))
            m--;
        if ((m == 1 && *p == '*') || (m == n && m && !strncasecmp(p, name, n)))
            return 1;
        p = *e ? e + 1 : e;
    }
    return 0;
}

int parse_host_allowed(const char *host, const char *listen_host, const char *allowed)
{
    char name[256];
    size_t n;
    struct in_addr a4;
    struct in6_addr a6;

    if (!host)
        return 1;
    if (host[0] == '[') { /* [v6]:port */
        const char *close = strchr(host, ']');
        n = close ? (size_t)(close - host - 1) : 0;
        if (!close || n >= sizeof name || (close[1] && close[1] != ':'))
            return 0;
        memcpy(name, host + 1, n);
        name[n] = 0;
        return inet_pton(AF_INET6, name, &a6) == 1 || in_list(allowed, name, n);
    }
    n = strcspn(host, ":");
    if (!n || n >= sizeof name)
        return 0;
    memcpy(name, host, n);
    name[n] = 0;
    if (n && name[n - 1] == '.') /* "localhost." is localhost */
        name[--n] = 0;
    if (inet_pton(AF_INET, name, &a4) == 1 || !strcasecmp(name, "localhost") ||
        (n > 10 && !strcasecmp(name + n - 10, ".localhost")))
        return 1;
    if (listen_host && !strcasecmp(name, listen_host))
        return 1;
    return in_list(allowed, name, n);
}

int parse_origin_allowed(const char *origin, const char *host, const char *allowed)
{
    const char *auth = NULL;

    if (!origin)
        return 1;
    if (in_list(allowed, origin, strlen(origin)))
        return 1;
    if (!strncasecmp(origin, "http://", 7))
        auth = origin + 7;
    else if (!strncasecmp(origin, "https://", 8))
        auth = origin + 8;
    return auth && host && *host && !strcasecmp(auth, host);
}
