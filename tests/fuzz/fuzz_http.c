/* fuzz_http.c - libFuzzer target: the daemon's pure HTTP parsers (router,
 * Accept, If-None-Match, query integers, job ids) on arbitrary text. The
 * input is split at its first NUL byte into a header value and a second
 * string (an ETag or a method). Seeds: tests/fuzz/seeds/http; crashes go to
 * tests/fuzz/crashes/http/, which test_http replays. */
#include "parse.h"
#include "route.h"
#include "store.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *s = malloc(size + 2), id[JOB_ID_LEN + 1];
    long v;
    meshio_format f;

    if (!s)
        return 0;
    memcpy(s, data, size);
    s[size] = s[size + 1] = 0;
    const char *second = s + strlen(s) + 1; /* "" when there is no NUL */
    int r = route_match(s, id);
    if (r > R_NONE && r != R_UI && !route_desc_of(r))
        abort();
    (void)route_method_ok(r, second);
    (void)parse_accept(s, &f);
    (void)etag_matches(s, second);
    (void)parse_long(s, -1, 1000, &v);
    (void)parse_is_job_id(s, strlen(s));
    free(s);
    return 0;
}
