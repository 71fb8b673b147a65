/* fuzz_multipart.c - libFuzzer target: the daemon's multipart/form-data
 * parser (server/multipart.c). The input's first line is a Content-Type
 * value (its boundary, if valid, cuts the rest; else "b" does); the rest is
 * the body. Every part found must lie inside the body and have a name.
 * Seeds: tests/fuzz/seeds/multipart; crashes go to
 * tests/fuzz/crashes/multipart/, which test_multipart replays. */
#include "multipart.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *nl = memchr(data, '\n', size);
    size_t hn = nl ? (size_t)(nl - (const char *)data) : size;
    char *ct = malloc(hn + 1), b[MP_BOUNDARY_MAX + 1], why[200];
    mp_part parts[4];
    int n = -1;

    if (!ct)
        return 0;
    memcpy(ct, data, hn);
    ct[hn] = 0;
    if (mp_boundary(ct, b))
        strcpy(b, "b");
    else if (!b[0] || strlen(b) > MP_BOUNDARY_MAX)
        abort();
    free(ct);
    const char *body = nl ? nl + 1 : (const char *)data + size;
    size_t len = (size_t)((const char *)data + size - body);
    /* the body in a buffer of its own size, so a read past it is caught */
    char *copy = malloc(len ? len : 1);
    if (!copy)
        return 0;
    memcpy(copy, body, len);
    if (mp_parse(copy, len, b, parts, 4, &n, why, sizeof why) == 0) {
        if (n < 0 || n > 4)
            abort();
        for (int k = 0; k < n; k++)
            if (!parts[k].name[0] || parts[k].off > len ||
                parts[k].len > len - parts[k].off)
                abort();
    } else if (!why[0]) {
        abort();
    }
    free(copy);
    return 0;
}
