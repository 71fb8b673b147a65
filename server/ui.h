/* ui.h - the web console: the files of web/, compiled into qdcd by
 * scripts/embed.sh (build/.../gen/web_assets.c), served at / and under /ui/. */
#ifndef QDCD_UI_H
#define QDCD_UI_H

#include "http.h"

#include <stddef.h>

typedef struct {
    const char *name;  /* file name in web/, the path under /ui/ */
    const char *ctype; /* Content-Type */
    const unsigned char *data;
    size_t len;
    const char *etag; /* strong, quoted: a SHA-256 prefix of the content */
} ui_asset;

extern const ui_asset ui_assets[];
extern const size_t ui_nassets;

/* The file a GET of url serves (the page for /, /ui/ and /ui/jobs/{id}), or
 * NULL when url is not the console's. */
const ui_asset *ui_asset_of(const char *url);
/* Answer a GET/HEAD of a console url (r->url): 200 or 304 (If-None-Match),
 * with Cache-Control: no-cache, the ETag and a Content-Security-Policy. */
enum MHD_Result ui_serve(struct MHD_Connection *c, req *r);

#endif
