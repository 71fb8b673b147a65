/* meshio_med.c - MED meshes (Salome, Code_Aster: .med, an HDF5 file) as the
 * qdc-h5 program hands them over: read, and written back only spliced.
 *
 * libqdc never calls HDF5: the qdc command runs `qdc-h5 med-read FILE`
 * (clients/qdc-h5) and gives this reader what it prints, and writes a result
 * by giving `qdc-h5 med-write IN OUT` the spliced frames (the same bytes with
 * new coordinates), which puts them into a copy of IN. The framed form:
 *
 *   "QDCH5v1\n", then frames to the end, each: a name of 16 bytes (NUL-padded
 *   ASCII), a type byte ('f' float64, 'i' int64, 'b' bytes), 7 zero bytes,
 *   the value count (uint64), the values (bytes: zero-padded to a multiple
 *   of 8); all little-endian, 8-byte aligned. (h5_frames reads them, here
 *   and for XDMF with HDF5 heavy data, meshio_xdmf.c.)
 *
 * Frames: "coords" (x y z a node, 3 per node), "te4" or "t10" (the 4 or 10
 * nodes of each tet, 1-based, MED's order: the corners, then the mid-edge
 * nodes of edges 12, 23, 31, 14, 24, 34, which is mesh_p2_edges'), and
 * "te4_fam"/"t10_fam" (each tet's family number: its region), "tr3" and
 * "tr6" (the 3 or 6 nodes of each triangle: the boundary triangles, their
 * corners kept) with "tr3_fam"/"tr6_fam" (their refs), and "noe_fam" (each
 * node's family: its ref). Other frames are skipped. A plain HDF5 file is refused with a
 * message saying how MED is read (QDC_EFORMAT). */
#include "io/format.h"

#include <string.h>

const char h5_magic[8] = {'Q', 'D', 'C', 'H', '5', 'v', '1', '\n'};
static const unsigned char hdf5_magic[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};

qdc_status h5_frames(const char *buf, size_t len, const char *what,
                     const char *const *names, const char *types, int count, h5_frame *fr,
                     qdc_error *err)
{
    size_t pos = sizeof h5_magic;

    memset(fr, 0, (size_t)count * sizeof *fr);
    if (len < sizeof h5_magic || memcmp(buf, h5_magic, sizeof h5_magic) != 0)
        return fail_bin(err, QDC_EPARSE, 0, "%s: not what qdc-h5 writes", what);
    while (pos < len) {
        const unsigned char *h = (const unsigned char *)buf + pos;
        uint64_t n, size;
        int k;
        if (len - pos < 32)
            return fail_bin(err, QDC_EPARSE, (int64_t)pos, "%s: a frame header cut short",
                            what);
        n = get_le64(h + 24);
        if (h[16] != 'f' && h[16] != 'i' && h[16] != 'b')
            return fail_bin(err, QDC_EPARSE, (int64_t)pos + 16, "%s: frame type %d", what,
                            h[16]);
        size = h[16] == 'b' ? (n > UINT64_MAX - 7 ? UINT64_MAX : (n + 7) / 8) : n;
        if (size > (len - pos - 32) / 8)
            return fail_bin(err, QDC_EPARSE, (int64_t)pos,
                            "%s: a frame of %llu values runs past the end", what,
                            (unsigned long long)n);
        for (k = 0; k < count; k++)
            if (strncmp((const char *)h, names[k], 16) == 0)
                break;
        if (k < count) {
            if (fr[k].type || (h[16] != types[k] && (types[k] != '?' || h[16] == 'b')))
                return fail_bin(err, QDC_EPARSE, (int64_t)pos,
                                "%s: frame %s twice or of the wrong type", what,
                                names[k]);
            fr[k].at = pos + 32;
            fr[k].n = n;
            fr[k].type = h[16];
        }
        pos += 32 + (size_t)size * 8;
    }
    return QDC_OK;
}

enum {
    F_COORDS,
    F_TE4,
    F_T10,
    F_TE4_FAM,
    F_T10_FAM,
    F_TR3,
    F_TR6,
    F_TR3_FAM,
    F_TR6_FAM,
    F_NOE_FAM,
    F_COUNT
};

int meshio_is_hdf5(const void *buf, size_t len)
{
    return len >= 8 && memcmp(buf, hdf5_magic, 8) == 0;
}

static qdc_status med_frames(const char *buf, size_t len, h5_frame *fr, qdc_error *err)
{
    static const char *const names[F_COUNT] = {"coords",  "te4",    "t10", "te4_fam",
                                               "t10_fam", "tr3",    "tr6", "tr3_fam",
                                               "tr6_fam", "noe_fam"};
    qdc_status st;

    if (meshio_is_hdf5(buf, len))
        return fail_bin(err, QDC_EFORMAT, 0,
                        "MED: an HDF5 file, read through qdc-h5 (the qdc command and "
                        "qdcd run it)");
    st = h5_frames(buf, len, "MED", names, "fiiiiiiiii", F_COUNT, fr, err);
    if (st != QDC_OK)
        return st;
    if (!fr[F_COORDS].type)
        return fail_bin(err, QDC_EPARSE, (int64_t)len, "MED: no coordinates");
    return QDC_OK;
}

/* Frame fr's n int64 values at b, each into out[k * stride] (stride 1: a
 * family a node or element) as an int32 (minus one: node numbers, checked
 * against [1, nv] when nv > 0): 0, or QDC_EPARSE naming what (the element
 * kind) and the element (values per element: per). */
static qdc_status med_ints(const unsigned char *b, const h5_frame *fr, int64_t nv,
                           const char *what, int per, int32_t *out, int keep,
                           qdc_error *err)
{
    for (uint64_t i = 0, o = 0; i < fr->n; i++) {
        uint64_t at = fr->at + 8 * i;
        int64_t v = (int64_t)get_le64(b + at);
        if (nv > 0 && (v < 1 || v > nv))
            return fail_bin(err, QDC_EPARSE, (int64_t)at,
                            "MED: %s %llu: node %lld out of range [1, %lld]", what,
                            (unsigned long long)(i / (uint64_t)per + 1), (long long)v,
                            (long long)nv);
        if (nv <= 0 && (v < INT32_MIN || v > INT32_MAX))
            return fail_bin(err, QDC_EPARSE, (int64_t)at,
                            "MED: %s %llu: family %lld is not an int32", what,
                            (unsigned long long)(i + 1), (long long)v);
        if ((int)(i % (uint64_t)per) < keep)
            out[o++] = (int32_t)(nv > 0 ? v - 1 : v);
    }
    return QDC_OK;
}

/* The boundary triangles (TR3 and TR6, corners only) and their families, and
 * the node families, of fr into pm (nv nodes). */
static qdc_status med_extras(const unsigned char *b, const h5_frame *fr, parsed *pm,
                             qdc_error *err)
{
    static const int tri[2] = {F_TR3, F_TR6}, nodes[2] = {3, 6};
    int64_t ntri = 0, at = 0;
    qdc_status st = QDC_OK;

    if (fr[F_NOE_FAM].type) {
        if (fr[F_NOE_FAM].n != (uint64_t)pm->nv)
            return fail_bin(err, QDC_EPARSE, (int64_t)fr[F_NOE_FAM].at,
                            "MED: %llu node families for %lld nodes",
                            (unsigned long long)fr[F_NOE_FAM].n, (long long)pm->nv);
        pm->vref = qdc_mallocn((size_t)pm->nv + 1, sizeof(int32_t));
        if (!pm->vref)
            return qdc_fail(err, QDC_ENOMEM, "out of memory");
        st = med_ints(b, &fr[F_NOE_FAM], 0, "node", 1, pm->vref, 1, err);
    }
    for (int k = 0; st == QDC_OK && k < 2; k++) {
        const h5_frame *fam = &fr[tri[k] + 2];
        if (fr[tri[k]].n % (uint64_t)nodes[k])
            return fail_bin(err, QDC_EPARSE, (int64_t)fr[tri[k]].at,
                            "MED: %llu triangle nodes, not %d a triangle",
                            (unsigned long long)fr[tri[k]].n, nodes[k]);
        if (fam->type && fam->n != fr[tri[k]].n / (uint64_t)nodes[k])
            return fail_bin(err, QDC_EPARSE, (int64_t)fam->at,
                            "MED: %llu families for %llu triangles",
                            (unsigned long long)fam->n,
                            (unsigned long long)(fr[tri[k]].n / (uint64_t)nodes[k]));
        ntri += (int64_t)(fr[tri[k]].n / (uint64_t)nodes[k]);
    }
    if (st != QDC_OK || ntri == 0)
        return st;
    if (ntri > MESH_MAX_TETS)
        return fail_bin(err, QDC_ETOOBIG, 0, "MED: %lld triangles", (long long)ntri);
    pm->ntri = ntri;
    pm->tris = qdc_mallocn((size_t)ntri * 3 + 1, sizeof(int32_t));
    pm->tri_ref = qdc_calloc((size_t)ntri + 1, sizeof(int32_t));
    if (!pm->tris || !pm->tri_ref)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    for (int k = 0; st == QDC_OK && k < 2; k++) {
        int64_t n = (int64_t)(fr[tri[k]].n / (uint64_t)nodes[k]);
        st = med_ints(b, &fr[tri[k]], pm->nv, "triangle", nodes[k], pm->tris + 3 * at, 3,
                      err);
        if (st == QDC_OK && fr[tri[k] + 2].type)
            st = med_ints(b, &fr[tri[k] + 2], 0, "triangle", 1, pm->tri_ref + at, 1, err);
        at += n;
    }
    return st;
}

static qdc_status read_med(const char *buf, size_t len, const meshio_options *o,
                           srcrec *rec, mesh_t **out, qdc_error *err)
{
    h5_frame fr[F_COUNT];
    const unsigned char *b = (const unsigned char *)buf;
    int nodes, conn, fam;
    int64_t nv, nt;
    parsed pm;
    qdc_status st;

    (void)o;
    st = med_frames(buf, len, fr, err);
    if (st != QDC_OK)
        return st;
    if (fr[F_TE4].n && fr[F_T10].n)
        return fail_bin(err, QDC_EFORMAT, (int64_t)fr[F_T10].at,
                        "MED: linear (TE4) and second-order (T10) tetrahedra in one "
                        "mesh are not supported");
    conn = fr[F_T10].n ? F_T10 : F_TE4;
    fam = conn == F_T10 ? F_T10_FAM : F_TE4_FAM;
    nodes = conn == F_T10 ? 10 : 4;
    if (!fr[conn].n)
        return fail_bin(err, QDC_EFORMAT, (int64_t)len,
                        "MED: no tetrahedra (TE4 or T10) in the first mesh");
    if (fr[F_COORDS].n % 3 || fr[conn].n % (uint64_t)nodes)
        return fail_bin(err, QDC_EPARSE, (int64_t)fr[F_COORDS].at,
                        "MED: %llu coordinates, %llu tet nodes",
                        (unsigned long long)fr[F_COORDS].n,
                        (unsigned long long)fr[conn].n);
    nv = (int64_t)(fr[F_COORDS].n / 3);
    nt = (int64_t)(fr[conn].n / (uint64_t)nodes);
    if (nv > MESH_MAX_VERTICES || nt > MESH_MAX_TETS)
        return fail_bin(err, QDC_ETOOBIG, 0, "MED: %lld nodes, %lld tetrahedra",
                        (long long)nv, (long long)nt);
    if (fr[fam].type && fr[fam].n != (uint64_t)nt)
        return fail_bin(err, QDC_EPARSE, (int64_t)fr[fam].at,
                        "MED: %llu families for %lld tetrahedra",
                        (unsigned long long)fr[fam].n, (long long)nt);
    parsed_init(&pm);
    pm.nv = nv;
    pm.nt = nt;
    pm.xyz = qdc_mallocn((size_t)nv * 3 + 1, sizeof(double));
    pm.tets = qdc_mallocn((size_t)nt * 4 + 1, sizeof(int32_t));
    pm.mid = nodes == 10 ? qdc_mallocn((size_t)nt * 6 + 1, sizeof(int32_t)) : NULL;
    pm.region = fr[fam].type ? qdc_mallocn((size_t)nt + 1, sizeof(int32_t)) : NULL;
    if (!pm.xyz || !pm.tets || (nodes == 10 && !pm.mid) || (fr[fam].type && !pm.region)) {
        parsed_free(&pm);
        return qdc_fail(err, QDC_ENOMEM, "out of memory for a mesh of %lld nodes",
                        (long long)nv);
    }
    for (int64_t i = 0; i < 3 * nv; i++) {
        uint64_t u = get_le64(b + fr[F_COORDS].at + 8 * (uint64_t)i);
        memcpy(&pm.xyz[i], &u, 8);
        if (!isfinite(pm.xyz[i])) {
            parsed_free(&pm);
            fail_bin(err, QDC_EPARSE, (int64_t)(fr[F_COORDS].at + 8 * (uint64_t)i),
                     "MED: node %lld has a coordinate that is not finite (NaN/Inf)",
                     (long long)(i / 3 + 1));
            set_index(err, "vertex", i / 3);
            return QDC_EPARSE;
        }
    }
    for (int64_t e = 0; e < nt; e++)
        for (int k = 0; k < nodes; k++) {
            uint64_t at = fr[conn].at + 8 * ((uint64_t)e * (uint64_t)nodes + (uint64_t)k);
            int64_t v = (int64_t)get_le64(b + at);
            if (v < 1 || v > nv) {
                parsed_free(&pm);
                fail_bin(err, QDC_EPARSE, (int64_t)at,
                         "MED: tetrahedron %lld: node %lld out of range [1, %lld]",
                         (long long)(e + 1), (long long)v, (long long)nv);
                set_index(err, "tet", e);
                return QDC_EPARSE;
            }
            if (k < 4)
                pm.tets[4 * e + k] = (int32_t)(v - 1);
            else
                pm.mid[6 * e + k - 4] = (int32_t)(v - 1);
        }
    for (int64_t e = 0; pm.region && e < nt; e++) {
        int64_t f = (int64_t)get_le64(b + fr[fam].at + 8 * (uint64_t)e);
        if (f < INT32_MIN || f > INT32_MAX) {
            parsed_free(&pm);
            return fail_bin(err, QDC_EPARSE, (int64_t)(fr[fam].at + 8 * (uint64_t)e),
                            "MED: tetrahedron %lld: family %lld is not an int32",
                            (long long)(e + 1), (long long)f);
        }
        pm.region[e] = (int32_t)f;
    }
    st = med_extras(b, fr, &pm, err);
    if (st != QDC_OK) {
        parsed_free(&pm);
        return st;
    }
    if (rec) {
        rec->fmt = MESHIO_MED;
        rec->kind = SRC_BIN;
        rec->width = 8;
        rec->big = 0;
        st = srcrec_alloc(rec, nv, err);
        if (st != QDC_OK) {
            parsed_free(&pm);
            return st;
        }
        for (int64_t v = 0; v < nv; v++)
            rec->off[v] = fr[F_COORDS].at + 24 * (uint64_t)v;
    }
    return parsed_mesh_move(&pm, out, err);
}

/* What qdc-h5 writes, or an HDF5 file (refused by the reader with how). */
static meshio_format sniff_med(const char *buf, size_t len, size_t i)
{
    (void)i;
    if ((len >= 8 && memcmp(buf, h5_magic, 8) == 0) || meshio_is_hdf5(buf, len))
        return MESHIO_MED;
    return MESHIO_AUTO;
}

const meshio_fmt fmt_med = {
    .name = "med",
    .about = "MED (Salome, Code_Aster; HDF5 through qdc-h5): TE4/T10 tetrahedra, "
             "families as regions, TR3/TR6 boundary triangles, node families as refs "
             "(written only spliced)",
    .ext = "med",
    .magic = 1,
    .sniff = sniff_med,
    .read = read_med,
    .input = "input.med", /* read by qdcd's qdc-h5 child (server/h5job.h) */
    .splices = 1,
};
