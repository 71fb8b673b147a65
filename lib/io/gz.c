/* gz.c - gzip-compressed mesh files through zlib (gz.h). */
#include "io/gz.h"

#include <limits.h>
#include <string.h>
#include <zlib.h>

int gz_is_gzip(const char *buf, size_t len)
{
    return len >= 2 && (unsigned char)buf[0] == 0x1f && (unsigned char)buf[1] == 0x8b;
}

size_t gz_budget(size_t len, size_t max_out, unsigned max_ratio)
{
    size_t b = max_out && max_out < GZ_MAX_OUT ? max_out : GZ_MAX_OUT;

    if (max_ratio && len <= b / max_ratio) {
        size_t r = len * max_ratio;
        r = r > GZ_RATIO_FLOOR ? r : GZ_RATIO_FLOOR;
        b = r < b ? r : b;
    }
    return b;
}

size_t gz_head(const char *buf, size_t len, char *dst, size_t cap)
{
    z_stream z;
    size_t n;
    int rc;

    if (!gz_is_gzip(buf, len) || !cap)
        return 0;
    memset(&z, 0, sizeof z);
    if (inflateInit2(&z, 16 + MAX_WBITS) != Z_OK)
        return 0;
    z.next_in = (Bytef *)(uintptr_t)buf;
    z.avail_in = len > UINT_MAX ? UINT_MAX : (uInt)len;
    z.next_out = (Bytef *)dst;
    z.avail_out = cap > UINT_MAX ? UINT_MAX : (uInt)cap;
    rc = inflate(&z, Z_SYNC_FLUSH);
    n = (size_t)((char *)z.next_out - dst);
    inflateEnd(&z);
    return rc == Z_OK || rc == Z_STREAM_END || rc == Z_BUF_ERROR ? n : 0;
}

qdc_status gz_inflate(const char *buf, size_t len, char **out, size_t *outlen,
                      qdc_error *err)
{
    return gz_inflate_max(buf, len, GZ_MAX_OUT, out, outlen, err);
}

qdc_status gz_inflate_max(const char *buf, size_t len, size_t max_out, char **out,
                          size_t *outlen, qdc_error *err)
{
    z_stream z;
    size_t lim = max_out && max_out < GZ_MAX_OUT ? max_out : GZ_MAX_OUT;
    size_t cap = len < 1024 ? 4096 : len * 4, n = 0;
    char *dst;
    int rc = Z_OK;

    /* one byte past the limit is room enough to see that it is passed */
    if (cap > lim + 1)
        cap = lim + 1;
    dst = qdc_malloc(cap + 1);
    *out = NULL;
    *outlen = 0;
    if (!dst)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    memset(&z, 0, sizeof z);
    /* 16 + MAX_WBITS: a gzip header, not a raw zlib stream */
    if (inflateInit2(&z, 16 + MAX_WBITS) != Z_OK) {
        qdc_free(dst);
        return qdc_fail(err, QDC_ENOMEM, "gzip: cannot start zlib");
    }
    z.next_in = (Bytef *)(uintptr_t)buf;
    for (;;) {
        size_t left = (size_t)((const Bytef *)buf + len - z.next_in);
        if (n > lim)
            break;
        if (n == cap) {
            size_t ncap = cap * 2 > lim + 1 ? lim + 1 : cap * 2;
            char *t = qdc_realloc(dst, ncap + 1);
            if (!t) {
                inflateEnd(&z);
                qdc_free(dst);
                return qdc_fail(err, QDC_ENOMEM, "out of memory");
            }
            dst = t;
            cap = ncap;
        }
        z.avail_in = left > UINT_MAX ? UINT_MAX : (uInt)left;
        z.next_out = (Bytef *)dst + n;
        z.avail_out = cap - n > UINT_MAX ? UINT_MAX : (uInt)(cap - n);
        rc = inflate(&z, Z_NO_FLUSH);
        n = (size_t)((char *)z.next_out - dst);
        if (rc == Z_STREAM_END) {
            /* concatenated members (gzip -c a b > c) are one file */
            if (z.next_in == (const Bytef *)buf + len || inflateReset(&z) != Z_OK)
                break;
            continue;
        }
        if (rc != Z_OK && rc != Z_BUF_ERROR)
            break;
        /* output room left over: zlib wants input, and there is none */
        if (z.avail_out != 0 &&
            (rc == Z_BUF_ERROR || z.next_in == (const Bytef *)buf + len))
            break;
    }
    if (n > lim) {
        inflateEnd(&z);
        qdc_free(dst);
        return qdc_fail(err, QDC_ETOOBIG, "gzip: the data inflate to more than %zu bytes",
                        lim);
    }
    inflateEnd(&z);
    if (rc != Z_STREAM_END) {
        qdc_free(dst);
        return qdc_fail(err, QDC_EPARSE, "gzip: %s",
                        rc == Z_DATA_ERROR ? "corrupt compressed data"
                                           : "the compressed data end too early");
    }
    dst[n] = 0;
    *out = dst;
    *outlen = n;
    return QDC_OK;
}

struct gz_writer {
    z_stream z;
    qdc_write_fn sink;
    void *ctx;
    int failed;
    unsigned char buf[1 << 16];
};

gz_writer *gz_writer_new(qdc_write_fn sink, void *sink_ctx)
{
    gz_writer *w = qdc_calloc(1, sizeof *w);

    if (!w)
        return NULL;
    if (deflateInit2(&w->z, 6, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) !=
        Z_OK) {
        qdc_free(w);
        return NULL;
    }
    w->sink = sink;
    w->ctx = sink_ctx;
    return w;
}

static int pump(gz_writer *w, int flush)
{
    int rc;

    do {
        w->z.next_out = w->buf;
        w->z.avail_out = sizeof w->buf;
        rc = deflate(&w->z, flush);
        if (rc == Z_STREAM_ERROR)
            return -1;
        size_t have = sizeof w->buf - w->z.avail_out;
        if (have && w->sink(w->ctx, w->buf, have))
            return -1;
    } while (w->z.avail_out == 0);
    return flush == Z_FINISH && rc != Z_STREAM_END ? -1 : 0;
}

int gz_write(void *wp, const void *data, size_t len)
{
    gz_writer *w = wp;
    const Bytef *p = data;

    while (len && !w->failed) {
        uInt n = len > UINT_MAX ? UINT_MAX : (uInt)len;
        w->z.next_in = (Bytef *)(uintptr_t)p;
        w->z.avail_in = n;
        if (pump(w, Z_NO_FLUSH))
            w->failed = 1;
        p += n;
        len -= n;
    }
    return w->failed ? -1 : 0;
}

int gz_writer_finish(gz_writer *w)
{
    int rc;

    if (!w)
        return -1;
    w->z.next_in = NULL;
    w->z.avail_in = 0;
    rc = w->failed || pump(w, Z_FINISH) ? -1 : 0;
    deflateEnd(&w->z);
    qdc_free(w);
    return rc;
}
