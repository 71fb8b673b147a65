/* test_fewrite.c - qdc's own writers of Abaqus/CalculiX .inp and Netgen
 * .vol, on hand-made meshes with known values: written, read back, the same
 * coordinates bit for bit, the same tets, regions, triangles and refs; the
 * text each writes (ELSET names, Netgen's domin/domout from the geometry);
 * tets regrouped by region in Abaqus; a mesh without regions or triangles;
 * negative, zero and extreme tags; second-order tets; triangle elements and
 * ELSET names of other writers read; errors. */
#include "testio.h"
#include "testlib.h"

static const meshio_format fmts[2] = {MESHIO_ABAQUS, MESHIO_NETGEN};

/* Doubles that stress exact printing: signed zero, a subnormal, the
 * extremes, thirds, integers, a power of ten with no '.' in %.17g. */
static const double nasty[15] = {0.0,
                                 -0.0,
                                 1.0 / 3.0,
                                 1.0,
                                 -2.0,
                                 1e21,
                                 4.9406564584124654e-324,
                                 -1.7976931348623157e308,
                                 0.1,
                                 1e-5,
                                 123456789012345678.0,
                                 2.2250738585072014e-308,
                                 -1.0 / 3.0,
                                 5.0,
                                 9007199254740993.0};

/* The corners of the unit tet and (1, 1, 1). */
static const double unit[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};

static qdc_status read_str(const char *s, meshio_format f, mesh_t **m, qdc_error *err)
{
    return meshio_read(s, strlen(s), f, m, err);
}

TEST(writers_declared)
{
    meshio_format_info fi;

    for (int k = 0; k < 2; k++) {
        ASSERT_TRUE(meshio_has_writer(fmts[k]));
        ASSERT_TRUE(meshio_format_info_of(fmts[k], &fi));
        ASSERT_TRUE(fi.writes && fi.splices);
        ASSERT_TRUE(strstr(fi.about, "spliced") == NULL);
    }
}

TEST(roundtrip_exact)
{
    mesh_t *m = five_mesh(nasty, 1, 3, 7, 2, 11, 12), *b;

    ASSERT_TRUE(m);
    for (int k = 0; k < 2; k++) {
        ASSERT_OK(roundtrip(m, fmts[k], &b));
        ASSERT_TRUE(same_mesh(m, b, K_REGION | K_TRIS)); /* bit for bit */
        ASSERT_EQ_INT(b->region[1], 7);
        ASSERT_EQ_INT(b->tri_ref[1], 12);
        ASSERT_TRUE(signbit(b->xyz[1]) && b->xyz[1] == 0); /* -0 stays -0 */
        ASSERT_TRUE(b->mid == NULL && b->vref == NULL && b->fixed == NULL);
        mesh_free(b);
    }
    mesh_free(m);
}

/* The text: nodes from 1, one *ELEMENT block per region and per ref with
 * qdc's ELSET names; Netgen's domin/domout: the normal of 1 2 3 (0-based)
 * is (1, 1, 1), vertex 0 behind it (tet 0, region 3, is domin) and 4 in
 * front (region 7 domout); that of 0 1 2 is +z, vertex 3 in front. */
TEST(written_text)
{
    mesh_t *m = five_mesh(unit, 1, 3, 7, 2, 11, 12);
    sink s = {0};
    qdc_error err;

    ASSERT_TRUE(m);
    m->xyz[3] = 1.0 / 3.0;
    ASSERT_OK(write_to(m, MESHIO_ABAQUS, &s, &err));
    ASSERT_TRUE(strcmp(s.b, "*HEADING\nwritten by qdc\n*NODE\n1, 0, 0, 0\n"
                            "2, 0.33333333333333331, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n"
                            "5, 1, 1, 1\n*ELEMENT, TYPE=C3D4, ELSET=REGION_3\n"
                            "1, 1, 2, 3, 4\n*ELEMENT, TYPE=C3D4, ELSET=REGION_7\n"
                            "2, 5, 2, 3, 4\n*ELEMENT, TYPE=S3, ELSET=SURFACE_11\n"
                            "3, 2, 3, 4\n*ELEMENT, TYPE=S3, ELSET=SURFACE_12\n"
                            "4, 1, 2, 3\n") == 0);
    m->xyz[3] = 1;
    ASSERT_OK(write_to(m, MESHIO_NETGEN, &s, &err));
    ASSERT_TRUE(strncmp(s.b, "mesh3d\ndimension\n3\ngeomtype\n0\n\n", 31) == 0);
    ASSERT_TRUE(
        strstr(s.b, "\nsurfaceelements\n2\n1 11 3 7 3 2 3 4\n1 12 0 3 3 1 2 3\n"));
    ASSERT_TRUE(strstr(s.b, "\nvolumeelements\n2\n3 4 1 2 3 4\n7 4 5 2 3 4\n"));
    ASSERT_TRUE(
        strstr(s.b, "\npoints\n5\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n\nendmesh\n"));
    /* the triangle the other way round: the sides swap */
    m->tris[1] = 3;
    m->tris[2] = 2;
    ASSERT_OK(write_to(m, MESHIO_NETGEN, &s, &err));
    ASSERT_TRUE(strstr(s.b, "\nsurfaceelements\n2\n1 11 7 3 3 2 4 3\n"));
    free(s.b);
    mesh_free(m);
}

/* Abaqus groups the tets by region (ascending; in order within one) and
 * numbers tet t as element t + 1; Netgen keeps the order. */
TEST(abaqus_groups_by_region)
{
    mesh_t *m = five_mesh(unit, 1, 9, -4, 2, 5, 2), *b;
    sink s = {0};
    qdc_error err;

    ASSERT_TRUE(m);
    ASSERT_OK(roundtrip(m, MESHIO_ABAQUS, &b));
    ASSERT_TRUE(memcmp(b->tets, m->tets + 4, 4 * sizeof(int32_t)) == 0);
    ASSERT_TRUE(memcmp(b->tets + 4, m->tets, 4 * sizeof(int32_t)) == 0);
    ASSERT_TRUE(b->region[0] == -4 && b->region[1] == 9);
    ASSERT_TRUE(memcmp(b->tris, m->tris + 3, 3 * sizeof(int32_t)) == 0);
    ASSERT_TRUE(b->tri_ref[0] == 2 && b->tri_ref[1] == 5);
    mesh_free(b);
    ASSERT_OK(write_to(m, MESHIO_ABAQUS, &s, &err));
    ASSERT_TRUE(strstr(s.b, "ELSET=REGION_M4\n2, 5, 2, 3, 4\n*ELEMENT, TYPE=C3D4, "
                            "ELSET=REGION_9\n1, 1, 2, 3, 4\n"));
    ASSERT_OK(roundtrip(m, MESHIO_NETGEN, &b));
    ASSERT_TRUE(same_mesh(m, b, K_REGION | K_TRIS));
    mesh_free(b);
    free(s.b);
    mesh_free(m);
}

/* No regions, no triangles: Abaqus reads back none (no ELSET); Netgen has
 * a material for every tet, written 1, so the regions come back all 1. */
TEST(no_regions_no_triangles)
{
    mesh_t *m = five_mesh(nasty, 0, 0, 0, 0, 0, 0), *b;
    sink s = {0};
    qdc_error err;

    ASSERT_TRUE(m);
    ASSERT_OK(roundtrip(m, MESHIO_ABAQUS, &b));
    ASSERT_TRUE(same_mesh(m, b, 0));
    ASSERT_TRUE(b->region == NULL && b->ntri == 0 && b->tri_ref == NULL);
    mesh_free(b);
    ASSERT_OK(roundtrip(m, MESHIO_NETGEN, &b));
    ASSERT_TRUE(same_mesh(m, b, 0));
    ASSERT_TRUE(b->region && b->region[0] == 1 && b->region[1] == 1 && b->ntri == 0);
    mesh_free(b);
    ASSERT_OK(write_to(m, MESHIO_ABAQUS, &s, &err));
    ASSERT_TRUE(strstr(s.b, "\n*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n2, 5, 2, 3, 4\n"));
    ASSERT_TRUE(strstr(s.b, "ELSET") == NULL && strstr(s.b, "S3") == NULL);
    ASSERT_OK(write_to(m, MESHIO_NETGEN, &s, &err));
    ASSERT_TRUE(strstr(s.b, "\nsurfaceelements\n0\n"));
    /* triangles without refs: no ELSET, read back as refs 0 */
    mesh_free(m);
    m = five_mesh(unit, 0, 0, 0, 2, 0, 0);
    ASSERT_TRUE(m);
    qdc_free(m->tri_ref);
    m->tri_ref = NULL;
    ASSERT_OK(roundtrip(m, MESHIO_ABAQUS, &b));
    ASSERT_TRUE(b->ntri == 2 && b->tri_ref == NULL);
    ASSERT_TRUE(memcmp(b->tris, m->tris, 6 * sizeof(int32_t)) == 0);
    mesh_free(b);
    free(s.b);
    mesh_free(m);
}

/* Negative, zero and extreme tags are held as they are. */
TEST(negative_and_zero_tags)
{
    mesh_t *m = five_mesh(nasty, 1, INT32_MIN, 0, 2, -1, INT32_MAX), *b;
    sink s = {0};
    qdc_error err;

    ASSERT_TRUE(m);
    for (int k = 0; k < 2; k++) {
        ASSERT_OK(roundtrip(m, fmts[k], &b));
        ASSERT_TRUE(same_mesh(m, b, K_REGION | K_TRIS));
        ASSERT_EQ_INT(b->region[0], INT32_MIN);
        ASSERT_EQ_INT(b->region[1], 0);
        ASSERT_EQ_INT(b->tri_ref[0], -1);
        ASSERT_EQ_INT(b->tri_ref[1], INT32_MAX);
        mesh_free(b);
    }
    ASSERT_OK(write_to(m, MESHIO_ABAQUS, &s, &err));
    ASSERT_TRUE(strstr(s.b, "ELSET=REGION_M2147483648\n1, 1, 2, 3, 4\n"));
    ASSERT_TRUE(strstr(s.b, "ELSET=REGION_0\n2, 5, 2, 3, 4\n"));
    ASSERT_TRUE(strstr(s.b, "ELSET=SURFACE_M1\n3, 2, 3, 4\n"));
    ASSERT_TRUE(strstr(s.b, "ELSET=SURFACE_2147483647\n4, 1, 2, 3\n"));
    free(s.b);
    mesh_free(m);
}

/* ELSET names of other writers, and qdc's spelled otherwise, number the
 * sets by their order; triangles of other element types are read, their
 * corners only. */
TEST(foreign_names_and_types)
{
    static const char inp[] =
        "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n5, 1, 1, 1\n"
        "6, .5, .5, 0\n7, 0, .5, 0\n8, .5, 0, 0\n"
        "*ELEMENT, TYPE=C3D4, ELSET=REGION_5\n1, 1, 2, 3, 4\n"
        "*ELEMENT, TYPE=C3D4, ELSET=REGION_05\n2, 5, 2, 3, 4\n"
        "*ELEMENT, TYPE=CPS6, ELSET=Surface1\n3, 1, 2, 3, 8, 6,\n 7\n"
        "*Element, type=R3D3\n4, 2, 3, 4\n*ELEMENT, TYPE=T3D2\n5, 1, 2\n";
    static const char named[] = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n"
                                "*ELEMENT, TYPE=C3D4, elset=region_m7\n1, 1, 2, 3, 4\n"
                                "*ELEMENT, TYPE=S3, ELSET=SURFACE_40\n2, 1, 2, 3\n"
                                "*ELEMENT, TYPE=S3\n3, 1, 2, 4\n";
    mesh_t *m;
    qdc_error err;

    ASSERT_OK(read_str(inp, MESHIO_ABAQUS, &m, &err));
    ASSERT_TRUE(m->nt == 2 && m->region[0] == 1 && m->region[1] == 2);
    ASSERT_EQ_INT(m->ntri, 2);
    ASSERT_TRUE(m->tris[0] == 0 && m->tris[1] == 1 && m->tris[2] == 2);
    ASSERT_TRUE(m->tris[3] == 1 && m->tris[4] == 2 && m->tris[5] == 3);
    ASSERT_TRUE(m->tri_ref[0] == 1 && m->tri_ref[1] == 0);
    mesh_free(m);
    ASSERT_OK(read_str(named, MESHIO_ABAQUS, &m, &err));
    ASSERT_TRUE(m->region[0] == -7 && m->ntri == 2);
    ASSERT_TRUE(m->tri_ref[0] == 40 && m->tri_ref[1] == 0);
    mesh_free(m);
}

/* Ten-node tets: C3D10 in the mesh_p2_edges order with STRI65 triangles
 * (mid-edge nodes of edges 01 12 20 from the tet); Netgen 10 points (edges
 * 01 02 03 12 13 23) and 6 for a triangle (edges 12 02 01). */
TEST(second_order)
{
    mesh_t *m = mesh_new(10, 1, MESH_WITH_REGION), *b;
    sink s = {0};
    qdc_error err;

    ASSERT_TRUE(m && mesh_set_mid(m) == QDC_OK && mesh_set_tris(m, 1, 1) == QDC_OK);
    for (int i = 0; i < 30; i++)
        m->xyz[i] = nasty[i % 15] + i;
    for (int k = 0; k < 4; k++)
        m->tets[k] = 9 - k; /* 9 8 7 6 */
    for (int e = 0; e < 6; e++)
        m->mid[e] = e; /* edges 01 12 02 03 13 23: 0..5 */
    m->region[0] = 4;
    m->tris[0] = 8; /* corners 1 2 3 of the tet: edges 12 23 31 are 1 5 4 */
    m->tris[1] = 7;
    m->tris[2] = 6;
    m->tri_ref[0] = 6;
    for (int k = 0; k < 2; k++) {
        ASSERT_OK(roundtrip(m, fmts[k], &b));
        ASSERT_TRUE(same_mesh(m, b, K_REGION | K_TRIS));
        ASSERT_TRUE(b->mid && memcmp(b->mid, m->mid, 6 * sizeof(int32_t)) == 0);
        mesh_free(b);
    }
    ASSERT_OK(write_to(m, MESHIO_ABAQUS, &s, &err));
    ASSERT_TRUE(strstr(s.b,
                       "\n*ELEMENT, TYPE=C3D10, ELSET=REGION_4\n"
                       "1, 10, 9, 8, 7, 1, 2, 3, 4, 5, 6\n"
                       "*ELEMENT, TYPE=STRI65, ELSET=SURFACE_6\n2, 9, 8, 7, 2, 6, 5\n"));
    ASSERT_OK(write_to(m, MESHIO_NETGEN, &s, &err));
    ASSERT_TRUE(strstr(s.b, "\nvolumeelements\n1\n4 10 10 9 8 7 1 3 4 2 5 6\n"));
    ASSERT_TRUE(strstr(s.b, " 6 9 8 7 6 5 2\n"));
    /* a triangle that is no face of a tet: S3 then, 3 points in Netgen */
    m->tris[0] = 9;
    m->tris[1] = 0;
    ASSERT_OK(write_to(m, MESHIO_ABAQUS, &s, &err));
    ASSERT_TRUE(strstr(s.b, "\n*ELEMENT, TYPE=S3, ELSET=SURFACE_6\n2, 10, 1, 7\n"));
    ASSERT_OK(write_to(m, MESHIO_NETGEN, &s, &err));
    ASSERT_TRUE(strstr(s.b, "\nsurfaceelements\n1\n1 6 0 0 3 10 1 7\n"));
    free(s.b);
    mesh_free(m);
}

/* An empty mesh reads back empty. */
TEST(empty_mesh)
{
    mesh_t *m = mesh_new(0, 0, 0), *b;

    ASSERT_TRUE(m);
    for (int k = 0; k < 2; k++) {
        ASSERT_OK(roundtrip(m, fmts[k], &b));
        ASSERT_TRUE(b->nv == 0 && b->nt == 0 && b->ntri == 0);
        mesh_free(b);
    }
    mesh_free(m);
}

/* Errors: a triangle element naming an unknown node or short of numbers;
 * a non-finite coordinate or an index out of range refused before writing;
 * a failing sink is QDC_EIO. */
TEST(errors)
{
    static const char unknown[] =
        "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n"
        "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n"
        "*ELEMENT, TYPE=S3\n2, 1, 2, 3\n3, 1, 2, 9\n";
    static const char shortl[] = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n"
                                 "*ELEMENT, TYPE=STRI65\n2, 1, 2, 3\n";
    mesh_t *m = five_mesh(unit, 1, 1, 2, 2, 1, 2), *b = NULL;
    sink s = {0};
    qdc_error err;

    ASSERT_EQ_INT(read_str(unknown, MESHIO_ABAQUS, &b, &err), QDC_EPARSE);
    ASSERT_TRUE(strstr(err.msg, "unknown node 9") && err.line == 10);
    ASSERT_EQ_INT(err.index, 1);
    ASSERT_EQ_INT(read_str(shortl, MESHIO_ABAQUS, &b, &err), QDC_EPARSE);
    ASSERT_TRUE(strstr(err.msg, "a triangle element needs 7 numbers, got 4"));
    ASSERT_TRUE(b == NULL && m);
    s.fail_after = 40;
    for (int k = 0; k < 2; k++)
        ASSERT_EQ_INT(meshio_write(m, fmts[k], sink_write, &s, &err), QDC_EIO);
    s.fail_after = 0;
    m->xyz[4] = NAN;
    for (int k = 0; k < 2; k++) {
        ASSERT_EQ_INT(write_to(m, fmts[k], &s, &err), QDC_EINVAL);
        ASSERT_EQ_INT(err.index, 1);
    }
    m->xyz[4] = 0;
    m->tris[5] = 5;
    for (int k = 0; k < 2; k++)
        ASSERT_EQ_INT(write_to(m, fmts[k], &s, &err), QDC_EINVAL);
    free(s.b);
    mesh_free(m);
}

/* A mesh read from a file and given new tets is written by the writer, not
 * spliced: the file's other keywords are gone, the new tets there. */
TEST(new_tets_not_spliced)
{
    static const char doc[] = "*HEADING\nmine\n*NODE\n10, 0, 0, 0\n20, 1, 0, 0\n"
                              "30, 0, 1, 0\n40, 0, 0, 1\n50, 1, 1, 1\n"
                              "*ELEMENT, TYPE=C3D4, ELSET=steel\n7, 10, 20, 30, 40\n"
                              "*STEP\n*STATIC\n*END STEP\n";
    meshio_options o = {.log = NULL, .log_ctx = NULL, .source = 1};
    mesh_t *m;
    sink s = {0};
    qdc_error err;

    ASSERT_OK(meshio_read_ex(doc, strlen(doc), MESHIO_ABAQUS, &o, &m, &err));
    ASSERT_TRUE(meshio_splices(m, MESHIO_ABAQUS, NULL));
    m->tets[0] = 4; /* node 50 for 10 */
    ASSERT_TRUE(!meshio_splices(m, MESHIO_ABAQUS, NULL));
    ASSERT_OK(write_to(m, MESHIO_ABAQUS, &s, &err));
    ASSERT_TRUE(strstr(s.b, "*STEP") == NULL);
    ASSERT_TRUE(strstr(s.b, "\n5, 1, 1, 1\n*ELEMENT, TYPE=C3D4, ELSET=REGION_1\n"
                            "1, 5, 2, 3, 4\n"));
    free(s.b);
    mesh_free(m);
}

TEST_MAIN("fewrite", T(writers_declared), T(roundtrip_exact), T(written_text),
          T(abaqus_groups_by_region), T(no_regions_no_triangles),
          T(negative_and_zero_tags), T(foreign_names_and_types), T(second_order),
          T(empty_mesh), T(errors), T(new_tets_not_spliced))
