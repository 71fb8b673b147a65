/* meshio_vtk.c - VTK legacy .vtk (ASCII and binary UNSTRUCTURED_GRID, the
 * 4.2 cell list and the 5.1 OFFSETS/CONNECTIVITY layouts) and VTK XML .vtu
 * (ascii, inline base64 and appended raw/base64 DataArrays, no compression).
 *
 * Reference: "VTK File Formats" (VTK User's Guide, ch. 19 and the 5.1 notes).
 * Coordinates and offsets are read into doubles (integers up to 2^53 are
 * exact, floats widen exactly), connectivity, cell types, regions and vertex
 * refs straight into int32s (see iarr), so one reader serves all value types
 * and encodings; indices, offsets and cell types are then checked to be
 * integers in range. Cells of type 10 become tets and of type 5 surface
 * triangles, others are skipped and counted for a note. The region is the cell array
 * "region", "gmsh:physical", "medit:ref" or "MeshDomain" (CGAL's subdomain index, as
 * Float64; in that order of preference), vref the point array "medit:ref", the other
 * point arrays point data (mesh_t.pdata, as doubles; written back as a FIELD of the
 * POINT_DATA and as <PointData> DataArrays). Legacy binary
 * data are big-endian; XML data follow byte_order. */
#include "io/format.h"
#include "io/gz.h"

#include <limits.h>
#include <zlib.h>

typedef enum { T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_I64, T_U64, T_F32, T_F64 } vtype;

static const int vsize[] = {1, 1, 2, 2, 4, 4, 8, 8, 4, 8};

/* A text value of a float32 array (VTK `float`, VTU Float32) as the float32
 * it stands for, as a binary one is, so that a file reads the same whatever
 * the digits its writer gave (qdc writes 9: splice.c); 1 if a finite value
 * is out of float32's range. */
static int text_f32(double *x)
{
    float f = (float)*x;

    if (isfinite(*x) && !isfinite(f))
        return 1;
    *x = (double)f;
    return 0;
}

static const struct {
    const char *name;
    vtype t;
} vtype_names[] = {
    {"Int8", T_I8},          {"UInt8", T_U8},
    {"Int16", T_I16},        {"UInt16", T_U16},
    {"Int32", T_I32},        {"UInt32", T_U32},
    {"Int64", T_I64},        {"UInt64", T_U64},
    {"Float32", T_F32},      {"Float64", T_F64},
    {"char", T_I8},          {"unsigned_char", T_U8},
    {"short", T_I16},        {"unsigned_short", T_U16},
    {"int", T_I32},          {"unsigned_int", T_U32},
    {"long", T_I64},         {"unsigned_long", T_U64},
    {"float", T_F32},        {"double", T_F64},
    {"vtktypeint64", T_I64}, {"vtktypeuint64", T_U64},
    {"vtktypeint32", T_I32}, {"vtktypeuint32", T_U32},
    {"vtkIdType", T_I64},
};

static int vtype_of(const char *w, size_t n, vtype *t)
{
    for (size_t i = 0; i < sizeof vtype_names / sizeof vtype_names[0]; i++)
        if (word_is(w, n, vtype_names[i].name)) {
            *t = vtype_names[i].t;
            return 0;
        }
    return -1;
}

/* The VTU name of a type ("Int32"...). */
static const char *vtk_type_name(vtype t)
{
    for (size_t i = 0; i < sizeof vtype_names / sizeof vtype_names[0]; i++)
        if (vtype_names[i].t == t)
            return vtype_names[i].name;
    return "";
}

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
enum { HOST_BIG = 1 };
#else
enum { HOST_BIG = 0 };
#endif

/* Unaligned loads of 2, 4 and 8 bytes, byte-swapped if swap. */
static inline uint16_t ld16(const unsigned char *b, int swap)
{
    uint16_t u;

    memcpy(&u, b, 2);
    return swap ? __builtin_bswap16(u) : u;
}

static inline uint32_t ld32(const unsigned char *b, int swap)
{
    uint32_t u;

    memcpy(&u, b, 4);
    return swap ? __builtin_bswap32(u) : u;
}

static inline uint64_t ld64(const unsigned char *b, int swap)
{
    uint64_t u;

    memcpy(&u, b, 8);
    return swap ? __builtin_bswap64(u) : u;
}

static inline double f32_of(uint32_t u)
{
    float f;

    memcpy(&f, &u, 4);
    return f;
}

static inline double f64_of(uint64_t u)
{
    double d;

    memcpy(&d, &u, 8);
    return d;
}

/* One loop per type and byte order, so each is a plain (vectorizable) load,
 * swap and convert. */
#define DECODE(EXPR)                                                                     \
    do {                                                                                 \
        for (int64_t i = 0; i < n; i++)                                                  \
            out[i] = (EXPR);                                                             \
    } while (0)

/* The loop for each type: NARROW for the types whose values are all int32s,
 * WIDE for the others (each given the value of element i of b). */
#define DECODE_EACH_TYPE(NARROW, WIDE)                                                   \
    switch (t) {                                                                         \
    case T_I8:                                                                           \
        NARROW((int8_t)b[i]);                                                            \
        break;                                                                           \
    case T_U8:                                                                           \
        NARROW(b[i]);                                                                    \
        break;                                                                           \
    case T_I16:                                                                          \
        NARROW((int16_t)ld16(b + 2 * i, swap));                                          \
        break;                                                                           \
    case T_U16:                                                                          \
        NARROW(ld16(b + 2 * i, swap));                                                   \
        break;                                                                           \
    case T_I32:                                                                          \
        NARROW((int32_t)ld32(b + 4 * i, swap));                                          \
        break;                                                                           \
    case T_U32:                                                                          \
        WIDE(ld32(b + 4 * i, swap));                                                     \
        break;                                                                           \
    case T_I64:                                                                          \
        WIDE((double)(int64_t)ld64(b + 8 * i, swap));                                    \
        break;                                                                           \
    case T_U64:                                                                          \
        WIDE((double)ld64(b + 8 * i, swap));                                             \
        break;                                                                           \
    case T_F32:                                                                          \
        WIDE(f32_of(ld32(b + 4 * i, swap)));                                             \
        break;                                                                           \
    case T_F64:                                                                          \
        WIDE(f64_of(ld64(b + 8 * i, swap)));                                             \
        break;                                                                           \
    }

static inline __attribute__((always_inline)) void
decode_swap(const unsigned char *b, int64_t n, vtype t, int swap, double *out)
{
    DECODE_EACH_TYPE(DECODE, DECODE)
}

/* n values of type t from bytes b (big-endian if big) into out. The swap
 * flag is a constant in each call so the compiler keeps two loops. */
static void decode_values(const unsigned char *b, int64_t n, vtype t, int big,
                          double *out)
{
    if (big != HOST_BIG)
        decode_swap(b, n, t, 1, out);
    else
        decode_swap(b, n, t, 0, out);
}

/* x is an integer in [lo, hi], bounds within int32 (NaN is not). */
static inline int int_in(double x, double lo, double hi)
{
    return x >= lo && x <= hi && (double)(int32_t)x == x;
}

static inline int is_int32(double x)
{
    return int_in(x, INT32_MIN, INT32_MAX);
}

/* An integer array (connectivity, cell types, regions, vertex refs) as
 * int32s, without a double array in between: a value that is not an int32
 * (1.5, 3e9, from a float or 64-bit type or text) is INT32_MIN in v, outside
 * every range checked, and its double is in odd (in index order) for the
 * message that names it. */
typedef struct {
    int64_t i;
    double x;
} oddval;

typedef struct {
    int32_t *v;
    int64_t n;
    oddval *odd;
    size_t nodd, cap;
} iarr;

static void iarr_free(iarr *a)
{
    qdc_free(a->v);
    qdc_free(a->odd);
    memset(a, 0, sizeof *a);
}

static qdc_status iarr_alloc(iarr *a, int64_t n, qdc_error *err)
{
    iarr_free(a);
    a->v = qdc_mallocn((size_t)n + 1, sizeof(int32_t));
    a->n = n;
    if (!a->v)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld values", (long long)n);
    return QDC_OK;
}

/* Value i is x, which is not an int32: -1 if out of memory. */
static int odd_put(iarr *a, int64_t i, double x)
{
    if (a->nodd == a->cap) {
        size_t cap = a->cap ? 2 * a->cap : 16;
        oddval *o = qdc_realloc(a->odd, cap * sizeof *o);
        if (!o)
            return -1;
        a->odd = o;
        a->cap = cap;
    }
    a->odd[a->nodd].i = i;
    a->odd[a->nodd++].x = x;
    a->v[i] = INT32_MIN;
    return 0;
}

/* Value i as the double it was read as. */
static double iarr_at(const iarr *a, int64_t i)
{
    size_t lo = 0, hi = a->nodd;

    if (a->v[i] != INT32_MIN)
        return a->v[i];
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (a->odd[mid].i < i)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < a->nodd && a->odd[lo].i == i ? a->odd[lo].x : INT32_MIN;
}

/* Value i is an int32 (an INT32_MIN read as such is one). */
static inline int iarr_ok(const iarr *a, int64_t i)
{
    return a->v[i] != INT32_MIN || is_int32(iarr_at(a, i));
}

/* Value i from the double x: -1 if out of memory. */
static inline int iarr_put(iarr *a, int64_t i, double x)
{
    if (!is_int32(x))
        return odd_put(a, i, x);
    a->v[i] = (int32_t)x;
    return 0;
}

/* One loop per type and byte order, as in decode_swap: types whose every
 * value is an int32 store it; the others go through a double, checked to be
 * finite (the first that is not ends the loop). */
#define DECODE_INT(EXPR)                                                                 \
    do {                                                                                 \
        for (int64_t i = 0; i < n; i++)                                                  \
            v[i] = (EXPR);                                                               \
    } while (0)
#define DECODE_WIDE(EXPR)                                                                \
    do {                                                                                 \
        for (int64_t i = 0; i < n; i++) {                                                \
            double x = (EXPR);                                                           \
            if (is_int32(x))                                                             \
                v[i] = (int32_t)x;                                                       \
            else if (!isfinite(x))                                                       \
                return i;                                                                \
            else if (odd_put(a, i, x) != 0)                                              \
                return -1;                                                               \
        }                                                                                \
    } while (0)

static inline __attribute__((always_inline)) int64_t
decode_int_swap(const unsigned char *b, int64_t n, vtype t, int swap, iarr *a)
{
    int32_t *v = a->v;

    DECODE_EACH_TYPE(DECODE_INT, DECODE_WIDE)
    return n;
}

/* n values of type t from bytes b (big-endian if big) into a (room for n):
 * the index of the first that is not finite, n if none, -1 if out of
 * memory. */
static int64_t decode_ints(const unsigned char *b, int64_t n, vtype t, int big, iarr *a)
{
    return big != HOST_BIG ? decode_int_swap(b, n, t, 1, a)
                           : decode_int_swap(b, n, t, 0, a);
}

/* Where a reader puts the values of an array: doubles (d) or an iarr (a). */
typedef struct {
    double *d;
    iarr *a;
} vsink;

/* n values of type t from bytes b into k: the index of the first that is
 * not finite, n if none, -1 if out of memory. */
static int64_t sink_decode(vsink *k, const unsigned char *b, int64_t n, vtype t, int big)
{
    int64_t i = 0;

    if (k->a)
        return decode_ints(b, n, t, big, k->a);
    decode_values(b, n, t, big, k->d);
    while (i < n && isfinite(k->d[i]))
        i++;
    return i;
}

/* Value i is x: -1 if out of memory. */
static inline int sink_put(vsink *k, int64_t i, double x)
{
    if (k->a)
        return iarr_put(k->a, i, x);
    k->d[i] = x;
    return 0;
}

/* ------------------------------------------------------------------------ */
/* From arrays to a mesh (both formats)                                      */

enum { PRIO_NONE = 99 };

/* Cell and point arrays a reader collected (an iarr's v is NULL until
 * read). */
typedef struct {
    int64_t nv, nc;
    double *xyz; /* 3 nv */
    iarr conn;   /* connectivity */
    int64_t nconn;
    double *offs;   /* nc + 1 offsets into conn, or NULL for the legacy list */
    iarr types;     /* nc cell types */
    iarr creg;      /* nc region values, or none */
    int creg_prio;  /* 0 region, 1 gmsh:physical, 2 medit:ref, 3 MeshDomain */
    iarr vref;      /* nv, or none */
    mesh_pdata *pd; /* the other point arrays, or NULL */
    const meshio_options *o;
} cells;

static void cells_free(cells *c)
{
    qdc_free(c->xyz);
    iarr_free(&c->conn);
    qdc_free(c->offs);
    iarr_free(&c->types);
    iarr_free(&c->creg);
    iarr_free(&c->vref);
    mesh_pdata_free(c->pd);
    c->pd = NULL;
}

static int region_prio(const char *name, size_t n)
{
    static const char *const names[] = {"region", "gmsh:physical", "medit:ref",
                                        "MeshDomain"};

    for (int i = 0; i < 4; i++)
        if (strlen(names[i]) == n && memcmp(name, names[i], n) == 0)
            return i;
    return PRIO_NONE;
}

/* Where cell i's points are: conn[*a .. *a + *k). The legacy list (no
 * offsets) is walked with *pos. -1 if the list ends inside a cell. */
static int cell_span(const cells *c, int64_t i, int64_t *pos, int64_t *a, int64_t *k)
{
    int32_t kd;

    if (c->offs) {
        *a = (int64_t)c->offs[i];
        *k = (int64_t)c->offs[i + 1] - *a;
        return 0;
    }
    if (*pos >= c->nconn)
        return -1;
    kd = c->conn.v[*pos];
    if (kd == 4) /* the common sizes as constants: the next cell's position */
        *k = 4;  /* is predicted, not waited for */
    else if (kd == 3)
        *k = 3;
    else if (kd >= 0) /* not an odd value (INT32_MIN) */
        *k = kd;
    else
        return -1;
    *a = *pos + 1;
    *pos = *a + *k;
    return *pos > c->nconn ? -1 : 0;
}

/* Cell i (a tet or triangle of k points at conn[a]): every point index in
 * range. */
static qdc_status check_points(const cells *c, const char *fmtname, int64_t i, int64_t a,
                               int64_t k, qdc_error *err)
{
    for (int64_t j = 0; j < k; j++) {
        int32_t v = c->conn.v[a + j];
        if (v < 0 || v >= c->nv) {
            qdc_fail(err, QDC_EPARSE,
                     "%s: cell %lld: point index %.17g out of range [0, %lld]", fmtname,
                     (long long)i, iarr_at(&c->conn, a + j), (long long)c->nv - 1);
            set_index(err, "cell", i);
            return QDC_EPARSE;
        }
    }
    return QDC_OK;
}

/* Cell i is a tet of the other order than those before it. */
static qdc_status mixed_order(const char *fmtname, int64_t i, qdc_error *err)
{
    qdc_fail(err, QDC_EFORMAT,
             "%s: cell %lld: linear (type 10) and second-order (type 24) tetrahedra in "
             "one file are not supported",
             fmtname, (long long)i);
    set_index(err, "cell", i);
    return QDC_EFORMAT;
}

/* Room for the cells a walk keeps: tets and triangles, at most nc of each
 * (the limits' worth), their regions; mid-edge nodes once a second-order tet
 * is seen. Pages the walk never writes are never touched. */
typedef struct {
    int64_t tcap, tricap;
} cells_room;

static qdc_status cells_alloc(const cells *c, parsed *pm, cells_room *r, qdc_error *err)
{
    r->tcap = c->nc < MESH_MAX_TETS ? c->nc : MESH_MAX_TETS;
    r->tricap = c->nc < INT32_MAX / 3 ? c->nc : INT32_MAX / 3;
    pm->tets = qdc_mallocn((size_t)r->tcap * 4 + 1, sizeof(int32_t));
    pm->tris = qdc_mallocn((size_t)r->tricap * 3 + 1, sizeof(int32_t));
    if (c->creg.v) {
        pm->region = qdc_mallocn((size_t)r->tcap + 1, sizeof(int32_t));
        pm->tri_ref = qdc_mallocn((size_t)r->tricap + 1, sizeof(int32_t));
    }
    if (!pm->tets || !pm->tris || (c->creg.v && (!pm->region || !pm->tri_ref)))
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld cells",
                        (long long)c->nc);
    return QDC_OK;
}

/* One walk over the cells: every check, the counts of tets and triangles
 * (*nt, *ntri) and skipped types (sk), and the kept cells' points and regions
 * into fill (arrays from cells_alloc; cells past their room are counted, not
 * stored: the caller then fails on the limit). */
static qdc_status cells_walk(const cells *c, const char *fmtname, parsed *fill,
                             const cells_room *r, skipped *sk, int64_t *nt, int64_t *ntri,
                             int64_t *n10, qdc_error *err)
{
    int64_t pos = 0, n4 = 0, n3 = 0, nq = 0;

    for (int64_t i = 0; i < c->nc; i++) {
        int64_t a, k, type;
        if (cell_span(c, i, &pos, &a, &k) != 0)
            return qdc_fail(err, QDC_EPARSE,
                            "%s: CELLS list ends inside a cell (wrong counts)", fmtname);
        type = c->types.v[i]; /* an odd value is INT32_MIN: skipped as negative */
        /* VTK_QUADRATIC_TETRA (24) and a Lagrange tetra (71) of order 2 list
         * their mid-edge nodes in the order of mesh_p2_edges */
        if ((type == 24 || type == 71) && k == 10) {
            if (n4 > nq)
                return mixed_order(fmtname, i, err);
            if (!fill->mid) { /* the first tet: all are second-order */
                fill->mid = qdc_mallocn((size_t)r->tcap * 6 + 1, sizeof(int32_t));
                if (!fill->mid)
                    return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld cells",
                                    (long long)c->nc);
            }
            k = 4;
            nq++;
        } else if (type == 24 || type == 71) { /* corners alone would break them */
            qdc_fail(
                err, QDC_EFORMAT,
                "%s: cell %lld is a %s tetrahedron (VTK cell type %lld, %lld points): "
                "not supported, qdc optimizes linear (type 10) and second-order (type "
                "24, 10 points) tetrahedra",
                fmtname, (long long)i, type == 24 ? "second-order" : "Lagrange",
                (long long)type, (long long)k);
            set_index(err, "cell", i);
            return QDC_EFORMAT;
        } else if (type == 10 && nq) {
            return mixed_order(fmtname, i, err);
        } else if (!((type == 10 && k == 4) || (type == 5 && k == 3))) {
            skip_count(sk, type, 1);
            continue;
        }
        if (check_points(c, fmtname, i, a, nq && k == 4 ? 10 : k, err) != QDC_OK)
            return QDC_EPARSE;
        if (c->creg.v && !iarr_ok(&c->creg, i)) {
            qdc_fail(err, QDC_EPARSE, "%s: cell %lld: region %.17g is not an int32",
                     fmtname, (long long)i, iarr_at(&c->creg, i));
            set_index(err, "cell", i);
            return QDC_EPARSE;
        }
        if (k == 4 ? n4 < r->tcap : n3 < r->tricap) {
            int32_t *dst = k == 4 ? fill->tets + 4 * n4 : fill->tris + 3 * n3;
            memcpy(dst, c->conn.v + a, (size_t)k * sizeof(int32_t));
            if (nq && k == 4)
                memcpy(fill->mid + 6 * n4, c->conn.v + a + 4, 6 * sizeof(int32_t));
            if (c->creg.v)
                *(k == 4 ? &fill->region[n4] : &fill->tri_ref[n3]) = c->creg.v[i];
        }
        if (k == 4)
            n4++;
        else
            n3++;
    }
    *nt = n4;
    *ntri = n3;
    *n10 = nq;
    return QDC_OK;
}

/* *p (n32 int32s' room) cut to n used ones; kept as is if that fails. */
static void shrink32(int32_t **p, int64_t n)
{
    int32_t *q = *p ? qdc_realloc(*p, ((size_t)n + 1) * sizeof(int32_t)) : NULL;
    if (q)
        *p = q;
}

/* The point array medit:ref, if any, as vertex refs (moved into pm). */
static qdc_status cells_vref(cells *c, const char *fmtname, parsed *pm, qdc_error *err)
{
    if (!c->vref.v)
        return QDC_OK;
    if (c->vref.n != c->nv) /* POINT_DATA 0 before the POINTS */
        return qdc_fail(err, QDC_EPARSE, "%s: medit:ref has %lld values for %lld points",
                        fmtname, (long long)c->vref.n, (long long)c->nv);
    if (c->vref.nodd) { /* the first value that is not an int32 */
        int64_t i = c->vref.odd[0].i;
        qdc_fail(err, QDC_EPARSE, "%s: point %lld: medit:ref %.17g is not an int32",
                 fmtname, (long long)i, c->vref.odd[0].x);
        set_index(err, "vertex", i);
        return QDC_EPARSE;
    }
    pm->vref = c->vref.v;
    c->vref.v = NULL;
    return QDC_OK;
}

static qdc_status cells_mesh(cells *c, const char *fmtname, const meshio_options *o,
                             mesh_t **out, qdc_error *err)
{
    parsed pm;
    skipped sk;
    cells_room room;
    int64_t nt = 0, ntri = 0, n10 = 0;
    qdc_status st;

    memset(&sk, 0, sizeof sk);
    parsed_init(&pm);
    if (!c->types.v && c->nc)
        return qdc_fail(err, QDC_EPARSE, "%s: no cell types", fmtname);
    if (c->creg.v && c->creg.n != c->nc) /* CELL_DATA 0 before the CELLS */
        return qdc_fail(err, QDC_EPARSE,
                        "%s: the region array has %lld values for %lld cells", fmtname,
                        (long long)c->creg.n, (long long)c->nc);
    st = cells_alloc(c, &pm, &room, err);
    if (st == QDC_OK)
        st = cells_walk(c, fmtname, &pm, &room, &sk, &nt, &ntri, &n10, err);
    if (st == QDC_OK && (nt > MESH_MAX_TETS || ntri > INT32_MAX / 3))
        st = qdc_fail(err, QDC_ETOOBIG, "%s: %lld tets exceed the limit", fmtname,
                      (long long)nt);
    if (st == QDC_OK) {
        shrink32(&pm.tets, 4 * nt);
        shrink32(&pm.tris, 3 * ntri);
        shrink32(&pm.region, nt);
        shrink32(&pm.tri_ref, ntri);
        shrink32(&pm.mid, n10 ? 6 * nt : 0);
    }
    if (st == QDC_OK)
        st = cells_vref(c, fmtname, &pm, err);
    if (st == QDC_OK) {
        pm.nv = c->nv;
        pm.xyz = c->xyz;
        pm.nt = nt;
        pm.ntri = ntri;
        if (!ntri) {
            qdc_free(pm.tri_ref);
            pm.tri_ref = NULL;
        }
        c->xyz = NULL; /* moves into the mesh */
        st = parsed_mesh_move(&pm, out, err);
        if (st == QDC_OK) {
            (*out)->pdata = c->pd;
            c->pd = NULL;
        }
    }
    parsed_free(&pm);
    if (st == QDC_OK)
        skip_note(o, &sk, fmtname, "cells");
    return st;
}

/* Offsets of the 5.1 / XML layout: nc+1 non-decreasing integers within
 * [0, nconn], with a leading 0 added for XML (which stores the ends only). */
static qdc_status check_offsets(const double *offs, int64_t nc, int64_t nconn,
                                const char *fmtname, qdc_error *err)
{
    for (int64_t i = 0; i <= nc; i++) {
        double o = offs[i];
        if (!(o >= 0 && o <= (double)nconn && (double)(int64_t)o == o &&
              (i == 0 || o >= offs[i - 1]))) {
            qdc_fail(err, QDC_EPARSE,
                     "%s: cell offset %lld (%.17g) is not within [%s, %lld]", fmtname,
                     (long long)i, o, i ? "previous" : "0", (long long)nconn);
            set_index(err, "cell", i);
            return QDC_EPARSE;
        }
    }
    return QDC_OK;
}

/* ------------------------------------------------------------------------ */
/* Legacy reader                                                             */

typedef struct {
    txt s;
    const unsigned char *b;
    int binary;
    cells c;
    int attr;       /* 0 none, 1 CELL_DATA, 2 POINT_DATA */
    int64_t attr_n; /* its count */
    srcrec *rec;    /* where the coordinates are, or NULL */
    uint64_t *voff; /* while reading POINTS with rec: where each vertex starts */
} vtk;

/* The next word into (w, n); n = 0 at the end of input. */
static void next_word(vtk *v, const char **w, size_t *n)
{
    skip_ws(&v->s);
    *w = v->s.p;
    *n = (size_t)(tok_end(&v->s, v->s.p) - v->s.p);
    v->s.p += *n;
}

/* Is the next line's first word `kw`? Consumed if so; nothing is skipped
 * otherwise (binary data may follow). */
static int next_is(vtk *v, const char *kw)
{
    txt save = v->s;
    const char *w;
    size_t n;

    next_word(v, &w, &n);
    if (word_is(w, n, kw))
        return 1;
    v->s = save;
    return 0;
}

/* Binary data start right after the newline ending the keyword line. */
static qdc_status data_start(vtk *v, qdc_error *err)
{
    txt *s = &v->s;
    char q[32];

    if (!v->binary)
        return QDC_OK;
    while (s->p < s->end && (*s->p == ' ' || *s->p == '\t' || *s->p == '\r'))
        s->p++;
    if (s->p == s->end || *s->p != '\n')
        return fail_txt(err, QDC_EPARSE, s, s->p, "expected the end of the line, got %s",
                        quote_tok(q, s, s->p, tok_end(s, s->p)));
    s->p++;
    s->line++;
    s->bol = s->p;
    return QDC_OK;
}

/* n values of type t; into out if not NULL (else checked and dropped).
 * finite: NaN/Inf are errors. */
static qdc_status vtk_values(vtk *v, const char *what, int64_t n, vtype t, int finite,
                             vsink *out, qdc_error *err)
{
    txt *s = &v->s;
    qdc_status st = data_start(v, err);

    if (st != QDC_OK)
        return st;
    if (v->binary) {
        size_t left = (size_t)(s->end - s->p), off = (size_t)(s->p - s->base);
        if ((uint64_t)n > left / (uint64_t)vsize[t])
            return fail_bin(
                err, QDC_EPARSE, (int64_t)off,
                "%s: %lld values of %d bytes do not fit in the %zu bytes left", what,
                (long long)n, vsize[t], left);
        for (int64_t i = 0; v->voff && i < n; i += 3)
            v->voff[i / 3] = off + (uint64_t)i * (uint64_t)vsize[t];
        if (out) {
            int64_t i = sink_decode(out, v->b + off, n, t, 1);
            if (i < 0)
                return qdc_fail(err, QDC_ENOMEM, "out of memory for %s", what);
            if (finite && i < n)
                return fail_bin(
                    err, QDC_EPARSE, (int64_t)(off + (size_t)i * (size_t)vsize[t]),
                    "%s: value %lld is not finite (NaN/Inf)", what, (long long)i);
        }
        s->p += (size_t)n * (size_t)vsize[t];
        return QDC_OK;
    }
    for (int64_t i = 0; i < n; i++) {
        double x;
        const char *te;
        char q[32];
        int64_t u;
        if (out && out->a && txt_uint_fast(s, 0, INT32_MAX, &u)) {
            out->a->v[i] = (int32_t)u; /* what parse_double would give */
            continue;
        }
        skip_ws(s);
        te = tok_end(s, s->p);
        if (v->voff && i % 3 == 0)
            v->voff[i / 3] = (uint64_t)(s->p - s->base);
        if (finite) {
            const char *at = s->p;
            st = tok_real(s, s->p, te, what, &x, err);
            if (st != QDC_OK)
                return st;
            if (t == T_F32 && text_f32(&x))
                return fail_txt(err, QDC_EPARSE, s, at, "%s: %s is out of float's range",
                                what, quote_tok(q, s, at, te));
        } else {
            if (s->p == te || parse_double(s->p, te, &x) != 0)
                return fail_txt(err, QDC_EPARSE, s, s->p, "%s: expected a number, got %s",
                                what, quote_tok(q, s, s->p, te));
            if (t == T_F32 && text_f32(&x))
                return fail_txt(err, QDC_EPARSE, s, s->p,
                                "%s: %s is out of float's range", what,
                                quote_tok(q, s, s->p, te));
            s->p = te;
        }
        if (out && sink_put(out, i, x) != 0)
            return qdc_fail(err, QDC_ENOMEM, "out of memory for %s", what);
    }
    return QDC_OK;
}

/* A count on a keyword line, checked against the bytes left for `per` values
 * of at least `minsz` bytes (binary) or 2 (text) each. */
static qdc_status vtk_count(vtk *v, const char *what, uint64_t per, int64_t max,
                            int64_t *c, qdc_error *err)
{
    qdc_status st = txt_count(&v->s, what, 1, max, c, err);

    if (st == QDC_OK && per > 1)
        st = txt_fits(&v->s, v->s.p, what, *c, per, err);
    return st;
}

/* n values of type t can still follow: vsize bytes each in binary, a digit
 * and a separator in text. */
static qdc_status vtk_fits(vtk *v, const char *what, int64_t n, vtype t, qdc_error *err)
{
    size_t left = (size_t)(v->s.end - v->s.p);

    if ((uint64_t)n > left / (v->binary ? (size_t)vsize[t] : 2))
        return fail_txt(err, QDC_EPARSE, &v->s, v->s.p,
                        "%s: %lld values do not fit in the %zu bytes left (truncated?)",
                        what, (long long)n, left);
    return QDC_OK;
}

static qdc_status vtk_type(vtk *v, const char *what, vtype *t, qdc_error *err)
{
    const char *w;
    size_t n;
    char q[32];

    next_word(v, &w, &n);
    if (!n || vtype_of(w, n, t) != 0)
        return fail_txt(err, QDC_EPARSE, &v->s, w, "%s: unknown data type %s", what,
                        quote_tok(q, &v->s, w, w + n));
    return QDC_OK;
}

static double *alloc_values(int64_t n, qdc_error *err)
{
    double *a = qdc_mallocn((size_t)n + 1, sizeof(double));

    if (!a)
        qdc_fail(err, QDC_ENOMEM, "out of memory for %lld values", (long long)n);
    return a;
}

/* 1 if a type holds integers. */
static int vtype_int(vtype t)
{
    return t != T_F32 && t != T_F64;
}

/* A point array of the POINTS' count (not medit:ref): its values as doubles
 * into c->pd (a NaN/Inf one dropped with a note). */
static qdc_status vtk_point_array(vtk *v, const char *name, size_t nlen, int64_t ncomp,
                                  vtype t, qdc_error *err)
{
    int64_t n = v->attr_n * ncomp;
    double *d = alloc_values(n, err);
    vsink k = {d, NULL};
    qdc_status st;

    if (!d)
        return QDC_ENOMEM;
    st = vtk_values(v, "attribute", n, t, 0, &k, err);
    if (st != QDC_OK) {
        qdc_free(d);
        return st;
    }
    return pdata_take(&v->c.pd, v->c.nv, name, nlen, ncomp, vtype_int(t),
                      vtk_type_name(t), d, v->c.o, v->binary ? "vtk" : "vtk-ascii", err);
}

/* An attribute array of v->attr_n tuples of ncomp values: kept if it is a
 * region (cells), medit:ref (points) with one component, or another point
 * array (point data, when the POINTS came first). */
static qdc_status vtk_attr_array(vtk *v, const char *name, size_t nlen, int64_t ncomp,
                                 vtype t, qdc_error *err)
{
    int prio = v->attr == 1 && ncomp == 1 ? region_prio(name, nlen) : PRIO_NONE;
    int vref = v->attr == 2 && ncomp == 1 && region_prio(name, nlen) == 2;
    int keep = prio < v->c.creg_prio || vref;
    iarr dst;
    vsink k = {NULL, &dst};
    int64_t n = v->attr_n * ncomp;
    qdc_status st;

    memset(&dst, 0, sizeof dst);
    if (ncomp && (uint64_t)v->attr_n > (uint64_t)(v->s.end - v->s.p) / (uint64_t)ncomp)
        return fail_txt(err, QDC_EPARSE, &v->s, v->s.p,
                        "%.*s: %lld tuples do not fit in the bytes left",
                        (int)(nlen > 32 ? 32 : nlen), name, (long long)v->attr_n);
    if (!keep && v->attr == 2 && nlen && ncomp >= 1 && v->c.xyz && v->attr_n == v->c.nv)
        return vtk_point_array(v, name, nlen, ncomp, t, err);
    if (keep && iarr_alloc(&dst, n, err) != QDC_OK)
        return QDC_ENOMEM;
    st = vtk_values(v, "attribute", n, t, keep, keep ? &k : NULL, err);
    if (st != QDC_OK || !keep) {
        iarr_free(&dst);
        return st;
    }
    if (vref) {
        iarr_free(&v->c.vref);
        v->c.vref = dst;
    } else {
        iarr_free(&v->c.creg);
        v->c.creg = dst;
        v->c.creg_prio = prio;
    }
    return QDC_OK;
}

static qdc_status vtk_points(vtk *v, const char *w, qdc_error *err)
{
    vtype t;
    qdc_status st;

    if (v->c.xyz)
        return fail_txt(err, QDC_EPARSE, &v->s, w, "duplicate POINTS");
    st = vtk_count(v, "POINTS", 3, MESH_MAX_VERTICES, &v->c.nv, err);
    if (st == QDC_OK)
        st = vtk_type(v, "POINTS", &t, err);
    if (st == QDC_OK && !(v->c.xyz = alloc_values(3 * v->c.nv, err)))
        st = QDC_ENOMEM;
    if (st == QDC_OK && v->rec) {
        srcrec *r = v->rec;
        r->fmt = v->binary ? MESHIO_VTK : MESHIO_VTK_ASCII;
        r->kind = v->binary ? SRC_BIN : SRC_TEXT;
        r->width = vsize[t];
        r->big = 1;
        if (t != T_F32 && t != T_F64)
            srcrec_refuse(r, "POINTS of an integer type");
        st = srcrec_alloc(r, v->c.nv, err);
        v->voff = r->off;
    }
    if (st == QDC_OK) {
        vsink k = {v->c.xyz, NULL};
        st = vtk_values(v, "POINTS: coordinate", 3 * v->c.nv, t, 1, &k, err);
    }
    v->voff = NULL;
    return st;
}

/* The 5.1 layout after "CELLS c c2": OFFSETS (c values) and the
 * CONNECTIVITY keyword line; *t the connectivity's type. */
static qdc_status vtk_offsets51(vtk *v, const char *w, int64_t c, vtype *t,
                                qdc_error *err)
{
    txt *s = &v->s;
    const char *tw;
    size_t tn;
    char q[32];
    qdc_status st;

    if (c < 1)
        return fail_txt(err, QDC_EPARSE, s, w,
                        "CELLS: 5.1 layout needs n+1 >= 1 offsets");
    v->c.nc = c - 1;
    st = vtk_type(v, "OFFSETS", t, err);
    if (st == QDC_OK)
        st = vtk_fits(v, "OFFSETS", c, *t, err);
    if (st == QDC_OK && !(v->c.offs = alloc_values(c, err)))
        st = QDC_ENOMEM;
    if (st == QDC_OK) {
        vsink k = {v->c.offs, NULL};
        st = vtk_values(v, "OFFSETS", c, *t, 1, &k, err);
    }
    if (st != QDC_OK)
        return st;
    next_word(v, &tw, &tn);
    if (!word_is(tw, tn, "CONNECTIVITY"))
        return fail_txt(err, QDC_EPARSE, s, tw, "expected CONNECTIVITY, got %s",
                        quote_tok(q, s, tw, tw + tn));
    return vtk_type(v, "CONNECTIVITY", t, err);
}

/* CELLS: the legacy list (count, then the points, per cell) or the 5.1
 * OFFSETS and CONNECTIVITY arrays. */
static qdc_status vtk_cells(vtk *v, const char *w, qdc_error *err)
{
    int64_t c, c2;
    vtype t = T_I32;
    vsink k = {NULL, &v->c.conn};
    qdc_status st;

    if (v->c.types.v || v->c.conn.v)
        return fail_txt(err, QDC_EPARSE, &v->s, w, "CELLS after CELL_TYPES or twice");
    st = vtk_count(v, "CELLS", 1, INT64_MAX, &c, err);
    if (st == QDC_OK)
        st = vtk_count(v, "CELLS: size", 1, INT64_MAX, &c2, err);
    if (st != QDC_OK)
        return st;
    v->c.nconn = c2;
    if (next_is(v, "OFFSETS"))
        st = vtk_offsets51(v, w, c, &t, err);
    else
        v->c.nc = c;
    if (st == QDC_OK)
        st = vtk_fits(v, "CELLS", v->c.nconn, t, err);
    if (st == QDC_OK)
        st = iarr_alloc(&v->c.conn, v->c.nconn, err);
    if (st == QDC_OK)
        st = vtk_values(v, "CELLS", v->c.nconn, t, 1, &k, err);
    if (st == QDC_OK && v->c.offs)
        st = check_offsets(v->c.offs, v->c.nc, v->c.nconn, "vtk", err);
    return st;
}

static qdc_status vtk_cell_types(vtk *v, const char *w, qdc_error *err)
{
    txt *s = &v->s;
    int64_t c;
    vsink k = {NULL, &v->c.types};
    qdc_status st;

    if (!v->c.conn.v)
        return fail_txt(err, QDC_EPARSE, s, w, "CELL_TYPES before CELLS");
    if (v->c.types.v)
        return fail_txt(err, QDC_EPARSE, s, w, "duplicate CELL_TYPES");
    st = vtk_count(v, "CELL_TYPES", 1, INT64_MAX, &c, err);
    if (st == QDC_OK && c != v->c.nc)
        st = fail_txt(err, QDC_EPARSE, s, s->p, "CELL_TYPES %lld for %lld CELLS",
                      (long long)c, (long long)v->c.nc);
    if (st == QDC_OK)
        st = vtk_fits(v, "CELL_TYPES", c, T_I32, err);
    if (st == QDC_OK)
        st = iarr_alloc(&v->c.types, c, err);
    return st == QDC_OK ? vtk_values(v, "CELL_TYPES", c, T_I32, 1, &k, err) : st;
}

/* CELL_DATA or POINT_DATA (cell): the attribute arrays that follow. */
static qdc_status vtk_attr_set(vtk *v, int cell, qdc_error *err)
{
    int64_t c;
    qdc_status st =
        vtk_count(v, cell ? "CELL_DATA" : "POINT_DATA", 1, INT64_MAX, &c, err);

    if (st == QDC_OK && c != (cell ? v->c.nc : v->c.nv))
        st = fail_txt(err, QDC_EPARSE, &v->s, v->s.p, "%s %lld for %lld %s",
                      cell ? "CELL_DATA" : "POINT_DATA", (long long)c,
                      (long long)(cell ? v->c.nc : v->c.nv), cell ? "cells" : "points");
    v->attr = cell ? 1 : 2;
    v->attr_n = c;
    return st;
}

/* METADATA: skipped up to an empty line. */
static void vtk_metadata(vtk *v)
{
    txt *s = &v->s;

    for (;;) {
        const char *p = s->p;
        while (p < s->end && *p != '\n')
            p++;
        if (p == s->end) {
            s->p = p;
            return;
        }
        s->p = p + 1;
        s->line++;
        s->bol = s->p;
        p = s->p;
        while (p < s->end && (*p == ' ' || *p == '\t' || *p == '\r'))
            p++;
        if (p == s->end || *p == '\n')
            return;
    }
}

/* SCALARS name type [components] [LOOKUP_TABLE name]. */
static qdc_status vtk_scalars(vtk *v, qdc_error *err)
{
    txt *s = &v->s;
    const char *name, *tw, *save;
    size_t nl, tn;
    int64_t k = 1;
    vtype t;
    qdc_status st;

    next_word(v, &name, &nl);
    st = vtk_type(v, "SCALARS", &t, err);
    /* optional component count on the same line */
    while (s->p < s->end && (*s->p == ' ' || *s->p == '\t' || *s->p == '\r'))
        s->p++;
    if (st == QDC_OK && s->p < s->end && *s->p != '\n')
        st = txt_int(s, "SCALARS: components", 1, 4, &k, err);
    save = s->p;
    next_word(v, &tw, &tn);
    if (word_is(tw, tn, "LOOKUP_TABLE"))
        next_word(v, &tw, &tn);
    else
        s->p = save;
    return st == QDC_OK ? vtk_attr_array(v, name, nl, k, t, err) : st;
}

/* FIELD name count, then per array: name components tuples type, values. */
static qdc_status vtk_field(vtk *v, qdc_error *err)
{
    txt *s = &v->s;
    int save_attr = v->attr;
    int64_t save_n = v->attr_n, c = 0, c2 = 0, k = 0;
    const char *name;
    size_t nl;
    vtype t;
    qdc_status st;

    next_word(v, &name, &nl);
    st = txt_int(s, "FIELD: array count", 0, 1 << 20, &c, err);
    for (int64_t i = 0; i < c && st == QDC_OK; i++) {
        next_word(v, &name, &nl);
        /* VTK 9 follows an array with its METADATA (INFORMATION keys) */
        while (word_is(name, nl, "METADATA")) {
            vtk_metadata(v);
            next_word(v, &name, &nl);
        }
        if (word_is(name, nl, "NULL") || !nl)
            continue;
        st = txt_int(s, "FIELD: components", 0, 1 << 20, &k, err);
        if (st == QDC_OK)
            st = vtk_count(v, "FIELD: tuples", 1, INT64_MAX, &c2, err);
        if (st == QDC_OK)
            st = vtk_type(v, "FIELD", &t, err);
        if (st != QDC_OK)
            break;
        /* a field array only counts as a region if it spans the attribute set */
        if (!save_attr || c2 != save_n)
            v->attr = 0;
        v->attr_n = c2;
        st = vtk_attr_array(v, name, nl, k, t, err);
        v->attr = save_attr;
        v->attr_n = save_n;
    }
    return st;
}

/* VECTORS, NORMALS, TENSORS, TEXTURE_COORDINATES and LOOKUP_TABLE: arrays
 * that are never ours, checked and passed over. */
static qdc_status vtk_other_attr(vtk *v, const char *w, size_t n, qdc_error *err)
{
    const char *name;
    size_t nl;
    int64_t k = 0, c = 0;
    vtype t;
    qdc_status st;

    next_word(v, &name, &nl);
    if (word_is(w, n, "TEXTURE_COORDINATES")) {
        st = txt_int(&v->s, "TEXTURE_COORDINATES: dimension", 1, 3, &k, err);
        if (st == QDC_OK)
            st = vtk_type(v, "TEXTURE_COORDINATES", &t, err);
        return st == QDC_OK ? vtk_attr_array(v, "", 0, k, t, err) : st;
    }
    if (word_is(w, n, "LOOKUP_TABLE")) {
        st = vtk_count(v, "LOOKUP_TABLE", 4, INT64_MAX, &c, err);
        return st == QDC_OK ? vtk_values(v, "LOOKUP_TABLE", 4 * c,
                                         v->binary ? T_U8 : T_F64, 0, NULL, err)
                            : st;
    }
    st = vtk_type(v, "VECTORS", &t, err);
    return st == QDC_OK
               ? vtk_attr_array(v, name, nl, word_is(w, n, "TENSORS") ? 9 : 3, t, err)
               : st;
}

static qdc_status vtk_keyword(vtk *v, const char *w, size_t n, qdc_error *err)
{
    txt *s = &v->s;
    const char *tw;
    size_t tn;
    char q[32];

    if (word_is(w, n, "DATASET")) {
        next_word(v, &tw, &tn);
        if (!word_is(tw, tn, "UNSTRUCTURED_GRID"))
            return fail_txt(err, QDC_EFORMAT, s, tw,
                            "DATASET %s: only UNSTRUCTURED_GRID is supported",
                            quote_tok(q, s, tw, tw + tn));
        return QDC_OK;
    }
    if (word_is(w, n, "POINTS"))
        return vtk_points(v, w, err);
    if (word_is(w, n, "CELLS"))
        return vtk_cells(v, w, err);
    if (word_is(w, n, "CELL_TYPES"))
        return vtk_cell_types(v, w, err);
    if (word_is(w, n, "CELL_DATA") || word_is(w, n, "POINT_DATA"))
        return vtk_attr_set(v, word_is(w, n, "CELL_DATA"), err);
    if (word_is(w, n, "METADATA")) { /* up to an empty line */
        vtk_metadata(v);
        return QDC_OK;
    }
    if (!v->attr && !word_is(w, n, "FIELD"))
        return fail_txt(err, QDC_EPARSE, s, w, "unexpected %s",
                        quote_tok(q, s, w, w + n));
    if (word_is(w, n, "SCALARS"))
        return vtk_scalars(v, err);
    if (word_is(w, n, "VECTORS") || word_is(w, n, "NORMALS") ||
        word_is(w, n, "TENSORS") || word_is(w, n, "TEXTURE_COORDINATES") ||
        word_is(w, n, "LOOKUP_TABLE"))
        return vtk_other_attr(v, w, n, err);
    if (word_is(w, n, "FIELD"))
        return vtk_field(v, err);
    return fail_txt(err, QDC_EPARSE, s, w, "unsupported keyword %s",
                    quote_tok(q, s, w, w + n));
}

static qdc_status read_vtk(const char *buf, size_t len, const meshio_options *o,
                           srcrec *rec, mesh_t **out, qdc_error *err)
{
    vtk v;
    txt *s = &v.s;
    const char *w;
    size_t n;
    char q[32];
    qdc_status st = QDC_OK;

    memset(&v, 0, sizeof v);
    v.rec = rec;
    v.c.creg_prio = PRIO_NONE;
    v.c.o = o;
    v.s = txt_init(buf, len, 0);
    v.b = (const unsigned char *)buf;
    if (len < 14 || memcmp(buf, "# vtk DataFile", 14) != 0)
        return fail_txt(err, QDC_EPARSE, s, s->p,
                        "not a legacy VTK file (no \"# vtk DataFile\")");
    for (int line = 0; line < 2; line++) { /* version line, title line */
        while (s->p < s->end && *s->p != '\n')
            s->p++;
        if (s->p == s->end)
            return fail_txt(err, QDC_EPARSE, s, s->p, "VTK: truncated header");
        s->p++;
        s->line++;
        s->bol = s->p;
    }
    next_word(&v, &w, &n);
    if (word_is(w, n, "BINARY"))
        v.binary = 1;
    else if (!word_is(w, n, "ASCII"))
        return fail_txt(err, QDC_EPARSE, s, w, "VTK: expected ASCII or BINARY, got %s",
                        quote_tok(q, s, w, w + n));
    for (;;) {
        next_word(&v, &w, &n);
        if (!n)
            break;
        st = vtk_keyword(&v, w, n, err);
        if (st != QDC_OK)
            break;
    }
    if (st == QDC_OK && !v.c.xyz)
        st = fail_txt(err, QDC_EPARSE, s, s->p, "VTK: no POINTS");
    if (st == QDC_OK)
        st = cells_mesh(&v.c, "vtk", o, out, err);
    cells_free(&v.c);
    return st;
}

/* ------------------------------------------------------------------------ */
/* Legacy writer                                                             */

/* One value in the encoding of the file: big-endian bytes or text. */
typedef struct {
    wbuf *w;
    int bin, big, per_line, i;
    int bin_nl; /* binary arrays end with a newline (legacy), or not (appended) */
} vw;

static void vw_sep(vw *o)
{
    if (!o->bin)
        wb_str(o->w, ++o->i % o->per_line ? " " : "\n");
}

static void vw_int(vw *o, int64_t x, int bytes)
{
    unsigned char b[8];

    if (!o->bin) {
        wb_int(o->w, x);
        vw_sep(o);
        return;
    }
    for (int j = 0; j < bytes; j++)
        b[o->big ? bytes - 1 - j : j] = (unsigned char)((uint64_t)x >> (8 * j));
    wb_put(o->w, b, (size_t)bytes);
}

static void vw_real(vw *o, double x)
{
    uint64_t u;

    if (!o->bin) {
        wb_real(o->w, x);
        vw_sep(o);
        return;
    }
    memcpy(&u, &x, 8);
    vw_int(o, (int64_t)u, 8);
}

/* End of an array: a newline (text arrays end with one unless complete). */
static void vw_end(vw *o)
{
    if (o->bin ? o->bin_nl : o->i % o->per_line != 0)
        wb_str(o->w, "\n");
    o->i = 0;
}

static int has_regions(const mesh_t *m)
{
    return m->region || (m->ntri && m->tri_ref);
}

static int32_t cell_region(const mesh_t *m, int64_t c)
{
    if (c < m->nt)
        return m->region ? m->region[c] : 0;
    return m->tri_ref ? m->tri_ref[c - m->nt] : 0;
}

/* The VTK cell type of m's tets: 10, or 24 (VTK_QUADRATIC_TETRA). */
static int tet_type(const mesh_t *m)
{
    return m->mid ? 24 : 10;
}

/* One point array's values: integers in ik bytes (pdata_ikind: 4, 8),
 * else doubles (%.17g in text: they read back exactly). */
static void vw_parray(vw *o, const mesh_parray *a, int64_t nv, int ik)
{
    size_t n = (size_t)nv * (size_t)a->ncomp;

    o->per_line = a->ncomp > 9 ? 9 : a->ncomp;
    o->i = 0;
    for (size_t i = 0; i < n; i++) {
        if (ik)
            vw_int(o, (int64_t)a->v[i], ik);
        else
            vw_real(o, a->v[i]);
    }
    vw_end(o);
}

/* The point arrays as one FIELD of the POINT_DATA. */
static void vtk_write_pdata(const mesh_t *m, vw *o)
{
    char name[256];

    wb_str(o->w, "FIELD FieldData ");
    wb_int(o->w, m->pdata->n);
    wb_str(o->w, "\n");
    for (int32_t i = 0; i < m->pdata->n; i++) {
        const mesh_parray *a = &m->pdata->a[i];
        int ik = pdata_ikind(a, m->nv);
        pdata_word(a, name);
        wb_str(o->w, name);
        wb_str(o->w, " ");
        wb_int(o->w, a->ncomp);
        wb_str(o->w, " ");
        wb_int(o->w, m->nv);
        wb_str(o->w, !ik ? " double\n" : ik == 4 ? " int\n" : " vtktypeint64\n");
        vw_parray(o, a, m->nv, ik);
    }
}

static void vtk_write(const mesh_t *m, int binary, wbuf *w)
{
    vw o = {w, binary, 1, 3, 0, 1};
    int64_t nc = (int64_t)m->nt + m->ntri;

    wb_str(w, "# vtk DataFile Version 4.2\nqdc\n");
    wb_str(w, binary ? "BINARY\n" : "ASCII\n");
    wb_str(w, "DATASET UNSTRUCTURED_GRID\nPOINTS ");
    wb_int(w, m->nv);
    wb_str(w, " double\n");
    for (size_t i = 0; i < 3 * (size_t)m->nv; i++)
        vw_real(&o, m->xyz[i]);
    vw_end(&o);
    wb_str(w, "CELLS ");
    wb_int(w, nc);
    wb_str(w, " ");
    wb_int(w, (m->mid ? 11 : 5) * (int64_t)m->nt + 4 * (int64_t)m->ntri);
    wb_str(w, "\n");
    for (int64_t c = 0; c < nc; c++) {
        int k = c < m->nt ? 4 : 3, q = c < m->nt && m->mid ? 6 : 0;
        const int32_t *v = k == 4 ? m->tets + 4 * c : m->tris + 3 * (c - m->nt);
        o.per_line = k + q + 1;
        o.i = 0;
        vw_int(&o, k + q, 4);
        for (int j = 0; j < k; j++)
            vw_int(&o, v[j], 4);
        for (int j = 0; j < q; j++)
            vw_int(&o, m->mid[6 * c + j], 4);
    }
    o.i = 0;
    vw_end(&o);
    wb_str(w, "CELL_TYPES ");
    wb_int(w, nc);
    wb_str(w, "\n");
    o.per_line = 16;
    for (int64_t c = 0; c < nc; c++)
        vw_int(&o, c < m->nt ? tet_type(m) : 5, 4);
    vw_end(&o);
    if (has_regions(m)) {
        wb_str(w, "CELL_DATA ");
        wb_int(w, nc);
        wb_str(w, "\nSCALARS region int 1\nLOOKUP_TABLE default\n");
        for (int64_t c = 0; c < nc; c++)
            vw_int(&o, cell_region(m, c), 4);
        vw_end(&o);
    }
    if (m->vref || (m->pdata && m->pdata->n)) {
        wb_str(w, "POINT_DATA ");
        wb_int(w, m->nv);
        wb_str(w, "\n");
    }
    if (m->vref) {
        wb_str(w, "SCALARS medit:ref int 1\nLOOKUP_TABLE default\n");
        for (int64_t i = 0; i < m->nv; i++)
            vw_int(&o, m->vref[i], 4);
        vw_end(&o);
    }
    if (m->pdata && m->pdata->n)
        vtk_write_pdata(m, &o);
}

/* ------------------------------------------------------------------------ */
/* VTU reader                                                                */

/* A start tag: its name and attribute text [a, ae). */
typedef struct {
    const char *name, *a, *ae, *after; /* after: first byte after '>' */
    size_t nlen;
    int closing, empty; /* </x>, <x/> */
} xtag;

typedef struct {
    txt s;
    const unsigned char *b;
    int big, hdr8;        /* byte_order BigEndian, header_type UInt64 */
    const char *appended; /* first byte after '_' in AppendedData, or NULL */
    xtag conn_tag;        /* connectivity seen before offsets: read at the end */
    txt conn_at;
    int app_base64;
    int zlib; /* compressor="vtkZLibDataCompressor" */
    cells c;
    srcrec *rec;     /* where the coordinates are, or NULL */
    size_t inflated; /* bytes of zlib arrays inflated so far */
    size_t zbudget;  /* what they may add up to (meshio_options) */
} vtu;

/* The next tag at or after s->p (comments, <? ?> and text skipped). */
static qdc_status next_tag(vtu *x, xtag *t, qdc_error *err)
{
    txt *s = &x->s;
    /* no tag reaches into the appended data: what the XML says never depends
     * on those bytes (a spliced write changes them) */
    const char *p = s->p, *e = x->appended && p < x->appended ? x->appended : s->end;

    memset(t, 0, sizeof *t);
    for (;;) {
        while (p < e && *p != '<') {
            if (*p == '\n') {
                s->line++;
                s->bol = p + 1;
            }
            p++;
        }
        if (p == e) {
            s->p = p;
            return QDC_OK;
        }
        if (e - p >= 4 && memcmp(p, "<!--", 4) == 0) {
            const char *q = p + 4;
            while (q + 3 <= e && memcmp(q, "-->", 3) != 0)
                q++;
            if (q + 3 > e)
                return fail_txt(err, QDC_EPARSE, s, p, "VTU: unterminated comment");
            p = q + 3;
            continue;
        }
        if (e - p >= 2 && (p[1] == '?' || p[1] == '!')) {
            while (p < e && *p != '>')
                p++;
            if (p == e)
                return fail_txt(err, QDC_EPARSE, s, s->p,
                                "VTU: unterminated declaration");
            p++;
            continue;
        }
        break;
    }
    s->p = p;
    p++;
    if (p < e && *p == '/') {
        t->closing = 1;
        p++;
    }
    t->name = p;
    while (p < e && (is_word((unsigned char)*p) || *p == ':' || *p == '-'))
        p++;
    t->nlen = (size_t)(p - t->name);
    t->a = p;
    while (p < e && *p != '>') {
        if (*p == '"' || *p == '\'') {
            char qc = *p++;
            while (p < e && *p != qc)
                p++;
            if (p == e)
                break;
        }
        p++;
    }
    if (p == e || !t->nlen)
        return fail_txt(err, QDC_EPARSE, s, s->p, "VTU: malformed tag");
    t->ae = p;
    t->empty = p > t->a && p[-1] == '/';
    if (t->empty)
        t->ae--;
    t->after = p + 1;
    s->p = t->after;
    return QDC_OK;
}

/* Attribute `key` of t: its value in [*v, *ve); 0 if absent. */
static int tag_attr(const xtag *t, const char *key, const char **v, const char **ve)
{
    size_t kl = strlen(key);
    const char *p = t->a;

    while (p < t->ae) {
        const char *k = p, *ke;
        char qc;
        while (p < t->ae && *p != '=')
            p++;
        for (ke = p; ke > k && is_space((unsigned char)ke[-1]); ke--)
            ;
        while (k < ke && is_space((unsigned char)*k))
            k++;
        if (p == t->ae)
            return 0;
        p++;
        while (p < t->ae && is_space((unsigned char)*p))
            p++;
        if (p == t->ae || (*p != '"' && *p != '\''))
            return 0;
        qc = *p++;
        *v = p;
        while (p < t->ae && *p != qc)
            p++;
        *ve = p;
        if (p < t->ae)
            p++;
        if ((size_t)(ke - k) == kl && memcmp(k, key, kl) == 0)
            return 1;
    }
    return 0;
}

static int attr_is(const xtag *t, const char *key, const char *val)
{
    const char *v, *ve;

    return tag_attr(t, key, &v, &ve) && (size_t)(ve - v) == strlen(val) &&
           memcmp(v, val, (size_t)(ve - v)) == 0;
}

static qdc_status attr_int(vtu *x, const xtag *t, const char *key, int64_t lo, int64_t hi,
                           int64_t *out, qdc_error *err)
{
    const char *v, *ve;
    int rc;

    if (!tag_attr(t, key, &v, &ve))
        return fail_txt(err, QDC_EPARSE, &x->s, t->name, "VTU: %.*s without %s",
                        (int)(t->nlen > 32 ? 32 : t->nlen), t->name, key);
    while (v < ve && is_space((unsigned char)*v)) /* FreeFEM: NumberOfCells=" 7200" */
        v++;
    while (ve > v && is_space((unsigned char)ve[-1]))
        ve--;
    rc = parse_int(v, ve, 0, out);
    if (rc != 0 || *out < lo || *out > hi)
        return fail_txt(
            err, QDC_EPARSE, &x->s, v, "VTU: %s=\"%.*s\" is not in [%lld, %lld]", key,
            (int)(ve - v > 24 ? 24 : ve - v), v, (long long)lo, (long long)hi);
    return QDC_OK;
}

static int b64_val(unsigned char c)
{
    if (c >= 'A' && c <= 'Z')
        return c - 'A';
    if (c >= 'a' && c <= 'z')
        return c - 'a' + 26;
    if (c >= '0' && c <= '9')
        return c - '0' + 52;
    return c == '+' ? 62 : c == '/' ? 63 : -1;
}

/* Decode base64 from [p, e) until `want` bytes are out (or e / a '<').
 * Quanta are decoded one by one, so blocks encoded separately (header, then
 * data, each with its padding) decode like one stream. Returns the bytes
 * written; *endp = where decoding stopped. */
static size_t b64_decode(const char *p, const char *e, unsigned char *out, size_t want,
                         const char **endp)
{
    size_t n = 0;
    int q[4], k = 0, pad = 0;

    while (p < e && n < want && *p != '<') {
        unsigned char c = (unsigned char)*p++;
        int d = b64_val(c);
        if (c == '=') {
            pad++;
            d = 0;
        } else if (d < 0) {
            continue; /* whitespace */
        }
        q[k++] = d;
        if (k < 4)
            continue;
        k = 0;
        {
            unsigned char b3[3] = {(unsigned char)(q[0] << 2 | q[1] >> 4),
                                   (unsigned char)(q[1] << 4 | q[2] >> 2),
                                   (unsigned char)(q[2] << 6 | q[3])};
            for (int j = 0; j < 3 - pad && n < want; j++)
                out[n++] = b3[j];
        }
        pad = 0;
    }
    *endp = p;
    return n;
}

/* Header word k (hsz bytes, byte order of the file) at h. */
static uint64_t hdr_word(const vtu *x, const unsigned char *h, size_t k)
{
    size_t hsz = x->hdr8 ? 8 : 4;
    uint64_t v = 0;

    h += k * hsz;
    for (size_t j = 0; j < hsz; j++)
        v = v << 8 | h[x->big ? j : hsz - 1 - j];
    return v;
}

/* Inflate the zlib blocks of a compressed array: header words hdr (count,
 * block size, last block size, then each block's compressed size), data at
 * z (zlen bytes available) into out (want bytes). *used: the compressed
 * bytes. */
static qdc_status vtu_inflate(vtu *x, const unsigned char *hdr, const unsigned char *z,
                              size_t zlen, unsigned char *out, size_t want, size_t *used,
                              int64_t at, qdc_error *err)
{
    uint64_t nb = hdr_word(x, hdr, 0), bs = hdr_word(x, hdr, 1),
             last = hdr_word(x, hdr, 2);
    uint64_t lastsz = last ? last : bs, total, zoff = 0;

    if (nb == 0)
        total = 0;
    else if (lastsz > bs || (nb > 1 && (bs == 0 || bs > want || nb - 1 > want / bs)))
        total = UINT64_MAX;
    else
        total = (nb - 1) * bs + lastsz;
    if (total != want)
        return fail_bin(err, QDC_EPARSE, at,
                        "VTU: zlib header of %llu blocks of %llu bytes (last %llu) for "
                        "%zu bytes expected",
                        (unsigned long long)nb, (unsigned long long)bs,
                        (unsigned long long)last, want);
    for (uint64_t k = 0; k < nb; k++) {
        uint64_t c = hdr_word(x, hdr, 3 + k), sz = k + 1 < nb ? bs : lastsz;
        uLongf dl = (uLongf)sz;
        if (c > zlen - zoff || c > ULONG_MAX || sz > ULONG_MAX)
            return fail_bin(
                err, QDC_EPARSE, at,
                "VTU: zlib block %llu of %llu bytes does not fit in the input",
                (unsigned long long)k, (unsigned long long)c);
        if (uncompress(out + k * bs, &dl, z + zoff, (uLong)c) != Z_OK || dl != sz)
            return fail_bin(err, QDC_EPARSE, at,
                            "VTU: zlib block %llu is corrupt (or not %llu bytes)",
                            (unsigned long long)k, (unsigned long long)sz);
        zoff += c;
    }
    *used = (size_t)zoff;
    return QDC_OK;
}

/* Where the data of an array at p must end: inline arrays before the
 * appended data, appended ones at the end of the input. */
static const char *data_end(const vtu *x, const char *p)
{
    return x->appended && p < x->appended ? x->appended : x->s.end;
}

/* Base64 from p, decoded until `want` bytes are out, into a new *tmp;
 * *endp where it stopped. */
static qdc_status b64_take(vtu *x, const char *p, size_t want, unsigned char **tmp,
                           const char **endp, qdc_error *err)
{
    const char *end = data_end(x, p);

    if (want / 3 * 4 > (size_t)(end - p))
        return fail_bin(err, QDC_EPARSE, p - x->s.base,
                        "VTU: %zu bytes of base64 data cannot fit in the input", want);
    qdc_free(*tmp);
    *tmp = qdc_malloc(want + 1);
    if (!*tmp)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for a VTU array");
    if (b64_decode(p, end, *tmp, want, endp) != want)
        return fail_bin(err, QDC_EPARSE, p - x->s.base,
                        "VTU: base64 data end before %zu bytes", want);
    return QDC_OK;
}

static int is_b64(unsigned char c)
{
    return b64_val(c) >= 0 || c == '=';
}

/* Room for `want` more inflated bytes in the zlib budget (a 1 MB file of
 * zlib blocks of zeros declares a GB of arrays): QDC_ETOOBIG when not. */
static qdc_status vtu_take_budget(vtu *x, size_t want, int64_t at, qdc_error *err)
{
    if (want > x->zbudget - x->inflated)
        return fail_bin(err, QDC_ETOOBIG, at,
                        "VTU: the zlib arrays inflate to more than %zu bytes",
                        x->zbudget);
    x->inflated += want;
    return QDC_OK;
}

/* Appended raw data at p (header words, then the data, as is or in zlib
 * blocks): exactly `want` bytes at *data (into the input, or *tmp). */
static qdc_status vtu_raw(vtu *x, const char *p, size_t want, srcrec *rec,
                          const unsigned char **data, unsigned char **tmp, qdc_error *err)
{
    const unsigned char *h = (const unsigned char *)p;
    size_t hsz = x->hdr8 ? 8 : 4, hn = x->zlib ? 3 * hsz : hsz, used = 0;
    size_t left = (size_t)(x->s.end - p);
    int64_t at = p - x->s.base;
    uint64_t nb;
    qdc_status st;

    if (left < hn)
        return fail_bin(err, QDC_EPARSE, at, "VTU: appended block header truncated");
    if (!x->zlib) {
        uint64_t nbytes = hdr_word(x, h, 0);
        if (nbytes != want || left - hn < want)
            return fail_bin(
                err, QDC_EPARSE, at,
                "VTU: appended block of %llu bytes for %zu expected (%zu left)",
                (unsigned long long)nbytes, want, left - hn);
        *data = h + hn;
        if (!rec)
            return QDC_OK;
        rec->kind = SRC_BIN; /* in place: offsets per vertex */
        rec->blk_b = (uint64_t)at + hn + want;
        st = srcrec_alloc(rec, rec->nv, err);
        for (int64_t v = 0; st == QDC_OK && v < rec->nv; v++)
            rec->off[v] =
                (uint64_t)(at + (int64_t)hn) + (uint64_t)v * 3 * (uint64_t)rec->width;
        return st;
    }
    nb = hdr_word(x, h, 0);
    if (nb > (left - hn) / hsz)
        return fail_bin(err, QDC_EPARSE, at,
                        "VTU: zlib header of %llu blocks does not fit",
                        (unsigned long long)nb);
    hn += (size_t)nb * hsz;
    st = vtu_take_budget(x, want, at, err);
    if (st != QDC_OK)
        return st;
    *tmp = qdc_malloc(want + 1);
    if (!*tmp)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for a VTU array");
    st = vtu_inflate(x, h, h + hn, left - hn, *tmp, want, &used, at, err);
    if (st != QDC_OK)
        return st;
    *data = *tmp;
    if (rec) {
        for (int k = 0; k < 3; k++)
            rec->zhdr[k] = hdr_word(x, h, (size_t)k);
        rec->blk_b = (uint64_t)at + hn + used;
    }
    return QDC_OK;
}

/* Base64 zlib data at p: the header (block count, sizes), then the blocks,
 * decoded and inflated into *tmp (want bytes). *hn: the header's bytes,
 * *endp where the base64 text stopped. */
static qdc_status vtu_b64_zlib(vtu *x, const char *p, size_t want, srcrec *rec,
                               unsigned char **tmp, size_t *hn, const char **endp,
                               qdc_error *err)
{
    size_t hsz = x->hdr8 ? 8 : 4, left = (size_t)(x->s.end - p), used = 0;
    int64_t at = p - x->s.base;
    unsigned char *z = NULL; /* the header and blocks decoded */
    uint64_t nb, sum = 0;
    qdc_status st = b64_take(x, p, *hn, &z, endp, err);

    nb = st == QDC_OK ? hdr_word(x, z, 0) : 0;
    if (st == QDC_OK && nb > left / hsz)
        st = fail_bin(err, QDC_EPARSE, at, "VTU: zlib header of %llu blocks does not fit",
                      (unsigned long long)nb);
    if (st == QDC_OK) {
        *hn += (size_t)nb * hsz;
        st = b64_take(x, p, *hn, &z, endp, err);
    }
    for (uint64_t k = 0; st == QDC_OK && k < nb && sum <= left; k++)
        sum += hdr_word(x, z, 3 + k) > left ? UINT64_MAX / 2 : hdr_word(x, z, 3 + k);
    if (st == QDC_OK && sum > left)
        st = fail_bin(err, QDC_EPARSE, at,
                      "VTU: zlib blocks of %llu bytes cannot fit in the input",
                      (unsigned long long)sum);
    if (st == QDC_OK)
        st = b64_take(x, p, *hn + (size_t)sum, &z, endp, err);
    if (st == QDC_OK)
        st = vtu_take_budget(x, want, at, err);
    if (st == QDC_OK && !(*tmp = qdc_malloc(want + 1)))
        st = qdc_fail(err, QDC_ENOMEM, "out of memory for a VTU array");
    if (st == QDC_OK)
        st = vtu_inflate(x, z, z + *hn, (size_t)sum, *tmp, want, &used, at, err);
    if (st == QDC_OK && rec)
        for (int k = 0; k < 3; k++)
            rec->zhdr[k] = hdr_word(x, z, (size_t)k);
    qdc_free(z);
    return st;
}

/* The bytes of a binary (base64) or appended DataArray, decoded and
 * decompressed: exactly `want` bytes at *data, which points into the input
 * or into *tmp (the caller frees it). rec (Points only): where they are. */
static qdc_status vtu_bytes(vtu *x, const xtag *t, int appended, size_t want, srcrec *rec,
                            const unsigned char **data, unsigned char **tmp,
                            qdc_error *err)
{
    txt *s = &x->s;
    size_t hsz = x->hdr8 ? 8 : 4, hn = x->zlib ? 3 * hsz : hsz;
    int b64 = !appended || x->app_base64;
    const char *p, *endp = NULL;
    int64_t off = 0, at;
    qdc_status st;

    if (appended) {
        if (!x->appended)
            return fail_txt(err, QDC_EPARSE, s, t->name,
                            "VTU: appended DataArray without AppendedData");
        st = attr_int(x, t, "offset", 0, (int64_t)(s->end - x->appended), &off, err);
        if (st != QDC_OK)
            return st;
        p = x->appended + off;
    } else {
        for (p = t->after; p < s->end && is_space((unsigned char)*p); p++)
            ;
    }
    at = p - s->base;
    if (rec) {
        rec->kind = SRC_BLOCK;
        rec->fmt = MESHIO_VTU;
        rec->blk_a = (uint64_t)at;
        rec->b64 = b64;
        rec->zlib = x->zlib;
        rec->hdr8 = x->hdr8;
        rec->appended = appended;
        rec->app_off = (uint64_t)off;
    }
    if (!b64)
        return vtu_raw(x, p, want, rec, data, tmp, err);
    /* base64: header and data decoded as one stream: VTK and meshio encode
     * the two separately (each padded), others together; both decode alike */
    if (!x->zlib) {
        st = b64_take(x, p, hn + want, tmp, &endp, err);
        if (st == QDC_OK && hdr_word(x, *tmp, 0) != want)
            st = fail_bin(err, QDC_EPARSE, at,
                          "VTU: base64 block of %llu bytes for %zu expected",
                          (unsigned long long)hdr_word(x, *tmp, 0), want);
        if (st != QDC_OK)
            return st;
        *data = *tmp + hn;
    } else {
        st = vtu_b64_zlib(x, p, want, rec, tmp, &hn, &endp, err);
        if (st != QDC_OK)
            return st;
        *data = *tmp;
    }
    if (rec) {
        size_t hc = (hn + 2) / 3 * 4; /* header characters if encoded alone */
        rec->blk_b = (uint64_t)(endp - s->base);
        rec->b64_sep = hn % 3 == 0 || (hc <= (size_t)(endp - p) && p[hc - 1] == '=');
        for (const char *q = p; q < endp; q++)
            if (!is_b64((unsigned char)*q)) {
                srcrec_refuse(rec, "VTU Points: whitespace inside base64 data");
                break;
            }
    }
    return QDC_OK;
}

/* The n values of an ascii DataArray into out (NULL: skip); finite: NaN
 * and infinities are errors. rec (Points only): where each vertex starts. */
static qdc_status vtu_ascii(vtu *x, const xtag *t, int64_t n, int finite, int f32,
                            vsink *out, srcrec *rec, qdc_error *err)
{
    txt *s = &x->s;
    qdc_status st;

    if (t->empty && n)
        return fail_txt(err, QDC_EPARSE, s, t->name, "VTU: empty ascii DataArray");
    if (rec) {
        rec->fmt = MESHIO_VTU_ASCII;
        rec->kind = SRC_TEXT;
        rec->lt = 1;
        st = srcrec_alloc(rec, n / 3, err);
        if (st != QDC_OK)
            return st;
    }
    for (int64_t i = 0; i < n; i++) {
        double y;
        const char *te, *at, *lim = data_end(x, s->p);
        char q[32];
        int64_t u;
        if (out && out->a && txt_uint_fast(s, 0, INT32_MAX, &u)) {
            out->a->v[i] = (int32_t)u; /* digits, then white space: no '<' */
            continue;
        }
        skip_ws(s);
        if (rec && i % 3 == 0)
            rec->off[i / 3] = (uint64_t)(s->p - s->base);
        for (te = s->p; te < lim && !is_space((unsigned char)*te) && *te != '<'; te++)
            ;
        at = s->p;
        if (finite)
            st = tok_real(s, s->p, te, "DataArray", &y, err);
        else
            st = s->p < te && parse_double(s->p, te, &y) == 0
                     ? QDC_OK
                     : fail_txt(err, QDC_EPARSE, s, s->p,
                                "DataArray: expected a number, got %s",
                                quote_tok(q, s, s->p, te));
        if (st != QDC_OK)
            return st;
        if (f32 && text_f32(&y))
            return fail_txt(err, QDC_EPARSE, s, at,
                            "DataArray: %s is out of Float32's range",
                            quote_tok(q, s, at, te));
        s->p = te;
        if (out && sink_put(out, i, y) != 0)
            return qdc_fail(err, QDC_ENOMEM, "out of memory for a VTU array");
    }
    return QDC_OK;
}

/* The data of one DataArray with n values of type t into out (NULL: skip).
 * rec (Points only): where the coordinates are. */
static qdc_status vtu_array(vtu *x, const xtag *t, int64_t n, vtype vt, int finite,
                            vsink *out, srcrec *rec, qdc_error *err)
{
    const char *fv, *fe;
    txt *s = &x->s;
    unsigned char *tmp = NULL;
    const unsigned char *data = NULL;
    size_t want = (size_t)n * (size_t)vsize[vt];
    int appended;
    qdc_status st;

    if (!tag_attr(t, "format", &fv, &fe)) { /* absent: ascii */
        fv = "ascii";
        fe = fv + 5;
    }
    if (rec) {
        rec->width = vsize[vt];
        rec->big = x->big;
        rec->nv = n / 3;
    }
    if ((size_t)(fe - fv) == 5 && memcmp(fv, "ascii", 5) == 0)
        return vtu_ascii(x, t, n, finite, vt == T_F32, out, rec, err);
    if ((size_t)(fe - fv) == 6 && memcmp(fv, "binary", 6) == 0)
        appended = 0;
    else if ((size_t)(fe - fv) == 8 && memcmp(fv, "appended", 8) == 0)
        appended = 1;
    else
        return fail_txt(err, QDC_EFORMAT, s, fv,
                        "VTU: DataArray format \"%.*s\" not supported",
                        (int)(fe - fv > 16 ? 16 : fe - fv), fv);
    st = vtu_bytes(x, t, appended, want, rec, &data, &tmp, err);
    if (st == QDC_OK && out) {
        int64_t i = sink_decode(out, data, n, vt, x->big);
        if (i < 0)
            st = qdc_fail(err, QDC_ENOMEM, "out of memory for a VTU array");
        else if (finite && i < n && appended && !x->app_base64 && !x->zlib)
            st = fail_bin(err, QDC_EPARSE, /* the value's bytes */
                          (const char *)data - s->base + i * vsize[vt],
                          "VTU: value %lld is not finite (NaN/Inf)", (long long)i);
        else if (finite && i < n) /* base64 or zlib: the DataArray's tag */
            st = fail_txt(err, QDC_EPARSE, s, t->name,
                          "VTU: value %lld is not finite (NaN/Inf)", (long long)i);
    }
    qdc_free(tmp);
    return st;
}

enum { SEC_NONE, SEC_POINTS, SEC_CELLS, SEC_CELLDATA, SEC_POINTDATA };

/* With a record: the Points' RangeMin and RangeMax (VTK: the range of the
 * point norms), for a spliced write to recompute them. */
static qdc_status vtu_note_range(vtu *x, const xtag *t, qdc_error *err)
{
    static const char *const keys[2] = {"RangeMin", "RangeMax"};
    derived *d = &x->rec->dv;
    qdc_status st = QDC_OK;

    for (int k = 0; k < 2 && st == QDC_OK; k++) {
        const char *v, *ve;
        double val;
        if (!tag_attr(t, keys[k], &v, &ve))
            continue;
        while (v < ve && is_space((unsigned char)*v))
            v++;
        while (ve > v && is_space((unsigned char)ve[-1]))
            ve--;
        if (parse_double(v, ve, &val) != 0 || !isfinite(val))
            continue;
        *(k ? &d->imax : &d->imin) = (int64_t)d->off.n;
        st = dv_value(d, (uint64_t)(v - x->s.base), val, err);
    }
    if (st == QDC_OK && d->off.n == 2 &&
        ((uint64_t *)d->off.a)[0] > ((uint64_t *)d->off.a)[1]) {
        uint64_t o = ((uint64_t *)d->off.a)[0];
        double f = ((double *)d->file.a)[0];
        ((uint64_t *)d->off.a)[0] = ((uint64_t *)d->off.a)[1];
        ((double *)d->file.a)[0] = ((double *)d->file.a)[1];
        ((uint64_t *)d->off.a)[1] = o;
        ((double *)d->file.a)[1] = f;
        d->imin = 1 - d->imin;
        d->imax = 1 - d->imax;
    }
    if (d->off.n)
        d->kind = DV_NORMS;
    return st;
}

/* One of our arrays: doubles (*d: the points, the offsets) or an iarr (a). */
typedef struct {
    double **d;
    iarr *a;
} vdst;

/* Which of our arrays (dst, none if both NULL) a DataArray named [nv, ne)
 * with ncomp components in section sec is, and its value count *n (-1: the
 * connectivity, sized by the offsets); *prio its region priority. */
static qdc_status vtu_target(vtu *x, const xtag *t, int sec, const char *nv,
                             const char *ne, int64_t ncomp, double **offs_end, vdst *dst,
                             int64_t *n, int *prio, qdc_error *err)
{
    size_t l = (size_t)(ne - nv);

    dst->d = NULL;
    dst->a = NULL;
    *prio = PRIO_NONE;
    if (sec == SEC_POINTS) {
        if (ncomp != 3)
            return fail_txt(err, QDC_EPARSE, &x->s, t->name,
                            "VTU: Points need 3 components");
        dst->d = &x->c.xyz;
        *n = 3 * x->c.nv;
        return x->rec && !x->c.xyz ? vtu_note_range(x, t, err) : QDC_OK;
    }
    if (sec == SEC_CELLS) {
        if (l == 12 && memcmp(nv, "connectivity", 12) == 0)
            dst->a = &x->c.conn;
        else if (l == 7 && memcmp(nv, "offsets", 7) == 0)
            dst->d = offs_end;
        else if (l == 5 && memcmp(nv, "types", 5) == 0)
            dst->a = &x->c.types;
        *n = dst->a == &x->c.conn ? -1 : x->c.nc;
    } else if (sec == SEC_CELLDATA) {
        *prio = ncomp == 1 ? region_prio(nv, l) : PRIO_NONE;
        if (*prio < x->c.creg_prio)
            dst->a = &x->c.creg;
        *n = ncomp * x->c.nc;
    } else {
        if (ncomp == 1 && region_prio(nv, l) == 2)
            dst->a = &x->c.vref;
        *n = ncomp * x->c.nv;
    }
    return QDC_OK;
}

/* The offsets (the ends of the cells) increase from 0. */
static qdc_status vtu_check_ends(vtu *x, const xtag *t, const double *a, int64_t n,
                                 qdc_error *err)
{
    for (int64_t i = 0; i < n; i++)
        if (!(a[i] >= 0 && a[i] <= 4e18 && (double)(int64_t)a[i] == a[i] &&
              (i == 0 || a[i] >= a[i - 1])))
            return fail_txt(err, QDC_EPARSE, &x->s, t->name,
                            "VTU: offsets not increasing from 0");
    return QDC_OK;
}

/* The n values of DataArray t (type vt) into a new array at dst (replacing
 * a region array of lower priority); offsets checked to increase from 0. */
static qdc_status vtu_store(vtu *x, const xtag *t, const vdst *dst, int64_t n, vtype vt,
                            int prio, double **offs_end, qdc_error *err)
{
    iarr ia;
    vsink k = {NULL, NULL};
    int pts = dst->d == &x->c.xyz;
    qdc_status st = QDC_OK;

    memset(&ia, 0, sizeof ia);
    if (dst->a) {
        st = iarr_alloc(&ia, n, err);
        k.a = &ia;
    } else if (!(k.d = alloc_values(n, err))) {
        st = QDC_ENOMEM;
    }
    if (st != QDC_OK)
        return st;
    if (pts && x->rec && vt != T_F32 && vt != T_F64)
        srcrec_refuse(x->rec, "VTU Points of an integer type");
    st =
        vtu_array(x, t, n, vt, 1, &k, pts && x->rec && !x->rec->why ? x->rec : NULL, err);
    if (st != QDC_OK) {
        qdc_free(k.d);
        iarr_free(&ia);
        return st;
    }
    if (dst->a) {
        iarr_free(dst->a);
        *dst->a = ia;
    } else {
        qdc_free(*dst->d);
        *dst->d = k.d;
    }
    if (dst->a == &x->c.creg)
        x->c.creg_prio = prio;
    return dst->d == offs_end ? vtu_check_ends(x, t, k.d, n, err) : QDC_OK;
}

/* A point array other than medit:ref (n values): into c.pd as doubles (a
 * NaN/Inf one dropped with a note). */
static qdc_status vtu_point_array(vtu *x, const xtag *t, const char *name, size_t nlen,
                                  int64_t ncomp, int64_t n, vtype vt, qdc_error *err)
{
    double *d = alloc_values(n, err);
    vsink k = {d, NULL};
    qdc_status st;

    if (!d)
        return QDC_ENOMEM;
    st = vtu_array(x, t, n, vt, 0, &k, NULL, err);
    if (st != QDC_OK) {
        qdc_free(d);
        return st;
    }
    return pdata_take(&x->c.pd, x->c.nv, name, nlen, ncomp, vtype_int(vt),
                      vtk_type_name(vt), d, x->c.o, "vtu", err);
}

static qdc_status vtu_dataarray(vtu *x, const xtag *t, int sec, double **offs_end,
                                qdc_error *err)
{
    const char *nv, *ne, *tv, *te;
    int64_t ncomp = 1, n = 0;
    vtype vt;
    vdst dst;
    int prio;
    qdc_status st;

    if (!tag_attr(t, "type", &tv, &te) || vtype_of(tv, (size_t)(te - tv), &vt) != 0)
        return fail_txt(err, QDC_EPARSE, &x->s, t->name,
                        "VTU: DataArray without a known type");
    if (!tag_attr(t, "Name", &nv, &ne))
        nv = ne = "";
    if (tag_attr(t, "NumberOfComponents", &tv, &te)) {
        st = attr_int(x, t, "NumberOfComponents", 1, 1 << 16, &ncomp, err);
        if (st != QDC_OK)
            return st;
    }
    st = vtu_target(x, t, sec, nv, ne, ncomp, offs_end, &dst, &n, &prio, err);
    if (st != QDC_OK)
        return st;
    if (n < 0) { /* connectivity: its size is the last offset */
        if (!*offs_end) {
            if (x->conn_tag.name)
                return fail_txt(err, QDC_EPARSE, &x->s, t->name,
                                "VTU: duplicate DataArray");
            x->conn_tag = *t;
            x->conn_at = x->s;
            return QDC_OK;
        }
        n = x->c.nc ? (int64_t)(*offs_end)[x->c.nc - 1] : 0;
        x->c.nconn = n;
    }
    if ((dst.d && *dst.d) || (dst.a && dst.a->v && dst.a != &x->c.creg))
        return fail_txt(err, QDC_EPARSE, &x->s, t->name, "VTU: duplicate DataArray");
    /* zlib inflates at most 1032 to 1 */
    if ((uint64_t)n > (uint64_t)(x->s.end - x->s.base) * (x->zlib ? 1032 : 1))
        return fail_txt(err, QDC_EPARSE, &x->s, t->name,
                        "VTU: %lld values cannot fit in the input", (long long)n);
    if (!dst.d && !dst.a && sec == SEC_POINTDATA && ne > nv)
        return vtu_point_array(x, t, nv, (size_t)(ne - nv), ncomp, n, vt, err);
    if (!dst.d && !dst.a) /* not ours: its text or base64 is passed over with the tags */
        return QDC_OK;
    return vtu_store(x, t, &dst, n, vt, prio, offs_end, err);
}

/* With a record: where an appended DataArray's offset="" value is, and the
 * value, so a spliced write can shift it. */
static qdc_status vtu_note_offset(vtu *x, const xtag *t, qdc_error *err)
{
    const char *v, *ve;
    int64_t off;
    uint64_t *a;

    if (!x->rec || !attr_is(t, "format", "appended") || !tag_attr(t, "offset", &v, &ve))
        return QDC_OK;
    while (v < ve && is_space((unsigned char)*v))
        v++;
    while (ve > v && is_space((unsigned char)ve[-1]))
        ve--;
    if (parse_int(v, ve, 0, &off) != 0 || off < 0) { /* its reader says so, if read */
        srcrec_refuse(x->rec, "VTU: an appended offset is not a number");
        return QDC_OK;
    }
    if (vec_grow(&x->rec->appoff, 3) != 0)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    a = (uint64_t *)x->rec->appoff.a + x->rec->appoff.n;
    a[0] = (uint64_t)(v - x->s.base);
    a[1] = (uint64_t)(ve - x->s.base);
    a[2] = (uint64_t)off;
    x->rec->appoff.n += 3;
    return QDC_OK;
}

/* The end of the appended array at offset off (raw or base64, zlib or not),
 * or NULL if its header does not fit. */
static const char *app_extent(vtu *x, uint64_t off)
{
    size_t hsz = x->hdr8 ? 8 : 4, hn = x->zlib ? 3 * hsz : hsz, left;
    const char *p, *endp = NULL;
    unsigned char *h = NULL;
    uint64_t n = 0;

    if (off > (uint64_t)(x->s.end - x->appended))
        return NULL;
    p = x->appended + off;
    left = (size_t)(x->s.end - p);
    if (!x->app_base64) {
        const unsigned char *b = (const unsigned char *)p;
        if (left < hn)
            return NULL;
        if (!x->zlib) {
            n = hdr_word(x, b, 0);
            return n <= left - hn ? p + hn + n : NULL;
        }
        n = hdr_word(x, b, 0);
        if (n > (left - hn) / hsz)
            return NULL;
        hn += (size_t)n * hsz;
        n = 0;
        for (uint64_t k = 0, c; k < hdr_word(x, b, 0); k++, n += c)
            if ((c = hdr_word(x, b, 3 + k)) > left - hn - n)
                return NULL;
        return p + hn + n;
    }
    if (b64_take(x, p, hn, &h, &endp, NULL) != QDC_OK)
        goto fail;
    n = hdr_word(x, h, 0);
    if (x->zlib) {
        uint64_t nb = n;
        if (nb > left / hsz ||
            b64_take(x, p, hn + (size_t)nb * hsz, &h, &endp, NULL) != QDC_OK)
            goto fail;
        hn += (size_t)nb * hsz;
        n = 0;
        for (uint64_t k = 0, c; k < nb; k++, n += c)
            if ((c = hdr_word(x, h, 3 + k)) > left - n)
                goto fail;
    }
    if (n > left || b64_take(x, p, hn + (size_t)n, &h, &endp, NULL) != QDC_OK)
        goto fail;
    qdc_free(h);
    return endp;
fail:
    qdc_free(h);
    return NULL;
}

/* A spliced write replaces the appended Points block: no other array may
 * share its bytes (a valid file never does; a damaged one is not spliced). */
static void check_app_overlap(vtu *x)
{
    srcrec *r = x->rec;
    const uint64_t *ao = r->appoff.a;
    int self = 0;

    for (size_t i = 0; i + 3 <= r->appoff.n; i += 3) {
        const char *e;
        if (ao[i + 2] == r->app_off && !self++)
            continue;
        e = app_extent(x, ao[i + 2]); /* NULL unless the offset is within the input */
        if (!e || ((uint64_t)(x->appended - x->s.base) + ao[i + 2] < r->blk_b &&
                   (uint64_t)(e - x->s.base) > r->blk_a)) {
            srcrec_refuse(r, "VTU: an appended array overlaps the Points");
            return;
        }
    }
}

/* Find <AppendedData ...> and its '_' first (offsets point into it). */
static qdc_status find_appended(vtu *x, qdc_error *err)
{
    static const char key[] = "<AppendedData";
    const char *p = x->s.base, *e = x->s.end;

    for (; p + sizeof key - 1 <= e; p++) {
        if (memcmp(p, key, sizeof key - 1) == 0) {
            vtu y = *x;
            xtag t;
            qdc_status st;
            y.s.p = p;
            st = next_tag(&y, &t, err);
            if (st != QDC_OK)
                return st;
            x->app_base64 = attr_is(&t, "encoding", "base64");
            if (!x->app_base64 && !attr_is(&t, "encoding", "raw"))
                return fail_txt(err, QDC_EFORMAT, &y.s, t.name,
                                "VTU: AppendedData encoding must be raw or base64");
            for (p = t.after; p < e && *p != '_'; p++)
                ;
            if (p == e)
                return fail_txt(err, QDC_EPARSE, &y.s, t.after,
                                "VTU: no '_' in AppendedData");
            x->appended = p + 1;
            return QDC_OK;
        }
    }
    return QDC_OK;
}

/* <VTKFile>: the type, compressor, byte order and header size. */
static qdc_status vtu_file_tag(vtu *x, const xtag *t, qdc_error *err)
{
    const char *cv, *ce;

    if (!attr_is(t, "type", "UnstructuredGrid"))
        return fail_txt(err, QDC_EFORMAT, &x->s, t->name,
                        "VTU: only type=\"UnstructuredGrid\" is supported");
    if (tag_attr(t, "compressor", &cv, &ce) && ce > cv) {
        x->zlib = (size_t)(ce - cv) == 21 && memcmp(cv, "vtkZLibDataCompressor", 21) == 0;
        if (!x->zlib)
            return fail_txt(err, QDC_EFORMAT, &x->s, cv,
                            "VTU: compressor \"%.*s\" not supported (only "
                            "vtkZLibDataCompressor)",
                            (int)(ce - cv > 32 ? 32 : ce - cv), cv);
    }
    x->big = attr_is(t, "byte_order", "BigEndian");
    x->hdr8 = attr_is(t, "header_type", "UInt64");
    return QDC_OK;
}

/* The section a <Points>, <Cells>, <CellData> or <PointData> tag opens (or
 * closes: SEC_NONE); -1 for other tags. */
static int vtu_section(const xtag *t)
{
    if (!word_is(t->name, t->nlen, "Points") && !word_is(t->name, t->nlen, "Cells") &&
        !word_is(t->name, t->nlen, "CellData") && !word_is(t->name, t->nlen, "PointData"))
        return -1;
    return t->closing || t->empty                  ? SEC_NONE
           : word_is(t->name, t->nlen, "Points")   ? SEC_POINTS
           : word_is(t->name, t->nlen, "Cells")    ? SEC_CELLS
           : word_is(t->name, t->nlen, "CellData") ? SEC_CELLDATA
                                                   : SEC_POINTDATA;
}

/* The tags up to <AppendedData> or the end: the arrays into x->c, the
 * offsets (ends of the cells) into *offs_end. */
static qdc_status vtu_tags(vtu *x, double **offs_end, qdc_error *err)
{
    xtag t;
    int sec = SEC_NONE, seen_file = 0, seen_piece = 0;
    qdc_status st = QDC_OK;

    while (st == QDC_OK) {
        st = next_tag(x, &t, err);
        if (st != QDC_OK || !t.name || (x->appended && x->s.p >= x->appended))
            break;
        if (word_is(t.name, t.nlen, "VTKFile") && !t.closing) {
            st = vtu_file_tag(x, &t, err);
            seen_file = 1;
        } else if (word_is(t.name, t.nlen, "Piece") && !t.closing) {
            if (seen_piece)
                st =
                    fail_txt(err, QDC_EFORMAT, &x->s, t.name, "VTU: more than one Piece");
            if (st == QDC_OK)
                st = attr_int(x, &t, "NumberOfPoints", 0, MESH_MAX_VERTICES, &x->c.nv,
                              err);
            if (st == QDC_OK)
                st = attr_int(x, &t, "NumberOfCells", 0, INT64_MAX / 16, &x->c.nc, err);
            seen_piece = 1;
        } else if (vtu_section(&t) >= 0) {
            sec = vtu_section(&t);
        } else if (word_is(t.name, t.nlen, "DataArray") && !t.closing &&
                   (st = vtu_note_offset(x, &t, err)) != QDC_OK) {
            break;
        } else if (word_is(t.name, t.nlen, "DataArray") && !t.closing &&
                   sec != SEC_NONE) {
            if (!seen_piece)
                st = fail_txt(err, QDC_EPARSE, &x->s, t.name,
                              "VTU: DataArray outside a Piece");
            else
                st = vtu_dataarray(x, &t, sec, offs_end, err);
        } else if (word_is(t.name, t.nlen, "AppendedData")) {
            break;
        }
    }
    if (st == QDC_OK && !seen_file)
        st = fail_txt(err, QDC_EPARSE, &x->s, x->s.p, "VTU: no VTKFile element");
    if (st == QDC_OK && (!seen_piece || !x->c.xyz))
        st = fail_txt(err, QDC_EPARSE, &x->s, x->s.p, "VTU: no Piece with Points");
    return st;
}

/* After the tags: the connectivity if it came before the offsets, then the
 * nc + 1 offsets from the ends of the cells, checked. */
static qdc_status vtu_cells(vtu *x, double **offs_end, qdc_error *err)
{
    qdc_status st = QDC_OK;

    if (x->conn_tag.name && *offs_end) { /* VTK writes it before offsets */
        txt here = x->s;
        x->s = x->conn_at;
        st = vtu_dataarray(x, &x->conn_tag, SEC_CELLS, offs_end, err);
        if (st == QDC_OK)
            x->s = here;
    }
    if (st == QDC_OK && x->c.nc && (!*offs_end || !x->c.conn.v || !x->c.types.v))
        st = fail_txt(err, QDC_EPARSE, &x->s, x->s.p,
                      "VTU: Cells need connectivity, offsets and types");
    if (st != QDC_OK)
        return st;
    x->c.offs = alloc_values(x->c.nc + 1, err);
    if (!x->c.offs)
        return QDC_ENOMEM;
    x->c.offs[0] = 0;
    for (int64_t i = 0; i < x->c.nc; i++)
        x->c.offs[i + 1] = (*offs_end)[i];
    return check_offsets(x->c.offs, x->c.nc, x->c.nconn, "vtu", err);
}

static qdc_status read_vtu(const char *buf, size_t len, const meshio_options *o,
                           srcrec *rec, mesh_t **out, qdc_error *err)
{
    vtu x;
    double *offs_end = NULL; /* XML offsets: the end of each cell */
    qdc_status st;

    memset(&x, 0, sizeof x);
    x.rec = rec;
    if (rec)
        rec->fmt = MESHIO_VTU;
    x.c.creg_prio = PRIO_NONE;
    x.c.o = o;
    x.s = txt_init(buf, len, 0);
    x.b = (const unsigned char *)buf;
    x.zbudget = gz_budget(len, o ? o->max_bytes : 0, o ? o->max_ratio : 0);
    st = find_appended(&x, err);
    if (st == QDC_OK)
        st = vtu_tags(&x, &offs_end, err);
    if (st == QDC_OK)
        st = vtu_cells(&x, &offs_end, err);
    if (st == QDC_OK && rec && rec->appended && rec->kind != SRC_NONE)
        check_app_overlap(&x);
    if (st == QDC_OK && rec && rec->dv.kind == DV_NORMS)
        st = dv_finish(&rec->dv, x.c.xyz, x.c.nv, err);
    if (st == QDC_OK)
        st = cells_mesh(&x.c, "vtu", o, out, err);
    qdc_free(offs_end);
    cells_free(&x.c);
    return st;
}

/* ------------------------------------------------------------------------ */
/* VTU writer                                                                */

typedef struct {
    const char *name;
    const char *type;
    int ncomp;
    uint64_t bytes;
} vtu_arr;

static void xml_array_head(wbuf *w, const vtu_arr *a, int appended, uint64_t *off)
{
    wb_str(w, "<DataArray type=\"");
    wb_str(w, a->type);
    wb_str(w, "\"");
    if (a->name) {
        wb_str(w, " Name=\"");
        wb_str(w, a->name);
        wb_str(w, "\"");
    }
    if (a->ncomp > 1) {
        wb_str(w, " NumberOfComponents=\"");
        wb_int(w, a->ncomp);
        wb_str(w, "\"");
    }
    if (appended) {
        wb_str(w, " format=\"appended\" offset=\"");
        wb_int(w, (int64_t)*off);
        wb_str(w, "\"/>\n");
        *off += 8 + a->bytes;
    } else {
        wb_str(w, " format=\"ascii\">\n");
    }
}

/* Array k of the file's fixed list (points, connectivity, offsets, types,
 * region, medit:ref) written as data; i picks the value. */
static void vtu_data(const mesh_t *m, int k, vw *o)
{
    int64_t nc = (int64_t)m->nt + m->ntri, tn = m->mid ? 10 : 4;

    switch (k) {
    case 0:
        for (size_t i = 0; i < 3 * (size_t)m->nv; i++)
            vw_real(o, m->xyz[i]);
        break;
    case 1:
        for (size_t t = 0; t < (size_t)m->nt; t++) {
            for (size_t j = 0; j < 4; j++)
                vw_int(o, m->tets[4 * t + j], 4);
            for (size_t j = 0; m->mid && j < 6; j++)
                vw_int(o, m->mid[6 * t + j], 4);
        }
        for (size_t i = 0; i < 3 * (size_t)m->ntri; i++)
            vw_int(o, m->tris[i], 4);
        break;
    case 2:
        for (int64_t c = 0; c < nc; c++)
            vw_int(o,
                   c < m->nt ? tn * (c + 1) : tn * (int64_t)m->nt + 3 * (c - m->nt + 1),
                   8);
        break;
    case 3:
        for (int64_t c = 0; c < nc; c++)
            vw_int(o, c < m->nt ? tet_type(m) : 5, 1);
        break;
    case 4:
        for (int64_t c = 0; c < nc; c++)
            vw_int(o, cell_region(m, c), 4);
        break;
    default:
        for (int64_t i = 0; i < m->nv; i++)
            vw_int(o, m->vref[i], 4);
        break;
    }
    vw_end(o);
}

/* Point array i of m as a VTU DataArray: its name (XML's special bytes and
 * control bytes as '_') into name; an integer array Int32, or Int64 when a
 * value is beyond (*ik 4 or 8), else Float64 (*ik 0: pdata_ikind). */
static vtu_arr vtu_parr(const mesh_t *m, int32_t i, char name[256], int *ik)
{
    const mesh_parray *a = &m->pdata->a[i];
    vtu_arr r;
    size_t k = 0;

    for (const char *c = a->name; *c && k < 255; c++, k++)
        name[k] = strchr("&<>\"'", *c) || (unsigned char)*c < 32 ? '_' : *c;
    name[k] = 0;
    *ik = pdata_ikind(a, m->nv);
    r.name = name;
    r.type = !*ik ? "Float64" : *ik == 4 ? "Int32" : "Int64";
    r.ncomp = a->ncomp;
    r.bytes = (uint64_t)m->nv * (uint64_t)a->ncomp * (*ik == 4 ? 4u : 8u);
    return r;
}

/* Array k of the list (vtu_data's, then m's point arrays from 6 on). */
static vtu_arr vtu_arr_of(const mesh_t *m, const vtu_arr *fixed, int k, char name[256],
                          int *ik)
{
    return k < 6 ? fixed[k] : vtu_parr(m, k - 6, name, ik);
}

static void vtu_data_of(const mesh_t *m, int k, int ik, vw *o)
{
    if (k < 6) {
        o->per_line = 6;
        vtu_data(m, k, o);
    } else {
        vw_parray(o, &m->pdata->a[k - 6], m->nv, ik);
    }
}

static void vtu_write(const mesh_t *m, int appended, wbuf *w)
{
    int64_t nc = (int64_t)m->nt + m->ntri;
    uint64_t nconn = (m->mid ? 10 : 4) * (uint64_t)m->nt + 3 * (uint64_t)m->ntri, off = 0;
    const vtu_arr arr[6] = {{NULL, "Float64", 3, 24 * (uint64_t)m->nv},
                            {"connectivity", "Int32", 1, 4 * nconn},
                            {"offsets", "Int64", 1, 8 * (uint64_t)nc},
                            {"types", "UInt8", 1, (uint64_t)nc},
                            {"region", "Int32", 1, 4 * (uint64_t)nc},
                            {"medit:ref", "Int32", 1, 4 * (uint64_t)m->nv}};
    static const char *const open[6] = {"<Points>\n", "<Cells>\n",    "",
                                        "",           "<CellData>\n", "<PointData>\n"};
    static const char *const close[6] = {
        "</Points>\n", "", "", "</Cells>\n", "</CellData>\n", "</PointData>\n"};
    int npd = m->pdata ? m->pdata->n : 0, nk = 6 + npd, ik = 0;
    int first_pd = m->vref ? 5 : 6, last_pd = npd ? nk - 1 : 5;
    vw o = {w, appended, 0, 6, 0, 0};
    char name[256];

    wb_str(w,
           "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
           "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n"
           "<Piece NumberOfPoints=\"");
    wb_int(w, m->nv);
    wb_str(w, "\" NumberOfCells=\"");
    wb_int(w, nc);
    wb_str(w, "\">\n");
    for (int k = 0; k < nk; k++) {
        vtu_arr a;
        if ((k == 4 && !has_regions(m)) || (k == 5 && !m->vref))
            continue;
        a = vtu_arr_of(m, arr, k, name, &ik);
        wb_str(w, k < 5 ? open[k] : k == first_pd ? open[5] : "");
        xml_array_head(w, &a, appended, &off);
        if (!appended) {
            vtu_data_of(m, k, ik, &o);
            wb_str(w, "</DataArray>\n");
        }
        wb_str(w, k < 5 ? close[k] : k == last_pd ? close[5] : "");
    }
    wb_str(w, "</Piece>\n</UnstructuredGrid>\n");
    if (appended) {
        unsigned char b[8];
        wb_str(w, "<AppendedData encoding=\"raw\">\n_");
        for (int k = 0; k < nk; k++) {
            if ((k == 4 && !has_regions(m)) || (k == 5 && !m->vref))
                continue;
            put_le64(b, vtu_arr_of(m, arr, k, name, &ik).bytes);
            wb_put(w, b, 8);
            vtu_data_of(m, k, ik, &o);
        }
        wb_str(w, "\n</AppendedData>\n");
    }
    wb_str(w, "</VTKFile>\n");
}

static qdc_status write_vtk(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                            qdc_error *err)
{
    (void)part;
    (void)err;
    vtk_write(m, fmt == MESHIO_VTK, w);
    return QDC_OK;
}

static qdc_status write_vtu(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                            qdc_error *err)
{
    (void)part;
    (void)err;
    vtu_write(m, fmt == MESHIO_VTU, w);
    return QDC_OK;
}

/* "# vtk DataFile", then the third line: ASCII or BINARY. */
static meshio_format sniff_vtk(const char *p, size_t n, size_t i)
{
    if (n < 14 || memcmp(p, "# vtk DataFile", 14) != 0)
        return MESHIO_AUTO;
    for (int line = 0; line < 2 && i < n; i++)
        line += p[i] == '\n';
    while (i < n && is_space((unsigned char)p[i]))
        i++;
    return n - i >= 5 && strncasecmp(p + i, "ASCII", 5) == 0 ? MESHIO_VTK_ASCII
                                                             : MESHIO_VTK;
}

/* Where the n bytes at p first hold the k bytes of w, or NULL. */
static const char *find_bytes(const char *p, size_t n, const char *w, size_t k)
{
    for (const char *e = p + n; k <= (size_t)(e - p); p++) {
        p = memchr(p, w[0], (size_t)(e - p) - k + 1);
        if (!p)
            return NULL;
        if (memcmp(p, w, k) == 0)
            return p;
    }
    return NULL;
}

/* An XML document whose first element, within 1 kB, is a VTKFile: VTU_ASCII
 * when its Points DataArray is ascii (as the reader records it), else VTU. */
static meshio_format sniff_vtu(const char *buf, size_t len, size_t i)
{
    static const char tag[] = "<VTKFile";
    const char *p = buf + i, *e = buf + len, *pts, *da, *end;
    size_t n = len - i, lim = n < 1024 ? n : 1024;

    if (i >= len || buf[i] != '<')
        return MESHIO_AUTO;
    for (size_t k = 0; k + sizeof tag - 1 <= lim; k++) {
        if (memcmp(p + k, tag, sizeof tag - 1) != 0)
            continue;
        p += k;
        n -= k;
        if (!(pts = find_bytes(p, n, "<Points", 7)) ||
            !(da = find_bytes(pts, (size_t)(e - pts), "<DataArray", 10)) ||
            !(end = memchr(da, '>', (size_t)(e - da))))
            return MESHIO_VTU;
        return find_bytes(da, (size_t)(end - da), "format=\"ascii\"", 14) ||
                       find_bytes(da, (size_t)(end - da), "format='ascii'", 14)
                   ? MESHIO_VTU_ASCII
                   : MESHIO_VTU;
    }
    return MESHIO_AUTO;
}

/* What the variants of each VTK family share: its reader and writer (one
 * for both encodings), spliced writes, ten-node tets (VTK_QUADRATIC_TETRA),
 * point data.
 * The binary variant of each sniffs and names the family. */
#define VTK_VARIANT(ext_, read_, write_)                                                 \
    .ext = ext_, .input = "input." ext_, .read = read_, .write = write_, .splices = 1,   \
    .p2 = 1, .pdata = 1

const meshio_fmt fmt_vtk = {
    .name = "vtk",
    .aliases = "vtk-bin",
    .about = "legacy VTK UNSTRUCTURED_GRID, binary (big-endian)",
    .media = "application/vnd.vtk",
    .media_alt = "application/x-vtk",
    .magic = 1,
    .sniff = sniff_vtk,
    VTK_VARIANT("vtk", read_vtk, write_vtk),
};

const meshio_fmt fmt_vtk_ascii = {
    .name = "vtk-ascii",
    .about = "legacy VTK UNSTRUCTURED_GRID, ASCII",
    .family = MESHIO_VTK,
    .media = "application/vnd.vtk;encoding=ascii",
    VTK_VARIANT("vtk", read_vtk, write_vtk),
};

const meshio_fmt fmt_vtu = {
    .name = "vtu",
    .about = "VTK XML .vtu, appended raw data (reads ascii, base64, raw, zlib)",
    .media = "application/vnd.vtk.vtu+xml",
    .media_alt = "application/x-vtu",
    .sniff = sniff_vtu,
    VTK_VARIANT("vtu", read_vtu, write_vtu),
};

const meshio_fmt fmt_vtu_ascii = {
    .name = "vtu-ascii",
    .about = "VTK XML .vtu, ascii DataArrays",
    .family = MESHIO_VTU,
    .media = "application/vnd.vtk.vtu+xml;encoding=ascii",
    VTK_VARIANT("vtu", read_vtu, write_vtu),
};
