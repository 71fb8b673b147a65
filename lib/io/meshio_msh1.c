/* meshio_msh1.c - Gmsh MSH 1 ($NOD/$ENDNOD, $ELM/$ENDELM): read and written.
 *
 * "$NOD", the node count, "number x y z" per node (numbers in any order, not
 * necessarily contiguous), "$ENDNOD"; "$ELM", the element count, "number type
 * physical elementary node-count nodes..." per element, "$ENDELM". Type 4
 * (tetrahedron) is read with its physical tag as region (the elementary tag
 * when no element has a physical one and they differ), type 2 (triangle)
 * with its physical tag as tri_ref; others are skipped with a note, type 11
 * (10-node tetrahedron) refused. Other sections ($PhysicalNames...) are
 * skipped, kept by a spliced write. A .msh file is Gmsh's whichever version
 * it holds: the Gmsh reader hands "$NOD" to this one. Physical tags may be
 * negative (Gmsh reads them with %d); elementary tags are >= 0.
 * Written (a mesh whose tets changed, or another format's): nodes 1..nv with
 * %.17g coordinates, the tets as type 4 (physical tag the region, 0 without
 * one; elementary tag the region's rank among the distinct regions, from 1,
 * so Gmsh makes one volume per region), then the triangles as type 2 (the
 * same with tri_ref), numbered on from the tets. Second-order tets are not
 * written (type 11 is not read): such a mesh is written only spliced. */
#include "io/format.h"

#include <stdlib.h>
#include <string.h>
#include <strings.h>

typedef struct {
    txt s;
    parsed pm;
    vec tags, tets, reg, ent, tris, tref; /* int64 tags; int32 the others */
    tagmap tm;
    skipped sk;
    int nod, elm;
} msh1;

/* The next "$Name" at the start of a line: [*name, +*n) after the '$'. */
static qdc_status msh1_marker(msh1 *g, const char **name, size_t *n, qdc_error *err)
{
    txt *s = &g->s;
    char q[32];

    skip_ws(s);
    if (s->p >= s->end) {
        *n = 0;
        return QDC_OK;
    }
    if (*s->p != '$')
        return fail_txt(err, QDC_EPARSE, s, s->p, "expected a $section, got %s",
                        quote_tok(q, s, s->p, tok_end(s, s->p)));
    *name = s->p + 1;
    s->p = tok_end(s, s->p);
    *n = (size_t)(s->p - *name);
    return QDC_OK;
}

/* Past "$END<name>" (any case): next for a section read (strict), after
 * anything for one skipped. */
static qdc_status msh1_end(msh1 *g, const char *name, size_t n, int strict,
                           qdc_error *err)
{
    txt *s = &g->s;
    char want[40], q[32];
    size_t wn =
        (size_t)snprintf(want, sizeof want, "$END%.*s", (int)(n < 30 ? n : 30), name);
    const char *t;

    for (;;) {
        skip_ws(s);
        if (s->p >= s->end)
            return fail_txt(err, QDC_EPARSE, s, s->p, "%s missing", want);
        t = s->p;
        s->p = tok_end(s, t);
        if ((size_t)(s->p - t) == wn && strncasecmp(t, want, wn) == 0)
            return QDC_OK;
        if (strict)
            return fail_txt(err, QDC_EPARSE, s, t, "expected %s, got %s", want,
                            quote_tok(q, s, t, s->p));
    }
}

static qdc_status msh1_nodes(msh1 *g, srcrec *rec, qdc_error *err)
{
    txt *s = &g->s;
    parsed *pm = &g->pm;
    int64_t tag, dup;
    qdc_status st;

    if (g->nod++)
        return fail_txt(err, QDC_EPARSE, s, s->p, "a second $NOD section");
    st = txt_count(s, "$NOD", 4, MESH_MAX_VERTICES, &pm->nv, err);
    if (st != QDC_OK)
        return st;
    pm->xyz = qdc_mallocn((size_t)pm->nv * 3 + 1, sizeof(double));
    if (!pm->xyz || vec_grow(&g->tags, (size_t)pm->nv + 1) != 0)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld nodes",
                        (long long)pm->nv);
    if (rec) {
        st = srcrec_alloc(rec, pm->nv, err);
        if (st != QDC_OK)
            return st;
        rec->fmt = MESHIO_MSH1;
        rec->kind = SRC_TEXT;
    }
    for (int64_t i = 0; i < pm->nv && st == QDC_OK; i++) {
        st = txt_int(s, "$NOD: node number", 1, INT32_MAX, &tag, err);
        ((int64_t *)g->tags.a)[i] = tag;
        if (st == QDC_OK && rec) {
            skip_ws(s);
            rec->off[i] = (uint64_t)(s->p - s->base);
        }
        for (int k = 0; k < 3 && st == QDC_OK; k++)
            st = txt_real(s, "$NOD: coordinate", &pm->xyz[3 * i + k], err);
        if (st != QDC_OK)
            set_index(err, "vertex", i);
    }
    if (st != QDC_OK)
        return st;
    g->tags.n = (size_t)pm->nv;
    st = tagmap_build(&g->tm, (const int64_t *)g->tags.a, pm->nv, &dup, err);
    if (st == QDC_OK && dup >= 0)
        st = qdc_fail(err, QDC_EPARSE, "$NOD: node %lld appears twice",
                      (long long)((int64_t *)g->tags.a)[dup]);
    return st;
}

/* One element: a tet's or a triangle's nodes as indices, with its tags; the
 * others counted for the note. */
static qdc_status msh1_element(msh1 *g, const meshio_options *o, qdc_error *err)
{
    txt *s = &g->s;
    int64_t num, type, phys, ent, nn, v;
    int32_t idx[4];
    vec *into = NULL, *tags = NULL;
    const char *at;
    char q[32];
    qdc_status st;

    (void)o;
    st = txt_int(s, "$ELM: element number", 1, INT64_MAX, &num, err);
    if (st == QDC_OK)
        st = txt_int(s, "$ELM: element type", 1, 1000, &type, err);
    if (st == QDC_OK)
        st = txt_int(s, "$ELM: physical tag", INT32_MIN, INT32_MAX, &phys, err);
    if (st == QDC_OK)
        st = txt_int(s, "$ELM: elementary tag", 0, INT32_MAX, &ent, err);
    if (st == QDC_OK)
        st = txt_int(s, "$ELM: node count", 1, 1000, &nn, err);
    if (st != QDC_OK)
        return st;
    if (type == 11)
        return fail_txt(err, QDC_EFORMAT, s, s->bol,
                        "second-order tetrahedra (type 11) are not supported: qdc "
                        "optimizes linear tetrahedra (4 nodes)");
    if ((type == 4 && nn != 4) || (type == 2 && nn != 3))
        return fail_txt(err, QDC_EPARSE, s, s->bol,
                        "element %lld of type %lld has %lld nodes", (long long)num,
                        (long long)type, (long long)nn);
    if (type == 4) {
        into = &g->tets;
        tags = &g->reg;
    } else if (type == 2) {
        into = &g->tris;
        tags = &g->tref;
    } else {
        skip_count(&g->sk, type, 1);
    }
    for (int64_t k = 0; k < nn; k++) {
        skip_ws(s);
        at = s->p;
        st = txt_int(s, "$ELM: node", 1, INT32_MAX, &v, err);
        if (st != QDC_OK)
            return st;
        if (!into)
            continue;
        v = tagmap_find(&g->tm, v);
        if (v < 0)
            return fail_txt(err, QDC_EPARSE, s, at, "element %lld: unknown node %s",
                            (long long)num, quote_tok(q, s, at, s->p));
        idx[k] = (int32_t)v;
    }
    if (!into)
        return QDC_OK;
    if ((type == 4 && g->tets.n / 4 >= MESH_MAX_TETS) ||
        vec_grow(into, (size_t)nn) != 0 || vec_grow(tags, 1) != 0 ||
        (type == 4 && vec_grow(&g->ent, 1) != 0))
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the elements");
    memcpy((int32_t *)into->a + into->n, idx, (size_t)nn * sizeof(int32_t));
    into->n += (size_t)nn;
    ((int32_t *)tags->a)[tags->n++] = (int32_t)phys;
    if (type == 4)
        ((int32_t *)g->ent.a)[g->ent.n++] = (int32_t)ent;
    return QDC_OK;
}

static qdc_status msh1_elements(msh1 *g, const meshio_options *o, qdc_error *err)
{
    int64_t c;
    qdc_status st;

    if (!g->nod)
        return fail_txt(err, QDC_EPARSE, &g->s, g->s.p, "$ELM before $NOD");
    if (g->elm++)
        return fail_txt(err, QDC_EPARSE, &g->s, g->s.p, "a second $ELM section");
    st = txt_count(&g->s, "$ELM", 6, INT64_MAX, &c, err);
    for (int64_t i = 0; i < c && st == QDC_OK; i++)
        st = msh1_element(g, o, err);
    return st;
}

static void msh1_free(msh1 *g)
{
    parsed_free(&g->pm);
    vec_free(&g->tags);
    vec_free(&g->tets);
    vec_free(&g->reg);
    vec_free(&g->ent);
    vec_free(&g->tris);
    vec_free(&g->tref);
    tagmap_free(&g->tm);
}

static qdc_status read_msh1(const char *buf, size_t len, const meshio_options *o,
                            srcrec *rec, mesh_t **out, qdc_error *err)
{
    msh1 g;
    const char *name = NULL;
    size_t n = 0;
    qdc_status st;

    memset(&g, 0, sizeof g);
    parsed_init(&g.pm);
    g.tags.size = sizeof(int64_t);
    g.tets.size = g.reg.size = g.ent.size = g.tris.size = g.tref.size = sizeof(int32_t);
    g.s = txt_init(buf, len, 0);
    for (;;) {
        st = msh1_marker(&g, &name, &n, err);
        if (st != QDC_OK || !n)
            break;
        if (word_is(name, n, "NOD"))
            st = msh1_nodes(&g, rec, err);
        else if (word_is(name, n, "ELM"))
            st = msh1_elements(&g, o, err);
        else if (word_is(name, n, "MeshFormat"))
            st = fail_txt(err, QDC_EPARSE, &g.s, name - 1,
                          "$MeshFormat: not MSH 1 (read it as gmsh)");
        if (st == QDC_OK)
            st = msh1_end(&g, name, n, word_is(name, n, "NOD") || word_is(name, n, "ELM"),
                          err);
        if (st != QDC_OK)
            break;
    }
    if (st == QDC_OK && (!g.nod || !g.elm))
        st =
            fail_txt(err, QDC_EPARSE, &g.s, g.s.p, "%s missing", g.nod ? "$ELM" : "$NOD");
    if (st == QDC_OK) {
        g.pm.nt = (int64_t)g.tets.n / 4;
        g.pm.ntri = (int64_t)g.tris.n / 3;
        g.pm.tets = g.tets.a;
        g.pm.tris = g.tris.a;
        g.pm.tri_ref = g.tris.n ? g.tref.a : NULL;
        g.tets.a = g.tris.a = NULL;
        if (!g.tris.n)
            vec_free(&g.tref);
        g.tref.a = NULL;
        pick_regions(g.reg.a, g.ent.a, g.pm.nt, &g.pm.region);
        g.reg.a = g.ent.a = NULL;
        skip_note(o, &g.sk, "MSH 1", "elements");
        st = parsed_mesh_move(&g.pm, out, err);
    }
    msh1_free(&g);
    return st;
}

static int cmp_i32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;

    return (x > y) - (x < y);
}

/* The distinct values of tag[n] (NULL: the single value 0), sorted, in *u
 * (qdc_free), their count in *nu; -1 out of memory. */
static int msh1_distinct(const int32_t *tag, int32_t n, int32_t **u, size_t *nu)
{
    *nu = 0;
    *u = qdc_mallocn((size_t)n + 1, sizeof(int32_t));
    if (!*u)
        return -1;
    if (!tag || !n) {
        (*u)[(*nu)++] = 0;
        return 0;
    }
    memcpy(*u, tag, (size_t)n * sizeof(int32_t));
    qsort(*u, (size_t)n, sizeof(int32_t), cmp_i32);
    for (int32_t i = 0; i < n; i++)
        if (!*nu || (*u)[*nu - 1] != (*u)[i])
            (*u)[(*nu)++] = (*u)[i];
    return 0;
}

/* Elements first..first+n-1 of type (4 or 2, k nodes): "number type
 * physical elementary k nodes...", the elementary tag the rank of the
 * physical one in u[nu]. */
static void msh1_write_elems(wbuf *w, int64_t first, const char *type, const int32_t *v,
                             int k, const int32_t *tag, int32_t n, const int32_t *u,
                             size_t nu)
{
    for (int32_t t = 0; t < n; t++) {
        int32_t x = tag ? tag[t] : 0;
        const int32_t *p = bsearch(&x, u, nu, sizeof(int32_t), cmp_i32);
        wb_int(w, first + t);
        wb_str(w, type);
        wb_int(w, x);
        wb_str(w, " ");
        wb_int(w, p ? p - u + 1 : 1);
        wb_str(w, k == 4 ? " 4 " : " 3 ");
        wb_ints(w, v + (size_t)k * (size_t)t, k, 1, " ", "\n");
    }
}

static qdc_status write_msh1(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                             qdc_error *err)
{
    int32_t *u[2] = {NULL, NULL};
    size_t nu[2];
    qdc_status st = QDC_OK;

    (void)fmt;
    (void)part;
    if (msh1_distinct(m->region, m->nt, &u[0], &nu[0]) != 0 ||
        msh1_distinct(m->tri_ref, m->ntri, &u[1], &nu[1]) != 0) {
        st = qdc_fail(err, QDC_ENOMEM, "out of memory for the Gmsh entities");
        goto out;
    }
    wb_str(w, "$NOD\n");
    wb_int(w, m->nv);
    wb_str(w, "\n");
    for (int32_t i = 0; i < m->nv; i++) {
        wb_int(w, (int64_t)i + 1);
        wb_str(w, " ");
        wb_reals(w, m->xyz + 3 * (size_t)i, 3, " ", "\n");
    }
    wb_str(w, "$ENDNOD\n$ELM\n");
    wb_int(w, (int64_t)m->nt + m->ntri);
    wb_str(w, "\n");
    msh1_write_elems(w, 1, " 4 ", m->tets, 4, m->region, m->nt, u[0], nu[0]);
    msh1_write_elems(w, (int64_t)m->nt + 1, " 2 ", m->tris, 3, m->tri_ref, m->ntri, u[1],
                     nu[1]);
    wb_str(w, "$ENDELM\n");
out:
    qdc_free(u[0]);
    qdc_free(u[1]);
    return st;
}

/* "$NOD" first. */
static meshio_format sniff_msh1(const char *buf, size_t len, size_t i)
{
    return len - i >= 4 && memcmp(buf + i, "$NOD", 4) == 0 ? MESHIO_MSH1 : MESHIO_AUTO;
}

const meshio_fmt fmt_msh1 = {
    .name = "msh1",
    .aliases = "gmsh1",
    .about = "Gmsh MSH 1 ($NOD, $ELM)",
    .ext = "msh",
    .input = "input.msh",
    .family = MESHIO_GMSH41,
    .sniff = sniff_msh1,
    .read = read_msh1,
    .write = write_msh1,
    .splices = 1,
};
