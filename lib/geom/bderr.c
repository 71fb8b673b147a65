/* bderr.c - boundary error (docs/method.md §9): symmetric Hausdorff distance between two
 * triangle surfaces, Metro style.
 *
 * Each side is sampled densely (every surface vertex, every face centroid, and
 * area-weighted random points) and every sample is measured exactly against
 * the other side through a BVH. Sample k of a side is a pure function of
 * (seed, side, k), and partial sums are formed per fixed-size chunk and added
 * in chunk order, so the result does not depend on the number of threads. */
#include "core/mesh_int.h"
#include "core/tet.h"
#include "geom/bderr_int.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* Sampling                                                                  */

/* splitmix64's output function: a good 64-bit mix, used as a counter-based
 * generator so sample k needs no state from samples before it. */
static uint64_t mix64(uint64_t x)
{
    x += UINT64_C(0x9e3779b97f4a7c15);
    x = (x ^ (x >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    x = (x ^ (x >> 27)) * UINT64_C(0x94d049bb133111eb);
    return x ^ (x >> 31);
}

static double unit_double(uint64_t x)
{
    return (double)(x >> 11) * 0x1.0p-53;
}

typedef struct {
    const double *xyz;
    const int32_t *tris;
    int32_t ntri;
    int32_t *verts; /* vertices used by a triangle */
    int32_t nverts;
    int32_t *tri_of; /* nv: a triangle of each used vertex (-1: unused) */
    double *cdf;     /* ntri running sums of triangle areas */
    int64_t nrand;   /* random samples (0 if the area is 0) */
    uint64_t seed;
} surface;

static void tri_corners(const surface *s, int32_t t, const double *c[3])
{
    for (int v = 0; v < 3; v++)
        c[v] = s->xyz + 3 * (size_t)s->tris[3 * (size_t)t + v];
}

static double tri_area(const double *c[3])
{
    double u[3], v[3], n[3];

    for (int d = 0; d < 3; d++) {
        u[d] = c[1][d] - c[0][d];
        v[d] = c[2][d] - c[0][d];
    }
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    return 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

static qdc_status surface_init(surface *s, const double *xyz, int32_t nv,
                               const int32_t *tris, int32_t ntri, int64_t nrand,
                               uint64_t seed, qdc_error *err)
{
    uint8_t *used;
    double acc = 0;

    memset(s, 0, sizeof *s);
    s->xyz = xyz;
    s->tris = tris;
    s->ntri = ntri;
    s->seed = seed;
    used = qdc_calloc((size_t)nv, 1);
    s->verts = qdc_mallocn((size_t)nv, sizeof(int32_t));
    s->tri_of = qdc_mallocn((size_t)nv + 1, sizeof(int32_t));
    s->cdf = qdc_mallocn((size_t)ntri, sizeof(double));
    if (!used || !s->verts || !s->cdf || !s->tri_of) {
        qdc_free(used);
        return qdc_fail(err, QDC_ENOMEM, "out of memory for surface samples");
    }
    for (int32_t v = 0; v < nv; v++)
        s->tri_of[v] = -1;
    for (int64_t i = 0; i < 3 * (int64_t)ntri; i++) {
        used[tris[i]] = 1;
        s->tri_of[tris[i]] = (int32_t)(i / 3);
    }
    for (int32_t v = 0; v < nv; v++)
        if (used[v])
            s->verts[s->nverts++] = v;
    qdc_free(used);
    for (int32_t t = 0; t < ntri; t++) {
        const double *c[3];
        tri_corners(s, t, c);
        acc += tri_area(c);
        s->cdf[t] = acc;
    }
    s->nrand = acc > 0 ? nrand : 0;
    return QDC_OK;
}

static void surface_free(surface *s)
{
    qdc_free(s->verts);
    qdc_free(s->tri_of);
    qdc_free(s->cdf);
}

static int64_t surface_count(const surface *s)
{
    return (int64_t)s->nverts + s->ntri + s->nrand;
}

/* Sample k: the vertices, then the centroids, then random points. Returns a
 * triangle the sample is on. */
static int32_t surface_point(const surface *s, int64_t k, double p[3])
{
    const double *c[3];
    double u0, s1, u2;
    int32_t lo, hi;

    if (k < s->nverts) {
        memcpy(p, s->xyz + 3 * (size_t)s->verts[k], 3 * sizeof(double));
        return s->tri_of[s->verts[k]];
    }
    k -= s->nverts;
    if (k < s->ntri) {
        tri_corners(s, (int32_t)k, c);
        for (int d = 0; d < 3; d++)
            p[d] = (c[0][d] + c[1][d] + c[2][d]) / 3;
        return (int32_t)k;
    }
    k -= s->ntri;
    u0 = unit_double(mix64(s->seed + 3 * (uint64_t)k)) * s->cdf[s->ntri - 1];
    s1 = sqrt(unit_double(mix64(s->seed + 3 * (uint64_t)k + 1)));
    u2 = unit_double(mix64(s->seed + 3 * (uint64_t)k + 2));
    lo = 0; /* first triangle whose running sum exceeds u0: never a zero-area one */
    hi = s->ntri - 1;
    while (lo < hi) {
        int32_t mid = lo + (hi - lo) / 2;
        if (s->cdf[mid] > u0)
            hi = mid;
        else
            lo = mid + 1;
    }
    tri_corners(s, lo, c);
    /* uniform on the triangle: sqrt for the first coordinate (Osada et al.) */
    for (int d = 0; d < 3; d++)
        p[d] = (1 - s1) * c[0][d] + s1 * (1 - u2) * c[1][d] + s1 * u2 * c[2][d];
    return lo;
}

enum { CHUNK = 1024 };

typedef struct {
    double max, sum, sum2;
    double vmax; /* the max over the vertex samples (the first ones) */
    int64_t n;
} dstats;

/* The samples of s in an order that keeps consecutive queries in one part of
 * the tree: by the leaf position in b of their starting triangle (a counting
 * sort, stable). *pts: their points (3 doubles each, by sample), *tri: the
 * triangle each is on, *ord: the order; all NULL when the samples are too
 * many or memory is short: the drawing order then, the same distances with
 * more cache misses (the random samples jump across the tree: on a 1M-tet
 * cube the queries took twice as long in that order). */
static void sample_order(const surface *s, const bderr_bvh *b, int64_t n, double **pts,
                         int32_t **tri, int32_t **ord)
{
    int32_t nt = bderr_bvh_size(b), *key = NULL, *cnt = NULL;

    *pts = NULL;
    *tri = NULL;
    *ord = NULL;
    if (n > BDERR_SORT_MAX || n <= 0)
        return;
    *pts = qdc_mallocn((size_t)n, 3 * sizeof(double));
    *tri = qdc_mallocn((size_t)n, sizeof(int32_t));
    *ord = qdc_mallocn((size_t)n, sizeof(int32_t));
    key = qdc_mallocn((size_t)n, sizeof(int32_t));
    cnt = qdc_calloc((size_t)nt + 2, sizeof(int32_t));
    if (!*pts || !*tri || !*ord || !key || !cnt) {
        qdc_free(*pts);
        qdc_free(*tri);
        qdc_free(*ord);
        *pts = NULL;
        *tri = NULL;
        *ord = NULL;
        goto out;
    }
#ifdef _OPENMP
#pragma omp parallel for schedule(static)
#endif
    for (int64_t k = 0; k < n; k++) { /* -1 (no triangle) first */
        (*tri)[k] = surface_point(s, k, *pts + 3 * k);
        key[k] = bderr_bvh_position(b, (*tri)[k]) + 1;
    }
    for (int64_t k = 0; k < n; k++)
        cnt[key[k] + 1]++;
    for (int32_t t = 0; t <= nt; t++)
        cnt[t + 1] += cnt[t];
    for (int64_t k = 0; k < n; k++)
        (*ord)[cnt[key[k]]++] = (int32_t)k;
out:
    qdc_free(key);
    qdc_free(cnt);
}

/* Distance d of a sample (a vertex one if vert) into the running max, the
 * vertices' max and the sums. */
static void add_distance(double d, int vert, double *mx, double *vmx, double *sm,
                         double *sm2)
{
    *mx = d > *mx ? d : *mx;
    if (vert)
        *vmx = d > *vmx ? d : *vmx;
    *sm += d;
    *sm2 += d * d;
}

/* Distances from every sample of s to the surface in b. The search for each
 * starts from the triangle of b with the sample's triangle's index: the same
 * answer (bderr_bvh_closest_near), found sooner when the two surfaces share
 * their triangles, as an input and its optimized mesh do. The sums are formed
 * per chunk of the order and added in chunk order, so they do not depend on
 * the number of threads. */
static qdc_status directed(const surface *s, const bderr_bvh *b, dstats *out,
                           qdc_error *err)
{
    int64_t n = surface_count(s), nchunk = (n + CHUNK - 1) / CHUNK;
    double *part = qdc_mallocn((size_t)nchunk, 4 * sizeof(double)), *pts;
    int32_t *tri, *ord;

    memset(out, 0, sizeof *out);
    if (!part)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for sample sums");
    sample_order(s, b, n, &pts, &tri, &ord);
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 4)
#endif
    for (int64_t c = 0; c < nchunk; c++) {
        double mx = 0, vmx = 0, sm = 0, sm2 = 0, p[3], gp[3 * BDERR_GROUP_MAX],
               gd[BDERR_GROUP_MAX];
        int32_t gn[BDERR_GROUP_MAX];
        int64_t end = (c + 1) * CHUNK < n ? (c + 1) * CHUNK : n;
        for (int64_t i = c * CHUNK; i < end;) {
            int64_t k = ord ? ord[i] : i;
            int32_t g = 0, leaf;
            double d;
            if (!ord) {
                d = bderr_bvh_closest_near(b, p, surface_point(s, k, p), NULL, NULL);
                add_distance(d, k < s->nverts, &mx, &vmx, &sm, &sm2);
                i++;
                continue;
            }
            /* the samples of one leaf of b (consecutive in the order) at once */
            leaf = bderr_bvh_leaf_of(b, tri[k]);
            while (i + g < end && g < BDERR_GROUP_MAX && leaf >= 0 &&
                   bderr_bvh_leaf_of(b, tri[ord[i + g]]) == leaf) {
                memcpy(gp + 3 * g, pts + 3 * (size_t)ord[i + g], 3 * sizeof(double));
                gn[g] = tri[ord[i + g]];
                g++;
            }
            if (g > 0 && bderr_bvh_closest_group(b, g, gp, gn, gd)) {
                for (int32_t j = 0; j < g; j++)
                    add_distance(gd[j], ord[i + j] < s->nverts, &mx, &vmx, &sm, &sm2);
                i += g;
                continue;
            }
            d = bderr_bvh_closest_near(b, pts + 3 * k, tri[k], NULL, NULL);
            add_distance(d, k < s->nverts, &mx, &vmx, &sm, &sm2);
            i++;
        }
        part[4 * c] = mx;
        part[4 * c + 1] = sm;
        part[4 * c + 2] = sm2;
        part[4 * c + 3] = vmx;
    }
    for (int64_t c = 0; c < nchunk; c++) {
        out->max = part[4 * c] > out->max ? part[4 * c] : out->max;
        out->sum += part[4 * c + 1];
        out->sum2 += part[4 * c + 2];
        out->vmax = part[4 * c + 3] > out->vmax ? part[4 * c + 3] : out->vmax;
    }
    out->n = n;
    qdc_free(part);
    qdc_free(pts);
    qdc_free(tri);
    qdc_free(ord);
    return QDC_OK;
}

/* Diagonal of the bounding box of the used vertices. */
static double surface_diag(const surface *s)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY},
           hi[3] = {-INFINITY, -INFINITY, -INFINITY};

    if (s->nverts == 0)
        return 0;
    for (int32_t i = 0; i < s->nverts; i++)
        for (int d = 0; d < 3; d++) {
            double x = s->xyz[3 * (size_t)s->verts[i] + d];
            lo[d] = fmin(lo[d], x);
            hi[d] = fmax(hi[d], x);
        }
    for (int d = 0; d < 3; d++)
        lo[d] -= hi[d];
    return sqrt(lo[0] * lo[0] + lo[1] * lo[1] + lo[2] * lo[2]);
}

qdc_status bderr_surfaces(const double *xa, int32_t nva, const int32_t *ta, int32_t nta,
                          const double *xb, int32_t nvb, const int32_t *tb, int32_t ntb,
                          int64_t samples_per_side, uint64_t seed, bderr_result *r,
                          qdc_error *err)
{
    surface sa, sb;
    bderr_bvh *ba = NULL, *bb = NULL;
    dstats da, db;
    qdc_status st;
    int64_t n;

    if (!r || samples_per_side < 0 || samples_per_side > (INT64_C(1) << 40))
        return qdc_fail(err, QDC_EINVAL, "bderr_surfaces: invalid arguments");
    memset(r, 0, sizeof *r);
    if (nta <= 0 || ntb <= 0)
        return qdc_fail(err, QDC_EINVAL,
                        "bderr_surfaces: empty surface (%d and %d triangles)", nta, ntb);
    /* the same triangles on both sides (a result and its input): A's tree is
     * B's, refitted (the build was a tenth of the report of a 1M-tet cube);
     * the figures then do not depend on whether the caller passed one list
     * or two equal ones */
    st = bderr_bvh_build(xb, nvb, tb, ntb, &bb, err);
    if (st == QDC_OK && nta == ntb &&
        (ta == tb || !memcmp(ta, tb, 3 * (size_t)nta * sizeof(int32_t))))
        st = bderr_bvh_refit(bb, xa, nva, &ba, err);
    else if (st == QDC_OK)
        st = bderr_bvh_build(xa, nva, ta, nta, &ba, err);
    if (st != QDC_OK) {
        bderr_bvh_free(ba);
        bderr_bvh_free(bb);
        return st;
    }
    memset(&sb, 0, sizeof sb);
    st = surface_init(&sa, xa, nva, ta, nta, samples_per_side, mix64(seed), err);
    if (st == QDC_OK)
        st = surface_init(&sb, xb, nvb, tb, ntb, samples_per_side, mix64(~seed), err);
    if (st == QDC_OK)
        st = directed(&sa, bb, &da, err);
    if (st == QDC_OK)
        st = directed(&sb, ba, &db, err);
    if (st == QDC_OK) {
        n = da.n + db.n;
        r->h_a_to_b = da.max;
        r->h_b_to_a = db.max;
        r->hausdorff = fmax(da.max, db.max);
        r->vertex_max = da.vmax;
        r->mean = (da.sum + db.sum) / (double)n;
        r->rms = sqrt((da.sum2 + db.sum2) / (double)n);
        r->diag = surface_diag(&sb);
        if (r->diag > 0) {
            r->hausdorff_rel = r->hausdorff / r->diag;
            r->mean_rel = r->mean / r->diag;
            r->rms_rel = r->rms / r->diag;
            r->vertex_max_rel = r->vertex_max / r->diag;
        }
        r->n_samples = n;
        r->ntri_a = nta;
        r->ntri_b = ntb;
    }
    surface_free(&sa);
    surface_free(&sb);
    bderr_bvh_free(ba);
    bderr_bvh_free(bb);
    return st;
}

/* ------------------------------------------------------------------------ */
/* Boundary faces                                                            */

/* Local faces of a tet, each seen from outside a positive tet. */

typedef struct {
    uint64_t key; /* the two larger vertices of the face */
    int32_t face; /* 4 * tet + local face */
} face_rec;

static int face_cmp(const void *a, const void *b)
{
    uint64_t x = ((const face_rec *)a)->key, y = ((const face_rec *)b)->key;

    return x < y ? -1 : x > y;
}

/* Buckets hold a dozen faces or so: insertion sort, qsort for the odd big one. */
static void sort_faces(face_rec *r, int64_t n)
{
    if (n > 32) {
        qsort(r, (size_t)n, sizeof *r, face_cmp);
        return;
    }
    for (int64_t i = 1; i < n; i++) {
        face_rec x = r[i];
        int64_t j = i;
        while (j > 0 && r[j - 1].key > x.key) {
            r[j] = r[j - 1];
            j--;
        }
        r[j] = x;
    }
}

static void face_sorted(const int32_t *t, int f, int32_t s[3])
{
    tet_sort3(t[tet_face_of[f][0]], t[tet_face_of[f][1]], t[tet_face_of[f][2]], s);
}

/* Faces of exactly one tet, as triangles in the tet's orientation. Faces are
 * bucketed by their smallest vertex (a counting sort), then each small bucket
 * is sorted by the other two, so equal faces end up side by side. */
static qdc_status boundary_faces(const mesh_t *m, const char *what, int32_t **out,
                                 int32_t *nout, qdc_error *err)
{
    int64_t nf = 4 * (int64_t)m->nt;
    int64_t *start = NULL;
    face_rec *rec = NULL;
    int32_t *tris = NULL, nb = 0;
    qdc_status st = QDC_OK;

    *out = NULL;
    *nout = 0;
    if (m->nv < 0 || m->nt < 0 || (m->nt && !m->tets) || (m->nv && !m->xyz))
        return qdc_fail(err, QDC_EINVAL, "%s: invalid mesh", what);
    for (int64_t i = 0; i < nf; i++)
        if (m->tets[i] < 0 || m->tets[i] >= m->nv)
            return qdc_fail(err, QDC_EINVAL, "%s: tet %lld: vertex %d out of range", what,
                            (long long)(i / 4), m->tets[i]);
    start = qdc_calloc((size_t)m->nv + 1, sizeof(int64_t));
    rec = qdc_mallocn((size_t)nf, sizeof *rec);
    if (!start || !rec) {
        st = qdc_fail(err, QDC_ENOMEM, "%s: out of memory for faces", what);
        goto out;
    }
    for (int64_t f = 0; f < nf; f++) {
        int32_t s[3];
        face_sorted(m->tets + 4 * (f / 4), (int)(f % 4), s);
        start[s[0] + 1]++;
    }
    for (int32_t v = 0; v < m->nv; v++)
        start[v + 1] += start[v];
    for (int64_t f = 0; f < nf; f++) {
        int32_t s[3];
        face_sorted(m->tets + 4 * (f / 4), (int)(f % 4), s);
        rec[start[s[0]]].key = (uint64_t)s[1] << 32 | (uint32_t)s[2];
        rec[start[s[0]]++].face = (int32_t)f;
    }
    for (int32_t v = m->nv; v > 0; v--) /* the fill moved each start to the next one */
        start[v] = start[v - 1];
    start[0] = 0;
    for (int32_t v = 0; v < m->nv; v++)
        sort_faces(rec + start[v], start[v + 1] - start[v]);
    /* count, then fill: a run of one record is a boundary face */
    for (int pass = 0; pass < 2; pass++) {
        nb = 0;
        for (int32_t v = 0; v < m->nv; v++) {
            for (int64_t i = start[v]; i < start[v + 1];) {
                int64_t j = i + 1;
                while (j < start[v + 1] && rec[j].key == rec[i].key)
                    j++;
                if (j == i + 1 && pass == 1) {
                    const int32_t *t = m->tets + 4 * (size_t)(rec[i].face / 4);
                    for (int k = 0; k < 3; k++)
                        tris[3 * (size_t)nb + k] = t[tet_face_of[rec[i].face % 4][k]];
                }
                nb += j == i + 1;
                i = j;
            }
        }
        if (pass == 0) {
            tris = qdc_mallocn(3 * (size_t)nb, sizeof(int32_t));
            if (!tris) {
                st = qdc_fail(err, QDC_ENOMEM, "%s: out of memory for faces", what);
                goto out;
            }
        }
    }
    *out = tris;
    *nout = nb;
out:
    qdc_free(start);
    qdc_free(rec);
    return st;
}

/* bderr_meshes on the boundary triangles ta (na) of out and tb (nb) of ref. */
static qdc_status meshes_with(const mesh_t *out, const mesh_t *ref, const int32_t *ta,
                              int32_t na, const int32_t *tb, int32_t nb,
                              int64_t samples_per_side, bderr_result *r, qdc_error *err)
{
    qdc_status st = QDC_OK;
    double lo[3], hi[3], diag, *xa = NULL, *xb = NULL;

    diag = mesh_bbox(ref, lo, hi);
    if (isfinite(diag) && diag > 0 && (diag < 1e-50 || diag > 1e50)) {
        /* squared distances of a mesh of size 1e200 overflow, of 1e-200
         * underflow: measure in units of the reference's diagonal */
        xa = qdc_mallocn(3 * (size_t)out->nv + 1, sizeof(double));
        xb = qdc_mallocn(3 * (size_t)ref->nv + 1, sizeof(double));
        if (!xa || !xb) {
            st = QDC_ENOMEM;
        } else {
            for (size_t i = 0; i < 3 * (size_t)out->nv; i++)
                xa[i] = (out->xyz[i] - lo[i % 3]) / diag;
            for (size_t i = 0; i < 3 * (size_t)ref->nv; i++)
                xb[i] = (ref->xyz[i] - lo[i % 3]) / diag;
            st = bderr_surfaces(xa, out->nv, ta, na, xb, ref->nv, tb, nb,
                                samples_per_side, UINT64_C(0x51ab5eed), r, err);
            if (st == QDC_OK) {
                r->hausdorff *= diag;
                r->h_a_to_b *= diag;
                r->h_b_to_a *= diag;
                r->mean *= diag;
                r->rms *= diag;
                r->diag = diag;
            }
        }
    } else {
        st = bderr_surfaces(out->xyz, out->nv, ta, na, ref->xyz, ref->nv, tb, nb,
                            samples_per_side, UINT64_C(0x51ab5eed), r, err);
    }
    qdc_free(xa);
    qdc_free(xb);
    return st;
}

qdc_status bderr_meshes(const mesh_t *out, const mesh_t *ref, int64_t samples_per_side,
                        bderr_result *r, qdc_error *err)
{
    int32_t *ta = NULL, *tb = NULL, na = 0, nb = 0;
    qdc_status st;

    if (!out || !ref || !r)
        return qdc_fail(err, QDC_EINVAL, "bderr_meshes: NULL argument");
    st = boundary_faces(out, "output mesh", &ta, &na, err);
    if (st == QDC_OK)
        st = boundary_faces(ref, "reference mesh", &tb, &nb, err);
    if (st == QDC_OK)
        st = meshes_with(out, ref, ta, na, tb, nb, samples_per_side, r, err);
    qdc_free(ta);
    qdc_free(tb);
    return st;
}

qdc_status bderr_meshes_faces(const mesh_t *out, const mesh_t *ref, const mesh_faces *f,
                              int64_t samples_per_side, bderr_result *r, qdc_error *err)
{
    if (!f)
        return bderr_meshes(out, ref, samples_per_side, r, err);
    if (!out || !ref || !r || out->nt != f->nt || ref->nt != f->nt || out->nv != ref->nv)
        return qdc_fail(err, QDC_EINVAL, "bderr_meshes_faces: invalid arguments");
    return meshes_with(out, ref, f->tris, f->ntri, f->tris, f->ntri, samples_per_side, r,
                       err);
}
