/* test_pdata.c - point data (mesh.h, "Point data"): hand-made VTK legacy
 * (ASCII and binary), VTU and Gmsh (2.2 and 4.1) inputs read with their
 * arrays' names, components and values; every writer that keeps point data
 * reads back bit for bit (awkward doubles, int32 and 64-bit integers);
 * bad sizes are errors, a NaN array is dropped with a note, a NaN given to
 * mesh_pdata_add is refused; copies; and the interpolation at new vertices
 * (mesh_pdata_remap) of a linear field is exact, integer arrays taking the
 * corner of largest weight. */
#include "qdc.h"
#include "testio.h"
#include "testlib.h"

static const meshio_format pd_formats[] = {
    MESHIO_VTK,       MESHIO_VTK_ASCII,  MESHIO_VTU,
    MESHIO_VTU_ASCII, MESHIO_GMSH41,     MESHIO_GMSH41_BIN,
    MESHIO_GMSH22,    MESHIO_GMSH22_BIN, MESHIO_GMSH40};
#define N_PD (int)(sizeof pd_formats / sizeof pd_formats[0])

static int is_gmsh(meshio_format f)
{
    return f == MESHIO_GMSH41 || f == MESHIO_GMSH41_BIN || f == MESHIO_GMSH22 ||
           f == MESHIO_GMSH22_BIN || f == MESHIO_GMSH40;
}

/* The array of m named name, or NULL. */
static const mesh_parray *arr(const mesh_t *m, const char *name)
{
    for (int32_t i = 0; m->pdata && i < m->pdata->n; i++)
        if (!strcmp(m->pdata->a[i].name, name))
            return &m->pdata->a[i];
    return NULL;
}

static char logged[512];
static void log_to(void *ctx, int level, const char *msg)
{
    (void)ctx;
    (void)level;
    snprintf(logged, sizeof logged, "%s", msg);
}

static qdc_status read_log(const char *s, size_t n, meshio_format f, mesh_t **m,
                           qdc_error *err)
{
    meshio_options o = {log_to, NULL, 0, 0, 0};

    logged[0] = 0;
    return meshio_read_ex(s, n, f, &o, m, err);
}

/* One tet, four points, and its POINT_DATA. */
#define VTK_HEAD                                                                         \
    "# vtk DataFile Version 4.2\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n" \
    "0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n"

TEST(vtk_ascii_arrays)
{
    static const char s[] =
        VTK_HEAD "POINT_DATA 4\nSCALARS temp double 1\nLOOKUP_TABLE default\n"
                 "0.1 -2.5 1e-300 7\nVECTORS vel float\n0.5 1 2 3 4 5 6 7 8 9 10 -0.25\n"
                 "SCALARS mat int 1\nLOOKUP_TABLE default\n-3 0 2147483647 -2147483648\n"
                 "FIELD FieldData 1\nbig 2 4 vtktypeint64\n"
                 "1099511627776 -1 2 3 4 5 6 -9007199254740992\n";
    mesh_t *m = NULL;
    qdc_error err;
    const mesh_parray *a;

    ASSERT_OK(meshio_read(s, sizeof s - 1, MESHIO_VTK_ASCII, &m, &err));
    ASSERT_TRUE(m->pdata && m->pdata->n == 4 && m->vref == NULL);
    a = arr(m, "temp");
    ASSERT_TRUE(a && a->ncomp == 1 && !a->integer);
    ASSERT_TRUE(a->v[0] == 0.1 && a->v[1] == -2.5 && a->v[2] == 1e-300 && a->v[3] == 7);
    a = arr(m, "vel");
    ASSERT_TRUE(a && a->ncomp == 3 && !a->integer && !strcmp(a->type, "Float32"));
    ASSERT_TRUE(a->v[0] == 0.5 && a->v[5] == 5 && a->v[11] == -0.25);
    a = arr(m, "mat");
    ASSERT_TRUE(a && a->ncomp == 1 && a->integer);
    ASSERT_TRUE(a->v[0] == -3 && a->v[2] == 2147483647.0 && a->v[3] == -2147483648.0);
    a = arr(m, "big");
    ASSERT_TRUE(a && a->ncomp == 2 && a->integer);
    ASSERT_TRUE(a->v[0] == 1099511627776.0 && a->v[7] == -9007199254740992.0);
    ASSERT_EQ_INT(m->pdata->ninterp, 0);
    mesh_free(m);
}

/* medit:ref stays the vertex refs, not point data; without POINT_DATA no
 * pdata at all. */
TEST(vtk_medit_ref_stays_vref)
{
    static const char s[] = VTK_HEAD "POINT_DATA 4\nSCALARS medit:ref int 1\n"
                                     "LOOKUP_TABLE default\n1 2 3 4\n";
    mesh_t *m = NULL;
    qdc_error err;

    ASSERT_OK(meshio_read(s, sizeof s - 1, MESHIO_AUTO, &m, &err));
    ASSERT_TRUE(m->vref && m->vref[3] == 4 && m->pdata == NULL);
    mesh_free(m);
    ASSERT_OK(meshio_read(VTK_HEAD, sizeof VTK_HEAD - 1, MESHIO_AUTO, &m, &err));
    ASSERT_TRUE(m->pdata == NULL);
    mesh_free(m);
}

TEST(vtk_bad_sizes_and_nan)
{
    static const char few[] = VTK_HEAD "POINT_DATA 4\nSCALARS t double 1\n"
                                       "LOOKUP_TABLE default\n1 2 3\n";
    static const char count[] = VTK_HEAD "POINT_DATA 5\nSCALARS t double 1\n"
                                         "LOOKUP_TABLE default\n1 2 3 4 5\n";
    static const char nan[] =
        VTK_HEAD "POINT_DATA 4\nSCALARS t double 1\n"
                 "LOOKUP_TABLE default\n1 nan 3 4\n"
                 "SCALARS u double 1\nLOOKUP_TABLE default\n1 2 3 4\n";
    mesh_t *m = NULL;
    qdc_error err;

    ASSERT_TRUE(meshio_read(few, sizeof few - 1, MESHIO_AUTO, &m, &err) == QDC_EPARSE);
    ASSERT_TRUE(m == NULL);
    ASSERT_TRUE(meshio_read(count, sizeof count - 1, MESHIO_AUTO, &m, &err) ==
                QDC_EPARSE);
    ASSERT_TRUE(strstr(err.msg, "POINT_DATA 5") != NULL);
    /* a NaN array is dropped with a note; the file reads as it did */
    ASSERT_OK(read_log(nan, sizeof nan - 1, MESHIO_AUTO, &m, &err));
    ASSERT_TRUE(m->pdata && m->pdata->n == 1 && arr(m, "u") && !arr(m, "t"));
    ASSERT_TRUE(strstr(logged, "point data t dropped") != NULL);
    mesh_free(m);
}

TEST(vtu_point_data)
{
    static const char s[] =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
        "byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n"
        "<Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n<PointData>\n"
        "<DataArray type=\"Int32\" Name=\"id\" format=\"ascii\">7 8 9 -10</DataArray>\n"
        "<DataArray type=\"Float64\" Name=\"g\" NumberOfComponents=\"3\" "
        "format=\"ascii\">"
        "0.1 0.2 0.3 1 2 3 4 5 6 -7 -8 -9.5</DataArray>\n</PointData>\n"
        "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
        "0 0 0 1 0 0 0 1 0 0 0 1</DataArray>\n</Points>\n<Cells>\n"
        "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 3"
        "</DataArray>\n<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4"
        "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10"
        "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
    mesh_t *m = NULL;
    qdc_error err;
    const mesh_parray *a;

    ASSERT_OK(meshio_read(s, sizeof s - 1, MESHIO_AUTO, &m, &err));
    ASSERT_TRUE(m->pdata && m->pdata->n == 2);
    a = arr(m, "id");
    ASSERT_TRUE(a && a->integer && a->ncomp == 1 && a->v[0] == 7 && a->v[3] == -10);
    a = arr(m, "g");
    ASSERT_TRUE(a && !a->integer && a->ncomp == 3 && a->v[0] == 0.1 && a->v[11] == -9.5);
    mesh_free(m);
}

/* Node tags out of order and sparse; two time steps of one view (the last
 * kept); a view of another count passed over with a note. */
TEST(gmsh_node_data)
{
    static const char s22[] =
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n40 0 0 1\n10 0 0 0\n"
        "20 1 0 0\n30 0 1 0\n$EndNodes\n$Elements\n1\n1 4 2 0 1 10 20 30 40\n"
        "$EndElements\n$NodeData\n1\n\"a b\"\n1\n0.0\n3\n0\n1\n4\n"
        "10 1\n20 2\n30 3\n40 4\n$EndNodeData\n"
        "$NodeData\n1\n\"a b\"\n1\n1.0\n3\n1\n1\n4\n"
        "30 13\n40 14\n10 11\n20 12\n$EndNodeData\n"
        "$NodeData\n1\n\"v\"\n1\n0\n3\n0\n3\n4\n"
        "10 1 2 3\n20 4 5 6\n30 7 8 9\n40 0.1 0.2 0.3\n$EndNodeData\n"
        "$NodeData\n1\n\"short\"\n1\n0\n3\n0\n1\n3\n10 1\n20 2\n30 3\n$EndNodeData\n";
    static const char s41[] =
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n"
        "0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n"
        "$EndElements\n$NodeData\n1\n\"p\"\n1\n0\n3\n0\n1\n4\n"
        "4 -4\n3 -3\n2 -2\n1 -1.5\n$EndNodeData\n";
    mesh_t *m = NULL;
    qdc_error err;
    const mesh_parray *a;

    ASSERT_OK(read_log(s22, sizeof s22 - 1, MESHIO_AUTO, &m, &err));
    ASSERT_TRUE(m->pdata && m->pdata->n == 2 && !arr(m, "short"));
    ASSERT_TRUE(strstr(logged, "short passed over") != NULL);
    a = arr(m, "a b"); /* vertices in file order: tags 40 10 20 30 */
    ASSERT_TRUE(a && a->ncomp == 1 && !a->integer);
    ASSERT_TRUE(a->v[0] == 14 && a->v[1] == 11 && a->v[2] == 12 && a->v[3] == 13);
    a = arr(m, "v");
    ASSERT_TRUE(a && a->ncomp == 3 && a->v[0] == 0.1 && a->v[5] == 3 && a->v[11] == 9);
    mesh_free(m);
    ASSERT_OK(meshio_read(s41, sizeof s41 - 1, MESHIO_AUTO, &m, &err));
    a = arr(m, "p");
    ASSERT_TRUE(a && a->v[0] == -1.5 && a->v[3] == -4);
    mesh_free(m);
}

/* Every writer that keeps point data gives it back bit for bit. */
TEST(roundtrip_bit_for_bit)
{
    mesh_t *m = make_mesh(200, 300, 20), *b = NULL;
    double *f = NULL, *i32 = NULL, *i64 = NULL;
    qdc_error err;

    ASSERT_TRUE(m);
    f = malloc(3 * 200 * sizeof *f);
    i32 = malloc(200 * sizeof *i32);
    i64 = malloc(200 * sizeof *i64);
    ASSERT_TRUE(f && i32 && i64);
    for (int i = 0; i < 600; i++)
        f[i] = nasty_double(i);
    for (int i = 0; i < 200; i++) {
        i32[i] = (double)((int32_t)rnd());
        i64[i] = (double)((int64_t)(rnd() % (1ull << 53)) - (1ll << 52));
    }
    i32[0] = INT32_MIN;
    i32[1] = INT32_MAX;
    ASSERT_OK(mesh_pdata_add(m, "f3", 2, 3, 0, "Float64", f, &err));
    ASSERT_OK(mesh_pdata_add(m, "i32", 3, 1, 1, "Int32", i32, &err));
    ASSERT_OK(mesh_pdata_add(m, "i64", 3, 1, 1, "Int64", i64, &err));
    for (int k = 0; k < N_PD; k++) {
        meshio_format fm = pd_formats[k];
        ASSERT_TRUE(meshio_writes_pdata(fm));
        ASSERT_OK(roundtrip(m, fm, &b));
        ASSERT_TRUE(b->pdata && b->pdata->n == 3);
        for (int32_t i = 0; i < 3; i++) {
            const mesh_parray *x = &m->pdata->a[i], *y = arr(b, x->name);
            if (!y || y->ncomp != x->ncomp || memcmp(x->v, y->v, 200 * 8 * x->ncomp))
                printf("  %s: %s differs\n", meshio_format_name(fm), x->name);
            ASSERT_TRUE(y && y->ncomp == x->ncomp);
            ASSERT_TRUE(memcmp(x->v, y->v, 200 * sizeof(double) * (size_t)x->ncomp) == 0);
            ASSERT_TRUE(y->integer == (is_gmsh(fm) ? 0 : x->integer));
        }
        mesh_free(b);
    }
    ASSERT_TRUE(!meshio_writes_pdata(MESHIO_MEDIT) && !meshio_writes_pdata(MESHIO_QMESH));
    /* a copy holds its own arrays */
    b = mesh_dup(m);
    ASSERT_TRUE(b && b->pdata && b->pdata != m->pdata && b->pdata->n == 3);
    ASSERT_TRUE(b->pdata->a[0].v != m->pdata->a[0].v);
    ASSERT_TRUE(memcmp(b->pdata->a[0].v, m->pdata->a[0].v, 600 * sizeof(double)) == 0);
    mesh_free(b);
    mesh_free(m);
}

TEST(add_refuses_nan_and_bad_shapes)
{
    mesh_t *m = mesh_new(3, 0, 0);
    double *v = malloc(3 * sizeof *v);
    qdc_error err;

    ASSERT_TRUE(m && v);
    v[0] = 1;
    v[1] = NAN;
    v[2] = 2;
    ASSERT_TRUE(mesh_pdata_add(m, "x", 1, 1, 0, NULL, v, &err) == QDC_EINVAL);
    ASSERT_EQ_INT(err.index, 1);
    ASSERT_TRUE(m->pdata == NULL);
    v = malloc(3 * sizeof *v);
    ASSERT_TRUE(v);
    ASSERT_TRUE(mesh_pdata_add(m, "x", 1, 0, 0, NULL, v, &err) == QDC_EINVAL);
    v = malloc(3 * sizeof *v);
    ASSERT_TRUE(v);
    v[0] = v[1] = v[2] = INFINITY;
    ASSERT_TRUE(mesh_pdata_add(m, "x", 1, 1, 0, NULL, v, &err) == QDC_EINVAL);
    mesh_free(m);
}

/* Control bytes of a name (a NUL inside the file's name too, as the VTK
 * fuzzer found: "medit:ref\0..." came back as the vertex refs) become '_',
 * and the name survives a VTK round trip as an array, not as the refs. */
TEST(name_control_bytes)
{
    static const char name[] = "medit:ref\0\t\x7f";
    mesh_t *m = mesh_new(4, 1, 0), *b = NULL;
    double *v = calloc(4, sizeof *v);
    sink s = {0};
    qdc_error err;
    static const double xyz[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};

    ASSERT_TRUE(m && v);
    memcpy(m->xyz, xyz, sizeof xyz);
    for (int i = 0; i < 4; i++)
        m->tets[i] = i;
    for (int i = 0; i < 4; i++)
        v[i] = i + 0.5;
    ASSERT_OK(mesh_pdata_add(m, name, sizeof name - 1, 1, 0, NULL, v, &err));
    ASSERT_TRUE(!strcmp(m->pdata->a[0].name, "medit:ref___"));
    ASSERT_OK(meshio_write(m, MESHIO_VTK_ASCII, sink_write, &s, &err));
    ASSERT_OK(meshio_read(s.b, s.n, MESHIO_VTK_ASCII, &b, &err));
    ASSERT_TRUE(arr(b, "medit:ref___") != NULL);
    ASSERT_TRUE(b->vref == NULL || (b->vref[1] == 0 && b->vref[3] == 0));
    ASSERT_TRUE(arr(b, "medit:ref___")->v[3] == 3.5);
    free(s.b);
    mesh_free(b);
    mesh_free(m);
}

/* An int array's text may hold 1.5 (a floating array then) or -0 (the
 * integer 0); integers beyond int64 are written as Float64. */
TEST(integer_arrays_stay_exact)
{
    static const char s[] = VTK_HEAD "POINT_DATA 4\nSCALARS k int 1\n"
                                     "LOOKUP_TABLE default\n-0 1.5 2 3\n"
                                     "SCALARS j int 1\nLOOKUP_TABLE default\n-0 1 2 3\n";
    mesh_t *m = NULL, *b = NULL;
    qdc_error err;
    const mesh_parray *a;
    double *big = malloc(4 * sizeof *big);

    ASSERT_TRUE(big);
    ASSERT_OK(meshio_read(s, sizeof s - 1, MESHIO_AUTO, &m, &err));
    a = arr(m, "k");
    ASSERT_TRUE(a && !a->integer && a->v[1] == 1.5 && signbit(a->v[0]));
    a = arr(m, "j");
    ASSERT_TRUE(a && a->integer && a->v[0] == 0 && !signbit(a->v[0]));
    big[0] = 1e19;
    big[1] = -1e300;
    big[2] = 1;
    big[3] = -9223372036854775808.0;
    ASSERT_OK(mesh_pdata_add(m, "big", 3, 1, 1, NULL, big, &err));
    for (int k = 0; k < 4; k++) {
        ASSERT_OK(roundtrip(m, pd_formats[k], &b));
        a = arr(b, "big");
        ASSERT_TRUE(a && !a->integer && a->v[0] == 1e19 && a->v[1] == -1e300 &&
                    a->v[3] == -9223372036854775808.0);
        ASSERT_TRUE(arr(b, "k") && arr(b, "k")->v[1] == 1.5);
        mesh_free(b);
    }
    mesh_free(m);
}

static double lin(const double *p)
{
    return p[0] + 2 * p[1] + 3 * p[2];
}

/* Two tets sharing the face 1 2 3 of a unit corner and its mirror; f = x +
 * 2y + 3z, an integer id per vertex. Old vertex 1 is removed, 0 2 3 4
 * become 3 0 1 2; new vertices 4..7: inside tet 0, inside tet 1, on their
 * shared face, and outside (clamped to the nearest tet's face). */
TEST(remap_interpolates_linear_fields)
{
    mesh_t *m = mesh_new(5, 2, 0);
    double *f = malloc(5 * sizeof *f), *id = malloc(5 * sizeof *id);
    static const double X[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    static const int32_t T[8] = {0, 1, 2, 3, 4, 3, 2, 1};
    const int32_t vmap[5] = {3, -1, 0, 1, 2};
    double nx[24] = {0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1}; /* kept: at 2 3 4 then 0 */
    static const double at[4][3] = {
        {0.1, 0.2, 0.3}, {0.8, 0.7, 0.6}, {0.4, 0.3, 0.3}, {-0.5, 0.1, 0.1}};
    mesh_pdata *q = NULL;
    qdc_error err;

    ASSERT_TRUE(m && f && id);
    memcpy(m->xyz, X, sizeof X);
    memcpy(m->tets, T, sizeof T);
    for (int v = 0; v < 5; v++) {
        f[v] = lin(X + 3 * v);
        id[v] = 100 + v;
    }
    ASSERT_OK(mesh_pdata_add(m, "f", 1, 1, 0, NULL, f, &err));
    ASSERT_OK(mesh_pdata_add(m, "id", 2, 1, 1, NULL, id, &err));
    memcpy(nx + 12, at, sizeof at);
#ifdef QDC_FAULT_INJECTION
    /* every allocation failing in turn: ENOMEM and nothing made (make fault:
     * under ASan, leaks checked) */
    for (long n = 1;; n++) {
        qdc_status st;
        qdc_fault_set(n);
        st = mesh_pdata_remap(m, 8, nx, vmap, &q, &err);
        qdc_fault_set(0);
        if (st == QDC_OK)
            break;
        ASSERT_EQ_INT(st, QDC_ENOMEM);
        ASSERT_TRUE(q == NULL);
    }
    mesh_pdata_free(q);
    q = NULL;
#endif
    ASSERT_OK(mesh_pdata_remap(m, 8, nx, vmap, &q, &err));
    ASSERT_TRUE(q && q->n == 2 && q->ninterp == 4);
    /* kept vertices: their own values, moved to their new index */
    ASSERT_TRUE(q->a[0].v[3] == f[0] && q->a[0].v[0] == f[2] && q->a[0].v[2] == f[4]);
    ASSERT_TRUE(q->a[1].v[3] == 100 && q->a[1].v[0] == 102 && q->a[1].v[2] == 104);
    ASSERT_TRUE(!q->made[0] && !q->made[3] && q->made[4] && q->made[7]);
    for (int k = 0; k < 3; k++)
        ASSERT_NEAR(q->a[0].v[4 + k], lin(at[k]), 1e-12);
    /* id: the corner of largest weight. (0.1,0.2,0.3) in tet 0: weights
     * 0.4 (vertex 0), 0.1, 0.2, 0.3; (0.8,0.7,0.6) in tet 1: 0.55 (vertex 4) */
    ASSERT_EQ_INT(q->a[1].v[4], 100);
    ASSERT_EQ_INT(q->a[1].v[5], 104);
    /* outside: nearest by weights tet 0 (weights of vertices 0..3: 1.3,
     * -0.5, 0.1, 0.1; tet 1's smallest is -0.65), clamped: 1.3, 0, 0.1, 0.1
     * over 1.5: f = (0.1 * 2 + 0.1 * 3) / 1.5, id of vertex 0 */
    ASSERT_NEAR(q->a[0].v[7], 0.5 / 1.5, 1e-12);
    ASSERT_EQ_INT(q->a[1].v[7], 100);
    /* again: the made flags carry through (nothing new this time) */
    {
        mesh_t *n = mesh_new(8, 0, 0);
        mesh_pdata *r = NULL;
        const int32_t same[8] = {0, 1, 2, 3, 4, 5, 6, 7};
        ASSERT_TRUE(n);
        n->pdata = q;
        q = NULL;
        ASSERT_OK(mesh_pdata_remap(n, 8, nx, same, &r, &err));
        ASSERT_TRUE(r && r->ninterp == 4 && r->made[4] && !r->made[0]);
        mesh_pdata_free(r);
        mesh_free(n);
    }
    mesh_free(m);
}

/* Without point data nothing is built. */
TEST(remap_without_pdata)
{
    mesh_t *m = mesh_new(4, 0, 0);
    const int32_t vmap[4] = {0, 1, 2, 3};
    double x[12] = {0};
    mesh_pdata *q = (mesh_pdata *)1;
    qdc_error err;

    ASSERT_TRUE(m);
    ASSERT_OK(mesh_pdata_remap(m, 4, x, vmap, &q, &err));
    ASSERT_TRUE(q == NULL);
    mesh_free(m);
}

TEST_MAIN("pdata", T(vtk_ascii_arrays), T(vtk_medit_ref_stays_vref),
          T(vtk_bad_sizes_and_nan), T(vtu_point_data), T(gmsh_node_data),
          T(roundtrip_bit_for_bit), T(add_refuses_nan_and_bad_shapes),
          T(name_control_bytes), T(integer_arrays_stay_exact),
          T(remap_interpolates_linear_fields), T(remap_without_pdata))
