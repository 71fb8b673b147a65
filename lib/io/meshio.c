/* meshio.c - Medit .mesh, TetGen .node/.ele, QMESH binary and JSON meshes.
 *
 * Parsers work on (buf, len) buffers that need not be NUL-terminated, so no
 * libc routine that scans for a terminator ever sees the input: numbers are
 * cut into tokens here and only copied into a small local buffer when strtod
 * is really needed. Counts read from a header are checked against the bytes
 * left before anything is allocated, so a short file claiming a billion
 * vertices fails at once instead of allocating gigabytes.
 * The scanners, number parsers and writer they share with the other formats
 * (meshio_gmsh.c, meshio_vtk.c) are in meshio_scan.h. */
#include "io/meshio.h"
#include "io/gz.h"
#include "io/meshio_scan.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

/* ------------------------------------------------------------------------ */
/* Format names                                                              */

static const char *const format_names[MESHIO_FORMAT_COUNT] = {
    "auto",       "medit",  "tetgen", "qmesh",     "json",   "gmsh",
    "gmsh-bin",   "gmsh22", "vtk",    "vtk-ascii", "vtu",    "vtu-ascii",
    "gmsh22-bin", "gmsh40", "dolfin", "meshb",     "abaqus", "netgen"};

static const struct {
    const char *name;
    meshio_format fmt;
} format_aliases[] = {
    {"medit", MESHIO_MEDIT},
    {"mesh", MESHIO_MEDIT},
    {"tetgen", MESHIO_TETGEN},
    {"node", MESHIO_TETGEN},
    {"ele", MESHIO_TETGEN},
    {"qmesh", MESHIO_QMESH},
    {"binary", MESHIO_QMESH},
    {"application/vnd.qdc.mesh", MESHIO_QMESH},
    {"json", MESHIO_JSON},
    {"application/json", MESHIO_JSON},
    {"gmsh", MESHIO_GMSH41},
    {"msh", MESHIO_GMSH41},
    {"msh41", MESHIO_GMSH41},
    {"gmsh41", MESHIO_GMSH41},
    {"gmsh-bin", MESHIO_GMSH41_BIN},
    {"msh41-bin", MESHIO_GMSH41_BIN},
    {"gmsh41-bin", MESHIO_GMSH41_BIN},
    {"gmsh22", MESHIO_GMSH22},
    {"msh22", MESHIO_GMSH22},
    {"gmsh22-bin", MESHIO_GMSH22_BIN},
    {"msh22-bin", MESHIO_GMSH22_BIN},
    {"gmsh40", MESHIO_GMSH40},
    {"msh40", MESHIO_GMSH40},
    {"dolfin", MESHIO_DOLFIN},
    {"dolfin-xml", MESHIO_DOLFIN},
    {"xml", MESHIO_DOLFIN},
    {"meshb", MESHIO_MESHB},
    {"medit-bin", MESHIO_MESHB},
    {"abaqus", MESHIO_ABAQUS},
    {"calculix", MESHIO_ABAQUS},
    {"inp", MESHIO_ABAQUS},
    {"netgen", MESHIO_NETGEN},
    {"vol", MESHIO_NETGEN},
    {"vtk", MESHIO_VTK},
    {"vtk-bin", MESHIO_VTK},
    {"vtk-ascii", MESHIO_VTK_ASCII},
    {"vtu", MESHIO_VTU},
    {"vtu-ascii", MESHIO_VTU_ASCII},
};

#define N_ALIASES (sizeof format_aliases / sizeof format_aliases[0])

const char *meshio_format_name(meshio_format f)
{
    if ((unsigned)f >= MESHIO_FORMAT_COUNT)
        return NULL;
    return format_names[f];
}

static meshio_format alias_format(const char *s)
{
    for (size_t i = 0; i < N_ALIASES; i++)
        if (strcasecmp(s, format_aliases[i].name) == 0)
            return format_aliases[i].fmt;
    return MESHIO_AUTO;
}

/* alias_format of an extension that ends at the first '.' or the end
 * ("mesh" in "mesh.gz"). */
static meshio_format ext_format(const char *ext)
{
    size_t n = strcspn(ext, ".");
    for (size_t i = 0; i < N_ALIASES; i++)
        if (strlen(format_aliases[i].name) == n &&
            strncasecmp(ext, format_aliases[i].name, n) == 0)
            return format_aliases[i].fmt;
    return MESHIO_AUTO;
}

/* 1 if path ends in ".gz" (a gzip-compressed file of the format before it). */
static int path_gz(const char *path)
{
    size_t n = strlen(path);
    return n > 3 && strcasecmp(path + n - 3, ".gz") == 0;
}

/* The extension that names the format: "mesh" for a.mesh, "mesh.gz" for
 * a.mesh.gz (ext_format reads it up to the next dot). */
static const char *path_ext(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *end = base + strlen(base) - (path_gz(base) ? 3 : 0);
    const char *dot = NULL;

    for (const char *p = base; p < end; p++)
        if (*p == '.')
            dot = p;
    return dot && dot + 1 < end ? dot + 1 : NULL;
}

meshio_format meshio_format_from_name(const char *s)
{
    meshio_format f;
    const char *ext;

    if (!s)
        return MESHIO_AUTO;
    f = alias_format(s);
    if (f != MESHIO_AUTO)
        return f;
    ext = path_ext(s);
    return ext ? ext_format(ext) : MESHIO_AUTO;
}

/* After "$MeshFormat": the version ("2.2", "4", "4.1") and the file type (0
 * ASCII, 1 binary). Unsupported versions go to the reader, which names them. */
static meshio_format sniff_gmsh(const char *p, size_t n)
{
    size_t i = 0, v, vn;
    int bin;

    while (i < n && is_space((unsigned char)p[i]))
        i++;
    for (v = i; i < n && !is_space((unsigned char)p[i]); i++)
        ;
    vn = i - v;
    while (i < n && (p[i] == ' ' || p[i] == '\t'))
        i++;
    bin = i < n && p[i] == '1';
    if (vn >= 1 && p[v] == '2')
        return bin ? MESHIO_GMSH22_BIN : MESHIO_GMSH22;
    if ((vn == 1 && p[v] == '4') || (vn >= 3 && memcmp(p + v, "4.0", 3) == 0))
        return MESHIO_GMSH40;
    return bin ? MESHIO_GMSH41_BIN : MESHIO_GMSH41;
}

/* Third line of a legacy VTK file: ASCII or BINARY. */
static meshio_format sniff_vtk(const char *p, size_t n)
{
    size_t i = 0;

    for (int line = 0; line < 2 && i < n; i++)
        line += p[i] == '\n';
    while (i < n && is_space((unsigned char)p[i]))
        i++;
    return n - i >= 5 && strncasecmp(p + i, "ASCII", 5) == 0 ? MESHIO_VTK_ASCII
                                                             : MESHIO_VTK;
}

/* Where the n bytes at p first hold the k bytes of w, or NULL. */
static const char *find_bytes(const char *p, size_t n, const char *w, size_t k)
{
    for (const char *e = p + n; k <= (size_t)(e - p); p++) {
        p = memchr(p, w[0], (size_t)(e - p) - k + 1);
        if (!p)
            return NULL;
        if (memcmp(p, w, k) == 0)
            return p;
    }
    return NULL;
}

/* A VTU's variant, as its reader records it: VTU_ASCII when the Points
 * DataArray is ascii, else VTU. */
static meshio_format sniff_vtu(const char *p, size_t n)
{
    const char *e = p + n, *pts = find_bytes(p, n, "<Points", 7), *da, *end;

    if (!pts || !(da = find_bytes(pts, (size_t)(e - pts), "<DataArray", 10)) ||
        !(end = memchr(da, '>', (size_t)(e - da))))
        return MESHIO_VTU;
    return find_bytes(da, (size_t)(end - da), "format=\"ascii\"", 14) ||
                   find_bytes(da, (size_t)(end - da), "format='ascii'", 14)
               ? MESHIO_VTU_ASCII
               : MESHIO_VTU;
}

/* An XML document whose first element, within 1 kB, is a VTKFile or a
 * dolfin. */
static meshio_format sniff_xml(const char *p, size_t n)
{
    static const char tag[] = "<VTKFile", dtag[] = "<dolfin";
    size_t lim = n < 1024 ? n : 1024;

    for (size_t i = 0; i + sizeof tag - 1 <= lim; i++)
        if (memcmp(p + i, tag, sizeof tag - 1) == 0)
            return sniff_vtu(p + i, n - i);
    for (size_t i = 0; i + sizeof dtag - 1 <= lim; i++)
        if (memcmp(p + i, dtag, sizeof dtag - 1) == 0 &&
            (i + sizeof dtag - 1 == n || !is_word((unsigned char)p[i + sizeof dtag - 1])))
            return MESHIO_DOLFIN;
    return MESHIO_AUTO;
}

/* ------------------------------------------------------------------------ */
/* Media types                                                               */

static const struct {
    const char *type;  /* without parameters */
    const char *param; /* the one parameter that selects the format, or NULL */
    meshio_format fmt;
} media_types[] = {
    {"application/vnd.qdc.mesh", NULL, MESHIO_QMESH},
    {"application/json", NULL, MESHIO_JSON},
    {"model/x-medit", NULL, MESHIO_MEDIT},
    {"model/vnd.gmsh", "version=2.2", MESHIO_GMSH22},
    {"model/vnd.gmsh", "encoding=binary", MESHIO_GMSH41_BIN},
    {"model/vnd.gmsh", NULL, MESHIO_GMSH41},
    {"application/vnd.vtk", "encoding=ascii", MESHIO_VTK_ASCII},
    {"application/vnd.vtk", NULL, MESHIO_VTK},
    {"application/vnd.vtk.vtu+xml", "encoding=ascii", MESHIO_VTU_ASCII},
    {"application/vnd.vtk.vtu+xml", NULL, MESHIO_VTU},
    {"text/x-medit", NULL, MESHIO_MEDIT},
    {"application/x-gmsh", "version=2.2", MESHIO_GMSH22},
    {"application/x-gmsh", "encoding=binary", MESHIO_GMSH41_BIN},
    {"application/x-gmsh", NULL, MESHIO_GMSH41},
    {"model/x-gmsh", NULL, MESHIO_GMSH41},
    {"application/x-vtk", NULL, MESHIO_VTK},
    {"application/x-vtu", NULL, MESHIO_VTU},
};

#define N_MEDIA (sizeof media_types / sizeof media_types[0])

const char *meshio_media_type(meshio_format f)
{
    /* static strings with the parameter, in the order of the enum */
    static const char *const full[MESHIO_FORMAT_COUNT] = {
        NULL,
        "model/x-medit",
        NULL,
        "application/vnd.qdc.mesh",
        "application/json",
        "model/vnd.gmsh",
        "model/vnd.gmsh;encoding=binary",
        "model/vnd.gmsh;version=2.2",
        "application/vnd.vtk",
        "application/vnd.vtk;encoding=ascii",
        "application/vnd.vtk.vtu+xml",
        "application/vnd.vtk.vtu+xml;encoding=ascii",
        NULL,
        NULL,
        NULL,
        NULL,
        NULL,
        NULL};

    if ((unsigned)f >= MESHIO_FORMAT_COUNT)
        return NULL;
    return full[f];
}

int meshio_has_writer(meshio_format f)
{
    return f > MESHIO_AUTO && f < MESHIO_FORMAT_COUNT && f != MESHIO_ABAQUS &&
           f != MESHIO_NETGEN;
}

/* Does the parameter list [p, e) (";a=b; c=d") hold want ("a=b")? Spaces
 * around ';' and '=' and the case are ignored, quotes around the value too. */
static int has_param(const char *p, const char *e, const char *want)
{
    const char *eq = strchr(want, '=');
    size_t kl = (size_t)(eq - want), vl = strlen(eq + 1);

    while (p < e) {
        const char *k, *ke, *v, *ve;
        while (p < e && (*p == ';' || *p == ' ' || *p == '\t'))
            p++;
        for (k = p; p < e && *p != '=' && *p != ';'; p++)
            ;
        for (ke = p; ke > k && (ke[-1] == ' ' || ke[-1] == '\t'); ke--)
            ;
        if (p < e && *p == '=')
            p++;
        while (p < e && (*p == ' ' || *p == '\t' || *p == '"'))
            p++;
        for (v = p; p < e && *p != ';'; p++)
            ;
        for (ve = p; ve > v && (ve[-1] == ' ' || ve[-1] == '\t' || ve[-1] == '"'); ve--)
            ;
        if ((size_t)(ke - k) == kl && strncasecmp(k, want, kl) == 0 &&
            (size_t)(ve - v) == vl && strncasecmp(v, eq + 1, vl) == 0)
            return 1;
    }
    return 0;
}

meshio_format meshio_format_from_media_type(const char *ct)
{
    const char *semi, *e, *te;

    if (!ct)
        return MESHIO_AUTO;
    while (*ct == ' ' || *ct == '\t')
        ct++;
    e = ct + strlen(ct);
    semi = memchr(ct, ';', (size_t)(e - ct));
    te = semi ? semi : e;
    while (te > ct && (te[-1] == ' ' || te[-1] == '\t'))
        te--;
    for (size_t i = 0; i < N_MEDIA; i++) {
        const char *t = media_types[i].type;
        if (strlen(t) != (size_t)(te - ct) || strncasecmp(ct, t, (size_t)(te - ct)) != 0)
            continue;
        if (!media_types[i].param || (semi && has_param(semi, e, media_types[i].param)))
            return media_types[i].fmt;
    }
    return MESHIO_AUTO;
}

meshio_format meshio_sniff(const char *buf, size_t len)
{
    static const char *const medit_words[] = {"MeshVersionFormatted", "Dimension",
                                              "Vertices"};
    size_t i = 0, w;

    if (!buf)
        return MESHIO_AUTO;
    if (len >= 7 && memcmp(buf, "QDCMESH", 7) == 0)
        return MESHIO_QMESH;
    if (len >= 12 && ((get_le32((const unsigned char *)buf) == 1 &&
                       get_le32((const unsigned char *)buf + 4) - 1 < 4 &&
                       get_le32((const unsigned char *)buf + 8) == 3) ||
                      (memcmp(buf, "\0\0\0\1\0\0\0", 7) == 0 && buf[7] >= 1 &&
                       buf[7] <= 4 && memcmp(buf + 8, "\0\0\0\3", 4) == 0)))
        return MESHIO_MESHB;
    if (len >= 14 && memcmp(buf, "# vtk DataFile", 14) == 0)
        return sniff_vtk(buf, len);
    while (i < len) {
        if (is_space((unsigned char)buf[i])) {
            i++;
        } else if (buf[i] == '#') {
            while (i < len && buf[i] != '\n')
                i++;
        } else {
            break;
        }
    }
    if (i < len && buf[i] == '{')
        return MESHIO_JSON;
    if (i < len && buf[i] == '<')
        return sniff_xml(buf + i, len - i);
    if (len - i >= 11 && memcmp(buf + i, "$MeshFormat", 11) == 0)
        return sniff_gmsh(buf + i + 11, len - i - 11);
    if (len - i >= 4 && memcmp(buf + i, "$NOD", 4) == 0)
        return MESHIO_GMSH41; /* MSH 1: the reader says what is supported */
    if (i < len && buf[i] == '*' && (i == 0 || buf[i - 1] == '\n'))
        return MESHIO_ABAQUS;
    for (w = i; w < len && is_word((unsigned char)buf[w]); w++)
        ;
    for (size_t k = 0; k < sizeof medit_words / sizeof medit_words[0]; k++)
        if (word_is(buf + i, w - i, medit_words[k]))
            return MESHIO_MEDIT;
    if (word_is(buf + i, w - i, "mesh3d") || word_is(buf + i, w - i, "mesh2d"))
        return MESHIO_NETGEN;
    return MESHIO_AUTO;
}

/* End of a JSON number (or of a bare word such as NaN or true) starting at t. */
static const char *json_tok_end(const txt *s, const char *t)
{
    const char *p = t;

    while (p < s->end &&
           (is_word((unsigned char)*p) || *p == '+' || *p == '-' || *p == '.'))
        p++;
    return p;
}

/* ------------------------------------------------------------------------ */
/* Medit                                                                     */

/* Sections we skip, with the number of values per entry. */
static const struct {
    const char *kw;
    int ntok;
} medit_skip[] = {
    {"Edges", 3},
    {"Quadrilaterals", 5},
    {"Pyramids", 6},
    {"Prisms", 7},
    {"Hexahedra", 9},
    {"Corners", 1},
    {"Ridges", 1},
    {"RequiredEdges", 1},
    {"RequiredTriangles", 1},
    {"RequiredQuadrilaterals", 1},
    {"RequiredTetrahedra", 1},
    {"Normals", 3},
    {"Tangents", 3},
    {"NormalAtVertices", 2},
    {"NormalAtTriangleVertices", 3},
    {"TangentAtVertices", 2},
    {"TangentAtEdges", 3},
};

/* ---- large sections in parallel ----
 * A section of c entries laid out one per line (as writers do) is cut into
 * PAR_RUNS runs of whole lines, each read by one thread with the serial
 * reader's own token functions. A run must hold exactly as many entries as
 * lines and end where its last line does: then, by induction from the first,
 * every run starts on an entry, and the values are those one serial pass
 * reads. Anything else (several entries on a line, a comment line, an entry
 * over two lines, a bad token) leaves the section to the serial pass, which
 * reads the same values or reports the error with its line. */
#define PAR_MIN_ENTRIES 50000
#define PAR_RUNS 64

typedef struct {
    const char *at[PAR_RUNS + 1];
} line_runs;

/* The runs of the c lines from the next token; 0 if fewer lines end. */
static int line_runs_of(txt *s, int64_t c, line_runs *lr)
{
    const char *p;
    int64_t i = 0;

    skip_ws(s);
    p = lr->at[0] = s->p;
    for (int r = 1; r <= PAR_RUNS; r++) {
        for (; i < c * r / PAR_RUNS; i++) {
            const char *nl = memchr(p, '\n', (size_t)(s->end - p));
            if (!nl)
                return 0;
            p = nl + 1;
        }
        lr->at[r] = p;
    }
    return 1;
}

/* Entry i of a section, read by t; 1 if it reads. */
typedef int (*entry_fn)(txt *t, int64_t i, void *ctx);

/* The c entries of a section in parallel runs of lines; 0: read them
 * serially. */
static int read_runs(txt *s, int64_t c, entry_fn fn, void *ctx)
{
    line_runs lr;
    int ok = 1;

    if (c < PAR_MIN_ENTRIES || !line_runs_of(s, c, &lr))
        return 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(&& : ok)
    for (int r = 0; r < PAR_RUNS; r++) {
        txt t = *s; /* s's state over the run's bytes */
        t.p = t.bol = lr.at[r];
        t.end = lr.at[r + 1];
        for (int64_t i = c * r / PAR_RUNS; ok && i < c * (r + 1) / PAR_RUNS; i++)
            ok = fn(&t, i, ctx);
        skip_ws(&t);
        ok = ok && t.p == t.end; /* the run ends with its last line */
    }
    if (ok) {
        s->p = s->bol = lr.at[PAR_RUNS];
        s->line += c;
    }
    return ok;
}

typedef struct {
    double *xyz;
    int32_t *vref;
    uint64_t *off;
} vertex_out;

static int vertex_entry(txt *t, int64_t i, void *ctx)
{
    vertex_out *o = ctx;
    int64_t ref;

    if (o->off) {
        skip_ws(t);
        o->off[i] = (uint64_t)(t->p - t->base);
    }
    for (int j = 0; j < 3; j++)
        if (txt_real(t, "", &o->xyz[3 * i + j], NULL) != QDC_OK)
            return 0;
    if (txt_int(t, "", INT32_MIN, INT32_MAX, &ref, NULL) != QDC_OK)
        return 0;
    o->vref[i] = (int32_t)ref;
    return 1;
}

typedef struct {
    int k;
    int64_t hi;
    int32_t *idx, *ref;
} elem_out;

static int elem_entry(txt *t, int64_t i, void *ctx)
{
    elem_out *o = ctx;
    int64_t v;

    for (int j = 0; j < o->k; j++) {
        if (txt_int(t, "", 1, o->hi, &v, NULL) != QDC_OK)
            return 0;
        o->idx[o->k * i + j] = (int32_t)(v - 1);
    }
    if (!o->ref)
        return 1;
    if (txt_int(t, "", INT32_MIN, INT32_MAX, &v, NULL) != QDC_OK)
        return 0;
    o->ref[i] = (int32_t)v;
    return 1;
}

static qdc_status medit_vertices(txt *s, int64_t c, double *xyz, int32_t *vref,
                                 uint64_t *off, qdc_error *err)
{
    qdc_status st = QDC_OK;
    int64_t i, ref;
    vertex_out vo = {xyz, vref, off};

    if (read_runs(s, c, vertex_entry, &vo))
        return QDC_OK;
    for (i = 0; i < c; i++) {
        if (off) {
            skip_ws(s);
            off[i] = (uint64_t)(s->p - s->base);
        }
        for (int j = 0; j < 3; j++) {
            st = txt_real(s, "Vertices: coordinate", &xyz[3 * i + j], err);
            if (st != QDC_OK)
                goto fail;
        }
        st = txt_int(s, "Vertices: ref", INT32_MIN, INT32_MAX, &ref, err);
        if (st != QDC_OK)
            goto fail;
        vref[i] = (int32_t)ref;
    }
    return QDC_OK;
fail:
    set_index(err, "vertex", i);
    return st;
}

/* What err->kind calls an entry of section sect. */
static const char *elem_kind(const char *sect)
{
    if (strcmp(sect, "Tetrahedra") == 0 || strcmp(sect, "tets") == 0)
        return "tet";
    if (strcmp(sect, "Triangles") == 0)
        return "triangle";
    if (strcmp(sect, "vertices") == 0)
        return "vertex";
    return "entry";
}

/* c entries of k 1-based vertex indices (checked against [1, nv] when nv >= 0)
 * and, if ref is not NULL, a ref. */
static qdc_status medit_elems(txt *s, const char *sect, int64_t c, int k, int64_t nv,
                              int32_t *idx, int32_t *ref, qdc_error *err)
{
    char what[48];
    qdc_status st = QDC_OK;
    int64_t i, v, hi = nv >= 0 ? nv : INT32_MAX;
    elem_out eo = {k, hi, idx, ref};

    if (read_runs(s, c, elem_entry, &eo))
        return QDC_OK;
    snprintf(what, sizeof what, "%s: vertex index", sect);
    for (i = 0; i < c; i++) {
        for (int j = 0; j < k; j++) {
            st = txt_int(s, what, 1, hi, &v, err);
            if (st != QDC_OK)
                goto fail;
            idx[k * i + j] = (int32_t)(v - 1);
        }
        if (!ref)
            continue;
        st = txt_int(s, "ref", INT32_MIN, INT32_MAX, &v, err);
        if (st != QDC_OK)
            goto fail;
        ref[i] = (int32_t)v;
    }
    return QDC_OK;
fail:
    set_index(err, elem_kind(sect), i);
    return st;
}

static int starts_number(char c)
{
    return c == '+' || c == '-' || c == '.' || (c >= '0' && c <= '9');
}

/* Skip an entry-counted section of ntok numbers per entry. */
static qdc_status medit_skip_section(txt *s, const char *sect, int ntok, qdc_error *err)
{
    int64_t c;
    char q[32];
    qdc_status st = txt_count(s, sect, ntok, INT64_MAX, &c, err);

    for (int64_t i = 0; st == QDC_OK && i < c * ntok; i++) {
        const char *t, *te;
        skip_ws(s);
        t = s->p;
        te = tok_end(s, t);
        if (t == te || !starts_number(*t))
            return fail_txt(err, QDC_EPARSE, s, t, "%s: expected a number, got %s", sect,
                            quote_tok(q, s, t, te));
        s->p = te;
    }
    return st;
}

/* Unknown keyword: its data are the numbers (or quoted strings, as after
 * Identifier or Geometry) up to the next word. */
static qdc_status medit_skip_unknown(txt *s, const char *kw, size_t kl, qdc_error *err)
{
    char q[32];

    for (;;) {
        const char *t;
        skip_ws(s);
        t = s->p;
        if (t == s->end || is_alpha((unsigned char)*t))
            return QDC_OK;
        if (!starts_number(*t) && *t != '"')
            return fail_txt(err, QDC_EPARSE, s, t, "%.*s: unexpected %s",
                            kl > 32 ? 32 : (int)kl, kw,
                            quote_tok(q, s, t, tok_end(s, t)));
        s->p = tok_end(s, t);
    }
}

typedef struct {
    parsed pm;
    txt tet_at, tri_at, fix_at; /* section bodies, rescanned if nv came later */
    srcrec *rec;                /* where the coordinates are, or NULL */
} medit_state;

/* An element section: count, allocation, entries. */
static qdc_status medit_elem_section(txt *s, const char *sect, int k, int64_t max,
                                     parsed *pm, int64_t *count, int32_t **idx,
                                     int32_t **ref, txt *at, qdc_error *err)
{
    qdc_status st;

    if (*count >= 0)
        return fail_txt(err, QDC_EPARSE, s, s->p, "duplicate %s section", sect);
    st = txt_count(s, sect, k + (ref != NULL), max, count, err);
    if (st != QDC_OK)
        return st;
    *idx = qdc_mallocn((size_t)*count * (size_t)k, sizeof(int32_t));
    if (ref)
        *ref = qdc_mallocn((size_t)*count, sizeof(int32_t));
    if (!*idx || (ref && !*ref))
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld %s", (long long)*count,
                        sect);
    *at = *s;
    return medit_elems(s, sect, *count, k, pm->nv, *idx, ref ? *ref : NULL, err);
}

/* Index checks deferred because the section came before Vertices: find the
 * first bad index, then rescan its section to say where it is. */
static qdc_status medit_recheck(const txt *at, const char *sect, int64_t c, int k,
                                int has_ref, int64_t nv, int32_t *idx, qdc_error *err)
{
    txt s = *at;
    int32_t *ref = NULL;
    qdc_status st;

    if (c <= 0 || first_bad_index(idx, c * k, nv) < 0)
        return QDC_OK;
    if (has_ref) {
        ref = qdc_mallocn((size_t)c, sizeof(int32_t));
        if (!ref)
            return qdc_fail(err, QDC_ENOMEM, "out of memory");
    }
    st = medit_elems(&s, sect, c, k, nv, idx, ref, err);
    qdc_free(ref);
    return st != QDC_OK ? st
                        : qdc_fail(err, QDC_EINTERNAL, "%s: recheck found nothing", sect);
}

static qdc_status medit_keyword(txt *s, const char *kw, size_t kl, medit_state *ms,
                                qdc_error *err)
{
    parsed *pm = &ms->pm;
    int64_t v;
    qdc_status st;

    if (word_is(kw, kl, "MeshVersionFormatted"))
        return txt_int(s, "MeshVersionFormatted", 1, 4, &v, err);
    if (word_is(kw, kl, "Dimension")) {
        st = txt_int(s, "Dimension", INT64_MIN, INT64_MAX, &v, err);
        if (st == QDC_OK && v != 3)
            return fail_txt(err, QDC_EPARSE, s, s->p,
                            "Dimension %lld: only 3 is supported", (long long)v);
        return st;
    }
    if (word_is(kw, kl, "Vertices")) {
        if (pm->nv >= 0)
            return fail_txt(err, QDC_EPARSE, s, s->p, "duplicate Vertices section");
        st = txt_count(s, "Vertices", 4, MESH_MAX_VERTICES, &pm->nv, err);
        if (st != QDC_OK)
            return st;
        pm->xyz = qdc_mallocn((size_t)pm->nv * 3, sizeof(double));
        pm->vref = qdc_mallocn((size_t)pm->nv, sizeof(int32_t));
        if (!pm->xyz || !pm->vref)
            return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld vertices",
                            (long long)pm->nv);
        if (ms->rec) {
            st = srcrec_alloc(ms->rec, pm->nv, err);
            if (st != QDC_OK)
                return st;
            ms->rec->kind = SRC_TEXT;
            ms->rec->hash = 1;
        }
        return medit_vertices(s, pm->nv, pm->xyz, pm->vref, ms->rec ? ms->rec->off : NULL,
                              err);
    }
    if (word_is(kw, kl, "Tetrahedra"))
        return medit_elem_section(s, "Tetrahedra", 4, MESH_MAX_TETS, pm, &pm->nt,
                                  &pm->tets, &pm->region, &ms->tet_at, err);
    if (word_is(kw, kl, "Triangles"))
        return medit_elem_section(s, "Triangles", 3, INT32_MAX / 3, pm, &pm->ntri,
                                  &pm->tris, &pm->tri_ref, &ms->tri_at, err);
    if (word_is(kw, kl, "TetrahedraP2"))
        return fail_txt(err, QDC_EFORMAT, s, kw,
                        "TetrahedraP2: second-order tetrahedra (10 vertices) are not "
                        "supported: qdc optimizes linear Tetrahedra");
    if (word_is(kw, kl, "RequiredVertices")) {
        return medit_elem_section(s, "RequiredVertices", 1, INT32_MAX, pm, &pm->nfix,
                                  &pm->fix, NULL, &ms->fix_at, err);
    }
    for (size_t i = 0; i < sizeof medit_skip / sizeof medit_skip[0]; i++)
        if (word_is(kw, kl, medit_skip[i].kw))
            return medit_skip_section(s, medit_skip[i].kw, medit_skip[i].ntok, err);
    return medit_skip_unknown(s, kw, kl, err);
}

static qdc_status read_medit(const char *buf, size_t len, srcrec *rec, mesh_t **out,
                             qdc_error *err)
{
    medit_state ms;
    parsed *pm = &ms.pm;
    txt s = txt_init(buf, len, 1);
    qdc_status st = QDC_OK;
    char q[32];

    memset(&ms, 0, sizeof ms);
    ms.rec = rec;
    if (rec)
        rec->fmt = MESHIO_MEDIT;
    parsed_init(pm);
    for (;;) {
        const char *kw, *ke;
        skip_ws(&s);
        if (s.p == s.end)
            break;
        kw = s.p;
        for (ke = kw; ke < s.end && is_word((unsigned char)*ke); ke++)
            ;
        if (ke == kw || !is_alpha((unsigned char)*kw)) {
            st = fail_txt(err, QDC_EPARSE, &s, kw, "expected a keyword, got %s",
                          quote_tok(q, &s, kw, tok_end(&s, kw)));
            goto out;
        }
        s.p = ke;
        if (word_is(kw, (size_t)(ke - kw), "End")) {
            st = txt_done(&s, "End", err);
            if (st != QDC_OK)
                goto out;
            break;
        }
        st = medit_keyword(&s, kw, (size_t)(ke - kw), &ms, err);
        if (st != QDC_OK)
            goto out;
    }
    if (pm->nv < 0) {
        st = fail_txt(err, QDC_EPARSE, &s, s.p, "no Vertices section");
        goto out;
    }
    st = medit_recheck(&ms.tet_at, "Tetrahedra", pm->nt, 4, 1, pm->nv, pm->tets, err);
    if (st == QDC_OK)
        st =
            medit_recheck(&ms.tri_at, "Triangles", pm->ntri, 3, 1, pm->nv, pm->tris, err);
    if (st == QDC_OK)
        st = medit_recheck(&ms.fix_at, "RequiredVertices", pm->nfix, 1, 0, pm->nv,
                           pm->fix, err);
    if (st == QDC_OK)
        st = parsed_mesh(pm, out, err);
out:
    parsed_free(pm);
    return st;
}

/* ------------------------------------------------------------------------ */
/* TetGen                                                                    */

/* .node: "<n> 3 <nattr> <0|1>", then "<i> x y z [attrs] [marker]"; the first
 * i (0 or 1) sets the numbering of both files. */
static qdc_status tetgen_node(txt *s, parsed *pm, int64_t *base, srcrec *rec,
                              qdc_error *err)
{
    int64_t dim, nattr, nbm, num, v;
    double a;
    qdc_status st;

    st = txt_count(s, ".node", 1, MESH_MAX_VERTICES, &pm->nv, err);
    if (st == QDC_OK)
        st = txt_int(s, ".node: dimension", 3, 3, &dim, err);
    if (st == QDC_OK)
        st = txt_int(s, ".node: attribute count", 0, 1000, &nattr, err);
    if (st == QDC_OK)
        st = txt_int(s, ".node: boundary marker count", 0, 1, &nbm, err);
    if (st == QDC_OK)
        st = txt_fits(s, s->p, ".node", pm->nv, 4 + (uint64_t)nattr + (uint64_t)nbm, err);
    if (st != QDC_OK)
        return st;
    pm->xyz = qdc_mallocn((size_t)pm->nv * 3, sizeof(double));
    pm->vref = nbm ? qdc_mallocn((size_t)pm->nv, sizeof(int32_t)) : NULL;
    if (!pm->xyz || (nbm && !pm->vref))
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld vertices",
                        (long long)pm->nv);
    if (rec) {
        st = srcrec_alloc(rec, pm->nv, err);
        if (st != QDC_OK)
            return st;
        rec->fmt = MESHIO_TETGEN;
        rec->kind = SRC_TEXT;
        rec->hash = 1;
    }
    for (int64_t i = 0; i < pm->nv; i++) {
        int64_t lo = i ? *base + i : 0, hi = i ? *base + i : 1;
        st = txt_int(s, ".node: vertex number", lo, hi, &num, err);
        if (st == QDC_OK && i == 0)
            *base = num;
        if (st == QDC_OK && rec) {
            skip_ws(s);
            rec->off[i] = (uint64_t)(s->p - s->base);
        }
        for (int j = 0; j < 3 && st == QDC_OK; j++)
            st = txt_real(s, ".node: coordinate", &pm->xyz[3 * i + j], err);
        for (int64_t j = 0; j < nattr && st == QDC_OK; j++)
            st = txt_real(s, ".node: attribute", &a, err);
        if (st == QDC_OK && nbm)
            st = txt_int(s, ".node: boundary marker", INT32_MIN, INT32_MAX, &v, err);
        if (st == QDC_OK && nbm)
            pm->vref[i] = (int32_t)v;
        if (st != QDC_OK) {
            set_index(err, "vertex", i);
            return st;
        }
    }
    return txt_done(s, "the vertices", err);
}

/* .ele: "<n> <4|10> <nattr>", then "<i> a b c d [6 more] [attrs]"; the first
 * attribute, an integer-valued number, is the region. */
static qdc_status tetgen_ele(txt *s, parsed *pm, int64_t base, qdc_error *err)
{
    int64_t npt, nattr, v;
    double a;
    char q[32];
    qdc_status st;

    txt head;

    st = txt_count(s, ".ele", 1, MESH_MAX_TETS, &pm->nt, err);
    skip_ws(s);
    head = *s;
    if (st == QDC_OK)
        st = txt_int(s, ".ele: nodes per tet", 4, 10, &npt, err);
    if (st == QDC_OK && npt != 4 && npt != 10)
        st = fail_txt(err, QDC_EPARSE, s, s->p, ".ele: %lld nodes per tet (4 or 10)",
                      (long long)npt);
    if (st == QDC_OK)
        st = txt_int(s, ".ele: attribute count", 0, 1000, &nattr, err);
    if (st == QDC_OK)
        st = txt_fits(s, s->p, ".ele", pm->nt, 1 + (uint64_t)npt + (uint64_t)nattr, err);
    if (st != QDC_OK)
        return st;
    pm->tets = qdc_mallocn((size_t)pm->nt * 4, sizeof(int32_t));
    pm->region = nattr ? qdc_mallocn((size_t)pm->nt, sizeof(int32_t)) : NULL;
    if (!pm->tets || (nattr && !pm->region))
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld tets",
                        (long long)pm->nt);
    for (int64_t i = 0; i < pm->nt; i++) {
        st = txt_int(s, ".ele: tet number", INT64_MIN, INT64_MAX, &v, err);
        for (int j = 0; j < npt && st == QDC_OK; j++) {
            st = txt_int(s, ".ele: vertex index", base, base + pm->nv - 1, &v, err);
            if (st == QDC_OK && j < 4)
                pm->tets[4 * i + j] = (int32_t)(v - base);
        }
        for (int64_t j = 0; j < nattr && st == QDC_OK; j++) {
            const char *at;
            skip_ws(s);
            at = s->p;
            st = txt_real(s, ".ele: attribute", &a, err);
            if (st == QDC_OK && j == 0 &&
                !(a == floor(a) && a >= INT32_MIN && a <= INT32_MAX))
                st = fail_txt(err, QDC_EPARSE, s, at,
                              ".ele: region attribute %s is not an int32",
                              quote_tok(q, s, at, tok_end(s, at)));
            if (st == QDC_OK && j == 0)
                pm->region[i] = (int32_t)a;
        }
        if (st != QDC_OK) {
            set_index(err, "tet", i);
            return st;
        }
    }
    st = txt_done(s, "the tets", err);
    if (st == QDC_OK && npt == 10) /* tetgen -o2: corners alone would break them */
        st = fail_txt(err, QDC_EFORMAT, &head, head.p,
                      ".ele: second-order tetrahedra (10 nodes per tet) are not "
                      "supported: qdc optimizes linear tetrahedra (4 nodes)");
    return st;
}

/* TetGen from its two buffers; with rec, the .node's vertex offsets. */
static qdc_status read_tetgen(const char *node, size_t node_len, const char *ele,
                              size_t ele_len, srcrec *rec, mesh_t **out, qdc_error *err)
{
    parsed pm;
    txt s;
    int64_t base = 0;
    qdc_status st;

    parsed_init(&pm);
    s = txt_init(node ? node : "", node_len, 1);
    st = tetgen_node(&s, &pm, &base, rec, err);
    if (st == QDC_OK && ele) {
        s = txt_init(ele, ele_len, 1);
        st = tetgen_ele(&s, &pm, base, err);
    }
    if (st == QDC_OK)
        st = parsed_mesh(&pm, out, err);
    parsed_free(&pm);
    return st;
}

qdc_status meshio_read_tetgen(const char *node, size_t node_len, const char *ele,
                              size_t ele_len, mesh_t **out, qdc_error *err)
{
    qdc_error_clear(err);
    if (!out || (!node && node_len) || (!ele && ele_len))
        return qdc_fail(err, QDC_EINVAL, "meshio_read_tetgen: NULL argument");
    *out = NULL;
    return read_tetgen(node, node_len, ele, ele_len, NULL, out, err);
}

/* ------------------------------------------------------------------------ */
/* QMESH binary                                                              */

#define QMESH_MAGIC "QDCMESH"
#define QMESH_HEADER 32
#define QMESH_VERSION 1u
#define QMESH_REGION 1u
#define QMESH_FIXED 2u

static qdc_status read_qmesh(const char *buf, size_t len, mesh_t **out, qdc_error *err)
{
    const unsigned char *b = (const unsigned char *)buf;
    uint32_t version, flags;
    uint64_t nv, nt, need;
    size_t off;
    mesh_t *m;

    if (memcmp(buf, QMESH_MAGIC, len < 8 ? len : 8) != 0)
        return fail_bin(err, QDC_EPARSE, 0, "QMESH: bad magic (expected \"QDCMESH\\0\")");
    if (len < QMESH_HEADER)
        return fail_bin(err, QDC_EPARSE, (int64_t)len,
                        "QMESH: truncated header (%zu of %d bytes)", len, QMESH_HEADER);
    version = get_le32(b + 8);
    flags = get_le32(b + 12);
    nv = get_le64(b + 16);
    nt = get_le64(b + 24);
    if (version != QMESH_VERSION)
        return fail_bin(err, QDC_EFORMAT, 8,
                        "QMESH: unsupported version %u (expected %u)", version,
                        QMESH_VERSION);
    if (flags & ~(QMESH_REGION | QMESH_FIXED))
        return fail_bin(err, QDC_EFORMAT, 12, "QMESH: unknown flags 0x%x", flags);
    /* Both counts below 2^40 keep the size arithmetic far from overflow; larger
     * ones cannot match any buffer we could be holding anyway. */
    need = UINT64_MAX;
    if (nv < (UINT64_C(1) << 40) && nt < (UINT64_C(1) << 40))
        need = QMESH_HEADER + 24 * nv + 16 * nt + (flags & QMESH_REGION ? 4 * nt : 0) +
               (flags & QMESH_FIXED ? nv : 0);
    if (need != len)
        return fail_bin(
            err, QDC_EPARSE, (int64_t)(need < len ? need : len),
            "QMESH: size mismatch: nv=%llu nt=%llu flags=%u need %s%llu bytes, "
            "got %zu",
            (unsigned long long)nv, (unsigned long long)nt, flags,
            need == UINT64_MAX ? "more than " : "", (unsigned long long)need, len);
    if (nv > MESH_MAX_VERTICES)
        return fail_bin(err, QDC_ETOOBIG, 16, "QMESH: %llu vertices exceed the limit %d",
                        (unsigned long long)nv, MESH_MAX_VERTICES);
    if (nt > MESH_MAX_TETS)
        return fail_bin(err, QDC_ETOOBIG, 24, "QMESH: %llu tets exceed the limit %d",
                        (unsigned long long)nt, MESH_MAX_TETS);
    m = mesh_new((int32_t)nv, (int32_t)nt,
                 (flags & QMESH_REGION ? MESH_WITH_REGION : 0) |
                     (flags & QMESH_FIXED ? MESH_WITH_FIXED : 0));
    if (!m)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for a mesh of %llu vertices",
                        (unsigned long long)nv);
    off = QMESH_HEADER;
    for (size_t i = 0; i < 3 * nv; i++, off += 8) {
        uint64_t u = get_le64(b + off);
        memcpy(&m->xyz[i], &u, 8);
        if (!isfinite(m->xyz[i])) {
            fail_bin(err, QDC_EPARSE, (int64_t)off,
                     "QMESH: vertex %zu: coordinate is not finite (NaN/Inf)", i / 3);
            set_index(err, "vertex", (int64_t)(i / 3));
            goto fail;
        }
    }
    for (size_t i = 0; i < 4 * nt; i++, off += 4) {
        int32_t v = (int32_t)get_le32(b + off);
        if (v < 0 || (uint64_t)v >= nv) {
            fail_bin(err, QDC_EPARSE, (int64_t)off,
                     "QMESH: tet %zu: vertex index %d out of range [0, %lld]", i / 4, v,
                     (long long)nv - 1);
            set_index(err, "tet", (int64_t)(i / 4));
            goto fail;
        }
        m->tets[i] = v;
    }
    for (size_t i = 0; m->region && i < nt; i++, off += 4)
        m->region[i] = (int32_t)get_le32(b + off);
    if (m->fixed)
        memcpy(m->fixed, b + off, nv);
    *out = m;
    return QDC_OK;
fail:
    mesh_free(m);
    return err ? err->status : QDC_EPARSE;
}

/* ------------------------------------------------------------------------ */
/* JSON                                                                      */

enum { JSON_MAX_DEPTH = 64 };

static qdc_status json_want(txt *s, char c, const char *what, qdc_error *err)
{
    char q[32];

    skip_ws(s);
    if (s->p < s->end && *s->p == c) {
        s->p++;
        return QDC_OK;
    }
    return fail_txt(err, QDC_EPARSE, s, s->p, "%s: expected '%c', got %s", what, c,
                    quote_tok(q, s, s->p, json_tok_end(s, s->p)));
}

/* 1 if the next character (after whitespace) is c, consumed. */
static int json_eat(txt *s, char c)
{
    skip_ws(s);
    if (s->p < s->end && *s->p == c) {
        s->p++;
        return 1;
    }
    return 0;
}

/* A JSON number token: -?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)? */
static int json_number_ok(const char *t, const char *te, int *is_int)
{
    const char *p = t;

    *is_int = 1;
    if (p < te && *p == '-')
        p++;
    if (p == te || (unsigned)(unsigned char)*p - '0' > 9)
        return 0;
    if (*p == '0')
        p++;
    else
        while (p < te && (unsigned)(unsigned char)*p - '0' <= 9)
            p++;
    if (p < te && *p == '.') {
        *is_int = 0;
        if (++p == te || (unsigned)(unsigned char)*p - '0' > 9)
            return 0;
        while (p < te && (unsigned)(unsigned char)*p - '0' <= 9)
            p++;
    }
    if (p < te && (*p == 'e' || *p == 'E')) {
        *is_int = 0;
        p++;
        if (p < te && (*p == '+' || *p == '-'))
            p++;
        if (p == te || (unsigned)(unsigned char)*p - '0' > 9)
            return 0;
        while (p < te && (unsigned)(unsigned char)*p - '0' <= 9)
            p++;
    }
    return p == te;
}

/* One number; integer in [lo, hi] if is_int, else a finite double. */
static qdc_status json_scalar(txt *s, const char *what, int want_int, int64_t lo,
                              int64_t hi, void *out, qdc_error *err)
{
    const char *t, *te;
    char q[32];
    int is_int;
    int64_t v;
    qdc_status st;

    skip_ws(s);
    t = s->p;
    te = json_tok_end(s, t);
    if (t < te && !json_number_ok(t, te, &is_int)) {
        const char *w = t + (*t == '-');
        if (word_is(w, (size_t)(te - w), "NaN") ||
            word_is(w, (size_t)(te - w), "Infinity") ||
            word_is(w, (size_t)(te - w), "Inf"))
            return fail_txt(err, QDC_EPARSE, s, t, "%s %s is not finite (NaN/Inf)", what,
                            quote_tok(q, s, t, te));
        return fail_txt(err, QDC_EPARSE, s, t, "%s: expected a number, got %s", what,
                        quote_tok(q, s, t, te));
    }
    if (t == te)
        return fail_txt(err, QDC_EPARSE, s, t, "%s: expected a number, got %s", what,
                        quote_tok(q, s, t, te));
    if (!want_int)
        return tok_real(s, t, te, what, (double *)out, err);
    if (!is_int)
        return fail_txt(err, QDC_EPARSE, s, t, "%s: expected an integer, got %s", what,
                        quote_tok(q, s, t, te));
    st = tok_int(s, t, te, 1, what, lo, hi, &v, err);
    if (st == QDC_OK)
        *(int32_t *)out = (int32_t)v;
    return st;
}

/* An array of numbers (width 0) or of arrays of exactly `width` numbers,
 * appended to v (doubles or int32). */
static qdc_status json_array(txt *s, const char *what, int width, int want_int,
                             int64_t lo, int64_t hi, vec *v, qdc_error *err)
{
    int k = width ? width : 1;
    qdc_status st = json_want(s, '[', what, err);

    if (st != QDC_OK || json_eat(s, ']'))
        return st;
    do {
        if (vec_grow(v, (size_t)k) != 0)
            return qdc_fail(err, QDC_ENOMEM, "%s: out of memory", what);
        st = width ? json_want(s, '[', what, err) : QDC_OK;
        for (int j = 0; j < k && st == QDC_OK; j++) {
            if (j)
                st = json_want(s, ',', what, err);
            if (st == QDC_OK)
                st = json_scalar(s, what, want_int, lo, hi, (char *)v->a + v->n * v->size,
                                 err);
            if (st == QDC_OK)
                v->n++;
        }
        if (st == QDC_OK && width)
            st = json_want(s, ']', what, err);
        if (st != QDC_OK) {
            set_index(err, elem_kind(what), (int64_t)(v->n / (size_t)k));
            return st;
        }
    } while (json_eat(s, ','));
    return json_want(s, ']', what, err);
}

/* A string; its decoded text (ASCII only, else '?') goes to key, truncated. */
static qdc_status json_string(txt *s, char *key, size_t keysz, qdc_error *err)
{
    size_t n = 0;
    qdc_status st = json_want(s, '"', "string", err);

    while (st == QDC_OK) {
        unsigned char c;
        if (s->p == s->end)
            return fail_txt(err, QDC_EPARSE, s, s->p, "unterminated string");
        c = (unsigned char)*s->p;
        if (c == '"') {
            s->p++;
            break;
        }
        if (c < 0x20)
            return fail_txt(err, QDC_EPARSE, s, s->p, "control character in a string");
        s->p++;
        if (c == '\\') {
            static const char esc_in[] = "\"\\/bfnrtu", esc_out[] = "\"\\/\b\f\n\r\t";
            const char *e = s->p < s->end && *s->p ? strchr(esc_in, *s->p) : NULL;
            if (!e)
                return fail_txt(err, QDC_EPARSE, s, s->p - 1, "bad escape in a string");
            s->p++;
            c = (unsigned char)esc_out[e - esc_in];
            if (*e == 'u') {
                unsigned u = 0;
                for (int i = 0; i < 4; i++, s->p++) {
                    int h = s->p < s->end ? *s->p : 0;
                    int d = h >= '0' && h <= '9' ? h - '0'
                            : (h | 0x20) >= 'a' && (h | 0x20) <= 'f'
                                ? (h | 0x20) - 'a' + 10
                                : -1;
                    if (d < 0)
                        return fail_txt(err, QDC_EPARSE, s, s->p, "bad \\u escape");
                    u = 16 * u + (unsigned)d;
                }
                c = u && u < 0x80 ? (unsigned char)u : '?';
            }
        }
        if (key && n + 1 < keysz)
            key[n++] = c >= 0x80 ? '?' : (char)c;
    }
    if (key && keysz)
        key[n] = '\0';
    return st;
}

/* Any JSON value, checked and thrown away (unknown keys). */
static qdc_status json_skip(txt *s, int depth, qdc_error *err)
{
    const char *t, *te;
    char q[32];
    int is_int;
    qdc_status st = QDC_OK;

    if (depth > JSON_MAX_DEPTH)
        return fail_txt(err, QDC_EPARSE, s, s->p, "JSON nested too deeply");
    skip_ws(s);
    t = s->p;
    if (t < s->end && *t == '"')
        return json_string(s, NULL, 0, err);
    if (t < s->end && (*t == '[' || *t == '{')) {
        char close = *t == '[' ? ']' : '}';
        s->p++;
        if (json_eat(s, close))
            return QDC_OK;
        do {
            if (close == '}') {
                st = json_string(s, NULL, 0, err);
                if (st == QDC_OK)
                    st = json_want(s, ':', "object", err);
            }
            if (st == QDC_OK)
                st = json_skip(s, depth + 1, err);
        } while (st == QDC_OK && json_eat(s, ','));
        return st == QDC_OK ? json_want(s, close, "value", err) : st;
    }
    te = json_tok_end(s, t);
    if (t < te &&
        (json_number_ok(t, te, &is_int) || word_is(t, (size_t)(te - t), "true") ||
         word_is(t, (size_t)(te - t), "false") || word_is(t, (size_t)(te - t), "null"))) {
        s->p = te;
        return QDC_OK;
    }
    return fail_txt(err, QDC_EPARSE, s, t, "expected a JSON value, got %s",
                    quote_tok(q, s, t, te));
}

/* 1 if the next value is null (consumed). */
static int json_null(txt *s)
{
    skip_ws(s);
    if (s->end - s->p >= 4 && memcmp(s->p, "null", 4) == 0 &&
        json_tok_end(s, s->p) == s->p + 4) {
        s->p += 4;
        return 1;
    }
    return 0;
}

enum { J_VERTICES, J_TETS, J_REGIONS, J_FIXED, J_KEYS };

static const char *const json_keys[J_KEYS] = {"vertices", "tets", "regions", "fixed"};

typedef struct {
    vec v[J_KEYS];
    txt at[J_KEYS];   /* where each value starts */
    int seen[J_KEYS]; /* 0 absent, 1 present, 2 null */
} json_state;

static qdc_status json_member(txt *s, json_state *js, qdc_error *err)
{
    char key[32];
    const char *kat;
    int k;
    qdc_status st;

    skip_ws(s);
    kat = s->p;
    st = json_string(s, key, sizeof key, err);
    if (st == QDC_OK)
        st = json_want(s, ':', "object", err);
    if (st != QDC_OK)
        return st;
    for (k = 0; k < J_KEYS && strcmp(key, json_keys[k]) != 0; k++)
        ;
    if (k == J_KEYS)
        return json_skip(s, 1, err);
    if (js->seen[k])
        return fail_txt(err, QDC_EPARSE, s, kat, "duplicate key \"%s\"", key);
    js->seen[k] = 1;
    skip_ws(s);
    js->at[k] = *s;
    if (k >= J_REGIONS && json_null(s)) {
        js->seen[k] = 2; /* present, null: as if absent */
        return QDC_OK;
    }
    switch (k) {
    case J_VERTICES:
        return json_array(s, "vertices", 3, 0, 0, 0, &js->v[k], err);
    case J_TETS:
        return json_array(s, "tets", 4, 1, 0, INT32_MAX, &js->v[k], err);
    case J_REGIONS:
        return json_array(s, "regions", 0, 1, INT32_MIN, INT32_MAX, &js->v[k], err);
    default:
        return json_array(s, "fixed", 0, 1, 0, INT32_MAX, &js->v[k], err);
    }
}

/* Indices read before "vertices" was known: find a bad one, then rescan its
 * array with the bound to say where it is. */
static qdc_status json_recheck(json_state *js, int k, int width, int64_t nv,
                               qdc_error *err)
{
    txt s = js->at[k];
    vec tmp = {NULL, 0, 0, sizeof(int32_t)};
    qdc_status st;

    if (!js->seen[k] || first_bad_index(js->v[k].a, (int64_t)js->v[k].n, nv) < 0)
        return QDC_OK;
    st = json_array(&s, json_keys[k], width, 1, 0, nv - 1, &tmp, err);
    vec_free(&tmp);
    return st != QDC_OK ? st : qdc_fail(err, QDC_EINTERNAL, "recheck found nothing");
}

static qdc_status read_json(const char *buf, size_t len, mesh_t **out, qdc_error *err)
{
    json_state js;
    parsed pm; /* a view of the vectors in js */
    txt s = txt_init(buf, len, 0);
    qdc_status st;
    size_t nv, nt;

    memset(&js, 0, sizeof js);
    js.v[J_VERTICES].size = sizeof(double);
    for (int k = J_TETS; k < J_KEYS; k++)
        js.v[k].size = sizeof(int32_t);
    parsed_init(&pm);
    st = json_want(&s, '{', "mesh", err);
    if (st == QDC_OK && !json_eat(&s, '}')) {
        do
            st = json_member(&s, &js, err);
        while (st == QDC_OK && json_eat(&s, ','));
        if (st == QDC_OK)
            st = json_want(&s, '}', "mesh", err);
    }
    if (st == QDC_OK)
        st = txt_done(&s, "the JSON object", err);
    if (st != QDC_OK)
        goto out;
    nv = js.v[J_VERTICES].n / 3;
    nt = js.v[J_TETS].n / 4;
    if (!js.seen[J_VERTICES] || !js.seen[J_TETS]) {
        st = fail_txt(err, QDC_EPARSE, &s, s.p, "missing \"%s\"",
                      js.seen[J_VERTICES] ? "tets" : "vertices");
        goto out;
    }
    if (nv > MESH_MAX_VERTICES || nt > MESH_MAX_TETS) {
        st = qdc_fail(err, QDC_ETOOBIG, "%zu vertices, %zu tets exceed the limits", nv,
                      nt);
        goto out;
    }
    if (js.seen[J_REGIONS] == 1 && js.v[J_REGIONS].n != nt) {
        st = fail_txt(err, QDC_EPARSE, &js.at[J_REGIONS], js.at[J_REGIONS].p,
                      "regions: %zu entries for %zu tets", js.v[J_REGIONS].n, nt);
        goto out;
    }
    st = json_recheck(&js, J_TETS, 4, (int64_t)nv, err);
    if (st == QDC_OK)
        st = json_recheck(&js, J_FIXED, 0, (int64_t)nv, err);
    if (st != QDC_OK)
        goto out;
    pm.nv = (int64_t)nv;
    pm.nt = (int64_t)nt;
    pm.xyz = js.v[J_VERTICES].a;
    pm.tets = js.v[J_TETS].a;
    pm.region = js.v[J_REGIONS].a;
    pm.fix = js.v[J_FIXED].a;
    pm.nfix = js.seen[J_FIXED] == 1 ? (int64_t)js.v[J_FIXED].n : -1;
    st = parsed_mesh(&pm, out, err);
out:
    for (int k = 0; k < J_KEYS; k++)
        vec_free(&js.v[k]);
    return st;
}

/* ------------------------------------------------------------------------ */
/* Reading                                                                   */

qdc_status meshio_read(const char *buf, size_t len, meshio_format fmt, mesh_t **out,
                       qdc_error *err)
{
    return meshio_read_ex(buf, len, fmt, NULL, out, err);
}

/* One plain (not gzip) buffer in format fmt; rec NULL or to be filled. */
static qdc_status read_plain(const char *buf, size_t len, meshio_format fmt,
                             const meshio_options *o, srcrec *rec, mesh_t **out,
                             qdc_error *err)
{
    if (fmt == MESHIO_AUTO)
        fmt = meshio_sniff(buf, len);
    switch (fmt) {
    case MESHIO_MEDIT:
        return read_medit(buf, len, rec, out, err);
    case MESHIO_QMESH:
        return read_qmesh(buf, len, out, err);
    case MESHIO_JSON:
        return read_json(buf, len, out, err);
    case MESHIO_GMSH41:
    case MESHIO_GMSH41_BIN:
    case MESHIO_GMSH22:
    case MESHIO_GMSH22_BIN:
    case MESHIO_GMSH40:
        return meshio_gmsh_read(buf, len, o, rec, out, err);
    case MESHIO_VTK:
    case MESHIO_VTK_ASCII:
        return meshio_vtk_read(buf, len, o, rec, out, err);
    case MESHIO_VTU:
    case MESHIO_VTU_ASCII:
        return meshio_vtu_read(buf, len, o, rec, out, err);
    case MESHIO_DOLFIN:
        return meshio_dolfin_read(buf, len, o, rec, out, err);
    case MESHIO_MESHB:
        return meshio_meshb_read(buf, len, o, rec, out, err);
    case MESHIO_ABAQUS:
        return meshio_abaqus_read(buf, len, o, rec, out, err);
    case MESHIO_NETGEN:
        return meshio_netgen_read(buf, len, o, rec, out, err);
    case MESHIO_TETGEN:
        return qdc_fail(err, QDC_EINVAL,
                        "TetGen needs two buffers: use meshio_read_tetgen");
    case MESHIO_AUTO:
        return qdc_fail(err, QDC_EFORMAT, "unrecognized mesh format");
    default:
        return qdc_fail(err, QDC_EINVAL, "unknown format %d", (int)fmt);
    }
}

/* buf (gzip or not) into *out; keep: attach the (decompressed) buffer as the
 * mesh's source. own: buf is qdc_malloc'ed and ours to take (it is then
 * always consumed, freed or kept). */
static qdc_status read_buf(char *buf, size_t len, int own, meshio_format fmt,
                           const meshio_options *o, int keep, mesh_t **out,
                           qdc_error *err)
{
    srcrec rec;
    qdc_status st;

    if (gz_is_gzip(buf, len)) {
        /* a gzip-compressed file of any format: read what it holds */
        char *plain = NULL;
        size_t plen = 0;
        st = gz_inflate_max(buf, len,
                            gz_budget(len, o ? o->max_bytes : 0, o ? o->max_ratio : 0),
                            &plain, &plen, err);
        if (own)
            qdc_free(buf);
        if (st == QDC_OK && gz_is_gzip(plain, plen))
            st = qdc_fail(err, QDC_EPARSE, "gzip: compressed twice");
        if (st != QDC_OK) {
            qdc_free(plain);
            return st;
        }
        return read_buf(plain, plen, 1, fmt, o, keep, out, err);
    }
    srcrec_init(&rec);
    st = read_plain(buf, len, fmt, o, keep ? &rec : NULL, out, err);
    if (st == QDC_OK && keep && rec.fmt != MESHIO_AUTO) { /* a format that splices */
        st = splice_attach(*out, &rec, buf, len, own, NULL, 0, err);
        if (st == QDC_OK && own)
            own = 0; /* the source has it */
        if (st != QDC_OK) {
            mesh_free(*out);
            *out = NULL;
        }
    }
    srcrec_free(&rec);
    if (own)
        qdc_free(buf);
    return st;
}

qdc_status meshio_read_ex(const char *buf, size_t len, meshio_format fmt,
                          const meshio_options *o, mesh_t **out, qdc_error *err)
{
    qdc_error_clear(err);
    if (!out || (!buf && len))
        return qdc_fail(err, QDC_EINVAL, "meshio_read: NULL argument");
    *out = NULL;
    if (!buf)
        buf = "";
    /* not ours: never freed or kept (a source is a copy) */
    return read_buf((char *)(uintptr_t)buf, len, 0, fmt, o, o && o->source > 0, out, err);
}

/* ------------------------------------------------------------------------ */
/* Writing                                                                   */

static void write_medit(const mesh_t *m, wbuf *w)
{
    int32_t nfix = 0;

    wb_str(w, "MeshVersionFormatted 2\n\nDimension 3\n\nVertices\n");
    wb_int(w, m->nv);
    wb_str(w, "\n");
    for (int32_t i = 0; i < m->nv; i++) {
        wb_reals(w, m->xyz + 3 * (size_t)i, 3, " ", " ");
        wb_int(w, m->vref ? m->vref[i] : 0);
        wb_str(w, "\n");
    }
    wb_str(w, "\nTetrahedra\n");
    wb_int(w, m->nt);
    wb_str(w, "\n");
    for (int32_t t = 0; t < m->nt; t++) {
        wb_ints(w, m->tets + 4 * (size_t)t, 4, 1, " ", " ");
        wb_int(w, m->region ? m->region[t] : 0);
        wb_str(w, "\n");
    }
    if (m->ntri > 0) {
        wb_str(w, "\nTriangles\n");
        wb_int(w, m->ntri);
        wb_str(w, "\n");
        for (int32_t t = 0; t < m->ntri; t++) {
            wb_ints(w, m->tris + 3 * (size_t)t, 3, 1, " ", " ");
            wb_int(w, m->tri_ref ? m->tri_ref[t] : 0);
            wb_str(w, "\n");
        }
    }
    for (int32_t i = 0; m->fixed && i < m->nv; i++)
        nfix += m->fixed[i] != 0;
    if (m->fixed) { /* even if empty: a fixed array round-trips as one */
        wb_str(w, "\nRequiredVertices\n");
        wb_int(w, nfix);
        wb_str(w, "\n");
        for (int32_t i = 0; i < m->nv; i++)
            if (m->fixed[i]) {
                wb_int(w, (int64_t)i + 1);
                wb_str(w, "\n");
            }
    }
    wb_str(w, "\nEnd\n");
}

static void write_node(const mesh_t *m, wbuf *w)
{
    wb_int(w, m->nv);
    wb_str(w, m->vref ? "  3  0  1\n" : "  3  0  0\n");
    for (int32_t i = 0; i < m->nv; i++) {
        wb_int(w, (int64_t)i + 1);
        wb_str(w, "  ");
        wb_reals(w, m->xyz + 3 * (size_t)i, 3, " ", m->vref ? " " : "\n");
        if (m->vref) {
            wb_int(w, m->vref[i]);
            wb_str(w, "\n");
        }
    }
}

static void write_ele(const mesh_t *m, wbuf *w)
{
    wb_int(w, m->nt);
    wb_str(w, m->region ? "  4  1\n" : "  4  0\n");
    for (int32_t t = 0; t < m->nt; t++) {
        wb_int(w, (int64_t)t + 1);
        wb_str(w, "  ");
        wb_ints(w, m->tets + 4 * (size_t)t, 4, 1, " ", m->region ? " " : "\n");
        if (m->region) {
            wb_int(w, m->region[t]);
            wb_str(w, "\n");
        }
    }
}

static void write_qmesh(const mesh_t *m, wbuf *w)
{
    unsigned char h[QMESH_HEADER], b[8];
    uint32_t flags = (m->region ? QMESH_REGION : 0) | (m->fixed ? QMESH_FIXED : 0);

    memcpy(h, QMESH_MAGIC, 8);
    put_le32(h + 8, QMESH_VERSION);
    put_le32(h + 12, flags);
    put_le64(h + 16, (uint64_t)m->nv);
    put_le64(h + 24, (uint64_t)m->nt);
    wb_put(w, h, sizeof h);
    for (size_t i = 0; i < 3 * (size_t)m->nv; i++) {
        uint64_t u;
        memcpy(&u, &m->xyz[i], 8);
        put_le64(b, u);
        wb_put(w, b, 8);
    }
    for (size_t i = 0; i < 4 * (size_t)m->nt; i++) {
        put_le32(b, (uint32_t)m->tets[i]);
        wb_put(w, b, 4);
    }
    for (size_t i = 0; m->region && i < (size_t)m->nt; i++) {
        put_le32(b, (uint32_t)m->region[i]);
        wb_put(w, b, 4);
    }
    if (m->fixed)
        wb_put(w, m->fixed, (size_t)m->nv);
}

static void write_json(const mesh_t *m, wbuf *w)
{
    wb_str(w, "{\"vertices\": [");
    for (int32_t i = 0; i < m->nv; i++) {
        wb_str(w, i ? ",\n[" : "\n[");
        wb_reals(w, m->xyz + 3 * (size_t)i, 3, ", ", "]");
    }
    wb_str(w, "],\n\"tets\": [");
    for (int32_t t = 0; t < m->nt; t++) {
        wb_str(w, t ? ",\n[" : "\n[");
        wb_ints(w, m->tets + 4 * (size_t)t, 4, 0, ", ", "]");
    }
    wb_str(w, "]");
    if (m->region) {
        wb_str(w, ",\n\"regions\": [");
        for (int32_t t = 0; t < m->nt; t++) {
            wb_str(w, t == 0 ? "" : t % 16 ? ", " : ",\n");
            wb_int(w, m->region[t]);
        }
        wb_str(w, "]");
    }
    if (m->fixed) {
        int32_t n = 0;
        wb_str(w, ",\n\"fixed\": [");
        for (int32_t i = 0; i < m->nv; i++) {
            if (!m->fixed[i])
                continue;
            wb_str(w, n == 0 ? "" : n % 16 ? ", " : ",\n");
            wb_int(w, i);
            n++;
        }
        wb_str(w, "]");
    }
    wb_str(w, "}\n");
}

/* part: for TetGen, 0 = .node, 1 = .ele. */
static qdc_status write_fmt(const mesh_t *m, meshio_format fmt, int part, qdc_write_fn fn,
                            void *ctx, qdc_error *err)
{
    wbuf w = {fn, ctx, NULL, 0, 0};
    qdc_status st = check_for_write(m, err);
    const char *why = NULL;

    if (st != QDC_OK)
        return st;
    if ((fmt == MESHIO_ABAQUS || fmt == MESHIO_NETGEN) && !splice_ok(m, fmt, &why))
        return qdc_fail(err, QDC_EINVAL,
                        "%s: written only as the input file with new coordinates, and "
                        "here %s (qdc has no %s writer of its own)",
                        format_names[fmt], why, format_names[fmt]);
    if (!fn)
        return qdc_fail(err, QDC_EINVAL, "meshio_write: NULL write function");
    w.b = qdc_malloc(WB_CAP);
    if (!w.b)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the write buffer");
    if (splice_ok(m, fmt, NULL)) {
        st = splice_write(m, part, &w, err);
        fmt = MESHIO_FORMAT_COUNT; /* done */
    }
    switch (fmt) {
    case MESHIO_FORMAT_COUNT:
        break;
    case MESHIO_MEDIT:
        write_medit(m, &w);
        break;
    case MESHIO_TETGEN:
        if (part == 0)
            write_node(m, &w);
        else
            write_ele(m, &w);
        break;
    case MESHIO_QMESH:
        write_qmesh(m, &w);
        break;
    case MESHIO_JSON:
        write_json(m, &w);
        break;
    case MESHIO_GMSH41:
    case MESHIO_GMSH41_BIN:
    case MESHIO_GMSH22:
    case MESHIO_GMSH22_BIN:
    case MESHIO_GMSH40:
        st = meshio_gmsh_write(m, fmt, &w, err);
        break;
    case MESHIO_VTK:
    case MESHIO_VTK_ASCII:
        meshio_vtk_write(m, fmt == MESHIO_VTK, &w);
        break;
    case MESHIO_VTU:
    case MESHIO_VTU_ASCII:
        meshio_vtu_write(m, fmt == MESHIO_VTU, &w);
        break;
    case MESHIO_DOLFIN:
        meshio_dolfin_write(m, &w);
        break;
    case MESHIO_MESHB:
        meshio_meshb_write(m, &w);
        break;
    case MESHIO_ABAQUS: /* spliced above, or refused */
    case MESHIO_NETGEN:
        break;
    default:
        st = qdc_fail(err, QDC_EINVAL, "cannot write format %d", (int)fmt);
        break;
    }
    wb_flush(&w);
    qdc_free(w.b);
    if (st == QDC_OK && w.bad)
        st = qdc_fail(err, QDC_EIO, "write failed");
    return st;
}

qdc_status meshio_write(const mesh_t *m, meshio_format fmt, qdc_write_fn fn, void *ctx,
                        qdc_error *err)
{
    qdc_error_clear(err);
    if (fmt == MESHIO_AUTO)
        fmt = meshio_source_format(m);
    if (fmt == MESHIO_TETGEN)
        return qdc_fail(err, QDC_EINVAL, "TetGen is two files: use meshio_save");
    if (fmt == MESHIO_AUTO)
        return qdc_fail(err, QDC_EINVAL, "meshio_write: no format and no source file");
    return write_fmt(m, fmt, 0, fn, ctx, err);
}

/* ------------------------------------------------------------------------ */
/* Files                                                                     */

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

/* path with its extension replaced by ext (".node"); a new string. */
static char *with_ext(const char *path, const char *ext)
{
    const char *e = path_ext(path);
    size_t keep = strlen(path);
    char *s;

    if (e && (strcasecmp(e, "node") == 0 || strcasecmp(e, "ele") == 0))
        keep = (size_t)(e - 1 - path);
    s = qdc_malloc(keep + strlen(ext) + 1);
    if (!s)
        return NULL;
    memcpy(s, path, keep);
    strcpy(s + keep, ext);
    return s;
}

static qdc_status load_tetgen(const char *path, int keep, mesh_t **out, qdc_error *err)
{
    char *np = with_ext(path, ".node"), *ep = with_ext(path, ".ele");
    char *nb = NULL, *eb = NULL;
    size_t nl = 0, el = 0;
    qdc_status st;

    if (!np || !ep)
        st = qdc_fail(err, QDC_ENOMEM, "out of memory");
    else
        st = meshio_slurp(np, &nb, &nl, err);
    if (st == QDC_OK)
        st = meshio_slurp(ep, &eb, &el, err);
    if (st == QDC_OK) {
        srcrec rec;
        srcrec_init(&rec);
        *out = NULL;
        st = read_tetgen(nb, nl, eb, el, keep ? &rec : NULL, out, err);
        if (st == QDC_OK && keep) {
            st = splice_attach(*out, &rec, nb, nl, 1, eb, el, err);
            if (st == QDC_OK)
                nb = NULL; /* the source has it */
            else {
                mesh_free(*out);
                *out = NULL;
            }
        }
        srcrec_free(&rec);
    }
    qdc_free(nb);
    qdc_free(eb);
    qdc_free(np);
    qdc_free(ep);
    return st;
}

static int file_exists(const char *path)
{
    struct stat sb;

    return stat(path, &sb) == 0;
}

qdc_status meshio_load(const char *path, meshio_format fmt, mesh_t **out, qdc_error *err)
{
    return meshio_load_ex(path, fmt, NULL, out, err);
}

qdc_status meshio_load_ex(const char *path, meshio_format fmt, const meshio_options *o,
                          mesh_t **out, qdc_error *err)
{
    char *buf = NULL;
    size_t len = 0;
    const char *ext;
    int keep = !o || o->source >= 0;
    qdc_status st;

    qdc_error_clear(err);
    if (!path || !out)
        return qdc_fail(err, QDC_EINVAL, "meshio_load: NULL argument");
    *out = NULL;
    ext = path_ext(path);
    if (fmt == MESHIO_AUTO && ext)
        fmt = ext_format(ext);
    if (fmt == MESHIO_AUTO && !file_exists(path)) {
        char *np = with_ext(path, ".node");
        if (np && file_exists(np))
            fmt = MESHIO_TETGEN;
        qdc_free(np);
    }
    if (fmt == MESHIO_TETGEN)
        return load_tetgen(path, keep, out, err);
    st = meshio_slurp(path, &buf, &len, err);
    if (st == QDC_OK)
        st = read_buf(buf, len, 1, fmt, o, keep, out, err); /* takes buf */
    if (st == QDC_OK && keep) {
        st = splice_set_path(*out, path, err);
        if (st != QDC_OK) {
            mesh_free(*out);
            *out = NULL;
        }
    }
    return st;
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
static int save_route(const char *path, char **target)
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

/* What a save writes: m in fmt (part 1: TetGen's .ele), or len bytes. */
typedef struct {
    const mesh_t *m;
    meshio_format fmt;
    int part;
    const void *bytes;
    size_t len;
} payload;

static qdc_status write_payload(const payload *p, qdc_write_fn fn, void *ctx,
                                qdc_error *err)
{
    if (!p->bytes)
        return write_fmt(p->m, p->fmt, p->part, fn, ctx, err);
    return fn(ctx, p->bytes, p->len) == 0 ? QDC_OK : QDC_EIO;
}

/* p into fd, gzip-compressed when path ends in .gz; where is the file written,
 * for a failed write's message. */
static qdc_status write_fd(int fd, const char *path, const char *where, const payload *p,
                           qdc_error *err)
{
    qdc_status st;

    if (path_gz(path)) {
        gz_writer *gw = gz_writer_new(fd_write, &fd);
        st = gw ? write_payload(p, gz_write, gw, err)
                : qdc_fail(err, QDC_ENOMEM, "out of memory");
        if (gz_writer_finish(gw) && st == QDC_OK)
            st = QDC_EIO;
    } else {
        st = write_payload(p, fd_write, &fd, err);
    }
    return st == QDC_EIO ? fail_errno(err, "cannot write", where, errno) : st;
}

/* Write straight into path (save_route() said 1). */
static qdc_status save_direct(const char *path, const payload *p, qdc_error *err)
{
    struct stat sb;
    qdc_status st;
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);

    if (fd < 0)
        return fail_errno(err, "cannot open", path, errno);
    st = write_fd(fd, path, path, p, err);
    if (st == QDC_OK && fstat(fd, &sb) == 0 && S_ISREG(sb.st_mode) && fsync(fd) != 0)
        st = fail_errno(err, "cannot fsync", path, errno);
    if (close(fd) != 0 && st == QDC_OK)
        st = fail_errno(err, "cannot close", path, errno);
    return st;
}

static qdc_status save_atomic(const char *path, const payload *p, qdc_error *err)
{
    char *tmp, *target;
    struct stat old;
    qdc_status st;
    int fd, route = save_route(path, &target);

    if (route < 0)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    if (route > 0)
        return save_direct(path, p, err);
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
    st = write_fd(fd, path, tmp, p, err);
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

/* The formats one extension stands for. */
static int family(meshio_format f)
{
    switch (f) {
    case MESHIO_GMSH41_BIN:
    case MESHIO_GMSH22:
    case MESHIO_GMSH22_BIN:
    case MESHIO_GMSH40:
        return MESHIO_GMSH41;
    case MESHIO_VTK_ASCII:
        return MESHIO_VTK;
    case MESHIO_VTU_ASCII:
        return MESHIO_VTU;
    default:
        return f;
    }
}

meshio_format meshio_format_variant(meshio_format named, meshio_format src)
{
    return named != MESHIO_AUTO && family(named) == family(src) ? src : named;
}

meshio_format meshio_save_format(const char *path, meshio_format fmt, const mesh_t *m)
{
    const char *ext = path ? path_ext(path) : NULL;
    meshio_format src = meshio_source_format(m);

    if (fmt != MESHIO_AUTO)
        return fmt;
    if (!ext) /* /dev/stdout, a pipe, a name without one: the input's format */
        return src;
    return meshio_format_variant(ext_format(ext), src);
}

qdc_status meshio_save(const char *path, meshio_format fmt, const mesh_t *m,
                       qdc_error *err)
{
    char *np, *ep;
    qdc_status st;

    qdc_error_clear(err);
    if (!path || !m)
        return qdc_fail(err, QDC_EINVAL, "meshio_save: NULL argument");
    fmt = meshio_save_format(path, fmt, m);
    if (fmt == MESHIO_AUTO)
        return qdc_fail(err, QDC_EFORMAT, "cannot tell the format of %s", path);
    if (fmt != MESHIO_TETGEN)
        return save_atomic(path, &(payload){m, fmt, 0, NULL, 0}, err);
    {
        char *target;
        int route = save_route(path, &target);
        qdc_free(target);
        if (route != 0)
            return qdc_fail(err, route < 0 ? QDC_ENOMEM : QDC_EINVAL,
                            "TetGen's format is two files (.node and .ele): give "
                            "their name, or another format");
    }
    np = with_ext(path, ".node");
    ep = with_ext(path, ".ele");
    if (!np || !ep)
        st = qdc_fail(err, QDC_ENOMEM, "out of memory");
    else
        st = save_atomic(np, &(payload){m, fmt, 0, NULL, 0}, err);
    if (st == QDC_OK)
        st = save_atomic(ep, &(payload){m, fmt, 1, NULL, 0}, err);
    qdc_free(np);
    qdc_free(ep);
    return st;
}

qdc_status meshio_save_bytes(const char *path, const void *buf, size_t len,
                             qdc_error *err)
{
    qdc_error_clear(err);
    if (!path || (!buf && len))
        return qdc_fail(err, QDC_EINVAL, "meshio_save_bytes: NULL argument");
    return save_atomic(path, &(payload){NULL, MESHIO_AUTO, 0, buf ? buf : "", len}, err);
}
