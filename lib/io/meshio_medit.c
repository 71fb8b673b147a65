/* meshio_medit.c - Medit .mesh ASCII: reader (large sections in parallel)
 * and writer. */
#include "io/format.h"

#include <math.h>
#include <string.h>

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
    int64_t np2;          /* TetrahedraP2 entries, -1 = none */
    int32_t *p2, *p2_ref; /* 10 indices each, and refs */
    txt p2_at;
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
        return medit_elem_section(s, "TetrahedraP2", 10, MESH_MAX_TETS, pm, &ms->np2,
                                  &ms->p2, &ms->p2_ref, &ms->p2_at, err);
    if (word_is(kw, kl, "RequiredVertices")) {
        return medit_elem_section(s, "RequiredVertices", 1, INT32_MAX, pm, &pm->nfix,
                                  &pm->fix, NULL, &ms->fix_at, err);
    }
    for (size_t i = 0; i < sizeof medit_skip / sizeof medit_skip[0]; i++)
        if (word_is(kw, kl, medit_skip[i].kw))
            return medit_skip_section(s, medit_skip[i].kw, medit_skip[i].ntok, err);
    return medit_skip_unknown(s, kw, kl, err);
}

/* The orders in which writers list a TetrahedraP2's mid-edge nodes, as
 * positions in mesh_p2_edges (01, 12, 02, 03, 13, 23): that one (Gmsh's
 * Medit writer, qdc), Mmg's edge numbering (01, 02, 03, 12, 13, 23) and
 * Gmsh's own (01, 12, 02, 03, 23, 13). */
static const int medit_p2_orders[3][6] = {
    {0, 1, 2, 3, 4, 5}, {0, 2, 3, 1, 4, 5}, {0, 1, 2, 3, 5, 4}};

/* Which of medit_p2_orders the file follows: the one that puts the
 * mid-edge nodes nearest their edges' midpoints (summed over the tets; a
 * tie keeps the first). p2 holds 10 checked indices per tet. */
static int medit_p2_order(const parsed *pm, const int32_t *p2, int64_t nt)
{
    double best = INFINITY;
    int pick = 0;

    for (int o = 0; o < 3; o++) {
        double sum = 0;
        for (int64_t t = 0; t < nt; t++) {
            const int32_t *e = p2 + 10 * t;
            for (int f = 0; f < 6; f++) { /* file position f is edge order[o][f] */
                const int *ab = mesh_p2_edges[medit_p2_orders[o][f]];
                const double *a = pm->xyz + 3 * (size_t)e[ab[0]],
                             *b = pm->xyz + 3 * (size_t)e[ab[1]],
                             *mm = pm->xyz + 3 * (size_t)e[4 + f];
                for (int k = 0; k < 3; k++)
                    sum += fabs(mm[k] - 0.5 * (a[k] + b[k]));
            }
        }
        if (sum < best) {
            best = sum;
            pick = o;
        }
    }
    return pick;
}

/* TetrahedraP2 (checked) into pm's tets and mid-edge table. */
static qdc_status medit_p2_split(medit_state *ms, const txt *s, qdc_error *err)
{
    parsed *pm = &ms->pm;
    int o;

    if (pm->nt > 0)
        return fail_txt(err, QDC_EFORMAT, s, s->p,
                        "Tetrahedra and TetrahedraP2: linear and second-order "
                        "tetrahedra in one file are not supported");
    qdc_free(pm->tets);
    qdc_free(pm->region);
    pm->nt = ms->np2;
    pm->tets = qdc_mallocn((size_t)pm->nt * 4 + 1, sizeof(int32_t));
    pm->mid = qdc_mallocn((size_t)pm->nt * 6 + 1, sizeof(int32_t));
    pm->region = ms->p2_ref;
    ms->p2_ref = NULL;
    if (!pm->tets || !pm->mid)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld tets",
                        (long long)pm->nt);
    o = medit_p2_order(pm, ms->p2, pm->nt);
    for (int64_t t = 0; t < pm->nt; t++) {
        memcpy(pm->tets + 4 * t, ms->p2 + 10 * t, 4 * sizeof(int32_t));
        for (int f = 0; f < 6; f++)
            pm->mid[6 * t + medit_p2_orders[o][f]] = ms->p2[10 * t + 4 + f];
    }
    return QDC_OK;
}

static qdc_status read_medit(const char *buf, size_t len, const meshio_options *o,
                             srcrec *rec, mesh_t **out, qdc_error *err)
{
    (void)o;
    medit_state ms;
    parsed *pm = &ms.pm;
    txt s = txt_init(buf, len, 1);
    qdc_status st = QDC_OK;
    char q[32];

    memset(&ms, 0, sizeof ms);
    ms.np2 = -1;
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
    if (st == QDC_OK && ms.np2 >= 0)
        st = medit_recheck(&ms.p2_at, "TetrahedraP2", ms.np2, 10, 1, pm->nv, ms.p2, err);
    if (st == QDC_OK && ms.np2 >= 0)
        st = medit_p2_split(&ms, &s, err);
    if (st == QDC_OK)
        st = parsed_mesh_move(pm, out, err);
out:
    parsed_free(pm);
    qdc_free(ms.p2);
    qdc_free(ms.p2_ref);
    return st;
}

static qdc_status write_medit(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                              qdc_error *err)
{
    (void)fmt;
    (void)part;
    (void)err;
    int32_t nfix = 0;

    wb_str(w, "MeshVersionFormatted 2\n\nDimension 3\n\nVertices\n");
    wb_int(w, m->nv);
    wb_str(w, "\n");
    for (int32_t i = 0; i < m->nv; i++) {
        wb_reals(w, m->xyz + 3 * (size_t)i, 3, " ", " ");
        wb_int(w, m->vref ? m->vref[i] : 0);
        wb_str(w, "\n");
    }
    wb_str(w, m->mid ? "\nTetrahedraP2\n" : "\nTetrahedra\n");
    wb_int(w, m->nt);
    wb_str(w, "\n");
    for (int32_t t = 0; t < m->nt; t++) {
        wb_ints(w, m->tets + 4 * (size_t)t, 4, 1, " ", " ");
        if (m->mid) /* in mesh_p2_edges order, as Gmsh writes it */
            wb_ints(w, m->mid + 6 * (size_t)t, 6, 1, " ", " ");
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
    return QDC_OK;
}

/* "MeshVersionFormatted", "Dimension" or "Vertices" first. */
static meshio_format sniff_medit(const char *buf, size_t len, size_t i)
{
    static const char *const words[] = {"MeshVersionFormatted", "Dimension", "Vertices"};
    size_t w;

    for (w = i; w < len && is_word((unsigned char)buf[w]); w++)
        ;
    for (size_t k = 0; k < sizeof words / sizeof words[0]; k++)
        if (word_is(buf + i, w - i, words[k]))
            return MESHIO_MEDIT;
    return MESHIO_AUTO;
}

const meshio_fmt fmt_medit = {
    .name = "medit",
    .aliases = "mesh",
    .about =
        "Medit .mesh ASCII (Vertices, Tetrahedra with refs as regions, Triangles kept)",
    .ext = "mesh",
    .input = "input.mesh",
    .media = "model/x-medit",
    .media_alt = "text/x-medit",
    .sniff = sniff_medit,
    .read = read_medit,
    .write = write_medit,
    .splices = 1,
    .p2 = 1,
};
