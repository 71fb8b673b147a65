// tetra.cpp - the C++ bridge to TetGen 1.5 (see tetra.h). Everything TetGen
// does happens inside one try block: with TETLIBRARY defined its
// terminatetetgen() throws the exit code (an int) instead of calling exit(),
// and new may throw std::bad_alloc; both, and anything else, are caught and
// turned into a qdc_status. Memory handed back is qdc_malloc'ed (mesh_new).
#define TETLIBRARY
#include <tetgen.h>

extern "C" { // the C headers tetra.h pulls in (base.h, mesh.h, surface.h)
#include "io/tetra.h"
}

#include <cstdio>
#include <cstring>
#include <new>

extern "C" void tetra_defaults(tetra_options *o)
{
    o->quality = 2.0;
    o->min_dihedral = 0;
    o->max_volume = 0;
    o->max_steiner = 0;
}

// The reason behind TetGen's exit codes (tetgen.h, terminatetetgen).
static const char *tetgen_reason(int code)
{
    switch (code) {
    case 1:
        return "out of memory";
    case 2:
        return "internal error in TetGen";
    case 3:
        return "the surface intersects itself";
    case 4:
        return "a very small input feature size was detected (below TetGen's tolerance)";
    case 5:
        return "two very close input facets were detected";
    case 10:
        return "TetGen found an input error";
    default:
        return "TetGen failed";
    }
}

// det[b-a, c-a, d-a] > 0: positive in the sense of mesh.h
static bool positive(const double *xyz, const int *t)
{
    const double *a = xyz + 3 * t[0], *b = xyz + 3 * t[1], *c = xyz + 3 * t[2],
                 *d = xyz + 3 * t[3];
    double u[3], v[3], w[3];

    for (int i = 0; i < 3; i++) {
        u[i] = b[i] - a[i];
        v[i] = c[i] - a[i];
        w[i] = d[i] - a[i];
    }
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
               u[2] * (v[0] * w[1] - v[1] * w[0]) >
           0;
}

static qdc_status fill_input(tetgenio &in, const surface_t &s)
{
    in.firstnumber = 0;
    in.numberofpoints = s.nv;
    in.pointlist = new REAL[3 * (size_t)s.nv];
    std::memcpy(in.pointlist, s.xyz, 3 * (size_t)s.nv * sizeof(double));
    in.numberoffacets = s.ntri;
    in.facetlist = new tetgenio::facet[s.ntri];
    for (int32_t t = 0; t < s.ntri; t++) { // null first, so a throw leaves it deletable
        in.facetlist[t].polygonlist = NULL;
        in.facetlist[t].numberofpolygons = 0;
        in.facetlist[t].holelist = NULL;
        in.facetlist[t].numberofholes = 0;
    }
    for (int32_t t = 0; t < s.ntri; t++) {
        tetgenio::facet &f = in.facetlist[t];
        f.polygonlist = new tetgenio::polygon[1];
        f.numberofpolygons = 1;
        f.polygonlist[0].vertexlist = NULL;
        f.polygonlist[0].numberofvertices = 0;
        f.polygonlist[0].vertexlist = new int[3];
        f.polygonlist[0].numberofvertices = 3;
        for (int j = 0; j < 3; j++)
            f.polygonlist[0].vertexlist[j] = s.tris[3 * (size_t)t + j];
    }
    if (s.tri_ref) {
        in.facetmarkerlist = new int[s.ntri];
        for (int32_t t = 0; t < s.ntri; t++)
            in.facetmarkerlist[t] = s.tri_ref[t];
    }
    if (s.nholes > 0) {
        in.numberofholes = s.nholes;
        in.holelist = new REAL[3 * (size_t)s.nholes];
        std::memcpy(in.holelist, s.holes, 3 * (size_t)s.nholes * sizeof(double));
    }
    if (s.nregions > 0) {
        in.numberofregions = s.nregions;
        in.regionlist = new REAL[5 * (size_t)s.nregions];
        std::memcpy(in.regionlist, s.regions, 5 * (size_t)s.nregions * sizeof(double));
    }
    return QDC_OK;
}

static qdc_status to_mesh(const tetgenio &out, bool with_faces, mesh_t **res,
                          qdc_error *err)
{
    int nv = out.numberofpoints, nt = out.numberoftetrahedra, npos = 0;
    bool attr = out.numberoftetrahedronattributes > 0 && out.tetrahedronattributelist;
    mesh_t *m;

    if (nv <= 0 || nt <= 0 || out.numberofcorners < 4)
        return qdc_fail(err, QDC_ETETGEN, "TetGen produced no tetrahedra");
    if (nt > MESH_MAX_TETS)
        return qdc_fail(err, QDC_ETOOBIG, "TetGen produced %d tets, above the limit", nt);
    m = mesh_new(nv, nt, MESH_WITH_REGION);
    if (!m)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %d tets", nt);
    std::memcpy(m->xyz, out.pointlist, 3 * (size_t)nv * sizeof(double));
    for (int t = 0; t < nt; t++) {
        const int *tt = out.tetrahedronlist + (size_t)out.numberofcorners * t;
        for (int j = 0; j < 4; j++)
            m->tets[4 * (size_t)t + j] = tt[j];
        npos += positive(out.pointlist, tt);
        m->region[t] = attr ? (int32_t)out.tetrahedronattributelist
                                  [(size_t)out.numberoftetrahedronattributes * t]
                            : 1;
    }
    if (2 * npos < nt) // TetGen's orientation is the opposite of ours
        for (int t = 0; t < nt; t++) {
            int32_t *tt = m->tets + 4 * (size_t)t, x = tt[2];
            tt[2] = tt[3];
            tt[3] = x;
        }
    if (with_faces && out.numberoftrifaces > 0 && out.trifacelist) {
        if (mesh_set_tris(m, out.numberoftrifaces, out.trifacemarkerlist != NULL) !=
            QDC_OK) {
            mesh_free(m);
            return qdc_fail(err, QDC_ENOMEM, "out of memory for the boundary triangles");
        }
        for (size_t i = 0; i < 3 * (size_t)out.numberoftrifaces; i++)
            m->tris[i] = out.trifacelist[i];
        for (int i = 0; out.trifacemarkerlist && i < out.numberoftrifaces; i++)
            m->tri_ref[i] = out.trifacemarkerlist[i];
    }
    *res = m;
    return QDC_OK;
}

extern "C" qdc_status tetra_from_surface_t(const surface_t *s, const tetra_options *o,
                                           mesh_t **out, qdc_error *err)
{
    tetra_options def;
    char sw[160];
    size_t n;
    qdc_status st;

    qdc_error_clear(err);
    if (!s || !out)
        return qdc_fail(err, QDC_EINVAL, "tetra_from_surface: NULL argument");
    *out = NULL;
    if (!o) {
        tetra_defaults(&def);
        o = &def;
    }
    if (!(o->quality == 0 || o->quality >= 1) || !(o->max_volume >= 0) ||
        !(o->min_dihedral >= 0 && o->min_dihedral < 70) || o->max_steiner < 0 ||
        o->quality > 1e6 || o->max_volume > 1e300)
        return qdc_fail(err, QDC_EINVAL,
                        "tetra options: quality >= 1 (or 0), 0 <= min dihedral < 70, "
                        "max volume >= 0, max steiner >= 0");
    st = surface_check(s, err);
    if (st != QDC_OK)
        return st;
    // p: piecewise linear complex, z: 0-based, Q: quiet, A: region attributes
    n = (size_t)std::snprintf(sw, sizeof sw, "pzQA");
    if (o->quality > 0) {
        n += (size_t)std::snprintf(sw + n, sizeof sw - n, "q%.17g", o->quality);
        if (o->min_dihedral > 0)
            n += (size_t)std::snprintf(sw + n, sizeof sw - n, "/%.17g", o->min_dihedral);
    }
    if (o->max_volume > 0)
        n += (size_t)std::snprintf(sw + n, sizeof sw - n, "a%.17g", o->max_volume);
    if (s->nregions > 0)
        n += (size_t)std::snprintf(sw + n, sizeof sw - n, "a");
    if (o->max_steiner > 0)
        std::snprintf(sw + n, sizeof sw - n, "S%d", (int)o->max_steiner);
    try {
        tetgenio in, res, diag;
        char dsw[] = "pzQd";
        fill_input(in, *s);
        // TetGen 1.5 frees its mesh in terminatetetgen() before throwing and
        // again when the mesh goes out of scope, which crashes; its -d run
        // (intersection detection) returns normally, so the commonest failure,
        // a self-intersecting surface, is found that way first.
        tetrahedralize(dsw, &in, &diag);
        if (diag.numberoftrifaces > 0 && diag.trifacelist && diag.pointlist) {
            const double *p = diag.pointlist + 3 * diag.trifacelist[0];
            st =
                qdc_fail(err, QDC_ETETGEN,
                         "the surface intersects itself: %d triangles involved, one near "
                         "(%g, %g, %g)",
                         diag.numberoftrifaces, p[0], p[1], p[2]);
        } else {
            tetrahedralize(sw, &in, &res);
            st = to_mesh(res, s->tri_ref != NULL, out, err);
        }
    } catch (int code) {
        st = qdc_fail(err, code == 1 ? QDC_ENOMEM : QDC_ETETGEN,
                      "TetGen (-%s): %s (code %d)", sw, tetgen_reason(code), code);
    } catch (const std::bad_alloc &) {
        st = qdc_fail(err, QDC_ENOMEM, "out of memory in TetGen");
    } catch (...) {
        st = qdc_fail(err, QDC_ETETGEN, "TetGen failed with an unexpected exception");
    }
    return st;
}

extern "C" qdc_status tetra_from_surface(const double *xyz, int32_t nv,
                                         const int32_t *tris, int32_t ntri,
                                         const tetra_options *o, mesh_t **out,
                                         qdc_error *err)
{
    surface_t s;

    if (!xyz || !tris || nv < 0 || ntri < 0 || !out)
        return qdc_fail(err, QDC_EINVAL, "tetra_from_surface: bad argument");
    std::memset(&s, 0, sizeof s);
    s.nv = nv;
    s.ntri = ntri;
    s.xyz = const_cast<double *>(xyz);
    s.tris = const_cast<int32_t *>(tris);
    return tetra_from_surface_t(&s, o, out, err);
}

extern "C" qdc_status tetra_from_buffer(const char *buf, size_t len, surface_format fmt,
                                        const tetra_options *o, mesh_t **out,
                                        qdc_error *err)
{
    surface_t *s = NULL;
    qdc_status st = surface_read(buf, len, fmt, &s, err);

    if (st == QDC_OK)
        st = tetra_from_surface_t(s, o, out, err);
    surface_free(s);
    return st;
}
