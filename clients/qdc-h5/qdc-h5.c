/* qdc-h5.c - the HDF5 side of qdc, a program of its own: libqdc never calls
 * HDF5 (a large parser for untrusted files, with process-wide state: its
 * library init, its error printing), so the qdc command runs this one as a
 * child and talks to it over a pipe in a framed form that libqdc parses
 * (lib/io/meshio_med.c says what it is).
 *
 *   qdc-h5 [-n NAME] med-read FILE.med          the mesh's datasets, framed,
 *                                               on stdout
 *   qdc-h5 [-n NAME] med-write IN.med OUT.med   OUT = IN with its coordinates
 *                                               replaced by the "coords" frame
 *                                               read from stdin
 *
 *   qdc-h5 [-n NAME] h5-read FILE.h5 NAME:T:DIMS:PATH...
 *                       XDMF's heavy data: each dataset PATH, checked to be
 *                       of shape DIMS ("356x3"), as frame NAME of type T
 *   qdc-h5 [-n NAME] h5-write IN.h5 OUT.h5 FRAME PATH
 *                       OUT = IN with dataset PATH replaced by the float64
 *                       frame FRAME read from stdin
 *
 * Options before the command: -i FILE, -o FILE (standard input, output from
 * and to FILE); --sandbox BYTES (qdcd's child: an address-space limit of
 * BYTES, killed with its parent, and no network: a network namespace of its
 * own, when the kernel lets it make one).
 *
 * NAME: what messages call the input (qdc gives a private copy of a .med.gz
 * file as /proc/self/fd/3, and its own name here).
 *
 * MED (Salome, Code_Aster): the first mesh of /ENS_MAA, its first step;
 * NOE/COO (x of every node, then y, then z) and NOE/FAM, MAI/TE4, MAI/T10,
 * MAI/TR3 and MAI/TR6 NOD (node k of every element, then node k + 1;
 * 1-based) and FAM. Frames carry them
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
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

/* What one dataset may hold: a mesh's arrays never come near it; a file that
 * claims more is refused before anything is allocated. */
#define MAX_VALUES ((hssize_t)1 << 31)

static const char magic[8] = {'Q', 'D', 'C', 'H', '5', 'v', '1', '\n'};

/* -n NAME, else NULL: what messages call the input file */
static const char *shown;

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

/* One frame: name, type 'f' (float64) or 'i' (int64), count, values (NULL:
 * the header alone, the caller writes them). */
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
    if (vals)
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

/* fname opened read-only. A link to a deleted file (qdc's private copy,
 * /proc/self/fd/3) is read whole and opened as a file image: HDF5 resolves a
 * link's target by its name, which such a file no longer has. */
static hid_t open_ro(const char *fname)
{
    struct stat sb;
    hid_t f = H5Fopen(fname, H5F_ACC_RDONLY, H5P_DEFAULT), fapl;
    unsigned char *img;
    size_t got = 0;
    int fd;

    if (f >= 0 || lstat(fname, &sb) != 0 || !S_ISLNK(sb.st_mode))
        return f;
    fd = open(fname, O_RDONLY);
    if (fd < 0 || fstat(fd, &sb) != 0 || !S_ISREG(sb.st_mode) || sb.st_size <= 0)
        return -1;
    img = xmalloc((size_t)sb.st_size);
    while (got < (size_t)sb.st_size) {
        ssize_t k = read(fd, img + got, (size_t)sb.st_size - got);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            die("%s: %s", shown ? shown : fname, k ? strerror(errno) : "cut short");
        got += (size_t)k;
    }
    close(fd);
    fapl = H5Pcreate(H5P_FILE_ACCESS);
    if (fapl < 0 || H5Pset_fapl_core(fapl, 1 << 20, 0) < 0 ||
        H5Pset_file_image(fapl, img, got) < 0)
        die("cannot set up an in-memory HDF5 file");
    f = H5Fopen("qdc-h5 image", H5F_ACC_RDONLY, fapl); /* a name, not a file */
    H5Pclose(fapl);
    free(img); /* H5Pset_file_image took a copy */
    return f;
}

/* The value count of dataset d (path), checked against MAX_VALUES. */
static uint64_t values_of(hid_t d, const char *path)
{
    hid_t sp = H5Dget_space(d);
    hssize_t n = sp < 0 ? -1 : H5Sget_simple_extent_npoints(sp);

    if (n < 0 || n > MAX_VALUES)
        die("dataset %s: %lld values (at most %lld)", path, (long long)n,
            (long long)MAX_VALUES);
    H5Sclose(sp);
    return (uint64_t)n;
}

/* HDF5's error stack says it could not allocate memory (under qdcd's
 * --sandbox limit: a chunk larger than the limit, to be inflated whole). */
static herr_t oom_walk(unsigned n, const H5E_error2_t *e, void *flag)
{
    (void)n;
    if (e->min_num == H5E_CANTALLOC || e->min_num == H5E_NOSPACE)
        *(int *)flag = 1;
    return 0;
}

static int h5_oom(void)
{
    int flag = 0;

    H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, oom_walk, &flag);
    return flag;
}

/* Rows of values a block of stream_frame: 256 KiB a column at most. */
#define BLOCK_ROWS ((hsize_t)1 << 15)

/* Dataset d (path) of n values in cols columns (MED's order: all of column
 * 0, then all of column 1...) written as frame name of type t ('f' float64,
 * 'i' int64) with its rows interlaced: a block of rows at a time, each
 * column's part read by HDF5 straight into a small buffer, interlaced into
 * another and written out, so that no copy of the whole dataset is made
 * (allocating and faulting in two of them took most of the time). */
static void stream_frame(hid_t d, const char *path, uint64_t n, int cols, const char *name,
                         char t)
{
    hid_t type = t == 'f' ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64;
    hid_t fs = H5Dget_space(d), ms;
    uint64_t rows = n / (uint64_t)cols;
    uint64_t *col = xmalloc((size_t)BLOCK_ROWS * (size_t)cols * 8);
    uint64_t *out = cols > 1 ? xmalloc((size_t)BLOCK_ROWS * (size_t)cols * 8) : col;

    if (fs < 0 || H5Sget_simple_extent_ndims(fs) != 1)
        die("dataset %s is not a list of values", path);
    frame(name, t, NULL, n);
    for (uint64_t r0 = 0; r0 < rows; r0 += BLOCK_ROWS) {
        hsize_t cnt = rows - r0 < BLOCK_ROWS ? rows - r0 : BLOCK_ROWS;
        ms = H5Screate_simple(1, &cnt, NULL);
        for (int c = 0; c < cols; c++) {
            hsize_t start = (hsize_t)c * rows + r0;
            if (ms < 0 ||
                H5Sselect_hyperslab(fs, H5S_SELECT_SET, &start, NULL, &cnt, NULL) < 0 ||
                H5Dread(d, type, ms, fs, H5P_DEFAULT, col + (size_t)c * cnt) < 0)
                die(h5_oom() ? "out of memory reading dataset %s" : "cannot read dataset %s",
                    path);
        }
        H5Sclose(ms);
        for (hsize_t r = 0; cols > 1 && r < cnt; r++)
            for (int c = 0; c < cols; c++)
                out[r * (hsize_t)cols + (hsize_t)c] = col[(hsize_t)c * cnt + r];
        put_all(out, (size_t)cnt * (size_t)cols * 8);
    }
    H5Sclose(fs);
    if (out != col)
        free(out);
    free(col);
}

/* Values a block of stream_rows: 512 KiB. */
#define BLOCK_VALUES ((hsize_t)1 << 16)

/* Dataset d (path) of n values, of rank dimensions dims, written as frame
 * name of type t ('f' float64, 'i' int64) in its own (row-major) order: a
 * block of rows (along the first dimension) at a time, read by HDF5 into a
 * small buffer and written out, so that no copy of the whole dataset is
 * made (XDMF's heavy data; MED's columns are stream_frame's). A chunked
 * (compressed) dataset's blocks are whole rows of chunks, so that each
 * chunk is inflated once without a chunk cache (meshio writes one chunk a
 * column: 7883 x 1 of a million tets). */
static void stream_rows(hid_t d, const char *path, uint64_t n, int rank,
                        const hsize_t *dims, const char *name, char t)
{
    hid_t type = t == 'f' ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64;
    hid_t fs = H5Dget_space(d), ms, pl = H5Dget_create_plist(d);
    hsize_t rows = rank ? dims[0] : 1, per = 1, start[H5S_MAX_RANK] = {0},
            cnt[H5S_MAX_RANK], ch[H5S_MAX_RANK];
    hsize_t block, m;
    void *buf;

    for (int i = 1; i < rank; i++)
        per *= dims[i];
    block = per && per < BLOCK_VALUES ? BLOCK_VALUES / per : 1;
    if (pl >= 0 && rank && H5Pget_layout(pl) == H5D_CHUNKED &&
        H5Pget_chunk(pl, rank, ch) == rank && ch[0] > 0)
        block = (block + ch[0] - 1) / ch[0] * ch[0];
    if (pl >= 0)
        H5Pclose(pl);
    if (fs < 0)
        die("cannot read dataset %s", path);
    frame(name, t, NULL, n);
    if (!n) {
        H5Sclose(fs);
        return;
    }
    buf = xmalloc((size_t)(block < rows ? block : rows) * (size_t)per * 8);
    for (int i = 1; i < rank; i++)
        cnt[i] = dims[i];
    for (hsize_t r0 = 0; r0 < rows; r0 += block) {
        cnt[0] = rows - r0 < block ? rows - r0 : block;
        start[0] = r0;
        m = cnt[0] * per;
        /* the block's own shape: HDF5 copies a selection of the same shape
         * as runs of values, another shape one value at a time */
        ms = H5Screate_simple(rank ? rank : 1, rank ? cnt : &m, NULL);
        if (ms < 0 ||
            (rank && H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, cnt, NULL) < 0) ||
            H5Dread(d, type, ms, fs, H5P_DEFAULT, buf) < 0)
            die(h5_oom() ? "out of memory reading dataset %s" : "cannot read dataset %s",
                path);
        H5Sclose(ms);
        put_all(buf, (size_t)m * 8);
    }
    H5Sclose(fs);
    free(buf);
}

/* Dataset path (of cols columns, each of rows values when rows > 0) as
 * frame name, or nothing when the file has no such dataset; its row count. */
static uint64_t med_frame(hid_t f, const char *path, int cols, uint64_t rows,
                          const char *name, char t)
{
    hid_t d, dapl;
    uint64_t n;

    if (!exists(f, path))
        return 0;
    /* a chunked (compressed) dataset: its chunks kept once inflated, each
     * column's blocks read from them (by default a chunk over 1 MiB is
     * inflated again for every block); at most the dataset's own size, as a
     * whole read would take */
    dapl = H5Pcreate(H5P_DATASET_ACCESS);
    if (dapl < 0 || H5Pset_chunk_cache(dapl, 10007, (size_t)MAX_VALUES * 8, 1.0) < 0)
        die("cannot set up the reading of %s", path);
    d = H5Dopen2(f, path, dapl);
    H5Pclose(dapl);
    if (d < 0)
        die("cannot open dataset %s", path);
    n = values_of(d, path);
    if (n % (uint64_t)cols)
        die("%s: %llu values, not %d a %s", path, (unsigned long long)n, cols,
            cols == 3 && t == 'f' ? "node" : "element");
    if (rows && n / (uint64_t)cols != rows)
        die("%s: %llu families for %llu %s", path, (unsigned long long)n,
            (unsigned long long)rows, t == 'i' && !strcmp(name, "noe_fam") ? "nodes"
                                                                          : "elements");
    stream_frame(d, path, n, cols, name, t);
    H5Dclose(d);
    return n / (uint64_t)cols;
}

static void med_read(const char *fname)
{
    hid_t f = open_ro(fname);
    const char *file = shown ? shown : fname;
    /* tetrahedra, and triangles: the boundary's (their families its refs) */
    static const char *const types[4] = {"TE4", "T10", "TR3", "TR6"};
    static const char *const names[4] = {"te4", "t10", "tr3", "tr6"};
    static const int nodes[4] = {4, 10, 3, 6};
    char base[1100], path[1200], fam[16];
    uint64_t nv, ne;
    int dim;

    if (f < 0)
        die("%s: not an HDF5 file, or unreadable", file);
    mesh_base(f, base, sizeof base, &dim);
    if (dim != 3)
        die("%s: a mesh of dimension %d: qdc reads 3D meshes", file, dim);
    snprintf(path, sizeof path, "%s/NOE/COO", base);
    if (!exists(f, path))
        die("cannot open dataset %s", path);
    put_all(magic, sizeof magic);
    nv = med_frame(f, path, 3, 0, "coords", 'f');
    /* the node families (NOE/FAM) */
    snprintf(path, sizeof path, "%s/NOE/FAM", base);
    med_frame(f, path, 1, nv, "noe_fam", 'i');
    for (int k = 0; k < 4; k++) {
        snprintf(path, sizeof path, "%s/MAI/%s/NOD", base, types[k]);
        ne = med_frame(f, path, nodes[k], 0, names[k], 'i');
        if (!ne)
            continue;
        snprintf(path, sizeof path, "%s/MAI/%s/FAM", base, types[k]);
        snprintf(fam, sizeof fam, "%s_fam", names[k]);
        med_frame(f, path, 1, ne, fam, 'i');
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

/* The values of the frame named want in the framed data of stdin (b, len):
 * a pointer into b and their count. */
static const unsigned char *stdin_frame(const unsigned char *b, size_t len,
                                        const char *want, uint64_t *count)
{
    size_t pos = sizeof magic;
    const unsigned char *vals = NULL;

    if (len < sizeof magic || memcmp(b, magic, sizeof magic) != 0)
        die("standard input is not framed data");
    while (len - pos >= 32) {
        uint64_t c = le64(b + pos + 24);
        uint64_t words = b[pos + 16] == 'b' ? c / 8 + (c % 8 != 0) : c;
        if (words > (len - pos - 32) / 8)
            die("a frame runs past the end of the input");
        if (strncmp((const char *)b + pos, want, 16) == 0 && b[pos + 16] == 'f') {
            vals = b + pos + 32;
            *count = c;
        }
        pos += 32 + (size_t)words * 8;
    }
    if (!vals)
        die("no frame %s in the input", want);
    return vals;
}

/* A copy of in beside out (its temporary name into tmp), opened read-write. */
static hid_t open_copy(const char *in, const char *out, char *tmp, size_t size)
{
    int fd;
    hid_t f;

    if (snprintf(tmp, size, "%s.qdc-h5.XXXXXX", out) >= (int)size)
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
        die("%s: not an HDF5 file", shown ? shown : in);
    }
    return f;
}

/* n doubles (vals, native order) over the dataset path of the copy f. */
static void put_dataset(hid_t f, const char *tmp, const char *path, const double *vals,
                        uint64_t n, const char *in)
{
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    hid_t sp = d < 0 ? -1 : H5Dget_space(d);

    if (sp < 0 || H5Sget_simple_extent_npoints(sp) != (hssize_t)n) {
        unlink(tmp);
        die("%s: %s: the coordinates given are not as many as the file's",
            shown ? shown : in, path);
    }
    if (H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, vals) < 0) {
        unlink(tmp);
        die("cannot write %s", path);
    }
    H5Sclose(sp);
    H5Dclose(d);
}

/* Close the copy f and rename it over out. */
static void close_copy(hid_t f, const char *tmp, const char *out)
{
    int fd;

    if (H5Fclose(f) < 0) {
        unlink(tmp);
        die("cannot close %s", tmp);
    }
    fd = open(tmp, O_RDONLY);
    if (fd < 0 || fsync(fd) != 0 || close(fd) != 0 || rename(tmp, out) != 0) {
        unlink(tmp);
        die("cannot save %s: %s", out, strerror(errno));
    }
}

static void med_write(const char *in, const char *out)
{
    size_t len;
    unsigned char *b = slurp_stdin(&len);
    const unsigned char *xyz;
    uint64_t n = 0;
    char tmp[4200], base[1100], path[1200];
    int dim;
    hid_t f;
    double *cols;

    xyz = stdin_frame(b, len, "coords", &n);
    if (n % 3)
        die("no coordinates in the input");
    f = open_copy(in, out, tmp, sizeof tmp);
    mesh_base(f, base, sizeof base, &dim);
    snprintf(path, sizeof path, "%s/NOE/COO", base);
    cols = xmalloc((size_t)n * 8);
    for (uint64_t v = 0; v < n / 3; v++)
        for (int a = 0; a < 3; a++) {
            uint64_t u = le64(xyz + 8 * (3 * v + (uint64_t)a));
            memcpy(&cols[(uint64_t)a * (n / 3) + v], &u, 8);
        }
    put_dataset(f, tmp, path, cols, n, in);
    free(cols);
    close_copy(f, tmp, out);
    free(b);
}

/* XDMF's heavy data: the datasets specs name ("NAME:T:DIMS:PATH", T 'f',
 * 'i' or 'a', either, framed as the dataset's class; DIMS "356x3" as the XDMF
 * gives them), each checked to have that shape, framed as NAME on stdout. */
static void h5_read(const char *fname, int nspec, char **spec)
{
    const char *file = shown ? shown : fname;
    struct stat sb;
    hid_t f;

    if (stat(fname, &sb) != 0)
        die("%s: %s", file, strerror(errno));
    f = H5Fopen(fname, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0)
        die("%s: not an HDF5 file, or unreadable", file);
    put_all(magic, sizeof magic);
    for (int k = 0; k < nspec; k++) {
        char name[17], want[160] = "", have[160] = "";
        const char *p = spec[k], *c1 = strchr(p, ':'), *c2, *c3, *path;
        hsize_t dims[H5S_MAX_RANK];
        unsigned long long xd[4];
        int rank, nd = 0, same;
        hid_t d, sp, ty;
        H5T_class_t cls;
        c2 = c1 ? strchr(c1 + 1, ':') : NULL;
        c3 = c2 ? strchr(c2 + 1, ':') : NULL;
        if (!c3 || c1 - p > 16 || c2 != c1 + 2 ||
            (c1[1] != 'f' && c1[1] != 'i' && c1[1] != 'a'))
            die("bad dataset spec %s (NAME:T:DIMS:PATH)", p);
        snprintf(name, sizeof name, "%.*s", (int)(c1 - p), p);
        for (const char *q = c2 + 1; q < c3 && nd < 4; nd++) {
            char *e;
            xd[nd] = strtoull(q, &e, 10);
            if (e == q || (e < c3 && *e != 'x'))
                die("bad dataset spec %s (NAME:T:DIMS:PATH)", p);
            snprintf(want + strlen(want), sizeof want - strlen(want), "%s%llu",
                     nd ? " x " : "", xd[nd]);
            q = e < c3 ? e + 1 : c3;
        }
        path = c3 + 1;
        d = H5Dopen2(f, path, H5P_DEFAULT);
        if (d < 0)
            die("%s: no dataset %s", file, path);
        sp = H5Dget_space(d);
        rank = sp < 0 ? -1 : H5Sget_simple_extent_ndims(sp);
        if (rank < 0 || rank > H5S_MAX_RANK ||
            H5Sget_simple_extent_dims(sp, dims, NULL) < 0)
            die("%s:%s: cannot read its shape", file, path);
        same = rank == nd;
        for (int i = 0; i < rank; i++) {
            snprintf(have + strlen(have), sizeof have - strlen(have), "%s%llu",
                     i ? " x " : "", (unsigned long long)dims[i]);
            same = same && i < nd && dims[i] == xd[i];
        }
        if (!same)
            die("%s:%s: a dataset of shape %s, where the XDMF says %s", file, path,
                rank ? have : "(scalar)", want);
        ty = H5Dget_type(d);
        cls = ty < 0 ? H5T_NO_CLASS : H5Tget_class(ty);
        if (cls != H5T_INTEGER && (cls != H5T_FLOAT || c1[1] == 'i'))
            die("%s:%s: a dataset of %s, where numbers%s are expected", file, path,
                cls == H5T_FLOAT ? "floating-point numbers" : "another type",
                c1[1] == 'i' ? " (integers)" : "");
        H5Tclose(ty);
        H5Sclose(sp);
        /* 'a': the frame's type says the class (integers 'i', else 'f') */
        stream_rows(d, path, values_of(d, path), rank, dims, name,
                    c1[1] != 'a' ? c1[1] : cls == H5T_INTEGER ? 'i' : 'f');
        H5Dclose(d);
    }
    H5Fclose(f);
    if (fflush(stdout) != 0)
        die("cannot write to standard output: %s", strerror(errno));
}

/* OUT = IN with the dataset path replaced by the float64 frame named fname
 * of stdin (XDMF's geometry: the values in the dataset's own order). */
static void h5_write(const char *in, const char *out, const char *fname,
                     const char *path)
{
    size_t len;
    unsigned char *b = slurp_stdin(&len);
    const unsigned char *raw;
    uint64_t n = 0;
    char tmp[4200];
    double *vals;
    hid_t f;

    raw = stdin_frame(b, len, fname, &n);
    vals = xmalloc((size_t)n * 8);
    for (uint64_t i = 0; i < n; i++) {
        uint64_t u = le64(raw + 8 * i);
        memcpy(&vals[i], &u, 8);
    }
    f = open_copy(in, out, tmp, sizeof tmp);
    put_dataset(f, tmp, path, vals, n, in);
    free(vals);
    close_copy(f, tmp, out);
    free(b);
}

int main(int argc, char **argv)
{
    const uint16_t one = 1;

    if (*(const unsigned char *)&one != 1)
        die("big-endian hosts are not supported");
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* errors as our own one line */
    while (argc > 2 && argv[1][0] == '-') {
        const char *o = argv[1], *v = argv[2];
        if (!strcmp(o, "-n")) {
            shown = v;
        } else if (!strcmp(o, "-i") || !strcmp(o, "-o")) {
            if (!freopen(v, o[1] == 'i' ? "rb" : "wb", o[1] == 'i' ? stdin : stdout))
                die("%s: %s", v, strerror(errno));
        } else if (!strcmp(o, "--sandbox")) {
            struct rlimit rl;
            char *end;
            rl.rlim_cur = rl.rlim_max = (rlim_t)strtoull(v, &end, 10);
            if (*end || !rl.rlim_cur)
                die("bad value for --sandbox: %s", v);
            prctl(PR_SET_PDEATHSIG, SIGKILL);
            if (getppid() == 1)
                die("the parent is gone");
            /* no network: a namespace of its own (root), or with a user
             * namespace (unprivileged), when the kernel allows either */
            if (unshare(CLONE_NEWNET) != 0)
                (void)unshare(CLONE_NEWUSER | CLONE_NEWNET);
            if (setrlimit(RLIMIT_AS, &rl) != 0)
                die("cannot limit memory: %s", strerror(errno));
        } else {
            break;
        }
        argc -= 2;
        argv += 2;
    }
    if (argc == 3 && strcmp(argv[1], "med-read") == 0)
        med_read(argv[2]);
    else if (argc == 4 && strcmp(argv[1], "med-write") == 0)
        med_write(argv[2], argv[3]);
    else if (argc >= 3 && strcmp(argv[1], "h5-read") == 0)
        h5_read(argv[2], argc - 3, argv + 3);
    else if (argc == 6 && strcmp(argv[1], "h5-write") == 0)
        h5_write(argv[2], argv[3], argv[4], argv[5]);
    else
        die("usage (options: -n NAME, -i FILE, -o FILE, --sandbox BYTES): qdc-h5 [-n NAME] med-read FILE.med > FRAMES | qdc-h5 [-n NAME] "
            "med-write IN.med OUT.med < FRAMES | qdc-h5 [-n NAME] h5-read FILE.h5 "
            "NAME:T:DIMS:PATH... > FRAMES | qdc-h5 [-n NAME] h5-write IN.h5 OUT.h5 "
            "FRAME PATH < FRAMES");
    return 0;
}
