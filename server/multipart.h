/* multipart.h - multipart/form-data request bodies (RFC 7578), what
 * `curl -F name=@file` and a browser's FormData send: a pure parser (no
 * libmicrohttpd, no allocation, no state) that finds the parts of a body
 * already in memory. Unit-tested in tests/unit/test_multipart.c, fuzzed by
 * tests/fuzz/fuzz_multipart.c. */
#ifndef QDCD_MULTIPART_H
#define QDCD_MULTIPART_H

#include <stddef.h>

/* A boundary is 1 to 70 characters (RFC 2046 5.1.1). */
#define MP_BOUNDARY_MAX 70
/* The bytes of a part's header block, at most. */
#define MP_HEADERS_MAX 8192

typedef struct {
    char name[64];      /* Content-Disposition's name="...": never empty */
    char filename[256]; /* its filename="...", "" when there is none */
    size_t off, len;    /* the part's content: buf[off .. off + len) */
} mp_part;

/* The boundary of a Content-Type value "multipart/form-data; boundary=B"
 * (B plain or quoted) into out: 0, or -1 when ct is another type or has no
 * valid boundary. */
int mp_boundary(const char *ct, char out[MP_BOUNDARY_MAX + 1]);

/* The parts of the body buf[0..len) cut by boundary: up to max into parts,
 * their number in *n. Lines end in CRLF; every part has a
 * Content-Disposition of form-data with a name; the body ends with the
 * closing delimiter ("--B--"). 0, or -1 with the reason in why (cap bytes):
 * a body that is not such a list, a header with a NUL or other control
 * byte, a header block over MP_HEADERS_MAX bytes, more than max parts. */
int mp_parse(const char *buf, size_t len, const char *boundary, mp_part *parts, int max,
             int *n, char *why, size_t cap);

#endif
