/* meshio_gmsh.c - Gmsh MSH 4.1 (ASCII and binary), 4.0 (ASCII) and 2.x
 * (ASCII and binary).
 *
 * Reference: the Gmsh manual, "MSH file format" (4.1) and "Legacy formats"
 * (4.0, 2.2). 4.0 differs from 4.1 in the order of the block headers (entity
 * tag before dimension), node tags interleaved with the coordinates, and
 * 6-value bounding boxes for points; 2.2 binary writes its counts as ASCII
 * lines and its records as int32 and float64 values. Node tags are arbitrary positive
 * numbers, so they are mapped to 0-based indices through a dense table when their range
 * is compact and a sorted table otherwise. Tetrahedra (type 4) become tets, triangles
 * (type 2) surface triangles; every other type is skipped and counted for a note. In 4.1
 * the physical tags live on the entities ($Entities), in 2.2 on each element (first tag);
 * see pick_regions for the rule.
 *
 * Binary files are read with explicit little-endian loads at checked offsets
 * (unaligned, any host); every block count is checked against the bytes left
 * before anything is allocated. Sections other than the ones we need are
 * skipped up to their $End marker. */
#include "io/format.h"

/* Nodes per element of the Gmsh types up to 31 (0 = unknown), to skip the
 * ones we don't read in binary files. */
static const unsigned char gmsh_nodes[32] = {0,  2,  3,  4,  4, 8, 6,  5,  3,  6, 9,
                                             10, 27, 18, 14, 1, 8, 20, 15, 13, 9, 10,
                                             12, 15, 15, 21, 4, 5, 6,  20, 35, 56};

static int64_t type_nodes(int64_t type)
{
    if (type >= 0 && type < 32)
        return gmsh_nodes[type];
    if (type == 92)
        return 64;
    if (type == 93)
        return 125;
    return 0;
}

/* ------------------------------------------------------------------------ */
/* Reader state                                                              */

/* An entity of dimension 2 or 3 with its first physical tag (0 if none). */
typedef struct {
    int64_t key; /* tag << 32 | (uint32_t)phys, sorted by tag */
} entity;

/* One element type being collected: tets (k=4) or triangles (k=3). */
typedef struct {
    vec idx, phys, ent; /* int32: k indices, physical and entity tag per element */
} elems;

typedef struct {
    txt s; /* ASCII scanner; also finds the section markers in binary */
    const unsigned char *b;
    int binary, dsize; /* data size of size_t values in binary files: 4 or 8 */
    int ver;           /* 41, 40 or 22 (2.0, 2.1 and 2.2) */
    int have_nodes;
    int64_t nv;
    double *xyz;
    int64_t *tags;
    tagmap tm;
    vec ent[2];  /* int64 entity keys of dimensions 2 and 3 (4.1) */
    elems el[2]; /* 0 triangles, 1 tets */
    vec mid;     /* int32: second-order tets' 6 mid-edge nodes each (mesh_p2_edges) */
    int order;   /* tets read so far: 0 none, 1 linear (type 4), 2 second order (11) */
    skipped sk;
    vec per;        /* int64 node tags of the $Periodic pairs, both sides */
    int64_t nlinks; /* $Periodic links read */
    srcrec *rec;    /* where the coordinates are, or NULL */
    mesh_pdata *pd; /* the $NodeData arrays, or NULL */
    const meshio_options *o;
} gmsh;

static const char *const elem_names[2] = {"triangle", "tet"};

static void gmsh_free(gmsh *g)
{
    qdc_free(g->xyz);
    qdc_free(g->tags);
    tagmap_free(&g->tm);
    vec_free(&g->per);
    vec_free(&g->mid);
    mesh_pdata_free(g->pd);
    g->pd = NULL;
    for (int k = 0; k < 2; k++) {
        vec_free(&g->ent[k]);
        vec_free(&g->el[k].idx);
        vec_free(&g->el[k].phys);
        vec_free(&g->el[k].ent);
    }
}

/* ---- binary access ---- */

static size_t boff(const gmsh *g)
{
    return (size_t)(g->s.p - g->s.base);
}

static qdc_status bin_need(gmsh *g, uint64_t n, const char *what, qdc_error *err)
{
    size_t left = (size_t)(g->s.end - g->s.p);

    if (n > left)
        return fail_bin(err, QDC_EPARSE, (int64_t)boff(g),
                        "%s: needs %llu bytes, %zu left (truncated?)", what,
                        (unsigned long long)n, left);
    return QDC_OK;
}

static int32_t bin_i32(gmsh *g)
{
    int32_t v = (int32_t)get_le32(g->b + boff(g));

    g->s.p += 4;
    return v;
}

/* A size_t of the file's data size. */
static uint64_t bin_size(gmsh *g)
{
    uint64_t v = g->dsize == 8 ? get_le64(g->b + boff(g)) : get_le32(g->b + boff(g));

    g->s.p += g->dsize;
    return v;
}

static double bin_f64(gmsh *g)
{
    uint64_t u = get_le64(g->b + boff(g));
    double x;

    g->s.p += 8;
    memcpy(&x, &u, 8);
    return x;
}

/* A count (size_t) of entries of `bytes` bytes each, checked against the bytes
 * left and against max. */
static qdc_status bin_count(gmsh *g, const char *what, uint64_t bytes, int64_t max,
                            int64_t *c, qdc_error *err)
{
    size_t at = boff(g);
    uint64_t v;
    qdc_status st = bin_need(g, (uint64_t)g->dsize, what, err);

    if (st != QDC_OK)
        return st;
    v = bin_size(g);
    if (bytes && v > (uint64_t)(g->s.end - g->s.p) / bytes)
        return fail_bin(err, QDC_EPARSE, (int64_t)at,
                        "%s: count %llu does not fit in the %zu bytes left (truncated?)",
                        what, (unsigned long long)v, (size_t)(g->s.end - g->s.p));
    if (v > (uint64_t)max)
        return fail_bin(err, QDC_ETOOBIG, (int64_t)at,
                        "%s: count %llu exceeds the limit %lld", what,
                        (unsigned long long)v, (long long)max);
    *c = (int64_t)v;
    return QDC_OK;
}

/* ---- values in either encoding ---- */

/* A size_t-like value (count, tag) in [lo, hi]. */
static qdc_status g_int(gmsh *g, const char *what, int64_t lo, int64_t hi, int64_t *v,
                        qdc_error *err)
{
    size_t at;
    uint64_t u;
    qdc_status st;

    if (!g->binary)
        return txt_int(&g->s, what, lo, hi, v, err);
    at = boff(g);
    st = bin_need(g, (uint64_t)g->dsize, what, err);
    if (st != QDC_OK)
        return st;
    u = bin_size(g);
    if (u > (uint64_t)hi || (int64_t)u < lo)
        return fail_bin(err, QDC_EPARSE, (int64_t)at, "%s %llu out of range [%lld, %lld]",
                        what, (unsigned long long)u, (long long)lo, (long long)hi);
    *v = (int64_t)u;
    return QDC_OK;
}

/* An int (4 bytes in binary: entity dims and tags, element types, physical tags). */
static qdc_status g_i32(gmsh *g, const char *what, int64_t lo, int64_t hi, int64_t *v,
                        qdc_error *err)
{
    size_t at;
    qdc_status st;

    if (!g->binary)
        return txt_int(&g->s, what, lo, hi, v, err);
    at = boff(g);
    st = bin_need(g, 4, what, err);
    if (st != QDC_OK)
        return st;
    *v = bin_i32(g);
    if (*v < lo || *v > hi)
        return fail_bin(err, QDC_EPARSE, (int64_t)at, "%s %lld out of range [%lld, %lld]",
                        what, (long long)*v, (long long)lo, (long long)hi);
    return QDC_OK;
}

static qdc_status g_real(gmsh *g, const char *what, double *v, qdc_error *err)
{
    size_t at;
    qdc_status st;

    if (!g->binary)
        return txt_real(&g->s, what, v, err);
    at = boff(g);
    st = bin_need(g, 8, what, err);
    if (st != QDC_OK)
        return st;
    *v = bin_f64(g);
    if (!isfinite(*v))
        return fail_bin(err, QDC_EPARSE, (int64_t)at, "%s is not finite (NaN/Inf)", what);
    return QDC_OK;
}

/* A count of entries of `tokens` ASCII tokens or `bytes` binary bytes each. */
static qdc_status g_count(gmsh *g, const char *what, int tokens, uint64_t bytes,
                          int64_t max, int64_t *c, qdc_error *err)
{
    if (g->binary)
        return bin_count(g, what, bytes, max, c, err);
    return txt_count(&g->s, what, tokens, max, c, err);
}

/* ---- sections ---- */

/* After a section name: the rest of its line. In binary files the data start
 * right after the newline, so nothing else may be skipped. */
static void end_of_line(gmsh *g)
{
    txt *s = &g->s;

    while (s->p < s->end && (*s->p == ' ' || *s->p == '\t' || *s->p == '\r'))
        s->p++;
    if (s->p < s->end && *s->p == '\n') {
        s->p++;
        s->line++;
        s->bol = s->p;
    }
}

/* The next "$Word" (after whitespace) into name; 0 at the end of input. */
static qdc_status next_marker(gmsh *g, const char **name, size_t *nlen, qdc_error *err)
{
    txt *s = &g->s;
    const char *w;
    char q[32];

    skip_ws(s);
    *nlen = 0;
    if (s->p == s->end)
        return QDC_OK;
    if (*s->p != '$')
        return fail_txt(err, QDC_EPARSE, s, s->p, "expected a $Section, got %s",
                        quote_tok(q, s, s->p, tok_end(s, s->p)));
    w = ++s->p;
    while (s->p < s->end && is_word((unsigned char)*s->p))
        s->p++;
    *name = w;
    *nlen = (size_t)(s->p - w);
    if (!*nlen)
        return fail_txt(err, QDC_EPARSE, s, w - 1, "expected a section name after '$'");
    return QDC_OK;
}

/* "$End<name>" must come next. */
static qdc_status want_end(gmsh *g, const char *name, qdc_error *err)
{
    txt *s = &g->s;
    size_t n = strlen(name);
    char q[32];

    skip_ws(s);
    if ((size_t)(s->end - s->p) >= n + 4 && memcmp(s->p, "$End", 4) == 0 &&
        memcmp(s->p + 4, name, n) == 0 &&
        (s->p + 4 + n == s->end || !is_word((unsigned char)s->p[4 + n]))) {
        s->p += 4 + n;
        return QDC_OK;
    }
    return fail_txt(err, QDC_EPARSE, s, s->p, "expected $End%s, got %s", name,
                    quote_tok(q, s, s->p, tok_end(s, s->p)));
}

/* Skip an unknown section up to "$End<name>" at the start of a line. */
static qdc_status skip_section(gmsh *g, const char *name, size_t nlen, qdc_error *err)
{
    txt *s = &g->s;
    const char *start = s->p - nlen - 1;

    for (const char *p = s->p; p + 4 + nlen <= s->end; p++) {
        if (*p == '\n') {
            s->line++;
            s->bol = p + 1;
        }
        if (p[0] == '$' && p[-1] == '\n' && memcmp(p + 1, "End", 3) == 0 &&
            memcmp(p + 4, name, nlen) == 0 &&
            (p + 4 + nlen == s->end || !is_word((unsigned char)p[4 + nlen]))) {
            s->p = p + 4 + nlen;
            return QDC_OK;
        }
    }
    s->p = start;
    return fail_txt(err, QDC_EPARSE, s, start, "$%.*s: no $End%.*s", (int)nlen, start + 1,
                    (int)nlen, start + 1);
}

static qdc_status mesh_format(gmsh *g, qdc_error *err)
{
    txt *s = &g->s;
    const char *at;
    double ver;
    int64_t ftype, dsize;
    qdc_status st;

    skip_ws(s);
    at = s->p;
    st = txt_real(s, "$MeshFormat: version", &ver, err);
    if (st == QDC_OK && ver != 4.1 && ver != 4.0 && ver != 2.2 && ver != 2.0 &&
        ver != 2.1)
        st = fail_txt(err, QDC_EFORMAT, s, at,
                      "$MeshFormat: version %g not supported (4.1, 4.0, 2.2, 2.1 or 2.0)",
                      ver);
    if (st == QDC_OK)
        st = txt_int(s, "$MeshFormat: file type", 0, 1, &ftype, err);
    if (st == QDC_OK)
        st = txt_int(s, "$MeshFormat: data size", 4, 8, &dsize, err);
    if (st == QDC_OK && dsize != 4 && dsize != 8)
        st = fail_txt(err, QDC_EFORMAT, s, s->p, "$MeshFormat: data size %lld (4 or 8)",
                      (long long)dsize);
    if (st != QDC_OK)
        return st;
    g->ver = ver == 4.1 ? 41 : ver == 4.0 ? 40 : 22;
    g->binary = (int)ftype;
    g->dsize = (int)dsize;
    if (g->binary && g->ver == 40)
        return fail_txt(err, QDC_EFORMAT, s, at,
                        "MSH 4.0 binary is not supported (4.0 ASCII, 4.1 ASCII or "
                        "binary, 2.2 ASCII or binary)");
    if (g->binary && g->ver == 22 && g->dsize != 8)
        return fail_txt(err, QDC_EFORMAT, s, at,
                        "$MeshFormat: MSH 2.2 binary with data size %d (8 only)",
                        g->dsize);
    if (g->binary) {
        end_of_line(g);
        st = bin_need(g, 4, "$MeshFormat: endianness word", err);
        if (st == QDC_OK && get_le32(g->b + boff(g)) != 1)
            st = fail_bin(err, QDC_EFORMAT, (int64_t)boff(g),
                          "$MeshFormat: big-endian binary files are not supported");
        if (st != QDC_OK)
            return st;
        g->s.p += 4;
    }
    return want_end(g, "MeshFormat", err);
}

/* Where the next value starts (the derived values of a spliced write). */
static uint64_t val_at(gmsh *g)
{
    if (!g->binary)
        skip_ws(&g->s);
    return (uint64_t)(g->s.p - g->s.base);
}

/* With a record: entity (d, tag) of $Entities, whose nval box values come
 * next, for the spliced write to recompute them. */
static qdc_status dv_entity(gmsh *g, int d, int64_t tag, int nval, qdc_error *err)
{
    derived *dv = &g->rec->dv;
    dv_ent *e;

    if (vec_grow(&dv->ent, 1) != 0)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the entities");
    dv->kind = DV_BOXES;
    dv->bin = g->binary;
    e = (dv_ent *)dv->ent.a + dv->ent.n++;
    e->dim = d;
    e->nval = nval;
    e->tag = tag;
    e->val = (int64_t)dv->off.n;
    e->bnd = (int64_t)dv->bnd.n;
    e->nbnd = 0;
    return QDC_OK;
}

/* One bounding box value (recorded with a record). */
static qdc_status entity_box(gmsh *g, qdc_error *err)
{
    uint64_t at = val_at(g);
    double x;
    qdc_status st = g_real(g, "$Entities: bounding box", &x, err);

    if (st == QDC_OK && g->rec)
        st = dv_value(&g->rec->dv, at, x, err);
    return st;
}

/* One bounding entity tag (kept with a record). */
static qdc_status entity_bound(gmsh *g, qdc_error *err)
{
    int64_t v;
    qdc_status st = g_i32(g, "$Entities: bounding entity", INT32_MIN, INT32_MAX, &v, err);
    derived *dv = g->rec ? &g->rec->dv : NULL;

    if (st != QDC_OK || !dv)
        return st;
    if (vec_grow(&dv->bnd, 1) != 0)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the entities");
    ((int64_t *)dv->bnd.a)[dv->bnd.n++] = v;
    ((dv_ent *)dv->ent.a)[dv->ent.n - 1].nbnd++;
    return QDC_OK;
}

/* With a record: the vertices [first, first + c) of node block (dim, tag). */
static qdc_status dv_block(gmsh *g, int64_t dim, int64_t tag, int64_t first, int64_t c,
                           qdc_error *err)
{
    vec *b;

    if (!g->rec)
        return QDC_OK;
    b = &g->rec->dv.blk;
    if (vec_grow(b, 4) != 0)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the node blocks");
    ((int64_t *)b->a)[b->n++] = dim;
    ((int64_t *)b->a)[b->n++] = tag;
    ((int64_t *)b->a)[b->n++] = first;
    ((int64_t *)b->a)[b->n++] = c;
    return QDC_OK;
}

/* $Entities (4.x): keep the first physical tag of each surface and volume;
 * with a record, where the bounding boxes are and what bounds what. */
static qdc_status entities(gmsh *g, qdc_error *err)
{
    int64_t n[4], v, np, nb, tag, phys;
    qdc_status st = QDC_OK;

    for (int d = 0; d < 4 && st == QDC_OK; d++)
        st = g_count(g, "$Entities: count", 1, 4, INT32_MAX, &n[d], err);
    for (int d = 0; d < 4 && st == QDC_OK; d++) {
        vec *ev = d >= 2 ? &g->ent[d - 2] : NULL;
        int nval = d || g->ver == 40 ? 6 : 3;
        if (ev && vec_grow(ev, (size_t)n[d]) != 0)
            return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld entities",
                            (long long)n[d]);
        for (int64_t i = 0; i < n[d] && st == QDC_OK; i++) {
            st = g_i32(g, "$Entities: tag", INT32_MIN, INT32_MAX, &tag, err);
            if (st == QDC_OK && g->rec)
                st = dv_entity(g, d, tag, nval, err);
            for (int j = 0; j < nval && st == QDC_OK; j++)
                st = entity_box(g, err);
            if (st == QDC_OK)
                st = g_count(g, "$Entities: physical tag count", 1, 4, INT32_MAX, &np,
                             err);
            phys = 0;
            for (int64_t j = 0; j < np && st == QDC_OK; j++) {
                st = g_i32(g, "$Entities: physical tag", INT32_MIN, INT32_MAX, &v, err);
                if (j == 0)
                    phys = v;
            }
            if (st == QDC_OK && d)
                st = g_count(g, "$Entities: bounding entity count", 1, 4, INT32_MAX, &nb,
                             err);
            for (int64_t j = 0; j < (d ? nb : 0) && st == QDC_OK; j++)
                st = entity_bound(g, err);
            if (st == QDC_OK && ev)
                ((int64_t *)ev->a)[ev->n++] = tag * (INT64_C(1) << 32) + (uint32_t)phys;
        }
    }
    for (int k = 0; k < 2 && st == QDC_OK; k++)
        if (g->ent[k].n)
            qsort(g->ent[k].a, g->ent[k].n, sizeof(int64_t), cmp_i64);
    return st == QDC_OK ? want_end(g, "Entities", err) : st;
}

/* Physical tag of entity `tag` of dimension 2 (k=0) or 3 (k=1); 0 if none. */
static int32_t entity_phys(const gmsh *g, int k, int64_t tag)
{
    const int64_t *e = g->ent[k].a;
    size_t a = 0, b = g->ent[k].n;

    while (a < b) {
        size_t mid = a + (b - a) / 2;
        int64_t mt = e[mid] >> 32; /* arithmetic shift: tags may be negative */
        if (mt == tag)
            return (int32_t)(uint32_t)e[mid];
        if (mt < tag)
            a = mid + 1;
        else
            b = mid;
    }
    return 0;
}

/* Room for c more vertices (and their offsets if recorded). */
static qdc_status nodes_alloc(gmsh *g, int64_t c, qdc_error *err)
{
    g->xyz = qdc_mallocn((size_t)c * 3, sizeof(double));
    g->tags = qdc_mallocn((size_t)c, sizeof(int64_t));
    if (!g->xyz || !g->tags)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld nodes", (long long)c);
    if (g->rec) {
        srcrec *r = g->rec;
        r->fmt = g->ver == 40   ? MESHIO_GMSH40
                 : g->ver == 22 ? (g->binary ? MESHIO_GMSH22_BIN : MESHIO_GMSH22)
                 : g->binary    ? MESHIO_GMSH41_BIN
                                : MESHIO_GMSH41;
        r->kind = g->binary ? SRC_BIN : SRC_TEXT;
        r->width = 8;
        return srcrec_alloc(r, c, err);
    }
    return QDC_OK;
}

/* Vertex i's first coordinate comes next: note where. */
static void node_at(gmsh *g, int64_t i)
{
    if (!g->rec)
        return;
    if (!g->binary)
        skip_ws(&g->s);
    g->rec->off[i] = (uint64_t)(g->s.p - g->s.base);
}

static qdc_status nodes_done(gmsh *g, qdc_error *err)
{
    int64_t dup;
    qdc_status st = tagmap_build(&g->tm, g->tags, g->nv, &dup, err);

    if (st == QDC_OK && dup >= 0) {
        st = qdc_fail(err, QDC_EPARSE, "$Nodes: node tag %lld appears twice",
                      (long long)g->tags[dup]);
        set_index(err, "vertex", dup);
    }
    g->have_nodes = 1;
    return st;
}

/* The $Nodes errors of a count that does not add up: at the line (4.0 ASCII)
 * or without one (4.1, whose counts may be binary). */
#define NODES_MORE "$Nodes: more nodes in the blocks than the %lld announced"
#define NODES_HOLD "$Nodes: blocks hold %lld nodes, %lld announced"

/* A block of c nodes after the i read so far fits the total announced. */
static qdc_status nodes_fit(gmsh *g, int64_t i, int64_t c, int64_t total, int at_line,
                            qdc_error *err)
{
    if (c <= total - i)
        return QDC_OK;
    return at_line
               ? fail_txt(err, QDC_EPARSE, &g->s, g->s.p, NODES_MORE, (long long)total)
               : qdc_fail(err, QDC_EPARSE, NODES_MORE, (long long)total);
}

/* Node i's coordinates, then its npar parametric ones (read and dropped). */
static qdc_status node_coords(gmsh *g, int64_t i, int64_t npar, qdc_error *err)
{
    qdc_status st = QDC_OK;
    double x;

    node_at(g, i);
    for (int a = 0; a < 3 && st == QDC_OK; a++)
        st = g_real(g, "$Nodes: coordinate", &g->xyz[3 * i + a], err);
    for (int64_t a = 0; a < npar && st == QDC_OK; a++)
        st = g_real(g, "$Nodes: parametric coordinate", &x, err);
    if (st != QDC_OK)
        set_index(err, "vertex", i);
    return st;
}

/* The end of $Nodes after its blocks (st: how they went): i nodes read of the
 * total announced, the tags checked, the end marker. */
static qdc_status nodes_close(gmsh *g, qdc_status st, int64_t i, int64_t total,
                              int at_line, qdc_error *err)
{
    if (st == QDC_OK && i != total)
        st = at_line
                 ? fail_txt(err, QDC_EPARSE, &g->s, g->s.p, NODES_HOLD, (long long)i,
                            (long long)total)
                 : qdc_fail(err, QDC_EPARSE, NODES_HOLD, (long long)i, (long long)total);
    g->nv = i;
    if (st == QDC_OK)
        st = nodes_done(g, err);
    return st == QDC_OK ? want_end(g, "Nodes", err) : st;
}

/* $Nodes (4.1): blocks of tags, then coordinates. */
static qdc_status nodes41(gmsh *g, qdc_error *err)
{
    int64_t nblk, total = 0, v, dim, par, c, i = 0;
    qdc_status st;

    st = g_count(g, "$Nodes: block count", 4, 16, INT32_MAX, &nblk, err);
    if (st == QDC_OK)
        st = g_count(g, "$Nodes: node count", 4, 32, MESH_MAX_VERTICES, &total, err);
    for (int k = 0; k < 2 && st == QDC_OK; k++)
        st = g_int(g, "$Nodes: node tag bound", 0, INT64_MAX, &v, err);
    if (st == QDC_OK)
        st = nodes_alloc(g, total, err);
    for (int64_t b = 0; b < nblk && st == QDC_OK; b++) {
        st = g_i32(g, "$Nodes: entity dimension", 0, 3, &dim, err);
        if (st == QDC_OK)
            st = g_i32(g, "$Nodes: entity tag", INT32_MIN, INT32_MAX, &v, err);
        if (st == QDC_OK)
            st = g_i32(g, "$Nodes: parametric", 0, 1, &par, err);
        if (st == QDC_OK)
            st = g_count(g, "$Nodes: nodes in block", 4, 32 + 8 * (uint64_t)(par * dim),
                         INT64_MAX, &c, err);
        if (st == QDC_OK)
            st = nodes_fit(g, i, c, total, 0, err);
        if (st == QDC_OK)
            st = dv_block(g, dim, v, i, c, err);
        for (int64_t j = 0; j < c && st == QDC_OK; j++)
            st = g_int(g, "$Nodes: node tag", 1, INT32_MAX, &g->tags[i + j], err);
        for (int64_t j = 0; j < c && st == QDC_OK; j++)
            st = node_coords(g, i + j, par * dim, err);
        i += c;
    }
    return nodes_close(g, st, i, total, 0, err);
}

/* $Nodes (4.0 ASCII): blocks "entity dim parametric n", then "tag x y z" lines. */
static qdc_status nodes40(gmsh *g, qdc_error *err)
{
    int64_t nblk, total = 0, v, dim, par, c, i = 0;
    qdc_status st;

    st = g_count(g, "$Nodes: block count", 4, 0, INT32_MAX, &nblk, err);
    if (st == QDC_OK)
        st = g_count(g, "$Nodes: node count", 4, 0, MESH_MAX_VERTICES, &total, err);
    if (st == QDC_OK)
        st = nodes_alloc(g, total, err);
    for (int64_t b = 0; b < nblk && st == QDC_OK; b++) {
        st = g_i32(g, "$Nodes: entity tag", INT32_MIN, INT32_MAX, &v, err);
        if (st == QDC_OK)
            st = g_i32(g, "$Nodes: entity dimension", 0, 3, &dim, err);
        if (st == QDC_OK)
            st = g_i32(g, "$Nodes: parametric", 0, 1, &par, err);
        if (st == QDC_OK)
            st = g_count(g, "$Nodes: nodes in block", 4, 0, INT64_MAX, &c, err);
        if (st == QDC_OK)
            st = nodes_fit(g, i, c, total, 1, err);
        if (st == QDC_OK)
            st = dv_block(g, dim, v, i, c, err);
        for (int64_t j = 0; j < c && st == QDC_OK; j++) {
            st = g_int(g, "$Nodes: node tag", 1, INT32_MAX, &g->tags[i + j], err);
            if (st == QDC_OK)
                st = node_coords(g, i + j, par * dim, err);
            else
                set_index(err, "vertex", i + j);
        }
        i += c;
    }
    return nodes_close(g, st, i, total, 1, err);
}

/* $Nodes (2.x): "n" on its own line, then "tag x y z" lines (ASCII) or n
 * records of an int32 tag and three float64 (binary). */
static qdc_status nodes22(gmsh *g, qdc_error *err)
{
    int64_t total;
    qdc_status st = txt_count(&g->s, "$Nodes", 4, MESH_MAX_VERTICES, &total, err);

    if (st == QDC_OK && g->binary) {
        end_of_line(g);
        st = bin_need(g, (uint64_t)total * 28, "$Nodes: binary records", err);
    }
    if (st == QDC_OK)
        st = nodes_alloc(g, total, err);
    for (int64_t i = 0; i < total && st == QDC_OK; i++) {
        if (g->binary)
            st = g_i32(g, "$Nodes: node tag", 1, INT32_MAX, &g->tags[i], err);
        else
            st = txt_int(&g->s, "$Nodes: node tag", 1, INT32_MAX, &g->tags[i], err);
        if (st == QDC_OK)
            st = node_coords(g, i, 0, err);
        else
            set_index(err, "vertex", i);
    }
    return nodes_close(g, st, total, total, 1, err);
}

/* Room for c more elements of kind k. */
static qdc_status elems_grow(gmsh *g, int k, int64_t c, qdc_error *err)
{
    elems *e = &g->el[k];

    if (e->idx.n / (size_t)(3 + k) + (size_t)c >
        (size_t)(k ? MESH_MAX_TETS : INT32_MAX / 3))
        return qdc_fail(err, QDC_ETOOBIG, "more than %d %ss",
                        k ? MESH_MAX_TETS : INT32_MAX / 3, elem_names[k]);
    if (vec_grow(&e->idx, (size_t)c * (size_t)(3 + k)) != 0 ||
        vec_grow(&e->phys, (size_t)c) != 0 || vec_grow(&e->ent, (size_t)c) != 0 ||
        (k && g->order == 2 && vec_grow(&g->mid, (size_t)c * 6) != 0))
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld %ss", (long long)c,
                        elem_names[k]);
    return QDC_OK;
}

/* One node reference: tag -> index. */
static qdc_status node_ref(gmsh *g, int k, int32_t *out, qdc_error *err)
{
    const char *at;
    int64_t tag, i;
    qdc_status st;

    if (!g->binary)
        skip_ws(&g->s); /* errors point at the tag */
    at = g->s.p;
    st = g->binary && g->ver == 22
             ? g_i32(g, "$Elements: node tag", 1, INT32_MAX, &tag, err)
             : g_int(g, "$Elements: node tag", 1, INT64_MAX, &tag, err);

    if (st != QDC_OK)
        return st;
    i = tagmap_find(&g->tm, tag);
    if (i < 0) {
        if (g->binary)
            fail_bin(err, QDC_EPARSE, at - g->s.base,
                     "$Elements: %s: unknown node tag %lld", elem_names[k],
                     (long long)tag);
        else
            fail_txt(err, QDC_EPARSE, &g->s, at, "$Elements: %s: unknown node tag %lld",
                     elem_names[k], (long long)tag);
        set_index(err, elem_names[k], (int64_t)(g->el[k].phys.n));
        return QDC_EPARSE;
    }
    *out = (int32_t)i;
    return QDC_OK;
}

/* Gmsh's 10-node tet lists its mid-edge nodes on edges 01, 12, 20, 30, 32,
 * 31 (the Gmsh manual's node ordering): the last two are swapped against
 * mesh_p2_edges. gmsh_p2[e]: which of the file's six is edge e. */
static const int gmsh_p2[6] = {0, 1, 2, 3, 5, 4};

/* The nodes of a 10-node tet past its corners, in(to) mesh_p2_edges order. */
static void put_mid(gmsh *g, const int32_t file[6])
{
    int32_t *o = (int32_t *)g->mid.a + g->mid.n;

    for (int e = 0; e < 6; e++)
        o[e] = file[gmsh_p2[e]];
    g->mid.n += 6;
}

/* Nodes per element of kind k: tets 4 or 10, triangles 3 or 6. */
static int kind_nodes(const gmsh *g, int k, int64_t type)
{
    return k ? (g->order == 2 ? 10 : 4) : type == 9 ? 6 : 3;
}

/* One element of kind k and type: its nodes (the element tag was read); a
 * 6-node triangle keeps its corners, a 10-node tet puts the rest in g->mid. */
static qdc_status elem_nodes(gmsh *g, int k, int64_t type, int32_t phys, int32_t ent,
                             qdc_error *err)
{
    elems *e = &g->el[k];
    int32_t *idx = (int32_t *)e->idx.a + e->idx.n, extra[6];
    const int nn = kind_nodes(g, k, type);
    qdc_status st = QDC_OK;

    for (int j = 0; j < nn && st == QDC_OK; j++)
        st = node_ref(g, k, j < 3 + k ? &idx[j] : &extra[j - 3 - k], err);
    if (st != QDC_OK)
        return st;
    if (k && nn == 10)
        put_mid(g, extra);
    e->idx.n += (size_t)(3 + k);
    ((int32_t *)e->phys.a)[e->phys.n++] = phys;
    ((int32_t *)e->ent.a)[e->ent.n++] = ent;
    return QDC_OK;
}

/* Higher-order tetrahedra past the second (Gmsh types 29, 30, 31: 20, 35,
 * 56 nodes) would be broken by moving their corners alone: refused, naming
 * the type; a file of both linear (4) and second-order (11) tets too. at:
 * where the type is. */
static qdc_status ho_tet(gmsh *g, const char *at, int64_t type, qdc_error *err)
{
    static const char *const order[] = {"second", "third", "fourth", "fifth"};
    int o = type >= 29 && type <= 31 ? (int)type - 28 : -1;

    if (type == 4 || type == 11) {
        int want = type == 4 ? 1 : 2;
        if (g->order && g->order != want) {
            if (g->binary)
                return fail_bin(err, QDC_EFORMAT, at - g->s.base,
                                "$Elements: linear (type 4) and second-order (type 11) "
                                "tetrahedra in one file are not supported");
            return fail_txt(err, QDC_EFORMAT, &g->s, at,
                            "$Elements: linear (type 4) and second-order (type 11) "
                            "tetrahedra in one file are not supported");
        }
        g->order = want;
    }
    if (o < 0)
        return QDC_OK;
    if (g->binary)
        return fail_bin(err, QDC_EFORMAT, at - g->s.base,
                        "$Elements: %s-order tetrahedra (Gmsh element type %lld, %lld "
                        "nodes) are not supported: qdc optimizes linear and "
                        "second-order tetrahedra (types 4 and 11)",
                        order[o], (long long)type, (long long)type_nodes(type));
    return fail_txt(err, QDC_EFORMAT, &g->s, at,
                    "$Elements: %s-order tetrahedra (Gmsh element type %lld, %lld nodes) "
                    "are not supported: qdc optimizes linear and second-order "
                    "tetrahedra (types 4 and 11)",
                    order[o], (long long)type, (long long)type_nodes(type));
}

/* Skip the rest of an ASCII line (an element of a type we don't read). */
static void skip_line(txt *s)
{
    while (s->p < s->end && *s->p != '\n')
        s->p++;
}

/* Binary, a block of cnt elements of kind k whose bytes are all there: each
 * an element tag, ntags tags (2.2: physical, elementary, ...) and 3 + k node
 * tags, all words of w bytes (4 or 8). The records are read and stored while
 * the element tag is not negative and every node tag is known (phys and ent:
 * the block's, when the record has no tags); returns how many, and leaves the
 * scanner at the first one not read, for the checked path to read again and
 * say what is wrong with it. A 1M-tet file reads in half the time it takes
 * with the checked reads alone. */
static int64_t elems_bin_fast(gmsh *g, int k, int64_t type, int64_t cnt, int64_t ntags,
                              int w, int32_t phys0, int32_t ent0)
{
    elems *e = &g->el[k];
    const int nn = kind_nodes(g, k, type), nc = 3 + k;
    const size_t rec = (size_t)w * (size_t)(1 + ntags + nn);
    const unsigned char *p = g->b + boff(g);
    int32_t *idx, *phys, *ent;
    int64_t j;

    if (cnt <= 0 || !e->idx.a || !e->phys.a || !e->ent.a)
        return 0; /* nothing to store, or nowhere yet: the checked path reads it */
    idx = (int32_t *)e->idx.a + e->idx.n;
    phys = (int32_t *)e->phys.a + e->phys.n;
    ent = (int32_t *)e->ent.a + e->ent.n;

    for (j = 0; j < cnt; j++, p += rec) {
        const unsigned char *q = p + (size_t)w * (size_t)(1 + ntags);
        int32_t ix[10];
        int a;
        if (w == 8 && (int64_t)get_le64(p) < 0)
            break;
        for (a = 0; a < nn; a++) {
            int64_t t = w == 4 ? (int64_t)(int32_t)get_le32(q + 4 * a)
                               : (int64_t)get_le64(q + 8 * a);
            int64_t i = tagmap_find(&g->tm, t);
            if (i < 0)
                break;
            ix[a] = (int32_t)i;
        }
        if (a < nn)
            break;
        memcpy(idx + (size_t)j * (size_t)nc, ix, sizeof(int32_t) * (size_t)nc);
        if (nn == 10)
            put_mid(g, ix + 4);
        phys[j] = ntags > 0 ? (int32_t)get_le32(p + 4) : phys0;
        ent[j] = ntags > 1 ? (int32_t)get_le32(p + 8) : ent0;
    }
    e->idx.n += (size_t)j * (size_t)nc;
    e->phys.n += (size_t)j;
    e->ent.n += (size_t)j;
    g->s.p += (size_t)j * rec;
    return j;
}

/* $Elements (4.1): blocks of one type on one entity. */
static qdc_status elements41(gmsh *g, qdc_error *err)
{
    int64_t nblk, total, v, dim, etag, type, c, j;
    int32_t phys;
    qdc_status st;

    st = g_count(g, "$Elements: block count", 4, 16, INT32_MAX, &nblk, err);
    if (st == QDC_OK)
        st = g_count(g, "$Elements: element count", 2, 16, INT64_MAX, &total, err);
    for (int k = 0; k < 2 && st == QDC_OK; k++)
        st = g_int(g, "$Elements: element tag bound", 0, INT64_MAX, &v, err);
    for (int64_t b = 0; b < nblk && st == QDC_OK; b++) {
        const char *at;
        int64_t nn;
        int k;
        st = g_i32(g, "$Elements: entity dimension", 0, 3, &dim, err);
        if (st == QDC_OK)
            st = g_i32(g, "$Elements: entity tag", INT32_MIN, INT32_MAX, &etag, err);
        if (!g->binary)
            skip_ws(&g->s);
        at = g->s.p;
        if (st == QDC_OK)
            st = g_i32(g, "$Elements: element type", INT32_MIN, INT32_MAX, &type, err);
        if (st == QDC_OK)
            st = ho_tet(g, at, type, err);
        if (st != QDC_OK)
            break;
        nn = type_nodes(type);
        if (!nn && g->binary)
            return fail_bin(err, QDC_EFORMAT, at - g->s.base,
                            "$Elements: unknown element type %lld", (long long)type);
        st = g_count(g, "$Elements: elements in block", 2,
                     (uint64_t)(nn + 1) * (uint64_t)g->dsize, INT64_MAX, &c, err);
        if (st != QDC_OK)
            break;
        k = type == 4 || type == 11 ? 1 : type == 2 || type == 9 ? 0 : -1;
        if (k < 0) {
            skip_count(&g->sk, type, c);
            if (g->binary) {
                g->s.p += (size_t)c * (size_t)(nn + 1) * (size_t)g->dsize;
            } else {
                for (j = 0; j < c; j++) {
                    skip_ws(&g->s);
                    skip_line(&g->s);
                }
            }
            continue;
        }
        st = elems_grow(g, k, c, err);
        if (st != QDC_OK)
            break;
        phys = entity_phys(g, k, etag);
        j = g->binary ? elems_bin_fast(g, k, type, c, 0, g->dsize, phys, (int32_t)etag)
                      : 0;
        for (; j < c && st == QDC_OK; j++) {
            st = g_int(g, "$Elements: element tag", 0, INT64_MAX, &v, err);
            if (st == QDC_OK)
                st = elem_nodes(g, k, type, phys, (int32_t)etag, err);
        }
    }
    return st == QDC_OK ? want_end(g, "Elements", err) : st;
}

/* $Elements (2.2 ASCII): "tag type ntags tags... nodes...". */
static qdc_status elements22(gmsh *g, qdc_error *err)
{
    txt *s = &g->s;
    int64_t total, v, type, ntags, phys, ent;
    qdc_status st = txt_count(s, "$Elements", 4, INT64_MAX, &total, err);

    for (int64_t i = 0; i < total && st == QDC_OK; i++) {
        int k;
        const char *at;
        st = txt_int(s, "$Elements: element tag", 0, INT64_MAX, &v, err);
        skip_ws(s);
        at = s->p;
        if (st == QDC_OK)
            st = txt_int(s, "$Elements: element type", INT32_MIN, INT32_MAX, &type, err);
        if (st == QDC_OK)
            st = ho_tet(g, at, type, err);
        if (st != QDC_OK)
            break;
        k = type == 4 || type == 11 ? 1 : type == 2 || type == 9 ? 0 : -1;
        if (k < 0) {
            skip_count(&g->sk, type, 1);
            skip_line(s);
            continue;
        }
        st = txt_int(s, "$Elements: tag count", 0, 1000, &ntags, err);
        phys = ent = 0;
        for (int64_t j = 0; j < ntags && st == QDC_OK; j++) {
            st = txt_int(s, "$Elements: tag", INT32_MIN, INT32_MAX, &v, err);
            if (j == 0)
                phys = v;
            else if (j == 1)
                ent = v;
        }
        if (st == QDC_OK)
            st = elems_grow(g, k, 1, err);
        if (st == QDC_OK)
            st = elem_nodes(g, k, type, (int32_t)phys, (int32_t)ent, err);
    }
    return st == QDC_OK ? want_end(g, "Elements", err) : st;
}

/* $Elements (4.0 ASCII): blocks "entity dim type n", then "tag nodes..." lines. */
static qdc_status elements40(gmsh *g, qdc_error *err)
{
    int64_t nblk, total, v, dim, etag, type, c;
    qdc_status st;

    st = g_count(g, "$Elements: block count", 4, 0, INT32_MAX, &nblk, err);
    if (st == QDC_OK)
        st = g_count(g, "$Elements: element count", 2, 0, INT64_MAX, &total, err);
    for (int64_t b = 0; b < nblk && st == QDC_OK; b++) {
        int k;
        st = g_i32(g, "$Elements: entity tag", INT32_MIN, INT32_MAX, &etag, err);
        const char *at;
        if (st == QDC_OK)
            st = g_i32(g, "$Elements: entity dimension", 0, 3, &dim, err);
        skip_ws(&g->s);
        at = g->s.p;
        if (st == QDC_OK)
            st = g_i32(g, "$Elements: element type", INT32_MIN, INT32_MAX, &type, err);
        if (st == QDC_OK)
            st = ho_tet(g, at, type, err);
        if (st == QDC_OK)
            st = g_count(g, "$Elements: elements in block", 2, 0, INT64_MAX, &c, err);
        if (st != QDC_OK)
            break;
        k = type == 4 || type == 11 ? 1 : type == 2 || type == 9 ? 0 : -1;
        if (k < 0) {
            skip_count(&g->sk, type, c);
            for (int64_t j = 0; j < c; j++) {
                skip_ws(&g->s);
                skip_line(&g->s);
            }
            continue;
        }
        st = elems_grow(g, k, c, err);
        for (int64_t j = 0; j < c && st == QDC_OK; j++) {
            st = g_int(g, "$Elements: element tag", 0, INT64_MAX, &v, err);
            if (st == QDC_OK)
                st = elem_nodes(g, k, type, entity_phys(g, k, etag), (int32_t)etag, err);
        }
    }
    return st == QDC_OK ? want_end(g, "Elements", err) : st;
}

/* $Elements (2.2 binary): "n" on its own line, then groups of one type: an
 * int32 header "type count ntags", then count records of int32 "tag tags...
 * nodes...". */
static qdc_status elements22_bin(gmsh *g, qdc_error *err)
{
    txt *s = &g->s;
    int64_t total, done = 0, type, cnt, ntags, v, phys, ent, j;
    qdc_status st = txt_count(s, "$Elements", 4, INT64_MAX, &total, err);

    if (st == QDC_OK)
        end_of_line(g);
    while (done < total && st == QDC_OK) {
        const char *at = s->p;
        uint64_t rec;
        int64_t nn;
        int k;
        st = g_i32(g, "$Elements: element type", INT32_MIN, INT32_MAX, &type, err);
        if (st == QDC_OK)
            st = ho_tet(g, at, type, err);
        if (st == QDC_OK)
            st = g_i32(g, "$Elements: elements in group", 1, total - done, &cnt, err);
        if (st == QDC_OK)
            st = g_i32(g, "$Elements: tag count", 0, 1000, &ntags, err);
        if (st != QDC_OK)
            break;
        nn = type_nodes(type);
        if (!nn)
            return fail_bin(err, QDC_EFORMAT, at - s->base,
                            "$Elements: unknown element type %lld", (long long)type);
        rec = 4 * (uint64_t)(1 + ntags + nn);
        st = bin_need(g, (uint64_t)cnt * rec, "$Elements: element group", err);
        if (st != QDC_OK)
            break;
        done += cnt;
        k = type == 4 || type == 11 ? 1 : type == 2 || type == 9 ? 0 : -1;
        if (k < 0) {
            skip_count(&g->sk, type, cnt);
            s->p += (size_t)cnt * (size_t)rec;
            continue;
        }
        st = elems_grow(g, k, cnt, err);
        if (st != QDC_OK)
            break;
        /* the group's bytes are there (bin_need above): whole records are read
         * here, and the first one that is not right is read again below, which
         * says what is wrong with it */
        j = elems_bin_fast(g, k, type, cnt, ntags, 4, 0, 0);
        for (; j < cnt && st == QDC_OK; j++) {
            st = g_i32(g, "$Elements: element tag", INT32_MIN, INT32_MAX, &v, err);
            phys = ent = 0;
            for (int64_t t = 0; t < ntags && st == QDC_OK; t++) {
                st = g_i32(g, "$Elements: tag", INT32_MIN, INT32_MAX, &v, err);
                if (t == 0)
                    phys = v;
                else if (t == 1)
                    ent = v;
            }
            if (st == QDC_OK)
                st = elem_nodes(g, k, type, (int32_t)phys, (int32_t)ent, err);
        }
    }
    return st == QDC_OK ? want_end(g, "Elements", err) : st;
}

/* 4.0 and 2.x: an optional "Affine" line of 16 values after the link header. */
static qdc_status affine_line(gmsh *g, qdc_error *err)
{
    txt *s = &g->s;
    double x;
    qdc_status st = QDC_OK;

    skip_ws(s);
    if ((size_t)(s->end - s->p) < 6 || memcmp(s->p, "Affine", 6) != 0)
        return QDC_OK;
    s->p += 6;
    for (int j = 0; j < 16 && st == QDC_OK; j++)
        st = txt_real(s, "$Periodic: affine value", &x, err);
    return st;
}

/* $Periodic: links "dim tag master-tag", their affine transform (4.1: a
 * count and values; 4.0, 2.x: an optional "Affine" line) and node pairs
 * "tag master-tag". The tags of both nodes of every pair are kept: those
 * vertices are held (gmsh_mesh), so a pair never moves apart. 4.1 binary
 * files write it in binary, 2.2 binary files in ASCII. */
static qdc_status periodic(gmsh *g, qdc_error *err)
{
    int bin = g->binary;
    int64_t nl, v, na, np;
    double x;
    qdc_status st;

    g->binary = bin && g->ver == 41;
    st = g_count(g, "$Periodic: link count", 4, 12 + 2 * (uint64_t)g->dsize, INT32_MAX,
                 &nl, err);
    for (int64_t l = 0; l < nl && st == QDC_OK; l++) {
        for (int j = 0; j < 3 && st == QDC_OK; j++)
            st = g_i32(g, j ? "$Periodic: entity tag" : "$Periodic: entity dimension",
                       j ? INT32_MIN : 0, j ? INT32_MAX : 3, &v, err);
        if (st == QDC_OK && g->ver == 41)
            st = g_count(g, "$Periodic: affine value count", 1, 8, 16, &na, err);
        for (int64_t j = 0; g->ver == 41 && j < na && st == QDC_OK; j++)
            st = g_real(g, "$Periodic: affine value", &x, err);
        if (st == QDC_OK && g->ver != 41)
            st = affine_line(g, err);
        if (st == QDC_OK)
            st = g_count(g, "$Periodic: node pair count", 2, 2 * (uint64_t)g->dsize,
                         INT32_MAX, &np, err);
        if (st == QDC_OK && vec_grow(&g->per, 2 * (size_t)np) != 0)
            st = qdc_fail(err, QDC_ENOMEM, "out of memory for %lld periodic pairs",
                          (long long)np);
        for (int64_t j = 0; j < 2 * np && st == QDC_OK; j++)
            st = g_int(g, "$Periodic: node tag", 1, INT64_MAX,
                       &((int64_t *)g->per.a)[g->per.n++], err);
    }
    g->nlinks += nl;
    g->binary = bin;
    return st == QDC_OK ? want_end(g, "Periodic", err) : st;
}

/* A $NodeData header line's first string tag (the view's name): quoted or
 * one word, into [*n, *ne); the rest of the line passed over. */
static void nd_string(gmsh *g, const char **n, const char **ne)
{
    txt *s = &g->s;
    const char *p;

    skip_ws(s);
    p = s->p;
    if (p < s->end && *p == '"') {
        *n = ++p;
        while (p < s->end && *p != '"' && *p != '\n')
            p++;
        *ne = p;
    } else {
        *n = p;
        *ne = p = tok_end(s, p);
    }
    while (p < s->end && *p != '\n')
        p++;
    s->p = p;
}

/* The $NodeData header: *name, the component and value counts (the 2nd and
 * 3rd integer tags). */
static qdc_status nd_header(gmsh *g, const char **name, size_t *nl, int64_t *ncomp,
                            int64_t *nitems, qdc_error *err)
{
    int64_t c, x;
    const char *n = "", *ne = "";
    qdc_status st = txt_int(&g->s, "$NodeData: string tags", 0, 1 << 16, &c, err);

    for (int64_t i = 0; i < c && st == QDC_OK; i++) {
        const char *a, *ae;
        nd_string(g, &a, &ae);
        if (i == 0) {
            n = a;
            ne = ae;
        }
    }
    if (st == QDC_OK)
        st = txt_int(&g->s, "$NodeData: real tags", 0, 1 << 16, &c, err);
    for (int64_t i = 0; i < c && st == QDC_OK; i++) {
        double t;
        skip_ws(&g->s);
        const char *te = tok_end(&g->s, g->s.p);
        if (parse_double(g->s.p, te, &t) != 0)
            st = qdc_fail(err, QDC_EPARSE, "$NodeData: a real tag is not a number");
        g->s.p = te;
    }
    if (st == QDC_OK)
        st = txt_int(&g->s, "$NodeData: integer tags", 3, 1 << 16, &c, err);
    for (int64_t i = 0; i < c && st == QDC_OK; i++) {
        st = txt_int(&g->s, "$NodeData: integer tag", INT32_MIN, INT32_MAX, &x, err);
        if (i == 1)
            *ncomp = x;
        if (i == 2)
            *nitems = x;
    }
    *name = n;
    *nl = (size_t)(ne - n);
    if (st == QDC_OK && (*ncomp < 1 || *ncomp > (1 << 16) || *nitems != g->nv))
        st = qdc_fail(err, QDC_EPARSE,
                      "$NodeData: %lld values of %lld components for %lld nodes",
                      (long long)*nitems, (long long)*ncomp, (long long)g->nv);
    return st;
}

/* The values of nitems nodes (tag, ncomp values each) into v, every node
 * once (v starts NaN: a node left out leaves one). */
static qdc_status nd_values(gmsh *g, int64_t ncomp, int64_t nitems, double *v,
                            qdc_error *err)
{
    uint64_t per = g->binary ? 4 + 8 * (uint64_t)ncomp : 2 * (1 + (uint64_t)ncomp);
    qdc_status st = QDC_OK;

    if (g->binary)
        end_of_line(g);
    if ((uint64_t)nitems > (uint64_t)(g->s.end - g->s.p) / per)
        return qdc_fail(err, QDC_EPARSE, "$NodeData: %lld values do not fit",
                        (long long)nitems);
    for (size_t i = 0; i < (size_t)nitems * (size_t)ncomp; i++)
        v[i] = NAN;
    for (int64_t i = 0; i < nitems && st == QDC_OK; i++) {
        int64_t tag, k;
        if (g->binary)
            tag = bin_i32(g);
        else
            st = txt_int(&g->s, "$NodeData: node tag", INT64_MIN / 2, INT64_MAX / 2, &tag,
                         err);
        k = st == QDC_OK ? tagmap_find(&g->tm, tag) : -1;
        if (st == QDC_OK && k < 0)
            st = qdc_fail(err, QDC_EPARSE, "$NodeData: node tag %lld is no node's",
                          (long long)tag);
        for (int64_t c = 0; c < ncomp && st == QDC_OK; c++) {
            double *x = &v[(size_t)k * (size_t)ncomp + (size_t)c];
            if (g->binary)
                *x = bin_f64(g);
            else
                st = txt_real(&g->s, "$NodeData: value", x, err);
        }
    }
    return st;
}

/* $NodeData (after its name): the array into g->pd, replacing one of the
 * same name (of an earlier time step: the last is kept). A section qdc
 * cannot take (before $Nodes, another count than the nodes', a node left
 * out or twice, a value NaN/Inf or not a number) is passed over with a note,
 * as qdc passed over every $NodeData before it kept them. */
static qdc_status node_data(gmsh *g, const char *sec, size_t slen, qdc_error *err)
{
    txt at = g->s;
    const char *name = "";
    size_t nl = 0;
    int64_t ncomp = 0, nitems = -1;
    double *v = NULL;
    qdc_status st = g->have_nodes ? QDC_OK : QDC_EPARSE;

    if (st == QDC_OK)
        st = nd_header(g, &name, &nl, &ncomp, &nitems, err);
    if (st == QDC_OK &&
        (uint64_t)nitems > (uint64_t)(g->s.end - g->s.p) /
                               (uint64_t)(g->binary ? 4 + 8 * ncomp : 2 + 2 * ncomp))
        st = qdc_fail(err, QDC_EPARSE, "$NodeData: %lld values do not fit",
                      (long long)nitems);
    if (st == QDC_OK && !(v = qdc_mallocn((size_t)nitems * (size_t)ncomp + 1, sizeof *v)))
        return qdc_fail(err, QDC_ENOMEM, "out of memory for $NodeData");
    if (st == QDC_OK)
        st = nd_values(g, ncomp, nitems, v, err);
    for (size_t i = 0; st == QDC_OK && i < (size_t)nitems * (size_t)ncomp; i++)
        if (!isfinite(v[i]))
            st = qdc_fail(err, QDC_EPARSE, "$NodeData: node %zu left out or NaN/Inf",
                          i / (size_t)ncomp);
    if (st == QDC_OK)
        st = want_end(g, "NodeData", err);
    if (st != QDC_OK) {
        note(g->o, "gmsh: $NodeData %.*s passed over: %s", (int)(nl > 64 ? 64 : nl), name,
             g->have_nodes ? err->msg : "before $Nodes");
        qdc_free(v);
        qdc_error_clear(err);
        g->s = at;
        return skip_section(g, sec, slen, err);
    }
    for (int32_t i = 0; g->pd && i < g->pd->n; i++)
        if (strlen(g->pd->a[i].name) == nl && !memcmp(g->pd->a[i].name, name, nl) &&
            g->pd->a[i].ncomp == ncomp) { /* an earlier time step */
            qdc_free(g->pd->a[i].v);
            g->pd->a[i].v = v;
            return QDC_OK;
        }
    return pdata_take(&g->pd, g->nv, nl ? name : "data", nl ? nl : 4, ncomp, 0, "double",
                      v, g->o, "gmsh", err);
}

static qdc_status gmsh_section(gmsh *g, const char *name, size_t nlen, qdc_error *err)
{
    if (word_is(name, nlen, "Periodic")) {
        end_of_line(g);
        return periodic(g, err);
    }
    if (word_is(name, nlen, "Entities") && g->ver >= 40) {
        end_of_line(g);
        return entities(g, err);
    }
    if (word_is(name, nlen, "Nodes")) {
        if (g->have_nodes)
            return fail_txt(err, QDC_EPARSE, &g->s, name - 1, "duplicate $Nodes section");
        end_of_line(g);
        return g->ver == 41   ? nodes41(g, err)
               : g->ver == 40 ? nodes40(g, err)
                              : nodes22(g, err);
    }
    if (word_is(name, nlen, "Elements")) {
        if (!g->have_nodes)
            return fail_txt(err, QDC_EPARSE, &g->s, name - 1, "$Elements before $Nodes");
        if (g->el[0].phys.n || g->el[1].phys.n)
            return fail_txt(err, QDC_EPARSE, &g->s, name - 1,
                            "duplicate $Elements section");
        end_of_line(g);
        return g->ver == 41   ? elements41(g, err)
               : g->ver == 40 ? elements40(g, err)
               : g->binary    ? elements22_bin(g, err)
                              : elements22(g, err);
    }
    if (word_is(name, nlen, "NodeData")) {
        end_of_line(g);
        return node_data(g, name, nlen, err);
    }
    return skip_section(g, name, nlen, err);
}

/* The vertices of the $Periodic pairs, held (pm->fix). A tag of no node
 * (a node of an entity the file does not hold) needs nothing. */
static qdc_status periodic_held(gmsh *g, parsed *pm, qdc_error *err)
{
    const int64_t *tag = g->per.a;

    if (!g->nlinks)
        return QDC_OK;
    pm->fix = qdc_mallocn(g->per.n + 1, sizeof(int32_t));
    if (!pm->fix)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the periodic nodes");
    pm->nfix = 0;
    for (size_t i = 0; i < g->per.n; i++) {
        int64_t v = tagmap_find(&g->tm, tag[i]);
        if (v >= 0)
            pm->fix[pm->nfix++] = (int32_t)v;
    }
    return QDC_OK;
}

static void periodic_note(const gmsh *g, const meshio_options *o, const mesh_t *m)
{
    int64_t n = 0;

    for (int32_t v = 0; v < m->nv; v++)
        n += m->fixed[v] != 0;
    note(o,
         "gmsh: $Periodic: %lld links, %lld node pairs: their %lld vertices are held "
         "fixed (a pair never moves apart)",
         (long long)g->nlinks, (long long)(g->per.n / 2), (long long)n);
}

static qdc_status gmsh_mesh(gmsh *g, const meshio_options *o, mesh_t **out,
                            qdc_error *err)
{
    parsed pm;
    int32_t *reg[2];
    qdc_status st;

    for (int k = 0; k < 2; k++) {
        pick_regions(g->el[k].phys.a, g->el[k].ent.a, (int64_t)g->el[k].phys.n, &reg[k]);
        g->el[k].phys.a = g->el[k].ent.a = NULL;
    }
    parsed_init(&pm);
    pm.nv = g->nv;
    pm.xyz = g->xyz;
    pm.nt = (int64_t)g->el[1].phys.n;
    pm.tets = g->el[1].idx.a;
    pm.region = reg[1];
    pm.ntri = (int64_t)g->el[0].phys.n;
    pm.tris = g->el[0].idx.a;
    pm.tri_ref = pm.ntri ? reg[0] : NULL;
    st = periodic_held(g, &pm, err);
    if (st == QDC_OK)
        st = parsed_mesh(&pm, out, err);
    if (st == QDC_OK && g->order == 2) {
        st = mesh_set_mid(*out);
        if (st != QDC_OK) {
            mesh_free(*out);
            *out = NULL;
            st = qdc_fail(err, QDC_ENOMEM, "out of memory for the mid-edge nodes");
        } else {
            memcpy((*out)->mid, g->mid.a, (size_t)pm.nt * 6 * sizeof(int32_t));
        }
    }
    if (st == QDC_OK && pm.nfix > 0)
        periodic_note(g, o, *out);
    if (st == QDC_OK) {
        (*out)->pdata = g->pd;
        g->pd = NULL;
    }
    qdc_free(reg[0]);
    qdc_free(reg[1]);
    qdc_free(pm.fix);
    skip_note(o, &g->sk, "gmsh", "elements");
    return st;
}

static qdc_status read_gmsh(const char *buf, size_t len, const meshio_options *o,
                            srcrec *rec, mesh_t **out, qdc_error *err)
{
    gmsh g;
    const char *name = NULL;
    size_t nlen;
    qdc_status st;

    memset(&g, 0, sizeof g);
    g.rec = rec;
    g.o = o;
    g.per.size = sizeof(int64_t);
    g.mid.size = sizeof(int32_t);
    for (int k = 0; k < 2; k++) {
        g.ent[k].size = sizeof(int64_t);
        g.el[k].idx.size = g.el[k].phys.size = g.el[k].ent.size = sizeof(int32_t);
    }
    g.s = txt_init(buf, len, 0);
    g.b = (const unsigned char *)buf;
    st = next_marker(&g, &name, &nlen, err);
    if (st == QDC_OK && word_is(name, nlen, "NOD")) /* MSH 1: its own reader */
        return fmt_msh1.read(buf, len, o, rec, out, err);
    if (st == QDC_OK && !word_is(name, nlen, "MeshFormat"))
        st = fail_txt(err, QDC_EPARSE, &g.s, g.s.p, "expected $MeshFormat first");
    if (st == QDC_OK) {
        end_of_line(&g);
        st = mesh_format(&g, err);
    }
    while (st == QDC_OK) {
        st = next_marker(&g, &name, &nlen, err);
        if (st != QDC_OK || !nlen)
            break;
        st = gmsh_section(&g, name, nlen, err);
    }
    if (st == QDC_OK && !g.have_nodes)
        st = fail_txt(err, QDC_EPARSE, &g.s, g.s.p, "no $Nodes section");
    if (st == QDC_OK && rec && rec->dv.kind == DV_BOXES)
        st = dv_finish(&rec->dv, g.xyz, g.nv, err);
    if (st == QDC_OK)
        st = gmsh_mesh(&g, o, out, err);
    gmsh_free(&g);
    return st;
}

/* ------------------------------------------------------------------------ */
/* Writing                                                                   */

static int cmp_i32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;

    return (x > y) - (x < y);
}

/* The distinct values of v[n] (NULL: the single value 0), sorted. */
typedef struct {
    int32_t *u;
    size_t n;
} distinct;

static int distinct_of(distinct *d, const int32_t *v, size_t n)
{
    d->n = 0;
    d->u = qdc_mallocn(n + 1, sizeof(int32_t));
    if (!d->u)
        return -1;
    if (!v || !n) {
        d->u[d->n++] = 0;
        return 0;
    }
    memcpy(d->u, v, n * sizeof(int32_t));
    qsort(d->u, n, sizeof(int32_t), cmp_i32);
    for (size_t i = 0; i < n; i++)
        if (!d->n || d->u[d->n - 1] != d->u[i])
            d->u[d->n++] = d->u[i];
    return 0;
}

/* 1-based entity tag of value x. */
static int64_t entity_of(const distinct *d, const int32_t *v, size_t i)
{
    int32_t x = v ? v[i] : 0;
    const int32_t *p = bsearch(&x, d->u, d->n, sizeof(int32_t), cmp_i32);

    return p ? p - d->u + 1 : 1;
}

typedef struct {
    wbuf *w;
    int bin;
} gw;

static void gw_size(gw *g, uint64_t v, const char *sep)
{
    unsigned char b[8];

    if (g->bin) {
        put_le64(b, v);
        wb_put(g->w, b, 8);
        return;
    }
    wb_int(g->w, (int64_t)v);
    wb_str(g->w, sep);
}

static void gw_i32(gw *g, int64_t v, const char *sep)
{
    unsigned char b[4];

    if (g->bin) {
        put_le32(b, (uint32_t)(int32_t)v);
        wb_put(g->w, b, 4);
        return;
    }
    wb_int(g->w, v);
    wb_str(g->w, sep);
}

static void gw_real(gw *g, double x, const char *sep)
{
    unsigned char b[8];
    uint64_t u;

    if (g->bin) {
        memcpy(&u, &x, 8);
        put_le64(b, u);
        wb_put(g->w, b, 8);
        return;
    }
    wb_real(g->w, x);
    wb_str(g->w, sep);
}

/* Surfaces (k=0) or volumes (k=1) of $Entities, one per distinct tag value;
 * value 0 has no physical tag. */
static void write_entities(gw *g, const distinct *d, const double lo[3],
                           const double hi[3])
{
    for (size_t i = 0; i < d->n; i++) {
        gw_i32(g, (int64_t)i + 1, " ");
        for (int a = 0; a < 6; a++)
            gw_real(g, a < 3 ? lo[a] : hi[a - 3], " ");
        gw_size(g, d->u[i] != 0, " ");
        if (d->u[i] != 0)
            gw_i32(g, d->u[i], " ");
        gw_size(g, 0, "\n");
    }
}

/* Elements of one kind as blocks of consecutive equal tags (order kept). */
static void write_blocks(gw *g, int dim, int type, const int32_t *idx, int k,
                         const int32_t *tag, int32_t n, const distinct *d, int64_t *etag)
{
    for (int32_t i = 0; i < n;) {
        int32_t j = i + 1;
        if (!tag)
            j = n;
        while (j < n && tag[j] == tag[i])
            j++;
        gw_i32(g, dim, " ");
        gw_i32(g, entity_of(d, tag, (size_t)i), " ");
        gw_i32(g, type, " ");
        gw_size(g, (uint64_t)(j - i), "\n");
        for (; i < j; i++) {
            gw_size(g, (uint64_t)++ * etag, " ");
            for (int a = 0; a < k; a++)
                gw_size(g, (uint64_t)idx[(size_t)k * (size_t)i + (size_t)a] + 1,
                        a + 1 < k ? " " : "\n");
        }
    }
}

static int32_t count_blocks(const int32_t *tag, int32_t n)
{
    int32_t b = n > 0;

    for (int32_t i = 1; tag && i < n; i++)
        b += tag[i] != tag[i - 1];
    return b;
}

/* The tets as written: their nodes (4, or 10 in Gmsh's order) and type. */
typedef struct {
    const int32_t *v;
    int k, type;
} gtets;

static void write41(const mesh_t *m, const gtets *gt, const distinct d[2], wbuf *w,
                    int bin)
{
    gw g = {w, bin};
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    int64_t etag = 0;
    int32_t nb = count_blocks(m->region, m->nt) + count_blocks(m->tri_ref, m->ntri);
    unsigned char one[4];

    if (m->nv)
        mesh_bbox(m, lo, hi);
    wb_str(w, bin ? "$MeshFormat\n4.1 1 8\n" : "$MeshFormat\n4.1 0 8\n");
    if (bin) {
        put_le32(one, 1);
        wb_put(w, one, 4);
        wb_str(w, "\n");
    }
    wb_str(w, "$EndMeshFormat\n$Entities\n");
    gw_size(&g, 0, " ");
    gw_size(&g, 0, " ");
    gw_size(&g, m->ntri ? d[0].n : 0, " ");
    gw_size(&g, d[1].n, "\n");
    if (m->ntri)
        write_entities(&g, &d[0], lo, hi);
    write_entities(&g, &d[1], lo, hi);
    wb_str(w, bin ? "\n$EndEntities\n$Nodes\n" : "$EndEntities\n$Nodes\n");
    gw_size(&g, m->nv ? 1 : 0, " ");
    gw_size(&g, (uint64_t)m->nv, " ");
    gw_size(&g, m->nv ? 1 : 0, " ");
    gw_size(&g, (uint64_t)m->nv, "\n");
    if (m->nv) {
        gw_i32(&g, 3, " ");
        gw_i32(&g, 1, " ");
        gw_i32(&g, 0, " ");
        gw_size(&g, (uint64_t)m->nv, "\n");
        for (int32_t i = 0; i < m->nv; i++)
            gw_size(&g, (uint64_t)i + 1, "\n");
        for (size_t i = 0; i < 3 * (size_t)m->nv; i++)
            gw_real(&g, m->xyz[i], i % 3 == 2 ? "\n" : " ");
    }
    wb_str(w, bin ? "\n$EndNodes\n$Elements\n" : "$EndNodes\n$Elements\n");
    gw_size(&g, (uint64_t)nb, " ");
    gw_size(&g, (uint64_t)m->nt + (uint64_t)m->ntri, " ");
    gw_size(&g, m->nt + m->ntri ? 1 : 0, " ");
    gw_size(&g, (uint64_t)m->nt + (uint64_t)m->ntri, "\n");
    write_blocks(&g, 3, gt->type, gt->v, gt->k, m->region, m->nt, &d[1], &etag);
    write_blocks(&g, 2, 2, m->tris, 3, m->tri_ref, m->ntri, &d[0], &etag);
    wb_str(w, bin ? "\n$EndElements\n" : "$EndElements\n");
}

/* MSH 4.0 ASCII: as 4.1, with 4.0's block headers and node lines. */
static void write40(const mesh_t *m, const gtets *gt, const distinct d[2], wbuf *w)
{
    gw g = {w, 0};
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    int64_t etag = 0;
    int32_t nb = count_blocks(m->region, m->nt) + count_blocks(m->tri_ref, m->ntri);
    const int32_t *tag[2] = {m->tri_ref, m->region}, *idx[2] = {m->tris, gt->v};
    int32_t n[2] = {m->ntri, m->nt};
    const int nk[2] = {3, gt->k};

    if (m->nv)
        mesh_bbox(m, lo, hi);
    wb_str(w, "$MeshFormat\n4 0 8\n$EndMeshFormat\n$Entities\n");
    wb_str(w, "0 0 ");
    wb_int(w, m->ntri ? (int64_t)d[0].n : 0);
    wb_str(w, " ");
    wb_int(w, (int64_t)d[1].n);
    wb_str(w, "\n");
    if (m->ntri)
        write_entities(&g, &d[0], lo, hi);
    write_entities(&g, &d[1], lo, hi);
    wb_str(w, "$EndEntities\n$Nodes\n");
    wb_str(w, m->nv ? "1 " : "0 ");
    wb_int(w, m->nv);
    wb_str(w, "\n");
    if (m->nv) {
        wb_str(w, "1 3 0 ");
        wb_int(w, m->nv);
        wb_str(w, "\n");
        for (int32_t i = 0; i < m->nv; i++) {
            wb_int(w, (int64_t)i + 1);
            wb_str(w, " ");
            wb_reals(w, m->xyz + 3 * (size_t)i, 3, " ", "\n");
        }
    }
    wb_str(w, "$EndNodes\n$Elements\n");
    wb_int(w, nb);
    wb_str(w, " ");
    wb_int(w, (int64_t)m->nt + m->ntri);
    wb_str(w, "\n");
    for (int k = 1; k >= 0; k--) {
        for (int32_t i = 0; i < n[k];) {
            int32_t j = tag[k] ? i + 1 : n[k];
            while (j < n[k] && tag[k][j] == tag[k][i])
                j++;
            wb_int(w, entity_of(&d[k], tag[k], (size_t)i));
            wb_str(w, k ? (gt->type == 11 ? " 3 11 " : " 3 4 ") : " 2 2 ");
            wb_int(w, j - i);
            wb_str(w, "\n");
            for (; i < j; i++) {
                wb_int(w, ++etag);
                wb_str(w, " ");
                wb_ints(w, idx[k] + (size_t)nk[k] * (size_t)i, nk[k], 1, " ", "\n");
            }
        }
    }
    wb_str(w, "$EndElements\n");
}

/* 2.2 binary element group header and records: int32 values. */
static void put_i32s(wbuf *w, const int32_t *v, int n, int64_t add)
{
    unsigned char b[4];

    for (int i = 0; i < n; i++) {
        put_le32(b, (uint32_t)(v[i] + add));
        wb_put(w, b, 4);
    }
}

/* Elementary tags follow the regions (as in 4.1), so Gmsh's entities match
 * its physical groups. bin: 2.2 binary (one group per element type). */
static void write22(const mesh_t *m, const gtets *gt, const distinct d[2], wbuf *w,
                    int bin)
{
    unsigned char b[28];

    wb_str(w, bin ? "$MeshFormat\n2.2 1 8\n" : "$MeshFormat\n2.2 0 8\n");
    if (bin) {
        put_le32(b, 1);
        wb_put(w, b, 4);
        wb_str(w, "\n");
    }
    wb_str(w, "$EndMeshFormat\n$Nodes\n");
    wb_int(w, m->nv);
    wb_str(w, "\n");
    for (int32_t i = 0; i < m->nv; i++) {
        if (bin) {
            put_le32(b, (uint32_t)i + 1);
            for (int a = 0; a < 3; a++) {
                uint64_t u;
                memcpy(&u, &m->xyz[3 * (size_t)i + (size_t)a], 8);
                put_le64(b + 4 + 8 * a, u);
            }
            wb_put(w, b, 28);
            continue;
        }
        wb_int(w, (int64_t)i + 1);
        wb_str(w, " ");
        wb_reals(w, m->xyz + 3 * (size_t)i, 3, " ", "\n");
    }
    wb_str(w, bin ? "\n$EndNodes\n$Elements\n" : "$EndNodes\n$Elements\n");
    wb_int(w, (int64_t)m->nt + m->ntri);
    wb_str(w, "\n");
    if (bin) {
        const int32_t *tag[2] = {m->tri_ref, m->region}, *idx[2] = {m->tris, gt->v};
        int32_t n[2] = {m->ntri, m->nt}, e = 0;
        const int nk[2] = {3, gt->k};
        for (int k = 1; k >= 0; k--) {
            int32_t h[3] = {k ? gt->type : 2, n[k], 2};
            if (!n[k])
                continue;
            put_i32s(w, h, 3, 0);
            for (int32_t t = 0; t < n[k]; t++) {
                int32_t r[3] = {++e, tag[k] ? tag[k][t] : 0,
                                (int32_t)entity_of(&d[k], tag[k], (size_t)t)};
                put_i32s(w, r, 3, 0);
                put_i32s(w, idx[k] + (size_t)nk[k] * (size_t)t, nk[k], 1);
            }
        }
        wb_str(w, "\n$EndElements\n");
        return;
    }
    for (int32_t t = 0; t < m->nt; t++) {
        wb_int(w, (int64_t)t + 1);
        wb_str(w, gt->type == 11 ? " 11 2 " : " 4 2 ");
        wb_int(w, m->region ? m->region[t] : 0);
        wb_str(w, " ");
        wb_int(w, entity_of(&d[1], m->region, (size_t)t));
        wb_str(w, " ");
        wb_ints(w, gt->v + (size_t)gt->k * (size_t)t, gt->k, 1, " ", "\n");
    }
    for (int32_t t = 0; t < m->ntri; t++) {
        wb_int(w, (int64_t)m->nt + t + 1);
        wb_str(w, " 2 2 ");
        wb_int(w, m->tri_ref ? m->tri_ref[t] : 0);
        wb_str(w, " ");
        wb_int(w, entity_of(&d[0], m->tri_ref, (size_t)t));
        wb_str(w, " ");
        wb_ints(w, m->tris + 3 * (size_t)t, 3, 1, " ", "\n");
    }
    wb_str(w, "$EndElements\n");
}

/* m's point arrays, one $NodeData each (every version: one string tag, the
 * name in quotes, '"' and control bytes as '_'; time 0; time step 0, the
 * components, the nodes), values as doubles (%.17g in ASCII: they read back
 * exactly), in binary an int tag and the doubles of each node. */
static void write_node_data(const mesh_t *m, wbuf *w, int bin)
{
    gw g = {w, bin};

    for (int32_t i = 0; m->pdata && i < m->pdata->n; i++) {
        const mesh_parray *a = &m->pdata->a[i];
        size_t k = 0;
        char name[256];
        for (const char *c = a->name; *c && k < 255; c++, k++)
            name[k] = *c == '"' || (unsigned char)*c < 32 ? '_' : *c;
        name[k] = 0;
        wb_str(w, "$NodeData\n1\n\"");
        wb_str(w, name);
        wb_str(w, "\"\n1\n0\n3\n0\n");
        wb_int(w, a->ncomp);
        wb_str(w, "\n");
        wb_int(w, m->nv);
        wb_str(w, "\n");
        for (int32_t v = 0; v < m->nv; v++) {
            gw_i32(&g, (int64_t)v + 1, " ");
            for (int32_t c = 0; c < a->ncomp; c++)
                gw_real(&g, a->v[(size_t)v * (size_t)a->ncomp + (size_t)c],
                        c + 1 < a->ncomp ? " " : "\n");
        }
        wb_str(w, bin ? "\n$EndNodeData\n" : "$EndNodeData\n");
    }
}

static qdc_status write_gmsh(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                             qdc_error *err)
{
    (void)part;
    distinct d[2] = {{NULL, 0}, {NULL, 0}};
    qdc_status st = QDC_OK;
    gtets gt = {m->tets, 4, 4};
    int32_t *t10 = NULL;

    if (m->mid) { /* second-order: type 11, its mid-edge nodes in Gmsh's order */
        t10 = qdc_mallocn((size_t)m->nt * 10 + 1, sizeof(int32_t));
        if (!t10)
            return qdc_fail(err, QDC_ENOMEM, "out of memory for the 10-node tets");
        for (size_t t = 0; t < (size_t)m->nt; t++) {
            memcpy(t10 + 10 * t, m->tets + 4 * t, 4 * sizeof(int32_t));
            for (int f = 0; f < 6; f++) /* gmsh_p2 is its own inverse */
                t10[10 * t + 4 + (size_t)f] = m->mid[6 * t + (size_t)gmsh_p2[f]];
        }
        gt.v = t10;
        gt.k = 10;
        gt.type = 11;
    }
    if (distinct_of(&d[0], m->tri_ref, (size_t)m->ntri) != 0 ||
        distinct_of(&d[1], m->region, (size_t)m->nt) != 0)
        st = qdc_fail(err, QDC_ENOMEM, "out of memory for the Gmsh entities");
    else if (fmt == MESHIO_GMSH22 || fmt == MESHIO_GMSH22_BIN)
        write22(m, &gt, d, w, fmt == MESHIO_GMSH22_BIN);
    else if (fmt == MESHIO_GMSH40)
        write40(m, &gt, d, w);
    else
        write41(m, &gt, d, w, fmt == MESHIO_GMSH41_BIN);
    if (st == QDC_OK && m->pdata)
        write_node_data(m, w, fmt == MESHIO_GMSH22_BIN || fmt == MESHIO_GMSH41_BIN);
    qdc_free(t10);
    qdc_free(d[0].u);
    qdc_free(d[1].u);
    return st;
}

/* After "$MeshFormat": the version ("2.2", "4", "4.1") and the file type (0
 * ASCII, 1 binary). Unsupported versions go to the reader, which names them
 * ("$NOD", MSH 1, is msh1's). */
static meshio_format sniff_gmsh(const char *buf, size_t len, size_t i)
{
    const char *p;
    size_t n, k = 0, v, vn;
    int bin;

    if (len - i < 11 || memcmp(buf + i, "$MeshFormat", 11) != 0)
        return MESHIO_AUTO;
    p = buf + i + 11;
    n = len - i - 11;
    while (k < n && is_space((unsigned char)p[k]))
        k++;
    for (v = k; k < n && !is_space((unsigned char)p[k]); k++)
        ;
    vn = k - v;
    while (k < n && (p[k] == ' ' || p[k] == '\t'))
        k++;
    bin = k < n && p[k] == '1';
    if (vn >= 1 && p[v] == '2')
        return bin ? MESHIO_GMSH22_BIN : MESHIO_GMSH22;
    if ((vn == 1 && p[v] == '4') || (vn >= 3 && memcmp(p + v, "4.0", 3) == 0))
        return MESHIO_GMSH40;
    return bin ? MESHIO_GMSH41_BIN : MESHIO_GMSH41;
}

/* What every Gmsh variant shares: one reader and writer for all versions and
 * encodings, spliced writes, ten-node tets, point data ($NodeData). The variants differ
 * in their names and media types; .msh names the family (MSH 4.1 ASCII), whose sniffer
 * tells the others apart. */
#define GMSH_VARIANT                                                                     \
    .ext = "msh", .input = "input.msh", .read = read_gmsh, .write = write_gmsh,          \
    .splices = 1, .p2 = 1, .pdata = 1
#define GMSH_OTHER(var, name_, aliases_, about_, media_, media_alt_)                     \
    const meshio_fmt var = {.name = name_,                                               \
                            .aliases = aliases_,                                         \
                            .about = about_,                                             \
                            .family = MESHIO_GMSH41,                                     \
                            .media = media_,                                             \
                            .media_alt = media_alt_,                                     \
                            GMSH_VARIANT}

const meshio_fmt fmt_gmsh41 = {
    .name = "gmsh",
    .aliases = "msh msh41 gmsh41",
    .about = "Gmsh MSH 4.1 ASCII",
    .media = "model/vnd.gmsh",
    .media_alt = "application/x-gmsh model/x-gmsh",
    .sniff = sniff_gmsh,
    GMSH_VARIANT,
};
GMSH_OTHER(fmt_gmsh41_bin, "gmsh-bin", "msh41-bin gmsh41-bin", "Gmsh MSH 4.1 binary",
           "model/vnd.gmsh;encoding=binary", "application/x-gmsh;encoding=binary");
GMSH_OTHER(fmt_gmsh22, "gmsh22", "msh22", "Gmsh MSH 2.2 ASCII",
           "model/vnd.gmsh;version=2.2", "application/x-gmsh;version=2.2");
GMSH_OTHER(fmt_gmsh22_bin, "gmsh22-bin", "msh22-bin", "Gmsh MSH 2.2 binary", NULL, NULL);
GMSH_OTHER(fmt_gmsh40, "gmsh40", "msh40", "Gmsh MSH 4.0 ASCII (4.0 binary is refused)",
           NULL, NULL);
