/* testio.h - helpers shared by the format tests (test_meshio, test_formats,
 * test_surface): a growable sink for writers, meshes full of awkward values,
 * exact comparison, dev meshes, the malformed-input corpus runner and the
 * fuzz seed/crash replayer. */
#ifndef QDC_TESTIO_H
#define QDC_TESTIO_H

#include "core/base_int.h"
#include "qdc.h"

#include <dirent.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

typedef struct {
    char *b;
    size_t n, cap;
    size_t fail_after; /* fail once more than this many bytes were written; 0 = never */
} sink;

static inline int sink_write(void *ctx, const void *d, size_t len)
{
    sink *s = ctx;

    if (s->fail_after && s->n + len > s->fail_after)
        return -1;
    if (s->n + len > s->cap) {
        size_t cap = s->cap ? s->cap : 4096;
        while (cap < s->n + len)
            cap *= 2;
        s->b = realloc(s->b, cap);
        if (!s->b)
            return -1;
        s->cap = cap;
    }
    memcpy(s->b + s->n, d, len);
    s->n += len;
    return 0;
}

static uint64_t rng_state __attribute__((unused)) = 88172645463325252ULL;

static inline uint64_t rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}

/* Doubles that stress exact printing: random bits, subnormals, signed zero,
 * extremes, short decimals. */
static inline double nasty_double(int i)
{
    static const double fixed[] = {0.0,
                                   -0.0,
                                   0.1,
                                   -0.3,
                                   1e308,
                                   -1.7976931348623157e308,
                                   4.9406564584124654e-324,
                                   2.2250738585072014e-308,
                                   1.0 / 3.0,
                                   123456789012345678.0,
                                   5e-1,
                                   9007199254740993.0};
    uint64_t u;
    double x;

    if (i < (int)(sizeof fixed / sizeof fixed[0]))
        return fixed[i];
    if (i % 3 == 0)
        return (double)(int64_t)(rnd() % 2001) / 1000.0 - 1.0;
    do {
        u = rnd();
        memcpy(&x, &u, 8);
    } while (!isfinite(x));
    return x;
}

/* A mesh with every optional array filled (not a valid tet mesh: the formats
 * don't care). */
static inline mesh_t *make_mesh(int32_t nv, int32_t nt, int32_t ntri)
{
    mesh_t *m = mesh_new(nv, nt, MESH_WITH_REGION | MESH_WITH_FIXED | MESH_WITH_VREF);

    if (!m)
        return NULL;
    for (int32_t i = 0; i < 3 * nv; i++)
        m->xyz[i] = nasty_double(i);
    for (int32_t i = 0; i < nv; i++) {
        m->vref[i] = (int32_t)(rnd() % 7) - 3;
        m->fixed[i] = rnd() % 3 == 0;
    }
    for (int32_t i = 0; i < 4 * nt; i++)
        m->tets[i] = (int32_t)(rnd() % (uint64_t)nv);
    for (int32_t t = 0; t < nt; t++)
        m->region[t] = t % 5 == 0 ? INT32_MIN + t : (int32_t)(rnd() % 1000) - 100;
    if (ntri && mesh_set_tris(m, ntri, 1) != QDC_OK) {
        mesh_free(m);
        return NULL;
    }
    for (int32_t i = 0; i < 3 * ntri; i++)
        m->tris[i] = (int32_t)(rnd() % (uint64_t)nv);
    for (int32_t t = 0; t < ntri; t++)
        m->tri_ref[t] = (int32_t)(rnd() % 100);
    return m;
}

static inline int same_bytes(const void *a, const void *b, size_t n)
{
    if (!a || !b)
        return a == b || n == 0;
    return memcmp(a, b, n) == 0;
}

/* What survives a format: 1 xyz+tets, 2 region, 4 fixed, 8 vref, 16 tris. */
enum { K_REGION = 2, K_FIXED = 4, K_VREF = 8, K_TRIS = 16 };

static inline int same_mesh(const mesh_t *a, const mesh_t *b, unsigned keep)
{
    if (a->nv != b->nv || a->nt != b->nt)
        return 0;
    if (!same_bytes(a->xyz, b->xyz, 24 * (size_t)a->nv) ||
        !same_bytes(a->tets, b->tets, 16 * (size_t)a->nt))
        return 0;
    if ((keep & K_REGION) && !same_bytes(a->region, b->region, 4 * (size_t)a->nt))
        return 0;
    if ((keep & K_FIXED) && !same_bytes(a->fixed, b->fixed, (size_t)a->nv))
        return 0;
    if ((keep & K_VREF) && !same_bytes(a->vref, b->vref, 4 * (size_t)a->nv))
        return 0;
    if ((keep & K_TRIS) &&
        (a->ntri != b->ntri || !same_bytes(a->tris, b->tris, 12 * (size_t)a->ntri) ||
         !same_bytes(a->tri_ref, b->tri_ref, 4 * (size_t)a->ntri)))
        return 0;
    return 1;
}

static inline qdc_status roundtrip(const mesh_t *m, meshio_format f, mesh_t **back)
{
    sink s = {0};
    qdc_error err;
    qdc_status st = meshio_write(m, f, sink_write, &s, &err);

    *back = NULL;
    if (st == QDC_OK)
        st = meshio_read(s.b, s.n, f, back, &err);
    if (st != QDC_OK)
        printf("  %s: %s\n", meshio_format_name(f), err.msg);
    free(s.b);
    return st;
}

static inline const char *root_path(const char *rel, char *buf, size_t n)
{
    const char *root = getenv("ROOT");

    snprintf(buf, n, "%s%s%s", root ? root : "", root ? "/" : "", rel);
    return buf;
}

/* gunzip a dev mesh into /tmp; returns its path or NULL if the mesh is missing. */
static inline const char *dev_mesh(const char *name, char *out, size_t n)
{
    char src[512], cmd[1200];
    struct stat sb;

    root_path("tests/data/dev/", src, sizeof src);
    strncat(src, name, sizeof src - strlen(src) - 1);
    strncat(src, ".mesh.gz", sizeof src - strlen(src) - 1);
    if (stat(src, &sb) != 0)
        return NULL;
    snprintf(out, n, "/tmp/qdc_test_meshio_%d_%s.mesh", (int)getpid(), name);
    snprintf(cmd, sizeof cmd, "gzip -dc '%s' > '%s'", src, out);
    return system(cmd) == 0 ? out : NULL;
}

static inline double now(void)
{
    return qdc_now();
}

/* The baseline the read speeds are judged against, on the same bytes in the
 * same process: seconds per pass of four FNV-1a passes over b[0..n) (a serial
 * chain of multiplies: CPU-bound, never vectorized, so it slows with the
 * reader when other work shares the cores; four, so it lasts about as long as
 * a read and sees the same spells of load). *h keeps the result live. */
static inline double ref_pass(const char *b, size_t n, uint64_t *h)
{
    double t0 = now();
    uint64_t x = 0xcbf29ce484222325u;

    for (int k = 0; k < 4; k++)
        for (size_t i = 0; i < n; i++)
            x = (x ^ (unsigned char)b[i]) * 0x100000001b3u;
    *h ^= x;
    return (now() - t0) / 4;
}

/* The big mesh of the speed tests: 1M tets on 200k vertices where the rates
 * are judged; a tenth of it in the sanitizer build, which judges none (its
 * round trips are checked the same way, through the same code; at 1M tets its
 * reads alone took ~45 s there). */
#if defined(__SANITIZE_ADDRESS__)
#define BIG_NV 20000
#define BIG_NT 100000
#define BIG_WHAT " of 100k tets"
#else
#define BIG_NV 200000
#define BIG_NT 1000000
#define BIG_WHAT " of 1M tets"
#endif

/* How much slower a read of f's bytes is than ref_pass over them: up to
 * `reps` reads, each right after a reference pass; the least ratio of a read
 * to the pass beside it (the pair that a busy spell of the machine disturbed
 * least). The caller judges that least ratio against `limit`: once a pair is
 * within it, more reads could only lower it, so none is made (limit 0: all
 * reps). One read in the sanitizer build, where no rate is judged. Prints
 * the absolute figures; *out gets the last mesh read (the caller frees it).
 * Returns -1 if a read fails. */
static inline double read_ratio(const char *b, size_t n, meshio_format f, int reps,
                                double limit, mesh_t **out, const char *what)
{
    double best = 1e9, ref = 1e9, ratio = 1e9, t0, tr, tp;
    uint64_t h = 0;
    qdc_error err;

#if defined(__SANITIZE_ADDRESS__)
    reps = 1;
#endif
    *out = NULL;
    for (int rep = 0; rep < reps; rep++) {
        tr = ref_pass(b, n, &h);
        mesh_free(*out);
        *out = NULL;
        t0 = now();
        if (meshio_read(b, n, f, out, &err) != QDC_OK)
            return -1;
        tp = now() - t0;
        best = fmin(best, tp);
        ref = fmin(ref, tr);
        ratio = fmin(ratio, tp / tr);
        if (ratio <= limit)
            break;
    }
    printf("  # %s read%s: %.1f MB in %.3f s = %.0f MB/s; reference pass %.0f MB/s;"
           " ratio %.2f (%llx)\n",
           meshio_format_name(f), what, n / 1e6, best, n / 1e6 / best, n / 1e6 / ref,
           ratio, (unsigned long long)(h & 0xf));
    return ratio;
}

/* A random 200k-vertex, 1M-tet mesh (BIG_NV, BIG_NT; regions in blocks)
 * written in format f and read back: how many times a reference pass over its
 * bytes the read takes (read_ratio, up to 3 pairs, judged against limit), or
 * -1 if the round trip fails or is not exact. */
static inline double read_1m_tets(meshio_format f, double limit)
{
    const int32_t nv = BIG_NV, nt = BIG_NT;
    mesh_t *m = mesh_new(nv, nt, MESH_WITH_REGION), *b = NULL;
    sink s = {0};
    qdc_error err;
    double r = -1;

    if (!m)
        return -1;
    for (int32_t i = 0; i < 3 * nv; i++)
        m->xyz[i] = (double)(rnd() >> 11) * 0x1.0p-53;
    for (int32_t i = 0; i < 4 * nt; i++)
        m->tets[i] = (int32_t)(rnd() % (uint64_t)nv);
    for (int32_t i = 0; i < nt; i++)
        m->region[i] = 1 + i / (3 * (BIG_NT / 10));
    if (meshio_write(m, f, sink_write, &s, &err) == QDC_OK) {
        r = read_ratio(s.b, s.n, f, 3, limit, &b, BIG_WHAT);
        if (b && !same_mesh(m, b, K_REGION))
            r = -1;
    }
    mesh_free(b);
    free(s.b);
    mesh_free(m);
    return r;
}

/* Abaqus, Netgen, Nastran and I-DEAS have no writer of qdc's own (they are
 * written only spliced): m as meshio lays them out (Netgen's materials:
 * m->region), Nastran with free-field GRIDs, I-DEAS as Gmsh does. */
/* One frame of what qdc-h5 prints: a 32-byte header (name, type 'f' or 'i',
 * the count, little-endian) and n 8-byte values. */
static inline void put_frame(sink *s, const char *name, char type, const void *v,
                             uint64_t n)
{
    unsigned char h[32] = {0};

    memcpy(h, name, strlen(name));
    h[16] = (unsigned char)type;
    for (int k = 0; k < 8; k++)
        h[24 + k] = (unsigned char)(n >> (8 * k));
    sink_write(s, h, sizeof h);
    sink_write(s, v, (size_t)n * 8);
}

/* A region as a tag the formats of write_other all take (0 to 9999999: a
 * Nastran PID, a Gmsh 1 physical tag, an I-DEAS group fit). */
#define OTHER_TAG(m, t) ((m)->region[t] < 0 ? 1 : (m)->region[t] % 10000000)

static inline void write_other(const mesh_t *m, meshio_format f, sink *s)
{
    char line[1100]; /* three %22.16f of up to 1e308 */
    int n;

#define OUT(...)                                                                         \
    (n = snprintf(line, sizeof line, __VA_ARGS__),                                       \
     sink_write(s, line, n < (int)sizeof line ? (size_t)n : sizeof line - 1))
    if (f == MESHIO_ABAQUS) {
        OUT("*HEADING\nAbaqus DataFile Version 6.14\n*NODE\n");
        for (int32_t i = 0; i < m->nv; i++)
            OUT("%d, %.16e, %.16e, %.16e\n", i + 1, m->xyz[3 * i], m->xyz[3 * i + 1],
                m->xyz[3 * i + 2]);
        OUT("*ELEMENT, TYPE=C3D4, ELSET=all\n");
        for (int32_t t = 0; t < m->nt; t++)
            OUT("%d, %d, %d, %d, %d\n", t + 1, m->tets[4 * t] + 1, m->tets[4 * t + 1] + 1,
                m->tets[4 * t + 2] + 1, m->tets[4 * t + 3] + 1);
    } else if (f == MESHIO_BDF) { /* free-field GRID (exact), small-field CTETRA */
        OUT("$ Nastran\nBEGIN BULK\n");
        for (int32_t i = 0; i < m->nv; i++)
            OUT("GRID,%d,,%.17g,%.17g,%.17g\n", i + 1, m->xyz[3 * i], m->xyz[3 * i + 1],
                m->xyz[3 * i + 2]);
        for (int32_t t = 0; t < m->nt; t++)
            OUT("CTETRA  %-8d%-8d%-8d%-8d%-8d%-8d\n", t + 1, OTHER_TAG(m, t),
                m->tets[4 * t] + 1, m->tets[4 * t + 1] + 1, m->tets[4 * t + 2] + 1,
                m->tets[4 * t + 3] + 1);
        OUT("ENDDATA\n");
    } else if (f == MESHIO_UNV) { /* as Gmsh writes it */
        OUT("    -1\n  2411\n");
        for (int32_t i = 0; i < m->nv; i++) {
            OUT("%10d%10d%10d%10d\n", i + 1, 1, 1, 11);
            n = 0;
            for (int a = 0; a < 3; a++)
                n += snprintf(line + n, sizeof line - (size_t)n, "%25.16E",
                              m->xyz[3 * i + a]);
            for (int k = 0; k < n; k++)
                line[k] = line[k] == 'E' ? 'D' : line[k];
            line[n++] = '\n';
            sink_write(s, line, (size_t)n);
        }
        OUT("    -1\n    -1\n  2412\n");
        for (int32_t t = 0; t < m->nt; t++)
            OUT("%10d%10d%10d%10d%10d%10d\n%10d%10d%10d%10d\n", t + 1, 111, 1,
                OTHER_TAG(m, t), 7, 4, m->tets[4 * t] + 1, m->tets[4 * t + 1] + 1,
                m->tets[4 * t + 2] + 1, m->tets[4 * t + 3] + 1);
        OUT("    -1\n");
    } else if (f == MESHIO_MED) { /* qdc-h5's frames: coordinates, 1-based te4 */
        int64_t *te = malloc(4 * (size_t)m->nt * sizeof *te + 1);
        if (!te)
            return;
        for (size_t i = 0; i < 4 * (size_t)m->nt; i++)
            te[i] = m->tets[i] + 1;
        sink_write(s, "QDCH5v1\n", 8);
        put_frame(s, "coords", 'f', m->xyz, 3 * (uint64_t)m->nv);
        put_frame(s, "te4", 'i', te, 4 * (uint64_t)m->nt);
        free(te);
    } else if (f == MESHIO_XDMF) { /* XDMF 3, the data inline */
        OUT("<Xdmf Version=\"3.0\"><Domain><Grid Name=\"g\"><Geometry "
            "GeometryType=\"XYZ\">"
            "<DataItem DataType=\"Float\" Dimensions=\"%d 3\" Format=\"XML\" "
            "Precision=\"8\">\n",
            m->nv);
        for (int32_t i = 0; i < m->nv; i++)
            OUT("%.17g %.17g %.17g\n", m->xyz[3 * i], m->xyz[3 * i + 1],
                m->xyz[3 * i + 2]);
        OUT("</DataItem></Geometry><Topology TopologyType=\"Tetrahedron\" "
            "NumberOfElements=\"%d\" NodesPerElement=\"4\"><DataItem DataType=\"Int\" "
            "Dimensions=\"%d 4\" Format=\"XML\" Precision=\"4\">\n",
            m->nt, m->nt);
        for (int32_t t = 0; t < m->nt; t++)
            OUT("%d %d %d %d\n", m->tets[4 * t], m->tets[4 * t + 1], m->tets[4 * t + 2],
                m->tets[4 * t + 3]);
        OUT("</DataItem></Topology></Grid></Domain></Xdmf>\n");
    } else if (f == MESHIO_MSH1) { /* Gmsh 1: $NOD, $ELM with type 4 (tags >= 0) */
        OUT("$NOD\n%d\n", m->nv);
        for (int32_t i = 0; i < m->nv; i++)
            OUT("%d %.17g %.17g %.17g\n", i + 1, m->xyz[3 * i], m->xyz[3 * i + 1],
                m->xyz[3 * i + 2]);
        OUT("$ENDNOD\n$ELM\n%d\n", m->nt);
        for (int32_t t = 0; t < m->nt; t++)
            OUT("%d 4 %d %d 4 %d %d %d %d\n", t + 1, OTHER_TAG(m, t), 1,
                m->tets[4 * t] + 1, m->tets[4 * t + 1] + 1, m->tets[4 * t + 2] + 1,
                m->tets[4 * t + 3] + 1);
        OUT("$ENDELM\n");
    } else {
        OUT("mesh3d\ndimension\n3\ngeomtype\n0\n\nsurfaceelements\n0\n\nvolumeelements\n%"
            "d\n",
            m->nt);
        for (int32_t t = 0; t < m->nt; t++)
            OUT("%d 4 %d %d %d %d\n", m->region[t], m->tets[4 * t] + 1,
                m->tets[4 * t + 1] + 1, m->tets[4 * t + 2] + 1, m->tets[4 * t + 3] + 1);
        OUT("\npoints\n%d\n", m->nv);
        for (int32_t i = 0; i < m->nv; i++)
            OUT("%22.16f %22.16f %22.16f\n", m->xyz[3 * i], m->xyz[3 * i + 1],
                m->xyz[3 * i + 2]);
        OUT("endmesh\n");
    }
#undef OUT
}

static inline char *read_file(const char *path, size_t *len)
{
    char *buf;
    qdc_error err;

    if (meshio_slurp(path, &buf, len, &err) != QDC_OK)
        return NULL;
    return buf;
}

/* The input file of a corpus case: "input.<ext>" (not input.ele); ext in *ext. */
static inline int find_input(const char *dir, char *path, size_t n, const char **ext)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    static char found[64];
    int ok = 0;

    if (!d)
        return 0;
    while (!ok && (e = readdir(d)))
        if (strncmp(e->d_name, "input.", 6) == 0 && strcmp(e->d_name, "input.ele") != 0 &&
            strlen(e->d_name) < sizeof found) {
            snprintf(found, sizeof found, "%s", e->d_name + 6);
            snprintf(path, n, "%s/%s", dir, e->d_name);
            ok = 1;
        }
    closedir(d);
    *ext = found;
    return ok;
}

/* One case dir: input.<ext> (input.node + input.ele for TetGen; a surface
 * extension goes to surface_read) and expect: "STATUS [LINE:COL | @OFFSET]
 * message substring". Returns 0 if it passes. */
static inline int run_case(const char *dir)
{
    char path[1024], want_status[32], where[32] = "", want_msg[256] = "";
    char *in = NULL, *ele = NULL, *exp = NULL;
    const char *ext = "";
    size_t len = 0, elen = 0, elen2;
    mesh_t *m = NULL;
    surface_t *sf = NULL;
    qdc_error err;
    qdc_status st;
    int ok = 1, got;
    long long l = -1, c = -1, off = -1;

    if (find_input(dir, path, sizeof path, &ext))
        in = read_file(path, &len);
    snprintf(path, sizeof path, "%s/expect", dir);
    exp = read_file(path, &elen2);
    if (!in || !exp) {
        printf("  %s: missing input.* or expect\n", dir);
        qdc_free(in);
        qdc_free(exp);
        return 1;
    }
    exp = realloc(exp, elen2 + 1);
    exp[elen2] = '\0';
    exp[strcspn(exp, "\n")] = '\0';
    sscanf(exp, "%31s %31s", want_status, where);
    if (sscanf(where, "%lld:%lld", &l, &c) == 2 || sscanf(where, "@%lld", &off) == 1)
        snprintf(want_msg, sizeof want_msg, "%s", strstr(exp, where) + strlen(where) + 1);
    else
        snprintf(want_msg, sizeof want_msg, "%s", exp + strlen(want_status) + 1);
    if (strcmp(ext, "node") == 0) {
        snprintf(path, sizeof path, "%s/input.ele", dir);
        ele = read_file(path, &elen);
        st = meshio_read_tetgen(in, len, ele, elen, &m, &err);
    } else if (meshio_format_from_name(ext) == MESHIO_AUTO &&
               surface_format_from_name(ext) != SURFACE_AUTO) {
        st = surface_read(in, len, surface_format_from_name(ext), &sf, &err);
        if (st == QDC_OK)
            st = surface_check(sf, &err);
    } else {
        st = meshio_read(in, len, meshio_format_from_name(ext), &m, &err);
    }
    got = m != NULL || sf != NULL;
    if (strcmp(qdc_status_name(st), want_status) != 0 || !strstr(err.msg, want_msg) ||
        (l >= 0 && (err.line != l || err.col != c)) || (off >= 0 && err.offset != off) ||
        (got && st != QDC_OK && !sf) || (!got && st == QDC_OK)) {
        printf("  %s: got %s %lld:%lld @%lld \"%s\", expected \"%s\"\n", dir,
               qdc_status_name(st), (long long)err.line, (long long)err.col,
               (long long)err.offset, err.msg, exp);
        ok = 0;
    }
    mesh_free(m);
    surface_free(sf);
    qdc_free(in);
    qdc_free(ele);
    free(exp);
    return ok ? 0 : 1;
}

/* Every case under tests/data/meshio whose name starts with one of the
 * comma-separated prefixes (NULL: all); -1 if the directory is missing. */
static inline int run_corpus(const char *prefixes, int *n)
{
    char dir[512], sub[800];
    DIR *d = opendir(root_path("tests/data/meshio", dir, sizeof dir));
    struct dirent *e;
    int bad = 0;

    *n = 0;
    if (!d)
        return -1;
    while ((e = readdir(d)) != NULL) {
        int take = !prefixes;
        for (const char *p = prefixes; p && *p && !take;) {
            size_t k = strcspn(p, ",");
            take = strncmp(e->d_name, p, k) == 0;
            p += k + (p[k] == ',');
        }
        if (e->d_name[0] == '.' || !take)
            continue;
        snprintf(sub, sizeof sub, "%s/%s", dir, e->d_name);
        bad += run_case(sub);
        (*n)++;
    }
    closedir(d);
    return bad;
}

/* Replay tests/fuzz/seeds/<name> and tests/fuzz/crashes/<name> through fn
 * (0 = fine), each whole and every prefix of the small ones (truncation
 * anywhere). Returns the failures; *n the inputs; -1 without seeds. */
static inline int replay_fuzz(const char *name, int (*fn)(const char *, size_t), int *n)
{
    int bad = 0;

    *n = 0;
    for (int k = 0; k < 2; k++) {
        char rel[256], dir[512], path[800];
        DIR *d;
        struct dirent *e;
        snprintf(rel, sizeof rel, "tests/fuzz/%s/%s", k ? "crashes" : "seeds", name);
        d = opendir(root_path(rel, dir, sizeof dir));
        if (!d) {
            if (k == 0)
                return -1; /* crashes/ exists only when there were some */
            continue;
        }
        while ((e = readdir(d)) != NULL) {
            size_t len;
            char *buf;
            if (e->d_name[0] == '.')
                continue;
            snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
            buf = read_file(path, &len);
            if (!buf)
                continue;
            if (fn(buf, len)) {
                printf("  %s: bad status\n", path);
                bad++;
            }
            for (size_t p = 0; len < 4096 && p < len; p++)
                bad += fn(buf, p);
            qdc_free(buf);
            (*n)++;
        }
        closedir(d);
    }
    return bad;
}

/* buf read as f with its source kept: the status contract, and for a mesh
 * that splices, written back unchanged it is buf itself (gzip aside), and
 * with moved coordinates it reads back as the same mesh at the new
 * coordinates (rounded to float32 if the file stores float32). 0 if so. */
static inline int splice_check(const char *buf, size_t len, meshio_format f)
{
    meshio_options o = {.log = NULL, .log_ctx = NULL, .source = 1};
    mesh_t *m = NULL, *b = NULL;
    sink s = {0}, s2 = {0};
    qdc_error err;
    qdc_status st = meshio_read_ex(buf, len, f, &o, &m, &err);
    meshio_format sf;
    int bad = 0, f32 = 0;

    if ((unsigned)st >= QDC_STATUS_COUNT || (st == QDC_OK) != (m != NULL) ||
        (st != QDC_OK && err.status != st))
        return 1;
    if (meshio_read(buf, len, f, &b, &err) != st) { /* keeping it changes nothing */
        printf("  splice: read with and without the source differ\n");
        mesh_free(m);
        mesh_free(b);
        return 1;
    }
    mesh_free(b);
    b = NULL;
    if (!m)
        return 0;
    sf = meshio_source_format(m);
    meshio_source_bytes(m, &f32);
    if (sf == MESHIO_AUTO || sf == MESHIO_TETGEN || !meshio_splices(m, sf, NULL)) {
        mesh_free(m);
        return 0;
    }
    if (meshio_write(m, sf, sink_write, &s, &err) != QDC_OK)
        bad = 1;
    else if (!(len >= 2 && (unsigned char)buf[0] == 0x1f &&
               (unsigned char)buf[1] == 0x8b) &&
             (s.n != len || memcmp(s.b, buf, len) != 0))
        bad = 2;
    for (int64_t i = 0; i < 3 * (int64_t)m->nv; i++)
        m->xyz[i] = m->xyz[i] * 0.5 + 0.125;
    if (!bad && (!meshio_splices(m, sf, NULL) ||
                 meshio_write(m, sf, sink_write, &s2, &err) != QDC_OK ||
                 meshio_read(s2.b, s2.n, sf, &b, &err) != QDC_OK))
        bad = 3;
    for (int64_t i = 0; !bad && i < 3 * (int64_t)m->nv; i++) {
        double want = f32 ? (double)(float)m->xyz[i] : m->xyz[i];
        /* Nastran's 8-character fields hold 2 to 7 digits ("-1.2-300") */
        if (sf == MESHIO_BDF ? !(fabs(b->xyz[i] - want) <= 0.05 * fabs(want))
                             : memcmp(&want, &b->xyz[i], sizeof want) != 0)
            bad = 4;
    }
    if (!bad && (b->nt != m->nt || b->nv != m->nv ||
                 (m->nt && memcmp(b->tets, m->tets, 16 * (size_t)m->nt) != 0)))
        bad = 5;
    if (bad)
        printf("  splice %s: check %d failed: %s\n", meshio_format_name(sf), bad,
               err.msg);
    mesh_free(m);
    mesh_free(b);
    free(s.b);
    free(s2.b);
    return bad != 0;
}

/* Every mesh reader on buf: a valid status, a mesh exactly on success; and
 * each with its source kept (splice_check). */
static inline int replay_meshio(const char *buf, size_t len)
{
    for (int f = 0; f < MESHIO_FORMAT_COUNT; f++) {
        mesh_t *m = NULL;
        qdc_error err;
        qdc_status st;
        if (f == MESHIO_TETGEN)
            st = meshio_read_tetgen(buf, len / 2, buf + len / 2, len - len / 2, &m, &err);
        else
            st = meshio_read(buf, len, (meshio_format)f, &m, &err);
        if ((unsigned)st >= QDC_STATUS_COUNT || (st == QDC_OK) != (m != NULL) ||
            (st != QDC_OK && err.status != st))
            return 1;
        mesh_free(m);
        if (f != MESHIO_TETGEN && splice_check(buf, len, (meshio_format)f))
            return 1;
    }
    return 0;
}

/* The two-tet case of the format tests: points a = 0, b = x, c = y, d = z,
 * e = (1,1,1) and tets a b c d, e b c d in regions r0 and r1. 1 if m is
 * exactly that; what differs is printed. */
static inline int is_two_tets(const mesh_t *m, int r0, int r1)
{
    static const double xyz[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    static const int32_t tets[8] = {0, 1, 2, 3, 4, 1, 2, 3};

    if (m->nv != 5 || m->nt != 2) {
        printf("  %d vertices, %d tets; want 5, 2\n", (int)m->nv, (int)m->nt);
        return 0;
    }
    if (memcmp(m->xyz, xyz, sizeof xyz) || memcmp(m->tets, tets, sizeof tets)) {
        printf("  not the two tets' coordinates or corners\n");
        return 0;
    }
    if (!m->region || m->region[0] != r0 || m->region[1] != r1) {
        printf("  regions not %d, %d\n", r0, r1);
        return 0;
    }
    return 1;
}

/* doc with its first `from` replaced by `to` (malloc'd), or NULL if from is
 * not in doc. */
static inline char *replaced(const char *doc, const char *from, const char *to)
{
    char *d = malloc(strlen(doc) + strlen(to) + 1);
    const char *at = strstr(doc, from);

    if (!d || !at) {
        free(d);
        return NULL;
    }
    memcpy(d, doc, (size_t)(at - doc));
    strcpy(d + (at - doc), to);
    strcat(d, at + strlen(from));
    return d;
}

/* Five vertices (xyz), tets 0 1 2 3 and 4 1 2 3, triangles 1 2 3 (the
 * face the two share) and 0 1 2, regions r0 r1 (with_region), refs f0 f1
 * (ntri 2). */
static inline mesh_t *five_mesh(const double *xyz, int with_region, int32_t r0,
                                int32_t r1, int32_t ntri, int32_t f0, int32_t f1)
{
    static const int32_t tets[8] = {0, 1, 2, 3, 4, 1, 2, 3}, tris[6] = {1, 2, 3, 0, 1, 2};
    mesh_t *m = mesh_new(5, 2, with_region ? MESH_WITH_REGION : 0);

    if (!m)
        return NULL;
    memcpy(m->xyz, xyz, 15 * sizeof(double));
    memcpy(m->tets, tets, sizeof tets);
    if (with_region) {
        m->region[0] = r0;
        m->region[1] = r1;
    }
    if (ntri && mesh_set_tris(m, ntri, 1) != QDC_OK) {
        mesh_free(m);
        return NULL;
    }
    if (ntri) {
        memcpy(m->tris, tris, sizeof tris);
        m->tri_ref[0] = f0;
        m->tri_ref[1] = f1;
    }
    return m;
}

/* m written as f into s (NUL-ended). */
static inline qdc_status write_to(const mesh_t *m, meshio_format f, sink *s,
                                  qdc_error *err)
{
    qdc_status st;

    s->n = 0;
    st = meshio_write(m, f, sink_write, s, err);
    if (st == QDC_OK && sink_write(s, "", 1) == 0)
        s->n--;
    return st;
}

#endif
