/* meshio_meshb.c - Medit binary .meshb (libMeshb's GMF binary files, mmg's
 * native format), versions 1 to 4, either byte order.
 *
 * Layout: an int32 code 1 (its byte order is the file's), an int32 version
 * (1: float32 reals, int32 integers and positions; 2: float64 reals; 3: also
 * 64-bit positions; 4: also 64-bit integers and counts), then keywords: an
 * int32 code, the position of the next keyword, a count and the records.
 * Dimension (3) holds one int32; End (54) ends the file. Vertices, Triangles,
 * Tetrahedra and RequiredVertices are read (as the ASCII Medit reader reads
 * them: refs, regions, fixed vertices); every other keyword is skipped
 * through its next-keyword position, and kept byte for byte by a spliced
 * write, which overwrites the coordinates in their own width and byte order
 * (version 1: float32). qdc's own writer writes version 2, little-endian. */
#include "io/format.h"

enum {
    GMF_DIMENSION = 3,
    GMF_VERTICES = 4,
    GMF_TRIANGLES = 6,
    GMF_TETRAHEDRA = 8,
    GMF_REQUIRED_VERTICES = 15,
    GMF_TETRAHEDRA_P2 = 30,
    GMF_END = 54
};

typedef struct {
    const unsigned char *b;
    size_t len, p;
    int big, rsz, isz, psz; /* byte order; sizes of reals, integers, positions */
} gmf;

static uint64_t gmf_word(const gmf *g, size_t at, int n)
{
    uint64_t v = 0;

    for (int k = 0; k < n; k++)
        v |= (uint64_t)g->b[at + (size_t)k] << (8 * (g->big ? n - 1 - k : k));
    return v;
}

static qdc_status gmf_need(const gmf *g, uint64_t n, const char *what, qdc_error *err)
{
    if (n > g->len - g->p)
        return fail_bin(err, QDC_EPARSE, (int64_t)g->p,
                        "meshb: %s needs %llu bytes, %zu left (truncated?)", what,
                        (unsigned long long)n, g->len - g->p);
    return QDC_OK;
}

/* A signed integer of n bytes at the cursor (n checked by the caller). */
static int64_t gmf_int(gmf *g, int n)
{
    uint64_t u = gmf_word(g, g->p, n);

    g->p += (size_t)n;
    return n == 4 ? (int64_t)(int32_t)(uint32_t)u : (int64_t)u;
}

static double gmf_real(gmf *g)
{
    uint64_t u = gmf_word(g, g->p, g->rsz);
    double x;

    g->p += (size_t)g->rsz;
    if (g->rsz == 4) {
        float f;
        uint32_t u32 = (uint32_t)u;
        memcpy(&f, &u32, 4);
        return f;
    }
    memcpy(&x, &u, 8);
    return x;
}

/* A count of records of `rec` bytes each, checked against the bytes left. */
static qdc_status gmf_count(gmf *g, const char *what, uint64_t rec, int64_t max,
                            int64_t *n, qdc_error *err)
{
    size_t at = g->p;
    qdc_status st = gmf_need(g, (uint64_t)g->isz, what, err);

    if (st != QDC_OK)
        return st;
    *n = gmf_int(g, g->isz);
    if (*n < 0 || (uint64_t)*n > (g->len - g->p) / rec)
        return fail_bin(err, QDC_EPARSE, (int64_t)at,
                        "meshb: %s: count %lld does not fit in the %zu bytes left "
                        "(truncated?)",
                        what, (long long)*n, g->len - g->p);
    if (*n > max)
        return fail_bin(err, QDC_ETOOBIG, (int64_t)at,
                        "meshb: %s: count %lld exceeds the limit %lld", what,
                        (long long)*n, (long long)max);
    return QDC_OK;
}

/* k vertex numbers and a ref per record; 1-based numbers checked later. */
static qdc_status gmf_elems(gmf *g, const char *what, int k, int64_t max, int64_t *n,
                            int32_t **idx, int32_t **ref, qdc_error *err)
{
    qdc_status st;

    if (*idx)
        return fail_bin(err, QDC_EPARSE, (int64_t)g->p, "meshb: a second %s keyword",
                        what);
    st = gmf_count(g, what, (uint64_t)(k + 1) * (uint64_t)g->isz, max, n, err);
    if (st != QDC_OK)
        return st;
    *idx = qdc_mallocn((size_t)*n * (size_t)k + 1, sizeof(int32_t));
    *ref = qdc_mallocn((size_t)*n + 1, sizeof(int32_t));
    if (!*idx || !*ref)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld %s", (long long)*n,
                        what);
    if (g->isz == 4 && !g->big) { /* the usual case, at 3x the speed */
        const unsigned char *p = g->b + g->p;
        for (int64_t i = 0; i < *n; i++, p += 4 * (size_t)(k + 1)) {
            for (int j = 0; j < k; j++) {
                int32_t v = (int32_t)get_le32(p + 4 * j);
                (*idx)[i * k + j] = v < 1 ? 0 : v; /* 0: bad */
            }
            (*ref)[i] = (int32_t)get_le32(p + 4 * k);
        }
        g->p += (size_t)*n * 4 * (size_t)(k + 1);
        return QDC_OK;
    }
    for (int64_t i = 0; i < *n; i++) {
        for (int j = 0; j < k; j++) {
            int64_t v = gmf_int(g, g->isz);
            (*idx)[i * k + j] = v < 1 || v > INT32_MAX ? 0 : (int32_t)v; /* 0: bad */
        }
        (*ref)[i] = (int32_t)gmf_int(g, g->isz);
    }
    return QDC_OK;
}

/* 1-based idx[n] to 0-based within nv; at: the keyword's offset (errors). */
static qdc_status gmf_check(int32_t *idx, int64_t n, int64_t nv, const char *what,
                            size_t at, qdc_error *err)
{
    for (int64_t i = 0; i < n; i++) {
        if (idx[i] < 1 || idx[i] > nv) {
            fail_bin(err, QDC_EPARSE, (int64_t)at,
                     "meshb: %s: entry %lld: vertex number out of range [1, %lld]", what,
                     (long long)i, (long long)nv);
            set_index(err, what, i);
            return QDC_EPARSE;
        }
        idx[i]--;
    }
    return QDC_OK;
}

/* What the keywords gave, and where (errors found after the last one). */
typedef struct {
    parsed pm;
    int32_t *fix;
    size_t at_tet, at_tri, at_fix;
} gmf_mesh;

/* The header: byte order from the code word, sizes from the version. */
static qdc_status gmf_header(gmf *g, qdc_error *err)
{
    int64_t ver, code;

    if (g->len < 8)
        return fail_bin(err, QDC_EPARSE, 0, "meshb: %zu bytes, too short for a header",
                        g->len);
    code = (int64_t)gmf_word(g, 0, 4);
    if (code != 1) {
        g->big = 1;
        if (gmf_word(g, 0, 4) != 1)
            return fail_bin(err, QDC_EFORMAT, 0,
                            "not a Medit binary file: first word %lld (1 expected)",
                            (long long)code);
    }
    ver = (int64_t)gmf_word(g, 4, 4);
    if (ver < 1 || ver > 4)
        return fail_bin(err, QDC_EFORMAT, 4, "meshb: version %lld not supported (1 to 4)",
                        (long long)ver);
    g->rsz = ver == 1 ? 4 : 8;
    g->isz = ver == 4 ? 8 : 4;
    g->psz = ver >= 3 ? 8 : 4;
    g->p = 8;
    return QDC_OK;
}

/* Vertices (keyword at `at`): coordinates and refs; rec: where each is. */
static qdc_status gmf_vertices(gmf *g, parsed *pm, srcrec *rec, size_t at, qdc_error *err)
{
    int64_t n;
    qdc_status st = QDC_OK;

    if (pm->xyz)
        return fail_bin(err, QDC_EPARSE, (int64_t)at, "meshb: a second Vertices");
    st = gmf_count(g, "Vertices", 3 * (uint64_t)g->rsz + (uint64_t)g->isz,
                   MESH_MAX_VERTICES, &n, err);
    if (st != QDC_OK)
        return st;
    pm->nv = n;
    pm->xyz = qdc_mallocn(3 * (size_t)n + 1, sizeof(double));
    pm->vref = qdc_mallocn((size_t)n + 1, sizeof(int32_t));
    if (!pm->xyz || !pm->vref)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld vertices", (long long)n);
    if (rec) {
        rec->fmt = MESHIO_MESHB;
        rec->kind = SRC_BIN;
        rec->width = g->rsz;
        rec->big = g->big;
        st = srcrec_alloc(rec, n, err);
    }
    for (int64_t i = 0; i < pm->nv && st == QDC_OK; i++) {
        size_t vat = g->p;
        if (rec)
            rec->off[i] = (uint64_t)g->p;
        for (int a = 0; a < 3; a++)
            pm->xyz[3 * i + a] = gmf_real(g);
        pm->vref[i] = (int32_t)gmf_int(g, g->isz);
        if (!isfinite(pm->xyz[3 * i]) || !isfinite(pm->xyz[3 * i + 1]) ||
            !isfinite(pm->xyz[3 * i + 2])) {
            st = fail_bin(err, QDC_EPARSE, (int64_t)vat,
                          "meshb: vertex %lld: a coordinate is not finite (NaN/Inf)",
                          (long long)i + 1);
            set_index(err, "vertex", i);
        }
    }
    return st;
}

/* RequiredVertices (keyword at `at`): 1-based numbers, checked later. */
static qdc_status gmf_required(gmf *g, gmf_mesh *gm, size_t at, qdc_error *err)
{
    int64_t n;
    qdc_status st;

    gm->at_fix = at;
    if (gm->fix)
        return fail_bin(err, QDC_EPARSE, (int64_t)at, "meshb: a second RequiredVertices");
    st = gmf_count(g, "RequiredVertices", (uint64_t)g->isz, INT32_MAX, &n, err);
    if (st != QDC_OK)
        return st;
    if (!(gm->fix = qdc_mallocn((size_t)n + 1, sizeof(int32_t))))
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    for (int64_t i = 0; i < n; i++) {
        int64_t v = gmf_int(g, g->isz);
        gm->fix[i] = v < 1 || v > INT32_MAX ? 0 : (int32_t)v;
    }
    gm->pm.nfix = n;
    return QDC_OK;
}

/* Keyword kw at `at` whose next keyword is at `next`; *last when it ends
 * the file. */
static qdc_status gmf_keyword(gmf *g, gmf_mesh *gm, int64_t kw, int64_t next, size_t at,
                              srcrec *rec, int *last, qdc_error *err)
{
    parsed *pm = &gm->pm;
    int64_t dim;
    qdc_status st;

    switch (kw) {
    case GMF_DIMENSION:
        st = gmf_need(g, 4, "Dimension", err);
        if (st == QDC_OK && (dim = gmf_int(g, 4)) != 3)
            st = fail_bin(err, QDC_EFORMAT, (int64_t)at,
                          "meshb: Dimension %lld (3D meshes only)", (long long)dim);
        return st;
    case GMF_VERTICES:
        return gmf_vertices(g, pm, rec, at, err);
    case GMF_TETRAHEDRA:
        gm->at_tet = at;
        return gmf_elems(g, "Tetrahedra", 4, MESH_MAX_TETS, &pm->nt, &pm->tets,
                         &pm->region, err);
    case GMF_TRIANGLES:
        gm->at_tri = at;
        return gmf_elems(g, "Triangles", 3, INT32_MAX / 3, &pm->ntri, &pm->tris,
                         &pm->tri_ref, err);
    case GMF_TETRAHEDRA_P2: /* corners alone would break them */
        return fail_bin(err, QDC_EFORMAT, (int64_t)at,
                        "meshb: TetrahedraP2: second-order tetrahedra (10 vertices) "
                        "are not supported: qdc optimizes linear Tetrahedra");
    case GMF_REQUIRED_VERTICES:
        return gmf_required(g, gm, at, err);
    default: /* skipped through its next-keyword position */
        if (next == 0) {
            *last = 1;
            return kw < 0 || kw > 200
                       ? fail_bin(err, QDC_EPARSE, (int64_t)at,
                                  "meshb: unknown keyword %lld", (long long)kw)
                       : QDC_OK;
        }
        if (next <= (int64_t)g->p || (uint64_t)next > g->len)
            return fail_bin(err, QDC_EPARSE, (int64_t)at,
                            "meshb: keyword %lld: next position %lld out of range",
                            (long long)kw, (long long)next);
        g->p = (size_t)next;
        return QDC_OK;
    }
}

/* The keywords up to End, the last keyword or the end of the file. */
static qdc_status gmf_keywords(gmf *g, gmf_mesh *gm, srcrec *rec, qdc_error *err)
{
    int last = 0;
    qdc_status st = QDC_OK;

    while (st == QDC_OK && !last) {
        size_t at = g->p;
        int64_t kw, next;
        if (g->p == g->len)
            break; /* no End keyword: the file ends here anyway */
        st = gmf_need(g, 4, "keyword", err);
        if (st != QDC_OK)
            break;
        kw = gmf_int(g, 4);
        if (kw == GMF_END)
            break;
        st = gmf_need(g, (uint64_t)g->psz, "keyword position", err);
        if (st != QDC_OK)
            break;
        next = gmf_int(g, g->psz);
        st = gmf_keyword(g, gm, kw, next, at, rec, &last, err);
    }
    return st;
}

static qdc_status read_meshb(const char *buf, size_t len, const meshio_options *o,
                             srcrec *rec, mesh_t **out, qdc_error *err)
{
    gmf g = {(const unsigned char *)buf, len, 0, 0, 0, 0, 0};
    gmf_mesh gm;
    parsed *pm = &gm.pm;
    qdc_status st;

    (void)o; /* nothing to note: what is skipped is kept by a spliced write */
    memset(&gm, 0, sizeof gm);
    parsed_init(pm);
    st = gmf_header(&g, err);
    if (st == QDC_OK)
        st = gmf_keywords(&g, &gm, rec, err);
    if (st == QDC_OK && !pm->xyz)
        st = fail_bin(err, QDC_EPARSE, (int64_t)g.p, "meshb: no Vertices");
    if (st == QDC_OK && pm->tets)
        st = gmf_check(pm->tets, 4 * pm->nt, pm->nv, "Tetrahedra", gm.at_tet, err);
    if (st == QDC_OK && pm->tris)
        st = gmf_check(pm->tris, 3 * pm->ntri, pm->nv, "Triangles", gm.at_tri, err);
    if (st == QDC_OK && gm.fix)
        st = gmf_check(gm.fix, pm->nfix, pm->nv, "RequiredVertices", gm.at_fix, err);
    if (st == QDC_OK) {
        pm->fix = gm.fix;
        gm.fix = NULL;
        /* the arrays move into the mesh (copied, with their first touch of
         * fresh pages, they were a third of a 1M-tet read) */
        st = parsed_mesh_move(pm, out, err);
    }
    qdc_free(gm.fix);
    parsed_free(pm);
    return st;
}

static void put32(wbuf *w, int64_t v)
{
    unsigned char b[4];

    put_le32(b, (uint32_t)(int32_t)v);
    wb_put(w, b, 4);
}

/* Version 2, little-endian: Dimension, Vertices, Triangles, Tetrahedra,
 * RequiredVertices (the fixed vertices), End. */
static qdc_status write_meshb(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                              qdc_error *err)
{
    (void)fmt;
    (void)part;
    (void)err;
    int64_t pos = 8, nfix = 0;
    int with_fix = m->fixed != NULL; /* even with none set: read back the same */

    for (int32_t i = 0; m->fixed && i < m->nv; i++)
        nfix += m->fixed[i] != 0;
    put32(w, 1);
    put32(w, 2);
    pos += 12;
    put32(w, GMF_DIMENSION);
    put32(w, pos);
    put32(w, 3);
    pos += 12 + 28 * (int64_t)m->nv;
    put32(w, GMF_VERTICES);
    put32(w, pos);
    put32(w, m->nv);
    for (int32_t i = 0; i < m->nv; i++) {
        unsigned char b[24];
        for (int a = 0; a < 3; a++) {
            uint64_t u;
            memcpy(&u, &m->xyz[3 * (size_t)i + (size_t)a], 8);
            put_le64(b + 8 * a, u);
        }
        wb_put(w, b, 24);
        put32(w, m->vref ? m->vref[i] : 0);
    }
    if (m->ntri) {
        pos += 12 + 16 * (int64_t)m->ntri;
        put32(w, GMF_TRIANGLES);
        put32(w, pos);
        put32(w, m->ntri);
        for (int32_t t = 0; t < m->ntri; t++) {
            for (int k = 0; k < 3; k++)
                put32(w, (int64_t)m->tris[3 * (size_t)t + (size_t)k] + 1);
            put32(w, m->tri_ref ? m->tri_ref[t] : 0);
        }
    }
    pos += 12 + 20 * (int64_t)m->nt;
    put32(w, GMF_TETRAHEDRA);
    put32(w, pos);
    put32(w, m->nt);
    for (int32_t t = 0; t < m->nt; t++) {
        for (int k = 0; k < 4; k++)
            put32(w, (int64_t)m->tets[4 * (size_t)t + (size_t)k] + 1);
        put32(w, m->region ? m->region[t] : 0);
    }
    if (with_fix) {
        pos += 12 + 4 * nfix;
        put32(w, GMF_REQUIRED_VERTICES);
        put32(w, pos);
        put32(w, nfix);
        for (int32_t i = 0; i < m->nv; i++)
            if (m->fixed[i])
                put32(w, (int64_t)i + 1);
    }
    put32(w, GMF_END);
    put32(w, 0);
    return QDC_OK;
}

/* The int32 words 1 (the byte order), 1..4 (the version), 3 (the
 * dimension's keyword) in either byte order. */
static meshio_format sniff_meshb(const char *buf, size_t len, size_t i)
{
    const unsigned char *b = (const unsigned char *)buf;

    (void)i;
    if (len >= 12 &&
        ((get_le32(b) == 1 && get_le32(b + 4) - 1 < 4 && get_le32(b + 8) == 3) ||
         (memcmp(buf, "\0\0\0\1\0\0\0", 7) == 0 && buf[7] >= 1 && buf[7] <= 4 &&
          memcmp(buf + 8, "\0\0\0\3", 4) == 0)))
        return MESHIO_MESHB;
    return MESHIO_AUTO;
}

const meshio_fmt fmt_meshb = {
    .name = "meshb",
    .aliases = "medit-bin",
    .about = "Medit binary .meshb (libMeshb versions 1-4, either byte order; written: "
             "version 2 little-endian)",
    .ext = "meshb",
    .input = "input.meshb",
    .magic = 1,
    .sniff = sniff_meshb,
    .read = read_meshb,
    .write = write_meshb,
    .splices = 1,
};
