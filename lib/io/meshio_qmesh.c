/* meshio_qmesh.c - qdc's own binary mesh (proto/mesh-binary.md). */
#include "io/format.h"

#include <string.h>

/* ------------------------------------------------------------------------ */
/* QMESH binary                                                              */

#define QMESH_MAGIC "QDCMESH"
#define QMESH_HEADER 32
#define QMESH_VERSION 1u
#define QMESH_REGION 1u
#define QMESH_FIXED 2u
#define QMESH_MID 4u /* second-order tets: i32[nt][6] mid-edge nodes after the rest */

static qdc_status read_qmesh(const char *buf, size_t len, const meshio_options *o,
                             srcrec *rec, mesh_t **out, qdc_error *err)
{
    const unsigned char *b = (const unsigned char *)buf;
    uint32_t version, flags;
    uint64_t nv, nt, need;
    size_t off;
    mesh_t *m;
    (void)o;
    (void)rec;

    if (memcmp(buf, QMESH_MAGIC, len < 8 ? len : 8) != 0)
        return fail_bin(err, QDC_EPARSE, 0, "QMESH: bad magic (expected \"QDCMESH\\0\")");
    if (len < QMESH_HEADER)
        return fail_bin(err, QDC_EPARSE, (int64_t)len,
                        "QMESH: truncated header (%zu of %d bytes)", len, QMESH_HEADER);
    version = get_le32(b + 8);
    flags = get_le32(b + 12);
    nv = get_le64(b + 16);
    nt = get_le64(b + 24);
    if (version != QMESH_VERSION)
        return fail_bin(err, QDC_EFORMAT, 8,
                        "QMESH: unsupported version %u (expected %u)", version,
                        QMESH_VERSION);
    if (flags & ~(QMESH_REGION | QMESH_FIXED | QMESH_MID))
        return fail_bin(err, QDC_EFORMAT, 12, "QMESH: unknown flags 0x%x", flags);
    /* Both counts below 2^40 keep the size arithmetic far from overflow; larger
     * ones cannot match any buffer we could be holding anyway. */
    need = UINT64_MAX;
    if (nv < (UINT64_C(1) << 40) && nt < (UINT64_C(1) << 40))
        need = QMESH_HEADER + 24 * nv + 16 * nt + (flags & QMESH_REGION ? 4 * nt : 0) +
               (flags & QMESH_FIXED ? nv : 0) + (flags & QMESH_MID ? 24 * nt : 0);
    if (need != len)
        return fail_bin(
            err, QDC_EPARSE, (int64_t)(need < len ? need : len),
            "QMESH: size mismatch: nv=%llu nt=%llu flags=%u need %s%llu bytes, "
            "got %zu",
            (unsigned long long)nv, (unsigned long long)nt, flags,
            need == UINT64_MAX ? "more than " : "", (unsigned long long)need, len);
    if (nv > MESH_MAX_VERTICES)
        return fail_bin(err, QDC_ETOOBIG, 16, "QMESH: %llu vertices exceed the limit %d",
                        (unsigned long long)nv, MESH_MAX_VERTICES);
    if (nt > MESH_MAX_TETS)
        return fail_bin(err, QDC_ETOOBIG, 24, "QMESH: %llu tets exceed the limit %d",
                        (unsigned long long)nt, MESH_MAX_TETS);
    m = mesh_new((int32_t)nv, (int32_t)nt,
                 (flags & QMESH_REGION ? MESH_WITH_REGION : 0) |
                     (flags & QMESH_FIXED ? MESH_WITH_FIXED : 0));
    if (!m)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for a mesh of %llu vertices",
                        (unsigned long long)nv);
    off = QMESH_HEADER;
    for (size_t i = 0; i < 3 * nv; i++, off += 8) {
        uint64_t u = get_le64(b + off);
        memcpy(&m->xyz[i], &u, 8);
        if (!isfinite(m->xyz[i])) {
            fail_bin(err, QDC_EPARSE, (int64_t)off,
                     "QMESH: vertex %zu: coordinate is not finite (NaN/Inf)", i / 3);
            set_index(err, "vertex", (int64_t)(i / 3));
            goto fail;
        }
    }
    for (size_t i = 0; i < 4 * nt; i++, off += 4) {
        int32_t v = (int32_t)get_le32(b + off);
        if (v < 0 || (uint64_t)v >= nv) {
            fail_bin(err, QDC_EPARSE, (int64_t)off,
                     "QMESH: tet %zu: vertex index %d out of range [0, %lld]", i / 4, v,
                     (long long)nv - 1);
            set_index(err, "tet", (int64_t)(i / 4));
            goto fail;
        }
        m->tets[i] = v;
    }
    for (size_t i = 0; m->region && i < nt; i++, off += 4)
        m->region[i] = (int32_t)get_le32(b + off);
    if (m->fixed)
        memcpy(m->fixed, b + off, nv);
    off += m->fixed ? nv : 0;
    if ((flags & QMESH_MID) && mesh_set_mid(m) != QDC_OK) {
        qdc_fail(err, QDC_ENOMEM, "out of memory for the mid-edge nodes");
        goto fail;
    }
    for (size_t i = 0; m->mid && i < 6 * nt; i++, off += 4) {
        int32_t v = (int32_t)get_le32(b + off);
        if (v < 0 || (uint64_t)v >= nv) {
            fail_bin(err, QDC_EPARSE, (int64_t)off,
                     "QMESH: tet %zu: mid-edge node %d out of range [0, %lld]", i / 6, v,
                     (long long)nv - 1);
            set_index(err, "tet", (int64_t)(i / 6));
            goto fail;
        }
        m->mid[i] = v;
    }
    *out = m;
    return QDC_OK;
fail:
    mesh_free(m);
    return err ? err->status : QDC_EPARSE;
}

static qdc_status write_qmesh(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                              qdc_error *err)
{
    (void)fmt;
    (void)part;
    (void)err;
    unsigned char h[QMESH_HEADER], b[8];
    uint32_t flags = (m->region ? QMESH_REGION : 0) | (m->fixed ? QMESH_FIXED : 0) |
                     (m->mid ? QMESH_MID : 0);

    memcpy(h, QMESH_MAGIC, 8);
    put_le32(h + 8, QMESH_VERSION);
    put_le32(h + 12, flags);
    put_le64(h + 16, (uint64_t)m->nv);
    put_le64(h + 24, (uint64_t)m->nt);
    wb_put(w, h, sizeof h);
    for (size_t i = 0; i < 3 * (size_t)m->nv; i++) {
        uint64_t u;
        memcpy(&u, &m->xyz[i], 8);
        put_le64(b, u);
        wb_put(w, b, 8);
    }
    for (size_t i = 0; i < 4 * (size_t)m->nt; i++) {
        put_le32(b, (uint32_t)m->tets[i]);
        wb_put(w, b, 4);
    }
    for (size_t i = 0; m->region && i < (size_t)m->nt; i++) {
        put_le32(b, (uint32_t)m->region[i]);
        wb_put(w, b, 4);
    }
    if (m->fixed)
        wb_put(w, m->fixed, (size_t)m->nv);
    for (size_t i = 0; m->mid && i < 6 * (size_t)m->nt; i++) {
        put_le32(b, (uint32_t)m->mid[i]);
        wb_put(w, b, 4);
    }
    return QDC_OK;
}

static meshio_format sniff_qmesh(const char *buf, size_t len, size_t i)
{
    (void)i;
    return len >= 7 && memcmp(buf, QMESH_MAGIC, 7) == 0 ? MESHIO_QMESH : MESHIO_AUTO;
}

const meshio_fmt fmt_qmesh = {
    .name = "qmesh",
    .aliases = "binary application/vnd.qdc.mesh",
    .about = "qdc binary mesh (proto/mesh-binary.md)",
    .ext = "qmesh",
    .input = "input.qmesh",
    .media = "application/vnd.qdc.mesh",
    .magic = 1,
    .sniff = sniff_qmesh,
    .read = read_qmesh,
    .write = write_qmesh,
    .p2 = 1,
};
