/* guard.c - the checks every request passes before routing (guard.h). */
#include "guard.h"

#include "parse.h"

#include <stdio.h>
#include <string.h>

/* Stops at the first query name or value with a control byte: a %00 would
 * cut the value short where it is read as a C string (format=json%00medit
 * was served as json). */
static enum MHD_Result scan_query(void *cls, enum MHD_ValueKind kind, const char *key,
                                  size_t key_size, const char *val, size_t val_size)
{
    const char **bad = cls;
    (void)kind;
    if (!parse_query_ok(key, key_size) || (val && !parse_query_ok(val, val_size))) {
        *bad = key;
        return MHD_NO;
    }
    return MHD_YES;
}

static int state_changing(const char *m)
{
    return !strcmp(m, "POST") || !strcmp(m, "PUT") || !strcmp(m, "PATCH") ||
           !strcmp(m, "DELETE");
}

int guard_request(struct MHD_Connection *c, req *r, const char *method,
                  enum MHD_Result *ret)
{
    const qdcd_config *cfg = &r->q->cfg;
    const char *bad = NULL, *host, *origin, *site;
    char d[400];
    int cross;

    /* A refused request's connection is closed after the reply: nothing
     * more of it (its framing is checked later, api.c) is read as a request. */
    r->close_after = 1;
    MHD_get_connection_values_n(c, MHD_GET_ARGUMENT_KIND, scan_query, &bad);
    if (bad) {
        snprintf(d, sizeof d,
                 "option or query parameter '%.60s': a NUL or other control character "
                 "is not allowed in a name or value",
                 bad);
        *ret = http_problem(c, r, 400, "invalid-parameter", NULL, d, NULL, NULL);
        return 1;
    }
    host = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_HOST);
    if (!parse_host_allowed(host, cfg->host, cfg->allowed_hosts)) {
        snprintf(d, sizeof d,
                 "this server does not answer to the name '%.100s'; its operator can "
                 "allow it with --allowed-hosts",
                 host);
        *ret = http_problem(c, r, 403, "host-not-allowed", NULL, d, NULL, NULL);
        return 1;
    }
    if (!state_changing(method)) {
        r->close_after = 0;
        return 0;
    }
    origin = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Origin");
    site = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Sec-Fetch-Site");
    cross = site && !strcmp(site, "cross-site");
    /* A cross-site page passes only when the operator listed its origin (a
     * console served from another site on purpose); without Origin or
     * Sec-Fetch-Site the client is not a browser. */
    if (origin ? !parse_origin_allowed(origin, cross ? NULL : host, cfg->allowed_origins)
               : cross) {
        sbuf x = {0};
        snprintf(d, sizeof d,
                 "%s from a page of another origin (%.100s) is refused; the server's "
                 "operator can allow that origin with --allowed-origins",
                 method, origin ? origin : "Sec-Fetch-Site: cross-site");
        sb_puts(&x, "\"origin\":");
        sb_json_str(&x, origin ? origin : "");
        *ret =
            http_problem(c, r, 403, "cross-origin", NULL, d, x.oom ? NULL : x.buf, NULL);
        sb_free(&x);
        return 1;
    }
    r->close_after = 0;
    return 0;
}
