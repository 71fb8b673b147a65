/* parse.c - pure parsers of the HTTP layer (parse.h). */
#include "parse.h"

#include "store.h"

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
