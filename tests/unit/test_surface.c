/* test_surface.c - surface readers (STL ASCII/binary, OFF, OBJ, .poly, .smesh),
 * vertex merging, the closed/manifold/oriented checks, TetGen through the
 * bridge (valid positive tets, regions, facet markers, quality and volume
 * options, self-intersections and open surfaces as clear errors, never a
 * crash), names and media types, and the surface fuzz seeds and crashes. */
#include "qdc.h"
#include "testio.h"
#include "testlib.h"

/* The unit cube as 8 vertices and 6 outward quads. */
static const double cube_v[8][3] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, {0, 1, 1},
                                    {1, 0, 0}, {1, 0, 1}, {1, 1, 0}, {1, 1, 1}};
static const int cube_q[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
                                 {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};

/* ASCII STL of the cube shifted by (dx, 0, 0); skip one triangle if `open`. */
static void cube_stl(char *out, size_t n, double dx, int open)
{
    size_t o = (size_t)snprintf(out, n, "solid cube\n");

    for (int f = 0; f < 6; f++)
        for (int h = 0; h < 2; h++) {
            int tri[3] = {cube_q[f][0], cube_q[f][1 + h], cube_q[f][2 + h]};
            if (open && f == 5 && h == 1)
                continue;
            o += (size_t)snprintf(out + o, n - o,
                                  "  facet normal 0 0 0\n    outer loop\n");
            for (int k = 0; k < 3; k++)
                o += (size_t)snprintf(out + o, n - o, "      vertex %g %g %g\n",
                                      cube_v[tri[k]][0] + dx, cube_v[tri[k]][1],
                                      cube_v[tri[k]][2]);
            o += (size_t)snprintf(out + o, n - o, "    endloop\n  endfacet\n");
        }
    snprintf(out + o, n - o, "endsolid cube\n");
}

static qdc_status surf_str(const char *s, surface_format f, surface_t **out,
                           qdc_error *err)
{
    return surface_read(s, strlen(s), f, out, err);
}

static double tet_det(const mesh_t *m, int32_t t)
{
    const int32_t *v = m->tets + 4 * t;
    const double *a = m->xyz + 3 * v[0], *b = m->xyz + 3 * v[1], *c = m->xyz + 3 * v[2],
                 *d = m->xyz + 3 * v[3];
    double u[3], w[3], z[3];

    for (int i = 0; i < 3; i++) {
        u[i] = b[i] - a[i];
        w[i] = c[i] - a[i];
        z[i] = d[i] - a[i];
    }
    return u[0] * (w[1] * z[2] - w[2] * z[1]) - u[1] * (w[0] * z[2] - w[2] * z[0]) +
           u[2] * (w[0] * z[1] - w[1] * z[0]);
}

/* Valid mesh, every tet positive, total volume vol. */
static int good_mesh(const mesh_t *m, double vol)
{
    double sum = 0;
    qdc_error err;

    if (mesh_validate(m, NULL, &err) != QDC_OK)
        return 0;
    for (int32_t t = 0; t < m->nt; t++) {
        double d = tet_det(m, t);
        if (!(d > 0))
            return 0;
        sum += d / 6;
    }
    return fabs(sum - vol) < 1e-9 * vol;
}

/* ---- readers ---- */

TEST(stl_ascii_merges_vertices)
{
    char buf[8192];
    surface_t *s;
    qdc_error err;

    cube_stl(buf, sizeof buf, 0, 0);
    ASSERT_OK(surf_str(buf, SURFACE_AUTO, &s, &err));
    ASSERT_EQ_INT(s->nv, 8);
    ASSERT_EQ_INT(s->ntri, 12);
    ASSERT_OK(surface_check(s, &err));
    surface_free(s);
}

TEST(stl_binary)
{
    unsigned char b[84 + 50 * 12];
    surface_t *s;
    qdc_error err;
    size_t o = 84;

    memset(b, 0, sizeof b);
    memcpy(b, "solid but binary", 16); /* binary files may start with "solid" */
    b[80] = 12;
    for (int f = 0; f < 6; f++)
        for (int h = 0; h < 2; h++) {
            int tri[3] = {cube_q[f][0], cube_q[f][1 + h], cube_q[f][2 + h]};
            o += 12;
            for (int k = 0; k < 3; k++)
                for (int a = 0; a < 3; a++) {
                    float x = (float)cube_v[tri[k]][a];
                    memcpy(b + o, &x, 4);
                    o += 4;
                }
            o += 2;
        }
    ASSERT_EQ_INT(surface_sniff((char *)b, sizeof b), SURFACE_STL);
    ASSERT_OK(surface_read((char *)b, sizeof b, SURFACE_STL, &s, &err));
    ASSERT_EQ_INT(s->nv, 8);
    ASSERT_OK(surface_check(s, &err));
    surface_free(s);
    ASSERT_EQ_INT(surface_read((char *)b, sizeof b - 1, SURFACE_STL, &s, &err),
                  QDC_EPARSE);
}

TEST(off_obj_poly_smesh)
{
    const char *off = "OFF\n# cube\n8 6 0\n0 0 0\n0 0 1\n0 1 0\n0 1 1\n1 0 0\n1 0 1\n"
                      "1 1 0\n1 1 1\n4 0 1 3 2\n4 4 6 7 5\n4 0 4 5 1\n4 2 3 7 6\n"
                      "4 0 2 6 4 255 0 0\n4 1 5 7 3\n";
    const char *obj =
        "# cube\nmtllib x.mtl\no cube\nv 0 0 0\nv 0 0 1\nv 0 1 0\nv 0 1 1\n"
        "v 1 0 0\nv 1 0 1\nv 1 1 0\nv 1 1 1\nvn 0 0 1\ns off\n"
        "f 1//1 2//1 4//1 3//1\nf 5 7 8 6\nf 1/1 5/1 6/1 2/1\nf -6 -5 -1 -2\n"
        "f 1 3 7 5\nf 2 6 8 4\n";
    const char *poly = "8 3 0 0\n1 0 0 0\n2 0 0 1\n3 0 1 0\n4 0 1 1\n5 1 0 0\n6 1 0 1\n"
                       "7 1 1 0\n8 1 1 1\n6 1\n1 0 1\n4 1 2 4 3\n1 0 2\n4 5 7 8 6\n"
                       "1 0 3\n4 1 5 6 2\n1 0 4\n4 3 4 8 7\n1 0 5\n4 1 3 7 5\n"
                       "1 0 6\n4 2 6 8 4\n0\n1\n1 0.5 0.5 0.5 7 0\n";
    const char *smesh = "8 3 0 0\n0 0 0 0\n1 0 0 1\n2 0 1 0\n3 0 1 1\n4 1 0 0\n5 1 0 1\n"
                        "6 1 1 0\n7 1 1 1\n6 1\n4 0 1 3 2 1\n4 4 6 7 5 2\n4 0 4 5 1 3\n"
                        "4 2 3 7 6 4\n4 0 2 6 4 5\n4 1 5 7 3 6\n0\n0\n";
    const char *const in[4] = {off, obj, poly, smesh};
    surface_t *s;
    qdc_error err;

    for (int i = 0; i < 4; i++) {
        ASSERT_OK(surf_str(
            in[i], i == 1 ? SURFACE_AUTO : (surface_format)(SURFACE_OFF + i), &s, &err));
        ASSERT_EQ_INT(s->nv, 8);
        ASSERT_EQ_INT(s->ntri, 12);
        ASSERT_OK(surface_check(s, &err));
        if (i >= 2) {
            ASSERT_TRUE(s->tri_ref);
            ASSERT_EQ_INT(s->tri_ref[11], 6);
        }
        if (i == 2) {
            ASSERT_EQ_INT(s->nregions, 1);
            ASSERT_NEAR(s->regions[3], 7, 0);
        }
        surface_free(s);
    }
}

TEST(reader_errors_say_where)
{
    surface_t *s;
    qdc_error err;

    ASSERT_EQ_INT(
        surf_str("OFF\n3 1 0\n0 0 0\n1 0 0\n0 nan 0\n3 0 1 2\n", SURFACE_OFF, &s, &err),
        QDC_EPARSE);
    ASSERT_EQ_INT(err.line, 5);
    ASSERT_EQ_INT(err.col, 3);
    ASSERT_EQ_INT(surf_str("OFF\n3 1000000000 0\n0 0 0\n", SURFACE_OFF, &s, &err),
                  QDC_EPARSE);
    ASSERT_TRUE(strstr(err.msg, "does not fit"));
    ASSERT_EQ_INT(surf_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", SURFACE_OBJ, &s, &err),
                  QDC_EPARSE);
    ASSERT_EQ_INT(err.line, 4);
    ASSERT_EQ_INT(surf_str("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n",
                           SURFACE_STL, &s, &err),
                  QDC_EPARSE);
    ASSERT_EQ_INT(surf_str("hello", SURFACE_AUTO, &s, &err), QDC_EFORMAT);
}

TEST(checks)
{
    char buf[8192];
    surface_t *s;
    qdc_error err;

    cube_stl(buf, sizeof buf, 0, 1);
    ASSERT_OK(surf_str(buf, SURFACE_STL, &s, &err));
    ASSERT_EQ_INT(surface_check(s, &err), QDC_EMESH);
    ASSERT_TRUE(strstr(err.msg, "not closed"));
    s->ntri = 0;
    ASSERT_EQ_INT(surface_check(s, &err), QDC_EMESH);
    surface_free(s);
    ASSERT_OK(surf_str("OFF\n4 2 0\n0 0 0\n1 0 0\n2 0 0\n0 1 0\n3 0 1 2\n3 0 1 3\n",
                       SURFACE_OFF, &s, &err));
    ASSERT_EQ_INT(surface_check(s, &err), QDC_EMESH);
    ASSERT_TRUE(strstr(err.msg, "zero area"));
    surface_free(s);
}

/* ---- TetGen ---- */

TEST(tetgen_cube_and_options)
{
    char buf[8192];
    surface_t *s;
    mesh_t *m;
    tetra_options o;
    qdc_error err;
    int32_t nt0;

    cube_stl(buf, sizeof buf, 0, 0);
    ASSERT_OK(surf_str(buf, SURFACE_STL, &s, &err));
    tetra_defaults(&o);
    ASSERT_OK(tetra_from_surface_t(s, &o, &m, &err));
    ASSERT_TRUE(good_mesh(m, 1));
    ASSERT_TRUE(m->region && m->region[0] == 1);
    nt0 = m->nt;
    mesh_free(m);
    o.quality = 1.4;
    o.max_volume = 0.001;
    ASSERT_OK(tetra_from_surface_t(s, &o, &m, &err));
    ASSERT_TRUE(good_mesh(m, 1));
    ASSERT_TRUE(m->nt >= 1000 && m->nt > nt0);
    mesh_free(m);
    o.quality = 0.5;
    ASSERT_EQ_INT(tetra_from_surface_t(s, &o, &m, &err), QDC_EINVAL);
    ASSERT_OK(tetra_from_surface(s->xyz, s->nv, s->tris, s->ntri, NULL, &m, &err));
    mesh_free(m);
    surface_free(s);
}

TEST(tetgen_regions_and_markers)
{
    const char *poly = "8 3 0 0\n1 0 0 0\n2 0 0 1\n3 0 1 0\n4 0 1 1\n5 1 0 0\n6 1 0 1\n"
                       "7 1 1 0\n8 1 1 1\n6 1\n1 0 1\n4 1 2 4 3\n1 0 2\n4 5 7 8 6\n"
                       "1 0 3\n4 1 5 6 2\n1 0 4\n4 3 4 8 7\n1 0 5\n4 1 3 7 5\n"
                       "1 0 6\n4 2 6 8 4\n0\n1\n1 0.5 0.5 0.5 7 0.01\n";
    mesh_t *m;
    qdc_error err;
    int markers[7] = {0};

    ASSERT_OK(tetra_from_buffer(poly, strlen(poly), SURFACE_POLY, NULL, &m, &err));
    ASSERT_TRUE(good_mesh(m, 1));
    ASSERT_TRUE(m->nt >= 100);
    for (int32_t t = 0; t < m->nt; t++)
        ASSERT_EQ_INT(m->region[t], 7);
    ASSERT_TRUE(m->ntri > 0 && m->tri_ref);
    for (int32_t t = 0; t < m->ntri; t++)
        if (m->tri_ref[t] >= 1 && m->tri_ref[t] <= 6)
            markers[m->tri_ref[t]] = 1;
    for (int k = 1; k <= 6; k++)
        ASSERT_TRUE(markers[k]);
    mesh_free(m);
}

TEST(tetgen_two_parts)
{
    char a[8192], b[8192], both[16384];
    mesh_t *m;
    qdc_error err;

    cube_stl(a, sizeof a, 0, 0);
    cube_stl(b, sizeof b, 3, 0);
    *strstr(a, "endsolid") = '\0';
    snprintf(both, sizeof both, "%s%s", a, strstr(b, "  facet"));
    ASSERT_OK(tetra_from_buffer(both, strlen(both), SURFACE_STL, NULL, &m, &err));
    ASSERT_TRUE(good_mesh(m, 2));
    mesh_free(m);
}

/* Problems come back as clear errors, never a crash or an exit. */
TEST(tetgen_bad_surfaces)
{
    char a[8192], b[8192], both[16384];
    mesh_t *m = NULL;
    qdc_error err;

    cube_stl(a, sizeof a, 0, 0);
    cube_stl(b, sizeof b, 0.5, 0);
    *strstr(a, "endsolid") = '\0';
    snprintf(both, sizeof both, "%s%s", a, strstr(b, "  facet"));
    ASSERT_EQ_INT(tetra_from_buffer(both, strlen(both), SURFACE_STL, NULL, &m, &err),
                  QDC_ETETGEN);
    ASSERT_TRUE(strstr(err.msg, "intersects itself"));
    ASSERT_TRUE(m == NULL);
    cube_stl(a, sizeof a, 0, 1);
    ASSERT_EQ_INT(tetra_from_buffer(a, strlen(a), SURFACE_STL, NULL, &m, &err),
                  QDC_EMESH);
    ASSERT_TRUE(strstr(err.msg, "not closed"));
    ASSERT_EQ_INT(
        tetra_from_buffer("solid x\nendsolid x\n", 19, SURFACE_STL, NULL, &m, &err),
        QDC_EMESH);
    ASSERT_EQ_INT(qdc_status_http(QDC_ETETGEN), 422);
    ASSERT_EQ_INT(qdc_status_http(QDC_EMESH), 422);
}

/* ---- names ---- */

TEST(names_and_media_types)
{
    ASSERT_EQ_INT(surface_format_from_name("a/b.STL"), SURFACE_STL);
    ASSERT_EQ_INT(surface_format_from_name("smesh"), SURFACE_SMESH);
    ASSERT_EQ_INT(surface_format_from_name("x.mesh"), SURFACE_AUTO);
    for (int f = 1; f < SURFACE_FORMAT_COUNT; f++) {
        ASSERT_EQ_INT(surface_format_from_name(surface_format_name((surface_format)f)),
                      f);
        ASSERT_EQ_INT(
            surface_format_from_media_type(surface_media_type((surface_format)f)), f);
    }
    ASSERT_EQ_INT(surface_format_from_media_type("model/stl; charset=binary"),
                  SURFACE_STL);
    ASSERT_EQ_INT(surface_format_from_media_type("model/vnd.gmsh"), SURFACE_AUTO);
    ASSERT_EQ_INT(surface_sniff("OFF\n", 4), SURFACE_OFF);
    ASSERT_EQ_INT(surface_sniff("# x\nv 1 2 3\n", 12), SURFACE_OBJ);
    ASSERT_EQ_INT(surface_sniff("MeshVersionFormatted 2\n", 23), SURFACE_AUTO);
}

/* ---- corpus and fuzz replay ---- */

TEST(malformed_corpus)
{
    int n, bad = run_corpus("surface_", &n);

    printf("  # %d surface corpus cases\n", n);
    ASSERT_TRUE(n >= 5);
    ASSERT_EQ_INT(bad, 0);
}

static int replay_surface(const char *buf, size_t len)
{
    for (int f = 0; f < SURFACE_FORMAT_COUNT; f++) {
        surface_t *s = NULL;
        qdc_error err;
        qdc_status st = surface_read(buf, len, (surface_format)f, &s, &err);
        if ((unsigned)st >= QDC_STATUS_COUNT || (st == QDC_OK) != (s != NULL) ||
            (st != QDC_OK && err.status != st))
            return 1;
        if (s)
            surface_check(s, &err);
        surface_free(s);
    }
    return 0;
}

TEST(fuzz_replay)
{
    int n, bad = replay_fuzz("surface", replay_surface, &n);

    printf("  # %d fuzz inputs replayed\n", n);
    ASSERT_TRUE(n > 0);
    ASSERT_EQ_INT(bad, 0);
}

TEST_MAIN("surface", T(stl_ascii_merges_vertices), T(stl_binary), T(off_obj_poly_smesh),
          T(reader_errors_say_where), T(checks), T(tetgen_cube_and_options),
          T(tetgen_regions_and_markers), T(tetgen_two_parts), T(tetgen_bad_surfaces),
          T(names_and_media_types), T(malformed_corpus), T(fuzz_replay))
