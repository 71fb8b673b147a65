/* meshio_fe.c - the formats of finite-element solvers and meshers: DOLFIN
 * (FEniCS) legacy XML, Abaqus/CalculiX .inp and Netgen .vol.
 *
 * Each reader takes (buf, len), checks every count against the bytes left
 * before allocating, every index against the vertex count, rejects NaN/Inf,
 * and says where (line:column) a problem is. What qdc does not use (DOLFIN
 * domains and mesh functions, Abaqus *ELSET and *NSET blocks, materials and
 * steps, Netgen surface elements of other kinds, edge segments, materials,
 * geometry) is skipped when reading and kept byte for byte by a spliced
 * write. Each format also has a writer of qdc's own, for a mesh whose tets
 * changed or that was read from another format: DOLFIN vertices and
 * tetrahedra (regions and triangles have no place in its plain mesh file);
 * Abaqus *NODE, the tets grouped by region as ELSET=REGION_<n> and the
 * triangles by ref as ELSET=SURFACE_<n> (which the reader maps back to n);
 * Netgen surface elements (ref as bc number, domin/domout from the tets),
 * volume elements (region as material) and points. Second-order tets are
 * written by both (C3D10 with STRI65 triangles; 10- and 6-point elements).
 * Vertex refs and fixed flags are written by none of the three. */
#include "io/format.h"

/* Move the scanner to `to`, counting the lines passed. */
static void adv(txt *s, const char *to)
{
    const char *p = s->p;

    while (p < to) {
        const char *nl = memchr(p, '\n', (size_t)(to - p));
        if (!nl)
            break;
        s->line++;
        s->bol = p = nl + 1;
    }
    s->p = to;
}

/* The scanner as it was at line/bol (for errors in a tag already passed). */
static txt at_line(const txt *s, int64_t line, const char *bol)
{
    txt e = *s;

    e.line = line;
    e.bol = bol;
    return e;
}

static qdc_status rec_alloc3(srcrec *r, meshio_format fmt, int64_t nv, qdc_error *err)
{
    if (!r)
        return QDC_OK;
    r->fmt = fmt;
    r->kind = SRC_TEXT3;
    r->nv = nv;
    qdc_free(r->off);
    r->off = qdc_mallocn(3 * (size_t)nv + 1, sizeof(uint64_t));
    if (!r->off)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld vertex offsets",
                        (long long)nv);
    return QDC_OK;
}

/* The number [t, te) as a finite double, or an error at t. */
static qdc_status num_at(const txt *s, const char *t, const char *te, const char *what,
                         double *v, qdc_error *err)
{
    char q[32];

    if (parse_double(t, te, v) != 0)
        return fail_txt(err, QDC_EPARSE, s, t, "%s: expected a number, got %s", what,
                        quote_tok(q, s, t, te));
    if (!isfinite(*v))
        return fail_txt(err, QDC_EPARSE, s, t, "%s %s is not finite (NaN/Inf)", what,
                        quote_tok(q, s, t, te));
    return QDC_OK;
}

static qdc_status int_at(const txt *s, const char *t, const char *te, const char *what,
                         int64_t lo, int64_t hi, int64_t *v, qdc_error *err)
{
    char q[32];
    int rc = parse_int(t, te, 0, v);

    if (rc == -1)
        return fail_txt(err, QDC_EPARSE, s, t, "%s: expected an integer, got %s", what,
                        quote_tok(q, s, t, te));
    if (rc == -2 || *v < lo || *v > hi)
        return fail_txt(err, QDC_EPARSE, s, t, "%s %s out of range [%lld, %lld]", what,
                        quote_tok(q, s, t, te), (long long)lo, (long long)hi);
    return QDC_OK;
}

/* ------------------------------------------------------------------------ */
/* DOLFIN XML                                                                */

enum { XML_ATTRS = 16 };

typedef struct {
    const char *n, *v; /* name, value (between the quotes) */
    size_t nl, vl;
} xattr;

typedef struct {
    const char *at, *name; /* '<', the name */
    size_t nlen;
    int close, empty; /* </name>, <name/> */
    int na;
    xattr a[XML_ATTRS];
    int64_t line; /* of the '<' */
    const char *bol;
} xtag;

static int xml_name_char(unsigned char c)
{
    return is_word(c) || c == ':' || c == '-' || c == '.';
}

/* Up to the '<' of the next tag (comments, <?...?> and <!...> skipped);
 * *eof at the end. */
static qdc_status xml_skip(txt *s, int *eof, qdc_error *err)
{
    const char *e = s->end;

    *eof = 0;
    for (;;) {
        const char *lt = memchr(s->p, '<', (size_t)(e - s->p)), *close;
        if (!lt) {
            adv(s, e);
            *eof = 1;
            return QDC_OK;
        }
        adv(s, lt);
        if (e - lt >= 4 && memcmp(lt, "<!--", 4) == 0) {
            for (close = lt + 4; close + 3 <= e && memcmp(close, "-->", 3) != 0; close++)
                ;
            if (close + 3 > e)
                return fail_txt(err, QDC_EPARSE, s, lt, "unterminated comment");
            adv(s, close + 3);
            continue;
        }
        if (e - lt >= 2 && (lt[1] == '?' || lt[1] == '!')) {
            close = memchr(lt, '>', (size_t)(e - lt));
            if (!close)
                return fail_txt(err, QDC_EPARSE, s, lt, "unterminated <%c", lt[1]);
            adv(s, close + 1);
            continue;
        }
        return QDC_OK;
    }
}

/* One attribute name="value" at *pp (the first XML_ATTRS kept in t). */
static qdc_status xml_attr_one(txt *s, xtag *t, const char **pp, qdc_error *err)
{
    const char *p = *pp, *e = s->end, *n = p, *q;
    size_t nl;

    while (p < e && xml_name_char((unsigned char)*p))
        p++;
    nl = (size_t)(p - n);
    while (p < e && is_space((unsigned char)*p))
        p++;
    if (!nl || p >= e || *p != '=') {
        adv(s, p < e ? p : e);
        return fail_txt(err, QDC_EPARSE, s, p < e ? p : e,
                        "<%.*s: expected attribute=\"value\"",
                        (int)(t->nlen > 32 ? 32 : t->nlen), t->name);
    }
    p++;
    while (p < e && is_space((unsigned char)*p))
        p++;
    if (p >= e || (*p != '"' && *p != '\'')) {
        adv(s, p < e ? p : e);
        return fail_txt(
            err, QDC_EPARSE, s, p < e ? p : e, "<%.*s %.*s=: expected a quoted value",
            (int)(t->nlen > 32 ? 32 : t->nlen), t->name, (int)(nl > 32 ? 32 : nl), n);
    }
    q = memchr(p + 1, *p, (size_t)(e - p - 1));
    if (!q) {
        adv(s, p);
        return fail_txt(err, QDC_EPARSE, s, p, "unterminated attribute value");
    }
    if (t->na < XML_ATTRS) {
        xattr *a = &t->a[t->na++];
        a->n = n;
        a->nl = nl;
        a->v = p + 1;
        a->vl = (size_t)(q - p - 1);
    }
    *pp = q + 1;
    return QDC_OK;
}

/* The next tag (comments, <?...?> and <!...> skipped); *eof at the end. */
static qdc_status xml_tag(txt *s, xtag *t, int *eof, qdc_error *err)
{
    const char *p, *e = s->end;
    qdc_status st = xml_skip(s, eof, err);

    if (st != QDC_OK || *eof)
        return st;
    t->close = t->empty = t->na = 0; /* the attributes past na are not read */
    t->at = s->p;
    t->line = s->line;
    t->bol = s->bol;
    p = s->p + 1;
    if (p < e && *p == '/') {
        t->close = 1;
        p++;
    }
    t->name = p;
    while (p < e && xml_name_char((unsigned char)*p))
        p++;
    t->nlen = (size_t)(p - t->name);
    if (!t->nlen)
        return fail_txt(err, QDC_EPARSE, s, t->at, "expected a tag name after '<'");
    for (;;) {
        while (p < e && is_space((unsigned char)*p))
            p++;
        if (p >= e)
            return fail_txt(err, QDC_EPARSE, s, t->at, "<%.*s: unterminated tag",
                            (int)(t->nlen > 32 ? 32 : t->nlen), t->name);
        if (*p == '>') {
            p++;
            break;
        }
        if (*p == '/' && p + 1 < e && p[1] == '>') {
            t->empty = 1;
            p += 2;
            break;
        }
        st = xml_attr_one(s, t, &p, err);
        if (st != QDC_OK)
            return st;
    }
    adv(s, p);
    return QDC_OK;
}

static const xattr *xml_attr(const xtag *t, const char *name)
{
    size_t n = strlen(name);

    for (int i = 0; i < t->na; i++)
        if (t->a[i].nl == n && t->a[i].n[0] == name[0] && memcmp(t->a[i].n, name, n) == 0)
            return &t->a[i];
    return NULL;
}

static int tag_is(const xtag *t, const char *name)
{
    return t->nlen == strlen(name) && memcmp(t->name, name, t->nlen) == 0;
}

/* Attribute `name` of t, required; trimmed of spaces. */
static qdc_status xml_need(const txt *s, const xtag *t, const char *name, const char **v,
                           const char **ve, qdc_error *err)
{
    const xattr *a = xml_attr(t, name);

    if (!a) {
        txt e = at_line(s, t->line, t->bol);
        return fail_txt(err, QDC_EPARSE, &e, t->at, "<%.*s>: no %s=\"\" attribute",
                        (int)(t->nlen > 32 ? 32 : t->nlen), t->name, name);
    }
    *v = a->v;
    *ve = a->v + a->vl;
    while (*v < *ve && is_space((unsigned char)**v))
        (*v)++;
    while (*ve > *v && is_space((unsigned char)(*ve)[-1]))
        (*ve)--;
    return QDC_OK;
}

/* Attribute `name` of t, an integer in [lo, hi]. The message names the
 * tag and the attribute, written only on failure (a 1M-tet file has 5M of
 * these). */
static qdc_status xml_int(const txt *s, const xtag *t, const char *name, int64_t lo,
                          int64_t hi, int64_t *out, qdc_error *err)
{
    const char *v, *ve;
    txt e;
    char what[48];
    qdc_status st = xml_need(s, t, name, &v, &ve, err);

    if (st != QDC_OK)
        return st;
    if (parse_int(v, ve, 0, out) == 0 && *out >= lo && *out <= hi)
        return QDC_OK;
    e = at_line(s, t->line, t->bol);
    snprintf(what, sizeof what, "<%.*s> %s", (int)(t->nlen > 20 ? 20 : t->nlen), t->name,
             name);
    return int_at(&e, v, ve, what, lo, hi, out, err);
}

typedef struct {
    parsed pm;
    uint8_t *seen_v, *seen_t; /* each vertex and cell index once */
    int64_t nvd, ntd;         /* declared sizes (-1 before <vertices>/<cells>) */
    int64_t got_v, got_t;
    int in_mesh, ordered; /* vertices in index order: the file can be spliced */
} dolfin;

static qdc_status dolfin_mesh(txt *s, const xtag *t, qdc_error *err)
{
    const char *v, *ve;
    txt e = at_line(s, t->line, t->bol);
    qdc_status st = xml_need(s, t, "celltype", &v, &ve, err);
    int64_t dim;

    if (st != QDC_OK)
        return st;
    if ((size_t)(ve - v) != 11 || memcmp(v, "tetrahedron", 11) != 0)
        return fail_txt(err, QDC_EFORMAT, &e, v,
                        "DOLFIN: celltype \"%.*s\" is not supported (tetrahedron)",
                        (int)(ve - v > 24 ? 24 : ve - v), v);
    st = xml_int(s, t, "dim", 3, 3, &dim, err);
    return st;
}

static qdc_status dolfin_vertices(txt *s, const xtag *t, dolfin *d, srcrec *rec,
                                  qdc_error *err)
{
    txt e = at_line(s, t->line, t->bol);
    int64_t n;
    qdc_status st;

    if (d->nvd >= 0)
        return fail_txt(err, QDC_EPARSE, &e, t->at, "DOLFIN: a second <vertices>");
    st = xml_int(s, t, "size", 0, INT64_MAX, &n, err);
    if (st != QDC_OK)
        return st;
    /* every vertex takes a tag of at least 24 bytes: <vertex index="" x=""/> */
    if ((uint64_t)n > (uint64_t)(s->end - s->p) / 24)
        return fail_txt(err, QDC_EPARSE, &e, t->at,
                        "<vertices> size %lld does not fit in the %zu bytes left "
                        "(truncated?)",
                        (long long)n, (size_t)(s->end - s->p));
    if (n > MESH_MAX_VERTICES)
        return fail_txt(err, QDC_ETOOBIG, &e, t->at,
                        "<vertices> size %lld exceeds the limit %d", (long long)n,
                        MESH_MAX_VERTICES);
    d->nvd = n;
    d->pm.nv = n;
    d->pm.xyz = qdc_mallocn(3 * (size_t)n + 1, sizeof(double));
    d->seen_v = qdc_calloc((size_t)n + 1, 1);
    if (!d->pm.xyz || !d->seen_v)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld vertices", (long long)n);
    return rec_alloc3(rec, MESHIO_DOLFIN, n, err);
}

static qdc_status dolfin_vertex(txt *s, const xtag *t, dolfin *d, srcrec *rec,
                                qdc_error *err)
{
    static const char *const axis[3] = {"x", "y", "z"};
    txt e = at_line(s, t->line, t->bol);
    const char *last = NULL;
    int64_t i;
    qdc_status st;

    if (d->nvd < 0)
        return fail_txt(err, QDC_EPARSE, &e, t->at,
                        "DOLFIN: <vertex> outside <vertices>");
    if (d->got_v == d->nvd)
        return fail_txt(err, QDC_EPARSE, &e, t->at,
                        "DOLFIN: more <vertex> than the %lld of <vertices size>",
                        (long long)d->nvd);
    st = xml_int(s, t, "index", 0, d->nvd - 1, &i, err);
    if (st == QDC_OK && d->seen_v[i])
        st = fail_txt(err, QDC_EPARSE, &e, t->at, "DOLFIN: vertex %lld appears twice",
                      (long long)i);
    for (int a = 0; a < 3 && st == QDC_OK; a++) {
        const char *v, *ve;
        st = xml_need(s, t, axis[a], &v, &ve, err);
        if (st == QDC_OK)
            st = num_at(&e, v, ve, axis[a], &d->pm.xyz[3 * i + a], err);
        if (st == QDC_OK && rec) {
            rec->off[3 * i + a] = (uint64_t)(v - s->base);
            if (v < last)
                d->ordered = 0; /* attributes not in x, y, z order */
            last = v;
        }
    }
    if (st != QDC_OK) {
        set_index(err, "vertex", d->got_v);
        return st;
    }
    if (i != d->got_v)
        d->ordered = 0;
    d->seen_v[i] = 1;
    d->got_v++;
    return QDC_OK;
}

static qdc_status dolfin_cells(txt *s, const xtag *t, dolfin *d, qdc_error *err)
{
    txt e = at_line(s, t->line, t->bol);
    int64_t n;
    qdc_status st;

    if (d->nvd < 0)
        return fail_txt(err, QDC_EPARSE, &e, t->at, "DOLFIN: <cells> before <vertices>");
    if (d->ntd >= 0)
        return fail_txt(err, QDC_EPARSE, &e, t->at, "DOLFIN: a second <cells>");
    st = xml_int(s, t, "size", 0, INT64_MAX, &n, err);
    if (st != QDC_OK)
        return st;
    if ((uint64_t)n > (uint64_t)(s->end - s->p) / 40)
        return fail_txt(err, QDC_EPARSE, &e, t->at,
                        "<cells> size %lld does not fit in the %zu bytes left "
                        "(truncated?)",
                        (long long)n, (size_t)(s->end - s->p));
    if (n > MESH_MAX_TETS)
        return fail_txt(err, QDC_ETOOBIG, &e, t->at,
                        "<cells> size %lld exceeds the limit %d", (long long)n,
                        MESH_MAX_TETS);
    d->ntd = n;
    d->pm.nt = n;
    d->pm.tets = qdc_mallocn(4 * (size_t)n + 1, sizeof(int32_t));
    d->seen_t = qdc_calloc((size_t)n + 1, 1);
    if (!d->pm.tets || !d->seen_t)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld tets", (long long)n);
    return QDC_OK;
}

static qdc_status dolfin_tet(txt *s, const xtag *t, dolfin *d, qdc_error *err)
{
    static const char *const vk[4] = {"v0", "v1", "v2", "v3"};
    txt e = at_line(s, t->line, t->bol);
    int64_t i, v;
    qdc_status st;

    if (d->ntd < 0)
        return fail_txt(err, QDC_EPARSE, &e, t->at,
                        "DOLFIN: <tetrahedron> outside <cells>");
    if (d->got_t == d->ntd)
        return fail_txt(err, QDC_EPARSE, &e, t->at,
                        "DOLFIN: more cells than the %lld of <cells size>",
                        (long long)d->ntd);
    st = xml_int(s, t, "index", 0, d->ntd - 1, &i, err);
    if (st == QDC_OK && d->seen_t[i])
        st = fail_txt(err, QDC_EPARSE, &e, t->at, "DOLFIN: cell %lld appears twice",
                      (long long)i);
    for (int k = 0; k < 4 && st == QDC_OK; k++) {
        st = xml_int(s, t, vk[k], 0, d->nvd - 1, &v, err);
        if (st == QDC_OK)
            d->pm.tets[4 * i + k] = (int32_t)v;
    }
    if (st != QDC_OK) {
        set_index(err, "tet", d->got_t);
        return st;
    }
    d->seen_t[i] = 1;
    d->got_t++;
    return QDC_OK;
}

/* A closing tag: </mesh>, or </vertices> and </cells> with their counts. */
static qdc_status dolfin_close(txt *s, const xtag *t, dolfin *d, qdc_error *err)
{
    txt e = at_line(s, t->line, t->bol);

    if (tag_is(t, "mesh"))
        d->in_mesh = 0;
    else if (d->in_mesh && tag_is(t, "vertices") && d->got_v != d->nvd)
        return fail_txt(err, QDC_EPARSE, &e, t->at,
                        "DOLFIN: %lld <vertex> elements, <vertices size=\"%lld\">",
                        (long long)d->got_v, (long long)d->nvd);
    else if (d->in_mesh && tag_is(t, "cells") && d->got_t != d->ntd)
        return fail_txt(err, QDC_EPARSE, &e, t->at,
                        "DOLFIN: %lld <tetrahedron> elements, <cells size=\"%lld\">",
                        (long long)d->got_t, (long long)d->ntd);
    return QDC_OK;
}

/* An opening tag inside <dolfin>; *nskip counts cells that are not
 * tetrahedra. */
static qdc_status dolfin_open(txt *s, const xtag *t, dolfin *d, srcrec *rec,
                              int64_t *nskip, qdc_error *err)
{
    if (tag_is(t, "mesh")) {
        if (d->nvd >= 0) {
            txt e = at_line(s, t->line, t->bol);
            return fail_txt(err, QDC_EPARSE, &e, t->at, "DOLFIN: a second <mesh>");
        }
        d->in_mesh = 1;
        return dolfin_mesh(s, t, err);
    }
    if (!d->in_mesh)
        return QDC_OK; /* mesh functions, data: kept by a spliced write */
    if (tag_is(t, "vertices"))
        return dolfin_vertices(s, t, d, rec, err);
    if (tag_is(t, "vertex"))
        return dolfin_vertex(s, t, d, rec, err);
    if (tag_is(t, "cells"))
        return dolfin_cells(s, t, d, err);
    if (tag_is(t, "tetrahedron"))
        return dolfin_tet(s, t, d, err);
    if (d->ntd >= 0 && !tag_is(t, "domains"))
        (*nskip)++;
    return QDC_OK;
}

/* After the last tag: a root, a mesh, and the counts its sizes said. */
static qdc_status dolfin_counts(txt *s, const dolfin *d, int root, qdc_error *err)
{
    if (!root)
        return fail_txt(err, QDC_EFORMAT, s, s->p, "not a DOLFIN XML file: no <dolfin>");
    if (d->nvd < 0)
        return fail_txt(err, QDC_EPARSE, s, s->p, "DOLFIN: no <mesh> with <vertices>");
    if (d->got_v != d->nvd)
        return fail_txt(err, QDC_EPARSE, s, s->p,
                        "DOLFIN: %lld <vertex> elements, <vertices size=\"%lld\">",
                        (long long)d->got_v, (long long)d->nvd);
    if (d->ntd >= 0 && d->got_t != d->ntd)
        return fail_txt(err, QDC_EPARSE, s, s->p,
                        "DOLFIN: %lld <tetrahedron> elements, <cells size=\"%lld\">",
                        (long long)d->got_t, (long long)d->ntd);
    return QDC_OK;
}

static qdc_status read_dolfin(const char *buf, size_t len, const meshio_options *o,
                              srcrec *rec, mesh_t **out, qdc_error *err)
{
    txt s = txt_init(buf, len, 0);
    dolfin d;
    xtag t;
    int eof = 0, root = 0;
    int64_t skipped_cells = 0;
    qdc_status st = QDC_OK;

    memset(&d, 0, sizeof d);
    parsed_init(&d.pm);
    d.nvd = d.ntd = -1;
    d.ordered = 1;
    while (st == QDC_OK) {
        st = xml_tag(&s, &t, &eof, err);
        if (st != QDC_OK || eof)
            break;
        if (!root) {
            if (!tag_is(&t, "dolfin") || t.close) {
                txt e = at_line(&s, t.line, t.bol);
                st = fail_txt(err, QDC_EFORMAT, &e, t.at,
                              "not a DOLFIN XML file: the first element is <%.*s>",
                              (int)(t.nlen > 24 ? 24 : t.nlen), t.name);
            }
            root = 1;
        } else if (t.close) {
            st = dolfin_close(&s, &t, &d, err);
        } else {
            st = dolfin_open(&s, &t, &d, rec, &skipped_cells, err);
        }
    }
    if (st == QDC_OK)
        st = dolfin_counts(&s, &d, root, err);
    if (st == QDC_OK && rec && !d.ordered)
        srcrec_refuse(rec, "the vertices are not in index order with x, y, z attributes");
    if (st == QDC_OK) {
        if (skipped_cells)
            note(o,
                 "dolfin: skipped %lld elements inside <cells> that are not "
                 "<tetrahedron>",
                 (long long)skipped_cells);
        st = parsed_mesh(&d.pm, out, err);
    }
    qdc_free(d.seen_v);
    qdc_free(d.seen_t);
    parsed_free(&d.pm);
    return st;
}

static qdc_status write_dolfin(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                               qdc_error *err)
{
    (void)fmt;
    (void)part;
    (void)err;
    wb_str(w, "<?xml version=\"1.0\"?>\n<dolfin nsmap=\"{'dolfin': "
              "'https://fenicsproject.org/'}\">\n"
              "  <mesh celltype=\"tetrahedron\" dim=\"3\">\n    <vertices size=\"");
    wb_int(w, m->nv);
    wb_str(w, "\">\n");
    for (int32_t i = 0; i < m->nv; i++) {
        const double *p = m->xyz + 3 * (size_t)i;
        wb_str(w, "      <vertex index=\"");
        wb_int(w, i);
        wb_str(w, "\" x=\"");
        wb_real(w, p[0]);
        wb_str(w, "\" y=\"");
        wb_real(w, p[1]);
        wb_str(w, "\" z=\"");
        wb_real(w, p[2]);
        wb_str(w, "\" />\n");
    }
    wb_str(w, "    </vertices>\n    <cells size=\"");
    wb_int(w, m->nt);
    wb_str(w, "\">\n");
    for (int32_t t = 0; t < m->nt; t++) {
        const int32_t *v = m->tets + 4 * (size_t)t;
        wb_str(w, "      <tetrahedron index=\"");
        wb_int(w, t);
        for (int k = 0; k < 4; k++) {
            static const char *const vk[4] = {"\" v0=\"", "\" v1=\"", "\" v2=\"",
                                              "\" v3=\""};
            wb_str(w, vk[k]);
            wb_int(w, v[k]);
        }
        wb_str(w, "\" />\n");
    }
    wb_str(w, "    </cells>\n  </mesh>\n</dolfin>\n");
    return QDC_OK;
}

/* ------------------------------------------------------------------------ */
/* Abaqus / CalculiX .inp                                                    */

enum { INP_SETS = 1024 };

/* The ELSET names of one kind of element (tets, triangles) in the order
 * first seen: an element's region or ref is the 1-based position of its
 * set, 0 without one (inp_numbered may then renumber them). */
typedef struct {
    const char *set[INP_SETS];
    size_t setl[INP_SETS];
    int n;
} inp_sets;

typedef struct {
    vec xyz, tags, off; /* double x3, int64, uint64 x3 (when recording) */
    vec at;             /* uint64: byte offset of each node's line (errors) */
    vec tets, reg;      /* int32 x4, int32 */
    vec mid;            /* int32 x6: C3D10's mid-edge nodes (mesh_p2_edges order) */
    vec tris, ref;      /* int32 x3 (corners), int32: the triangles' */
    int order;          /* tets read: 0 none yet, 1 C3D4, 2 C3D10 */
    int tri_nodes;      /* nodes of the triangles of this *ELEMENT: 3 or 6 */
    tagmap tm;
    int64_t tm_n; /* nodes in tm; -1 when not built */
    inp_sets tet_sets, tri_sets;
    int64_t skipped;
    char skipped_types[64];
} inp;

static void inp_free(inp *a)
{
    vec_free(&a->at);
    vec_free(&a->xyz);
    vec_free(&a->tags);
    vec_free(&a->off);
    vec_free(&a->tets);
    vec_free(&a->reg);
    vec_free(&a->mid);
    vec_free(&a->tris);
    vec_free(&a->ref);
    tagmap_free(&a->tm);
}

/* Whitespace within a line (a token ends there, as for the splicer). */
static int is_blank(char c)
{
    return c != '\n' && is_space((unsigned char)c);
}

/* The next comma-separated field of [*p, eol) as [t, te); 0 if none left. */
static int inp_field(const char **p, const char *eol, const char **t, const char **te)
{
    const char *q = *p;

    while (q < eol && is_blank(*q))
        q++;
    if (q >= eol)
        return 0;
    *t = q;
    while (q < eol && *q != ',' && !is_blank(*q))
        q++;
    *te = q;
    while (q < eol && is_blank(*q))
        q++;
    if (q < eol && *q == ',')
        q++;
    *p = q;
    return 1;
}

/* Value of parameter key (case-insensitive) of a keyword line [p, eol). */
static int inp_param(const char *p, const char *eol, const char *key, const char **v,
                     const char **ve)
{
    size_t kl = strlen(key);

    while (p < eol) {
        const char *f = p, *fe = memchr(p, ',', (size_t)(eol - p)), *eq;
        if (!fe)
            fe = eol;
        p = fe < eol ? fe + 1 : eol;
        while (f < fe && is_blank(*f))
            f++;
        eq = memchr(f, '=', (size_t)(fe - f));
        if (!eq)
            continue;
        {
            const char *ke = eq;
            while (ke > f && is_blank(ke[-1]))
                ke--;
            if ((size_t)(ke - f) != kl || strncasecmp(f, key, kl) != 0)
                continue;
        }
        *v = eq + 1;
        *ve = fe;
        while (*v < *ve && is_blank(**v))
            (*v)++;
        while (*ve > *v && is_blank((*ve)[-1]))
            (*ve)--;
        return 1;
    }
    return 0;
}

/* Element type [t, te): 1 linear tet, 2 second-order tet, 0 other. */
static int inp_tet_type(const char *t, const char *te)
{
    size_t n = (size_t)(te - t);

    if (n >= 1 && (*t == 'D' || *t == 'd')) { /* DC3D4: heat transfer */
        t++;
        n--;
    }
    if (n < 4 || strncasecmp(t, "C3D", 3) != 0)
        return 0;
    if (t[3] == '4' && (n == 4 || !(t[4] >= '0' && t[4] <= '9')))
        return 1;
    if (n >= 5 && t[3] == '1' && t[4] == '0')
        return 2;
    return 0;
}

/* Triangle element type [t, te): its node count, 3 or 6 (the corners
 * first, then the mid-edge nodes, which are not read), 0 if not one. Shells,
 * membranes, surface, rigid and plane elements: what Abaqus, CalculiX,
 * Gmsh (CPS3, CPS6) and meshio (R3D3) write for boundary triangles. */
static int inp_tri_type(const char *t, const char *te)
{
    static const char *const three[] = {"S3",   "S3R",  "S3RS", "STRI3",  "CPS3", "CPE3",
                                        "CAX3", "M3D3", "R3D3", "SFM3D3", "DS3"};
    static const char *const six[] = {"S6",   "STRI65", "CPS6",   "CPE6",
                                      "CAX6", "M3D6",   "SFM3D6", "DS6"};
    size_t n = (size_t)(te - t);

    for (size_t i = 0; i < sizeof three / sizeof three[0]; i++)
        if (strlen(three[i]) == n && strncasecmp(t, three[i], n) == 0)
            return 3;
    for (size_t i = 0; i < sizeof six / sizeof six[0]; i++)
        if (strlen(six[i]) == n && strncasecmp(t, six[i], n) == 0)
            return 6;
    return 0;
}

enum { INP_SKIP, INP_NODE, INP_TET, INP_TRI, INP_OTHER };

static qdc_status inp_node(txt *s, const char *p, const char *eol, inp *a, srcrec *rec,
                           qdc_error *err)
{
    const char *t, *te;
    int64_t id;
    double x[3];
    uint64_t off[3], end;
    qdc_status st;

    inp_field(&p, eol, &t, &te);
    st = int_at(s, t, te, "*NODE: node number", 1, INT32_MAX, &id, err);
    /* A coordinate left blank or out at the end of the line is 0, as Abaqus
     * and CalculiX read it; a spliced write puts the value there (after a
     * comma for one left out) if the vertex moves off 0 (SRC_BLANK). */
    end = (uint64_t)(te - s->base);
    for (int k = 0, out = 0; k < 3 && st == QDC_OK; k++) {
        out = out || !inp_field(&p, eol, &t, &te);
        if (out || t == te) {
            x[k] = 0;
            off[k] = (out ? end | SRC_COMMA : (uint64_t)(t - s->base)) | SRC_BLANK;
            if (!out) /* a coordinate left out after it goes past this field */
                end = (uint64_t)(te - s->base);
            continue;
        }
        st = num_at(s, t, te, "*NODE: coordinate", &x[k], err);
        off[k] = (uint64_t)(t - s->base);
        end = (uint64_t)(te - s->base);
    }
    if (st != QDC_OK)
        return st;
    if ((int64_t)a->tags.n >= MESH_MAX_VERTICES)
        return fail_txt(err, QDC_ETOOBIG, s, s->bol, "more than %d nodes",
                        MESH_MAX_VERTICES);
    if (vec_grow(&a->xyz, 3) != 0 || vec_grow(&a->tags, 1) != 0 ||
        vec_grow(&a->at, 1) != 0 || (rec && vec_grow(&a->off, 3) != 0))
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the nodes");
    memcpy((double *)a->xyz.a + a->xyz.n, x, sizeof x);
    a->xyz.n += 3;
    ((int64_t *)a->tags.a)[a->tags.n++] = id;
    ((uint64_t *)a->at.a)[a->at.n++] = (uint64_t)(s->bol - s->base);
    if (rec) {
        memcpy((uint64_t *)a->off.a + a->off.n, off, sizeof off);
        a->off.n += 3;
    }
    return QDC_OK;
}

/* The node map, rebuilt when nodes were added; a node number defined twice
 * is an error at its second definition. */
static qdc_status inp_map(const txt *s, inp *a, qdc_error *err)
{
    int64_t dup;
    qdc_status st;

    if (a->tm_n == (int64_t)a->tags.n)
        return QDC_OK;
    tagmap_free(&a->tm);
    st = tagmap_build(&a->tm, a->tags.a, (int64_t)a->tags.n, &dup, err);
    if (st == QDC_OK && dup >= 0) {
        txt e = txt_init(s->base, (size_t)(s->end - s->base), 0);
        adv(&e, s->base + ((uint64_t *)a->at.a)[dup]);
        fail_txt(err, QDC_EPARSE, &e, e.p, "*NODE: node %lld defined twice",
                 (long long)((int64_t *)a->tags.a)[dup]);
        set_index(err, "vertex", dup);
        return QDC_EPARSE;
    }
    a->tm_n = (int64_t)a->tags.n;
    return st;
}

/* The element number and the nn - 1 nodes of one element (of type name),
 * continued on the next line after a trailing comma (*pp and *peol move
 * with it); the nodes as vertex indices in idx. kind and index name the
 * element in an error. */
static qdc_status inp_numbers(txt *s, const char **pp, const char **peol, inp *a, int nn,
                              const char *name, const char *kind, int64_t index,
                              int32_t *idx, qdc_error *err)
{
    const char *p = *pp, *eol = *peol, *t = p, *te;
    int64_t v[11];
    qdc_status st = inp_map(s, a, err); /* nodes may have been added since */

    for (int k = 0; k < nn && st == QDC_OK; k++) {
        while (!inp_field(&p, eol, &t, &te)) {
            /* continued after a trailing comma */
            const char *q = eol;
            while (q > s->p && is_blank(q[-1]))
                q--;
            if (q == s->p || q[-1] != ',' || eol >= s->end)
                return fail_txt(err, QDC_EPARSE, s, eol,
                                "*ELEMENT: a %s element needs %d numbers, got %d", name,
                                nn, k);
            adv(s, eol + 1);
            p = s->p;
            eol = memchr(p, '\n', (size_t)(s->end - p));
            if (!eol)
                eol = s->end;
        }
        st = int_at(s, t, te, k ? "*ELEMENT: node" : "*ELEMENT: element number", 1,
                    INT64_MAX, &v[k], err);
        if (st == QDC_OK && k) {
            int64_t i = tagmap_find(&a->tm, v[k]);
            if (i < 0) {
                fail_txt(err, QDC_EPARSE, s, t,
                         "*ELEMENT: element %lld: unknown node %lld", (long long)v[0],
                         (long long)v[k]);
                set_index(err, kind, index);
                return QDC_EPARSE;
            }
            idx[k - 1] = (int32_t)i;
        }
    }
    *pp = p;
    *peol = eol;
    return st;
}

/* One C3D4 element: "id, n1, n2, n3, n4", or C3D10: "id, n1, ..., n10", the
 * mid-edge nodes of edges 12, 23, 31, 14, 24, 34 (the Abaqus manual's node
 * ordering; mesh_p2_edges); *pp and *peol move past it. */
static qdc_status inp_tet(txt *s, const char **pp, const char **peol, inp *a, int32_t reg,
                          qdc_error *err)
{
    const int nn = a->order == 2 ? 11 : 5;
    int32_t idx[10];
    qdc_status st = inp_numbers(s, pp, peol, a, nn, nn == 11 ? "C3D10" : "C3D4", "tet",
                                (int64_t)a->reg.n, idx, err);

    if (st != QDC_OK)
        return st;
    if ((int64_t)a->reg.n >= MESH_MAX_TETS)
        return fail_txt(err, QDC_ETOOBIG, s, s->bol, "more than %d tets", MESH_MAX_TETS);
    if (vec_grow(&a->tets, 4) != 0 || vec_grow(&a->reg, 1) != 0 ||
        (nn == 11 && vec_grow(&a->mid, 6) != 0))
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the tets");
    memcpy((int32_t *)a->tets.a + a->tets.n, idx, 4 * sizeof(int32_t));
    a->tets.n += 4;
    if (nn == 11) {
        memcpy((int32_t *)a->mid.a + a->mid.n, idx + 4, 6 * sizeof(int32_t));
        a->mid.n += 6;
    }
    ((int32_t *)a->reg.a)[a->reg.n++] = reg;
    return QDC_OK;
}

/* One triangle element of 3 or 6 nodes: its corners, with ref. */
static qdc_status inp_tri(txt *s, const char **pp, const char **peol, inp *a, int32_t ref,
                          qdc_error *err)
{
    int32_t idx[6];
    qdc_status st = inp_numbers(s, pp, peol, a, a->tri_nodes + 1, "triangle", "triangle",
                                (int64_t)a->ref.n, idx, err);

    if (st != QDC_OK)
        return st;
    if ((int64_t)a->ref.n >= INT32_MAX / 3)
        return fail_txt(err, QDC_ETOOBIG, s, s->bol, "more than %d triangles",
                        INT32_MAX / 3);
    if (vec_grow(&a->tris, 3) != 0 || vec_grow(&a->ref, 1) != 0)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the triangles");
    memcpy((int32_t *)a->tris.a + a->tris.n, idx, 3 * sizeof(int32_t));
    a->tris.n += 3;
    ((int32_t *)a->ref.a)[a->ref.n++] = ref;
    return QDC_OK;
}

/* The number of an ELSET name of set list l: its 1-based position among
 * those seen (what names the elements of a kind). */
static qdc_status inp_set(txt *s, inp_sets *l, const char *what, const char *v,
                          const char *ve, int32_t *reg, qdc_error *err)
{
    for (int i = 0; i < l->n; i++)
        if (l->setl[i] == (size_t)(ve - v) &&
            strncasecmp(l->set[i], v, l->setl[i]) == 0) {
            *reg = i + 1;
            return QDC_OK;
        }
    if (l->n == INP_SETS)
        return fail_txt(err, QDC_ETOOBIG, s, v, "more than %d element sets of %s",
                        INP_SETS, what);
    l->set[l->n] = v;
    l->setl[l->n++] = (size_t)(ve - v);
    *reg = l->n;
    return QDC_OK;
}

/* The number n that name [v, ve) holds when it is prefix (case-insensitive)
 * and then n as qdc's writer spells it: decimal digits without a leading
 * zero, "M" and the digits for a negative n ("REGION_12", "SURFACE_M3").
 * 1 and *n if so, else 0. (MED's group names too: meshio_med.c.) */
int meshio_name_number(const char *v, const char *ve, const char *prefix, int32_t *n)
{
    size_t pl = strlen(prefix);
    int neg = 0;
    int64_t x = 0;

    if ((size_t)(ve - v) <= pl || strncasecmp(v, prefix, pl) != 0)
        return 0;
    v += pl;
    if (*v == 'M' || *v == 'm') {
        neg = 1;
        v++;
    }
    if (v == ve || ve - v > 10 || *v < '0' || *v > '9' ||
        (*v == '0' && (neg || ve - v > 1)))
        return 0;
    for (; v < ve; v++) {
        if (*v < '0' || *v > '9')
            return 0;
        x = 10 * x + (*v - '0');
    }
    x = neg ? -x : x;
    if (x < INT32_MIN || x > INT32_MAX)
        return 0;
    *n = (int32_t)x;
    return 1;
}

/* If every set of l is named prefix and a number (meshio_name_number: the
 * names qdc's writer gives), the numbers of the n elements num[] (1-based
 * set positions, 0 for none) become those numbers; else they stay the
 * positions. An element without a set keeps 0. */
static void inp_numbered(const inp_sets *l, const char *prefix, int32_t *num, size_t n)
{
    int32_t val[INP_SETS];

    for (int i = 0; i < l->n; i++)
        if (!meshio_name_number(l->set[i], l->set[i] + l->setl[i], prefix, &val[i]))
            return;
    for (size_t i = 0; i < n; i++)
        if (num[i] > 0)
            num[i] = val[num[i] - 1];
}

/* Remember an element type skipped, for the note: printable ASCII, the
 * first few, then "...". */
static void skipped_type(inp *a, const char *v, const char *ve)
{
    char *b = a->skipped_types;
    size_t n = strlen(b), cap = sizeof a->skipped_types, vl = (size_t)(ve - v);

    if (n >= 3 && strcmp(b + n - 3, "...") == 0)
        return;
    for (const char *w = b; *w;) { /* already listed? */
        size_t l = strcspn(w, ",");
        if (l == vl && strncmp(w, v, vl) == 0)
            return;
        w += l;
        if (*w == ',')
            w += 2; /* ", " */
    }
    if (n + 2 + vl + 4 >= cap) {
        if (n + 4 < cap)
            memcpy(b + n, "...", 4);
        return;
    }
    if (n) {
        memcpy(b + n, ", ", 2);
        n += 2;
    }
    for (size_t i = 0; i < vl; i++)
        b[n++] = v[i] >= 0x20 && v[i] < 0x7f ? v[i] : '?';
    b[n] = '\0';
}

static qdc_status inp_keyword(txt *s, const char *p, const char *eol, inp *a, int *mode,
                              int32_t *reg, qdc_error *err)
{
    const char *k = p + 1, *ke, *v, *ve;

    for (ke = k; ke < eol && *ke != ','; ke++)
        ;
    while (ke > k && is_blank(ke[-1]))
        ke--;
    *mode = INP_SKIP;
    if (word_is(k, (size_t)(ke - k), "NODE")) {
        *mode = INP_NODE;
    } else if (word_is(k, (size_t)(ke - k), "ELEMENT")) {
        int tt;
        if (!inp_param(ke, eol, "TYPE", &v, &ve))
            return fail_txt(err, QDC_EPARSE, s, p, "*ELEMENT without TYPE=");
        tt = inp_tet_type(v, ve);
        if (tt && a->order && tt != a->order)
            return fail_txt(err, QDC_EFORMAT, s, v,
                            "*ELEMENT TYPE=%.*s: linear (C3D4) and second-order (C3D10) "
                            "tetrahedra in one file are not supported",
                            (int)(ve - v > 16 ? 16 : ve - v), v);
        if (tt) {
            a->order = tt;
            *mode = INP_TET;
            *reg = 0;
            if (inp_param(ke, eol, "ELSET", &v, &ve))
                return inp_set(s, &a->tet_sets, "tets", v, ve, reg, err);
        } else if ((tt = inp_tri_type(v, ve)) != 0) {
            a->tri_nodes = tt;
            *mode = INP_TRI;
            *reg = 0;
            if (inp_param(ke, eol, "ELSET", &v, &ve))
                return inp_set(s, &a->tri_sets, "triangles", v, ve, reg, err);
        } else {
            *mode = INP_OTHER;
            skipped_type(a, v, ve);
        }
    } else if (word_is(k, (size_t)(ke - k), "INCLUDE")) {
        return fail_txt(err, QDC_EFORMAT, s, p,
                        "*INCLUDE is not supported (a single self-contained file)");
    }
    return QDC_OK;
}

static qdc_status read_abaqus(const char *buf, size_t len, const meshio_options *o,
                              srcrec *rec, mesh_t **out, qdc_error *err)
{
    txt s = txt_init(buf, len, 0);
    inp a;
    int mode = INP_SKIP, any_kw = 0;
    int32_t reg = 0;
    qdc_status st = QDC_OK;
    parsed pm;

    memset(&a, 0, sizeof a);
    a.xyz.size = sizeof(double);
    a.tags.size = a.off.size = a.at.size = sizeof(int64_t);
    a.tets.size = a.reg.size = a.mid.size = a.tris.size = a.ref.size = sizeof(int32_t);
    a.tm_n = -1;
    while (s.p < s.end && st == QDC_OK) {
        const char *eol = memchr(s.p, '\n', (size_t)(s.end - s.p)), *p = s.p;
        if (!eol)
            eol = s.end;
        while (p < eol && is_blank(*p))
            p++;
        if (p == eol || (eol - p >= 2 && p[0] == '*' && p[1] == '*')) {
            /* blank line or comment */
        } else if (*p == '*') {
            any_kw = 1;
            st = inp_keyword(&s, p, eol, &a, &mode, &reg, err);
        } else if (!any_kw) {
            st = fail_txt(err, QDC_EFORMAT, &s, p,
                          "not an Abaqus input file: data before the first *keyword");
        } else if (mode == INP_NODE) {
            st = inp_node(&s, p, eol, &a, rec, err);
        } else if (mode == INP_TET) {
            st = inp_tet(&s, &p, &eol, &a, reg, err);
        } else if (mode == INP_TRI) {
            st = inp_tri(&s, &p, &eol, &a, reg, err);
        } else if (mode == INP_OTHER) {
            a.skipped++;
        }
        if (st == QDC_OK)
            adv(&s, eol < s.end ? eol + 1 : s.end);
    }
    if (st == QDC_OK && !any_kw)
        st = fail_txt(err, QDC_EFORMAT, &s, s.p, "not an Abaqus input file: no *keyword");
    if (st == QDC_OK)
        st = inp_map(&s, &a, err); /* nodes after the last element */
    if (st == QDC_OK && rec) {
        rec->fmt = MESHIO_ABAQUS;
        rec->kind = SRC_TEXT3;
        rec->nv = (int64_t)a.tags.n;
        rec->off = a.off.a;
        a.off.a = NULL;
        if (!rec->off)
            rec->off = qdc_malloc(sizeof(uint64_t));
        if (!rec->off)
            st = qdc_fail(err, QDC_ENOMEM, "out of memory");
    }
    if (st == QDC_OK) {
        parsed_init(&pm);
        pm.nv = (int64_t)a.tags.n;
        pm.xyz = a.xyz.a;
        pm.nt = (int64_t)a.reg.n;
        pm.tets = a.tets.a;
        pm.region = a.tet_sets.n ? a.reg.a : NULL;
        pm.mid = a.order == 2 ? a.mid.a : NULL;
        pm.ntri = (int64_t)a.ref.n;
        pm.tris = a.tris.a;
        pm.tri_ref = a.tri_sets.n ? a.ref.a : NULL;
        inp_numbered(&a.tet_sets, "REGION_", a.reg.a, a.reg.n);
        inp_numbered(&a.tri_sets, "SURFACE_", a.ref.a, a.ref.n);
        st = parsed_mesh(&pm, out, err);
        if (a.skipped)
            note(o,
                 "abaqus: skipped %lld elements of other types (%s): only C3D4, C3D10 "
                 "and triangles are read",
                 (long long)a.skipped, a.skipped_types);
    }
    inp_free(&a);
    return st;
}

/* ------------------------------------------------------------------------ */
/* Netgen .vol                                                               */

typedef struct {
    vec tets, reg, tris, ref; /* int32: 1-based points until checked */
    vec mid;                  /* int32 x6: second-order tets' mid-edge points */
    vec at_tet, at_tri;       /* uint64: byte offset of each element (errors) */
    int64_t skipped;
    int np; /* points of the tets read: 0 none yet, 4, 10 */
} vol;

static void vol_free(vol *g)
{
    vec_free(&g->mid);
    vec_free(&g->at_tet);
    vec_free(&g->at_tri);
    vec_free(&g->tets);
    vec_free(&g->reg);
    vec_free(&g->tris);
    vec_free(&g->ref);
}

/* volumeelements: "matnr np p1 .. pnp"; a tet of np 4, or 10 (second
 * order: Netgen lists the mid-edge points of edges 01 02 03 12 13 23 after
 * the corners); all tets of one order. */
static qdc_status vol_volume(txt *s, vol *g, qdc_error *err)
{
    static const int edge[6] = {0, 2, 3, 1, 4, 5}; /* Netgen's to mesh_p2_edges */
    int64_t n, mat = 0, np = 0, v = 0;
    qdc_status st = txt_count(s, "volumeelements", 6, MESH_MAX_TETS, &n, err);

    if (st == QDC_OK &&
        (vec_grow(&g->tets, 4 * (size_t)n) != 0 || vec_grow(&g->reg, (size_t)n) != 0 ||
         vec_grow(&g->at_tet, (size_t)n) != 0))
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld tets", (long long)n);
    for (int64_t i = 0; i < n && st == QDC_OK; i++) {
        const char *at;
        int32_t *mid = NULL;
        skip_ws(s);
        ((uint64_t *)g->at_tet.a)[g->at_tet.n] = (uint64_t)(s->p - s->base);
        st = txt_int(s, "volumeelements: material", INT32_MIN, INT32_MAX, &mat, err);
        skip_ws(s);
        at = s->p;
        if (st == QDC_OK)
            st = txt_int(s, "volumeelements: point count", 1, 64, &np, err);
        if (st == QDC_OK && (np == 4 || np == 10) && g->np && np != g->np)
            return fail_txt(err, QDC_EFORMAT, s, at,
                            "volumeelements: linear (4 points) and second-order (10 "
                            "points) tetrahedra in one mesh are not supported");
        if (st == QDC_OK && np == 10) {
            if (vec_grow(&g->mid, 6) != 0)
                return qdc_fail(err, QDC_ENOMEM, "out of memory for the mid-edge points");
            mid = (int32_t *)g->mid.a + g->mid.n;
        }
        for (int64_t k = 0; k < np && st == QDC_OK; k++) {
            st = txt_int(s, "volumeelements: point", 1, INT32_MAX, &v, err);
            if (st == QDC_OK && (np == 4 || (np == 10 && k < 4)))
                ((int32_t *)g->tets.a)[g->tets.n + (size_t)k] = (int32_t)v;
            else if (st == QDC_OK && np == 10)
                mid[edge[k - 4]] = (int32_t)v;
        }
        if (st != QDC_OK)
            set_index(err, "tet", i);
        else if (np == 4 || np == 10) {
            g->np = (int)np;
            g->mid.n += np == 10 ? 6 : 0;
            g->at_tet.n++;
            g->tets.n += 4;
            ((int32_t *)g->reg.a)[g->reg.n++] = (int32_t)mat;
        } else {
            g->skipped++;
        }
    }
    return st;
}

/* surfaceelements[gi|uv]: "surfnr bcnr domin domout np p1 .. pnp" (+ np
 * geometry ints for gi, np u v pairs for uv); a triangle of np 3, or 6
 * (second order: its corners first, read). */
static qdc_status vol_surface(txt *s, vol *g, int kind, qdc_error *err)
{
    int64_t n, v = 0, bc = 0, np = 0;
    double x;
    qdc_status st = txt_count(s, "surfaceelements", 8, INT32_MAX / 3, &n, err);

    if (st == QDC_OK &&
        (vec_grow(&g->tris, 3 * (size_t)n) != 0 || vec_grow(&g->ref, (size_t)n) != 0 ||
         vec_grow(&g->at_tri, (size_t)n) != 0))
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld triangles",
                        (long long)n);
    for (int64_t i = 0; i < n && st == QDC_OK; i++) {
        skip_ws(s);
        ((uint64_t *)g->at_tri.a)[g->at_tri.n] = (uint64_t)(s->p - s->base);
        for (int k = 0; k < 4 && st == QDC_OK; k++) {
            st = txt_int(s, "surfaceelements: number", INT32_MIN, INT32_MAX, &v, err);
            if (k == 1)
                bc = v;
        }
        if (st == QDC_OK)
            st = txt_int(s, "surfaceelements: point count", 1, 64, &np, err);
        for (int64_t k = 0; k < np && st == QDC_OK; k++) {
            st = txt_int(s, "surfaceelements: point", 1, INT32_MAX, &v, err);
            if (st == QDC_OK && (np == 3 || np == 6) && k < 3)
                ((int32_t *)g->tris.a)[g->tris.n + (size_t)k] = (int32_t)v;
        }
        for (int64_t k = 0; k < (kind == 1 ? np : 0) && st == QDC_OK; k++)
            st = txt_int(s, "surfaceelementsgi: geometry info", INT64_MIN, INT64_MAX, &v,
                         err);
        for (int64_t k = 0; k < (kind == 2 ? 2 * np : 0) && st == QDC_OK; k++)
            st = txt_real(s, "surfaceelementsuv: parameter", &x, err);
        if (st == QDC_OK && (np == 3 || np == 6)) {
            g->at_tri.n++;
            g->tris.n += 3;
            ((int32_t *)g->ref.a)[g->ref.n++] = (int32_t)bc;
        }
    }
    return st;
}

/* 1-based points idx[n] to 0-based, each checked against nv; an error at
 * the element's own line (at[]: byte offsets of the elements). */
static qdc_status vol_check(const txt *s, const uint64_t *at, int32_t *idx, size_t n,
                            int k, int64_t nv, const char *what, qdc_error *err)
{
    for (size_t i = 0; i < n; i++) {
        if (idx[i] < 1 || idx[i] > nv) {
            txt e = txt_init(s->base, (size_t)(s->end - s->base), 1);
            adv(&e, s->base + at[i / (size_t)k]);
            fail_txt(err, QDC_EPARSE, &e, e.p,
                     "%s: element %zu: point %d out of range [1, %lld]", what,
                     i / (size_t)k + 1, (int)idx[i], (long long)nv);
            set_index(err, k == 3 ? "triangle" : "tet", (int64_t)(i / (size_t)k));
            return QDC_EPARSE;
        }
        idx[i]--;
    }
    return QDC_OK;
}

/* points (the keyword at t): the count and the coordinates. */
static qdc_status vol_points(txt *s, const char *t, parsed *pm, srcrec *rec,
                             qdc_error *err)
{
    int64_t nv;
    qdc_status st;

    if (pm->nv >= 0)
        return fail_txt(err, QDC_EPARSE, s, t, "a second points section");
    st = txt_count(s, "points", 3, MESH_MAX_VERTICES, &nv, err);
    if (st != QDC_OK)
        return st;
    pm->nv = nv;
    pm->xyz = qdc_mallocn(3 * (size_t)nv + 1, sizeof(double));
    if (!pm->xyz)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld points", (long long)nv);
    if (rec) {
        rec->fmt = MESHIO_NETGEN;
        rec->kind = SRC_TEXT;
        rec->hash = 1;
        st = srcrec_alloc(rec, nv, err);
    }
    for (int64_t i = 0; i < nv && st == QDC_OK; i++) {
        if (rec) {
            skip_ws(s);
            rec->off[i] = (uint64_t)(s->p - s->base);
        }
        for (int a = 0; a < 3 && st == QDC_OK; a++)
            st = txt_real(s, "points: coordinate", &pm->xyz[3 * i + a], err);
        if (st != QDC_OK)
            set_index(err, "vertex", i);
    }
    return st;
}

/* The sections up to endmesh or the end of the file. Anything not read
 * (edge segments, face colours, geometry) is skipped a token at a time and
 * kept by a spliced write. */
static qdc_status vol_sections(txt *s, vol *g, parsed *pm, srcrec *rec, qdc_error *err)
{
    const char *t, *te;
    int64_t dim, c;
    qdc_status st = QDC_OK;

    while (st == QDC_OK) {
        size_t n;
        skip_ws(s);
        if (s->p == s->end)
            break;
        t = s->p;
        te = tok_end(s, t);
        n = (size_t)(te - t);
        s->p = te;
        if (word_is(t, n, "endmesh")) {
            break;
        } else if (word_is(t, n, "dimension")) {
            st = txt_int(s, "dimension", 3, 3, &dim, err);
        } else if (word_is(t, n, "volumeelements")) {
            st = vol_volume(s, g, err);
        } else if (word_is(t, n, "surfaceelements") ||
                   word_is(t, n, "surfaceelementsgi") ||
                   word_is(t, n, "surfaceelementsuv")) {
            if (g->ref.n)
                st = fail_txt(err, QDC_EPARSE, s, t, "a second surfaceelements section");
            if (st == QDC_OK)
                st = vol_surface(s, g, n == 15 ? 0 : (t[16] == 'i') ? 1 : 2, err);
        } else if (word_is(t, n, "points")) {
            st = vol_points(s, t, pm, rec, err);
        } else if (word_is(t, n, "materials") || word_is(t, n, "bcnames") ||
                   word_is(t, n, "cd2names") || word_is(t, n, "cd3names")) {
            /* "number name" pairs: a name may be any word, "points" too */
            st = txt_count(s, "names", 2, INT32_MAX, &c, err);
            /* the status first: c is unset when the count did not parse */
            for (int64_t i = 0; st == QDC_OK && i < 2 * c; i++) {
                skip_ws(s);
                s->p = tok_end(s, s->p);
            }
        }
    }
    return st;
}

static qdc_status read_netgen(const char *buf, size_t len, const meshio_options *o,
                              srcrec *rec, mesh_t **out, qdc_error *err)
{
    txt s = txt_init(buf, len, 1);
    vol g;
    parsed pm;
    const char *t, *te;
    qdc_status st;

    memset(&g, 0, sizeof g);
    g.tets.size = g.reg.size = g.tris.size = g.ref.size = g.mid.size = sizeof(int32_t);
    g.at_tet.size = g.at_tri.size = sizeof(uint64_t);
    parsed_init(&pm);
    skip_ws(&s);
    t = s.p;
    te = tok_end(&s, t);
    if (word_is(t, (size_t)(te - t), "mesh2d"))
        return fail_txt(err, QDC_EFORMAT, &s, t,
                        "Netgen: 2D meshes (mesh2d) are not supported");
    if (!word_is(t, (size_t)(te - t), "mesh3d"))
        return fail_txt(err, QDC_EFORMAT, &s, t, "not a Netgen mesh: no mesh3d");
    s.p = te;
    st = vol_sections(&s, &g, &pm, rec, err);
    if (st == QDC_OK && pm.nv < 0)
        st = fail_txt(err, QDC_EPARSE, &s, s.p, "Netgen: no points section");
    if (st == QDC_OK)
        st = vol_check(&s, g.at_tet.a, g.tets.a, g.tets.n, 4, pm.nv, "volumeelements",
                       err);
    if (st == QDC_OK)
        st = vol_check(&s, g.at_tet.a, g.mid.a, g.mid.n, 6, pm.nv, "volumeelements", err);
    if (st == QDC_OK)
        st = vol_check(&s, g.at_tri.a, g.tris.a, g.tris.n, 3, pm.nv, "surfaceelements",
                       err);
    if (st == QDC_OK) {
        pm.nt = (int64_t)g.reg.n;
        pm.tets = g.tets.a;
        pm.region = g.reg.a;
        pm.ntri = (int64_t)g.ref.n;
        pm.tris = g.tris.a;
        pm.tri_ref = g.ref.a;
        pm.mid = g.np == 10 ? g.mid.a : NULL;
        st = parsed_mesh(&pm, out, err);
        pm.tets = pm.region = pm.tris = pm.tri_ref = pm.mid = NULL;
        if (g.skipped)
            note(o, "netgen: skipped %lld volume elements that are not tetrahedra",
                 (long long)g.skipped);
    }
    parsed_free(&pm);
    vol_free(&g);
    return st;
}

/* ------------------------------------------------------------------------ */
/* Writing Abaqus and Netgen                                                 */

/* A face of a tet: its corners sorted, and the tet. */
typedef struct {
    int32_t v[3];
    int32_t t;
} fe_face;

static void sort3(int32_t *v)
{
    int32_t x;

    if (v[0] > v[1]) {
        x = v[0], v[0] = v[1], v[1] = x;
    }
    if (v[1] > v[2]) {
        x = v[1], v[1] = v[2], v[2] = x;
    }
    if (v[0] > v[1]) {
        x = v[0], v[0] = v[1], v[1] = x;
    }
}

static int fe_face_cmp(const void *x, const void *y)
{
    const fe_face *a = x, *b = y;

    for (int k = 0; k < 3; k++)
        if (a->v[k] != b->v[k])
            return a->v[k] < b->v[k] ? -1 : 1;
    return (a->t > b->t) - (a->t < b->t);
}

/* The faces of m's tets (4 nt), sorted; NULL with err on failure. */
static fe_face *fe_faces(const mesh_t *m, qdc_error *err)
{
    fe_face *f = qdc_mallocn(4 * (size_t)m->nt + 1, sizeof *f);

    if (!f) {
        qdc_fail(err, QDC_ENOMEM, "out of memory for the faces of %d tets", (int)m->nt);
        return NULL;
    }
    for (int32_t t = 0; t < m->nt; t++)
        for (int k = 0; k < 4; k++) {
            fe_face *e = &f[4 * (size_t)t + (size_t)k];
            for (int j = 0, n = 0; j < 4; j++)
                if (j != k)
                    e->v[n++] = m->tets[4 * (size_t)t + (size_t)j];
            sort3(e->v);
            e->t = t;
        }
    qsort(f, 4 * (size_t)m->nt, sizeof *f, fe_face_cmp);
    return f;
}

/* The tets (two at most) that have triangle tri as a face: their count,
 * the tets in t[]. */
static int fe_face_tets(const mesh_t *m, const fe_face *f, const int32_t *tri,
                        int32_t t[2])
{
    fe_face want;
    size_t lo = 0, hi = 4 * (size_t)m->nt;
    int n = 0;

    memcpy(want.v, tri, sizeof want.v);
    sort3(want.v);
    want.t = -1;
    while (lo < hi) { /* the first face not before want */
        size_t mid = lo + (hi - lo) / 2;
        if (fe_face_cmp(&f[mid], &want) < 0)
            lo = mid + 1;
        else
            hi = mid;
    }
    for (; lo < 4 * (size_t)m->nt && n < 2 && memcmp(f[lo].v, want.v, sizeof want.v) == 0;
         lo++)
        t[n++] = f[lo].t;
    return n;
}

/* The mid-edge node of edge (x, y) of tet t (a second-order mesh), -1 if
 * the tet has no such edge. */
static int32_t fe_mid(const mesh_t *m, int32_t t, int32_t x, int32_t y)
{
    const int32_t *v = m->tets + 4 * (size_t)t;

    for (int e = 0; e < 6; e++) {
        int32_t a = v[mesh_p2_edges[e][0]], b = v[mesh_p2_edges[e][1]];
        if ((a == x && b == y) || (a == y && b == x))
            return m->mid[6 * (size_t)t + (size_t)e];
    }
    return -1;
}

/* The mid-edge nodes of triangle tri's edges 01, 12, 20 in mid[3], from a
 * tet it is a face of (f: fe_faces); 0 if it is the face of none. */
static int fe_tri_mid(const mesh_t *m, const fe_face *f, const int32_t *tri,
                      int32_t mid[3])
{
    int32_t t[2];

    if (fe_face_tets(m, f, tri, t) == 0)
        return 0;
    for (int e = 0; e < 3; e++)
        mid[e] = fe_mid(m, t[0], tri[e], tri[(e + 1) % 3]);
    return mid[0] >= 0 && mid[1] >= 0 && mid[2] >= 0;
}

qdc_status meshio_tri_mids(const mesh_t *m, int32_t *mid, int *all, qdc_error *err)
{
    fe_face *f = fe_faces(m, err);

    *all = 0;
    if (!f)
        return err ? err->status : QDC_ENOMEM;
    *all = 1;
    for (int32_t i = 0; *all && i < m->ntri; i++)
        *all = fe_tri_mid(m, f, m->tris + 3 * (size_t)i, mid + 3 * (size_t)i);
    qdc_free(f);
    return QDC_OK;
}

static int cmp_u64(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;

    return (a > b) - (a < b);
}

/* 0..n-1 ordered by key[] (ascending; in order within a key, and all in
 * order if key is NULL) in the low 32 bits of a new array (qdc_free);
 * NULL with err on failure. */
static uint64_t *fe_order(const int32_t *key, int32_t n, qdc_error *err)
{
    uint64_t *o = qdc_mallocn((size_t)n + 1, sizeof *o);

    if (!o) {
        qdc_fail(err, QDC_ENOMEM, "out of memory for the order of %d elements", (int)n);
        return NULL;
    }
    for (int32_t i = 0; i < n; i++)
        o[i] = (key ? (uint64_t)((int64_t)key[i] - INT32_MIN) << 32 : 0) | (uint32_t)i;
    if (key)
        qsort(o, (size_t)n, sizeof *o, cmp_u64);
    return o;
}

/* An ELSET name of qdc's: prefix and n, "M" before a negative n's digits
 * (meshio_name_number reads it back). */
static void inp_set_name(wbuf *w, const char *prefix, int32_t n)
{
    wb_str(w, prefix);
    if (n < 0)
        wb_str(w, "M");
    wb_int(w, n < 0 ? -(int64_t)n : n);
}

/* The tets: one *ELEMENT block per region (ascending), ELSET=REGION_<n>
 * (none without regions); tet t is element t + 1. */
static qdc_status inp_write_tets(const mesh_t *m, wbuf *w, qdc_error *err)
{
    uint64_t *o = fe_order(m->region, m->nt, err);

    if (!o)
        return err->status;
    for (int32_t k = 0; k < m->nt; k++) {
        int32_t t = (int32_t)(uint32_t)o[k], prev = (int32_t)(uint32_t)o[k ? k - 1 : 0];
        if (k == 0 || (m->region && m->region[t] != m->region[prev])) {
            wb_str(w, m->mid ? "*ELEMENT, TYPE=C3D10" : "*ELEMENT, TYPE=C3D4");
            if (m->region) {
                wb_str(w, ", ELSET=");
                inp_set_name(w, "REGION_", m->region[t]);
            }
            wb_str(w, "\n");
        }
        wb_int(w, (int64_t)t + 1);
        wb_str(w, ", ");
        wb_ints(w, m->tets + 4 * (size_t)t, 4, 1, ", ", m->mid ? ", " : "\n");
        if (m->mid) /* C3D10's node order is mesh_p2_edges' */
            wb_ints(w, m->mid + 6 * (size_t)t, 6, 1, ", ", "\n");
    }
    qdc_free(o);
    return QDC_OK;
}

/* The triangles: one *ELEMENT block per ref (ascending), ELSET=SURFACE_<n>
 * (none without refs), S3, or STRI65 in a second-order mesh whose
 * triangles are all faces of its tets (their mid-edge nodes the tets');
 * triangle i is element nt + i + 1. */
static qdc_status inp_write_tris(const mesh_t *m, wbuf *w, qdc_error *err)
{
    fe_face *f = m->mid ? fe_faces(m, err) : NULL;
    int32_t *mid = m->mid ? qdc_mallocn(3 * (size_t)m->ntri + 1, sizeof *mid) : NULL;
    uint64_t *o = (!m->mid || (f && mid)) ? fe_order(m->tri_ref, m->ntri, err) : NULL;
    int six = m->mid != NULL;

    if (!o || (m->mid && (!f || !mid))) {
        qdc_free(f);
        qdc_free(mid);
        qdc_free(o);
        return o ? qdc_fail(err, QDC_ENOMEM, "out of memory for the triangles")
                 : err->status;
    }
    for (int32_t i = 0; six && i < m->ntri; i++)
        six = fe_tri_mid(m, f, m->tris + 3 * (size_t)i, mid + 3 * (size_t)i);
    for (int32_t k = 0; k < m->ntri; k++) {
        int32_t i = (int32_t)(uint32_t)o[k], prev = (int32_t)(uint32_t)o[k ? k - 1 : 0];
        if (k == 0 || (m->tri_ref && m->tri_ref[i] != m->tri_ref[prev])) {
            wb_str(w, six ? "*ELEMENT, TYPE=STRI65" : "*ELEMENT, TYPE=S3");
            if (m->tri_ref) {
                wb_str(w, ", ELSET=");
                inp_set_name(w, "SURFACE_", m->tri_ref[i]);
            }
            wb_str(w, "\n");
        }
        wb_int(w, (int64_t)m->nt + i + 1);
        wb_str(w, ", ");
        wb_ints(w, m->tris + 3 * (size_t)i, 3, 1, ", ", six ? ", " : "\n");
        if (six)
            wb_ints(w, mid + 3 * (size_t)i, 3, 1, ", ", "\n");
    }
    qdc_free(f);
    qdc_free(mid);
    qdc_free(o);
    return QDC_OK;
}

/* Abaqus/CalculiX: *HEADING, *NODE (numbered from 1), the tets and the
 * triangles (inp_write_tets, inp_write_tris). Vertex refs and fixed flags
 * are not written. */
static qdc_status write_abaqus(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                               qdc_error *err)
{
    qdc_status st;

    (void)fmt;
    (void)part;
    wb_str(w, "*HEADING\nwritten by qdc\n*NODE\n");
    for (int32_t i = 0; i < m->nv; i++) {
        wb_int(w, (int64_t)i + 1);
        wb_str(w, ", ");
        wb_reals(w, m->xyz + 3 * (size_t)i, 3, ", ", "\n");
    }
    st = inp_write_tets(m, w, err);
    if (st == QDC_OK && m->ntri > 0)
        st = inp_write_tris(m, w, err);
    return st;
}

/* The domains on either side of triangle tri as Netgen gives them (the
 * triangle's normal, right-handed, points from domin into domout): the
 * materials (region, 1 without) of the tets it is a face of, 0 for none. */
static void vol_sides(const mesh_t *m, const fe_face *f, const int32_t *tri,
                      int32_t side[2])
{
    int32_t t[2];
    int n = fe_face_tets(m, f, tri, t), taken[2] = {0, 0};
    const double *a = m->xyz + 3 * (size_t)tri[0], *b = m->xyz + 3 * (size_t)tri[1],
                 *c = m->xyz + 3 * (size_t)tri[2];
    double u[3], v[3], nrm[3];

    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
    }
    nrm[0] = u[1] * v[2] - u[2] * v[1];
    nrm[1] = u[2] * v[0] - u[0] * v[2];
    nrm[2] = u[0] * v[1] - u[1] * v[0];
    side[0] = side[1] = 0;
    for (int k = 0; k < n; k++) {
        const int32_t *tv = m->tets + 4 * (size_t)t[k];
        double dot = 0;
        int s;
        for (int j = 0; j < 4; j++)
            if (tv[j] != tri[0] && tv[j] != tri[1] && tv[j] != tri[2])
                for (int q = 0; q < 3; q++)
                    dot += nrm[q] * (m->xyz[3 * (size_t)tv[j] + (size_t)q] - a[q]);
        s = dot > 0; /* the tet is on the side the normal points to: domout */
        if (taken[s])
            s = !s;
        taken[s] = 1;
        side[s] = m->region ? m->region[t[k]] : 1;
    }
}

/* surfaceelements: "surfnr bcnr domin domout np p1 .. pnp", surface 1,
 * the ref as bc number, 6 points (corners, then the mid-edge nodes of edges
 * 12 02 01 as Netgen lists them) in a second-order mesh where the triangle
 * is a tet's face. */
static void vol_write_tris(const mesh_t *m, const fe_face *f, wbuf *w)
{
    wb_str(w, "# surfnr    bcnr   domin  domout      np      p1      p2      p3\n"
              "surfaceelements\n");
    wb_int(w, m->ntri);
    wb_str(w, "\n");
    for (int32_t i = 0; i < m->ntri; i++) {
        const int32_t *tri = m->tris + 3 * (size_t)i;
        int32_t side[2], mid[3];
        int six = m->mid && fe_tri_mid(m, f, tri, mid);
        vol_sides(m, f, tri, side);
        wb_str(w, "1 ");
        wb_int(w, m->tri_ref ? m->tri_ref[i] : 0);
        wb_str(w, " ");
        wb_ints(w, side, 2, 0, " ", six ? " 6 " : " 3 ");
        wb_ints(w, tri, 3, 1, " ", six ? " " : "\n");
        if (six) {
            int32_t nm[3] = {mid[1], mid[2], mid[0]};
            wb_ints(w, nm, 3, 1, " ", "\n");
        }
    }
}

/* Netgen mesh3d as Netgen writes it: surfaceelements (vol_write_tris),
 * volumeelements "matnr np p1 .. pnp" (the region, 1 without; 10 points
 * for a second-order tet, mid-edge nodes of edges 01 02 03 12 13 23),
 * edgesegmentsgi2 (none), points. Vertex refs and fixed flags are not
 * written. */
static qdc_status write_netgen(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                               qdc_error *err)
{
    static const int edge[6] = {0, 2, 3, 1, 4, 5}; /* Netgen's to mesh_p2_edges */
    fe_face *f = m->ntri > 0 ? fe_faces(m, err) : NULL;

    (void)fmt;
    (void)part;
    if (m->ntri > 0 && !f)
        return err->status;
    wb_str(w, "mesh3d\ndimension\n3\ngeomtype\n0\n\n");
    vol_write_tris(m, f, w);
    qdc_free(f);
    wb_str(w, "\n#  matnr      np      p1      p2      p3      p4\nvolumeelements\n");
    wb_int(w, m->nt);
    wb_str(w, "\n");
    for (int32_t t = 0; t < m->nt; t++) {
        wb_int(w, m->region ? m->region[t] : 1);
        wb_str(w, m->mid ? " 10 " : " 4 ");
        wb_ints(w, m->tets + 4 * (size_t)t, 4, 1, " ", m->mid ? " " : "\n");
        for (int j = 0; m->mid && j < 6; j++) {
            wb_int(w, (int64_t)m->mid[6 * (size_t)t + (size_t)edge[j]] + 1);
            wb_str(w, j < 5 ? " " : "\n");
        }
    }
    wb_str(w,
           "\nedgesegmentsgi2\n0\n\n#          X             Y             Z\npoints\n");
    wb_int(w, m->nv);
    wb_str(w, "\n");
    for (int32_t i = 0; i < m->nv; i++)
        wb_reals(w, m->xyz + 3 * (size_t)i, 3, " ", "\n");
    wb_str(w, "\nendmesh\n");
    return QDC_OK;
}

/* An XML document whose first element, within 1 kB, is a dolfin. */
static meshio_format sniff_dolfin(const char *buf, size_t len, size_t i)
{
    static const char dtag[] = "<dolfin";
    const char *p = buf + i;
    size_t n = len - i, lim = n < 1024 ? n : 1024;

    if (i >= len || buf[i] != '<')
        return MESHIO_AUTO;
    for (size_t k = 0; k + sizeof dtag - 1 <= lim; k++)
        if (memcmp(p + k, dtag, sizeof dtag - 1) == 0 &&
            (k + sizeof dtag - 1 == n || !is_word((unsigned char)p[k + sizeof dtag - 1])))
            return MESHIO_DOLFIN;
    return MESHIO_AUTO;
}

/* A first line starting with '*'. */
static meshio_format sniff_abaqus(const char *buf, size_t len, size_t i)
{
    return i < len && buf[i] == '*' && (i == 0 || buf[i - 1] == '\n') ? MESHIO_ABAQUS
                                                                      : MESHIO_AUTO;
}

/* "mesh3d" (or "mesh2d", which the reader refuses) first. */
static meshio_format sniff_netgen(const char *buf, size_t len, size_t i)
{
    size_t w;

    for (w = i; w < len && is_word((unsigned char)buf[w]); w++)
        ;
    return word_is(buf + i, w - i, "mesh3d") || word_is(buf + i, w - i, "mesh2d")
               ? MESHIO_NETGEN
               : MESHIO_AUTO;
}

const meshio_fmt fmt_dolfin = {
    .name = "dolfin",
    .aliases = "dolfin-xml xml",
    .about = "DOLFIN/FEniCS legacy XML, celltype tetrahedron (domains and mesh "
             "functions kept by splicing)",
    .ext = "xml",
    .input = "input.xml",
    .sniff = sniff_dolfin,
    .read = read_dolfin,
    .write = write_dolfin,
    .splices = 1,
};

const meshio_fmt fmt_abaqus = {
    .name = "abaqus",
    .aliases = "calculix inp",
    .about = "Abaqus/CalculiX .inp: *NODE, *ELEMENT TYPE=C3D4 or C3D10, ELSETs as "
             "regions, triangle elements (S3, CPS3, R3D3...) kept",
    .ext = "inp",
    .input = "input.inp",
    .sniff = sniff_abaqus,
    .read = read_abaqus,
    .write = write_abaqus,
    .splices = 1,
    .p2 = 1,
};

const meshio_fmt fmt_netgen = {
    .name = "netgen",
    .aliases = "vol",
    .about = "Netgen .vol mesh3d: materials as regions, surface elements kept",
    .ext = "vol",
    .input = "input.vol",
    .sniff = sniff_netgen,
    .read = read_netgen,
    .write = write_netgen,
    .splices = 1,
    .p2 = 1,
};
