/* h5.c - MED files (HDF5) through the qdc-h5 program, run as a child: libqdc
 * never calls HDF5. Reading: `qdc-h5 med-read FILE`, its standard output read
 * as the mesh (lib/io/meshio_med.c); writing: the mesh written spliced into a
 * pipe to `qdc-h5 med-write SOURCE OUT`. qdc-h5 is found as $QDC_H5, beside
 * this program's own file, or on PATH. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "qdc.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

/* The MED file the mesh being written was read from (one a run). */
static char med_source[PATH_MAX];

static const char *h5_program(char *buf, size_t n)
{
    const char *env = getenv("QDC_H5");
    ssize_t k;

    if (env && *env)
        return env;
    k = readlink("/proc/self/exe", buf, n - 8);
    if (k > 0) {
        char *slash;
        buf[k] = '\0';
        slash = strrchr(buf, '/');
        if (slash) {
            strcpy(slash + 1, "qdc-h5");
            if (access(buf, X_OK) == 0)
                return buf;
        }
    }
    return "qdc-h5";
}

int cli_h5_wanted(const char *path, meshio_format f)
{
    static const unsigned char sig[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
    unsigned char head[8];
    FILE *fp;
    int h5 = 0;

    if (f == MESHIO_MED)
        return 1;
    if (f != MESHIO_AUTO || !strcmp(path, "-"))
        return 0;
    fp = fopen(path, "rb");
    if (fp) {
        h5 = fread(head, 1, 8, fp) == 8 && memcmp(head, sig, 8) == 0;
        fclose(fp);
    }
    return h5;
}

/* A pipe whose ends the child does not inherit (only the one given as its
 * stdin or stdout): else it would hold our write end and never see the end. */
static qdc_status cloexec_pipe(int fd[2], qdc_error *err)
{
    if (pipe(fd) != 0)
        return qdc_fail(err, QDC_EIO, "pipe: %s", strerror(errno));
    if (fcntl(fd[0], F_SETFD, FD_CLOEXEC) != 0 ||
        fcntl(fd[1], F_SETFD, FD_CLOEXEC) != 0) {
        close(fd[0]);
        close(fd[1]);
        return qdc_fail(err, QDC_EIO, "fcntl: %s", strerror(errno));
    }
    return QDC_OK;
}

/* Run qdc-h5 with args; in_fd/out_fd: the child's stdin and stdout (-1:
 * /dev/null, the default). The child's pid in *pid. */
static qdc_status spawn(char *const argv[], int in_fd, int out_fd, pid_t *pid,
                        qdc_error *err)
{
    posix_spawn_file_actions_t fa;
    int rc;

    posix_spawn_file_actions_init(&fa);
    if (in_fd >= 0)
        posix_spawn_file_actions_adddup2(&fa, in_fd, 0);
    else
        posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", 0, 0);
    if (out_fd >= 0)
        posix_spawn_file_actions_adddup2(&fa, out_fd, 1);
    rc = posix_spawnp(pid, argv[0], &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0)
        return qdc_fail(err, QDC_EIO,
                        "cannot run %s (MED files are read by it; make builds it with "
                        "libhdf5-dev): %s",
                        argv[0], strerror(rc));
    return QDC_OK;
}

static qdc_status reap(pid_t pid, const char *what, qdc_error *err)
{
    int ws;

    while (waitpid(pid, &ws, 0) < 0)
        if (errno != EINTR)
            return qdc_fail(err, QDC_EIO, "qdc-h5: %s", strerror(errno));
    if (WIFEXITED(ws) && WEXITSTATUS(ws) == 0)
        return QDC_OK;
    if (WIFSIGNALED(ws))
        return qdc_fail(err, QDC_EIO, "qdc-h5 %s: killed by signal %d", what,
                        WTERMSIG(ws));
    return qdc_fail(err, QDC_EPARSE, "qdc-h5 %s failed (its message above)", what);
}

qdc_status cli_h5_read(const char *path, const meshio_options *mo, mesh_t **m,
                       qdc_error *err)
{
    char prog[PATH_MAX + 8];
    char *argv[] = {(char *)h5_program(prog, sizeof prog), "med-read", (char *)path,
                    NULL};
    int fd[2];
    pid_t pid;
    char *buf = NULL;
    size_t len = 0, cap = 0;
    qdc_status st, st2;

    st = cloexec_pipe(fd, err);
    if (st != QDC_OK)
        return st;
    st = spawn(argv, -1, fd[1], &pid, err);
    close(fd[1]);
    if (st != QDC_OK) {
        close(fd[0]);
        return st;
    }
    for (;;) {
        ssize_t k;
        if (len == cap) {
            char *nb = qdc_realloc(buf, cap ? 2 * cap : 1 << 20);
            if (!nb) {
                st = qdc_fail(err, QDC_ENOMEM, "out of memory reading %s", path);
                break;
            }
            buf = nb;
            cap = cap ? 2 * cap : 1 << 20;
        }
        k = read(fd[0], buf + len, cap - len);
        if (k < 0 && errno == EINTR)
            continue;
        if (k < 0)
            st = qdc_fail(err, QDC_EIO, "reading qdc-h5's output: %s", strerror(errno));
        if (k <= 0)
            break;
        len += (size_t)k;
    }
    close(fd[0]);
    st2 = reap(pid, "med-read", st == QDC_OK ? err : NULL);
    if (st == QDC_OK)
        st = st2;
    if (st == QDC_OK)
        st = meshio_read_ex(buf, len, MESHIO_MED, mo, m, err);
    if (st == QDC_OK)
        snprintf(med_source, sizeof med_source, "%s", path);
    qdc_free(buf);
    return st;
}

static int fd_write(void *ctx, const void *data, size_t len)
{
    const char *p = data;
    int fd = *(const int *)ctx;

    while (len) {
        ssize_t k = write(fd, p, len);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            return -1;
        p += k;
        len -= (size_t)k;
    }
    return 0;
}

qdc_status cli_h5_write(const char *out, const mesh_t *m, qdc_error *err)
{
    char prog[PATH_MAX + 8];
    char *argv[] = {(char *)h5_program(prog, sizeof prog), "med-write", med_source,
                    (char *)out, NULL};
    int fd[2];
    pid_t pid;
    qdc_status st, st2;
    void (*old)(int);

    if (!strcmp(out, "-"))
        return qdc_fail(err, QDC_EINVAL,
                        "a MED file is written to a file, not to a pipe");
    if (!med_source[0] || meshio_source_format(m) != MESHIO_MED ||
        !meshio_splices(m, MESHIO_MED, NULL))
        return qdc_fail(err, QDC_EINVAL,
                        "MED is written only over the MED file the mesh was read from "
                        "(its coordinates replaced)");
    st = cloexec_pipe(fd, err);
    if (st != QDC_OK)
        return st;
    st = spawn(argv, fd[0], -1, &pid, err);
    close(fd[0]);
    if (st != QDC_OK) {
        close(fd[1]);
        return st;
    }
    old = signal(SIGPIPE, SIG_IGN); /* a child that died early: EPIPE, not death */
    st = meshio_write(m, MESHIO_MED, fd_write, &fd[1], err);
    close(fd[1]);
    signal(SIGPIPE, old);
    st2 = reap(pid, "med-write", st == QDC_OK ? err : NULL);
    return st == QDC_OK ? st2 : st;
}
