/* meshio_tetgen.c - TetGen .node/.ele: reader of the two buffers and writer
 * of each file (meshio.c loads and saves the pair). */
#include "io/format.h"

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
qdc_status meshio_tetgen_read2(const char *node, size_t node_len, const char *ele,
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
    return meshio_tetgen_read2(node, node_len, ele, ele_len, NULL, out, err);
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

static qdc_status write_tetgen(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                               qdc_error *err)
{
    (void)fmt;
    (void)err;
    if (part == 0)
        write_node(m, w);
    else
        write_ele(m, w);
    return QDC_OK;
}

/* One buffer is not TetGen: it needs its .node and .ele. */
static qdc_status read_one(const char *buf, size_t len, const meshio_options *o,
                           srcrec *rec, mesh_t **out, qdc_error *err)
{
    (void)buf;
    (void)len;
    (void)o;
    (void)rec;
    (void)out;
    return qdc_fail(err, QDC_EINVAL, "TetGen needs two buffers: use meshio_read_tetgen");
}

const meshio_fmt fmt_tetgen = {
    .name = "tetgen",
    .aliases = "node ele",
    .about = "TetGen .node + .ele (attributes as regions; two files)",
    .ext = "node",
    .read = read_one,
    .write = write_tetgen,
    .splices = 1,
};
