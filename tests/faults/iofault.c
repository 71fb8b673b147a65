/* iofault.c - transient I/O faults for a running process (LD_PRELOAD), for
 * tests/faults/io.sh. write, pwrite, pwrite64, fsync and fdatasync on a file
 * whose path contains a given text fail, or write short, for a given number
 * of calls, then work again: a full disk that is freed, a flaky device.
 *
 * IOFAULT_CTL=FILE names a control file holding one line "MODE TEXT COUNT",
 * re-read whenever it changes (write a new file and rename it over FILE):
 *   enospc TEXT N   the next N writes fail with ENOSPC
 *   eio TEXT N      the next N writes fail with EIO
 *   short TEXT N    the next N writes write at most half of what they are
 *                   given (at least one byte): callers must loop
 *   fsync TEXT N    the next N fsync/fdatasync calls fail with EIO
 *   off             nothing
 * on files whose path (/proc/self/fd/N) contains TEXT. Each injected fault
 * appends one line "MODE PATH" to FILE.hits, so a test can tell that its
 * fault happened. Not part of qdc: glibc's stdio writes (fwrite, fflush) go
 * around these symbols and are not affected. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

typedef ssize_t (*write_fn)(int, const void *, size_t);
typedef ssize_t (*pwrite_fn)(int, const void *, size_t, off_t);
typedef int (*sync_fn)(int);

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static struct stat seen;         /* the control file as last read */
static char mode[16], text[512]; /* "" when off */
static long left;                /* faults still to inject */

static void *real(const char *name)
{
    return dlsym(RTLD_NEXT, name);
}

/* Re-read the control file if it changed (lock held). */
static void refresh(void)
{
    const char *ctl = getenv("IOFAULT_CTL");
    struct stat sb;
    char line[600];
    FILE *f;

    if (!ctl || stat(ctl, &sb))
        return;
    /* tests replace it (a new inode), so a change within one clock tick counts */
    if (sb.st_ino == seen.st_ino && sb.st_size == seen.st_size &&
        sb.st_mtim.tv_sec == seen.st_mtim.tv_sec &&
        sb.st_mtim.tv_nsec == seen.st_mtim.tv_nsec)
        return;
    seen = sb;
    mode[0] = text[0] = 0;
    left = 0;
    f = fopen(ctl, "r");
    if (!f)
        return;
    if (fgets(line, sizeof line, f) &&
        sscanf(line, "%15s %511s %ld", mode, text, &left) != 3)
        mode[0] = 0;
    fclose(f);
}

/* The fault kind to inject for a call of class cls ('w' write, 's' sync) on
 * fd, or 0; the count is taken. */
static char take(int fd, char cls)
{
    char link[64], path[1024];
    char kind = 0;
    ssize_t n;

    pthread_mutex_lock(&lock);
    refresh();
    if (left <= 0 || !mode[0])
        goto out;
    if (cls == 's' ? strcmp(mode, "fsync") != 0 : !strcmp(mode, "fsync"))
        goto out;
    snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
    n = readlink(link, path, sizeof path - 1);
    if (n <= 0)
        goto out;
    path[n] = 0;
    if (!strstr(path, text))
        goto out;
    left--;
    kind = mode[0] == 'e' && mode[1] == 'n' ? 'n' : mode[0];
    {
        const char *ctl = getenv("IOFAULT_CTL");
        char hits[1100], rec[1200];
        int h;
        snprintf(hits, sizeof hits, "%s.hits", ctl);
        h = open(hits, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
        if (h >= 0) {
            int len = snprintf(rec, sizeof rec, "%s %s\n", mode, path);
            ((write_fn)real("write"))(h, rec, (size_t)len);
            close(h);
        }
    }
out:
    pthread_mutex_unlock(&lock);
    return kind;
}

/* What a write of len bytes does under fault kind k: -1 with errno, or the
 * length to really write. */
static ssize_t fault_len(char k, size_t len)
{
    if (k == 'n') {
        errno = ENOSPC;
        return -1;
    }
    if (k == 'e') {
        errno = EIO;
        return -1;
    }
    if (k == 's' && len > 1)
        return (ssize_t)(len / 2);
    return (ssize_t)len;
}

ssize_t write(int fd, const void *buf, size_t len)
{
    ssize_t n = fault_len(take(fd, 'w'), len);
    return n < 0 ? -1 : ((write_fn)real("write"))(fd, buf, (size_t)n);
}

ssize_t pwrite(int fd, const void *buf, size_t len, off_t off)
{
    ssize_t n = fault_len(take(fd, 'w'), len);
    return n < 0 ? -1 : ((pwrite_fn)real("pwrite"))(fd, buf, (size_t)n, off);
}

ssize_t pwrite64(int fd, const void *buf, size_t len, off_t off)
{
    ssize_t n = fault_len(take(fd, 'w'), len);
    return n < 0 ? -1 : ((pwrite_fn)real("pwrite64"))(fd, buf, (size_t)n, off);
}

int fsync(int fd)
{
    if (take(fd, 's')) {
        errno = EIO;
        return -1;
    }
    return ((sync_fn)real("fsync"))(fd);
}

int fdatasync(int fd)
{
    if (take(fd, 's')) {
        errno = EIO;
        return -1;
    }
    return ((sync_fn)real("fdatasync"))(fd);
}
