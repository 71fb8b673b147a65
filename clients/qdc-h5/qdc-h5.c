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
 *   qdc-h5 med-new OUT.med                      OUT: a new MED file (MED-fichier
 *                                               4.1's layout) of the whole mesh
 *                                               framed on stdin (qdc's MED
 *                                               writer's frames: coords, te4 or
 *                                               t10, tr3 or tr6, their _fam,
 *                                               noe_fam, families)
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
 * 1-based) and FAM, and the families' group names (/FAS/<mesh>: ELEME,
 * NOEUD) as the "families" frame, lines "NUMBER GROUP". Frames carry them
 * interlaced (x y z a node, the nodes of an element together), as int64 and
 * float64, little-endian. Exit status 0, or 1 with one line "qdc-h5: ..." on
 * stderr. */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <hdf5.h>
#include <sched.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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
/* a file being made, removed if we die (med-new's) */
static char *made;

static void die(const char *fmt, ...) __attribute__((noreturn, format(printf, 1, 2)));

static void die(const char *fmt, ...)
{
    va_list ap;

    fputs("qdc-h5: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    if (made)
        unlink(made);
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
static void stream_frame(hid_t d, const char *path, uint64_t n, int cols,
                         const char *name, char t)
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
                die(h5_oom() ? "out of memory reading dataset %s"
                             : "cannot read dataset %s",
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
            (rank &&
             H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, cnt, NULL) < 0) ||
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
            (unsigned long long)rows,
            t == 'i' && !strcmp(name, "noe_fam") ? "nodes" : "elements");
    stream_frame(d, path, n, cols, name, t);
    H5Dclose(d);
    return n / (uint64_t)cols;
}

/* A growing text (the "families" frame). */
typedef struct {
    char *b;
    size_t n, cap;
} text;

static void text_put(text *t, const char *s, size_t n)
{
    if (t->cap - t->n < n) {
        while (t->cap - t->n < n)
            t->cap = t->cap ? 2 * t->cap : 4096;
        t->b = realloc(t->b, t->cap);
        if (!t->b)
            die("out of memory for the families");
    }
    memcpy(t->b + t->n, s, n);
    t->n += n;
}

/* The names of the links of a group, collected (at most 1 << 20). */
typedef struct {
    char **name;
    size_t n, cap;
} linklist;

static herr_t collect(hid_t g, const char *name, const H5L_info_t *info, void *ctx)
{
    linklist *l = ctx;

    (void)g;
    (void)info;
    if (l->n == l->cap) {
        if (l->cap >= (size_t)1 << 20)
            return 1;
        l->cap = l->cap ? 2 * l->cap : 64;
        l->name = realloc(l->name, l->cap * sizeof *l->name);
        if (!l->name)
            die("out of memory for the families");
    }
    l->name[l->n] = strdup(name);
    if (!l->name[l->n])
        die("out of memory for the families");
    l->n++;
    return 0;
}

/* Each family under group path (ELEME or NOEUD of /FAS/<mesh>) as lines
 * "NUM GROUP" into t: its NUM attribute, the names of GRO/NOM (fixed-size
 * names, MED's 80 bytes), their trailing blanks and NULs dropped and other
 * control bytes made '?', so that a line stays a line. */
static void families_of(hid_t f, const char *path, text *t)
{
    hid_t g = exists(f, path) ? H5Gopen2(f, path, H5P_DEFAULT) : -1;
    hsize_t idx = 0;
    linklist l = {NULL, 0, 0};

    if (g < 0)
        return;
    H5Literate(g, H5_INDEX_NAME, H5_ITER_INC, &idx, collect, &l);
    for (size_t i = 0; i < l.n; i++) {
        hid_t fam = H5Gopen2(g, l.name[i], H5P_DEFAULT), a, d, ty, sp;
        long long num = 0;
        size_t size;
        hssize_t n;
        char *buf, head[32];
        free(l.name[i]);
        if (fam < 0)
            continue;
        a = H5Aexists(fam, "NUM") > 0 ? H5Aopen(fam, "NUM", H5P_DEFAULT) : -1;
        d = H5Lexists(fam, "GRO", H5P_DEFAULT) > 0 &&
                    H5Lexists(fam, "GRO/NOM", H5P_DEFAULT) > 0
                ? H5Dopen2(fam, "GRO/NOM", H5P_DEFAULT)
                : -1;
        if (a < 0 || H5Aread(a, H5T_NATIVE_LLONG, &num) < 0 || d < 0) {
            if (a >= 0)
                H5Aclose(a);
            if (d >= 0)
                H5Dclose(d);
            H5Gclose(fam);
            continue;
        }
        H5Aclose(a);
        ty = H5Dget_type(d);
        sp = H5Dget_space(d);
        size = ty < 0 ? 0 : H5Tget_size(ty);
        n = sp < 0 ? -1 : H5Sget_simple_extent_npoints(sp);
        /* MED's names: 80 bytes; a dataset far off that is no group list */
        if (size == 0 || size > 4096 || n < 0 || n > 100000)
            die("family %s: its group names are not a list of names", path);
        buf = xmalloc((size_t)n * size);
        if (n && H5Dread(d, ty, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0)
            die("cannot read the group names of a family under %s", path);
        for (hssize_t k = 0; k < n; k++) {
            char *nm = buf + (size_t)k * size;
            size_t len = size;
            while (len && (nm[len - 1] == ' ' || nm[len - 1] == '\0'))
                len--;
            for (size_t c = 0; c < len; c++)
                if ((unsigned char)nm[c] < 0x20)
                    nm[c] = '?';
            text_put(t, head, (size_t)snprintf(head, sizeof head, "%lld ", num));
            text_put(t, nm, len);
            text_put(t, "\n", 1);
        }
        free(buf);
        H5Tclose(ty);
        H5Sclose(sp);
        H5Dclose(d);
        H5Gclose(fam);
    }
    free(l.name);
    H5Gclose(g);
}

/* The "families" frame of the first mesh (mesh): its element and node
 * families (/FAS/<mesh>; MED 2's under the mesh's own group), when any has
 * a group. */
static void med_families(hid_t f, const char *mesh)
{
    static const char *const where[2] = {"/FAS/%s/%s", "/ENS_MAA/%s/FAS/%s"};
    static const char *const kinds[2] = {"ELEME", "NOEUD"};
    static const unsigned char zero[8] = {0};
    char path[700];
    text t = {NULL, 0, 0};

    for (int w = 0; w < 2 && !t.n; w++)
        for (int k = 0; k < 2; k++) {
            snprintf(path, sizeof path, where[w], mesh, kinds[k]);
            families_of(f, path, &t);
        }
    if (!t.n)
        return;
    frame("families", 'b', NULL, t.n);
    put_all(t.b, t.n);
    put_all(zero, (8 - t.n % 8) % 8);
    free(t.b);
}

static void med_read(const char *fname)
{
    hid_t f = open_ro(fname);
    const char *file = shown ? shown : fname;
    /* tetrahedra, and triangles: the boundary's (their families its refs) */
    static const char *const types[4] = {"TE4", "T10", "TR3", "TR6"};
    static const char *const names[4] = {"te4", "t10", "tr3", "tr6"};
    static const int nodes[4] = {4, 10, 3, 6};
    char base[1100], path[1200], fam[16], mesh[256];
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
    first_in(f, "/ENS_MAA", mesh);
    med_families(f, mesh);
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

/* The values of the frame named want of type type in the framed data of
 * stdin (b, len): a pointer into b and their count; NULL if there is none. */
static const unsigned char *find_frame(const unsigned char *b, size_t len,
                                       const char *want, char type, uint64_t *count)
{
    size_t pos = sizeof magic;
    const unsigned char *vals = NULL;

    if (len < sizeof magic || memcmp(b, magic, sizeof magic) != 0)
        die("standard input is not framed data");
    *count = 0;
    while (len - pos >= 32) {
        uint64_t c = le64(b + pos + 24);
        uint64_t words = b[pos + 16] == 'b' ? c / 8 + (c % 8 != 0) : c;
        if (words > (len - pos - 32) / 8)
            die("a frame runs past the end of the input");
        if (strncmp((const char *)b + pos, want, 16) == 0 && b[pos + 16] == type) {
            vals = b + pos + 32;
            *count = c;
        }
        pos += 32 + (size_t)words * 8;
    }
    return vals;
}

/* The float64 frame named want of stdin (b, len), which must be there. */
static const unsigned char *stdin_frame(const unsigned char *b, size_t len,
                                        const char *want, uint64_t *count)
{
    const unsigned char *vals = find_frame(b, len, want, 'f', count);

    if (!vals)
        die("no frame %s in the input", want);
    return vals;
}

/* A new file beside out, mode 0644, its temporary name into tmp (mkstemp's
 * template): the descriptor, open for writing. */
static int temp_beside(const char *out, char *tmp, size_t size)
{
    int fd;

    if (snprintf(tmp, size, "%s.qdc-h5.XXXXXX", out) >= (int)size)
        die("%s: name too long", out);
    fd = mkstemp(tmp);
    if (fd < 0)
        die("cannot create a file beside %s: %s", out, strerror(errno));
    if (fchmod(fd, 0644) != 0)
        die("cannot set the mode of %s: %s", tmp, strerror(errno));
    return fd;
}

/* A copy of in beside out (its temporary name into tmp), opened read-write. */
static hid_t open_copy(const char *in, const char *out, char *tmp, size_t size)
{
    int fd = temp_beside(out, tmp, size);
    hid_t f;

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

/* ------------------------------------------------------------------------ */
/* med-new: a MED file of its own for a whole mesh                          */

/* What MED-fichier 4.1 writes (MEDfileOpen, MEDmeshCr...), so that Salome,
 * Code_Aster and Gmsh take the file as one of theirs: integers as int32
 * (med_int), strings NUL-ended, the version 4.1.0, an HDF5 file of the 1.8
 * format (superblock 2), the computation step "no step" (NDT = NOR = -1),
 * profiles MED_NO_PROFILE_INTERNAL. */
#define MED_PROFILE "MED_NO_PROFILE_INTERNAL"
#define MED_STEP "-0000000000000000001-0000000000000000001"
/* MED's geometry codes (med.h: MED_TETRA4 ...) */
enum { GEO_TR3 = 203, GEO_TR6 = 206, GEO_TE4 = 304, GEO_T10 = 310 };
/* the length of a group name (MED_LNAME_SIZE) and of a family's (MED_NAME_SIZE) */
enum { MED_LNAME = 80, MED_NAME = 64 };

/* A scalar attribute: v's value of memory type mt, stored as ft. */
static void attr_scalar(hid_t o, const char *name, hid_t ft, hid_t mt, const void *v)
{
    hid_t sp = H5Screate(H5S_SCALAR);
    hid_t a = sp < 0 ? -1 : H5Acreate2(o, name, ft, sp, H5P_DEFAULT, H5P_DEFAULT);

    if (a < 0 || H5Awrite(a, mt, v) < 0)
        die("cannot write attribute %s", name);
    H5Aclose(a);
    H5Sclose(sp);
}

static void attr_int(hid_t o, const char *name, int v)
{
    attr_scalar(o, name, H5T_STD_I32LE, H5T_NATIVE_INT, &v);
}

static void attr_real(hid_t o, const char *name, double v)
{
    attr_scalar(o, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &v);
}

/* A string attribute as MED writes one: its length and a NUL. */
static void attr_str(hid_t o, const char *name, const char *v)
{
    hid_t ty = H5Tcopy(H5T_C_S1), sp = H5Screate(H5S_SCALAR), a = -1;

    if (ty >= 0 && sp >= 0 && H5Tset_size(ty, strlen(v) + 1) >= 0 &&
        H5Tset_strpad(ty, H5T_STR_NULLTERM) >= 0)
        a = H5Acreate2(o, name, ty, sp, H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0 || H5Awrite(a, ty, v) < 0)
        die("cannot write attribute %s", name);
    H5Aclose(a);
    H5Sclose(sp);
    H5Tclose(ty);
}

static hid_t new_group(hid_t at, const char *name)
{
    hid_t g = H5Gcreate2(at, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);

    if (g < 0)
        die("cannot create group %s", name);
    return g;
}

/* The frame of int64 values vals, rows of cols (interlaced, as framed),
 * written as dataset name of group g in MED's order (column 0 of every row,
 * then column 1...) as int32, a column at a time (a copy of one column, not
 * of the frame); NBR = rows. Each value checked in [lo, hi]. */
static void put_ints(hid_t g, const char *name, const unsigned char *vals, uint64_t rows,
                     int cols, int64_t lo, int64_t hi, const char *what)
{
    hsize_t n = (hsize_t)rows * (hsize_t)cols, cnt = rows;
    hid_t fs = H5Screate_simple(1, &n, NULL), ms = H5Screate_simple(1, &cnt, NULL);
    hid_t d = fs < 0 ? -1
                     : H5Dcreate2(g, name, H5T_STD_I32LE, fs, H5P_DEFAULT, H5P_DEFAULT,
                                  H5P_DEFAULT);
    int32_t *col = xmalloc((size_t)rows * sizeof *col);

    if (d < 0 || ms < 0)
        die("cannot create dataset %s", name);
    for (int c = 0; c < cols; c++) {
        hsize_t start = (hsize_t)c * rows;
        for (uint64_t r = 0; r < rows; r++) {
            int64_t v = (int64_t)le64(vals + 8 * (r * (uint64_t)cols + (uint64_t)c));
            if (v < lo || v > hi)
                die("%s %llu: %lld is not in [%lld, %lld]", what,
                    (unsigned long long)r + 1, (long long)v, (long long)lo,
                    (long long)hi);
            col[r] = (int32_t)v;
        }
        if (rows &&
            (H5Sselect_hyperslab(fs, H5S_SELECT_SET, &start, NULL, &cnt, NULL) < 0 ||
             H5Dwrite(d, H5T_NATIVE_INT32, ms, fs, H5P_DEFAULT, col) < 0))
            die("cannot write dataset %s", name);
    }
    free(col);
    attr_int(d, "CGT", 1);
    attr_int(d, "NBR", (int)rows);
    H5Dclose(d);
    H5Sclose(ms);
    H5Sclose(fs);
}

/* n values of zeros as dataset name (FAM: family 0, where no frame gave
 * them). */
static void put_zeros(hid_t g, const char *name, uint64_t n)
{
    unsigned char *z = calloc((size_t)n + 1, 8);

    if (!z)
        die("out of memory for %llu families", (unsigned long long)n);
    put_ints(g, name, z, n, 1, 0, 0, name);
    free(z);
}

/* A group whose links are listed in the order they were made: MED 4 finds
 * the families of ELEME and NOEUD (and FAMILLE_ZERO) by their position in
 * that order (in a 4.1 file made without it, MED-fichier 4.1's mdump failed
 * to read the families; a 3.0 file, meshio's, it reads by name). */
static hid_t new_ordered_group(hid_t at, const char *name)
{
    hid_t pl = H5Pcreate(H5P_GROUP_CREATE), g = -1;

    if (pl >= 0 && H5Pset_link_creation_order(pl, H5P_CRT_ORDER_TRACKED |
                                                      H5P_CRT_ORDER_INDEXED) >= 0)
        g = H5Gcreate2(at, name, H5P_DEFAULT, pl, H5P_DEFAULT);
    if (g < 0)
        die("cannot create group %s", name);
    H5Pclose(pl);
    return g;
}

/* A group of an entity type (MAI/TE4, NOE) as MED makes it. */
static hid_t entity_group(hid_t at, const char *name, int geo)
{
    hid_t g = new_group(at, name);

    attr_int(g, "CGT", 1);
    attr_int(g, "CGS", 1);
    if (geo)
        attr_int(g, "GEO", geo);
    attr_str(g, "PFL", MED_PROFILE);
    return g;
}

/* A family's group name as MED stores it: 80 bytes, blank-padded. */
typedef struct {
    int64_t num;
    char name[MED_LNAME];
} famgroup;

static int famgroup_cmp(const void *x, const void *y)
{
    const famgroup *a = x, *b = y;

    return (a->num > b->num) - (a->num < b->num);
}

/* The families of the "families" frame (lines "NUM GROUP", meshio_med.c)
 * in *out, sorted by number; their count. */
static size_t parse_families(const unsigned char *t, uint64_t len, famgroup **out)
{
    size_t n = 0, lines = 1;
    const char *p = (const char *)t, *end = p + len;
    famgroup *fg;

    for (uint64_t i = 0; i < len; i++)
        lines += t[i] == '\n';
    fg = xmalloc(lines * sizeof *fg);
    while (p < end) {
        const char *eol = memchr(p, '\n', (size_t)(end - p)), *sp;
        char *e;
        size_t nl;
        if (!eol)
            eol = end;
        sp = memchr(p, ' ', (size_t)(eol - p));
        fg[n].num = strtoll(p, &e, 10);
        nl = sp ? (size_t)(eol - sp - 1) : 0;
        if (!sp || e != sp || nl == 0 || nl > MED_LNAME || fg[n].num == 0 ||
            fg[n].num < INT32_MIN || fg[n].num > INT32_MAX)
            die("families: a line that is no \"NUMBER GROUP\" of an int32 family "
                "and a name of 1 to %d characters",
                MED_LNAME);
        memset(fg[n].name, ' ', MED_LNAME);
        memcpy(fg[n].name, sp + 1, nl);
        n++;
        p = eol < end ? eol + 1 : end;
    }
    qsort(fg, n, sizeof *fg, famgroup_cmp);
    *out = fg;
    return n;
}

/* Every nonzero family of the frame fam (n values; where: its dataset)
 * among the n families of fg, with the sign MED gives its kind (element
 * families below zero, node families above). */
static void check_families(const unsigned char *fam, uint64_t n, const famgroup *fg,
                           size_t nfg, int sign, const char *where)
{
    for (uint64_t i = 0; fam && i < n; i++) {
        famgroup key;
        key.num = (int64_t)le64(fam + 8 * i);
        if (key.num == 0)
            continue;
        if ((key.num > 0) != (sign > 0))
            die("%s %llu: family %lld (MED numbers %s families %s zero)", where,
                (unsigned long long)i + 1, (long long)key.num,
                sign > 0 ? "node" : "element", sign > 0 ? "above" : "below");
        if (!bsearch(&key, fg, nfg, sizeof *fg, famgroup_cmp))
            die("%s %llu: family %lld is not among the families", where,
                (unsigned long long)i + 1, (long long)key.num);
    }
}

/* /FAS/<mesh>: FAMILLE_ZERO, and each family of fg (a run of one number)
 * under ELEME (below zero) or NOEUD, named FAM_<num>_<first group>, with
 * its groups as GRO/NOM (80-byte names). */
static void put_families(hid_t f, const famgroup *fg, size_t n)
{
    hid_t fas = new_group(f, "FAS"), mesh = new_group(fas, "mesh"), kind[2] = {-1, -1};
    hid_t z = new_ordered_group(mesh, "FAMILLE_ZERO");

    attr_int(z, "NUM", 0);
    H5Gclose(z);
    for (size_t i = 0, j; i < n; i = j) {
        int node = fg[i].num > 0;
        char fname[MED_NAME + 1], gname[MED_LNAME + 1];
        hsize_t cnt;
        hid_t fam, gro, arr, sp, d;
        for (j = i; j < n && fg[j].num == fg[i].num; j++)
            ;
        if (kind[node] < 0)
            kind[node] = new_ordered_group(mesh, node ? "NOEUD" : "ELEME");
        memcpy(gname, fg[i].name, MED_LNAME);
        gname[MED_LNAME] = '\0';
        for (size_t k = MED_LNAME; k > 0 && gname[k - 1] == ' '; k--)
            gname[k - 1] = '\0';
        /* a '/' would make a path of it */
        for (char *c = gname; *c; c++)
            *c = *c == '/' ? '_' : *c;
        /* at most 16 + 40 characters of MED's 64; the number makes it unique */
        snprintf(fname, sizeof fname, "FAM_%lld_%.40s", (long long)fg[i].num, gname);
        fam = new_group(kind[node], fname);
        attr_int(fam, "NUM", (int)fg[i].num);
        gro = new_group(fam, "GRO");
        attr_int(gro, "NBR", (int)(j - i));
        cnt = (hsize_t)(j - i);
        {
            hsize_t len = MED_LNAME;
            arr = H5Tarray_create2(H5T_STD_I8LE, 1, &len);
        }
        sp = H5Screate_simple(1, &cnt, NULL);
        d = arr < 0 || sp < 0
                ? -1
                : H5Dcreate2(gro, "NOM", arr, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        {
            char *names_buf = xmalloc((j - i) * MED_LNAME);
            for (size_t k = i; k < j; k++)
                memcpy(names_buf + (k - i) * MED_LNAME, fg[k].name, MED_LNAME);
            if (d < 0 || H5Dwrite(d, arr, H5S_ALL, H5S_ALL, H5P_DEFAULT, names_buf) < 0)
                die("cannot write the groups of family %s", fname);
            free(names_buf);
        }
        H5Dclose(d);
        H5Sclose(sp);
        H5Tclose(arr);
        H5Gclose(gro);
        H5Gclose(fam);
    }
    for (int k = 0; k < 2; k++)
        if (kind[k] >= 0)
            H5Gclose(kind[k]);
    H5Gclose(mesh);
    H5Gclose(fas);
}

/* OUT: a new MED file (MED-fichier 4.1's layout) of the whole mesh framed on
 * stdin (meshio_med.c: write_med): one mesh "mesh" of dimension 3, its
 * nodes (NOE/COO, NOE/FAM), tets (MAI/TE4 or T10), triangles (MAI/TR3 or
 * TR6) and families (/FAS/mesh). A FAM the frames do not give is written as
 * family 0. Written beside OUT and renamed over it. */
static void med_new(const char *out)
{
    static const char *const cell[2] = {"te4", "t10"}, *const cfam[2] = {"te4_fam",
                                                                         "t10_fam"};
    static const char *const tri[2] = {"tr3", "tr6"}, *const tfam[2] = {"tr3_fam",
                                                                        "tr6_fam"};
    static const char *const mtet[2] = {"TE4", "T10"}, *const mtri[2] = {"TR3", "TR6"};
    static const int tet_nodes[2] = {4, 10}, tri_nodes[2] = {3, 6};
    static const int tet_geo[2] = {GEO_TE4, GEO_T10}, tri_geo[2] = {GEO_TR3, GEO_TR6};
    size_t len, nfg = 0;
    unsigned char *b = slurp_stdin(&len);
    const unsigned char *xyz, *te[2], *tr[2], *fam, *noe, *ft;
    uint64_t n, nte[2], ntr[2], nfam, nnoe = 0, nft = 0, nv, nt;
    famgroup *fg = NULL;
    char tmp[4200], name[32];
    hid_t fapl, f, g, meshg, step, noeg, mai, e;
    double *col;
    int k;

    xyz = find_frame(b, len, "coords", 'f', &n);
    if (!xyz || n % 3)
        die("no coordinates (frame coords) in the input");
    nv = n / 3;
    if (nv > INT32_MAX)
        die("%llu nodes: more than MED's integers hold", (unsigned long long)nv);
    for (k = 0; k < 2; k++) {
        te[k] = find_frame(b, len, cell[k], 'i', &nte[k]);
        tr[k] = find_frame(b, len, tri[k], 'i', &ntr[k]);
        if (nte[k] % (uint64_t)tet_nodes[k] || ntr[k] % (uint64_t)tri_nodes[k])
            die("frame %s or %s: not %d or %d nodes an element", cell[k], tri[k],
                tet_nodes[k], tri_nodes[k]);
        nte[k] /= (uint64_t)tet_nodes[k];
        ntr[k] /= (uint64_t)tri_nodes[k];
    }
    if (!te[0] == !te[1])
        die("the input has %s tets: frame te4 or t10, one of them",
            te[0] ? "both linear and second-order" : "no");
    if (nte[0] + nte[1] > INT32_MAX || ntr[0] + ntr[1] > INT32_MAX)
        die("more elements than MED's integers hold");
    ft = find_frame(b, len, "families", 'b', &nft);
    if (ft)
        nfg = parse_families(ft, nft, &fg);
    noe = find_frame(b, len, "noe_fam", 'i', &nnoe);
    if (noe && nnoe != nv)
        die("noe_fam: %llu families for %llu nodes", (unsigned long long)nnoe,
            (unsigned long long)nv);
    check_families(noe, nnoe, fg, nfg, 1, "node");

    k = temp_beside(out, tmp, sizeof tmp);
    made = tmp;
    if (close(k) != 0)
        die("cannot set up %s: %s", tmp, strerror(errno));
    fapl = H5Pcreate(H5P_FILE_ACCESS);
    if (fapl < 0 || H5Pset_libver_bounds(fapl, H5F_LIBVER_V18, H5F_LIBVER_V18) < 0)
        die("cannot set up an HDF5 file");
    f = H5Fcreate(tmp, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    H5Pclose(fapl);
    if (f < 0)
        die("cannot create %s", tmp);
    g = new_group(f, "INFOS_GENERALES");
    attr_int(g, "MAJ", 4);
    attr_int(g, "MIN", 1);
    attr_int(g, "REL", 0);
    H5Gclose(g);

    e = new_group(f, "ENS_MAA");
    meshg = new_group(e, "mesh");
    attr_str(meshg, "DES", "written by qdc");
    attr_int(meshg, "DIM", 3);
    attr_int(meshg, "ESP", 3);
    attr_str(meshg, "NOM", "X               Y               Z               ");
    attr_int(meshg, "NXI", -1);
    attr_int(meshg, "NXT", -1);
    attr_int(meshg, "REP", 0); /* cartesian */
    attr_int(meshg, "SRT", 0); /* MED_SORT_DTIT */
    attr_int(meshg, "TYP", 0); /* unstructured */
    attr_str(meshg, "UNI", "                                                ");
    attr_str(meshg, "UNT", "");
    step = new_group(meshg, MED_STEP);
    attr_int(step, "CGT", 1);
    attr_int(step, "NDT", -1);
    attr_int(step, "NOR", -1);
    attr_int(step, "NXI", -1);
    attr_int(step, "NXT", -1);
    attr_real(step, "PDT", 0);
    attr_int(step, "PVI", -1);
    attr_int(step, "PVT", -1);

    /* NOE/COO: all x, then all y, then all z */
    noeg = entity_group(step, "NOE", 0);
    {
        hsize_t dim = (hsize_t)n;
        hid_t sp = H5Screate_simple(1, &dim, NULL);
        hid_t d = sp < 0 ? -1
                         : H5Dcreate2(noeg, "COO", H5T_IEEE_F64LE, sp, H5P_DEFAULT,
                                      H5P_DEFAULT, H5P_DEFAULT);
        col = xmalloc((size_t)n * 8);
        for (uint64_t v = 0; v < nv; v++)
            for (int a = 0; a < 3; a++) {
                uint64_t u = le64(xyz + 8 * (3 * v + (uint64_t)a));
                memcpy(&col[(uint64_t)a * nv + v], &u, 8);
            }
        if (d < 0 ||
            H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, col) < 0)
            die("cannot write the coordinates");
        free(col);
        attr_int(d, "CGT", 1);
        attr_int(d, "NBR", (int)nv);
        H5Dclose(d);
        H5Sclose(sp);
    }
    if (noe)
        put_ints(noeg, "FAM", noe, nv, 1, 0, INT32_MAX, "node");
    else
        put_zeros(noeg, "FAM", nv);
    H5Gclose(noeg);

    mai = new_group(step, "MAI");
    attr_int(mai, "CGT", 1);
    k = te[1] ? 1 : 0;
    nt = nte[k];
    fam = find_frame(b, len, cfam[k], 'i', &nfam);
    if (fam && nfam != nt)
        die("%s: %llu families for %llu tets", cfam[k], (unsigned long long)nfam,
            (unsigned long long)nt);
    check_families(fam, nfam, fg, nfg, -1, "tet");
    g = entity_group(mai, mtet[k], tet_geo[k]);
    put_ints(g, "NOD", te[k], nt, tet_nodes[k], 1, (int64_t)nv, "tet");
    if (fam)
        put_ints(g, "FAM", fam, nt, 1, INT32_MIN, 0, "tet");
    else
        put_zeros(g, "FAM", nt);
    H5Gclose(g);
    for (k = 0; k < 2; k++) {
        if (!ntr[k])
            continue;
        fam = find_frame(b, len, tfam[k], 'i', &nfam);
        if (fam && nfam != ntr[k])
            die("%s: %llu families for %llu triangles", tfam[k], (unsigned long long)nfam,
                (unsigned long long)ntr[k]);
        snprintf(name, sizeof name, "triangle (%s)", mtri[k]);
        check_families(fam, nfam, fg, nfg, -1, name);
        g = entity_group(mai, mtri[k], tri_geo[k]);
        put_ints(g, "NOD", tr[k], ntr[k], tri_nodes[k], 1, (int64_t)nv, name);
        if (fam)
            put_ints(g, "FAM", fam, ntr[k], 1, INT32_MIN, 0, name);
        else
            put_zeros(g, "FAM", ntr[k]);
        H5Gclose(g);
    }
    H5Gclose(mai);
    H5Gclose(step);
    H5Gclose(meshg);
    H5Gclose(e);
    put_families(f, fg, nfg);
    free(fg);
    close_copy(f, tmp, out);
    made = NULL;
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
                    c1[1] != 'a'         ? c1[1]
                    : cls == H5T_INTEGER ? 'i'
                                         : 'f');
        H5Dclose(d);
    }
    H5Fclose(f);
    if (fflush(stdout) != 0)
        die("cannot write to standard output: %s", strerror(errno));
}

/* OUT = IN with the dataset path replaced by the float64 frame named fname
 * of stdin (XDMF's geometry: the values in the dataset's own order). */
static void h5_write(const char *in, const char *out, const char *fname, const char *path)
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
    else if (argc == 3 && strcmp(argv[1], "med-new") == 0)
        med_new(argv[2]);
    else if (argc >= 3 && strcmp(argv[1], "h5-read") == 0)
        h5_read(argv[2], argc - 3, argv + 3);
    else if (argc == 6 && strcmp(argv[1], "h5-write") == 0)
        h5_write(argv[2], argv[3], argv[4], argv[5]);
    else
        die("usage (options: -n NAME, -i FILE, -o FILE, --sandbox BYTES): qdc-h5 [-n "
            "NAME] med-read FILE.med > FRAMES | qdc-h5 [-n NAME] "
            "med-write IN.med OUT.med < FRAMES | qdc-h5 med-new OUT.med < FRAMES | "
            "qdc-h5 [-n NAME] h5-read FILE.h5 "
            "NAME:T:DIMS:PATH... > FRAMES | qdc-h5 [-n NAME] h5-write IN.h5 OUT.h5 "
            "FRAME PATH < FRAMES");
    return 0;
}
