/* meshio_med.c - MED meshes (Salome, Code_Aster: .med, an HDF5 file) as the
 * qdc-h5 program hands them over: read, written back spliced, and written
 * whole for a mesh that cannot be (its tets changed, or it was read from
 * another format).
 *
 * libqdc never calls HDF5: the qdc command runs `qdc-h5 med-read FILE`
 * (clients/qdc-h5) and gives this reader what it prints. A result is written
 * by giving `qdc-h5 med-write IN OUT` the spliced frames (the same bytes with
 * new coordinates), which puts them into a copy of IN, or, when the mesh
 * does not splice, by giving `qdc-h5 med-new OUT` what write_med frames (the
 * same frames, for the whole mesh), from which it makes a new MED file. The
 * framed form:
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
 * corners kept) with "tr3_fam"/"tr6_fam" (their refs), "noe_fam" (each
 * node's family: its ref), and "families" (bytes: a line "NUMBER GROUP" for
 * each group of each family of /FAS, the group name's trailing blanks
 * dropped). Other frames are skipped. A plain HDF5 file is refused with a
 * message saying how MED is read (QDC_EFORMAT).
 *
 * Tags and families. MED numbers element families below zero and node
 * families above (0: FAMILLE_ZERO, no group), so a region tag cannot be a
 * tet's family as it is. write_med numbers the families -1, -2... (the
 * regions in ascending order, then the triangle refs) and 1, 2... (the
 * vertex refs), each with one group that names its tag as the Abaqus writer
 * names its sets: REGION_<n>, SURFACE_<n>, NODE_<n>, "M" before a negative
 * n's digits (REGION_M3); tag 0 is family 0. The reader maps the families
 * back through those names when every nonzero family of the tets (of the
 * triangles, of the nodes) has exactly one group of its kind's name; other
 * groups of a family are ignored (Salome adds a family for each mix of
 * groups a user makes). Otherwise the family numbers are the tags, as
 * before these names existed (meshio's material_0, Salome's own groups). */
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
    F_FAMILIES,
    F_COUNT
};

int meshio_is_hdf5(const void *buf, size_t len)
{
    return len >= 8 && memcmp(buf, hdf5_magic, 8) == 0;
}

static qdc_status med_frames(const char *buf, size_t len, h5_frame *fr, qdc_error *err)
{
    static const char *const names[F_COUNT] = {"coords",  "te4",     "t10",     "te4_fam",
                                               "t10_fam", "tr3",     "tr6",     "tr3_fam",
                                               "tr6_fam", "noe_fam", "families"};
    qdc_status st;

    if (meshio_is_hdf5(buf, len))
        return fail_bin(err, QDC_EFORMAT, 0,
                        "MED: an HDF5 file, read through qdc-h5 (the qdc command and "
                        "qdcd run it)");
    st = h5_frames(buf, len, "MED", names, "fiiiiiiiiib", F_COUNT, fr, err);
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

/* The names of qdc's groups (write_med), by kind: the tets', the
 * triangles', the nodes'. */
static const char *const kind_prefix[3] = {"REGION_", "SURFACE_", "NODE_"};

/* A family whose group names a tag of a kind; dup: it has another group of
 * that kind with another tag. */
typedef struct {
    int32_t fam, tag;
    int kind, dup;
} famtag;

static int famtag_cmp(const void *x, const void *y)
{
    const famtag *a = x, *b = y;

    if (a->kind != b->kind)
        return a->kind < b->kind ? -1 : 1;
    return (a->fam > b->fam) - (a->fam < b->fam);
}

/* The tag group name [v, ve) names (meshio_name_number), spelled as
 * write_med spells it: in capitals, as MED's names are compared (meshio
 * calls its groups "surface_3": not ours, read as before). */
static int med_group_tag(const char *v, const char *ve, const char *prefix, int32_t *tag)
{
    size_t n = strlen(prefix);

    return (size_t)(ve - v) > n && memcmp(v, prefix, n) == 0 && v[n] != 'm' &&
           meshio_name_number(v, ve, prefix, tag);
}

/* The groups of the "families" frame fr that name a tag (kind_prefix),
 * sorted by kind and family, into *out (qdc_free), their count in *n.
 * Lines that are no "NUMBER NAME" of an int32 family are skipped. */
static qdc_status med_famtags(const unsigned char *b, const h5_frame *fr, famtag **out,
                              size_t *n, qdc_error *err)
{
    const char *p = (const char *)b + fr->at, *end = p + fr->n;
    size_t lines = 1, k = 0;
    famtag *t;

    *out = NULL;
    *n = 0;
    for (const char *q = p; q < end; q++)
        lines += *q == '\n';
    t = qdc_mallocn(lines, sizeof *t);
    if (!t)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %llu MED family groups",
                        (unsigned long long)lines);
    while (p < end) {
        const char *eol = memchr(p, '\n', (size_t)(end - p)), *q = p;
        int64_t num = 0;
        int neg = 0, digits = 0;
        if (!eol)
            eol = end;
        if (q < eol && *q == '-') {
            neg = 1;
            q++;
        }
        for (; q < eol && *q >= '0' && *q <= '9' && digits <= 10; q++, digits++)
            num = 10 * num + (*q - '0');
        num = neg ? -num : num;
        if (digits && digits <= 10 && q < eol && *q == ' ' && num != 0 &&
            num >= INT32_MIN && num <= INT32_MAX)
            for (int kd = 0; kd < 3; kd++)
                if (med_group_tag(q + 1, eol, kind_prefix[kd], &t[k].tag)) {
                    t[k].fam = (int32_t)num;
                    t[k].kind = kd;
                    t[k].dup = 0;
                    k++;
                    break;
                }
        p = eol < end ? eol + 1 : end;
    }
    qsort(t, k, sizeof *t, famtag_cmp);
    for (size_t i = 1; i < k; i++)
        if (famtag_cmp(&t[i - 1], &t[i]) == 0 && t[i - 1].tag != t[i].tag)
            t[i - 1].dup = t[i].dup = 1;
    *out = t;
    *n = k;
    return QDC_OK;
}

/* v[0..n) (families of a kind) replaced by their tags when each nonzero one
 * has one group of that kind among t[0..nt); else left as they are. */
static void med_map(int32_t *v, int64_t n, const famtag *t, size_t nt, int kind)
{
    for (int pass = 0; v && nt && pass < 2; pass++)
        for (int64_t i = 0; i < n; i++) {
            famtag key = {.fam = v[i], .kind = kind};
            const famtag *f;
            if (v[i] == 0)
                continue;
            f = bsearch(&key, t, nt, sizeof *t, famtag_cmp);
            if (!f || f->dup)
                return; /* pass 0: nothing changed */
            if (pass)
                v[i] = f->tag;
        }
}

/* pm's regions, triangle refs and vertex refs (read as family numbers)
 * mapped to the tags their groups name (fr: the "families" frame). */
static qdc_status med_tags(const unsigned char *b, const h5_frame *fr, parsed *pm,
                           qdc_error *err)
{
    famtag *t;
    size_t n;
    qdc_status st;

    if (!fr->type)
        return QDC_OK;
    st = med_famtags(b, fr, &t, &n, err);
    if (st != QDC_OK)
        return st;
    med_map(pm->region, pm->nt, t, n, 0);
    med_map(pm->tri_ref, pm->ntri, t, n, 1);
    med_map(pm->vref, pm->nv, t, n, 2);
    qdc_free(t);
    return QDC_OK;
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
    /* an empty frame (qdc's writer's of an empty mesh): no tets */
    conn = fr[F_T10].n || (fr[F_T10].type && !fr[F_TE4].type) ? F_T10 : F_TE4;
    fam = conn == F_T10 ? F_T10_FAM : F_TE4_FAM;
    nodes = conn == F_T10 ? 10 : 4;
    if (!fr[conn].type)
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
    if (st == QDC_OK)
        st = med_tags(b, &fr[F_FAMILIES], &pm, err);
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

/* ------------------------------------------------------------------------ */
/* Writing a whole mesh (qdc-h5 med-new makes the MED file)                  */

static void put_head(wbuf *w, const char *name, char type, uint64_t n)
{
    unsigned char h[32] = {0};

    memcpy(h, name, strlen(name));
    h[16] = (unsigned char)type;
    put_le64(h + 24, n);
    wb_put(w, h, sizeof h);
}

static void put_word(wbuf *w, uint64_t u)
{
    unsigned char b[8];

    put_le64(b, u);
    wb_put(w, b, 8);
}

static int cmp_i32(const void *x, const void *y)
{
    int32_t a = *(const int32_t *)x, b = *(const int32_t *)y;

    return (a > b) - (a < b);
}

/* The distinct nonzero values of v[0..n) (v NULL: none), ascending, into
 * *out (qdc_free), their count into *k. */
static qdc_status med_distinct(const int32_t *v, int64_t n, int32_t **out, int64_t *k,
                               qdc_error *err)
{
    int32_t *s;
    int64_t j = 0;

    *out = NULL;
    *k = 0;
    if (!v)
        return QDC_OK;
    s = qdc_mallocn((size_t)n + 1, sizeof *s);
    if (!s)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the MED families");
    for (int64_t i = 0; i < n; i++)
        if (v[i] != 0)
            s[j++] = v[i];
    qsort(s, (size_t)j, sizeof *s, cmp_i32);
    *k = 0;
    for (int64_t i = 0; i < j; i++)
        if (i == 0 || s[i] != s[i - 1])
            s[(*k)++] = s[i];
    *out = s;
    return QDC_OK;
}

/* Tag x's family among the k distinct tags s (med_distinct): its position
 * from 1; 0 for tag 0. */
static int64_t med_rank(const int32_t *s, int64_t k, int32_t x)
{
    const int32_t *f = x ? bsearch(&x, s, (size_t)k, sizeof *s, cmp_i32) : NULL;

    return f ? (int64_t)(f - s) + 1 : 0;
}

/* The "families" frame's text for the k distinct tags s of kind (prefix):
 * a line "FAMILY PREFIX<tag>" each, the family sign * (base + position),
 * appended at *len to t. */
static void med_family_lines(char *t, size_t *len, const int32_t *s, int64_t k,
                             int64_t base, int sign, const char *prefix)
{
    for (int64_t i = 0; i < k; i++)
        *len += (size_t)sprintf(
            t + *len, "%lld %s%s%lld\n", (long long)(sign * (base + i + 1)), prefix,
            s[i] < 0 ? "M" : "", s[i] < 0 ? -(long long)s[i] : (long long)s[i]);
}

/* The whole mesh framed for qdc-h5 med-new: the coordinates, the tets (T10
 * with the mid-edge nodes of a second-order mesh), the triangles (TR6 when
 * every one is a face of a second-order tet, with the tets' mid-edge nodes;
 * else TR3), and the families (see the top: element families -1... for the
 * regions then the refs, node families 1... for the vertex refs, each with
 * the group that names its tag); a tag array the mesh lacks is no frame
 * (qdc-h5 writes family 0 for it). */
static qdc_status write_med(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                            qdc_error *err)
{
    int32_t *reg = NULL, *ref = NULL, *vr = NULL, *mid = NULL;
    int64_t nreg = 0, nref = 0, nvr = 0;
    int p2 = m->mid != NULL, six = 0, per = p2 ? 10 : 4;
    char *text = NULL;
    size_t tlen = 0;
    qdc_status st;

    (void)fmt;
    (void)part;
    st = med_distinct(m->region, m->nt, &reg, &nreg, err);
    if (st == QDC_OK)
        st = med_distinct(m->tri_ref, m->ntri, &ref, &nref, err);
    if (st == QDC_OK)
        st = med_distinct(m->vref, m->nv, &vr, &nvr, err);
    if (st == QDC_OK && p2 && m->ntri > 0) {
        mid = qdc_mallocn(3 * (size_t)m->ntri, sizeof *mid);
        st = mid ? meshio_tri_mids(m, mid, &six, err)
                 : qdc_fail(err, QDC_ENOMEM, "out of memory for the triangles");
    }
    /* a line: a family of 11 characters at most, a space, a prefix of 8,
     * "M", a tag of 10, a line break */
    if (st == QDC_OK && nreg + nref + nvr > 0 &&
        !(text = qdc_mallocn((size_t)(nreg + nref + nvr), 32)))
        st = qdc_fail(err, QDC_ENOMEM, "out of memory for the MED families");
    if (st == QDC_OK) {
        med_family_lines(text, &tlen, reg, nreg, 0, -1, kind_prefix[0]);
        med_family_lines(text, &tlen, ref, nref, nreg, -1, kind_prefix[1]);
        med_family_lines(text, &tlen, vr, nvr, 0, 1, kind_prefix[2]);
        wb_put(w, h5_magic, sizeof h5_magic);
        put_head(w, "coords", 'f', 3 * (uint64_t)m->nv);
        for (int64_t i = 0; i < 3 * (int64_t)m->nv; i++) {
            uint64_t u;
            memcpy(&u, &m->xyz[i], 8);
            put_word(w, u);
        }
        put_head(w, p2 ? "t10" : "te4", 'i', (uint64_t)per * (uint64_t)m->nt);
        for (int64_t t = 0; t < m->nt; t++)
            for (int k = 0; k < per; k++) /* mid: mesh_p2_edges' order, MED's */
                put_word(w,
                         (uint64_t)(k < 4 ? m->tets[4 * t + k] : m->mid[6 * t + k - 4]) +
                             1);
        if (m->region) {
            put_head(w, p2 ? "t10_fam" : "te4_fam", 'i', (uint64_t)m->nt);
            for (int64_t t = 0; t < m->nt; t++)
                put_word(w, (uint64_t)-med_rank(reg, nreg, m->region[t]));
        }
    }
    if (st == QDC_OK && m->ntri > 0) {
        put_head(w, six ? "tr6" : "tr3", 'i',
                 (uint64_t)(six ? 6 : 3) * (uint64_t)m->ntri);
        for (int64_t i = 0; i < m->ntri; i++)
            for (int k = 0; k < (six ? 6 : 3); k++)
                put_word(w,
                         (uint64_t)(k < 3 ? m->tris[3 * i + k] : mid[3 * i + k - 3]) + 1);
        if (m->tri_ref) {
            put_head(w, six ? "tr6_fam" : "tr3_fam", 'i', (uint64_t)m->ntri);
            for (int64_t i = 0; i < m->ntri; i++) {
                int64_t r = med_rank(ref, nref, m->tri_ref[i]);
                put_word(w, (uint64_t)(r ? -(nreg + r) : 0));
            }
        }
    }
    if (st == QDC_OK && m->vref) {
        put_head(w, "noe_fam", 'i', (uint64_t)m->nv);
        for (int64_t i = 0; i < m->nv; i++)
            put_word(w, (uint64_t)med_rank(vr, nvr, m->vref[i]));
    }
    if (st == QDC_OK && tlen) {
        static const char zero[8] = {0};
        put_head(w, "families", 'b', tlen);
        wb_put(w, text, tlen);
        wb_put(w, zero, (8 - tlen % 8) % 8);
    }
    qdc_free(reg);
    qdc_free(ref);
    qdc_free(vr);
    qdc_free(mid);
    qdc_free(text);
    return st;
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
             "families as regions, TR3/TR6 boundary triangles, node families as refs",
    .ext = "med",
    .magic = 1,
    .sniff = sniff_med,
    .read = read_med,
    .write = write_med,   /* frames for qdc-h5 med-new, not the HDF5 file */
    .input = "input.med", /* read by qdcd's qdc-h5 child (server/h5job.h) */
    .splices = 1,
    .p2 = 1,
};
