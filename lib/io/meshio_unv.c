/* meshio_unv.c - I-DEAS universal files (.unv): read and written.
 *
 * A file is a series of datasets, each between two lines "    -1", its number
 * on the first line after the opening one. Read: 2411 (nodes: label, export
 * and displacement coordinate systems, color; then X, Y, Z as D25.16, "D"
 * exponents; the export system is taken as the global Cartesian one, label 1
 * as Gmsh and Salome write it) and 2412 (elements: label, FE descriptor,
 * physical and material property tables, color, node count; beams (FE 11,
 * 21-24) have a record of orientation and end nodes; then the nodes, 8 a
 * line). FE descriptors 111 (linear tetrahedron) and 118 (parabolic: its
 * nodes go around, corner 1, mid-edge 1-2, corner 2, 2-3, corner 3, 3-1,
 * then 1-4, 2-4, 3-4 and corner 4; second order, mesh_t.mid) are read with
 * their material property as region (the physical property when no
 * material is set and they differ), linear and parabolic triangles (41, 51,
 * 61, 74, 81, 91; 42, 52, 62, 72, 82, 92: their corners) likewise as
 * triangles; others skipped with a note.
 * Every other dataset (2467/2477 groups, units 164, coordinate systems
 * 2420...) is kept; a spliced write rewrites only the 25-column coordinate
 * fields, in the same form (splice.c, SRC_FIELD with FIELD_EXP).
 * Integers are read as blank-separated tokens (as Gmsh reads them), the
 * property numbers may be negative.
 * Written (a mesh whose tets changed, or another format's), as Gmsh writes
 * the format: 2411 with labels 1..nv (systems 1 1, color 11) and the
 * coordinates as 3D25.16 (17 significant digits: they read back bit for
 * bit); 2412 with the tets as FE 111 (118 for second-order tets, its nodes
 * in the order above), physical and material property both the region (0
 * without), color 7, then the triangles as FE 91 (thin shell linear
 * triangle) with both properties their ref, labels numbered on from the
 * tets. Integers are I10; one that fills its 10 columns (beyond 999999999
 * or below -99999999) is written after a blank, wider, so that token
 * readers (qdc, Gmsh) still read it. */
#include "io/format.h"

#include <stdio.h>
#include <string.h>

typedef struct {
    txt s;
    labelled l;
    skipped sk;
} unv;

/* The token at the scanner (after blanks): [*t, *te). */
static void unv_token(txt *s, const char **t, const char **te)
{
    skip_ws(s);
    *t = s->p;
    *te = tok_end(s, s->p);
}

/* A line "-1" next (a dataset's end): consumed, 1. */
static int unv_delim(txt *s)
{
    const char *t, *te;

    unv_token(s, &t, &te);
    if (te - t == 2 && t[0] == '-' && t[1] == '1') {
        s->p = te;
        return 1;
    }
    return 0;
}

/* Past the rest of the dataset: lines up to one that is "-1" alone. */
static qdc_status unv_skip(txt *s, int64_t num, qdc_error *err)
{
    const char *p = s->p;

    while (p < s->end) {
        const char *e = memchr(p, '\n', (size_t)(s->end - p)), *t = p, *te;
        e = e ? e : s->end;
        te = e;
        while (t < te && *t == ' ')
            t++;
        while (te > t && (te[-1] == ' ' || te[-1] == '\r'))
            te--;
        if (te - t == 2 && t[0] == '-' && t[1] == '1' && p != s->p) {
            s->p = te;
            return QDC_OK;
        }
        if (e < s->end) {
            s->line++;
            s->bol = e + 1;
        }
        p = e + 1;
    }
    return fail_txt(err, QDC_EPARSE, s, s->end, "dataset %lld: no closing -1",
                    (long long)num);
}

static int blanks(const char *p, const char *e)
{
    for (; p < e; p++)
        if (*p != ' ')
            return 0;
    return 1;
}

static qdc_status unv_nodes(unv *u, qdc_error *err)
{
    txt *s = &u->s;
    int64_t label, sys;
    qdc_status st = QDC_OK;

    while (st == QDC_OK && !unv_delim(s)) {
        double x[3];
        uint64_t off[3];
        st = txt_int(s, "2411: node label", 1, INT32_MAX, &label, err);
        for (int k = 0; k < 3 && st == QDC_OK; k++) /* systems, color */
            st = txt_int(s, "2411: node record", 0, INT32_MAX, &sys, err);
        for (int k = 0; k < 3 && st == QDC_OK; k++) {
            const char *t, *te;
            char q[32];
            size_t col;
            unv_token(s, &t, &te);
            col = (size_t)(te - s->bol);
            if (t == te || parse_fortran_real(t, te, &x[k]) != 0)
                return fail_txt(err, QDC_EPARSE, s, t,
                                "2411: node %lld: expected a coordinate, got %s",
                                (long long)label, quote_tok(q, s, t, te));
            if (!isfinite(x[k]))
                return fail_txt(err, QDC_EPARSE, s, t,
                                "2411: node %lld: coordinate %s is not finite (NaN/Inf)",
                                (long long)label, quote_tok(q, s, t, te));
            if (col == 25 * (size_t)(k + 1) && (size_t)(t - s->bol) >= 25 * (size_t)k &&
                blanks(s->bol + 25 * k, t)) /* its own 25 columns */
                off[k] = FIELD(s->bol + 25 * k - s->base, 25, FIELD_EXP);
            else
                off[k] = FIELD(t - s->base, te - t > 25 ? (int)(te - t) : 25,
                               FIELD_EXP | FIELD_FREE);
            s->p = te;
        }
        if (st == QDC_OK)
            st = lab_node(&u->l, label, x, off, err);
    }
    return st;
}

/* The nodes of a triangle of FE descriptor fe (linear 3, parabolic 6), or 0. */
static int tri_nodes(int64_t fe)
{
    if (fe == 41 || fe == 51 || fe == 61 || fe == 74 || fe == 81 || fe == 91)
        return 3;
    if (fe == 42 || fe == 52 || fe == 62 || fe == 72 || fe == 82 || fe == 92)
        return 6;
    return 0;
}

/* Where an element's k-th node goes in g: a parabolic tet's (FE 118, see
 * above) corners to 0-3, its mid-edge nodes to 4-9 (mesh_p2_edges); a
 * parabolic triangle's corners to 0-2 (the others to 3-5, not used). */
static int node_slot(int nodes, int tri, int64_t k)
{
    static const int tet10[10] = {0, 4, 1, 5, 2, 6, 7, 8, 9, 3},
                     tri6[6] = {0, 3, 1, 4, 2, 5};

    return tri && nodes == 6 ? tri6[k] : !tri && nodes == 10 ? tet10[k] : (int)k;
}

static qdc_status unv_elements(unv *u, qdc_error *err)
{
    txt *s = &u->s;
    qdc_status st = QDC_OK;

    while (st == QDC_OK && !unv_delim(s)) {
        int64_t r[6], g[10], v;
        const char *at;
        int tet = 0, tri = 0, nodes;
        static const char *const what[6] = {
            "2412: element label",     "2412: FE descriptor", "2412: physical property",
            "2412: material property", "2412: color",         "2412: node count"};
        skip_ws(s);
        at = s->p;
        for (int k = 0; k < 6 && st == QDC_OK; k++)
            st = txt_int(s, what[k],
                         k == 5 || k == 0   ? 1
                         : k == 2 || k == 3 ? INT32_MIN
                                            : 0,
                         k == 5 ? 1000 : INT32_MAX, &r[k], err);
        if (st != QDC_OK)
            break;
        tet = r[1] == 111 || r[1] == 118;
        tri = tri_nodes(r[1]) > 0;
        nodes = tri ? tri_nodes(r[1]) : r[1] == 118 ? 10 : 4;
        if ((tet || tri) && r[5] != nodes)
            return fail_txt(err, QDC_EPARSE, s, at,
                            "2412: element %lld (FE descriptor %lld) has %lld nodes",
                            (long long)r[0], (long long)r[1], (long long)r[5]);
        if (tet && lab_mixed(&u->l, nodes))
            return fail_txt(
                err, QDC_EFORMAT, s, at,
                "2412: element %lld: linear (FE descriptor 111) and parabolic "
                "(118) tetrahedra in one file are not supported",
                (long long)r[0]);
        if (r[1] == 11 || (r[1] >= 21 && r[1] <= 24)) /* beam record */
            for (int k = 0; k < 3 && st == QDC_OK; k++)
                st = txt_int(s, "2412: beam record", 0, INT32_MAX, &v, err);
        for (int64_t k = 0; k < r[5] && st == QDC_OK; k++) {
            st = txt_int(s, "2412: node label", 1, INT32_MAX, &v, err);
            if (tet || tri)
                g[node_slot(nodes, tri, k)] = v;
        }
        if (st != QDC_OK)
            break;
        if (!tet && !tri) {
            skip_count(&u->sk, r[1], 1);
            continue;
        }
        st = lab_elem(&u->l, tri, g, (int32_t)r[3], (int32_t)r[2], at - s->base, err);
    }
    return st;
}

static qdc_status read_unv(const char *buf, size_t len, const meshio_options *o,
                           srcrec *rec, mesh_t **out, qdc_error *err)
{
    unv u;
    int64_t num;
    int nodes = 0;
    qdc_status st = QDC_OK;

    memset(&u, 0, sizeof u);
    lab_init(&u.l, "node", "2412", "2412");
    u.s = txt_init(buf, len, 0);
    for (;;) {
        const char *t, *te;
        char q[32];
        unv_token(&u.s, &t, &te);
        if (t >= u.s.end)
            break;
        if (!unv_delim(&u.s)) {
            st = fail_txt(err, QDC_EPARSE, &u.s, t, "expected -1 (a dataset), got %s",
                          quote_tok(q, &u.s, t, te));
            break;
        }
        unv_token(&u.s, &t, &te);
        if (parse_int(t, te, 0, &num) != 0 || num < 1) {
            st = fail_txt(err, QDC_EPARSE, &u.s, t, "expected a dataset number, got %s",
                          quote_tok(q, &u.s, t, te));
            break;
        }
        u.s.p = te;
        if (num == 2411)
            st = unv_nodes(&u, err);
        else if (num == 2412)
            st = unv_elements(&u, err);
        else
            st = unv_skip(&u.s, num, err);
        nodes += num == 2411;
        if (st != QDC_OK)
            break;
    }
    if (st == QDC_OK && !nodes)
        st = qdc_fail(err, QDC_EPARSE, "not an I-DEAS mesh: no dataset 2411 (nodes)");
    if (st == QDC_OK)
        st = lab_mesh(&u.l, &u.s, MESHIO_UNV, rec, out, err);
    if (st == QDC_OK)
        skip_note(o, &u.sk, "UNV", "elements with FE descriptor");
    lab_free(&u.l);
    return st;
}

/* v as I10: right-aligned in 10 columns, or after a blank if it fills them. */
static void unv_i10(wbuf *w, int64_t v)
{
    static const char pad[] = "          ";
    int n = 1;

    for (int64_t a = v < 0 ? -v : v; a >= 10; a /= 10)
        n++;
    n += v < 0;
    wb_put(w, pad, n < 10 ? (size_t)(10 - n) : 1);
    wb_int(w, v);
}

/* Record 1 of a 2412 element and its nodes, 8 a line. */
static void unv_element(wbuf *w, int64_t label, int fe, int32_t tag, const int32_t *g,
                        int n)
{
    const int64_t r[6] = {label, fe, tag, tag, 7, n};

    for (int k = 0; k < 6; k++)
        unv_i10(w, r[k]);
    for (int k = 0; k < n; k++) {
        wb_str(w, k % 8 == 0 ? "\n" : "");
        unv_i10(w, (int64_t)g[k] + 1);
    }
    wb_str(w, "\n");
}

static void unv_coords(wbuf *w, const double *x)
{
    char t[3 * 40];
    int n = 0;

    for (int k = 0; k < 3; k++)
        n += snprintf(t + n, sizeof t - (size_t)n, "%25.16E", x[k]);
    for (int k = 0; k < n; k++)
        t[k] = t[k] == 'E' ? 'D' : t[k];
    wb_put(w, t, (size_t)n);
    wb_str(w, "\n");
}

static qdc_status write_unv(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                            qdc_error *err)
{
    static const int tet10[10] = {0, 4, 1, 5, 2, 6, 7, 8, 9, 3}; /* node_slot's */
    int32_t g[10];

    (void)fmt;
    (void)part;
    (void)err;
    wb_str(w, "    -1\n  2411\n");
    for (int32_t i = 0; i < m->nv; i++) {
        unv_i10(w, (int64_t)i + 1);
        wb_str(w, "         1         1        11\n");
        unv_coords(w, m->xyz + 3 * (size_t)i);
    }
    wb_str(w, "    -1\n    -1\n  2412\n");
    for (int32_t t = 0; t < m->nt; t++) {
        int32_t all[10];
        memcpy(all, m->tets + 4 * (size_t)t, 4 * sizeof(int32_t));
        if (m->mid) /* corner, mid-edge, corner... (node_slot's inverse) */
            memcpy(all + 4, m->mid + 6 * (size_t)t, 6 * sizeof(int32_t));
        for (int k = 0; k < (m->mid ? 10 : 4); k++)
            g[k] = m->mid ? all[tet10[k]] : all[k];
        unv_element(w, (int64_t)t + 1, m->mid ? 118 : 111, m->region ? m->region[t] : 0,
                    g, m->mid ? 10 : 4);
    }
    for (int32_t t = 0; t < m->ntri; t++)
        unv_element(w, (int64_t)m->nt + t + 1, 91, m->tri_ref ? m->tri_ref[t] : 0,
                    m->tris + 3 * (size_t)t, 3);
    wb_str(w, "    -1\n");
    return QDC_OK;
}

/* "-1" alone on the first line, then a dataset number. */
static meshio_format sniff_unv(const char *buf, size_t len, size_t i)
{
    size_t k = i + 2;

    if (len - i < 4 || buf[i] != '-' || buf[i + 1] != '1' ||
        (buf[k] != '\n' && buf[k] != '\r' && buf[k] != ' '))
        return MESHIO_AUTO;
    while (k < len && is_space((unsigned char)buf[k]))
        k++;
    return k < len && buf[k] >= '1' && buf[k] <= '9' ? MESHIO_UNV : MESHIO_AUTO;
}

const meshio_fmt fmt_unv = {
    .name = "unv",
    .aliases = "ideas",
    .about = "I-DEAS universal: datasets 2411, 2412, tets FE 111 and 118",
    .ext = "unv",
    .input = "input.unv",
    .sniff = sniff_unv,
    .read = read_unv,
    .write = write_unv,
    .splices = 1,
    .p2 = 1,
};
