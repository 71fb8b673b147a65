/* util.c - string buffer, clocks, durable file writes. */
#define _GNU_SOURCE
#include "util.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

void sb_free(sbuf *b)
{
    free(b->buf);
    b->buf = NULL;
    b->len = b->cap = 0;
    b->oom = 0;
}

static int sb_reserve(sbuf *b, size_t extra)
{
    size_t cap;
    char *p;

    if (b->oom)
        return -1;
    if (b->len + extra + 1 <= b->cap)
        return 0;
    cap = b->cap ? b->cap : 256;
    while (cap < b->len + extra + 1)
        cap *= 2;
    p = realloc(b->buf, cap);
    if (!p) {
        b->oom = 1;
        return -1;
    }
    b->buf = p;
    b->cap = cap;
    return 0;
}

void sb_add(sbuf *b, const void *data, size_t len)
{
    if (sb_reserve(b, len))
        return;
    memcpy(b->buf + b->len, data, len);
    b->len += len;
    b->buf[b->len] = 0;
}

void sb_puts(sbuf *b, const char *s)
{
    sb_add(b, s, strlen(s));
}

void sb_printf(sbuf *b, const char *fmt, ...)
{
    va_list ap;
    int n;

    va_start(ap, fmt);
    n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0 || sb_reserve(b, (size_t)n))
        return;
    va_start(ap, fmt);
    vsnprintf(b->buf + b->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    b->len += (size_t)n;
}

/* Length of the valid UTF-8 sequence at s (1-4), or 0 if s does not start
 * one (a stray continuation byte, an overlong form, a surrogate, a sequence
 * cut short: by the end of the string or by a %.Ns that cut a character). */
static int utf8_len(const unsigned char *s)
{
    int n;
    unsigned cp;

    if (s[0] < 0x80)
        return 1;
    if (s[0] >= 0xc2 && s[0] <= 0xdf)
        n = 2, cp = s[0] & 0x1fu;
    else if (s[0] >= 0xe0 && s[0] <= 0xef)
        n = 3, cp = s[0] & 0x0fu;
    else if (s[0] >= 0xf0 && s[0] <= 0xf4)
        n = 4, cp = s[0] & 0x07u;
    else
        return 0;
    for (int i = 1; i < n; i++) {
        if ((s[i] & 0xc0) != 0x80)
            return 0;
        cp = cp << 6 | (s[i] & 0x3fu);
    }
    if ((n == 3 && cp < 0x800) || (n == 4 && (cp < 0x10000 || cp > 0x10ffff)) ||
        (cp >= 0xd800 && cp <= 0xdfff))
        return 0;
    return n;
}

/* A JSON string of s: always valid UTF-8 (bytes that are not are written as
 * U+FFFD, so a client's bytes echoed in a problem detail cannot break it). */
void sb_json_str(sbuf *b, const char *s)
{
    sb_add(b, "\"", 1);
    while (*s) {
        unsigned char c = (unsigned char)*s;
        int n = utf8_len((const unsigned char *)s);
        if (c == '"' || c == '\\') {
            char e[2] = {'\\', (char)c};
            sb_add(b, e, 2);
        } else if (c < 0x20) {
            sb_printf(b, "\\u%04x", c);
        } else if (n == 0) {
            sb_add(b, "\xef\xbf\xbd", 3); /* U+FFFD */
            n = 1;
        } else {
            sb_add(b, s, (size_t)n);
            s += n;
            continue;
        }
        s += n ? n : 1;
    }
    sb_add(b, "\"", 1);
}

int sb_writer(void *ctx, const void *data, size_t len)
{
    sbuf *b = ctx;
    sb_add(b, data, len);
    return b->oom ? -1 : 0;
}

double mono_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

int fsync_parent(const char *path)
{
    char tmp[4096];
    int fd, rc;

    snprintf(tmp, sizeof tmp, "%s", path);
    fd = open(dirname(tmp), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0)
        return -1;
    rc = fsync(fd);
    close(fd);
    return rc;
}

int file_write_atomic(const char *path, const void *data, size_t len)
{
    char tmp[4096];
    const char *p = data;
    int fd;

    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0)
        return -1;
    while (len) {
        ssize_t n = write(fd, p, len);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            close(fd);
            unlink(tmp);
            return -1;
        }
        p += n;
        len -= (size_t)n;
    }
    if (fsync(fd) || close(fd) || rename(tmp, path)) {
        unlink(tmp);
        return -1;
    }
    return fsync_parent(path);
}

char *file_read_all(const char *path, size_t *len)
{
    return file_read_after(path, 0, len);
}

char *file_read_after(const char *path, size_t room, size_t *len)
{
    FILE *f = fopen(path, "rb");
    char *buf = NULL;
    long n;

    if (!f)
        return NULL;
    if (fseek(f, 0, SEEK_END) || (n = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) ||
        (size_t)n > SIZE_MAX - 1 - room)
        goto out;
    buf = malloc(room + (size_t)n + 1);
    if (!buf)
        goto out;
    if (fread(buf + room, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
        goto out;
    }
    buf[room + (size_t)n] = 0;
    if (len)
        *len = room + (size_t)n;
out:
    fclose(f);
    return buf;
}

int dir_ensure(const char *path)
{
    if (mkdir(path, 0755) && errno != EEXIST)
        return -1;
    return 0;
}

void dir_clear(const char *path, int depth)
{
    DIR *d = opendir(path);
    struct dirent *e;
    char p[4608];

    if (!d)
        return;
    while ((e = readdir(d)) != NULL) {
        if (e->d_name[0] == '.' &&
            (!e->d_name[1] || (e->d_name[1] == '.' && !e->d_name[2])))
            continue;
        snprintf(p, sizeof p, "%s/%s", path, e->d_name);
        if (unlink(p) && depth > 0) {
            dir_clear(p, depth - 1);
            rmdir(p);
        }
    }
    closedir(d);
}

void dir_remove(const char *path)
{
    dir_clear(path, 0);
    rmdir(path);
}
