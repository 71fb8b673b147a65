/* file.c - whole files: read into memory (gunzipped when compressed) and
 * saved through a temporary file, an fsync and a rename (file.h). Knows no
 * mesh format: the formats (meshio.c) and the splicer (splice.c) both sit
 * above it. */
#include "io/file.h"
#include "core/base_int.h"
#include "io/gz.h"

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

/* 1 if path ends in ".gz" (a gzip-compressed file of the format before it). */
int file_path_gz(const char *path)
{
    size_t n = strlen(path);
    return n > 3 && strcasecmp(path + n - 3, ".gz") == 0;
}

/* The extension that names the format: "mesh" for a.mesh, "mesh.gz" for
 * a.mesh.gz (ext_format reads it up to the next dot). */
const char *file_path_ext(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *end = base + strlen(base) - (file_path_gz(base) ? 3 : 0);
    const char *dot = NULL;

    for (const char *p = base; p < end; p++)
        if (*p == '.')
            dot = p;
    return dot && dot + 1 < end ? dot + 1 : NULL;
}

static qdc_status fail_errno(qdc_error *err, const char *what, const char *path, int e)
{
    char msg[128];

    if (strerror_r(e, msg, sizeof msg) != 0)
        snprintf(msg, sizeof msg, "errno %d", e);
    return qdc_fail(err, e == ENOMEM ? QDC_ENOMEM : QDC_EIO, "%s %s: %s", what, path,
                    msg);
}

qdc_status meshio_slurp(const char *path, char **buf, size_t *len, qdc_error *err)
{
    struct stat sb;
    size_t cap, n = 0;
    char *b = NULL;
    int fd, e = 0;

    if (!path || !buf || !len)
        return qdc_fail(err, QDC_EINVAL, "meshio_slurp: NULL argument");
    *buf = NULL;
    *len = 0;
    fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return fail_errno(err, "cannot open", path, errno);
    cap = fstat(fd, &sb) == 0 && sb.st_size > 0 ? (size_t)sb.st_size + 1 : 65536;
    for (;;) {
        ssize_t r;
        if (n == cap || !b) {
            char *nb;
            if (b && cap > SIZE_MAX / 2) {
                e = ENOMEM;
                break;
            }
            cap = b ? 2 * cap : cap;
            nb = qdc_realloc(b, cap);
            if (!nb) {
                e = ENOMEM;
                break;
            }
            b = nb;
        }
        r = read(fd, b + n, cap - n);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0) {
            e = errno;
            break;
        }
        if (r == 0)
            break;
        n += (size_t)r;
    }
    close(fd);
    if (e) {
        qdc_free(b);
        return fail_errno(err, "cannot read", path, e);
    }
    *buf = b;
    *len = n;
    return QDC_OK;
}

qdc_status meshio_slurp_plain(const char *path, char **buf, size_t *len, qdc_error *err)
{
    char *plain = NULL;
    size_t plen = 0;
    qdc_status st = meshio_slurp(path, buf, len, err);

    if (st != QDC_OK || !gz_is_gzip(*buf, *len))
        return st;
    st = gz_inflate(*buf, *len, &plain, &plen, err);
    qdc_free(*buf);
    *buf = plain;
    *len = st == QDC_OK ? plen : 0;
    return st;
}

int file_exists(const char *path)
{
    struct stat sb;

    return stat(path, &sb) == 0;
}

static int fd_write(void *ctx, const void *data, size_t len)
{
    int fd = *(int *)ctx;
    const char *p = data;

    while (len) {
        ssize_t r = write(fd, p, len);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            return -1;
        p += r;
        len -= (size_t)r;
    }
    return 0;
}

static uint64_t mix64(uint64_t x)
{
    x += UINT64_C(0x9e3779b97f4a7c15);
    x = (x ^ (x >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    x = (x ^ (x >> 27)) * UINT64_C(0x94d049bb133111eb);
    return x ^ (x >> 31);
}

/* Create path.tmp.XXXXXX exclusively (mode 0666 less the umask, unlike
 * mkstemp's 0600); tmp must have room for strlen(path) + 12. */
static int open_tmp(const char *path, char *tmp)
{
    static const char an[] =
        "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
    uint64_t r = mix64((uint64_t)(qdc_now() * 1e9) ^ (uint64_t)getpid() << 32 ^
                       (uint64_t)(uintptr_t)tmp);

    for (int attempt = 0; attempt < 100; attempt++) {
        size_t n = strlen(path);
        int fd;
        memcpy(tmp, path, n);
        memcpy(tmp + n, ".tmp.", 5);
        n += 5;
        r = mix64(r + (uint64_t)attempt);
        for (int i = 0; i < 6; i++)
            tmp[n++] = an[(r >> (6 * i)) % (sizeof an - 1)];
        tmp[n] = '\0';
        fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0 || errno != EEXIST)
            return fd;
    }
    return -1;
}

/* Flush the directory holding path, so the rename itself is durable. */
static void sync_dir(const char *path)
{
    const char *slash = strrchr(path, '/');
    char *dir;
    int fd;

    if (!slash) {
        fd = open(".", O_RDONLY | O_CLOEXEC);
    } else {
        size_t n = slash == path ? 1 : (size_t)(slash - path);
        dir = qdc_malloc(n + 1);
        if (!dir)
            return;
        memcpy(dir, path, n);
        dir[n] = '\0';
        fd = open(dir, O_RDONLY | O_CLOEXEC);
        qdc_free(dir);
    }
    if (fd >= 0) {
        fsync(fd);
        close(fd);
    }
}

/* 1 if the directory holding path is in /proc's file system (/proc/self/fd,
 * which /dev/fd names): its entries are a process's descriptors. */
static int in_proc(const char *path)
{
    const char *slash = strrchr(path, '/');
    struct stat d, p;
    char *dir;
    int r;

    if (!slash)
        return 0;
    dir = qdc_malloc((size_t)(slash - path) + 2);
    if (!dir)
        return 0;
    memcpy(dir, path, (size_t)(slash - path) + 1);
    dir[slash - path + (slash == path)] = '\0';
    r = stat(dir, &d) == 0 && stat("/proc", &p) == 0 && d.st_dev == p.st_dev;
    qdc_free(dir);
    return r;
}

/* Where a file written to path goes. 0: through a temporary file renamed onto
 * *target (qdc_malloc'd): path itself, or the regular file its symbolic links
 * lead to, so that the links stay links. 1: straight into path: a device, a
 * pipe, a process's descriptor (/dev/stdout, /dev/fd/N, /proc/self/fd/N:
 * renaming onto it would replace the link with a file, and a rename of the
 * file it names would leave the descriptor on the old one), or a link to
 * nothing yet. -1: out of memory. */
int file_save_route(const char *path, char **target)
{
    char *cur = qdc_malloc(strlen(path) + 1);

    *target = NULL;
    if (!cur)
        return -1;
    strcpy(cur, path);
    for (int hops = 0; hops < 40; hops++) {
        struct stat sb;
        char link[4096];
        ssize_t n;
        const char *slash;
        char *next;
        size_t dn;
        if (lstat(cur, &sb) != 0) {
            if (hops == 0) { /* a new file */
                *target = cur;
                return 0;
            }
            break; /* a link to nothing: open() creates what it names */
        }
        if (!S_ISLNK(sb.st_mode)) {
            if (!S_ISREG(sb.st_mode))
                break;
            *target = cur;
            return 0;
        }
        if (in_proc(cur))
            break;
        n = readlink(cur, link, sizeof link - 1);
        if (n <= 0)
            break;
        link[n] = '\0';
        slash = strrchr(cur, '/');
        dn = link[0] == '/' || !slash ? 0 : (size_t)(slash - cur) + 1;
        next = qdc_malloc(dn + (size_t)n + 1);
        if (!next) {
            qdc_free(cur);
            return -1;
        }
        memcpy(next, cur, dn);
        memcpy(next + dn, link, (size_t)n + 1);
        qdc_free(cur);
        cur = next;
        if (!strncmp(cur, "/proc/", 6) || !strcmp(cur, "/proc"))
            break;
    }
    qdc_free(cur);
    return 1;
}

/* What emit writes into fd, gzip-compressed when path ends in .gz; where is
 * the file written, for a failed write's message. */
static qdc_status write_fd(int fd, const char *path, const char *where, file_emit_fn emit,
                           const void *arg, qdc_error *err)
{
    qdc_status st;

    if (file_path_gz(path)) {
        gz_writer *gw = gz_writer_new(fd_write, &fd);
        st = gw ? emit(arg, gz_write, gw, err)
                : qdc_fail(err, QDC_ENOMEM, "out of memory");
        if (gz_writer_finish(gw) && st == QDC_OK)
            st = QDC_EIO;
    } else {
        st = emit(arg, fd_write, &fd, err);
    }
    return st == QDC_EIO ? fail_errno(err, "cannot write", where, errno) : st;
}

/* Write straight into path (file_save_route() said 1). */
static qdc_status save_direct(const char *path, file_emit_fn emit, const void *arg,
                              qdc_error *err)
{
    struct stat sb;
    qdc_status st;
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);

    if (fd < 0)
        return fail_errno(err, "cannot open", path, errno);
    st = write_fd(fd, path, path, emit, arg, err);
    if (st == QDC_OK && fstat(fd, &sb) == 0 && S_ISREG(sb.st_mode) && fsync(fd) != 0)
        st = fail_errno(err, "cannot fsync", path, errno);
    if (close(fd) != 0 && st == QDC_OK)
        st = fail_errno(err, "cannot close", path, errno);
    return st;
}

qdc_status file_save(const char *path, file_emit_fn emit, const void *arg, qdc_error *err)
{
    char *tmp, *target;
    struct stat old;
    qdc_status st;
    int fd, route = file_save_route(path, &target);

    if (route < 0)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    if (route > 0)
        return save_direct(path, emit, arg, err);
    path = target;
    tmp = qdc_malloc(strlen(path) + 12);
    if (!tmp) {
        qdc_free(target);
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    }
    fd = open_tmp(path, tmp);
    if (fd < 0) {
        st = fail_errno(err, "cannot create a temporary file for", path, errno);
        qdc_free(tmp);
        qdc_free(target);
        return st;
    }
    st = write_fd(fd, path, tmp, emit, arg, err);
    /* a file replaced keeps its permissions */
    if (st == QDC_OK && stat(path, &old) == 0 && fchmod(fd, old.st_mode & 07777) != 0)
        st = fail_errno(err, "cannot set the permissions of", tmp, errno);
    if (st == QDC_OK && fsync(fd) != 0)
        st = fail_errno(err, "cannot fsync", tmp, errno);
    if (close(fd) != 0 && st == QDC_OK)
        st = fail_errno(err, "cannot close", tmp, errno);
    if (st == QDC_OK && rename(tmp, path) != 0)
        st = fail_errno(err, "cannot rename to", path, errno);
    if (st != QDC_OK)
        unlink(tmp);
    else
        sync_dir(path);
    qdc_free(tmp);
    qdc_free(target);
    return st;
}
