/* p2.c - second-order (10-node) tets after a run on their corners: the
 * mid-edge nodes moved with their edges, kept on the input's curved boundary,
 * and the element's Jacobian kept positive at its nodes (p2.h). */
#include "opt/p2.h"

#include "core/tet.h"
#include "geom/bderr_int.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The 10 nodes of the element in reference coordinates (r, s, t). */
static const double p2_ref[11][3] = {{0, 0, 0},     {1, 0, 0},         {0, 1, 0},
                                     {0, 0, 1},     {0.5, 0, 0},       {0.5, 0.5, 0},
                                     {0, 0.5, 0},   {0, 0, 0.5},       {0.5, 0, 0.5},
                                     {0, 0.5, 0.5}, {0.25, 0.25, 0.25}};

static double det3(const double a[3], const double b[3], const double c[3])
{
    return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
           a[2] * (b[0] * c[1] - b[1] * c[0]);
}

double p2_jacobian(const double x[10][3], double r, double s, double t)
{
    static const double dl[4][3] = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const double l[4] = {1 - r - s - t, r, s, t};
    double col[3][3] = {{0}}; /* col[j]: d x / d (r, s, t)_j */

    for (int k = 0; k < 4; k++)
        for (int j = 0; j < 3; j++) {
            double dn = (4 * l[k] - 1) * dl[k][j];
            for (int i = 0; i < 3; i++)
                col[j][i] += x[k][i] * dn;
        }
    for (int e = 0; e < 6; e++) {
        int a = mesh_p2_edges[e][0], b = mesh_p2_edges[e][1];
        for (int j = 0; j < 3; j++) {
            double dn = 4 * (l[b] * dl[a][j] + l[a] * dl[b][j]);
            for (int i = 0; i < 3; i++)
                col[j][i] += x[4 + e][i] * dn;
        }
    }
    return det3(col[0], col[1], col[2]);
}

double p2_scaled_jacobian(const double x[10][3])
{
    double e[3][3], d0, lo = DBL_MAX;

    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 3; i++)
            e[j][i] = x[j + 1][i] - x[0][i];
    d0 = det3(e[0], e[1], e[2]);
    if (d0 == 0 || !isfinite(d0))
        return -1;
    for (int k = 0; k < 11; k++)
        lo = fmin(lo, p2_jacobian(x, p2_ref[k][0], p2_ref[k][1], p2_ref[k][2]) / d0);
    return lo;
}

/* The point and the two tangents of the quadratic triangle at (u, v). */
static void tri_eval(const double x[6][3], double u, double v, double p[3], double du[3],
                     double dv[3])
{
    const double l[3] = {1 - u - v, u, v};
    const double dl[3][2] = {{-1, -1}, {1, 0}, {0, 1}};
    static const int te[3][2] = {{0, 1}, {1, 2}, {0, 2}};

    for (int i = 0; i < 3; i++)
        p[i] = du[i] = dv[i] = 0;
    for (int k = 0; k < 3; k++) {
        double n = l[k] * (2 * l[k] - 1), g = 4 * l[k] - 1;
        for (int i = 0; i < 3; i++) {
            p[i] += n * x[k][i];
            du[i] += g * dl[k][0] * x[k][i];
            dv[i] += g * dl[k][1] * x[k][i];
        }
    }
    for (int e = 0; e < 3; e++) {
        int a = te[e][0], b = te[e][1];
        double n = 4 * l[a] * l[b];
        double gu = 4 * (l[b] * dl[a][0] + l[a] * dl[b][0]);
        double gv = 4 * (l[b] * dl[a][1] + l[a] * dl[b][1]);
        for (int i = 0; i < 3; i++) {
            p[i] += n * x[3 + e][i];
            du[i] += gu * x[3 + e][i];
            dv[i] += gv * x[3 + e][i];
        }
    }
}

static void clamp_uv(double uv[2])
{
    uv[0] = fmax(uv[0], 0);
    uv[1] = fmax(uv[1], 0);
    if (uv[0] + uv[1] > 1) {
        double over = (uv[0] + uv[1] - 1) / 2;
        uv[0] -= over;
        uv[1] -= over;
        uv[0] = fmin(fmax(uv[0], 0), 1);
        uv[1] = 1 - uv[0];
    }
}

double p2_tri_closest(const double x[6][3], const double p[3], double uv[2], double cp[3])
{
    double best = DBL_MAX, bu[2];

    clamp_uv(uv);
    bu[0] = uv[0];
    bu[1] = uv[1];
    for (int it = 0; it < 40; it++) {
        double q[3], du[3], dv[3], r[3], a11 = 0, a12 = 0, a22 = 0, b1 = 0, b2 = 0, det,
                                         d;
        tri_eval(x, uv[0], uv[1], q, du, dv);
        for (int i = 0; i < 3; i++) {
            r[i] = q[i] - p[i];
            a11 += du[i] * du[i];
            a12 += du[i] * dv[i];
            a22 += dv[i] * dv[i];
            b1 += du[i] * r[i];
            b2 += dv[i] * r[i];
        }
        d = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        if (d < best) {
            best = d;
            bu[0] = uv[0];
            bu[1] = uv[1];
            memcpy(cp, q, sizeof q);
        }
        det = a11 * a22 - a12 * a12;
        if (!(det > 0))
            break;
        {
            double su = -(a22 * b1 - a12 * b2) / det, sv = -(a11 * b2 - a12 * b1) / det;
            double u0 = uv[0], v0 = uv[1];
            uv[0] += su;
            uv[1] += sv;
            clamp_uv(uv);
            if (fabs(uv[0] - u0) + fabs(uv[1] - v0) < 1e-15) /* converged, or */
                break;                                       /* stopped at a side */
        }
    }
    uv[0] = bu[0];
    uv[1] = bu[1];
    return best;
}

/* The element of tet t at coordinates x. */
static void gather(const double *x, const int32_t *tt, const int32_t *mid,
                   double e[10][3])
{
    for (int k = 0; k < 4; k++)
        memcpy(e[k], x + 3 * (size_t)tt[k], sizeof e[k]);
    for (int k = 0; k < 6; k++)
        memcpy(e[4 + k], x + 3 * (size_t)mid[k], sizeof e[k]);
}

static int moved(const double *x, const double *x0, int32_t v)
{
    return memcmp(x + 3 * (size_t)v, x0 + 3 * (size_t)v, 3 * sizeof(double)) != 0;
}

/* A face of a tet (its sorted vertices), for the boundary faces. */
typedef struct {
    int32_t v[3];
    int32_t tf; /* 4 * tet + local face */
} p2_face;

static int face_cmp(const void *a, const void *b)
{
    const p2_face *x = a, *y = b;

    for (int k = 0; k < 3; k++)
        if (x->v[k] != y->v[k])
            return x->v[k] < y->v[k] ? -1 : 1;
    return 0;
}

/* The input's curved boundary: the quadratic triangles (6 vertex indices
 * each, corners first) and a BVH over their corner triangles. */
typedef struct {
    int32_t n;
    int32_t *tri6;            /* 6*n */
    int32_t *tri3;            /* 3*n */
    int32_t *vt_ptr, *vt_idx; /* the triangles around each vertex (CSR, nv+1) */
    bderr_bvh *bvh;           /* over tri3 at the input's coordinates */
} p2_surface;

static qdc_status surface_build(const mesh_t *m, const double *x0, uint8_t *role,
                                p2_surface *s, qdc_error *err)
{
    int eidx[4][4];
    size_t nf = (size_t)m->nt * 4;
    p2_face *f = qdc_mallocn(nf + 1, sizeof *f);
    qdc_status st = QDC_OK;

    memset(s, 0, sizeof *s);
    if (!f)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the faces");
    for (int e = 0; e < 6; e++) {
        eidx[mesh_p2_edges[e][0]][mesh_p2_edges[e][1]] = e;
        eidx[mesh_p2_edges[e][1]][mesh_p2_edges[e][0]] = e;
    }
    for (size_t i = 0; i < nf; i++) {
        const int32_t *tt = m->tets + 4 * (i / 4);
        const int *fo = tet_face_of[i % 4];
        tet_sort3(tt[fo[0]], tt[fo[1]], tt[fo[2]], f[i].v);
        f[i].tf = (int32_t)i;
    }
    qsort(f, nf, sizeof *f, face_cmp);
    s->tri6 = qdc_mallocn(nf * 6 + 1, sizeof(int32_t));
    s->tri3 = qdc_mallocn(nf * 3 + 1, sizeof(int32_t));
    if (!s->tri6 || !s->tri3) {
        st = qdc_fail(err, QDC_ENOMEM, "out of memory for the boundary");
        goto out;
    }
    for (size_t i = 0, j; i < nf; i = j) {
        for (j = i + 1; j < nf && face_cmp(&f[i], &f[j]) == 0; j++)
            ;
        if (j - i == 1) {
            int32_t t = f[i].tf / 4;
            const int *fo = tet_face_of[f[i].tf % 4];
            const int32_t *tt = m->tets + 4 * (size_t)t, *mid = m->mid + 6 * (size_t)t;
            int32_t *o = s->tri6 + 6 * (size_t)s->n;
            for (int k = 0; k < 3; k++) {
                o[k] = tt[fo[k]];
                s->tri3[3 * (size_t)s->n + (size_t)k] = o[k];
            }
            o[3] = mid[eidx[fo[0]][fo[1]]];
            o[4] = mid[eidx[fo[1]][fo[2]]];
            o[5] = mid[eidx[fo[0]][fo[2]]];
            for (int k = 3; k < 6; k++)
                role[o[k]] = 2;
            for (int k = 0; k < 3; k++)
                role[o[k]] = 3;
            s->n++;
        }
    }
    s->vt_ptr = qdc_calloc((size_t)m->nv + 2, sizeof(int32_t));
    s->vt_idx = qdc_mallocn((size_t)s->n * 3 + 1, sizeof(int32_t));
    if (!s->vt_ptr || !s->vt_idx) {
        st = qdc_fail(err, QDC_ENOMEM, "out of memory for the boundary");
        goto out;
    }
    for (size_t i = 0; i < (size_t)s->n * 3; i++)
        s->vt_ptr[s->tri3[i] + 2]++;
    for (int32_t v = 0; v < m->nv; v++)
        s->vt_ptr[v + 2] += s->vt_ptr[v + 1];
    for (size_t i = 0; i < (size_t)s->n * 3; i++)
        s->vt_idx[s->vt_ptr[s->tri3[i] + 1]++] = (int32_t)(i / 3);
    st = bderr_bvh_build(x0, m->nv, s->tri3, s->n, &s->bvh, err);
out:
    qdc_free(f);
    return st;
}

static void surface_free(p2_surface *s)
{
    qdc_free(s->tri6);
    qdc_free(s->tri3);
    qdc_free(s->vt_ptr);
    qdc_free(s->vt_idx);
    bderr_bvh_free(s->bvh);
}

/* The closest point cp to p on quadratic triangle tri of the input's
 * boundary, from the barycentric of lin (a point of its corner triangle). */
static double patch_closest(const p2_surface *s, const double *x0, int32_t tri,
                            const double p[3], const double lin[3], double cp[3])
{
    double q[6][3], uv[2], e1[3], e2[3], w[3];
    double a11 = 0, a12 = 0, a22 = 0, b1 = 0, b2 = 0, det;

    for (int k = 0; k < 6; k++)
        memcpy(q[k], x0 + 3 * (size_t)s->tri6[6 * (size_t)tri + (size_t)k], sizeof q[k]);
    for (int i = 0; i < 3; i++) {
        e1[i] = q[1][i] - q[0][i];
        e2[i] = q[2][i] - q[0][i];
        w[i] = lin[i] - q[0][i];
        a11 += e1[i] * e1[i];
        a12 += e1[i] * e2[i];
        a22 += e2[i] * e2[i];
        b1 += e1[i] * w[i];
        b2 += e2[i] * w[i];
    }
    det = a11 * a22 - a12 * a12;
    uv[0] = det > 0 ? (a22 * b1 - a12 * b2) / det : 1.0 / 3;
    uv[1] = det > 0 ? (a11 * b2 - a12 * b1) / det : 1.0 / 3;
    return p2_tri_closest((const double(*)[3])q, p, uv, cp);
}

/* The closest point cp to p on the input's curved boundary: on the patches
 * of the corner triangle closest to p and of the triangles around its
 * corners (a curved patch bulges past its corner triangle's neighbours);
 * the distance. */
static double surface_closest(const p2_surface *s, const double *x0, const double p[3],
                              double cp[3])
{
    double lin[3], best;
    int32_t tri = -1;

    if (!isfinite(bderr_bvh_closest(s->bvh, p, lin, &tri)) || tri < 0) {
        memcpy(cp, p, 3 * sizeof(double));
        return 0;
    }
    best = patch_closest(s, x0, tri, p, lin, cp);
    for (int k = 0; k < 3; k++) {
        int32_t v = s->tri3[3 * (size_t)tri + (size_t)k];
        for (int32_t i = s->vt_ptr[v]; i < s->vt_ptr[v + 1]; i++) {
            int32_t u = s->vt_idx[i];
            double l2[3], c2[3], d;
            if (u == tri)
                continue;
            bderr_point_triangle(p, x0 + 3 * (size_t)s->tri3[3 * (size_t)u],
                                 x0 + 3 * (size_t)s->tri3[3 * (size_t)u + 1],
                                 x0 + 3 * (size_t)s->tri3[3 * (size_t)u + 2], l2);
            d = patch_closest(s, x0, u, p, l2, c2);
            if (d < best) {
                best = d;
                memcpy(cp, c2, sizeof c2);
            }
        }
    }
    return best;
}

/* Each mid-edge node whose edge moved: the new midpoint plus its input
 * offset mapped by the average of the affine maps of its tets' corners.
 * first[v]: 6 * tet + edge of v's first appearance (-1: no mid-edge node). */
static void transport(mesh_t *m, const double *x0, const int32_t *first, double *sum,
                      int32_t *cnt)
{
    double *x = m->xyz;

    for (int32_t t = 0; t < m->nt; t++) {
        const int32_t *tt = m->tets + 4 * (size_t)t, *mid = m->mid + 6 * (size_t)t;
        double e0[3][3], e1[3][3], d0, inv[3][3];
        for (int j = 0; j < 3; j++)
            for (int i = 0; i < 3; i++) {
                e0[j][i] = x0[3 * (size_t)tt[j + 1] + (size_t)i] -
                           x0[3 * (size_t)tt[0] + (size_t)i];
                e1[j][i] = x[3 * (size_t)tt[j + 1] + (size_t)i] -
                           x[3 * (size_t)tt[0] + (size_t)i];
            }
        d0 = det3(e0[0], e0[1], e0[2]);
        if (geom_tet_degenerate(fabs(d0), geom_tet_l2sum(x0, tt)) ||
            geom_tet_degenerate(fabs(det3(e1[0], e1[1], e1[2])), geom_tet_l2sum(x, tt)))
            continue;
        /* inv: rows are the dual basis of the columns e0[j] */
        {
            double c[3][3];
            for (int j = 0; j < 3; j++) {
                const double *a = e0[(j + 1) % 3], *b = e0[(j + 2) % 3];
                c[j][0] = a[1] * b[2] - a[2] * b[1];
                c[j][1] = a[2] * b[0] - a[0] * b[2];
                c[j][2] = a[0] * b[1] - a[1] * b[0];
                for (int i = 0; i < 3; i++)
                    inv[j][i] = c[j][i] / d0;
            }
        }
        for (int e = 0; e < 6; e++) {
            int32_t v = mid[e], a = tt[mesh_p2_edges[e][0]], b = tt[mesh_p2_edges[e][1]];
            double off[3], lam[3];
            if (!moved(x, x0, a) && !moved(x, x0, b))
                continue;
            for (int i = 0; i < 3; i++)
                off[i] =
                    x0[3 * (size_t)v + (size_t)i] -
                    0.5 * (x0[3 * (size_t)a + (size_t)i] + x0[3 * (size_t)b + (size_t)i]);
            for (int j = 0; j < 3; j++)
                lam[j] = inv[j][0] * off[0] + inv[j][1] * off[1] + inv[j][2] * off[2];
            for (int i = 0; i < 3; i++)
                sum[3 * (size_t)v + (size_t)i] +=
                    e1[0][i] * lam[0] + e1[1][i] * lam[1] + e1[2][i] * lam[2];
            cnt[v]++;
        }
    }
    for (int32_t v = 0; v < m->nv; v++) {
        int32_t a, b, t;
        double l0 = 0, l1 = 0;
        if (first[v] < 0)
            continue;
        t = first[v] / 6;
        a = m->tets[4 * (size_t)t + (size_t)mesh_p2_edges[first[v] % 6][0]];
        b = m->tets[4 * (size_t)t + (size_t)mesh_p2_edges[first[v] % 6][1]];
        if ((!moved(x, x0, a) && !moved(x, x0, b)) || (m->fixed && m->fixed[v]))
            continue;
        for (int i = 0; i < 3; i++) {
            double d0 = x0[3 * (size_t)b + (size_t)i] - x0[3 * (size_t)a + (size_t)i];
            double d1 = x[3 * (size_t)b + (size_t)i] - x[3 * (size_t)a + (size_t)i];
            l0 += d0 * d0;
            l1 += d1 * d1;
        }
        for (int i = 0; i < 3; i++) {
            double mp =
                0.5 * (x[3 * (size_t)a + (size_t)i] + x[3 * (size_t)b + (size_t)i]);
            double off =
                x0[3 * (size_t)v + (size_t)i] -
                0.5 * (x0[3 * (size_t)a + (size_t)i] + x0[3 * (size_t)b + (size_t)i]);
            /* no tet around the edge was a proper map: the offset scaled with
             * the edge */
            x[3 * (size_t)v + (size_t)i] =
                mp + (cnt[v] ? sum[3 * (size_t)v + (size_t)i] / cnt[v]
                             : (l0 > 0 ? off * sqrt(l1 / l0) : off));
        }
    }
}

/* 1 if both corners of the edge at 6 * tet + edge fe are within bound
 * (and a rounding's width) of the input's boundary. */
static int corners_on_input(const mesh_t *m, const p2_surface *s, int32_t fe,
                            double bound)
{
    const int32_t *tt = m->tets + 4 * (size_t)(fe / 6);

    for (int k = 0; k < 2; k++) {
        const double *p = m->xyz + 3 * (size_t)tt[mesh_p2_edges[fe % 6][k]];
        double tol = bound + 1e-12 * (fabs(p[0]) + fabs(p[1]) + fabs(p[2]) + 1);
        if (!(bderr_bvh_closest(s->bvh, p, NULL, NULL) <= tol))
            return 0;
    }
    return 1;
}

/* Scaled Jacobians of every element at x into j. */
static void jacobians(const mesh_t *m, const double *x, double *j)
{
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < m->nt; t++) {
        double e[10][3];
        gather(x, m->tets + 4 * (size_t)t, m->mid + 6 * (size_t)t, e);
        j[t] = p2_scaled_jacobian((const double(*)[3])e);
    }
}

/* An element's scaled Jacobian is kept at least min(input's, this): a
 * valid input element never comes out folded nor much more curved. */
#define P2_JAC_FLOOR 0.2

/* Pull the mid-edge nodes of the elements whose scaled Jacobian fell below
 * P2_JAC_FLOOR and their input's toward their straight midpoints: interior
 * ones halfway each round, then boundary ones too, then all of them onto the
 * straight edge (scaled Jacobian 1 while the corner tet is positive: the
 * optimizer never inverts one). */
static void straighten(mesh_t *m, const double *jin, double *jout, uint8_t *tries,
                       const uint8_t *role, uint8_t *pulled)
{
    double *x = m->xyz;
    uint8_t *now = qdc_calloc((size_t)m->nv + 1, 1); /* moved this round */

    for (int round = 0; round < 64; round++) {
        int any = 0;
        for (int32_t t = 0; t < m->nt; t++) {
            const int32_t *tt = m->tets + 4 * (size_t)t, *mid = m->mid + 6 * (size_t)t;
            if (!(jin[t] > 0 && jout[t] < fmin(jin[t], P2_JAC_FLOOR)))
                continue;
            any = 1;
            tries[t] += tries[t] < 255;
            for (int e = 0; e < 6; e++) {
                int32_t v = mid[e], a = tt[mesh_p2_edges[e][0]],
                        b = tt[mesh_p2_edges[e][1]];
                double f = tries[t] > 16 ? 0.0 : 0.5;
                if (role[v] == 2 && tries[t] <= 8)
                    continue; /* boundary: only if the interior ones were not enough */
                for (int i = 0; i < 3; i++) {
                    double mp = 0.5 * (x[3 * (size_t)a + (size_t)i] +
                                       x[3 * (size_t)b + (size_t)i]);
                    x[3 * (size_t)v + (size_t)i] =
                        mp + f * (x[3 * (size_t)v + (size_t)i] - mp);
                }
                pulled[v] = 1;
                if (now)
                    now[v] = 1;
            }
        }
        if (!any)
            break;
        if (!now) {
            jacobians(m, x, jout);
            continue;
        }
        /* again only the elements around the nodes that moved */
#pragma omp parallel for schedule(static)
        for (int32_t t = 0; t < m->nt; t++) {
            const int32_t *mid = m->mid + 6 * (size_t)t;
            double e[10][3];
            if (!(now[mid[0]] | now[mid[1]] | now[mid[2]] | now[mid[3]] | now[mid[4]] |
                  now[mid[5]]))
                continue;
            gather(x, m->tets + 4 * (size_t)t, mid, e);
            jout[t] = p2_scaled_jacobian((const double(*)[3])e);
        }
        memset(now, 0, (size_t)m->nv);
    }
    qdc_free(now);
}

qdc_status p2_finish(mesh_t *m, const double *x0, opt_result *res, qdc_error *err)
{
    size_t nv = (size_t)m->nv;
    uint8_t *role = qdc_calloc(nv + 1, 1), *pulled = qdc_calloc(nv + 1, 1);
    uint8_t *tries = qdc_calloc((size_t)m->nt + 1, 1);
    int32_t *first = qdc_mallocn(nv + 1, sizeof(int32_t));
    int32_t *cnt = qdc_calloc(nv + 1, sizeof(int32_t));
    double *sum = qdc_calloc(3 * nv + 1, sizeof(double));
    double *jin = qdc_mallocn((size_t)m->nt + 1, sizeof(double));
    double *jout = qdc_mallocn((size_t)m->nt + 1, sizeof(double));
    p2_surface s;
    qdc_status st = QDC_OK;

    memset(&s, 0, sizeof s);
    if (!role || !pulled || !tries || !first || !cnt || !sum || !jin || !jout) {
        st = qdc_fail(err, QDC_ENOMEM, "out of memory for the second-order nodes");
        goto out;
    }
    for (size_t v = 0; v < nv; v++)
        first[v] = -1;
    for (size_t i = 0; i < (size_t)m->nt * 6; i++)
        if (first[m->mid[i]] < 0) {
            first[m->mid[i]] = (int32_t)i;
            role[m->mid[i]] = 1;
        }
    st = surface_build(m, x0, role, &s, err);
    if (st != QDC_OK)
        goto out;
    jacobians(m, x0, jin);
    transport(m, x0, first, sum, cnt);
    /* boundary mid-edge nodes back onto the input's curved surface where
     * both corners stayed on the input's boundary (within the run's bound:
     * they slid along it); where the surface itself moved (an affine map of
     * the whole mesh, boundary lsq without a bound) the transport alone is
     * right */
#pragma omp parallel for schedule(dynamic, 256)
    for (int32_t v = 0; v < m->nv; v++) {
        double cp[3];
        if (role[v] != 2 || !moved(m->xyz, x0, v) ||
            !corners_on_input(m, &s, first[v], res->hausd_bound))
            continue;
        surface_closest(&s, x0, m->xyz + 3 * (size_t)v, cp);
        memcpy(m->xyz + 3 * (size_t)v, cp, sizeof cp);
    }
    jacobians(m, m->xyz, jout);
    straighten(m, jin, jout, tries, role, pulled);
    res->p2_tets = m->nt;
    res->p2_jac_min_in = res->p2_jac_min_out = DBL_MAX;
    for (int32_t t = 0; t < m->nt; t++) {
        res->p2_bad_in += !(jin[t] > 0);
        res->p2_bad_out += !(jout[t] > 0);
        res->p2_jac_min_in = fmin(res->p2_jac_min_in, jin[t]);
        res->p2_jac_min_out = fmin(res->p2_jac_min_out, jout[t]);
    }
    for (size_t v = 0; v < nv; v++) {
        double cp[3], d;
        res->p2_mid += role[v] == 1 || role[v] == 2;
        res->p2_boundary_mid += role[v] == 2;
        res->p2_pulled += pulled[v];
        if ((role[v] == 1 || role[v] == 2) && moved(m->xyz, x0, (int32_t)v))
            res->p2_mid_moved++;
        if (role[v] < 2)
            continue;
        d = surface_closest(&s, x0, m->xyz + 3 * v, cp);
        if (role[v] == 2)
            res->p2_bd_mid_dist = fmax(res->p2_bd_mid_dist, d);
        else
            res->p2_bd_corner_dist = fmax(res->p2_bd_corner_dist, d);
    }
out:
    surface_free(&s);
    qdc_free(role);
    qdc_free(pulled);
    qdc_free(tries);
    qdc_free(first);
    qdc_free(cnt);
    qdc_free(sum);
    qdc_free(jin);
    qdc_free(jout);
    return st;
}
