/* test_p2.c - second-order (10-node) tets: each format's mid-edge node order
 * mapped to the one of mesh_p2_edges (a straight tet read from every format
 * has every mid-edge node at its edge's midpoint), the Jacobian of the
 * quadratic element against closed forms, the closest point of a quadratic
 * triangle, and the mid-edge nodes moved exactly by an affine map of the
 * corners, straightened where their element's Jacobian would turn negative. */
#include "opt/p2.h"
#include "qdc.h"
#include "testio.h"
#include "testlib.h"

#include <stdarg.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The straight reference tet: corners, then the midpoints of mesh_p2_edges. */
static void ref_nodes(double x[10][3])
{
    static const double c[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

    memcpy(x, c, sizeof c);
    for (int e = 0; e < 6; e++)
        for (int i = 0; i < 3; i++)
            x[4 + e][i] = 0.5 * (c[mesh_p2_edges[e][0]][i] + c[mesh_p2_edges[e][1]][i]);
}

/* The file lists node perm[j] at position j: scrambled, so that an index
 * taken for another one shows. */
static const int perm[10] = {7, 2, 9, 0, 5, 3, 8, 1, 6, 4};

static int pos_of(int node)
{
    for (int j = 0; j < 10; j++)
        if (perm[j] == node)
            return j;
    return -1;
}

/* The element's ten node positions in the file's order: corners, then the
 * mid-edge nodes as the format lists them (order[f]: the mesh_p2_edges
 * edge of the file's f-th mid-edge node). */
static void element(const int order[6], int out[10])
{
    for (int k = 0; k < 4; k++)
        out[k] = pos_of(k);
    for (int f = 0; f < 6; f++)
        out[4 + f] = pos_of(4 + order[f]);
}

typedef struct {
    char b[8192];
    size_t n;
} txtbuf;

static void put(txtbuf *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put(txtbuf *t, const char *fmt, ...)
{
    va_list ap;

    va_start(ap, fmt);
    t->n += (size_t)vsnprintf(t->b + t->n, sizeof t->b - t->n, fmt, ap);
    va_end(ap);
}

enum { F_GMSH22, F_GMSH41, F_VTK, F_VTU, F_MEDIT, F_INP, F_BDF, F_UNV, F_VOL };

/* The straight tet as a file of format f, its mid-edge nodes in order. */
static void write_tet(txtbuf *t, int f, const int order[6])
{
    double x[10][3];
    int el[10];

    ref_nodes(x);
    element(order, el);
    t->n = 0;
    if (f == F_GMSH22 || f == F_GMSH41) {
        put(t, "$MeshFormat\n%s 0 8\n$EndMeshFormat\n$Nodes\n",
            f == F_GMSH22 ? "2.2" : "4.1");
        if (f == F_GMSH41) {
            put(t, "1 10 101 110\n3 1 0 10\n");
            for (int j = 0; j < 10; j++)
                put(t, "%d\n", 101 + j);
        } else {
            put(t, "10\n");
        }
        for (int j = 0; j < 10; j++) {
            const double *p = x[perm[j]];
            if (f == F_GMSH22)
                put(t, "%d ", 101 + j);
            put(t, "%.17g %.17g %.17g\n", p[0], p[1], p[2]);
        }
        put(t, "$EndNodes\n$Elements\n");
        put(t, f == F_GMSH22 ? "1\n1 11 2 0 1" : "1 1 1 1\n3 1 11 1\n1");
        for (int k = 0; k < 10; k++)
            put(t, " %d", 101 + el[k]);
        put(t, "\n$EndElements\n");
    } else if (f == F_VTK) {
        put(t, "# vtk DataFile Version 2.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n"
               "POINTS 10 double\n");
        for (int j = 0; j < 10; j++)
            put(t, "%.17g %.17g %.17g\n", x[perm[j]][0], x[perm[j]][1], x[perm[j]][2]);
        put(t, "CELLS 1 11\n10");
        for (int k = 0; k < 10; k++)
            put(t, " %d", el[k]);
        put(t, "\nCELL_TYPES 1\n24\n");
    } else if (f == F_VTU) {
        put(t,
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" "
            "version=\"0.1\" byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n"
            "<Piece NumberOfPoints=\"10\" NumberOfCells=\"1\">\n<Points>\n"
            "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
        for (int j = 0; j < 10; j++)
            put(t, "%.17g %.17g %.17g\n", x[perm[j]][0], x[perm[j]][1], x[perm[j]][2]);
        put(t, "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int32\" "
               "Name=\"connectivity\" format=\"ascii\">\n");
        for (int k = 0; k < 10; k++)
            put(t, " %d", el[k]);
        put(t, "\n</DataArray>\n<DataArray type=\"Int32\" Name=\"offsets\" "
               "format=\"ascii\">10</DataArray>\n<DataArray type=\"UInt8\" "
               "Name=\"types\" format=\"ascii\">24</DataArray>\n</Cells>\n</Piece>\n"
               "</UnstructuredGrid>\n</VTKFile>\n");
    } else if (f == F_MEDIT) {
        put(t, "MeshVersionFormatted 2\nDimension 3\nVertices\n10\n");
        for (int j = 0; j < 10; j++)
            put(t, "%.17g %.17g %.17g 0\n", x[perm[j]][0], x[perm[j]][1], x[perm[j]][2]);
        put(t, "TetrahedraP2\n1\n");
        for (int k = 0; k < 10; k++)
            put(t, "%d ", el[k] + 1);
        put(t, "3\nEnd\n");
    } else if (f == F_BDF) { /* small field, the CTETRA continued */
        put(t, "BEGIN BULK\n");
        for (int j = 0; j < 10; j++)
            put(t, "GRID    %-8d        %-8.5g%-8.5g%-8.5g\n", 101 + j, x[perm[j]][0],
                x[perm[j]][1], x[perm[j]][2]);
        put(t, "CTETRA  1       1       ");
        for (int k = 0; k < 10; k++)
            put(t, "%-8d%s", 101 + el[k], k == 5 ? "+\n+       " : "");
        put(t, "\nENDDATA\n");
    } else if (f == F_VOL) {
        put(t, "mesh3d\ndimension\n3\nvolumeelements\n1\n1 10");
        for (int k = 0; k < 10; k++)
            put(t, " %d", el[k] + 1);
        put(t, "\npoints\n10\n");
        for (int j = 0; j < 10; j++)
            put(t, "%.17g %.17g %.17g\n", x[perm[j]][0], x[perm[j]][1], x[perm[j]][2]);
        put(t, "endmesh\n");
    } else if (f == F_UNV) { /* corners and mid-edge nodes interleaved */
        static const int slot[10] = {0, 4, 1, 5, 2, 6, 7, 8, 9, 3};
        put(t, "    -1\n  2411\n");
        for (int j = 0; j < 10; j++)
            put(t, "%10d%10d%10d%10d\n%25.16E%25.16E%25.16E\n", 101 + j, 1, 1, 11,
                x[perm[j]][0], x[perm[j]][1], x[perm[j]][2]);
        put(t, "    -1\n    -1\n  2412\n%10d%10d%10d%10d%10d%10d\n", 1, 118, 1, 1, 7, 10);
        for (int k = 0; k < 10; k++)
            put(t, "%10d%s", 101 + el[slot[k]], k == 7 || k == 9 ? "\n" : "");
        put(t, "    -1\n");
    } else {
        put(t, "*HEADING\nt\n*NODE\n");
        for (int j = 0; j < 10; j++)
            put(t, "%d, %.17g, %.17g, %.17g\n", 101 + j, x[perm[j]][0], x[perm[j]][1],
                x[perm[j]][2]);
        put(t, "*ELEMENT, TYPE=C3D10, ELSET=E\n1");
        for (int k = 0; k < 10; k++)
            put(t, ",%s%d", k == 7 ? "\n" : " ", 101 + el[k]); /* a continued line */
        put(t, "\n");
    }
}

/* Largest distance of a mid-edge node from its edge's midpoint, or -1 if the
 * mesh is not one 10-node tet with its corners in the file's order. */
static double mid_offset(const mesh_t *m)
{
    double x[10][3], worst = 0;

    ref_nodes(x);
    if (!m->mid || m->nt != 1 || m->nv != 10)
        return -1;
    for (int k = 0; k < 4; k++)
        if (memcmp(m->xyz + 3 * m->tets[k], x[k], sizeof x[k]) != 0)
            return -1;
    for (int e = 0; e < 6; e++) {
        const double *a = m->xyz + 3 * m->tets[mesh_p2_edges[e][0]],
                     *b = m->xyz + 3 * m->tets[mesh_p2_edges[e][1]],
                     *p = m->xyz + 3 * m->mid[e];
        for (int i = 0; i < 3; i++)
            worst = fmax(worst, fabs(p[i] - 0.5 * (a[i] + b[i])));
    }
    return worst;
}

TEST(each_format_puts_mid_nodes_on_their_edges)
{
    /* each format's documented order: Gmsh (manual, "node ordering"): 01 12 20
     * 30 32 31; VTK_QUADRATIC_TETRA, Abaqus C3D10 and Nastran CTETRA (G5-G10:
     * edges 1-2, 2-3, 3-1, 1-4, 2-4, 3-4): 01 12 20 03 13 23; I-DEAS FE 118
     * the same, interleaved with the corners (write_tet); Netgen (its
     * tet10 as meshio maps it, and its SecondOrder output): 01 02 03 12 13 23 */
    static const int gmsh[6] = {0, 1, 2, 3, 5, 4}, vtk[6] = {0, 1, 2, 3, 4, 5},
                     netgen[6] = {0, 2, 3, 1, 4, 5};
    static const struct {
        int f;
        meshio_format fmt;
        const int *order;
    } cases[] = {{F_GMSH22, MESHIO_GMSH22, gmsh}, {F_GMSH41, MESHIO_GMSH41, gmsh},
                 {F_VTK, MESHIO_VTK_ASCII, vtk},  {F_VTU, MESHIO_VTU_ASCII, vtk},
                 {F_MEDIT, MESHIO_MEDIT, vtk},    {F_INP, MESHIO_ABAQUS, vtk},
                 {F_BDF, MESHIO_BDF, vtk},        {F_UNV, MESHIO_UNV, vtk},
                 {F_VOL, MESHIO_NETGEN, netgen}};
    txtbuf t;
    qdc_error err;

    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        mesh_t *m = NULL;
        write_tet(&t, cases[c].f, cases[c].order);
        ASSERT_OK(meshio_read(t.b, t.n, MESHIO_AUTO, &m, &err));
        ASSERT_EQ_INT(meshio_sniff(t.b, t.n), cases[c].fmt);
        if (mid_offset(m) != 0)
            printf("  %s: offset %g\n", meshio_format_name(cases[c].fmt), mid_offset(m));
        ASSERT_TRUE(mid_offset(m) == 0);
        /* the wrong order puts a node off its edge: the check can fail */
        mesh_free(m);
        write_tet(&t, cases[c].f, cases[c].order == vtk ? gmsh : vtk);
        ASSERT_OK(meshio_read(t.b, t.n, MESHIO_AUTO, &m, &err));
        ASSERT_TRUE(cases[c].f == F_MEDIT ? mid_offset(m) == 0 : mid_offset(m) > 0.4);
        mesh_free(m);
    }
}

TEST(netgen_refuses_mixed_orders)
{
    static const int netgen[6] = {0, 2, 3, 1, 4, 5};
    static const char lin[] = "volumeelements\n2\n1 4 1 2 3 4\n";
    txtbuf t;
    char *at, doc[sizeof t.b + 64];
    mesh_t *m = NULL;
    qdc_error err;

    write_tet(&t, F_VOL, netgen);
    /* a second, linear, tet before the 10-point one */
    at = strstr(t.b, "volumeelements\n1\n");
    ASSERT_TRUE(at != NULL);
    snprintf(doc, sizeof doc, "%.*s%s%s", (int)(at - t.b), t.b, lin,
             at + strlen("volumeelements\n1\n"));
    ASSERT_EQ_INT(meshio_read(doc, strlen(doc), MESHIO_NETGEN, &m, &err), QDC_EFORMAT);
    ASSERT_TRUE(strstr(err.msg, "linear (4 points) and second-order (10 points)") !=
                NULL);
    ASSERT_EQ_INT(err.line, 7); /* the 10-point tet after a linear one */
    ASSERT_TRUE(m == NULL);
}

TEST(medit_takes_the_order_that_fits)
{
    /* Mmg numbers a tet's edges 01 02 03 12 13 23 */
    static const int orders[3][6] = {
        {0, 1, 2, 3, 4, 5}, {0, 2, 3, 1, 4, 5}, {0, 1, 2, 3, 5, 4}};
    txtbuf t;

    for (int o = 0; o < 3; o++) {
        mesh_t *m = NULL;
        write_tet(&t, F_MEDIT, orders[o]);
        ASSERT_OK(meshio_read(t.b, t.n, MESHIO_MEDIT, &m, NULL));
        ASSERT_TRUE(mid_offset(m) == 0);
        ASSERT_EQ_INT(m->region[0], 3);
        mesh_free(m);
    }
}

TEST(writers_keep_ten_nodes)
{
    static const meshio_format fmts[] = {
        MESHIO_VTK,        MESHIO_VTK_ASCII, MESHIO_VTU,        MESHIO_VTU_ASCII,
        MESHIO_MEDIT,      MESHIO_QMESH,     MESHIO_JSON,       MESHIO_GMSH41,
        MESHIO_GMSH41_BIN, MESHIO_GMSH22,    MESHIO_GMSH22_BIN, MESHIO_GMSH40};
    static const int gmsh[6] = {0, 1, 2, 3, 5, 4};
    txtbuf t;
    mesh_t *m = NULL;
    qdc_error err;
    sink s = {0};

    write_tet(&t, F_GMSH22, gmsh);
    ASSERT_OK(meshio_read(t.b, t.n, MESHIO_GMSH22, &m, NULL));
    for (size_t i = 0; i < sizeof fmts / sizeof fmts[0]; i++) {
        mesh_t *b = NULL;
        s.n = 0;
        ASSERT_OK(meshio_write(m, fmts[i], sink_write, &s, &err));
        ASSERT_OK(meshio_read(s.b, s.n, fmts[i], &b, &err));
        ASSERT_TRUE(mid_offset(b) == 0);
        ASSERT_TRUE(memcmp(b->tets, m->tets, 4 * sizeof(int32_t)) == 0);
        ASSERT_TRUE(memcmp(b->mid, m->mid, 6 * sizeof(int32_t)) == 0);
        mesh_free(b);
    }
    /* a writer of linear tets refuses rather than drop the mid-edge nodes */
    s.n = 0;
    ASSERT_EQ_INT(meshio_write(m, MESHIO_DOLFIN, sink_write, &s, &err), QDC_EINVAL);
    ASSERT_TRUE(strstr(err.msg, "second-order") != NULL);
    free(s.b);
    mesh_free(m);
}

TEST(jacobian_closed_forms)
{
    double x[10][3];

    ref_nodes(x);
    /* straight: 6 times the volume everywhere, scaled 1 */
    ASSERT_NEAR(p2_jacobian((const double(*)[3])x, 0.1, 0.2, 0.3), 1.0, 1e-15);
    ASSERT_NEAR(p2_scaled_jacobian((const double(*)[3])x), 1.0, 1e-15);
    /* the node of edge 01 moved by d along it: J = 1 + 4d(L0 - L1), least
     * at corner 1: 1 - 4d */
    x[4][0] += 0.1;
    ASSERT_NEAR(p2_jacobian((const double(*)[3])x, 0, 0, 0), 1.4, 1e-15);
    ASSERT_NEAR(p2_jacobian((const double(*)[3])x, 1, 0, 0), 0.6, 1e-15);
    ASSERT_NEAR(p2_jacobian((const double(*)[3])x, 0.25, 0.25, 0.25), 1.0, 1e-15);
    ASSERT_NEAR(p2_scaled_jacobian((const double(*)[3])x), 0.6, 1e-15);
    x[4][0] += 0.15; /* d = 1/4: zero at corner 1 */
    ASSERT_TRUE(p2_scaled_jacobian((const double(*)[3])x) <= 1e-15);
    /* scaled by the straight tet: the same for a mirrored element */
    for (int k = 0; k < 10; k++)
        x[k][2] = -x[k][2];
    x[4][0] -= 0.15;
    ASSERT_NEAR(p2_scaled_jacobian((const double(*)[3])x), 0.6, 1e-15);
}

TEST(closest_point_of_a_quadratic_triangle)
{
    /* the triangle z = 0 with its edge 01 bulged to y = -0.2 at its middle:
     * the patch is still in z = 0 */
    double x[6][3] = {{0, 0, 0},      {1, 0, 0},     {0, 1, 0},
                      {0.5, -0.2, 0}, {0.5, 0.5, 0}, {0, 0.5, 0}};
    double p[3] = {0.5, -0.1, 0.3}, uv[2] = {0.3, 0.1}, cp[3];

    ASSERT_NEAR(p2_tri_closest((const double(*)[3])x, p, uv, cp), 0.3, 1e-12);
    ASSERT_NEAR(cp[1], -0.1, 1e-12);
    /* past the bulge: the closest point is on the curved edge, y = -0.2 at
     * its middle */
    p[1] = -0.5;
    p[2] = 0;
    uv[0] = 0.5;
    uv[1] = 0;
    ASSERT_NEAR(p2_tri_closest((const double(*)[3])x, p, uv, cp), 0.3, 1e-9);
    ASSERT_NEAR(cp[0], 0.5, 1e-9);
}

/* Three tets around the edge a = (0,0,-1), b = (0,0,1) (vertices 0, 1),
 * their outer corners p0, p1, p2 (vertices 2, 3, 4) at 120 degrees in z = 0;
 * the interior edge ab's mid-edge node (vertex 5) at inner, every other one
 * at its edge's midpoint. */
static mesh_t *ring(const double inner[3])
{
    mesh_t *m = mesh_new(16, 3, 0);
    int32_t next = 6;

    if (!m || mesh_set_mid(m) != QDC_OK)
        return NULL;
    m->xyz[2] = -1;
    m->xyz[5] = 1;
    for (int i = 0; i < 3; i++) {
        m->xyz[3 * (2 + i)] = cos(2 * 3.14159265358979323846 * i / 3);
        m->xyz[3 * (2 + i) + 1] = sin(2 * 3.14159265358979323846 * i / 3);
    }
    for (int t = 0; t < 3; t++) {
        int32_t *tt = m->tets + 4 * t;
        tt[0] = 0;
        tt[1] = 1;
        tt[2] = 2 + t;
        tt[3] = 2 + (t + 1) % 3;
    }
    for (int t = 0; t < 3; t++) {
        int32_t *mid = m->mid + 6 * t, *tt = m->tets + 4 * t;
        for (int e = 0; e < 6; e++) {
            int32_t a = tt[mesh_p2_edges[e][0]], b = tt[mesh_p2_edges[e][1]], found = -1;
            for (int u = 0; u < t && found < 0; u++)
                for (int f = 0; f < 6; f++) {
                    int32_t c = m->tets[4 * u + mesh_p2_edges[f][0]],
                            d = m->tets[4 * u + mesh_p2_edges[f][1]];
                    if ((c == a && d == b) || (c == b && d == a))
                        found = m->mid[6 * u + f];
                }
            mid[e] = e == 0 ? 5 : found >= 0 ? found : next++;
            for (int i = 0; i < 3; i++)
                m->xyz[3 * mid[e] + i] = 0.5 * (m->xyz[3 * a + i] + m->xyz[3 * b + i]);
        }
    }
    memcpy(m->xyz + 15, inner, 3 * sizeof(double));
    m->nv = next; /* 5 corners and 10 edges */
    return m;
}

TEST(affine_map_moves_mid_nodes_exactly)
{
    static const double A[3][3] = {{1.1, 0.2, -0.1}, {0.05, 0.9, 0.3}, {-0.2, 0.1, 1.2}};
    static const double tr[3] = {0.3, -0.2, 0.7};
    const double inner[3] = {0.1, 0.05, 0.2};
    mesh_t *m = ring(inner);
    double *x0, want[3];
    opt_result res;

    ASSERT_TRUE(m != NULL);
    ASSERT_EQ_INT(m->nv, 15);
    ASSERT_OK(mesh_validate(m, NULL, NULL));
    x0 = malloc(3 * sizeof(double) * (size_t)m->nv);
    memcpy(x0, m->xyz, 3 * sizeof(double) * (size_t)m->nv);
    for (int32_t v = 0; v < 5; v++) { /* the corners */
        double *p = m->xyz + 3 * v, q[3];
        for (int i = 0; i < 3; i++)
            q[i] = A[i][0] * p[0] + A[i][1] * p[1] + A[i][2] * p[2] + tr[i];
        memcpy(p, q, sizeof q);
    }
    memset(&res, 0, sizeof res);
    ASSERT_OK(p2_finish(m, x0, &res, NULL));
    for (int i = 0; i < 3; i++)
        want[i] = A[i][0] * inner[0] + A[i][1] * inner[1] + A[i][2] * inner[2] + tr[i];
    for (int i = 0; i < 3; i++)
        ASSERT_NEAR(m->xyz[15 + i], want[i], 1e-14);
    /* the boundary ones too: the whole surface moved, they move with it */
    for (int32_t v = 6; v < m->nv; v++)
        for (int i = 0; i < 3; i++)
            ASSERT_NEAR(m->xyz[3 * v + i],
                        A[i][0] * x0[3 * v] + A[i][1] * x0[3 * v + 1] +
                            A[i][2] * x0[3 * v + 2] + tr[i],
                        1e-14);
    ASSERT_EQ_INT(res.p2_tets, 3);
    ASSERT_EQ_INT(res.p2_mid, 10);
    ASSERT_EQ_INT(res.p2_boundary_mid, 9);
    ASSERT_EQ_INT(res.p2_mid_moved, 10);
    ASSERT_EQ_INT(res.p2_bad_in, 0);
    ASSERT_EQ_INT(res.p2_bad_out, 0);
    ASSERT_EQ_INT(res.p2_pulled, 0);
    free(x0);
    mesh_free(m);
}

/* ring(inner) with its coordinate k set to x, its mid-edge nodes then moved
 * by p2_finish (the run's bound on the surface: bound) against the ring as
 * it was, which *x0 gets (the caller frees it); NULL if either fails. */
static mesh_t *ring_moved(const double inner[3], int k, double x, double bound,
                          opt_result *res, double **x0)
{
    mesh_t *m = ring(inner);

    *x0 = m ? malloc(3 * sizeof(double) * (size_t)m->nv) : NULL;
    if (!*x0) {
        mesh_free(m);
        return NULL;
    }
    memcpy(*x0, m->xyz, 3 * sizeof(double) * (size_t)m->nv);
    m->xyz[k] = x;
    memset(res, 0, sizeof *res);
    res->hausd_bound = bound;
    if (p2_finish(m, *x0, res, NULL) != QDC_OK) {
        mesh_free(m);
        return NULL;
    }
    return m;
}

TEST(boundary_mid_nodes_stay_on_the_input_surface)
{
    /* apex a moved 0.1 inside, within the run's bound of 0.2 of the input's
     * surface: the mid-edge nodes of its edges go back onto that surface */
    const double inner[3] = {0, 0, 0.1};
    double *x0 = NULL;
    opt_result res;
    mesh_t *m = ring_moved(inner, 2, -0.9, 0.2, &res, &x0);

    ASSERT_TRUE(m != NULL);
    ASSERT_TRUE(res.p2_bd_mid_dist < 1e-12);
    ASSERT_EQ_INT(res.p2_bad_out, 0);
    /* a corner left alone keeps its edges' nodes where they were */
    for (int32_t t = 0; t < 3; t++)
        for (int e = 0; e < 6; e++) {
            int32_t a = m->tets[4 * t + mesh_p2_edges[e][0]],
                    b = m->tets[4 * t + mesh_p2_edges[e][1]];
            int32_t v = m->mid[6 * t + e];
            if (a != 0 && b != 0)
                ASSERT_TRUE(memcmp(m->xyz + 3 * v, x0 + 3 * v, 3 * sizeof(double)) == 0);
        }
    free(x0);
    mesh_free(m);
}

TEST(non_affine_move_straightens_until_positive)
{
    /* ab bent far toward p0; p0 then moved next to the axis: the mapped
     * offset would put ab's node outside the tets at p0 */
    const double inner[3] = {0.25, 0, 0};
    double *x0 = NULL;
    opt_result res;
    mesh_t *m = ring_moved(inner, 3 * 2, 0.12, 0, &res, &x0);

    ASSERT_TRUE(m != NULL);
    ASSERT_EQ_INT(res.p2_bad_in, 0);
    ASSERT_EQ_INT(res.p2_bad_out, 0);
    ASSERT_TRUE(res.p2_pulled > 0);
    ASSERT_TRUE(res.p2_jac_min_out > 0);
    free(x0);
    mesh_free(m);
}

/* 1 if every mid-edge node but ab's (vertex 5) is at its edge's midpoint. */
static int ring_consistent(const mesh_t *m)
{
    for (int32_t t = 0; t < m->nt; t++)
        for (int e = 0; e < 6; e++) {
            const int32_t *tt = m->tets + 4 * t;
            int32_t v = m->mid[6 * t + e];
            const double *a = m->xyz + 3 * tt[mesh_p2_edges[e][0]],
                         *b = m->xyz + 3 * tt[mesh_p2_edges[e][1]];
            if (v == 5)
                continue;
            for (int i = 0; i < 3; i++)
                if (m->xyz[3 * v + i] != 0.5 * (a[i] + b[i]))
                    return 0;
        }
    return 1;
}

TEST(reorienting_a_tet_moves_its_mid_edge_nodes_along)
{
    const double inner[3] = {0, 0, 0.1};
    mesh_t *m = ring(inner);
    mesh_orientation o;
    int32_t *tt, *mid, x;

    ASSERT_TRUE(m != NULL);
    /* tet 1 written in the other vertex order, its table rewritten to match:
     * swapping corners 0 and 1 exchanges edges 12/02 and 03/13 */
    tt = m->tets + 4;
    mid = m->mid + 6;
    x = tt[0], tt[0] = tt[1], tt[1] = x;
    x = mid[1], mid[1] = mid[2], mid[2] = x;
    x = mid[3], mid[3] = mid[4], mid[4] = x;
    ASSERT_TRUE(ring_consistent(m));
    ASSERT_OK(mesh_reorient(m, &o, NULL));
    ASSERT_EQ_INT(o.flipped, 1);
    ASSERT_TRUE(ring_consistent(m));
    ASSERT_EQ_INT(m->tets[4], 0); /* back in the order of the others */
    mesh_free(m);
}

TEST_MAIN("p2", T(each_format_puts_mid_nodes_on_their_edges),
          T(netgen_refuses_mixed_orders), T(medit_takes_the_order_that_fits),
          T(writers_keep_ten_nodes), T(jacobian_closed_forms),
          T(closest_point_of_a_quadratic_triangle), T(affine_map_moves_mid_nodes_exactly),
          T(boundary_mid_nodes_stay_on_the_input_surface),
          T(non_affine_move_straightens_until_positive),
          T(reorienting_a_tet_moves_its_mid_edge_nodes_along))
