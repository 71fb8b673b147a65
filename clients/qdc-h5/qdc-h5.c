/* qdc-h5.c - the HDF5 side of qdc, a program of its own: libqdc never calls
 * HDF5 (a large parser for untrusted files, with process-wide state: its
 * library init, its error printing), so the qdc command runs this one as a
 * child and talks to it over a pipe in a framed form that libqdc parses
 * (lib/io/meshio_med.c says what it is).
 *
 *   qdc-h5 med-read FILE.med          the mesh's datasets, framed, on stdout
 *   qdc-h5 med-write IN.med OUT.med   OUT = IN with its coordinates replaced
 *                                     by the "coords" frame read from stdin
 *
 * MED (Salome, Code_Aster): the first mesh of /ENS_MAA, its first step;
 * NOE/COO (x of every node, then y, then z), MAI/TE4 and MAI/T10 NOD (node k
 * of every element, then node k + 1; 1-based) and FAM. Frames carry them
 * interlaced (x y z a node, the nodes of an element together), as int64 and
 * float64, little-endian. Exit status 0, or 1 with one line "qdc-h5: ..." on
 * stderr. */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <hdf5.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* What one dataset may hold: a mesh's arrays never come near it; a file that
 * claims more is refused before anything is allocated. */
#define MAX_VALUES ((hssize_t)1 << 31)

static const char magic[8] = {'Q', 'D', 'C', 'H', '5', 'v', '1', '\n'};

static void die(const char *fmt, ...) __attribute__((noreturn, format(printf, 1, 2)));

static void die(const char *fmt, ...)
{
    va_list ap;

    fputs("qdc-h5: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    exit(1);
}

static void *xmalloc(size_t n)
{
    void *p = malloc(n ? n : 1);

    if (!p)
        die("out of memory for %zu bytes", n);
    return p;
}

static void put_all(const void *p, size_t n)
{
    if (fwrite(p, 1, n, stdout) != n)
        die("cannot write to standard output: %s", strerror(errno));
}

/* One frame: name, type 'f' (float64) or 'i' (int64), count, values. */
static void frame(const char *name, char type, const void *vals, uint64_t count)
{
    unsigned char h[32];

    memset(h, 0, sizeof h);
    strncpy((char *)h, name, 16);
    h[16] = (unsigned char)type;
    for (int k = 0; k < 8; k++)
        h[24 + k] = (unsigned char)(count >> (8 * k));
    put_all(h, sizeof h);
    /* little-endian hosts only (checked in main) */
    put_all(vals, (size_t)count * 8);
}

/* 1 if every group on the way to path and path itself exist. */
static int exists(hid_t f, const char *path)
{
    char buf[1024];
    size_t n = strlen(path);

    if (n >= sizeof buf)
        return 0;
    memcpy(buf, path, n + 1);
    for (size_t i = 1; i <= n; i++)
        if (buf[i] == '/' || buf[i] == '\0') {
            char c = buf[i];
            buf[i] = '\0';
            if (H5Lexists(f, buf, H5P_DEFAULT) <= 0)
                return 0;
            buf[i] = c;
        }
    return 1;
}

/* The name of the first link in group path, into out. */
static herr_t first_name(hid_t g, const char *name, const H5L_info_t *info, void *out)
{
    (void)g;
    (void)info;
    snprintf(out, 256, "%s", name);
    return 1; /* stop */
}

static void first_in(hid_t f, const char *path, char out[256])
{
    hid_t g = H5Gopen2(f, path, H5P_DEFAULT);
    hsize_t idx = 0;

    out[0] = '\0';
    if (g < 0)
        die("no group %s: not a MED file", path);
    if (H5Literate(g, H5_INDEX_NAME, H5_ITER_INC, &idx, first_name, out) < 0 || !out[0])
        die("group %s is empty", path);
    H5Gclose(g);
}

/* The whole dataset path as type (H5T_NATIVE_DOUBLE or H5T_NATIVE_INT64):
 * a new array and its size. */
static void *read_all(hid_t f, const char *path, hid_t type, uint64_t *count)
{
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT), sp;
    hssize_t n;
    void *buf;

    if (d < 0)
        die("cannot open dataset %s", path);
    sp = H5Dget_space(d);
    n = sp < 0 ? -1 : H5Sget_simple_extent_npoints(sp);
    if (n < 0 || n > MAX_VALUES)
        die("dataset %s: %lld values (at most %lld)", path, (long long)n,
            (long long)MAX_VALUES);
    buf = xmalloc((size_t)n * 8);
    if (n && H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0)
        die("cannot read dataset %s", path);
    H5Sclose(sp);
    H5Dclose(d);
    *count = (uint64_t)n;
    return buf;
}

/* Columns to rows: in holds `cols` runs of `rows` values (MED's
 * non-interlaced order), out gets rows of cols. */
static void *interlace(const void *in, uint64_t rows, int cols)
{
    const uint64_t *a = in;
    uint64_t *b = xmalloc((size_t)(rows * (uint64_t)cols) * 8);

    for (uint64_t r = 0; r < rows; r++)
        for (int c = 0; c < cols; c++)
            b[r * (uint64_t)cols + (uint64_t)c] = a[(uint64_t)c * rows + r];
    return b;
}

/* "/ENS_MAA/<first mesh>/<its first step>" */
static void mesh_base(hid_t f, char *base, size_t size, int *dim)
{
    char mesh[256], step[256], path[600];
    hid_t g, a;
    int esp = 3;

    first_in(f, "/ENS_MAA", mesh);
    snprintf(path, sizeof path, "/ENS_MAA/%s", mesh);
    g = H5Gopen2(f, path, H5P_DEFAULT);
    if (g >= 0 && H5Aexists(g, "ESP") > 0) {
        a = H5Aopen(g, "ESP", H5P_DEFAULT);
        if (a < 0 || H5Aread(a, H5T_NATIVE_INT, &esp) < 0)
            die("mesh %s: cannot read its dimension (ESP)", mesh);
        H5Aclose(a);
    }
    if (g >= 0)
        H5Gclose(g);
    first_in(f, path, step);
    snprintf(base, size, "%s/%s", path, step);
    *dim = esp;
}

static void med_read(const char *file)
{
    hid_t f = H5Fopen(file, H5F_ACC_RDONLY, H5P_DEFAULT);
    static const char *const types[2] = {"TE4", "T10"};
    static const int nodes[2] = {4, 10};
    char base[1100], path[1200];
    uint64_t n;
    void *raw, *rows;
    int dim;

    if (f < 0)
        die("%s: not an HDF5 file, or unreadable", file);
    mesh_base(f, base, sizeof base, &dim);
    if (dim != 3)
        die("%s: a mesh of dimension %d: qdc reads 3D meshes", file, dim);
    snprintf(path, sizeof path, "%s/NOE/COO", base);
    raw = read_all(f, path, H5T_NATIVE_DOUBLE, &n);
    if (n % 3)
        die("%s: %llu coordinates, not 3 a node", path, (unsigned long long)n);
    rows = interlace(raw, n / 3, 3);
    put_all(magic, sizeof magic);
    frame("coords", 'f', rows, n);
    free(raw);
    free(rows);
    for (int k = 0; k < 2; k++) {
        uint64_t ne, nf;
        snprintf(path, sizeof path, "%s/MAI/%s/NOD", base, types[k]);
        if (!exists(f, path))
            continue;
        raw = read_all(f, path, H5T_NATIVE_INT64, &n);
        if (n % (uint64_t)nodes[k])
            die("%s: %llu nodes, not %d an element", path, (unsigned long long)n,
                nodes[k]);
        ne = n / (uint64_t)nodes[k];
        rows = interlace(raw, ne, nodes[k]);
        frame(k ? "t10" : "te4", 'i', rows, n);
        free(raw);
        free(rows);
        snprintf(path, sizeof path, "%s/MAI/%s/FAM", base, types[k]);
        if (!exists(f, path))
            continue;
        raw = read_all(f, path, H5T_NATIVE_INT64, &nf);
        if (nf != ne)
            die("%s: %llu families for %llu elements", path, (unsigned long long)nf,
                (unsigned long long)ne);
        frame(k ? "t10_fam" : "te4_fam", 'i', raw, nf);
        free(raw);
    }
    H5Fclose(f);
    if (fflush(stdout) != 0)
        die("cannot write to standard output: %s", strerror(errno));
}

/* All of standard input. */
static unsigned char *slurp_stdin(size_t *len)
{
    size_t cap = 1 << 20, n = 0;
    unsigned char *b = xmalloc(cap);

    for (;;) {
        size_t got = fread(b + n, 1, cap - n, stdin);
        n += got;
        if (n < cap) {
            if (ferror(stdin))
                die("cannot read standard input");
            break;
        }
        cap *= 2;
        b = realloc(b, cap);
        if (!b)
            die("out of memory for the input");
    }
    *len = n;
    return b;
}

static uint64_t le64(const unsigned char *p)
{
    uint64_t v = 0;

    for (int k = 7; k >= 0; k--)
        v = v << 8 | p[k];
    return v;
}

static void copy_file(const char *from, int to)
{
    int fd = open(from, O_RDONLY);
    char buf[1 << 16];
    ssize_t n;

    if (fd < 0)
        die("%s: %s", from, strerror(errno));
    while ((n = read(fd, buf, sizeof buf)) > 0)
        if (write(to, buf, (size_t)n) != n)
            die("cannot write the copy: %s", strerror(errno));
    if (n < 0)
        die("%s: %s", from, strerror(errno));
    close(fd);
}

static void med_write(const char *in, const char *out)
{
    size_t len, pos = sizeof magic;
    unsigned char *b = slurp_stdin(&len);
    const unsigned char *xyz = NULL;
    uint64_t n = 0;
    char tmp[4200], base[1100], path[1200];
    int fd, dim;
    hid_t f, d, sp;
    double *cols;

    if (len < sizeof magic || memcmp(b, magic, sizeof magic) != 0)
        die("standard input is not framed data");
    while (len - pos >= 32) {
        uint64_t c = le64(b + pos + 24);
        if (c > (len - pos - 32) / 8)
            die("a frame runs past the end of the input");
        if (strncmp((const char *)b + pos, "coords", 16) == 0) {
            xyz = b + pos + 32;
            n = c;
        }
        pos += 32 + (size_t)c * 8;
    }
    if (!xyz || n % 3)
        die("no coordinates in the input");
    if (snprintf(tmp, sizeof tmp, "%s.qdc-h5.XXXXXX", out) >= (int)sizeof tmp)
        die("%s: name too long", out);
    fd = mkstemp(tmp);
    if (fd < 0)
        die("cannot create a file beside %s: %s", out, strerror(errno));
    if (fchmod(fd, 0644) != 0)
        die("cannot set the mode of %s: %s", tmp, strerror(errno));
    copy_file(in, fd);
    if (close(fd) != 0)
        die("cannot write %s: %s", tmp, strerror(errno));
    f = H5Fopen(tmp, H5F_ACC_RDWR, H5P_DEFAULT);
    if (f < 0) {
        unlink(tmp);
        die("%s: not an HDF5 file", in);
    }
    mesh_base(f, base, sizeof base, &dim);
    snprintf(path, sizeof path, "%s/NOE/COO", base);
    d = H5Dopen2(f, path, H5P_DEFAULT);
    sp = d < 0 ? -1 : H5Dget_space(d);
    if (sp < 0 || H5Sget_simple_extent_npoints(sp) != (hssize_t)n) {
        unlink(tmp);
        die("%s: the coordinates given are not as many as the file's", in);
    }
    cols = xmalloc((size_t)n * 8);
    for (uint64_t v = 0; v < n / 3; v++)
        for (int a = 0; a < 3; a++) {
            uint64_t u = le64(xyz + 8 * (3 * v + (uint64_t)a));
            memcpy(&cols[(uint64_t)a * (n / 3) + v], &u, 8);
        }
    if (H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, cols) < 0) {
        unlink(tmp);
        die("cannot write %s", path);
    }
    free(cols);
    H5Sclose(sp);
    H5Dclose(d);
    if (H5Fclose(f) < 0) {
        unlink(tmp);
        die("cannot close %s", tmp);
    }
    fd = open(tmp, O_RDONLY);
    if (fd < 0 || fsync(fd) != 0 || close(fd) != 0 || rename(tmp, out) != 0) {
        unlink(tmp);
        die("cannot save %s: %s", out, strerror(errno));
    }
    free(b);
}

int main(int argc, char **argv)
{
    const uint16_t one = 1;

    if (*(const unsigned char *)&one != 1)
        die("big-endian hosts are not supported");
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* errors as our own one line */
    if (argc == 3 && strcmp(argv[1], "med-read") == 0)
        med_read(argv[2]);
    else if (argc == 4 && strcmp(argv[1], "med-write") == 0)
        med_write(argv[2], argv[3]);
    else
        die("usage: qdc-h5 med-read FILE.med > FRAMES | qdc-h5 med-write IN.med OUT.med "
            "< FRAMES");
    return 0;
}
