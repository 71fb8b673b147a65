/* meshio_bdf.c - Nastran bulk data (.bdf, .nas): read and written.
 *
 * A card is a line and its continuation lines (first character '+', '*' or
 * ','; '$' starts a comment). Its fields are fixed (small: 8 characters,
 * data in fields 2-9; large, a name ending in '*': data in four fields of 16
 * after the 8-character name, the continuation line starting with '*') or
 * free (separated by commas, at most 8 data fields a line, 4 for a large
 * card). Read: GRID (ID, CP, X1-X3, CD; CP 0 or blank, the basic system, as
 * other systems would need their CORD cards), CTETRA with 4 nodes or 10
 * (second order: mesh_t.mid; PID as region) and CTRIA3 and CTRIA6 (their
 * corners, PID as tri_ref); everything else is kept, and written
 * back unchanged: only the GRID coordinate fields are rewritten, each in its
 * own width (splice.c, SRC_FIELD). Reals take Nastran's short forms, "1.-3"
 * (1e-3) and "-.5+2" (-50), and the D exponent. Lines before BEGIN BULK
 * (executive and case control) and after ENDDATA are skipped. A PID may be
 * negative or blank (0). A file of no GRID card is refused unless it is an
 * empty bulk section: BEGIN BULK, ENDDATA and nothing after (an empty mesh).
 * Written (a mesh whose tets changed, or another format's), free field:
 * "BEGIN BULK", GRID,ID,,X1,X2,X3 with IDs 1..nv and each coordinate as
 * %.17g with a decimal point added where it has none ("1.", "1.e-05": it
 * reads back bit for bit; a free field of up to 24 characters), CTETRA,EID,
 * PID,G1-G4 (10-node: G1-G6,+ then "+,G7,G8,G9,G10", G5-G10 the mid-side
 * nodes in the order above), PID the region (blank without regions), then
 * CTRIA3,EID,PID,G1-G3 with PID the triangle's ref (blank without), EIDs
 * numbered on from the tets, "ENDDATA". No property cards (PSOLID, PSHELL):
 * Gmsh and meshio read the file without them. */
#include "io/format.h"

#include <stdio.h>
#include <string.h>

enum { BDF_FIELDS = 16 }; /* data fields kept of a card: CTETRA has 12 */

/* One data field: [t, te) without its blanks; [a, a + w) the field (w 0: past
 * the line's end); the line it is on. */
typedef struct {
    const char *t, *te, *a, *bol;
    int w, free;
    int64_t line;
} field;

typedef struct {
    txt s;
    field f[BDF_FIELDS];
    int nf;
    labelled l;
    int64_t other;          /* cards kept unread */
    const char *other_name; /* the first of them */
    size_t other_len;
    int blank_field; /* a coordinate field past its line's end */
    int empty_bulk;  /* BEGIN BULK, ENDDATA, nothing but comments after */
} bdf;

/* Line [*bol, *eol) at p (the '\n' and a '\r' before it not included). */
static const char *line_end(const txt *s, const char *p)
{
    const char *e = memchr(p, '\n', (size_t)(s->end - p));

    return e ? e : s->end;
}

static const char *trim_end(const char *a, const char *e)
{
    while (e > a && (e[-1] == ' ' || e[-1] == '\r'))
        e--;
    return e;
}

/* The data fields of one line [bol, eol) into b->f, large or small; free if
 * it has a comma. A '$' ends the data. */
static qdc_status line_fields(bdf *b, const char *bol, const char *eol, int large,
                              qdc_error *err)
{
    const char *dollar = memchr(bol, '$', (size_t)(eol - bol));
    const char *e = trim_end(bol, dollar ? dollar : eol);
    int per = large ? 4 : 8;

    if (memchr(bol, ',', (size_t)(e - bol))) {
        const char *p = (const char *)memchr(bol, ',', (size_t)(e - bol)) + 1;
        for (int k = 0; k < per && p <= e && b->nf < BDF_FIELDS; k++) {
            const char *c = memchr(p, ',', (size_t)(e - p));
            const char *fe = c ? c : e, *t = p;
            field *f = &b->f[b->nf++];
            while (t < fe && is_space((unsigned char)*t))
                t++;
            f->t = f->a = t;
            f->te = fe;
            while (f->te > t && is_space((unsigned char)f->te[-1]))
                f->te--;
            f->w = 16;
            f->free = 1;
            f->line = b->s.line;
            f->bol = bol;
            if (!c)
                break;
            p = c + 1;
        }
        return QDC_OK;
    }
    if (memchr(bol, '\t', (size_t)(e - bol)))
        return fail_txt(err, QDC_EFORMAT, &b->s,
                        (const char *)memchr(bol, '\t', (size_t)(e - bol)),
                        "a tab in a fixed-field card (tabs are not read: use blanks "
                        "or commas)");
    for (int k = 0; k < per && b->nf < BDF_FIELDS; k++) {
        size_t w = large ? 16 : 8, at = 8 + (size_t)k * w, n = (size_t)(e - bol);
        field *f = &b->f[b->nf++];
        f->free = 0;
        f->line = b->s.line;
        f->bol = bol;
        if (n <= at) { /* the line ends before the field: blank */
            f->t = f->te = f->a = e;
            f->w = 0;
            continue;
        }
        f->a = f->t = bol + at;
        f->w = (int)w;
        f->te = bol + (n - at < w ? n : at + w);
        while (f->t < f->te && *f->t == ' ')
            f->t++;
        while (f->te > f->t && f->te[-1] == ' ')
            f->te--;
    }
    return QDC_OK;
}

/* Data field k as an integer in [lo, hi]; blank: dflt (or an error if dflt < lo). */
static qdc_status field_int(bdf *b, int k, const char *what, int64_t lo, int64_t hi,
                            int64_t dflt, int64_t *v, qdc_error *err)
{
    const field *f = &b->f[k];
    char q[32];
    int rc;

    b->s.line = k < b->nf ? f->line : b->s.line;
    b->s.bol = k < b->nf ? f->bol : b->s.bol;
    if (k >= b->nf || f->t == f->te) {
        if (dflt < lo)
            return fail_txt(err, QDC_EPARSE, &b->s, k < b->nf ? f->t : b->f[0].t,
                            "%s: missing", what);
        *v = dflt;
        return QDC_OK;
    }
    rc = parse_int(f->t, f->te, 0, v);
    if (rc == -1)
        return fail_txt(err, QDC_EPARSE, &b->s, f->t, "%s: expected an integer, got %s",
                        what, quote_tok(q, &b->s, f->t, f->te));
    if (rc == -2 || *v < lo || *v > hi)
        return fail_txt(err, QDC_EPARSE, &b->s, f->t, "%s %s out of range [%lld, %lld]",
                        what, quote_tok(q, &b->s, f->t, f->te), (long long)lo,
                        (long long)hi);
    return QDC_OK;
}

/* Data field k as a finite real; blank: 0. */
static qdc_status field_real(bdf *b, int k, const char *what, double *v, qdc_error *err)
{
    const field *f = &b->f[k];
    char q[32];

    *v = 0;
    if (k >= b->nf || f->t == f->te)
        return QDC_OK;
    b->s.line = f->line;
    b->s.bol = f->bol;
    if (parse_fortran_real(f->t, f->te, v) != 0)
        return fail_txt(err, QDC_EPARSE, &b->s, f->t, "%s: expected a number, got %s",
                        what, quote_tok(q, &b->s, f->t, f->te));
    if (!isfinite(*v))
        return fail_txt(err, QDC_EPARSE, &b->s, f->t, "%s %s is not finite (NaN/Inf)",
                        what, quote_tok(q, &b->s, f->t, f->te));
    return QDC_OK;
}

static qdc_status bdf_grid(bdf *b, qdc_error *err)
{
    int64_t id, cp, cd;
    double x[3];
    uint64_t off[3];
    qdc_status st;

    st = field_int(b, 0, "GRID: ID", 1, INT32_MAX, -1, &id, err);
    if (st == QDC_OK)
        st = field_int(b, 1, "GRID: CP", 0, INT32_MAX, 0, &cp, err);
    if (st == QDC_OK && cp != 0)
        return fail_txt(err, QDC_EFORMAT, &b->s, b->f[1].t,
                        "GRID %lld: coordinate system %lld (CP) is not supported: qdc "
                        "reads GRID coordinates in the basic system (CP 0 or blank)",
                        (long long)id, (long long)cp);
    for (int k = 0; k < 3 && st == QDC_OK; k++) {
        const field *f = &b->f[2 + k];
        st = field_real(b, 2 + k, "GRID: coordinate", &x[k], err);
        if (2 + k >= b->nf || (!f->free && f->w == 0)) {
            b->blank_field = 1;
            off[k] = 0;
        } else {
            off[k] = FIELD(f->free ? f->t - b->s.base : f->a - b->s.base, f->w,
                           f->free ? FIELD_FREE : 0);
        }
    }
    if (st == QDC_OK) /* CD orients displacements only: kept, not used */
        st = field_int(b, 5, "GRID: CD", -1, INT32_MAX, 0, &cd, err);
    if (st != QDC_OK)
        return st;
    return lab_node(&b->l, id, x, off, err);
}

/* Where field k is, for an error there. */
static const char *at_field(bdf *b, int k)
{
    b->s.line = b->f[k].line;
    b->s.bol = b->f[k].bol;
    return b->f[k].t;
}

/* CTETRA (n 4: G1-G4, or all of G1-G10: the mid-side nodes of edges 1-2,
 * 2-3, 3-1, 1-4, 2-4, 3-4, the order of mesh_p2_edges), CTRIA3 (n 3) or
 * CTRIA6 (n 6: its corners read, G4-G6 may be blank): element id, PID, the
 * node ids. */
static qdc_status bdf_element(bdf *b, int n, const char *at, qdc_error *err)
{
    int64_t eid, pid, g[10];
    int tri = n != 4, mids = 0, last = 2 + (tri ? n : 10);
    const char *name = !tri ? "CTETRA" : n == 3 ? "CTRIA3" : "CTRIA6";
    char what[3][16];
    qdc_status st;

    snprintf(what[0], sizeof what[0], "%s: EID", name);
    snprintf(what[1], sizeof what[1], "%s: PID", name);
    snprintf(what[2], sizeof what[2], "%s: node", name);
    st = field_int(b, 0, what[0], 1, INT64_MAX, -1, &eid, err);
    if (st == QDC_OK)
        st = field_int(b, 1, what[1], INT32_MIN, INT32_MAX, 0, &pid, err);
    for (int k = last; k < b->nf && st == QDC_OK; k++)
        if (b->f[k].t != b->f[k].te)
            return fail_txt(err, QDC_EFORMAT, &b->s, at_field(b, k),
                            "%s %lld: more than %d nodes", name, (long long)eid,
                            last - 2);
    for (int k = 6; !tri && k < last && k < b->nf; k++)
        mids += b->f[k].t != b->f[k].te;
    if (st == QDC_OK && mids && mids < 6)
        return fail_txt(err, QDC_EFORMAT, &b->s, at_field(b, 6),
                        "CTETRA %lld: the mid-side nodes G5-G10 must be all given (10 "
                        "nodes) or all left out (4 nodes)",
                        (long long)eid);
    n = mids ? 10 : n;
    for (int k = 0; k < n && st == QDC_OK; k++)
        st = field_int(b, 2 + k, what[2], k < 3 || !tri ? 1 : 0, INT32_MAX,
                       k < 3 || !tri ? -1 : 0, &g[k], err);
    if (st == QDC_OK && !tri && lab_mixed(&b->l, n))
        return fail_txt(err, QDC_EFORMAT, &b->s, at_field(b, 0),
                        "CTETRA %lld: 4-node and 10-node CTETRA in one file are not "
                        "supported",
                        (long long)eid);
    if (st != QDC_OK)
        return st;
    return lab_elem(&b->l, tri, g, (int32_t)pid, 0, at - b->s.base, err);
}

/* The card name [t, te) of the line at bol (up to 8 characters or a comma);
 * *large if it ends in '*'. */
static void card_name(const char *bol, const char *eol, const char **te, int *large)
{
    const char *p = bol;

    while (p < eol && p - bol < 8 && *p != ',' && *p != ' ' && *p != '\t' && *p != '\r' &&
           *p != '$')
        p++;
    *large = p > bol && p[-1] == '*';
    *te = *large ? p - 1 : p;
}

/* A continuation line at p: its first field a '+' or '*' marker, a comma
 * (free field), or blank (Gmsh's large-field CTETRA) on a line that is not. */
static int is_cont(const char *p, const char *end)
{
    const char *q = p;

    if (p < end && (*p == '+' || *p == '*' || *p == ','))
        return 1;
    while (q < end && *q == ' ')
        q++;
    return q - p >= 8 && q < end && *q != '\n' && *q != '\r';
}

/* 1 if the lines after eol are blank or '$' comments. */
static int only_comments(const txt *s, const char *eol)
{
    const char *p = eol < s->end ? eol + 1 : s->end;

    while (p < s->end) {
        const char *e = line_end(s, p);
        if (*p != '$' && trim_end(p, e) != p)
            return 0;
        p = e + 1;
    }
    return 1;
}

/* CTETRA, or "CTETRA_", meshio 5.0's name for the 10-node one (its writer
 * puts it in the file). */
static int is_ctetra(const char *name, size_t n)
{
    return word_is(name, n, "CTETRA") || word_is(name, n, "CTETRA_");
}

/* The cards, line by line, into b. */
static qdc_status bdf_cards(bdf *b, qdc_error *err)
{
    txt *s = &b->s;
    const char *p = s->base, *bulk = NULL;
    qdc_status st = QDC_OK;

    /* BEGIN BULK, if any, at the start of a line */
    for (const char *q = p; q < s->end; q = line_end(s, q) + 1) {
        const char *t = q;
        while (t < s->end && *t == ' ')
            t++;
        if (s->end - t >= 10 && strncasecmp(t, "BEGIN", 5) == 0) {
            const char *u = t + 5;
            while (u < s->end && *u == ' ')
                u++;
            if (s->end - u >= 4 && strncasecmp(u, "BULK", 4) == 0) {
                bulk = line_end(s, q);
                break;
            }
        }
        if (line_end(s, q) >= s->end)
            break;
    }
    if (bulk) {
        txt_locate(s, bulk);
        p = bulk < s->end ? bulk + 1 : s->end;
        s->line++;
    }
    while (p < s->end && st == QDC_OK) {
        const char *eol = line_end(s, p), *nte, *card = p;
        int large;

        s->bol = p;
        if (*p == '$' || trim_end(p, eol) == p || is_cont(p, s->end)) {
            /* a comment, a blank line, or a continuation of a card not read */
            p = eol + 1;
            s->line++;
            continue;
        }
        card_name(p, eol, &nte, &large);
        if (word_is(p, (size_t)(nte - p), "ENDDATA")) {
            b->empty_bulk = bulk != NULL && only_comments(s, eol);
            break;
        }
        if (word_is(p, (size_t)(nte - p), "GRID") || is_ctetra(p, (size_t)(nte - p)) ||
            word_is(p, (size_t)(nte - p), "CTRIA3") ||
            word_is(p, (size_t)(nte - p), "CTRIA6")) {
            const char *name = p;
            size_t nn = (size_t)(nte - p);
            b->nf = 0;
            st = line_fields(b, p, eol, large, err);
            while (st == QDC_OK && eol + 1 < s->end && is_cont(eol + 1, s->end)) {
                p = eol + 1;
                s->line++;
                s->bol = p;
                eol = line_end(s, p);
                st = line_fields(b, p, eol, large || *p == '*', err);
            }
            if (st == QDC_OK && word_is(name, nn, "GRID"))
                st = bdf_grid(b, err);
            else if (st == QDC_OK)
                st = bdf_element(b,
                                 is_ctetra(name, nn)           ? 4
                                 : word_is(name, nn, "CTRIA3") ? 3
                                                               : 6,
                                 card, err);
        } else if (b->other++ == 0) {
            b->other_name = p;
            b->other_len = (size_t)(nte - p);
        }
        p = eol + 1;
        s->line++;
    }
    return st;
}

static qdc_status read_bdf(const char *buf, size_t len, const meshio_options *o,
                           srcrec *rec, mesh_t **out, qdc_error *err)
{
    bdf b;
    qdc_status st;

    memset(&b, 0, sizeof b);
    lab_init(&b.l, "GRID", "CTETRA", "CTRIA3");
    b.s = txt_init(buf, len, 0);
    st = bdf_cards(&b, err);
    if (st == QDC_OK && b.l.tags.n == 0 && !b.empty_bulk)
        st = qdc_fail(err, QDC_EPARSE, "not a Nastran bulk data file: no GRID card");
    if (st == QDC_OK)
        st = lab_mesh(&b.l, &b.s, MESHIO_BDF, rec, out, err);
    if (st == QDC_OK && b.blank_field)
        srcrec_refuse(rec, "a GRID card leaves a coordinate field out");
    if (st == QDC_OK && b.other)
        note(o,
             "Nastran: kept %lld cards not read (%.*s...) unchanged: GRID, CTETRA, "
             "CTRIA3 and CTRIA6 are read",
             (long long)b.other, (int)(b.other_len < 16 ? b.other_len : 16),
             b.other_name);
    lab_free(&b.l);
    return st;
}

/* A real as a free field: %.17g, with a decimal point if it has none. */
static void bdf_real(wbuf *w, double x)
{
    char t[40];
    int n = numfmt_g17(x, t), e = n;

    if (memchr(t, '.', (size_t)n)) {
        wb_put(w, t, (size_t)n);
        return;
    }
    for (int k = 0; k < n; k++)
        if (t[k] == 'e')
            e = k;
    wb_put(w, t, (size_t)e);
    wb_str(w, ".");
    wb_put(w, t + e, (size_t)(n - e));
}

/* ",PID" of element t: blank without tags. */
static void bdf_pid(wbuf *w, const int32_t *tag, int32_t t)
{
    wb_str(w, ",");
    if (tag)
        wb_int(w, tag[t]);
}

static qdc_status write_bdf(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                            qdc_error *err)
{
    (void)fmt;
    (void)part;
    (void)err;
    wb_str(w, "$ Nastran bulk data written by qdc\nBEGIN BULK\n");
    for (int32_t i = 0; i < m->nv; i++) {
        wb_str(w, "GRID,");
        wb_int(w, (int64_t)i + 1);
        wb_str(w, ",");
        for (int k = 0; k < 3; k++) {
            wb_str(w, ",");
            bdf_real(w, m->xyz[3 * (size_t)i + (size_t)k]);
        }
        wb_str(w, "\n");
    }
    for (int32_t t = 0; t < m->nt; t++) {
        wb_str(w, "CTETRA,");
        wb_int(w, (int64_t)t + 1);
        bdf_pid(w, m->region, t);
        wb_str(w, ",");
        wb_ints(w, m->tets + 4 * (size_t)t, 4, 1, ",", m->mid ? "," : "\n");
        if (m->mid) { /* G5-G10: edges 12 23 31 14 24 34, mesh_p2_edges' order;
                       * Gmsh reads the second line only after a "+" field */
            wb_ints(w, m->mid + 6 * (size_t)t, 2, 1, ",", ",+\n+,");
            wb_ints(w, m->mid + 6 * (size_t)t + 2, 4, 1, ",", "\n");
        }
    }
    for (int32_t t = 0; t < m->ntri; t++) {
        wb_str(w, "CTRIA3,");
        wb_int(w, (int64_t)m->nt + t + 1);
        bdf_pid(w, m->tri_ref, t);
        wb_str(w, ",");
        wb_ints(w, m->tris + 3 * (size_t)t, 3, 1, ",", "\n");
    }
    wb_str(w, "ENDDATA\n");
    return QDC_OK;
}

/* A '$' comment ("$ ", "$$", "$-": Gmsh's sections are "$Name"), or a first
 * card or statement Nastran files start with. */
static meshio_format sniff_bdf(const char *buf, size_t len, size_t i)
{
    static const char *const first[] = {"BEGIN BULK", "GRID", "CTETRA",  "SOL ",
                                        "ID ",        "CEND", "NASTRAN", "INIT ",
                                        "ASSIGN ",    "TIME "};
    const char *p = buf + i;
    size_t n = len - i;

    if (n >= 2 && p[0] == '$' && !is_alpha((unsigned char)p[1]))
        return MESHIO_BDF;
    for (size_t k = 0; k < sizeof first / sizeof first[0]; k++)
        if (n >= strlen(first[k]) && strncasecmp(p, first[k], strlen(first[k])) == 0)
            return MESHIO_BDF;
    return MESHIO_AUTO;
}

const meshio_fmt fmt_bdf = {
    .name = "bdf",
    .aliases = "nas nastran",
    .about = "Nastran bulk data: GRID, CTETRA (4 or 10 nodes), CTRIA3/6",
    .ext = "bdf",
    .input = "input.bdf",
    .sniff = sniff_bdf,
    .read = read_bdf,
    .write = write_bdf,
    .splices = 1,
    .p2 = 1,
};
