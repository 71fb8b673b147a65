/* surface.c - STL, OFF, OBJ, TetGen .poly/.smesh triangle surfaces.
 *
 * The text scanners and number parsers are meshio's (meshio_scan.h), so the
 * same exactness and bounds checks hold. Every reader appends to one builder:
 * raw vertices, then polygons split into fans; at the end vertices with
 * bit-identical coordinates (-0.0 taken as 0.0) are merged through an open-
 * addressing hash table and the unreferenced ones dropped. */
#include "io/surface.h"
#include "io/meshio_scan.h"

void surface_free(surface_t *s)
{
    if (!s)
        return;
    qdc_free(s->xyz);
    qdc_free(s->tris);
    qdc_free(s->tri_ref);
    qdc_free(s->holes);
    qdc_free(s->regions);
    qdc_free(s);
}

/* ------------------------------------------------------------------------ */
/* Names                                                                     */

static const char *const surf_names[SURFACE_FORMAT_COUNT] = {NULL,  "stl",  "off",
                                                             "obj", "poly", "smesh"};

static const struct {
    const char *type;
    surface_format f;
} surf_media[] = {
    {"model/stl", SURFACE_STL},
    {"model/x-off", SURFACE_OFF},
    {"model/obj", SURFACE_OBJ},
    {"application/vnd.qdc.surface+poly", SURFACE_POLY},
    {"application/vnd.qdc.surface+smesh", SURFACE_SMESH},
    {"application/sla", SURFACE_STL},
    {"model/x.stl-binary", SURFACE_STL},
    {"model/x.stl-ascii", SURFACE_STL},
};

const char *surface_format_name(surface_format f)
{
    return (unsigned)f < SURFACE_FORMAT_COUNT ? surf_names[f] : NULL;
}

const char *surface_media_type(surface_format f)
{
    for (size_t i = 0; i < sizeof surf_media / sizeof surf_media[0]; i++)
        if (surf_media[i].f == f)
            return surf_media[i].type;
    return NULL;
}

surface_format surface_format_from_name(const char *s)
{
    const char *slash, *dot;

    if (!s)
        return SURFACE_AUTO;
    slash = strrchr(s, '/');
    dot = strrchr(slash ? slash : s, '.');
    if (dot)
        s = dot + 1;
    for (int f = 1; f < SURFACE_FORMAT_COUNT; f++)
        if (strcasecmp(s, surf_names[f]) == 0)
            return (surface_format)f;
    return SURFACE_AUTO;
}

surface_format surface_format_from_media_type(const char *ct)
{
    size_t n;

    if (!ct)
        return SURFACE_AUTO;
    while (*ct == ' ' || *ct == '\t')
        ct++;
    n = strcspn(ct, "; \t");
    for (size_t i = 0; i < sizeof surf_media / sizeof surf_media[0]; i++)
        if (strlen(surf_media[i].type) == n &&
            strncasecmp(ct, surf_media[i].type, n) == 0)
            return surf_media[i].f;
    return SURFACE_AUTO;
}

static int starts(const char *p, size_t n, const char *w)
{
    size_t l = strlen(w);

    return n >= l && strncasecmp(p, w, l) == 0;
}

surface_format surface_sniff(const char *buf, size_t len)
{
    size_t i = 0;

    if (!buf)
        return SURFACE_AUTO;
    if (len >= 84 && len == 84 + 50 * (size_t)get_le32((const unsigned char *)buf + 80))
        return SURFACE_STL;
    while (i < len && is_space((unsigned char)buf[i]))
        i++;
    if (starts(buf + i, len - i, "solid"))
        return SURFACE_STL;
    if (starts(buf + i, len - i, "OFF") || starts(buf + i, len - i, "COFF") ||
        starts(buf + i, len - i, "NOFF"))
        return SURFACE_OFF;
    for (size_t p = 0; p + 2 < len && p < 4096; p++) /* an OBJ vertex line early on */
        if ((p == 0 || buf[p - 1] == '\n') && buf[p] == 'v' &&
            (buf[p + 1] == ' ' || buf[p + 1] == '\t'))
            return SURFACE_OBJ;
    return SURFACE_AUTO;
}

/* ------------------------------------------------------------------------ */
/* Builder                                                                   */

typedef struct {
    vec xyz;  /* doubles */
    vec tris; /* int32, 3 per triangle */
    vec ref;  /* int32 per triangle, when markers are read */
    vec holes, regions;
    int with_ref;
} builder;

static void builder_init(builder *b)
{
    memset(b, 0, sizeof *b);
    b->xyz.size = b->holes.size = b->regions.size = sizeof(double);
    b->tris.size = b->ref.size = sizeof(int32_t);
}

static void builder_free(builder *b)
{
    vec_free(&b->xyz);
    vec_free(&b->tris);
    vec_free(&b->ref);
    vec_free(&b->holes);
    vec_free(&b->regions);
}

static qdc_status oom(qdc_error *err)
{
    return qdc_fail(err, QDC_ENOMEM, "out of memory for the surface");
}

static qdc_status add_vertex(builder *b, const double p[3], qdc_error *err)
{
    if (b->xyz.n / 3 >= MESH_MAX_VERTICES)
        return qdc_fail(err, QDC_ETOOBIG, "more than %d vertices", MESH_MAX_VERTICES);
    if (vec_grow(&b->xyz, 3) != 0)
        return oom(err);
    memcpy((double *)b->xyz.a + b->xyz.n, p, 3 * sizeof(double));
    b->xyz.n += 3;
    return QDC_OK;
}

/* A polygon of k vertex indices (0-based, checked by the caller) as a fan. */
static qdc_status add_polygon(builder *b, const int32_t *v, int64_t k, int32_t ref,
                              qdc_error *err)
{
    for (int64_t j = 1; j + 1 < k; j++) {
        int32_t *t;
        if (b->tris.n / 3 >= INT32_MAX / 3)
            return qdc_fail(err, QDC_ETOOBIG, "more than %d triangles", INT32_MAX / 3);
        if (vec_grow(&b->tris, 3) != 0 || vec_grow(&b->ref, 1) != 0)
            return oom(err);
        t = (int32_t *)b->tris.a + b->tris.n;
        t[0] = v[0];
        t[1] = v[j];
        t[2] = v[j + 1];
        b->tris.n += 3;
        ((int32_t *)b->ref.a)[b->ref.n++] = ref;
    }
    return QDC_OK;
}

static uint64_t hash_point(const double *p)
{
    uint64_t h = 0x9e3779b97f4a7c15u;

    for (int i = 0; i < 3; i++) {
        double x = p[i] == 0 ? 0.0 : p[i];
        uint64_t u;
        memcpy(&u, &x, 8);
        h = (h ^ u) * 0xff51afd7ed558ccdu;
        h ^= h >> 32;
    }
    return h;
}

static int same_point(const double *a, const double *b)
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/* Merge equal vertices, drop unreferenced ones, hand the arrays to *out. */
static qdc_status build(builder *b, surface_t **out, qdc_error *err)
{
    size_t nv = b->xyz.n / 3, ntri = b->tris.n / 3, cap = 16;
    const double *xyz = b->xyz.a;
    int32_t *slot = NULL, *map = NULL, *tris = b->tris.a;
    surface_t *s = NULL;
    int32_t nu = 0;

    while (cap < 2 * nv)
        cap *= 2;
    slot = qdc_mallocn(cap, sizeof(int32_t));
    map = qdc_mallocn(nv + 1, sizeof(int32_t));
    s = qdc_calloc(1, sizeof *s);
    if (!slot || !map || !s)
        goto nomem;
    memset(slot, 0xff, cap * sizeof(int32_t));
    /* map[i]: the first vertex equal to i */
    for (size_t i = 0; i < nv; i++) {
        size_t h = (size_t)hash_point(xyz + 3 * i) & (cap - 1);
        while (slot[h] >= 0 && !same_point(xyz + 3 * (size_t)slot[h], xyz + 3 * i))
            h = (h + 1) & (cap - 1);
        if (slot[h] < 0)
            slot[h] = (int32_t)i;
        map[i] = slot[h];
    }
    /* renumber the referenced representatives in order of first use */
    qdc_free(slot);
    slot = qdc_mallocn(nv + 1, sizeof(int32_t));
    if (!slot)
        goto nomem;
    memset(slot, 0xff, (nv + 1) * sizeof(int32_t));
    for (size_t t = 0; t < 3 * ntri; t++) {
        int32_t r = map[tris[t]];
        if (slot[r] < 0)
            slot[r] = nu++;
        tris[t] = slot[r];
    }
    s->xyz = qdc_mallocn((size_t)nu * 3 + 1, sizeof(double));
    if (!s->xyz)
        goto nomem;
    for (size_t i = 0; i < nv; i++)
        if (slot[i] >= 0)
            memcpy(s->xyz + 3 * (size_t)slot[i], xyz + 3 * i, 3 * sizeof(double));
    s->nv = nu;
    s->ntri = (int32_t)ntri;
    s->tris = b->tris.a;
    b->tris.a = NULL;
    if (b->with_ref) {
        s->tri_ref = b->ref.a;
        b->ref.a = NULL;
    }
    s->nholes = (int32_t)(b->holes.n / 3);
    s->holes = b->holes.a;
    b->holes.a = NULL;
    s->nregions = (int32_t)(b->regions.n / 5);
    s->regions = b->regions.a;
    b->regions.a = NULL;
    qdc_free(slot);
    qdc_free(map);
    *out = s;
    return QDC_OK;
nomem:
    qdc_free(slot);
    qdc_free(map);
    surface_free(s);
    return oom(err);
}

/* ------------------------------------------------------------------------ */
/* STL                                                                       */

static qdc_status stl_binary(const char *buf, size_t len, builder *b, qdc_error *err)
{
    const unsigned char *p = (const unsigned char *)buf;
    uint32_t n = get_le32(p + 80);

    if ((uint64_t)n * 50 + 84 != len)
        return fail_bin(err, QDC_EPARSE, 80,
                        "binary STL: %u triangles need %llu bytes, got %zu", n,
                        (unsigned long long)n * 50 + 84, len);
    if (n > INT32_MAX / 3)
        return fail_bin(err, QDC_ETOOBIG, 80, "binary STL: %u triangles exceed the limit",
                        n);
    for (uint32_t t = 0; t < n; t++) {
        const unsigned char *f = p + 84 + 50 * (size_t)t + 12;
        int32_t v[3];
        for (int k = 0; k < 3; k++) {
            double q[3];
            for (int a = 0; a < 3; a++) {
                uint32_t u = get_le32(f + 12 * k + 4 * a);
                float x;
                memcpy(&x, &u, 4);
                q[a] = x;
                if (!isfinite(q[a])) {
                    fail_bin(err, QDC_EPARSE, (int64_t)(f - p) + 12 * k + 4 * a,
                             "binary STL: triangle %u: coordinate is not finite", t);
                    set_index(err, "triangle", t);
                    return QDC_EPARSE;
                }
            }
            if (add_vertex(b, q, err) != QDC_OK)
                return err ? err->status : QDC_ENOMEM;
            v[k] = (int32_t)(b->xyz.n / 3 - 1);
        }
        if (add_polygon(b, v, 3, 0, err) != QDC_OK)
            return err ? err->status : QDC_ENOMEM;
    }
    return QDC_OK;
}

/* The next word must be kw. */
static qdc_status want_word(txt *s, const char *kw, qdc_error *err)
{
    const char *t;
    char q[32];

    skip_ws(s);
    t = s->p;
    s->p = tok_end(s, t);
    if (!word_is(t, (size_t)(s->p - t), kw))
        return fail_txt(err, QDC_EPARSE, s, t, "STL: expected '%s', got %s", kw,
                        quote_tok(q, s, t, s->p));
    return QDC_OK;
}

static void skip_rest_of_line(txt *s)
{
    while (s->p < s->end && *s->p != '\n')
        s->p++;
}

static qdc_status stl_ascii(const char *buf, size_t len, builder *b, qdc_error *err)
{
    txt s = txt_init(buf, len, 0);
    qdc_status st = want_word(&s, "solid", err);

    skip_rest_of_line(&s); /* the solid's name */
    while (st == QDC_OK) {
        const char *t;
        size_t n;
        int32_t v[3];
        skip_ws(&s);
        t = s.p;
        n = (size_t)(tok_end(&s, t) - t);
        if (word_is(t, n, "endsolid"))
            break;
        st = want_word(&s, "facet", err);
        skip_rest_of_line(&s); /* normal nx ny nz: recomputed by whoever needs it */
        if (st == QDC_OK)
            st = want_word(&s, "outer", err);
        if (st == QDC_OK)
            st = want_word(&s, "loop", err);
        for (int k = 0; k < 3 && st == QDC_OK; k++) {
            double q[3];
            st = want_word(&s, "vertex", err);
            for (int a = 0; a < 3 && st == QDC_OK; a++)
                st = txt_real(&s, "STL: vertex coordinate", &q[a], err);
            if (st == QDC_OK)
                st = add_vertex(b, q, err);
            v[k] = (int32_t)(b->xyz.n / 3 - 1);
        }
        if (st == QDC_OK)
            st = want_word(&s, "endloop", err);
        if (st == QDC_OK)
            st = want_word(&s, "endfacet", err);
        if (st == QDC_OK)
            st = add_polygon(b, v, 3, 0, err);
        if (st != QDC_OK)
            set_index(err, "triangle", (int64_t)(b->tris.n / 3));
    }
    return st;
}

/* ------------------------------------------------------------------------ */
/* OFF, .poly, .smesh: counted lists                                         */

/* One polygon "k i1 .. ik" with indices from `base`, nv vertices; extra values
 * on the line (OFF colours) are skipped when `rest` is set. */
static qdc_status read_polygon(txt *s, builder *b, int64_t base, int64_t nv, int32_t ref,
                               int rest, const char *what, qdc_error *err)
{
    int64_t k, v;
    int32_t small[16], *idx = small;
    qdc_status st = txt_int(s, what, 1, 1 << 20, &k, err);

    if (st != QDC_OK)
        return st;
    if (k < 3)
        return fail_txt(err, QDC_EPARSE, s, s->p, "%s: a polygon of %lld vertices", what,
                        (long long)k);
    st = txt_fits(s, s->p, what, k, 1, err);
    if (st == QDC_OK && k > 16 && !(idx = qdc_mallocn((size_t)k, sizeof(int32_t))))
        st = oom(err);
    for (int64_t j = 0; j < k && st == QDC_OK; j++) {
        st = txt_int(s, what, base, base + nv - 1, &v, err);
        idx[j] = (int32_t)(v - base);
    }
    if (st == QDC_OK)
        st = add_polygon(b, idx, k, ref, err);
    if (idx != small)
        qdc_free(idx);
    if (st == QDC_OK && rest)
        skip_rest_of_line(s);
    return st;
}

static qdc_status read_off(const char *buf, size_t len, builder *b, qdc_error *err)
{
    txt s = txt_init(buf, len, 1);
    const char *t;
    int64_t nv, nf, ne;
    qdc_status st;
    char q[32];

    skip_ws(&s);
    t = s.p;
    s.p = tok_end(&s, t);
    if (!word_is(t, (size_t)(s.p - t), "OFF") && !word_is(t, (size_t)(s.p - t), "COFF") &&
        !word_is(t, (size_t)(s.p - t), "NOFF"))
        return fail_txt(err, QDC_EPARSE, &s, t, "OFF: expected 'OFF', got %s",
                        quote_tok(q, &s, t, s.p));
    st = txt_count(&s, "OFF: vertex count", 3, MESH_MAX_VERTICES, &nv, err);
    if (st == QDC_OK)
        st = txt_count(&s, "OFF: face count", 4, INT32_MAX / 3, &nf, err);
    if (st == QDC_OK)
        st = txt_int(&s, "OFF: edge count", 0, INT64_MAX, &ne, err);
    skip_rest_of_line(&s);
    for (int64_t i = 0; i < nv && st == QDC_OK; i++) {
        double p[3];
        for (int a = 0; a < 3 && st == QDC_OK; a++)
            st = txt_real(&s, "OFF: coordinate", &p[a], err);
        if (st == QDC_OK)
            st = add_vertex(b, p, err);
        skip_rest_of_line(&s); /* colours, normals */
        if (st != QDC_OK)
            set_index(err, "vertex", i);
    }
    for (int64_t i = 0; i < nf && st == QDC_OK; i++) {
        st = read_polygon(&s, b, 0, nv, 0, 1, "OFF: face", err);
        if (st != QDC_OK)
            set_index(err, "face", i);
    }
    return st;
}

/* TetGen node list "<n> 3 <nattr> <nbm>" then "<i> x y z [attrs] [marker]";
 * the first index sets the numbering. */
static qdc_status poly_nodes(txt *s, builder *b, int64_t *base, int64_t *nv,
                             qdc_error *err)
{
    int64_t dim, nattr, nbm, num;
    double x;
    qdc_status st = txt_count(s, ".poly: node count", 4, MESH_MAX_VERTICES, nv, err);

    if (st == QDC_OK)
        st = txt_int(s, ".poly: dimension", 3, 3, &dim, err);
    if (st == QDC_OK)
        st = txt_int(s, ".poly: attribute count", 0, 1000, &nattr, err);
    if (st == QDC_OK)
        st = txt_int(s, ".poly: boundary marker count", 0, 1, &nbm, err);
    for (int64_t i = 0; i < *nv && st == QDC_OK; i++) {
        double p[3];
        st = txt_int(s, ".poly: node number", i ? *base + i : 0, i ? *base + i : 1, &num,
                     err);
        if (i == 0)
            *base = num;
        for (int a = 0; a < 3 && st == QDC_OK; a++)
            st = txt_real(s, ".poly: coordinate", &p[a], err);
        for (int64_t a = 0; a < nattr + nbm && st == QDC_OK; a++)
            st = txt_real(s, ".poly: node attribute", &x, err);
        if (st == QDC_OK)
            st = add_vertex(b, p, err);
        if (st != QDC_OK)
            set_index(err, "vertex", i);
    }
    return st;
}

/* n points of `k` values after an index: the hole and region lists. */
static qdc_status poly_points(txt *s, vec *v, int k, const char *what, qdc_error *err)
{
    int64_t n, num;
    qdc_status st;

    skip_ws(s);
    if (s->p == s->end) /* both lists are optional at the end */
        return QDC_OK;
    st = txt_count(s, what, 1 + k, INT32_MAX / 8, &n, err);
    if (st == QDC_OK && vec_grow(v, (size_t)n * 5) != 0)
        st = oom(err);
    for (int64_t i = 0; i < n && st == QDC_OK; i++) {
        double *p = (double *)v->a + v->n;
        st = txt_int(s, what, INT64_MIN, INT64_MAX, &num, err);
        p[3] = 0;
        p[4] = -1;
        for (int a = 0; a < k && st == QDC_OK; a++)
            st = txt_real(s, what, &p[a], err);
        /* regions: x y z attribute [maxvol] on one line */
        if (st == QDC_OK && k == 4) {
            const char *q = s->p;
            while (q < s->end && (*q == ' ' || *q == '\t' || *q == '\r'))
                q++;
            if (q < s->end && *q != '\n' && *q != '#')
                st = txt_real(s, what, &p[4], err);
        }
        v->n += k == 3 ? 3 : 5;
    }
    return st;
}

static qdc_status read_poly(const char *buf, size_t len, int smesh, builder *b,
                            qdc_error *err)
{
    txt s = txt_init(buf, len, 1);
    const char *name = smesh ? ".smesh" : ".poly";
    int64_t base = 0, nv, nf, nbm, npoly, nhole, v;
    qdc_status st = poly_nodes(&s, b, &base, &nv, err);

    if (st == QDC_OK && nv == 0)
        return fail_txt(err, QDC_EFORMAT, &s, s.p,
                        "%s without nodes (a separate .node file) is not supported",
                        name);
    if (st == QDC_OK)
        st = txt_count(&s, "facet count", 2, INT32_MAX / 3, &nf, err);
    if (st == QDC_OK)
        st = txt_int(&s, "facet boundary marker count", 0, 1, &nbm, err);
    b->with_ref = nbm == 1;
    for (int64_t i = 0; i < nf && st == QDC_OK; i++) {
        int32_t ref = 0;
        if (smesh) { /* "k i1..ik [marker]" */
            size_t r0 = b->ref.n;
            st = read_polygon(&s, b, base, nv, 0, 0, ".smesh: facet", err);
            if (st == QDC_OK && nbm)
                st = txt_int(&s, ".smesh: facet marker", INT32_MIN, INT32_MAX, &v, err);
            for (size_t r = r0; st == QDC_OK && nbm && r < b->ref.n; r++)
                ((int32_t *)b->ref.a)[r] = (int32_t)v;
        } else { /* "npolygons [nholes [marker]]" then polygons, then hole points */
            const char *q;
            st = txt_int(&s, ".poly: polygon count", 1, 1 << 20, &npoly, err);
            nhole = 0;
            q = s.p;
            while (q < s.end && (*q == ' ' || *q == '\t' || *q == '\r'))
                q++;
            if (st == QDC_OK && q < s.end && *q != '\n' && *q != '#')
                st = txt_int(&s, ".poly: facet hole count", 0, 0, &nhole, err);
            if (st == QDC_OK && nbm)
                st = txt_int(&s, ".poly: facet marker", INT32_MIN, INT32_MAX, &v, err);
            ref = nbm ? (int32_t)v : 0;
            for (int64_t j = 0; j < npoly && st == QDC_OK; j++)
                st = read_polygon(&s, b, base, nv, ref, 0, ".poly: polygon", err);
        }
        if (st != QDC_OK)
            set_index(err, "facet", i);
    }
    if (st == QDC_OK)
        st = poly_points(&s, &b->holes, 3, "hole list", err);
    if (st == QDC_OK)
        st = poly_points(&s, &b->regions, 4, "region list", err);
    if (st == QDC_OK)
        st = txt_done(&s, "the region list", err);
    return st;
}

/* ------------------------------------------------------------------------ */
/* OBJ                                                                       */

static qdc_status obj_face(txt *s, builder *b, qdc_error *err)
{
    vec idx = {NULL, 0, 0, sizeof(int32_t)};
    int64_t nv = (int64_t)(b->xyz.n / 3), v;
    qdc_status st = QDC_OK;

    for (;;) {
        const char *t, *te, *slash;
        while (s->p < s->end && (*s->p == ' ' || *s->p == '\t' || *s->p == '\r'))
            s->p++;
        if (s->p == s->end || *s->p == '\n' || *s->p == '#')
            break;
        t = s->p;
        te = tok_end(s, t);
        for (slash = t; slash < te && *slash != '/'; slash++)
            ;
        st = tok_int(s, t, slash, 0, "OBJ: f: vertex index", -nv, nv, &v, err);
        if (st == QDC_OK && v == 0)
            st = fail_txt(err, QDC_EPARSE, s, t,
                          "OBJ: f: vertex index 0 (indices start at 1)");
        if (st != QDC_OK)
            break;
        s->p = te;
        if (vec_grow(&idx, 1) != 0) {
            st = oom(err);
            break;
        }
        ((int32_t *)idx.a)[idx.n++] = (int32_t)(v > 0 ? v - 1 : nv + v);
    }
    if (st == QDC_OK && idx.n < 3)
        st = fail_txt(err, QDC_EPARSE, s, s->p, "OBJ: a face of %zu vertices", idx.n);
    if (st == QDC_OK)
        st = add_polygon(b, idx.a, (int64_t)idx.n, 0, err);
    vec_free(&idx);
    return st;
}

static qdc_status read_obj(const char *buf, size_t len, builder *b, qdc_error *err)
{
    txt s = txt_init(buf, len, 1);
    qdc_status st = QDC_OK;

    while (st == QDC_OK) {
        const char *t;
        size_t n;
        skip_ws(&s);
        if (s.p == s.end)
            break;
        t = s.p;
        n = (size_t)(tok_end(&s, t) - t);
        s.p = t + n;
        if (n == 1 && *t == 'v') {
            double p[3];
            for (int a = 0; a < 3 && st == QDC_OK; a++)
                st = txt_real(&s, "OBJ: v: coordinate", &p[a], err);
            if (st == QDC_OK)
                st = add_vertex(b, p, err);
        } else if (n == 1 && *t == 'f') {
            st = obj_face(&s, b, err);
            continue;
        }
        skip_rest_of_line(&s); /* w, vn, vt, g, o, s, usemtl, mtllib, l ... */
    }
    return st;
}

/* ------------------------------------------------------------------------ */
/* Entry points                                                              */

qdc_status surface_read(const char *buf, size_t len, surface_format fmt, surface_t **out,
                        qdc_error *err)
{
    builder b;
    qdc_status st;

    qdc_error_clear(err);
    if (!out || (!buf && len))
        return qdc_fail(err, QDC_EINVAL, "surface_read: NULL argument");
    *out = NULL;
    if (!buf)
        buf = "";
    if (fmt == SURFACE_AUTO)
        fmt = surface_sniff(buf, len);
    builder_init(&b);
    switch (fmt) {
    case SURFACE_STL:
        if (len >= 84 &&
            len == 84 + 50 * (size_t)get_le32((const unsigned char *)buf + 80))
            st = stl_binary(buf, len, &b, err);
        else
            st = stl_ascii(buf, len, &b, err);
        break;
    case SURFACE_OFF:
        st = read_off(buf, len, &b, err);
        break;
    case SURFACE_OBJ:
        st = read_obj(buf, len, &b, err);
        break;
    case SURFACE_POLY:
    case SURFACE_SMESH:
        st = read_poly(buf, len, fmt == SURFACE_SMESH, &b, err);
        break;
    case SURFACE_AUTO:
        st = qdc_fail(err, QDC_EFORMAT, "unrecognized surface format");
        break;
    default:
        st = qdc_fail(err, QDC_EINVAL, "unknown surface format %d", (int)fmt);
        break;
    }
    if (st == QDC_OK)
        st = build(&b, out, err);
    builder_free(&b);
    return st;
}

qdc_status surface_load(const char *path, surface_format fmt, surface_t **out,
                        qdc_error *err)
{
    char *buf = NULL;
    size_t len = 0;
    qdc_status st;

    if (fmt == SURFACE_AUTO && path)
        fmt = surface_format_from_name(path);
    st = meshio_slurp(path, &buf, &len, err);
    if (st == QDC_OK)
        st = surface_read(buf, len, fmt, out, err);
    qdc_free(buf);
    return st;
}

/* ------------------------------------------------------------------------ */
/* Checks                                                                    */

static int cmp_edge(const void *a, const void *b)
{
    const int64_t *x = a, *y = b;

    return (x[0] > y[0]) - (x[0] < y[0]);
}

qdc_status surface_check(const surface_t *s, qdc_error *err)
{
    int64_t *e; /* per directed edge: key (min << 32 | max), then tri << 1 | reversed */
    int64_t ne;
    qdc_status st = QDC_OK;

    if (!s || s->ntri <= 0)
        return qdc_fail(err, QDC_EMESH, "the surface has no triangles");
    for (int32_t t = 0; t < s->ntri; t++) {
        const int32_t *v = s->tris + 3 * (size_t)t;
        const double *a, *b, *c;
        double u[3], w[3], n[3];
        if (first_bad_index(v, 3, s->nv) >= 0 || v[0] == v[1] || v[1] == v[2] ||
            v[0] == v[2]) {
            qdc_fail(err, QDC_EMESH, "triangle %d: %s", t,
                     first_bad_index(v, 3, s->nv) >= 0 ? "vertex index out of range"
                                                       : "repeated vertex (degenerate)");
            set_index(err, "triangle", t);
            return QDC_EMESH;
        }
        a = s->xyz + 3 * (size_t)v[0];
        b = s->xyz + 3 * (size_t)v[1];
        c = s->xyz + 3 * (size_t)v[2];
        for (int i = 0; i < 3; i++) {
            u[i] = b[i] - a[i];
            w[i] = c[i] - a[i];
        }
        n[0] = u[1] * w[2] - u[2] * w[1];
        n[1] = u[2] * w[0] - u[0] * w[2];
        n[2] = u[0] * w[1] - u[1] * w[0];
        if (n[0] == 0 && n[1] == 0 && n[2] == 0) {
            qdc_fail(err, QDC_EMESH, "triangle %d has zero area (degenerate)", t);
            set_index(err, "triangle", t);
            return QDC_EMESH;
        }
    }
    ne = 3 * (int64_t)s->ntri;
    e = qdc_mallocn((size_t)ne * 2, sizeof(int64_t));
    if (!e)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the surface edges");
    for (int64_t t = 0; t < s->ntri; t++)
        for (int j = 0; j < 3; j++) {
            int64_t a = s->tris[3 * t + j], b = s->tris[3 * t + (j + 1) % 3];
            int64_t *p = e + 2 * (3 * t + j);
            p[0] = (a < b ? a : b) << 32 | (a < b ? b : a);
            p[1] = t << 1 | (a > b);
        }
    qsort(e, (size_t)ne, 2 * sizeof(int64_t), cmp_edge);
    for (int64_t i = 0; i < ne && st == QDC_OK;) {
        int64_t j = i + 1;
        while (j < ne && e[2 * j] == e[2 * i])
            j++;
        if (j - i != 2 || (e[2 * i + 1] & 1) == (e[2 * i + 3] & 1)) {
            int64_t a = e[2 * i] >> 32, b = e[2 * i] & 0xffffffff;
            st = qdc_fail(err, QDC_EMESH,
                          j - i == 1 ? "the surface is not closed: edge (%lld, %lld) at "
                                       "(%g, %g, %g) belongs to one triangle only"
                          : j - i > 2
                              ? "the surface is not manifold: edge (%lld, %lld) at "
                                "(%g, %g, %g) is shared by more than two triangles"
                              : "the surface is not consistently oriented: the two "
                                "triangles on edge (%lld, %lld) at (%g, %g, %g) "
                                "run it the same way",
                          (long long)a, (long long)b, s->xyz[3 * a], s->xyz[3 * a + 1],
                          s->xyz[3 * a + 2]);
            set_index(err, "triangle", e[2 * i + 1] >> 1);
        }
        i = j;
    }
    qdc_free(e);
    return st;
}
