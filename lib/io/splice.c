/* splice.c - writing a mesh back as the file it was read from, with only
 * the coordinates replaced (meshio.h, "Spliced writing").
 *
 * The source keeps the decompressed input and what its reader recorded
 * (meshio_scan.h, srcrec): one uint64 offset per vertex for text and binary
 * coordinates, or, for VTU Points under base64 or zlib, the byte range of the
 * encoded block. Writing streams the input through the writer's buffer and
 * replaces the coordinate fields on the way; the source itself is never
 * written to, and every offset is checked against its length before use, so
 * a damaged record gives QDC_EINTERNAL, never an access outside the buffer.
 * A hash of everything the optimizer must not change (connectivity, regions,
 * triangles and refs) taken at reading is checked again at writing. */
#include "io/meshio.h"
#include "io/meshio_scan.h"

#include <limits.h>
#include <zlib.h>

typedef struct {
    mesh_source base; /* first: released through it */
    srcrec r;
    char *buf;
    size_t len;
    char *ele; /* TetGen .ele, copied unchanged */
    size_t ele_len;
    int32_t nv;
    uint64_t hash;     /* mesh_hash at reading */
    uint64_t xyz_hash; /* of the coordinates as read: unchanged, the file is copied */
    char *path;        /* the file buf was read from (NULL: a buffer) */
    uint64_t buf_hash; /* of buf, while it is parked (buf NULL) */
} source;

static void source_release(mesh_source *ms)
{
    source *s = (source *)ms;

    srcrec_free(&s->r);
    qdc_free(s->buf);
    qdc_free(s->ele);
    qdc_free(s->path);
    qdc_free(s);
}

static uint64_t mix(uint64_t h, uint64_t x)
{
    h ^= x;
    h *= UINT64_C(0x9e3779b97f4a7c15);
    return h ^ (h >> 29);
}

static uint64_t hash_bytes(uint64_t h, const void *p, size_t n)
{
    const unsigned char *b = p;
    uint64_t x;

    h = mix(h, p ? n : UINT64_MAX); /* present or not */
    for (; b && n >= 8; b += 8, n -= 8) {
        memcpy(&x, b, 8);
        h = mix(h, x);
    }
    if (b && n) {
        x = 0;
        memcpy(&x, b, n);
        h = mix(h, x);
    }
    return h;
}

/* Everything a spliced write takes from the file instead of the mesh. */
static uint64_t mesh_hash(const mesh_t *m)
{
    uint64_t h = mix(0, (uint64_t)(uint32_t)m->nv << 32 | (uint32_t)m->nt);

    h = mix(h, (uint64_t)(uint32_t)m->ntri);
    h = hash_bytes(h, m->tets, 16 * (size_t)m->nt);
    h = hash_bytes(h, m->region, 4 * (size_t)m->nt);
    h = hash_bytes(h, m->vref, 4 * (size_t)m->nv);
    h = hash_bytes(h, m->tris, 12 * (size_t)m->ntri);
    h = hash_bytes(h, m->tri_ref, 4 * (size_t)m->ntri);
    if (m->mid)
        h = hash_bytes(h, m->mid, 24 * (size_t)m->nt);
    return h;
}

qdc_status splice_attach(mesh_t *m, srcrec *r, char *buf, size_t len, int own,
                         const char *ele, size_t ele_len, qdc_error *err)
{
    source *s = qdc_calloc(1, sizeof *s);

    if (!s || (!own && !(s->buf = qdc_malloc(len + 1))) ||
        (ele && !(s->ele = qdc_malloc(ele_len + 1)))) {
        if (s) {
            qdc_free(own ? NULL : s->buf);
            qdc_free(s);
        }
        srcrec_free(r);
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the source file");
    }
    if (own) {
        s->buf = buf;
    } else {
        memcpy(s->buf, buf, len);
        s->buf[len] = '\0';
    }
    if (ele) {
        memcpy(s->ele, ele, ele_len);
        s->ele_len = ele_len;
    }
    s->len = len;
    s->base.release = source_release;
    s->r = *r;
    srcrec_init(r);
    s->nv = m->nv;
    s->hash = mesh_hash(m);
    s->xyz_hash = hash_bytes(0, m->xyz, 24 * (size_t)m->nv);
    if (s->r.kind != SRC_BLOCK && s->r.kind != SRC_NONE &&
        (s->r.nv != m->nv || !s->r.off))
        srcrec_refuse(&s->r, "the reader did not record every vertex");
    if (m->source)
        m->source->release(m->source);
    m->source = &s->base;
    return QDC_OK;
}

meshio_format meshio_source_format(const mesh_t *m)
{
    return m && m->source ? ((const source *)m->source)->r.fmt : MESHIO_AUTO;
}

size_t meshio_source_bytes(const mesh_t *m, int *float32)
{
    const source *s = m ? (const source *)m->source : NULL;

    if (float32)
        *float32 =
            s &&
            (s->r.kind == SRC_BIN || s->r.kind == SRC_BLOCK || s->r.kind == SRC_TEXT) &&
            s->r.width == 4;
    if (!s)
        return 0;
    return sizeof *s + (s->buf ? s->len : 0) + s->ele_len +
           (s->r.off ? (s->r.kind == SRC_TEXT3 || s->r.kind == SRC_FIELD ? 24 : 8) *
                           (size_t)s->r.nv
                     : 0) +
           s->r.appoff.n * sizeof(uint64_t);
}

void meshio_drop_source(mesh_t *m)
{
    if (m && m->source) {
        m->source->release(m->source);
        m->source = NULL;
    }
}

int splice_ok(const mesh_t *m, meshio_format fmt, const char **why)
{
    const source *s = m ? (const source *)m->source : NULL;
    const char *w = NULL;

    if (!s)
        w = "no source file kept";
    else if (!s->buf)
        w = "the input file is not in memory (meshio_unpark_source)";
    else if (fmt != s->r.fmt)
        w = "another format, version or encoding than the input's";
    else if (s->r.kind == SRC_NONE)
        w = s->r.why ? s->r.why : "the input's layout is not kept";
    else if (m->nv != s->nv || mesh_hash(m) != s->hash)
        w = "the connectivity, regions or tags changed since reading";
    if (why)
        *why = w;
    return w == NULL;
}

int meshio_splices(const mesh_t *m, meshio_format fmt, const char **why)
{
    return splice_ok(m, fmt, why);
}

qdc_status splice_set_path(mesh_t *m, const char *path, qdc_error *err)
{
    source *s = m ? (source *)m->source : NULL;
    size_t n = path ? strlen(path) : 0;

    if (!s || !path)
        return QDC_OK;
    qdc_free(s->path);
    s->path = qdc_malloc(n + 1);
    if (!s->path)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the source's path");
    memcpy(s->path, path, n + 1);
    return QDC_OK;
}

int meshio_park_source(mesh_t *m)
{
    source *s = m ? (source *)m->source : NULL;

    if (!s || !s->path || !s->buf || s->ele)
        return 0;
    s->buf_hash = hash_bytes(0, s->buf, s->len);
    qdc_free(s->buf);
    s->buf = NULL;
    return 1;
}

qdc_status meshio_unpark_source(mesh_t *m, qdc_error *err)
{
    source *s = m ? (source *)m->source : NULL;
    char *buf = NULL;
    size_t len = 0;
    qdc_status st;

    if (!s || s->buf)
        return QDC_OK;
    st = meshio_slurp_plain(s->path, &buf, &len, err);
    if (st != QDC_OK)
        return st;
    if (len != s->len || hash_bytes(0, buf, len) != s->buf_hash) {
        qdc_free(buf);
        return qdc_fail(err, QDC_EIO, "%s: changed since it was read", s->path);
    }
    s->buf = buf;
    return QDC_OK;
}

/* ---- values derived from the coordinates ---- */

static int cmp_key(const void *a, const void *b)
{
    const int64_t *x = a, *y = b;

    return (x[0] > y[0]) - (x[0] < y[0]);
}

static int64_t ent_key(int64_t dim, int64_t tag)
{
    return dim * (INT64_C(1) << 34) + tag + (INT64_C(1) << 32);
}

/* Entity index of (dim, tag) in the sorted (key, index) pairs; -1 if none. */
static int64_t find_ent(const int64_t *keys, size_t n, int64_t dim, int64_t tag)
{
    int64_t k[2] = {ent_key(dim, tag < 0 ? -tag : tag), 0};
    const int64_t *p = bsearch(k, keys, n, 2 * sizeof(int64_t), cmp_key);

    return p ? p[1] : -1;
}

/* Bounding entities and node blocks to entity indices; 0, or -1 if a tag
 * names no entity or a block lies outside the vertices. */
static int dv_resolve(derived *d, int64_t nv, int64_t *keys)
{
    dv_ent *e = d->ent.a;
    int64_t *bnd = d->bnd.a, *blk = d->blk.a;

    for (size_t i = 0; i < d->ent.n; i++) {
        keys[2 * i] = ent_key(e[i].dim, e[i].tag < 0 ? -e[i].tag : e[i].tag);
        keys[2 * i + 1] = (int64_t)i;
    }
    qsort(keys, d->ent.n, 2 * sizeof(int64_t), cmp_key);
    for (size_t i = 0; i < d->ent.n; i++) {
        for (int64_t j = e[i].bnd; j < e[i].bnd + e[i].nbnd; j++) {
            if (e[i].dim < 1 || j < 0 || (size_t)j >= d->bnd.n)
                return -1;
            bnd[j] = find_ent(keys, d->ent.n, e[i].dim - 1, bnd[j]);
            if (bnd[j] < 0)
                return -1;
        }
    }
    for (size_t i = 0; i + 4 <= d->blk.n; i += 4) {
        blk[i + 1] = find_ent(keys, d->ent.n, blk[i], blk[i + 1]);
        if (blk[i + 1] < 0 || blk[i + 2] < 0 || blk[i + 3] < 0 || blk[i + 2] > nv ||
            blk[i + 3] > nv - blk[i + 2])
            return -1;
    }
    return 0;
}

static void box_add(double *b, const double *p)
{
    for (int a = 0; a < 3; a++) {
        b[a] = p[a] < b[a] ? p[a] : b[a];
        b[3 + a] = p[a] > b[3 + a] ? p[a] : b[3 + a];
    }
}

/* The derived values at coordinates xyz into out[] (NaN: none, keep the
 * file's); box: 6 doubles per entity, scratch. */
static void dv_compute(const derived *d, const double *xyz, int64_t nv, double *out,
                       double *box)
{
    const dv_ent *e = d->ent.a;
    const int64_t *bnd = d->bnd.a, *blk = d->blk.a;

    for (size_t i = 0; i < d->off.n; i++)
        out[i] = NAN;
    if (d->kind == DV_NORMS) {
        double lo = INFINITY, hi = -INFINITY;
        for (int64_t v = 0; v < nv; v++) {
            const double *p = xyz + 3 * v;
            double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            lo = r < lo ? r : lo;
            hi = r > hi ? r : hi;
        }
        if (nv && d->imin >= 0)
            out[d->imin] = lo;
        if (nv && d->imax >= 0)
            out[d->imax] = hi;
        return;
    }
    for (size_t i = 0; i < d->ent.n; i++)
        for (int a = 0; a < 3; a++) {
            box[6 * i + (size_t)a] = INFINITY;
            box[6 * i + 3 + (size_t)a] = -INFINITY;
        }
    for (size_t i = 0; i + 4 <= d->blk.n; i += 4)
        for (int64_t v = blk[i + 2]; v < blk[i + 2] + blk[i + 3]; v++)
            box_add(box + 6 * blk[i + 1], xyz + 3 * v);
    for (int dim = 1; dim <= 3; dim++) /* closures: a volume holds its surfaces... */
        for (size_t i = 0; i < d->ent.n; i++)
            for (int64_t j = 0; e[i].dim == dim && j < e[i].nbnd; j++) {
                const double *b = box + 6 * bnd[e[i].bnd + j];
                if (b[0] <= b[3]) {
                    box_add(box + 6 * i, b);
                    box_add(box + 6 * i, b + 3);
                }
            }
    for (size_t i = 0; i < d->ent.n; i++) {
        const double *b = box + 6 * i;
        for (int32_t k = 0; b[0] <= b[3] && k < e[i].nval; k++)
            out[e[i].val + k] = b[k];
    }
}

qdc_status dv_finish(derived *d, const double *xyz, int64_t nv, qdc_error *err)
{
    const uint64_t *off = d->off.a;
    const dv_ent *e = d->ent.a;
    int64_t *keys;
    double *box;
    int ok = d->kind != DV_NONE && d->off.n == d->file.n && d->off.n > 0;

    for (size_t i = 1; ok && i < d->off.n; i++)
        ok = off[i] > off[i - 1];
    for (size_t i = 0; ok && d->kind == DV_BOXES && i < d->ent.n; i++)
        ok = e[i].val >= 0 && e[i].nval >= 0 && e[i].nval <= 6 &&
             (size_t)e[i].val + (size_t)e[i].nval <= d->off.n;
    if (!ok) {
        dv_free(d);
        return QDC_OK;
    }
    keys = qdc_mallocn(2 * d->ent.n + 2, sizeof(int64_t));
    box = qdc_mallocn(6 * d->ent.n + 6, sizeof(double));
    if (!keys || !box || vec_grow(&d->ref, d->off.n) != 0) {
        qdc_free(keys);
        qdc_free(box);
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the derived values");
    }
    if (d->kind == DV_BOXES && dv_resolve(d, nv, keys) != 0) {
        dv_free(d);
    } else {
        dv_compute(d, xyz, nv, d->ref.a, box);
        d->ref.n = d->off.n;
    }
    qdc_free(keys);
    qdc_free(box);
    return QDC_OK;
}

/* What a spliced write puts in place of the derived values: vals[i] NaN
 * keeps value i as in the file. */
typedef struct {
    const source *s;
    double *vals;
    size_t i, n;
} edits;

static qdc_status edits_init(edits *ed, const source *s, const double *xyz,
                             qdc_error *err)
{
    const derived *d = &s->r.dv;
    double *box = NULL;

    memset(ed, 0, sizeof *ed);
    ed->s = s;
    if (d->kind == DV_NONE || d->ref.n != d->off.n)
        return QDC_OK;
    ed->vals = qdc_mallocn(d->off.n + 1, sizeof(double));
    box = qdc_mallocn(6 * d->ent.n + 6, sizeof(double));
    if (!ed->vals || !box) {
        qdc_free(box);
        qdc_free(ed->vals);
        ed->vals = NULL;
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the derived values");
    }
    dv_compute(d, xyz, s->nv, ed->vals, box);
    qdc_free(box);
    for (size_t i = 0; i < d->off.n; i++) {
        double now = ed->vals[i], ref = ((const double *)d->ref.a)[i];
        double file = ((const double *)d->file.a)[i];
        if (isnan(now) || isnan(ref) || now == ref)
            ed->vals[i] = NAN;
        else if (d->kind == DV_BOXES) /* shifted as far as the nodes' bound moved */
            ed->vals[i] = file + (now - ref);
    }
    ed->n = d->off.n;
    return QDC_OK;
}

/* The source's bytes [from, to) with the derived values in that range replaced. */
static qdc_status put_src(edits *ed, wbuf *w, size_t from, size_t to, qdc_error *err)
{
    const source *s = ed->s;
    const uint64_t *off = s->r.dv.off.a;

    for (; ed->i < ed->n && off[ed->i] < to; ed->i++) {
        size_t p = (size_t)off[ed->i], te = p;
        double x = ed->vals[ed->i];
        if (s->r.dv.bin) {
            te = p + 8;
        } else {
            while (te < s->len && !is_space((unsigned char)s->buf[te]) &&
                   s->buf[te] != '"' && s->buf[te] != '\'' && s->buf[te] != '<')
                te++;
        }
        if (p < from || te > to || te == p)
            return qdc_fail(err, QDC_EINTERNAL, "source: derived value at byte %zu", p);
        wb_put(w, s->buf + from, p - from);
        if (isnan(x)) {
            wb_put(w, s->buf + p, te - p);
        } else if (s->r.dv.bin) {
            unsigned char b[8];
            uint64_t u;
            memcpy(&u, &x, 8);
            put_le64(b, u);
            wb_put(w, b, 8);
        } else {
            wb_real(w, x);
        }
        from = te;
    }
    wb_put(w, s->buf + from, to - from);
    return QDC_OK;
}

/* ---- text ---- */

static size_t skip_sep(const source *s, size_t p)
{
    while (p < s->len) {
        unsigned char c = (unsigned char)s->buf[p];
        if (is_space(c)) {
            p++;
        } else if (c == '#' && s->r.hash) {
            while (p < s->len && s->buf[p] != '\n')
                p++;
        } else {
            break;
        }
    }
    return p;
}

static size_t token_end(const source *s, size_t p)
{
    while (p < s->len) {
        unsigned char c = (unsigned char)s->buf[p];
        if (is_space(c) || (c == '#' && s->r.hash) || (c == '<' && s->r.lt))
            break;
        p++;
    }
    return p;
}

/* The text of x in place of the token [t, te) into out (36 bytes): its
 * length, or 0 if the token itself reads as x (and is kept). In a field
 * declared float32 (f32: VTK's `float`, VTU's Float32, written as text) x is
 * rounded to float32 and written with the 9 digits that read back as it, so
 * that every reader sees the value qdc wrote, as in a binary float32 field. */
static int number_text(const char *t, const char *te, double x, int f32, char *out)
{
    double old;
    float f = (float)x;

    if (f32 && isfinite(f)) {
        if (parse_double(t, te, &old) == 0 && (float)old == f)
            return 0;
        return snprintf(out, 36, "%.9g", (double)f);
    }
    if (parse_double(t, te, &old) == 0 && memcmp(&old, &x, sizeof x) == 0)
        return 0;
    return numfmt_g17(x, out);
}

/* x in place of the token [t, te): the token itself if it reads as x. */
static void put_number(wbuf *w, const char *t, const char *te, double x)
{
    char buf[36];
    int n = number_text(t, te, x, 0, buf);

    if (n > 0)
        wb_put(w, buf, (size_t)n);
    else
        wb_put(w, t, (size_t)(te - t));
}

/* The text of one coordinate for splice_text: its token [t, te) in the
 * source, and n bytes of new text in txt (n = 0: the token reads as the
 * value and is copied; te == t: no token there). */
typedef struct {
    size_t t, te;
    int n;
    char txt[36];
} coord_text;

/* Vertices formatted at once (in parallel) before they are written in order:
 * formatting the coordinates was most of the write of an optimized mesh (5M
 * tets: 1.9 s of 2.1). */
#define SPLICE_BLOCK 8192

/* The tokens of vertex v's coordinates and their new text, into c[0..3). */
static void coord_texts(const source *s, const double *xyz, int32_t v, coord_text *c)
{
    size_t p = s->r.off[v];

    for (int a = 0; a < 3; a++) {
        c[a].t = c[a].te = p;
        c[a].n = 0;
        if (p >= s->len)
            continue;
        if (a)
            p = skip_sep(s, p);
        c[a].t = p;
        c[a].te = p = token_end(s, p);
        if (c[a].te == c[a].t)
            return;
        c[a].n = number_text(s->buf + c[a].t, s->buf + c[a].te,
                             xyz[3 * (size_t)v + (size_t)a], s->r.width == 4, c[a].txt);
    }
}

static qdc_status splice_text(const source *s, const double *xyz, edits *ed, wbuf *w,
                              qdc_error *err)
{
    size_t pos = 0;
    qdc_status st = QDC_OK;
    coord_text *ct = qdc_mallocn(3 * (size_t)SPLICE_BLOCK, sizeof *ct);

    if (!ct)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    for (int32_t v0 = 0; v0 < s->nv && st == QDC_OK; v0 += SPLICE_BLOCK) {
        int32_t v1 = s->nv - v0 > SPLICE_BLOCK ? v0 + SPLICE_BLOCK : s->nv;
#pragma omp parallel for schedule(static) if (v1 - v0 > 1024)
        for (int32_t v = v0; v < v1; v++)
            coord_texts(s, xyz, v, ct + 3 * (size_t)(v - v0));
        for (int32_t v = v0; v < v1 && st == QDC_OK; v++) {
            const coord_text *c = ct + 3 * (size_t)(v - v0);
            size_t p = s->r.off[v];
            if (p < pos || p >= s->len) {
                st = qdc_fail(err, QDC_EINTERNAL,
                              "source: vertex %d at byte %zu is out of order", (int)v, p);
                break;
            }
            for (int a = 0; a < 3; a++) {
                if (c[a].te == c[a].t) {
                    st = qdc_fail(err, QDC_EINTERNAL,
                                  "source: no coordinate of vertex %d at byte %zu",
                                  (int)v, c[a].t);
                    break;
                }
                st = put_src(ed, w, pos, c[a].t, err);
                if (st != QDC_OK)
                    break;
                if (c[a].n > 0)
                    wb_put(w, c[a].txt, (size_t)c[a].n);
                else
                    wb_put(w, s->buf + c[a].t, c[a].te - c[a].t);
                pos = c[a].te;
            }
        }
    }
    qdc_free(ct);
    return st == QDC_OK ? put_src(ed, w, pos, s->len, err) : st;
}

/* Coordinates one by one (SRC_TEXT3). */
/* Coordinate i, not in the file (SRC_BLANK): its value at the recorded
 * place if it is not 0, or if a coordinate left out after it is not (",
 * value" for those left out: SRC_COMMA). */
static qdc_status splice_blank(const source *s, const double *xyz, size_t i, size_t *pos,
                               edits *ed, wbuf *w, qdc_error *err)
{
    size_t p = (size_t)(s->r.off[i] & ~(SRC_BLANK | SRC_COMMA));
    int comma = (s->r.off[i] & SRC_COMMA) != 0, need = 0;
    char buf[36];
    qdc_status st;

    for (size_t k = i; k < i / 3 * 3 + 3 && (k == i || comma); k++)
        need = need || xyz[k] != 0;
    if (p < *pos || p > s->len)
        return qdc_fail(
            err, QDC_EINTERNAL,
            "source: coordinate %zu of vertex %zu at byte %zu is out of order", i % 3,
            i / 3, p);
    if (!need)
        return QDC_OK;
    st = put_src(ed, w, *pos, p, err);
    if (st != QDC_OK)
        return st;
    *pos = p;
    if (comma)
        wb_str(w, ", ");
    wb_put(w, buf, (size_t)numfmt_g17(xyz[i], buf));
    return QDC_OK;
}

static qdc_status splice_text3(const source *s, const double *xyz, edits *ed, wbuf *w,
                               qdc_error *err)
{
    size_t pos = 0;
    qdc_status st;

    for (size_t i = 0; i < 3 * (size_t)s->nv; i++) {
        size_t p = s->r.off[i], te = p;
        if (s->r.off[i] & SRC_BLANK) {
            st = splice_blank(s, xyz, i, &pos, ed, w, err);
            if (st != QDC_OK)
                return st;
            continue;
        }
        while (te < s->len) {
            unsigned char c = (unsigned char)s->buf[te];
            if (is_space(c) || c == ',' || c == '"' || c == '\'' || c == '<')
                break;
            te++;
        }
        if (p < pos || p >= s->len || te == p)
            return qdc_fail(err, QDC_EINTERNAL,
                            "source: coordinate %zu of vertex %zu at byte %zu is out of "
                            "order or empty",
                            i % 3, i / 3, p);
        st = put_src(ed, w, pos, p, err);
        if (st != QDC_OK)
            return st;
        put_number(w, s->buf + p, s->buf + te, xyz[i]);
        pos = te;
    }
    return put_src(ed, w, pos, s->len, err);
}

/* ---- fixed-width fields (Nastran, I-DEAS) ---- */

/* x with p significant digits (1..17) in Fortran's form, the exponent
 * letter given: "1.2500000000000000D-01" for p = 17. Length into out[64]. */
static int fortran_text(double x, int p, char letter, char *out)
{
    int n = snprintf(out, 64, "%.*E", p - 1, x);

    for (int i = 0; i < n; i++)
        if (out[i] == 'E')
            out[i] = letter;
    return n;
}

/* x with p significant digits in Nastran's forms, the shortest that fits
 * in w: "0.125" (or ".125"), "1.25E-1", "1.25-1". A '.' always (a field
 * without one is an integer). Length into out[64], or 0 if none fits. */
static int nastran_text(double x, int p, int w, char *out)
{
    char e[40], dig[24], c[3][64];
    int n, nd = 0, ex, len[3];
    const char *m = e;

    snprintf(e, sizeof e, "%.*e", p - 1, x);
    if (*m == '-')
        m++;
    for (; *m && *m != 'e'; m++)
        if (*m >= '0' && *m <= '9')
            dig[nd++] = *m;
    ex = atoi(m + 1);
    while (nd > 1 && dig[nd - 1] == '0')
        nd--;
    dig[nd] = '\0';
    /* positional */
    n = 0;
    if (x < 0)
        c[0][n++] = '-';
    if (ex >= 0 && ex < 20) {
        for (int i = 0; i <= ex || i < nd; i++) {
            if (i == ex + 1)
                c[0][n++] = '.';
            c[0][n++] = i < nd ? dig[i] : '0';
        }
        if (ex + 1 >= nd)
            c[0][n++] = '.';
    } else if (ex < 0 && ex > -20) {
        if (w - n - nd + ex >= 1) /* room for "0." */
            c[0][n++] = '0';
        c[0][n++] = '.';
        for (int i = -1; i > ex; i--)
            c[0][n++] = '0';
        for (int i = 0; i < nd; i++)
            c[0][n++] = dig[i];
    } else {
        n = 64;
    }
    len[0] = n;
    for (int k = 1; k < 3; k++) { /* "1.25E-1", then "1.25-1" */
        len[k] = snprintf(c[k], 64, "%s%c.%s%s%c%d", x < 0 ? "-" : "", dig[0], dig + 1,
                          k == 1 ? "E" : "", ex < 0 ? '-' : '+', ex < 0 ? -ex : ex);
    }
    for (int k = 0; k < 3; k++)
        if (len[k] <= w) {
            memcpy(out, c[k], (size_t)len[k]);
            return len[k];
        }
    return 0;
}

/* x as the text of a field of width w: Fortran's form with 17 digits
 * (D25.16, as I-DEAS files have them), Nastran's with the fewest digits
 * that read back as x; fewer if that does not fit. Length into out[64]; 0
 * if not even one digit fits (w too small). */
static int field_text(double x, int w, int fortran, char letter, char *out)
{
    int p = fortran ? 17 : 15, n = 0;
    double back;

    for (; p < 17; p++) { /* the fewest of 15, 16, 17 that read back as x */
        n = fortran ? fortran_text(x, p, letter, out) : nastran_text(x, p, 64, out);
        if (n > 0 && parse_fortran_real(out, out + n, &back) == 0 && back == x)
            break;
    }
    for (; p >= 1; p--) {
        n = fortran ? fortran_text(x, p, letter, out) : nastran_text(x, p, w, out);
        if (n > 0 && n <= w)
            return n;
    }
    return 0;
}

/* The field [*a, *b) of coordinate off in the source, blanks trimmed into
 * [*t, *te); FIELD_FREE: the token at off. Fixed fields end at the line's end
 * ("\r\n" too) or a '$' (a Nastran comment). */
static void field_span(const source *s, uint64_t off, size_t *a, size_t *b, size_t *t,
                       size_t *te)
{
    size_t p = FIELD_AT(off), e = p;

    if (off & FIELD_FREE) {
        while (e < s->len && !is_space((unsigned char)s->buf[e]) && s->buf[e] != ',' &&
               s->buf[e] != '$')
            e++;
    } else {
        while (e < s->len && e - p < (size_t)FIELD_WIDTH(off) && s->buf[e] != '\n' &&
               s->buf[e] != '$' &&
               !(s->buf[e] == '\r' && (e + 1 == s->len || s->buf[e + 1] == '\n')))
            e++;
    }
    *a = p;
    *b = e;
    while (p < e && s->buf[p] == ' ')
        p++;
    while (e > p && s->buf[e - 1] == ' ')
        e--;
    *t = p;
    *te = e;
}

static qdc_status splice_field(const source *s, const double *xyz, edits *ed, wbuf *w,
                               qdc_error *err)
{
    size_t pos = 0;
    char text[64];
    qdc_status st;

    for (size_t i = 0; i < 3 * (size_t)s->nv; i++) {
        uint64_t off = s->r.off[i];
        size_t a, b, t, te;
        int width = FIELD_WIDTH(off), n;
        char letter = 'E';
        double old;

        field_span(s, off, &a, &b, &t, &te);
        if (a < pos || a > s->len || width < 1)
            return qdc_fail(err, QDC_EINTERNAL,
                            "source: coordinate %zu of vertex %zu at byte %zu is out of "
                            "order",
                            i % 3, i / 3, a);
        if (te == t ? xyz[i] == 0 && !signbit(xyz[i])
                    : parse_fortran_real(s->buf + t, s->buf + te, &old) == 0 &&
                          memcmp(&old, &xyz[i], sizeof old) == 0)
            continue; /* reads as the value: kept as it is */
        for (size_t k = t; k < te; k++)
            if (s->buf[k] == 'D' || s->buf[k] == 'd')
                letter = 'D';
        n = field_text(xyz[i], width, (off & FIELD_EXP) != 0, letter, text);
        if (n == 0)
            return qdc_fail(err, QDC_EINVAL,
                            "vertex %zu: coordinate %g does not fit in a field of %d "
                            "characters",
                            i / 3, xyz[i], width);
        st = put_src(ed, w, pos, a, err);
        if (st != QDC_OK)
            return st;
        for (int k = n; !(off & FIELD_FREE) && k < width; k++)
            wb_put(w, " ", 1);
        wb_put(w, text, (size_t)n);
        pos = b;
    }
    return put_src(ed, w, pos, s->len, err);
}

/* ---- binary ---- */

/* x as `width` bytes (4: float32) in the byte order big. */
static void encode_value(unsigned char *b, double x, int width, int big)
{
    uint64_t u;

    if (width == 4) {
        float f = (float)x;
        uint32_t u32;
        memcpy(&u32, &f, 4);
        u = u32;
    } else {
        memcpy(&u, &x, 8);
    }
    for (int j = 0; j < width; j++)
        b[big ? width - 1 - j : j] = (unsigned char)(u >> (8 * j));
}

static qdc_status splice_bin(const source *s, const double *xyz, edits *ed, wbuf *w,
                             qdc_error *err)
{
    size_t pos = 0, vb = 3 * (size_t)s->r.width;
    unsigned char b[24];
    qdc_status st;

    for (int32_t v = 0; v < s->nv; v++) {
        size_t p = s->r.off[v];
        if (p < pos || p > s->len || s->len - p < vb)
            return qdc_fail(err, QDC_EINTERNAL,
                            "source: vertex %d at byte %zu is out of order or range",
                            (int)v, p);
        for (int a = 0; a < 3; a++)
            encode_value(b + a * s->r.width, xyz[3 * (size_t)v + (size_t)a], s->r.width,
                         s->r.big);
        st = put_src(ed, w, pos, p, err);
        if (st != QDC_OK)
            return st;
        wb_put(w, b, vb);
        pos = p + vb;
    }
    return put_src(ed, w, pos, s->len, err);
}

/* ---- VTU blocks ---- */

static const char b64_chars[] =
    "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/* base64 of [b, b+n) appended at out (4*ceil(n/3) bytes); returns the end. */
static char *b64_encode(const unsigned char *b, size_t n, char *out)
{
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)b[i] << 16 | (i + 1 < n ? (uint32_t)b[i + 1] << 8 : 0) |
                     (i + 2 < n ? b[i + 2] : 0);
        *out++ = b64_chars[v >> 18 & 63];
        *out++ = b64_chars[v >> 12 & 63];
        *out++ = i + 1 < n ? b64_chars[v >> 6 & 63] : '=';
        *out++ = i + 2 < n ? b64_chars[v & 63] : '=';
    }
    return out;
}

static void put_word(unsigned char *p, uint64_t v, int hsz, int big)
{
    for (int j = 0; j < hsz; j++)
        p[big ? hsz - 1 - j : j] = (unsigned char)(v >> (8 * j));
}

/* raw (raw_n bytes) in zlib blocks of the source's block size: the header
 * words (*hdr, *hn bytes) and the compressed blocks (*data, *dn bytes). */
static qdc_status block_zlib(const srcrec *r, const unsigned char *raw, size_t raw_n,
                             unsigned char **hdr, size_t *hn, unsigned char **data,
                             size_t *dn, qdc_error *err)
{
    int hsz = r->hdr8 ? 8 : 4;
    size_t bs = (size_t)r->zhdr[1], nb = (size_t)r->zhdr[0];
    size_t blk = bs < raw_n ? bs : raw_n; /* a one-block header may claim 2 GB blocks */
    qdc_status st = QDC_OK;

    if (bs == 0 || nb == 0 || nb > (raw_n + bs - 1) / bs + 1 ||
        (nb - 1) * bs >= raw_n + (raw_n == 0))
        return qdc_fail(err, QDC_EINTERNAL, "source: zlib header does not fit");
    *hn = (3 + nb) * (size_t)hsz;
    *hdr = qdc_malloc(*hn);
    *data = qdc_malloc(nb * compressBound((uLong)blk) + 1);
    if (!*hdr || !*data)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the Points block");
    for (size_t k = 0; k < 3; k++)
        put_word(*hdr + k * (size_t)hsz, r->zhdr[k], hsz, r->big);
    for (size_t k = 0; k < nb && st == QDC_OK; k++) {
        size_t a = k * bs, len = k + 1 < nb ? bs : raw_n - a;
        uLongf cn = compressBound((uLong)blk);
        if (compress2(*data + *dn, &cn, raw + a, (uLong)len, Z_DEFAULT_COMPRESSION) !=
            Z_OK)
            st = qdc_fail(err, QDC_EINTERNAL, "zlib: cannot compress the Points");
        put_word(*hdr + (3 + k) * (size_t)hsz, cn, hsz, r->big);
        *dn += cn;
    }
    return st;
}

/* The block as the file holds it: header and data as they are, or in
 * base64 (the two encoded together, or each on its own). */
static qdc_status block_text(const srcrec *r, const unsigned char *hdr, size_t hn,
                             const unsigned char *data, size_t dn, char **out, size_t *n,
                             qdc_error *err)
{
    size_t cap = r->b64 ? 4 * ((hn + 2) / 3 + (dn + 2) / 3 + 1) : hn + dn;
    char *o = qdc_malloc(cap + 1), *e;

    if (!o)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the Points block");
    if (!r->b64) {
        memcpy(o, hdr, hn);
        memcpy(o + hn, data, dn);
        e = o + hn + dn;
    } else if (r->b64_sep) {
        e = b64_encode(data, dn, b64_encode(hdr, hn, o));
    } else {
        unsigned char *j = qdc_malloc(hn + dn + 1);
        if (!j) {
            qdc_free(o);
            return qdc_fail(err, QDC_ENOMEM, "out of memory for the Points block");
        }
        memcpy(j, hdr, hn);
        memcpy(j + hn, data, dn);
        e = b64_encode(j, hn + dn, o);
        qdc_free(j);
    }
    *out = o;
    *n = (size_t)(e - o);
    return QDC_OK;
}

/* The new encoded Points block: header and (compressed) data, base64 if the
 * file had it. *out (qdc_free) of *n bytes. */
static qdc_status encode_block(const source *s, const double *xyz, char **out, size_t *n,
                               qdc_error *err)
{
    const srcrec *r = &s->r;
    int hsz = r->hdr8 ? 8 : 4;
    size_t raw_n = 3 * (size_t)s->nv * (size_t)r->width, hn = 0, dn = 0;
    unsigned char *raw = qdc_malloc(raw_n + 1), *hdr = NULL, *data = NULL;
    qdc_status st = QDC_OK;

    *out = NULL;
    if (!raw)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the Points block");
    for (size_t i = 0; i < 3 * (size_t)s->nv; i++)
        encode_value(raw + i * (size_t)r->width, xyz[i], r->width, r->big);
    if (r->zlib) {
        st = block_zlib(r, raw, raw_n, &hdr, &hn, &data, &dn, err);
    } else {
        hn = (size_t)hsz;
        hdr = qdc_malloc(hn);
        if (!hdr)
            st = qdc_fail(err, QDC_ENOMEM, "out of memory for the Points block");
        else
            put_word(hdr, raw_n, hsz, r->big);
        data = raw;
        raw = NULL;
        dn = raw_n;
    }
    if (st == QDC_OK)
        st = block_text(r, hdr, hn, data, dn, out, n, err);
    qdc_free(raw);
    qdc_free(hdr);
    qdc_free(data);
    return st;
}

static qdc_status splice_block(const source *s, const double *xyz, edits *ed, wbuf *w,
                               qdc_error *err)
{
    const srcrec *r = &s->r;
    const uint64_t *ao = r->appoff.a;
    size_t pos = 0, n = 0;
    char *blk = NULL;
    int64_t delta;
    qdc_status st;

    if (r->blk_a > r->blk_b || r->blk_b > s->len)
        return qdc_fail(err, QDC_EINTERNAL, "source: Points block out of range");
    st = encode_block(s, xyz, &blk, &n, err);
    if (st != QDC_OK)
        return st;
    delta = (int64_t)n - (int64_t)(r->blk_b - r->blk_a);
    for (size_t i = 0; r->appended && delta && i + 3 <= r->appoff.n; i += 3) {
        if (ao[i + 2] <= r->app_off)
            continue;
        if (ao[i] < pos || ao[i + 1] < ao[i] || ao[i + 1] > r->blk_a) {
            qdc_free(blk);
            return qdc_fail(err, QDC_EINTERNAL, "source: appended offsets out of order");
        }
        st = put_src(ed, w, pos, (size_t)ao[i], err);
        if (st != QDC_OK) {
            qdc_free(blk);
            return st;
        }
        wb_int(w, (int64_t)ao[i + 2] + delta);
        pos = (size_t)ao[i + 1];
    }
    st = put_src(ed, w, pos, (size_t)r->blk_a, err);
    if (st == QDC_OK) {
        wb_put(w, blk, n);
        st = put_src(ed, w, (size_t)r->blk_b, s->len, err);
    }
    qdc_free(blk);
    return st;
}

qdc_status splice_write(const mesh_t *m, int part, wbuf *w, qdc_error *err)
{
    const source *s = (const source *)m->source;
    edits ed;
    qdc_status st;

    if (part == 1) {
        if (!s->ele)
            return qdc_fail(err, QDC_EINTERNAL, "source: no .ele kept");
        wb_put(w, s->ele, s->ele_len);
        return QDC_OK;
    }
    if (hash_bytes(0, m->xyz, 24 * (size_t)m->nv) == s->xyz_hash) {
        wb_put(w, s->buf, s->len); /* nothing moved (a base64 or zlib block as is) */
        return QDC_OK;
    }
    st = edits_init(&ed, s, m->xyz, err);
    if (st != QDC_OK)
        return st;
    switch (s->r.kind) {
    case SRC_TEXT:
        st = splice_text(s, m->xyz, &ed, w, err);
        break;
    case SRC_BIN:
        st = splice_bin(s, m->xyz, &ed, w, err);
        break;
    case SRC_TEXT3:
        st = splice_text3(s, m->xyz, &ed, w, err);
        break;
    case SRC_BLOCK:
        st = splice_block(s, m->xyz, &ed, w, err);
        break;
    case SRC_FIELD:
        st = splice_field(s, m->xyz, &ed, w, err);
        break;
    default:
        st = qdc_fail(err, QDC_EINTERNAL, "source: nothing recorded");
    }
    qdc_free(ed.vals);
    return st;
}
