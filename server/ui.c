/* ui.c - the web console's files (web/, compiled in; docs in README.md "Web
 * console"). The page is static: everything it shows comes from the public
 * API (/v1/...), so it needs no token to load and asks for one when /v1 says
 * 401. Every reply carries a strict Content-Security-Policy (scripts and
 * styles from this origin only, no inline code, no framing) and is revalidated
 * by its ETag (no-cache), so a new qdcd build is picked up at the next load. */
#include "ui.h"

#include "parse.h"

#include <string.h>

static const char csp[] =
    "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' blob:; "
    "connect-src 'self'; object-src 'none'; base-uri 'none'; form-action 'none'; "
    "frame-ancestors 'none'";

static const ui_asset *by_name(const char *name)
{
    for (size_t i = 0; i < ui_nassets; i++)
        if (!strcmp(ui_assets[i].name, name))
            return &ui_assets[i];
    return NULL;
}

static int lower_hex(const char *s, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!((s[i] >= '0' && s[i] <= '9') || (s[i] >= 'a' && s[i] <= 'f')))
            return 0;
    return 1;
}

const ui_asset *ui_asset_of(const char *url)
{
    if (!strcmp(url, "/") || !strcmp(url, "/ui") || !strcmp(url, "/ui/"))
        return by_name("index.html");
    if (strncmp(url, "/ui/", 4))
        return NULL;
    url += 4;
    if (!strncmp(url, "jobs/", 5)) { /* the job view: a URL people share */
        url += 5;
        if (strlen(url) == JOB_ID_LEN && lower_hex(url, JOB_ID_LEN))
            return by_name("index.html");
        return NULL;
    }
    if (strchr(url, '/'))
        return NULL;
    return by_name(url);
}

enum MHD_Result ui_serve(struct MHD_Connection *c, req *r)
{
    const ui_asset *a = ui_asset_of(r->url);
    const char *inm;
    struct MHD_Response *resp;

    if (!a)
        return http_problem(c, r, 404, "not-found", NULL, "no such page", NULL, NULL);
    const char *const h[] = {MHD_HTTP_HEADER_ETAG,
                             a->etag,
                             MHD_HTTP_HEADER_CACHE_CONTROL,
                             "no-cache",
                             "Content-Security-Policy",
                             csp,
                             "Referrer-Policy",
                             "no-referrer",
                             NULL};
    inm = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_IF_NONE_MATCH);
    if (etag_matches(inm, a->etag)) {
        resp = MHD_create_response_from_buffer(0, (void *)"", MHD_RESPMEM_PERSISTENT);
        return http_reply_response(c, r, MHD_HTTP_NOT_MODIFIED, resp, h);
    }
    resp =
        MHD_create_response_from_buffer(a->len, (void *)a->data, MHD_RESPMEM_PERSISTENT);
    if (!resp)
        return MHD_NO;
    if (MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, a->ctype) !=
        MHD_YES) {
        MHD_destroy_response(resp);
        return MHD_NO;
    }
    return http_reply_response(c, r, MHD_HTTP_OK, resp, h);
}
