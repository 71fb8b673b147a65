/* h5.c - MED files (HDF5) through the qdc-h5 program, run as a child: libqdc
 * never calls HDF5. Reading: `qdc-h5 med-read FILE`, its standard output read
 * as the mesh (lib/io/meshio_med.c); writing: the mesh written spliced into a
 * pipe to `qdc-h5 med-write SOURCE OUT`, or, when it does not splice (its
 * tets changed, it was read from another format), written whole by qdc's
 * MED writer into a pipe to `qdc-h5 med-new OUT`. qdc-h5 is found as
 * $QDC_H5, beside this program's own file, or on PATH.
 *
 * A MED file that is not a plain file on disk (gzip-compressed, or standard
 * input) is first inflated, within the limits of every gzip read
 * (meshio_gunzip), into a private temporary file that is unlinked as soon as
 * it is made: no path of ours, error or signal, can leave it behind. The
 * child opens it as /proc/self/fd/3; it stays open for the write back. */
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

/* The child's descriptor for a private copy, and the name it opens it by. */
enum { COPY_FD = 3 };
#define COPY_PATH "/proc/self/fd/3"

/* The MED file the mesh being written was read from (one a run): its name,
 * and the private copy (-1: the file itself is read again). */
static char med_source[PATH_MAX];
static int med_copy = -1;

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

/* 1 if head[0..n) starts an HDF5 file, or a gzip stream of one. */
static int h5_head(const char *head, size_t n)
{
    char plain[8];

    if (meshio_is_hdf5(head, n))
        return 1;
    return gz_is_gzip(head, n) && gz_head(head, n, plain, 8) == 8 &&
           meshio_is_hdf5(plain, 8);
}

int cli_h5_wanted(const char *path, meshio_format f)
{
    char head[4096];
    FILE *fp;
    size_t n = 0;

    if (f == MESHIO_MED)
        return 1;
    if (f != MESHIO_AUTO || !strcmp(path, "-"))
        return 0;
    fp = fopen(path, "rb");
    if (fp) {
        n = fread(head, 1, sizeof head, fp);
        fclose(fp);
    }
    return h5_head(head, n);
}

int cli_h5_bytes(const char *buf, size_t len)
{
    return h5_head(buf, len);
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

/* buf[0..len) into a new private temporary file, already unlinked: its
 * descriptor (close-on-exec, above the child's COPY_FD so that dup2 to it is
 * a real one) in *out. */
static qdc_status private_copy(const char *buf, size_t len, int *out, qdc_error *err)
{
    const char *dir = getenv("TMPDIR");
    char tmp[PATH_MAX];
    int fd, hi;
    size_t done = 0;

    *out = -1;
    if (snprintf(tmp, sizeof tmp, "%s/qdc-med.XXXXXX", dir && *dir ? dir : "/tmp") >=
        (int)sizeof tmp)
        return qdc_fail(err, QDC_EIO, "TMPDIR too long");
    fd = mkstemp(tmp);
    if (fd < 0)
        return qdc_fail(err, QDC_EIO, "cannot make a temporary file in %s: %s",
                        dir && *dir ? dir : "/tmp", strerror(errno));
    unlink(tmp);
    hi = fcntl(fd, F_DUPFD_CLOEXEC, 10);
    close(fd);
    if (hi < 0)
        return qdc_fail(err, QDC_EIO, "fcntl: %s", strerror(errno));
    while (done < len) {
        ssize_t k = write(hi, buf + done, len - done);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0) {
            int e = k < 0 ? errno : ENOSPC;
            close(hi);
            return qdc_fail(err, QDC_EIO, "cannot write a temporary file: %s",
                            strerror(e));
        }
        done += (size_t)k;
    }
    *out = hi;
    return QDC_OK;
}

/* Run qdc-h5 with args; in_fd/out_fd: the child's stdin and stdout (-1:
 * /dev/null, the default); copy_fd (-1: none): given to it as COPY_FD. The
 * child's pid in *pid. */
static qdc_status spawn(char *const argv[], int in_fd, int out_fd, int copy_fd,
                        pid_t *pid, qdc_error *err)
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
    if (copy_fd >= 0)
        posix_spawn_file_actions_adddup2(&fa, copy_fd, COPY_FD);
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

/* What qdc-h5 argv prints on its stdout, after room bytes left free, into
 * *buf (qdc_free) of *len bytes (room included); size: what it is expected
 * to print (0 if unknown), allocated at once. */
static qdc_status run_output(char *const argv[], int copy_fd, size_t room, size_t size,
                             char **out, size_t *outlen, qdc_error *err)
{
    int fd[2];
    pid_t pid;
    char *buf = NULL;
    size_t len = room, cap = 0;
    qdc_status st, st2;

    *out = NULL;
    *outlen = 0;
    st = cloexec_pipe(fd, err);
    if (st != QDC_OK)
        return st;
    st = spawn(argv, -1, fd[1], copy_fd, &pid, err);
    close(fd[1]);
    if (st != QDC_OK) {
        close(fd[0]);
        return st;
    }
    for (;;) {
        ssize_t k;
        if (len >= cap) {
            /* the expected size and a byte (to see the end), else doubled */
            size_t want = !cap && size ? room + size + 1
                          : cap        ? 2 * cap
                                       : room + (1 << 20);
            char *nb = qdc_realloc(buf, want);
            if (!nb) {
                st = qdc_fail(err, QDC_ENOMEM, "out of memory reading qdc-h5's output");
                break;
            }
            buf = nb;
            cap = want;
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
    st2 = reap(pid, argv[3], st == QDC_OK ? err : NULL);
    if (st == QDC_OK)
        st = st2;
    if (st != QDC_OK) {
        qdc_free(buf);
        return st;
    }
    *out = buf;
    *outlen = len;
    return QDC_OK;
}

/* The MED file name (shown as path), from the private copy copy_fd or, if
 * -1, from path itself. Takes copy_fd (kept for the write, or closed). */
static qdc_status med_read(const char *path, int copy_fd, const meshio_options *mo,
                           mesh_t **m, qdc_error *err)
{
    char prog[PATH_MAX + 8];
    char *argv[] = {
        (char *)h5_program(prog, sizeof prog),     "-n", (char *)path, "med-read",
        (char *)(copy_fd >= 0 ? COPY_PATH : path), NULL};
    char *buf;
    size_t len;
    qdc_status st = run_output(argv, copy_fd, 0, 0, &buf, &len, err);

    if (st == QDC_OK)
        st = meshio_read_ex(buf, len, MESHIO_MED, mo, m, err);
    qdc_free(buf);
    if (st != QDC_OK) {
        if (copy_fd >= 0)
            close(copy_fd);
        return st;
    }
    snprintf(med_source, sizeof med_source, "%s", path);
    if (med_copy >= 0)
        close(med_copy);
    med_copy = copy_fd;
    return QDC_OK;
}

qdc_status cli_h5_read_bytes(const char *name, const char *buf, size_t len,
                             const meshio_options *mo, mesh_t **m, qdc_error *err)
{
    char *plain = NULL;
    size_t plen = 0;
    int fd;
    qdc_status st = QDC_OK;

    if (gz_is_gzip(buf, len)) {
        st = meshio_gunzip(buf, len, mo, &plain, &plen, err);
        buf = plain;
        len = plen;
    }
    if (st == QDC_OK)
        st = private_copy(buf, len, &fd, err);
    qdc_free(plain);
    return st == QDC_OK ? med_read(name, fd, mo, m, err) : st;
}

qdc_status cli_h5_read(const char *path, const meshio_options *mo, mesh_t **m,
                       qdc_error *err)
{
    char head[2];
    FILE *fp = fopen(path, "rb");
    int gz = fp && fread(head, 1, 2, fp) == 2 && gz_is_gzip(head, 2);
    char *buf;
    size_t len;
    qdc_status st;

    if (fp)
        fclose(fp);
    if (!gz)
        return med_read(path, -1, mo, m, err);
    st = meshio_slurp(path, &buf, &len, err);
    if (st != QDC_OK)
        return st;
    st = cli_h5_read_bytes(path, buf, len, mo, m, err);
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

/* m written spliced as fmt into the stdin of qdc-h5 argv (copy_fd as for
 * spawn). */
static qdc_status run_input(char *const argv[], int copy_fd, const mesh_t *m,
                            meshio_format fmt, qdc_error *err)
{
    int fd[2];
    pid_t pid;
    qdc_status st, st2;
    void (*old)(int);

    st = cloexec_pipe(fd, err);
    if (st != QDC_OK)
        return st;
    st = spawn(argv, fd[0], -1, copy_fd, &pid, err);
    close(fd[0]);
    if (st != QDC_OK) {
        close(fd[1]);
        return st;
    }
    old = signal(SIGPIPE, SIG_IGN); /* a child that died early: EPIPE, not death */
    st = meshio_write(m, fmt, fd_write, &fd[1], err);
    close(fd[1]);
    signal(SIGPIPE, old);
    st2 = reap(pid, argv[3], st == QDC_OK ? err : NULL);
    return st == QDC_OK ? st2 : st;
}

static int ends_gz(const char *path)
{
    size_t n = strlen(path);

    return n > 3 && !strcmp(path + n - 3, ".gz");
}

qdc_status cli_h5_write(const char *out, const mesh_t *m, qdc_error *err)
{
    char prog[PATH_MAX + 8];
    char *argv[] = {
        (char *)h5_program(prog, sizeof prog),  "-n",        med_source, "med-write",
        med_copy >= 0 ? COPY_PATH : med_source, (char *)out, NULL};
    char *fresh[] = {argv[0], "-n", (char *)out, "med-new", (char *)out, NULL};

    if (!strcmp(out, "-"))
        return qdc_fail(err, QDC_EINVAL,
                        "a MED file is written to a file, not to a pipe");
    if (ends_gz(out))
        return qdc_fail(err, QDC_EINVAL,
                        "a MED file is written uncompressed (HDF5 has its own "
                        "compression): name it .med");
    /* the MED file read, with new coordinates; else (new tets, another
     * format read, --no-keep-source) a MED file of its own from qdc's
     * writer's frames (lib/io/meshio_med.c) */
    if (med_source[0] && meshio_source_format(m) == MESHIO_MED &&
        meshio_splices(m, MESHIO_MED, NULL))
        return run_input(argv, med_copy, m, MESHIO_MED, err);
    return run_input(fresh, -1, m, MESHIO_MED, err);
}

/* ------------------------------------------------------------------------ */
/* XDMF with its heavy data in HDF5                                          */

/* The XDMF the mesh being written was read from (one a run): its XML, its
 * .h5 file and the geometry's dataset there. */
static char *xdmf_xml;
static size_t xdmf_len;
static char xdmf_h5[PATH_MAX];
static char xdmf_geom[1024];

/* The folder of path, with its '/', into dir ("" for a bare name). */
static void folder_of(const char *path, char *dir, size_t size)
{
    const char *slash = strrchr(path, '/');
    size_t n = slash ? (size_t)(slash - path) + 1 : 0;

    snprintf(dir, size, "%.*s", (int)(n < size ? n : size - 1), path);
}

/* qdc-h5's specs of h's datasets ("geometry:f:356x3:/data0") into spec and
 * args (NULL-ended); the index of the geometry's (-1: none) and into *size
 * the bytes qdc-h5 prints for them (0 when over 1 GiB: the buffer then
 * grows as they come, and a file smaller than its XML says costs nothing). */
static int h5_specs(const meshio_xdmf_h5 *h, char spec[7][1200], char **args,
                    size_t *size)
{
    int geom = -1;
    double bytes = 8;

    for (int k = 0; k < h->n; k++) {
        double vals = 1;
        size_t n = (size_t)snprintf(spec[k], sizeof spec[k], "%s:%c:", h->set[k].name,
                                    h->set[k].type);
        for (int d = 0; d < h->set[k].ndims; d++) {
            n += (size_t)snprintf(spec[k] + n, sizeof spec[k] - n, "%s%lld", d ? "x" : "",
                                  (long long)h->set[k].dims[d]);
            vals *= (double)h->set[k].dims[d];
        }
        snprintf(spec[k] + n, sizeof spec[k] - n, ":%s", h->set[k].path);
        args[k] = spec[k];
        bytes += 32 + 8 * vals;
        if (!strcmp(h->set[k].name, "geometry"))
            geom = k;
    }
    args[h->n] = NULL;
    *size = bytes <= (double)(1u << 30) ? (size_t)bytes : 0;
    return geom;
}

qdc_status cli_xdmf_h5_retry(const char *path, qdc_status st, const meshio_options *mo,
                             mesh_t **m, qdc_error *err)
{
    char prog[PATH_MAX + 8], dir[PATH_MAX], h5[PATH_MAX], spec[7][1200];
    char *argv[13];
    char *xml = NULL, *in = NULL;
    size_t xml_len, in_len, size;
    meshio_xdmf_h5 h;
    qdc_error e;
    int geom;

    if (st != QDC_EFORMAT || meshio_slurp_plain(path, &xml, &xml_len, &e) != QDC_OK)
        return st;
    if (meshio_sniff(xml, xml_len) != MESHIO_XDMF) {
        qdc_free(xml);
        return st;
    }
    if (meshio_xdmf_h5_refs(xml, xml_len, &h, &e) != QDC_OK || !h.n) {
        qdc_free(xml);
        if (e.status != QDC_OK && err) /* this one's message says more */
            *err = e;
        return e.status != QDC_OK ? e.status : st;
    }
    folder_of(path, dir, sizeof dir);
    if (snprintf(h5, sizeof h5, "%s%s", dir, h.file) >= (int)sizeof h5) {
        qdc_free(xml);
        return qdc_fail(err, QDC_EINVAL, "%s: the .h5 file's path is too long", path);
    }
    argv[0] = (char *)h5_program(prog, sizeof prog);
    argv[1] = "-n";
    argv[2] = h5;
    argv[3] = "h5-read";
    argv[4] = h5;
    geom = h5_specs(&h, spec, argv + 5, &size);
    if (geom < 0) {
        qdc_free(xml);
        return qdc_fail(err, QDC_EFORMAT,
                        "XDMF: the Geometry inline, the rest of the mesh in HDF5: not "
                        "read (qdc writes the coordinates back into the .h5 file)");
    }
    /* the frames read after room for the XML: the form is made in place */
    st = run_output(argv, -1, meshio_xdmf_h5_room(xml_len), size, &in, &in_len, err);
    if (st == QDC_OK)
        st = meshio_xdmf_h5_fill(in, in_len, xml, xml_len, err);
    if (st == QDC_OK)
        st = meshio_read_ex(in, in_len, MESHIO_XDMF, mo, m, err);
    qdc_free(in);
    if (st != QDC_OK) {
        qdc_free(xml);
        return st;
    }
    qdc_free(xdmf_xml);
    xdmf_xml = xml;
    xdmf_len = xml_len;
    snprintf(xdmf_h5, sizeof xdmf_h5, "%s", h5);
    snprintf(xdmf_geom, sizeof xdmf_geom, "%s", h.set[geom].path);
    return QDC_OK;
}

int cli_xdmf_h5_source(const mesh_t *m)
{
    return xdmf_xml && meshio_source_format(m) == MESHIO_XDMF &&
           meshio_splices(m, MESHIO_XDMF, NULL);
}

typedef struct {
    char *b;
    size_t n, cap;
} membuf;

static int mem_write(void *ctx, const void *data, size_t len)
{
    membuf *mb = ctx;

    if (mb->cap - mb->n < len) {
        size_t cap = mb->cap ? mb->cap : 1 << 16;
        char *nb;
        while (cap - mb->n < len)
            cap *= 2;
        nb = qdc_realloc(mb->b, cap);
        if (!nb)
            return -1;
        mb->b = nb;
        mb->cap = cap;
    }
    memcpy(mb->b + mb->n, data, len);
    mb->n += len;
    return 0;
}

qdc_status cli_xdmf_h5_write(const char *out, const mesh_t *m, qdc_error *err)
{
    char prog[PATH_MAX + 8], dir[PATH_MAX], name[PATH_MAX], h5out[2 * PATH_MAX];
    char *argv[] = {(char *)h5_program(prog, sizeof prog),
                    "-n",
                    xdmf_h5,
                    "h5-write",
                    xdmf_h5,
                    h5out,
                    "geometry",
                    xdmf_geom,
                    NULL};
    const char *base = strrchr(out, '/');
    char *dot;
    membuf mb = {NULL, 0, 0};
    qdc_status st;

    if (!strcmp(out, "-") || ends_gz(out))
        return qdc_fail(err, QDC_EINVAL,
                        "XDMF with its heavy data in HDF5 is written to a file (not "
                        "compressed), its .h5 file beside it");
    base = base ? base + 1 : out;
    folder_of(out, dir, sizeof dir);
    snprintf(name, sizeof name, "%s", base);
    dot = strrchr(name, '.');
    if (dot && dot != name)
        *dot = '\0';
    if (strlen(name) + 4 >= sizeof name)
        return qdc_fail(err, QDC_EINVAL, "%s: name too long", out);
    strcat(name, ".h5");
    snprintf(h5out, sizeof h5out, "%s%s", dir, name);
    if (!strcmp(h5out, out))
        return qdc_fail(err, QDC_EINVAL,
                        "%s would be both the .xdmf file and its .h5 file: name the "
                        "output .xdmf",
                        out);
    /* the .h5 first: the .xdmf names it */
    st = run_input(argv, -1, m, MESHIO_XDMF, err);
    if (st == QDC_OK)
        st = meshio_xdmf_h5_rename(xdmf_xml, xdmf_len, name, mem_write, &mb, err);
    if (st == QDC_OK)
        st = meshio_save_bytes(out, mb.b, mb.n, err);
    qdc_free(mb.b);
    return st;
}

/* fn(ctx, the text s) as a status */
static qdc_status form_put(qdc_write_fn fn, void *ctx, const char *s, size_t n,
                           qdc_error *err)
{
    return fn(ctx, s, n) ? qdc_fail(err, QDC_ENOMEM, "out of memory") : QDC_OK;
}

qdc_status cli_xdmf_h5_form(const char *name, const char *b, qdc_write_fn fn, void *ctx,
                            qdc_error *err)
{
    const char *xb = strrchr(name, '/'), *hb = strrchr(xdmf_h5, '/');
    char head[2 * PATH_MAX + 400];
    char *h5 = NULL;
    size_t h5_len = 0;
    int n;
    qdc_status st;

    if (!xdmf_xml)
        return qdc_fail(err, QDC_EINVAL, "no XDMF file with HDF5 data was read");
    xb = xb ? xb + 1 : name;
    hb = hb ? hb + 1 : xdmf_h5;
    /* a quote or line break in a name would end the header: not sent */
    if (strpbrk(xb, "\"\r\n") || strpbrk(hb, "\"\r\n"))
        return qdc_fail(err, QDC_EINVAL, "%s: a file name with a quote or line break",
                        name);
    st = cli_slurp(xdmf_h5, &h5, &h5_len, err);
    if (st != QDC_OK)
        return st;
    n = snprintf(head, sizeof head,
                 "--%s\r\nContent-Disposition: form-data; name=\"xdmf\"; "
                 "filename=\"%s\"\r\nContent-Type: application/xml\r\n\r\n",
                 b, xb);
    st = form_put(fn, ctx, head, (size_t)n, err);
    if (st == QDC_OK)
        st = form_put(fn, ctx, xdmf_xml, xdmf_len, err);
    n = snprintf(head, sizeof head,
                 "\r\n--%s\r\nContent-Disposition: form-data; name=\"h5\"; "
                 "filename=\"%s\"\r\nContent-Type: application/x-hdf5\r\n\r\n",
                 b, hb);
    if (st == QDC_OK)
        st = form_put(fn, ctx, head, (size_t)n, err);
    if (st == QDC_OK)
        st = form_put(fn, ctx, h5, h5_len, err);
    n = snprintf(head, sizeof head, "\r\n--%s--\r\n", b);
    if (st == QDC_OK)
        st = form_put(fn, ctx, head, (size_t)n, err);
    qdc_free(h5);
    return st;
}
