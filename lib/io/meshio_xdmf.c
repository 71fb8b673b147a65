/* meshio_xdmf.c - XDMF 2 and 3 with the data inline (Format="XML"): read,
 * written (XDMF 3, inline, as meshio writes it) and written back spliced.
 *
 * The mesh is the first Grid with a Topology or Geometry child (inside a
 * temporal Collection: its first step). Topology Tetrahedron (4 nodes) or
 * Tetrahedron_10 (the VTK order of the mid-edge nodes, as mesh_p2_edges),
 * 0-based; Geometry XYZ, "N 3". Its cell attributes: the first scalar one of
 * integers (Int, UInt, Char, UChar) is the region (one named "region",
 * "gmsh:physical", "cell_tags" or "name_to_read" first), as DOLFIN's
 * MeshFunction and meshio's cell data write them (DOLFIN 2019 gives its
 * MeshFunction in HDF5 no NumberType, as a DG0 Function's float values: such
 * a dataset is asked of qdc-h5 as either class, 'a', and is the region if it
 * holds integers, after any typed one). Grids after the mesh that
 * share its geometry (dolfinx MeshTags: an xi:include of the Geometry) with
 * Tetrahedron topology and an integer cell attribute (in HDF5 one with no
 * NumberType too, as dolfinx 0.5 writes it) give the region of the tets they
 * list; the first such grid with Triangle topology (facet tags)
 * gives the boundary triangles, its values their refs (each must be a face of
 * a tet: on the boundary, or between two tets, kept as it is); in any order. Other
 * attributes, grids and elements are kept by a spliced
 * write, which rewrites only the numbers of the Geometry's DataItem.
 *
 * The XML is read without any entity expansion: a DOCTYPE is taken only with
 * an empty internal subset (DOLFIN writes "<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd"
 * []>"), any other declaration (ENTITY...) and CDATA are refused, and an
 * attribute value that qdc reads must not hold a reference ('&').
 * Heavy data in a binary file or a function of other items is refused
 * (QDC_EFORMAT).
 *
 * Heavy data in HDF5 (Format="HDF", the text "file.h5:/dataset", meshio's and
 * dolfin's default) is read by the qdc-h5 program, outside the library, as
 * MED is (meshio_med.c): meshio_xdmf_h5_refs lists the datasets the mesh
 * needs (its Geometry, Topology and region attribute), qdc-h5 reads them,
 * and the reader is given the framed form of meshio_med.c: a frame "xdmf"
 * (bytes: the XML) and frames "geometry", "topology", "region" (float64,
 * int64, int64; the values in the dataset's order). Such a mesh is written
 * back spliced as that framed form with the geometry frame's values
 * replaced; the qdc command puts them into a copy of the .h5 and writes the
 * XML again with only the .h5 file's name changed (meshio_xdmf_h5_rename).
 * Every HDF reference must name one file, relative and inside the .xdmf's
 * folder (no "..", not absolute). A plain read refuses HDF heavy data in the
 * mesh's Grid with a message saying how it is read. dolfinx MeshTags grids
 * with their data in HDF5 (the first tag grid of tets after the mesh that
 * shares its geometry, and the first of triangles, whichever comes first)
 * are listed too ("tagtopo", "tagvals"; "tritopo", "trivals") and applied
 * as inline tags are. */
#include "core/tet.h"
#include "io/format.h"

#include <string.h>

enum { XD_DEPTH = 64 };

/* How HDF heavy data is taken: refused, listed, or from the frames. */
enum { X_PLAIN, X_COLLECT, X_FRAMED };
/* The datasets the mesh takes from HDF5: its own, the tets and values of a
 * tag grid after it and the triangles and values of a facet tag grid after
 * it (dolfinx MeshTags: cell tags, facet tags). Each pair is read from one
 * grid, or not at all. */
enum { H_GEOM, H_TOPO, H_REG, H_TTOPO, H_TVALS, H_FTOPO, H_FVALS, H_COUNT };
static const char *const h5_names[H_COUNT] = {"geometry", "topology", "region", "tagtopo",
                                              "tagvals",  "tritopo",  "trivals"};

/* What an element is to the reader. */
enum { K_OTHER, K_XDMF, K_GRID, K_TOPO, K_GEOM, K_ATTR, K_DATA, K_INCLUDE };

typedef struct {
    const char *at;     /* its '<' */
    const char *n, *ne; /* its name */
    const char *a, *ae; /* its attributes */
    int empty;          /* <.../> */
    int end;            /* </...> */
} xtag;

typedef struct {
    int64_t dims[4], n; /* the dimensions and their product */
    int ndims;
    int integer; /* NumberType Int, UInt, Char, UChar */
    int typed;   /* NumberType or DataType given (else Float, XDMF's default) */
    int hdf;     /* Format="HDF" (not in X_PLAIN) */
} item;

/* A DataItem the mesh takes from HDF5: its dataset and shape. */
typedef struct {
    int set;
    const char *p, *pe; /* the dataset's path */
    item it;
} pend;

/* A grid after the mesh holding tet or triangle tags (dolfinx MeshTags). */
typedef struct {
    vec tets;   /* int32, 4 a tet (3 a triangle) */
    vec vals;   /* int32 */
    int shares; /* its geometry is an xi:include */
} tagset;

typedef struct {
    txt s;
    const meshio_options *o;
    srcrec *rec;
    /* the mesh grid */
    int mesh_depth; /* depth of its Grid element, 0 not found yet */
    int mesh_done;  /* its Grid closed */
    int64_t nv, nt; /* -1 until read */
    int nodes;      /* 4 or 10 a tet */
    double *xyz;
    int32_t *conn; /* nodes a tet */
    int32_t *region;
    int region_rank; /* how good a name the region's attribute has */
    int64_t nreg;
    const char *topo_at, *reg_at;
    /* what the element being read is about */
    int kind[XD_DEPTH];
    const char *name[XD_DEPTH], *name_end[XD_DEPTH]; /* the open elements' names */
    int depth;
    int attr_cell_int; /* the Attribute open is a scalar cell one (mesh grid) */
    int attr_rank;
    /* grids after the mesh */
    tagset ts; /* the one being read (inline) */
    tagset fs; /* the facet tags from the frames (X_FRAMED) */
    int ts_depth;
    int ts_topo; /* its Topology: 4 tets, 3 triangles, 0 other */
    int ts_attr;
    int32_t *ftris, *fref; /* the first facet tag grid's: boundary triangles */
    int64_t nftri;
    /* heavy data in HDF5 */
    int mode;
    const char *h5f, *h5fe; /* the file every reference names */
    vec spans;              /* (uint64) start and end of each reference's file */
    pend pend[H_COUNT];
    h5_frame fr[H_COUNT]; /* X_FRAMED */
} xd;

/* ------------------------------------------------------------------------ */
/* XML markup                                                                */

static int is_name(unsigned char c)
{
    return is_word(c) || c == ':' || c == '-' || c == '.' || c >= 0x80;
}

/* Past the next occurrence of lit (the scanner's line count kept); 0 if none. */
static int skip_past(txt *s, const char *lit)
{
    size_t n = strlen(lit);

    while (s->p < s->end) {
        if ((size_t)(s->end - s->p) >= n && memcmp(s->p, lit, n) == 0) {
            s->p += n;
            return 1;
        }
        if (*s->p == '\n') {
            s->line++;
            s->bol = s->p + 1;
        }
        s->p++;
    }
    return 0;
}

/* Through markup from s->p to the first of '>', '[' or '<' outside quotes,
 * the line count kept: that character (s->p at it), or 0 at the end. */
static char markup_stop(txt *s)
{
    char quote = 0;

    for (; s->p < s->end; s->p++) {
        char c = *s->p;
        if (c == '\n') {
            s->line++;
            s->bol = s->p + 1;
        }
        if (quote)
            quote = c == quote ? 0 : quote;
        else if (c == '"' || c == '\'')
            quote = c;
        else if (c == '>' || c == '[' || c == '<')
            return c;
    }
    return 0;
}

/* A DOCTYPE at s->p ("<!DOCTYPE"): its internal subset, if any, must be blank. */
static qdc_status xd_doctype(txt *s, qdc_error *err)
{
    const char *at = s->p;
    char c;

    s->p += 9;
    while ((c = markup_stop(s)) == '[') {
        s->p++;
        skip_ws(s);
        if (s->p >= s->end || *s->p != ']')
            return fail_txt(err, QDC_EPARSE, s, s->p,
                            "XDMF: a DOCTYPE with declarations (entities are not "
                            "expanded): refused");
        s->p++;
    }
    if (c == '>') {
        s->p++;
        return QDC_OK;
    }
    return fail_txt(err, QDC_EPARSE, s, at, "XDMF: DOCTYPE not closed");
}

/* The next tag (comments, processing instructions, a DOCTYPE and text
 * skipped); t->at NULL at the end of the input. */
static qdc_status xd_tag(txt *s, xtag *t, qdc_error *err)
{
    memset(t, 0, sizeof *t);
    for (;;) {
        const char *q = memchr(s->p, '<', (size_t)(s->end - s->p));
        const char *lt;
        for (const char *p = s->p; p < (q ? q : s->end); p++)
            if (*p == '\n') {
                s->line++;
                s->bol = p + 1;
            }
        if (!q) {
            s->p = s->end;
            return QDC_OK;
        }
        s->p = lt = q;
        if ((size_t)(s->end - lt) >= 4 && memcmp(lt, "<!--", 4) == 0) {
            if (!skip_past(s, "-->"))
                return fail_txt(err, QDC_EPARSE, s, lt, "XDMF: comment not closed");
            continue;
        }
        if ((size_t)(s->end - lt) >= 2 && lt[1] == '?') {
            if (!skip_past(s, "?>"))
                return fail_txt(err, QDC_EPARSE, s, lt,
                                "XDMF: processing instruction not closed");
            continue;
        }
        if ((size_t)(s->end - lt) >= 9 && memcmp(lt, "<!DOCTYPE", 9) == 0) {
            qdc_status st = xd_doctype(s, err);
            if (st != QDC_OK)
                return st;
            continue;
        }
        if ((size_t)(s->end - lt) >= 2 && lt[1] == '!')
            return fail_txt(err, QDC_EPARSE, s, lt,
                            "XDMF: declarations and CDATA are not read (no entity is "
                            "expanded)");
        break;
    }
    t->at = s->p++;
    if (s->p < s->end && *s->p == '/') {
        t->end = 1;
        s->p++;
    }
    t->n = s->p;
    while (s->p < s->end && is_name((unsigned char)*s->p))
        s->p++;
    t->ne = s->p;
    if (t->n == t->ne)
        return fail_txt(err, QDC_EPARSE, s, t->at, "XDMF: expected an element name");
    t->a = s->p;
    if (markup_stop(s) == '>') { /* '[' in a start tag: not XML */
        t->ae = s->p;
        t->empty = s->p > t->a && s->p[-1] == '/';
        if (t->empty)
            t->ae--;
        s->p++;
        return QDC_OK;
    }
    return fail_txt(err, QDC_EPARSE, s, t->at, "XDMF: tag <%.*s not closed",
                    t->ne - t->n > 24 ? 24 : (int)(t->ne - t->n), t->n);
}

/* The value of attribute key in [a, ae): 1 and [*v, *ve); 0 if absent. */
static int xattr(const char *a, const char *ae, const char *key, const char **v,
                 const char **ve)
{
    size_t kn = strlen(key);

    while (a < ae) {
        const char *n, *ne;
        char quote;
        while (a < ae && is_space((unsigned char)*a))
            a++;
        n = a;
        while (a < ae && is_name((unsigned char)*a))
            a++;
        ne = a;
        while (a < ae && is_space((unsigned char)*a))
            a++;
        if (n == ne || a >= ae || *a != '=')
            return 0;
        a++;
        while (a < ae && is_space((unsigned char)*a))
            a++;
        if (a >= ae || (*a != '"' && *a != '\''))
            return 0;
        quote = *a++;
        *v = a;
        while (a < ae && *a != quote)
            a++;
        if (a >= ae)
            return 0;
        *ve = a++;
        if ((size_t)(ne - n) == kn && memcmp(n, key, kn) == 0)
            return 1;
    }
    return 0;
}

/* The value of key (or of key2 if key is absent; key2 may be NULL) into
 * out[size] with blanks trimmed: 1; 0 if absent; -1 if it holds a reference
 * or is too long. */
static int xattr_str(const xtag *t, const char *key, const char *key2, char *out,
                     size_t size)
{
    const char *v, *ve;

    if (!xattr(t->a, t->ae, key, &v, &ve) && !(key2 && xattr(t->a, t->ae, key2, &v, &ve)))
        return 0;
    while (v < ve && is_space((unsigned char)*v))
        v++;
    while (ve > v && is_space((unsigned char)ve[-1]))
        ve--;
    if ((size_t)(ve - v) >= size || memchr(v, '&', (size_t)(ve - v)))
        return -1;
    memcpy(out, v, (size_t)(ve - v));
    out[ve - v] = '\0';
    return 1;
}

static int name_is(const xtag *t, const char *name)
{
    size_t n = strlen(name);

    return (size_t)(t->ne - t->n) == n && memcmp(t->n, name, n) == 0;
}

/* An attribute qdc reads, as text (XDMF: case as written, compared without
 * case). */
static qdc_status attr_text(xd *x, const xtag *t, const char *key, const char *key2,
                            const char *dflt, char *out, size_t size, qdc_error *err)
{
    int rc = xattr_str(t, key, key2, out, size);

    if (rc < 0)
        return fail_txt(err, QDC_EPARSE, &x->s, t->at,
                        "XDMF: <%.*s %s=...>: a reference (&) or a value too long",
                        t->ne - t->n > 24 ? 24 : (int)(t->ne - t->n), t->n, key);
    if (rc == 0)
        snprintf(out, size, "%s", dflt);
    return QDC_OK;
}

/* ------------------------------------------------------------------------ */
/* DataItems                                                                 */

/* Check what the DataItem t is (XML data, one uniform item) and its size. */
static qdc_status item_read(xd *x, const xtag *t, item *it, qdc_error *err)
{
    char fmt[16], type[16], kind[16], dims[96];
    qdc_status st;
    const char *p, *p_end;

    memset(it, 0, sizeof *it);
    st = attr_text(x, t, "Format", NULL, "XML", fmt, sizeof fmt, err);
    if (st == QDC_OK)
        st = attr_text(x, t, "NumberType", "DataType", "Float", type, sizeof type, err);
    if (st == QDC_OK)
        st = attr_text(x, t, "ItemType", NULL, "Uniform", kind, sizeof kind, err);
    if (st == QDC_OK)
        st = attr_text(x, t, "Dimensions", NULL, "", dims, sizeof dims, err);
    if (st != QDC_OK)
        return st;
    if (strcasecmp(kind, "Uniform") != 0)
        return fail_txt(err, QDC_EFORMAT, &x->s, t->at,
                        "XDMF: DataItem of ItemType %s: only data given as it is "
                        "(Uniform) is read",
                        kind);
    it->hdf = strcasecmp(fmt, "HDF") == 0;
    if (it->hdf && x->mode == X_PLAIN)
        return fail_txt(
            err, QDC_EFORMAT, &x->s, t->at,
            "XDMF: heavy data in HDF5 (Format=\"HDF\"): the qdc command reads "
            "it from the .h5 file beside the .xdmf file (a stream or an "
            "upload to qdcd has no such file: write the data inline, "
            "meshio: data_format=\"XML\")");
    if (!it->hdf && strcasecmp(fmt, "XML") != 0)
        return fail_txt(err, QDC_EFORMAT, &x->s, t->at,
                        "XDMF: DataItem Format %s: only XML (inline) and HDF are read",
                        fmt);
    it->typed = xattr(t->a, t->ae, "NumberType", &p, &p_end) ||
                xattr(t->a, t->ae, "DataType", &p, &p_end);
    it->integer = strcasecmp(type, "Int") == 0 || strcasecmp(type, "UInt") == 0 ||
                  strcasecmp(type, "Char") == 0 || strcasecmp(type, "UChar") == 0;
    if (!it->integer && strcasecmp(type, "Float") != 0)
        return fail_txt(err, QDC_EPARSE, &x->s, t->at, "XDMF: unknown NumberType %s",
                        type);
    it->n = 1;
    for (p = dims; *p;) {
        int64_t d;
        const char *e;
        while (*p && is_space((unsigned char)*p))
            p++;
        if (!*p)
            break;
        for (e = p; *e && !is_space((unsigned char)*e); e++)
            ;
        if (it->ndims == 4 || parse_int(p, e, 0, &d) != 0 || d < 0 || d > INT32_MAX)
            return fail_txt(err, QDC_EPARSE, &x->s, t->at,
                            "XDMF: DataItem Dimensions \"%s\" are not up to four "
                            "counts",
                            dims);
        it->dims[it->ndims++] = d;
        it->n = d && it->n > INT64_MAX / d ? INT64_MAX : it->n * d;
        p = e;
    }
    if (!it->ndims)
        return fail_txt(err, QDC_EPARSE, &x->s, t->at,
                        "XDMF: DataItem without Dimensions");
    /* each number needs a character and a separator */
    if (!it->hdf && it->n > (int64_t)((size_t)(x->s.end - x->s.p) / 2 + 1))
        return fail_txt(err, QDC_EPARSE, &x->s, t->at,
                        "XDMF: DataItem of %lld values does not fit in the %zu bytes "
                        "left (truncated?)",
                        (long long)it->n, (size_t)(x->s.end - x->s.p));
    return QDC_OK;
}

/* The end of the token at p: white space or '<'. */
static const char *xd_tok_end(const txt *s, const char *p)
{
    while (p < s->end && !is_space((unsigned char)*p) && *p != '<')
        p++;
    return p;
}

/* n numbers of the item's text into d (doubles) or i (int32 in [lo, hi]);
 * off: where every third starts (the Geometry). Then </DataItem>. */
static qdc_status item_values(xd *x, int64_t n, double *d, int32_t *iv, int64_t lo,
                              int64_t hi, uint64_t *off, qdc_error *err)
{
    txt *s = &x->s;
    xtag t;
    qdc_status st;
    char q[32];

    for (int64_t k = 0; k < n; k++) {
        const char *tk, *te;
        skip_ws(s);
        tk = s->p;
        te = xd_tok_end(s, tk);
        if (tk == te)
            return fail_txt(err, QDC_EPARSE, s, tk,
                            "XDMF: DataItem: %lld values, expected %lld", (long long)k,
                            (long long)n);
        if (d) {
            st = tok_real(s, tk, te, "XDMF: coordinate", &d[k], err);
            if (off && st == QDC_OK && k % 3 == 0)
                off[k / 3] = (uint64_t)(tk - s->base);
        } else {
            int64_t v = 0;
            st = tok_int(s, tk, te, 0, "XDMF: value", lo, hi, &v, err);
            iv[k] = (int32_t)v;
        }
        if (st != QDC_OK)
            return st;
    }
    skip_ws(s);
    if (s->p < s->end && *s->p != '<')
        return fail_txt(err, QDC_EPARSE, s, s->p,
                        "XDMF: DataItem holds more than its %lld values: %s",
                        (long long)n, quote_tok(q, s, s->p, xd_tok_end(s, s->p)));
    st = xd_tag(s, &t, err);
    if (st == QDC_OK && (!t.at || !t.end || !name_is(&t, "DataItem")))
        st = fail_txt(err, QDC_EPARSE, s, t.at ? t.at : s->end,
                      "XDMF: expected </DataItem> after the values");
    return st;
}

/* ------------------------------------------------------------------------ */
/* Elements                                                                  */

/* The region names, best first; 0 for another name. */
static int region_rank(const xtag *t)
{
    static const char *const names[] = {"region", "gmsh:physical", "cell_tags",
                                        "name_to_read"};
    char name[64];

    if (xattr_str(t, "Name", NULL, name, sizeof name) != 1)
        return 0;
    for (int k = 0; k < 4; k++)
        if (strcmp(name, names[k]) == 0)
            return 4 - k;
    return 0;
}

static qdc_status topo_start(xd *x, const xtag *t, int *nodes, qdc_error *err)
{
    char type[32], npe[16];
    qdc_status st = attr_text(x, t, "TopologyType", "Type", "", type, sizeof type, err);

    if (st == QDC_OK)
        st = attr_text(x, t, "NodesPerElement", NULL, "", npe, sizeof npe, err);
    if (st != QDC_OK)
        return st;
    if (strcasecmp(type, "Tetrahedron") == 0)
        *nodes = 4;
    else if (strcasecmp(type, "Tetrahedron_10") == 0)
        *nodes = 10;
    else if (strcasecmp(type, "Mixed") == 0)
        return fail_txt(err, QDC_EFORMAT, &x->s, t->at,
                        "XDMF: Topology Mixed: qdc reads one topology of tetrahedra");
    else
        return fail_txt(err, QDC_EFORMAT, &x->s, t->at,
                        "XDMF: Topology \"%s\": qdc optimizes tetrahedra (Tetrahedron, "
                        "Tetrahedron_10)",
                        type);
    if (*npe && (strtol(npe, NULL, 10) != *nodes))
        return fail_txt(err, QDC_EPARSE, &x->s, t->at,
                        "XDMF: Topology %s with NodesPerElement %s", type, npe);
    return QDC_OK;
}

/* The nodes an element of a tag grid's Topology t: 4 (Tetrahedron), 3
 * (Triangle), 0 for another (not read). */
static int tag_nodes(xd *x, const xtag *t)
{
    char type[32], npe[16];
    int nodes = 0;

    if (topo_start(x, t, &nodes, NULL) == QDC_OK)
        return nodes == 4 ? 4 : 0;
    if (xattr_str(t, "TopologyType", "Type", type, sizeof type) != 1 ||
        strcasecmp(type, "Triangle") != 0)
        return 0;
    if (xattr_str(t, "NodesPerElement", NULL, npe, sizeof npe) == 1 &&
        strcmp(npe, "3") != 0)
        return 0;
    return 3;
}

/* Is dataset k to be read from HDF5 (a tag grid's: both of its two)? */
static int pend_used(const xd *x, int k)
{
    int pair = k < H_TTOPO ? -1 : H_TTOPO + (k - H_TTOPO) / 2 * 2;

    return x->pend[k].set && (pair < 0 || (x->pend[pair].set && x->pend[pair + 1].set));
}

static int have_region(const xd *x)
{
    return x->region || x->pend[H_REG].set;
}

/* The DataItem t in HDF5 (its path [p, pe)) is the mesh's role k: kept to
 * be read from the frames (X_FRAMED) or listed (X_COLLECT). */
static void pend_set(xd *x, int k, const char *p, const char *pe, const item *it)
{
    x->pend[k].set = 1;
    x->pend[k].p = p;
    x->pend[k].pe = pe;
    x->pend[k].it = *it;
}

/* A DataItem in the mesh grid's Topology, Geometry or a cell Attribute;
 * *read 1 if its values and end tag were read. HDF heavy data: [rp, rpe) is
 * its dataset (its text and end tag already read), else rp is NULL. */
/* The rank of the open scalar cell attribute's item it as the region, -1 if
 * it is none or no better than the region taken: integers, or (rp, in HDF5)
 * no NumberType at all, as DOLFIN writes its MeshFunction (qdc-h5 reports
 * the dataset's class: integers are the region, floats, a DG0 Function's
 * values, are not; heavy_fill). Typed integers first, then by name. */
static int region_candidate(const xd *x, const item *it, const char *rp)
{
    int rank = it->integer ? 16 + x->attr_rank : x->attr_rank;

    if ((!it->integer && (!rp || it->typed)) || !x->attr_cell_int)
        return -1;
    return !have_region(x) || rank > x->region_rank ? rank : -1;
}

static qdc_status mesh_item(xd *x, const xtag *t, int parent, const char *rp,
                            const char *rpe, int *read, qdc_error *err)
{
    item it;
    qdc_status st;

    *read = 0;
    if (t->empty)
        return fail_txt(err, QDC_EPARSE, &x->s, t->at, "XDMF: empty DataItem");
    st = item_read(x, t, &it, err);
    if (st != QDC_OK)
        return st;
    *read = parent != K_ATTR || region_candidate(x, &it, rp) >= 0;
    if (parent == K_GEOM) {
        if (x->nv >= 0)
            return fail_txt(err, QDC_EFORMAT, &x->s, t->at,
                            "XDMF: a second DataItem in the Geometry");
        if (it.n % 3 || (it.ndims == 2 && it.dims[1] != 3) || it.ndims > 2)
            return fail_txt(err, QDC_EFORMAT, &x->s, t->at,
                            "XDMF: Geometry XYZ of Dimensions other than \"N 3\"");
        if (it.n / 3 > MESH_MAX_VERTICES)
            return fail_txt(err, QDC_ETOOBIG, &x->s, t->at, "XDMF: %lld vertices",
                            (long long)(it.n / 3));
        x->nv = it.n / 3;
        if (rp) {
            pend_set(x, H_GEOM, rp, rpe, &it);
            return QDC_OK;
        }
        x->xyz = qdc_mallocn((size_t)it.n + 1, sizeof(double));
        if (!x->xyz)
            return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld vertices",
                            (long long)x->nv);
        if (x->rec) {
            x->rec->fmt = MESHIO_XDMF;
            x->rec->kind = SRC_TEXT;
            x->rec->lt = 1;
            st = srcrec_alloc(x->rec, x->nv, err);
            if (st != QDC_OK)
                return st;
        }
        return item_values(x, it.n, x->xyz, NULL, 0, 0, x->rec ? x->rec->off : NULL, err);
    }
    if (parent == K_TOPO) {
        if (x->nt >= 0)
            return fail_txt(err, QDC_EFORMAT, &x->s, t->at,
                            "XDMF: a second DataItem in the Topology");
        if (!it.integer)
            return fail_txt(err, QDC_EPARSE, &x->s, t->at,
                            "XDMF: Topology of NumberType Float");
        if (it.n % x->nodes || (it.ndims == 2 && it.dims[1] != x->nodes) || it.ndims > 2)
            return fail_txt(err, QDC_EPARSE, &x->s, t->at,
                            "XDMF: Topology of %lld values, not %d a tetrahedron",
                            (long long)it.n, x->nodes);
        if (it.n / x->nodes > MESH_MAX_TETS)
            return fail_txt(err, QDC_ETOOBIG, &x->s, t->at, "XDMF: %lld tetrahedra",
                            (long long)(it.n / x->nodes));
        x->nt = it.n / x->nodes;
        x->topo_at = t->at;
        if (rp) {
            pend_set(x, H_TOPO, rp, rpe, &it);
            return QDC_OK;
        }
        x->conn = qdc_mallocn((size_t)it.n + 1, sizeof(int32_t));
        if (!x->conn)
            return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld tetrahedra",
                            (long long)x->nt);
        return item_values(x, it.n, NULL, x->conn, 0, INT32_MAX, NULL, err);
    }
    /* a scalar cell attribute: integers become the region */
    if (region_candidate(x, &it, rp) >= 0) {
        qdc_free(x->region);
        x->region = NULL;
        x->pend[H_REG].set = 0;
        x->nreg = it.n;
        x->region_rank = region_candidate(x, &it, rp);
        x->reg_at = t->at;
        if (rp) {
            pend_set(x, H_REG, rp, rpe, &it);
            return QDC_OK;
        }
        x->region = qdc_mallocn((size_t)it.n + 1, sizeof(int32_t));
        if (!x->region)
            return qdc_fail(err, QDC_ENOMEM, "out of memory for the regions");
        return item_values(x, it.n, NULL, x->region, INT32_MIN, INT32_MAX, NULL, err);
    }
    return QDC_OK; /* skipped with the rest of the element */
}

/* A DataItem of a tag grid (after the mesh; its Topology of x->ts_topo
 * nodes an element); *read as for mesh_item. */
static qdc_status tags_item(xd *x, const xtag *t, int parent, int *read, qdc_error *err)
{
    item it;
    vec *v = parent == K_TOPO ? &x->ts.tets : &x->ts.vals;
    qdc_status st;

    *read = 0;
    if (t->empty)
        return QDC_OK;
    st = item_read(x, t, &it, err);
    if (st != QDC_OK)
        return st;
    if (!it.integer || it.n > INT32_MAX || (parent == K_TOPO && it.n % x->ts_topo))
        return QDC_OK;
    *read = 1;
    if (vec_grow(v, (size_t)it.n + 1) != 0)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the tags");
    st = item_values(x, it.n, NULL, (int32_t *)v->a + v->n,
                     parent == K_TOPO ? 0 : INT32_MIN, INT32_MAX, NULL, err);
    if (st == QDC_OK)
        v->n += (size_t)it.n;
    return st;
}

/* The region of the tets a tag grid lists (dolfinx MeshTags), by their
 * sorted corners. */
static int cmp_key4(const void *a, const void *b)
{
    const int32_t *p = a, *q = b;

    for (int k = 0; k < 5; k++)
        if (p[k] != q[k])
            return p[k] < q[k] ? -1 : 1;
    return 0;
}

/* The order of three sorted corners (a facet tag triangle's key). */
static int cmp_key3(const int32_t *p, const int32_t *q)
{
    for (int k = 0; k < 3; k++)
        if (p[k] != q[k])
            return p[k] < q[k] ? -1 : 1;
    return 0;
}

/* qsort's order of facet tag keys: sorted corners, then the index. */
static int cmp_tri(const void *a, const void *b)
{
    const int32_t *p = a, *q = b;
    int c = cmp_key3(p, q);

    return c ? c : (p[3] > q[3]) - (p[3] < q[3]);
}

static void sort4(int32_t *k)
{
    for (int i = 1; i < 4; i++)
        for (int j = i; j > 0 && k[j - 1] > k[j]; j--) {
            int32_t tmp = k[j];
            k[j] = k[j - 1];
            k[j - 1] = tmp;
        }
}

static qdc_status tags_apply(xd *x, qdc_error *err)
{
    size_t n = x->ts.tets.n / 4;
    int32_t *keys;
    const int32_t *tt = x->ts.tets.a, *tv = x->ts.vals.a;

    if (!x->ts.shares || !n || x->ts.vals.n != n || x->nt <= 0 || !x->conn)
        return QDC_OK; /* (no conn: the mesh's Topology is in HDF5, not read yet) */
    keys = qdc_mallocn(5 * n, sizeof(int32_t));
    if (!keys)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the tags");
    for (size_t i = 0; i < n; i++) {
        memcpy(keys + 5 * i, tt + 4 * i, 4 * sizeof(int32_t));
        sort4(keys + 5 * i);
        keys[5 * i + 4] = tv[i];
    }
    qsort(keys, n, 5 * sizeof(int32_t), cmp_key4);
    if (!x->region) {
        x->region = qdc_calloc((size_t)x->nt + 1, sizeof(int32_t));
        x->nreg = x->nt;
    }
    if (!x->region) {
        qdc_free(keys);
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the regions");
    }
    for (int64_t e = 0; e < x->nt; e++) {
        int32_t k[4];
        size_t a = 0, b = n;
        memcpy(k, x->conn + x->nodes * e, sizeof k);
        sort4(k);
        while (a < b) {
            size_t mid = a + (b - a) / 2;
            int c = 0;
            for (int j = 0; j < 4 && !c; j++)
                c = keys[5 * mid + j] < k[j] ? -1 : keys[5 * mid + j] > k[j];
            if (!c) {
                x->region[e] = keys[5 * mid + 4];
                break;
            }
            if (c < 0)
                a = mid + 1;
            else
                b = mid;
        }
    }
    qdc_free(keys);
    return QDC_OK;
}

/* The triangles a facet tag grid (ts, sharing the mesh's geometry) lists,
 * with their values: the mesh's boundary triangles and their refs, from the
 * first such grid. */
static void facets_take(xd *x, tagset *ts)
{
    size_t n = ts->tets.n / 3;

    if (x->ftris || !ts->shares || !n || ts->vals.n != n || ts->tets.n % 3)
        return;
    x->ftris = ts->tets.a;
    x->fref = ts->vals.a;
    x->nftri = (int64_t)n;
    ts->tets.a = ts->vals.a = NULL;
    ts->tets.n = ts->tets.cap = ts->vals.n = ts->vals.cap = 0;
}

/* A tag grid's datasets in HDF5 are taken from one grid: at the start of
 * the next, a pair the grid before gave only half of is dropped. */
static void tags_hdf_grid(xd *x)
{
    for (int k = H_TTOPO; k < H_COUNT; k += 2)
        if (x->pend[k].set != x->pend[k + 1].set)
            x->pend[k].set = x->pend[k + 1].set = 0;
}

/* An HDF DataItem of a tag grid of tets or triangles sharing the mesh's
 * geometry (its dataset [p, pe)): the first such grid's of each kept to be
 * read from the frames, as inline tags are read from the first grid that
 * has them, whichever comes first. */
static qdc_status tags_hdf(xd *x, const xtag *t, int parent, const char *p,
                           const char *pe, qdc_error *err)
{
    int base = x->ts_topo == 3 ? H_FTOPO : H_TTOPO;
    int k = parent == K_TOPO ? base : base + 1;
    item it;
    qdc_status st;

    if (x->pend[base].set && x->pend[base + 1].set)
        return QDC_OK;
    st = item_read(x, t, &it, err);
    /* dolfinx (0.5) writes its MeshTags values with no NumberType: in a grid
     * with a Topology of its own, read as integers (qdc-h5 refusing a
     * dataset of another class) */
    if (st == QDC_OK && k == base + 1 && !it.typed && x->ts_topo)
        it.integer = 1;
    if (st != QDC_OK || !it.integer || it.n > INT32_MAX ||
        (k == base && it.n % x->ts_topo))
        return st;
    pend_set(x, k, p, pe, &it);
    return QDC_OK;
}

static int is_hdf(const xtag *t)
{
    char fmt[16];

    return xattr_str(t, "Format", NULL, fmt, sizeof fmt) == 1 &&
           strcasecmp(fmt, "HDF") == 0;
}

/* The text of the HDF DataItem t, "file:/dataset", and its end tag: the
 * dataset in [*p, *pe). The file must be the one every reference names,
 * relative, inside the .xdmf's folder. */
static qdc_status hdf_ref(xd *x, const xtag *t, const char **p, const char **pe,
                          qdc_error *err)
{
    txt *s = &x->s;
    const char *a, *e, *colon, *c;
    xtag end;
    qdc_status st;

    skip_ws(s);
    a = s->p;
    e = memchr(a, '<', (size_t)(s->end - a));
    e = e ? e : s->end;
    for (c = a; c < e; c++)
        if (*c == '\n') {
            s->line++;
            s->bol = c + 1;
        }
    s->p = e;
    while (e > a && is_space((unsigned char)e[-1]))
        e--;
    colon = memchr(a, ':', (size_t)(e - a));
    if (!colon || colon == a || colon + 1 == e || memchr(a, '&', (size_t)(e - a)))
        return fail_txt(err, QDC_EPARSE, s, t->at,
                        "XDMF: an HDF DataItem whose text is not \"file.h5:/dataset\"");
    if (*a == '/' || *a == '\\')
        return fail_txt(err, QDC_EFORMAT, s, a,
                        "XDMF: heavy data in \"%.*s\", an absolute path: only a file in "
                        "the .xdmf file's folder is read",
                        (int)(colon - a > 64 ? 64 : colon - a), a);
    for (c = a; c < colon; c++) {
        int dots = c + 1 < colon && c[0] == '.' && c[1] == '.' &&
                   (c == a || c[-1] == '/') && (c + 2 == colon || c[2] == '/');
        if (dots || *c == '\\' || *c < ' ')
            return fail_txt(err, QDC_EFORMAT, s, a,
                            "XDMF: heavy data in \"%.*s\", outside the .xdmf file's "
                            "folder: only a file in it is read",
                            (int)(colon - a > 64 ? 64 : colon - a), a);
    }
    if (x->h5f && ((size_t)(x->h5fe - x->h5f) != (size_t)(colon - a) ||
                   memcmp(x->h5f, a, (size_t)(colon - a)) != 0))
        return fail_txt(err, QDC_EFORMAT, s, a,
                        "XDMF: heavy data in two HDF5 files (%.*s, %.*s): qdc reads one",
                        (int)(x->h5fe - x->h5f > 64 ? 64 : x->h5fe - x->h5f), x->h5f,
                        (int)(colon - a > 64 ? 64 : colon - a), a);
    x->h5f = a;
    x->h5fe = colon;
    if (x->spans.size) {
        if (vec_grow(&x->spans, 2) != 0)
            return qdc_fail(err, QDC_ENOMEM, "out of memory for the references");
        ((uint64_t *)x->spans.a)[x->spans.n++] = (uint64_t)(a - s->base);
        ((uint64_t *)x->spans.a)[x->spans.n++] = (uint64_t)(colon - s->base);
    }
    *p = colon + 1;
    *pe = e;
    st = xd_tag(s, &end, err);
    if (st == QDC_OK && (!end.at || !end.end || !name_is(&end, "DataItem")))
        st = fail_txt(err, QDC_EPARSE, s, end.at ? end.at : s->end,
                      "XDMF: expected </DataItem> after the HDF5 reference");
    return st;
}

static qdc_status xd_start(xd *x, const xtag *t, qdc_error *err)
{
    int parent = x->depth ? x->kind[x->depth - 1] : -1, k = K_OTHER;
    int in_mesh = x->mesh_depth && !x->mesh_done;
    qdc_status st = QDC_OK;

    if (name_is(t, "Xdmf"))
        k = K_XDMF;
    else if (name_is(t, "Grid"))
        k = K_GRID;
    else if (name_is(t, "Topology"))
        k = K_TOPO;
    else if (name_is(t, "Geometry"))
        k = K_GEOM;
    else if (name_is(t, "Attribute"))
        k = K_ATTR;
    else if (name_is(t, "DataItem"))
        k = K_DATA;
    else if (name_is(t, "xi:include"))
        k = K_INCLUDE;
    if (!x->depth && k != K_XDMF)
        return fail_txt(err, QDC_EPARSE, &x->s, t->at,
                        "not an XDMF file: the root element is not <Xdmf>");
    if (x->depth == XD_DEPTH)
        return fail_txt(err, QDC_EPARSE, &x->s, t->at,
                        "XDMF: elements nested deeper "
                        "than %d",
                        XD_DEPTH);
    /* the mesh: the first grid with a topology or geometry */
    if ((k == K_TOPO || k == K_GEOM) && parent == K_GRID && !x->mesh_depth) {
        x->mesh_depth = x->depth;
        in_mesh = 1;
    }
    if (k == K_DATA && !t->empty && x->mode != X_PLAIN && is_hdf(t)) {
        const char *p = NULL, *pe = NULL;
        int read;
        st = hdf_ref(x, t, &p, &pe, err);
        if (st == QDC_OK && in_mesh && x->depth == x->mesh_depth + 1 &&
            (parent == K_TOPO || parent == K_GEOM || parent == K_ATTR))
            st = mesh_item(x, t, parent, p, pe, &read, err);
        else if (st == QDC_OK && x->ts_depth && x->depth == x->ts_depth + 1 &&
                 x->ts.shares &&
                 ((parent == K_TOPO && x->ts_topo) || (parent == K_ATTR && x->ts_attr)))
            st = tags_hdf(x, t, parent, p, pe, err);
        return st; /* its text and end tag read */
    }
    if (in_mesh && x->depth == x->mesh_depth && k == K_TOPO) {
        if (x->nodes)
            return fail_txt(err, QDC_EFORMAT, &x->s, t->at,
                            "XDMF: a second Topology in the mesh's Grid");
        st = topo_start(x, t, &x->nodes, err);
    } else if (in_mesh && x->depth == x->mesh_depth && k == K_GEOM) {
        char type[16];
        st = attr_text(x, t, "GeometryType", "Type", "XYZ", type, sizeof type, err);
        if (st == QDC_OK && strcasecmp(type, "XYZ") != 0)
            st = fail_txt(err, QDC_EFORMAT, &x->s, t->at,
                          "XDMF: Geometry %s: qdc reads XYZ (three coordinates a point)",
                          type);
    } else if (in_mesh && x->depth == x->mesh_depth && k == K_ATTR) {
        char center[16], type[16];
        st = attr_text(x, t, "Center", NULL, "Node", center, sizeof center, err);
        if (st == QDC_OK)
            st = attr_text(x, t, "AttributeType", NULL, "Scalar", type, sizeof type, err);
        x->attr_cell_int =
            strcasecmp(center, "Cell") == 0 && strcasecmp(type, "Scalar") == 0;
        x->attr_rank = region_rank(t);
    } else if (in_mesh && x->depth == x->mesh_depth + 1 && k == K_DATA &&
               (parent == K_TOPO || parent == K_GEOM || parent == K_ATTR)) {
        int read = 0;
        st = mesh_item(x, t, parent, NULL, NULL, &read, err);
        if (read)
            k = -1; /* its end tag was read with the values */
    } else if (in_mesh && x->depth > x->mesh_depth && k == K_INCLUDE &&
               (parent == K_TOPO || parent == K_GEOM)) {
        st = fail_txt(err, QDC_EFORMAT, &x->s, t->at,
                      "XDMF: the mesh's Topology or Geometry by reference (xi:include)");
    } else if (in_mesh && x->depth == x->mesh_depth && k == K_INCLUDE) {
        st = fail_txt(err, QDC_EFORMAT, &x->s, t->at,
                      "XDMF: part of the mesh's Grid by reference (xi:include)");
    } else if (x->mesh_done && k == K_GRID && !x->ts_depth) {
        x->ts_depth = x->depth + 1;
        x->ts.tets.n = x->ts.vals.n = 0;
        x->ts.shares = x->ts_topo = x->ts_attr = 0;
        tags_hdf_grid(x);
    } else if (x->ts_depth && x->depth == x->ts_depth) {
        if (k == K_INCLUDE)
            x->ts.shares = 1;
        if (k == K_TOPO)
            x->ts_topo = tag_nodes(x, t);
        if (k == K_ATTR) {
            char center[16];
            x->ts_attr = xattr_str(t, "Center", NULL, center, sizeof center) == 1 &&
                         strcasecmp(center, "Cell") == 0;
        }
    } else if (x->ts_depth && x->depth == x->ts_depth + 1 && k == K_DATA &&
               ((parent == K_TOPO && x->ts_topo && !x->ts.tets.n) ||
                (parent == K_ATTR && x->ts_attr && !x->ts.vals.n))) {
        int read = 0;
        st = tags_item(x, t, parent, &read, err);
        if (read)
            k = -1;
    }
    if (st != QDC_OK || t->empty || k < 0)
        return st;
    x->name[x->depth] = t->n;
    x->name_end[x->depth] = t->ne;
    x->kind[x->depth++] = k;
    return QDC_OK;
}

static qdc_status xd_end(xd *x, const xtag *t, qdc_error *err)
{
    size_t n;

    if (!x->depth)
        return fail_txt(err, QDC_EPARSE, &x->s, t->at,
                        "XDMF: an end tag with no element");
    x->depth--;
    n = (size_t)(x->name_end[x->depth] - x->name[x->depth]);
    if ((size_t)(t->ne - t->n) != n || memcmp(t->n, x->name[x->depth], n) != 0)
        return fail_txt(err, QDC_EPARSE, &x->s, t->at, "XDMF: expected </%.*s>",
                        n > 24 ? 24 : (int)n, x->name[x->depth]);
    if (x->kind[x->depth] == K_GRID && x->mesh_depth == x->depth + 1 && !x->mesh_done)
        x->mesh_done = 1;
    if (x->kind[x->depth] == K_GRID && x->ts_depth == x->depth + 1) {
        qdc_status st = QDC_OK;
        if (x->ts_topo == 3)
            facets_take(x, &x->ts);
        else
            st = tags_apply(x, err);
        x->ts_depth = 0;
        if (st != QDC_OK)
            return st;
    }
    return QDC_OK;
}

static void xd_free(xd *x)
{
    qdc_free(x->xyz);
    qdc_free(x->conn);
    qdc_free(x->region);
    qdc_free(x->ftris);
    qdc_free(x->fref);
    vec_free(&x->ts.tets);
    vec_free(&x->ts.vals);
    vec_free(&x->fs.tets);
    vec_free(&x->fs.vals);
    vec_free(&x->spans);
}

/* The mesh's datasets in HDF5 from the frames (X_FRAMED); whole: the
 * framed buffer, which x->s.base is. */
static qdc_status heavy_fill(xd *x, qdc_error *err)
{
    const unsigned char *b = (const unsigned char *)x->s.base;

    for (int k = 0; k < H_COUNT; k++) {
        const h5_frame *f = &x->fr[k];
        int64_t n = x->pend[k].it.n;
        if (!pend_used(x, k))
            continue;
        if (!f->type || f->n != (uint64_t)n)
            return qdc_fail(err, QDC_EPARSE,
                            "XDMF: the %s dataset %.*s: %llu values from the HDF5 file, "
                            "the XDMF says %lld",
                            h5_names[k],
                            (int)(x->pend[k].pe - x->pend[k].p > 64
                                      ? 64
                                      : x->pend[k].pe - x->pend[k].p),
                            x->pend[k].p, (unsigned long long)f->n, (long long)n);
        if (k == H_REG && f->type == 'f') /* an untyped attribute of floats */
            continue;
        if (k == H_GEOM) {
            x->xyz = qdc_mallocn((size_t)n + 1, sizeof(double));
            if (!x->xyz)
                return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld vertices",
                                (long long)x->nv);
            for (int64_t i = 0; i < n; i++) {
                uint64_t u = get_le64(b + f->at + 8 * (uint64_t)i);
                memcpy(&x->xyz[i], &u, 8);
                if (!isfinite(x->xyz[i])) {
                    fail_bin(err, QDC_EPARSE, (int64_t)(f->at + 8 * (uint64_t)i),
                             "XDMF: node %lld has a coordinate that is not finite "
                             "(NaN/Inf)",
                             (long long)(i / 3));
                    set_index(err, "vertex", i / 3);
                    return QDC_EPARSE;
                }
            }
            if (x->rec) {
                qdc_status st;
                x->rec->fmt = MESHIO_XDMF;
                x->rec->kind = SRC_BIN;
                x->rec->width = 8;
                x->rec->big = 0;
                st = srcrec_alloc(x->rec, x->nv, err);
                if (st != QDC_OK)
                    return st;
                for (int64_t v = 0; v < x->nv; v++)
                    x->rec->off[v] = f->at + 24 * (uint64_t)v;
            }
        } else {
            int32_t *a = qdc_mallocn((size_t)n + 1, sizeof(int32_t));
            int conn = k == H_TOPO || k == H_TTOPO || k == H_FTOPO;
            int64_t lo = conn ? 0 : INT32_MIN;
            tagset *ts = k >= H_FTOPO ? &x->fs : &x->ts;
            vec *tv = conn ? &ts->tets : &ts->vals;
            if (!a)
                return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld values",
                                (long long)n);
            if (k >= H_TTOPO) { /* a tag grid's: tags_apply, facets_take */
                qdc_free(tv->a);
                tv->a = a;
                tv->n = tv->cap = (size_t)n;
            } else {
                *(k == H_TOPO ? &x->conn : &x->region) = a;
            }
            for (int64_t i = 0; i < n; i++) {
                int64_t v = (int64_t)get_le64(b + f->at + 8 * (uint64_t)i);
                if (v < lo || v > INT32_MAX)
                    return fail_bin(err, QDC_EPARSE, (int64_t)(f->at + 8 * (uint64_t)i),
                                    "XDMF: the %s dataset: value %lld at %lld is out of "
                                    "range",
                                    h5_names[k], (long long)v, (long long)i);
                a[i] = (int32_t)v;
            }
        }
    }
    return QDC_OK;
}

/* Every facet tag triangle is a face of a tet (dolfinx MeshTags of dimension
 * 2 list the mesh's own facets): a triangle on the boundary, or between two
 * tets (an interface or an inner surface, kept as it is, as Medit's and
 * Gmsh's triangles are). A triangle that is no face of any tet is refused,
 * named. The triangles' sorted corners with their index, searched for each
 * face of each tet. */
static qdc_status facets_are_faces(const xd *x, qdc_error *err)
{
    size_t n = (size_t)x->nftri;
    int32_t *keys = qdc_mallocn(4 * n + 1, sizeof(int32_t));
    uint8_t *hit = qdc_calloc(n + 1, 1);
    qdc_status st = QDC_OK;

    if (!keys || !hit) {
        qdc_free(keys);
        qdc_free(hit);
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %zu facet tags", n);
    }
    for (size_t i = 0; i < n; i++) {
        tet_sort3(x->ftris[3 * i], x->ftris[3 * i + 1], x->ftris[3 * i + 2],
                  keys + 4 * i);
        keys[4 * i + 3] = (int32_t)i;
    }
    qsort(keys, n, 4 * sizeof(int32_t), cmp_tri);
    for (int64_t e = 0; e < x->nt; e++)
        for (int f = 0; f < 4; f++) {
            const int32_t *c = x->conn + x->nodes * e;
            int32_t k[3];
            size_t a = 0, b = n;
            tet_sort3(c[tet_face_of[f][0]], c[tet_face_of[f][1]], c[tet_face_of[f][2]],
                      k);
            while (a < b) { /* the first triangle with these corners */
                size_t mid = a + (b - a) / 2;
                if (cmp_key3(keys + 4 * mid, k) < 0)
                    a = mid + 1;
                else
                    b = mid;
            }
            for (; a < n && cmp_key3(keys + 4 * a, k) == 0; a++)
                hit[keys[4 * a + 3]] = 1;
        }
    for (size_t i = 0; i < n && st == QDC_OK; i++)
        if (!hit[i]) {
            st =
                qdc_fail(err, QDC_EPARSE,
                         "XDMF: facet tag triangle %zu (vertices %d %d %d) is no face of "
                         "a tetrahedron",
                         i, (int)x->ftris[3 * i], (int)x->ftris[3 * i + 1],
                         (int)x->ftris[3 * i + 2]);
            set_index(err, "triangle", (int64_t)i);
        }
    qdc_free(keys);
    qdc_free(hit);
    return st;
}

/* The mesh from what was read: indices checked, corners and mid-edge nodes
 * apart. */
static qdc_status xd_mesh(xd *x, mesh_t **out, qdc_error *err)
{
    parsed pm;
    int64_t bad;
    qdc_status st;

    if (x->nv < 0 || x->nt < 0)
        return qdc_fail(err, QDC_EPARSE, "XDMF: no %s in the mesh's Grid",
                        x->nv < 0 ? "Geometry DataItem" : "Topology DataItem");
    bad = first_bad_index(x->conn, x->nt * x->nodes, x->nv);
    if (bad >= 0) {
        txt_locate(&x->s, x->topo_at);
        st = fail_txt(err, QDC_EPARSE, &x->s, x->topo_at,
                      "XDMF: tetrahedron %lld: vertex %d out of range [0, %lld)",
                      (long long)(bad / x->nodes), (int)x->conn[bad], (long long)x->nv);
        set_index(err, "tet", bad / x->nodes);
        return st;
    }
    bad = first_bad_index(x->ftris, 3 * x->nftri, x->nv);
    if (bad >= 0) {
        st = qdc_fail(err, QDC_EPARSE,
                      "XDMF: facet tag triangle %lld: vertex %d out of range [0, %lld)",
                      (long long)(bad / 3), (int)x->ftris[bad], (long long)x->nv);
        set_index(err, "triangle", bad / 3);
        return st;
    }
    if (x->nftri > 0 && x->conn) {
        st = facets_are_faces(x, err);
        if (st != QDC_OK)
            return st;
    }
    if (x->region && x->nreg != x->nt) {
        txt_locate(&x->s, x->reg_at);
        return fail_txt(err, QDC_EPARSE, &x->s, x->reg_at,
                        "XDMF: cell attribute of %lld values for %lld tetrahedra",
                        (long long)x->nreg, (long long)x->nt);
    }
    parsed_init(&pm);
    pm.nv = x->nv;
    pm.nt = x->nt;
    pm.xyz = x->xyz;
    x->xyz = NULL;
    pm.region = x->region;
    x->region = NULL;
    if (x->nftri > 0) { /* facet tags: boundary triangles and their refs */
        pm.ntri = x->nftri;
        pm.tris = x->ftris;
        pm.tri_ref = x->fref;
        x->ftris = x->fref = NULL;
    }
    if (x->nodes == 4) {
        pm.tets = x->conn;
        x->conn = NULL;
    } else {
        pm.tets = qdc_mallocn((size_t)x->nt * 4 + 1, sizeof(int32_t));
        pm.mid = qdc_mallocn((size_t)x->nt * 6 + 1, sizeof(int32_t));
        if (!pm.tets || !pm.mid) {
            parsed_free(&pm);
            return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld tetrahedra",
                            (long long)x->nt);
        }
        for (int64_t e = 0; e < x->nt; e++) {
            memcpy(pm.tets + 4 * e, x->conn + 10 * e, 4 * sizeof(int32_t));
            memcpy(pm.mid + 6 * e, x->conn + 10 * e + 4, 6 * sizeof(int32_t));
        }
    }
    return parsed_mesh_move(&pm, out, err);
}

/* x set up over its text: read it to the end of the root element. */
static qdc_status xd_run(xd *x, qdc_error *err)
{
    qdc_status st = QDC_OK;

    x->nv = x->nt = -1;
    x->ts.tets.size = x->ts.vals.size = sizeof(int32_t);
    x->fs.tets.size = x->fs.vals.size = sizeof(int32_t);
    for (;;) {
        xtag t;
        st = xd_tag(&x->s, &t, err);
        if (st != QDC_OK || !t.at)
            break;
        st = t.end ? xd_end(x, &t, err) : xd_start(x, &t, err);
        if (st != QDC_OK)
            break;
        if (!x->depth && !t.empty) /* the root closed */
            break;
    }
    if (st == QDC_OK && x->depth)
        st = fail_txt(err, QDC_EPARSE, &x->s, x->s.end, "XDMF: ends inside an element");
    if (st == QDC_OK) {
        xtag t;
        st = xd_tag(&x->s, &t, err);
        if (st == QDC_OK && t.at)
            st = fail_txt(err, QDC_EPARSE, &x->s, t.at, "XDMF: markup after </Xdmf>");
    }
    return st;
}

/* x over the XML of buf[0..len): the text itself, or the "xdmf" frame of the
 * framed form (X_FRAMED, its frames in x->fr). */
static qdc_status xd_open(xd *x, const char *buf, size_t len, qdc_error *err)
{
    static const char *const names[H_COUNT + 1] = {"geometry", "topology", "region",
                                                   "tagtopo",  "tagvals",  "tritopo",
                                                   "trivals",  "xdmf"};
    h5_frame fr[H_COUNT + 1];
    qdc_status st;

    if (len < sizeof h5_magic || memcmp(buf, h5_magic, sizeof h5_magic) != 0) {
        x->s = txt_init(buf, len, 0);
        return QDC_OK;
    }
    st = h5_frames(buf, len, "XDMF", names, "fi?iiiib", H_COUNT + 1, fr, err);
    if (st != QDC_OK)
        return st;
    if (!fr[H_COUNT].type)
        return fail_bin(err, QDC_EPARSE, 0, "XDMF: framed input without its XML");
    memcpy(x->fr, fr, sizeof x->fr);
    x->mode = X_FRAMED;
    /* the text's offsets are the buffer's, as a spliced write needs them */
    x->s = txt_init(buf, (size_t)(fr[H_COUNT].at + fr[H_COUNT].n), 0);
    x->s.p = x->s.bol = buf + fr[H_COUNT].at;
    return QDC_OK;
}

static qdc_status read_xdmf(const char *buf, size_t len, const meshio_options *o,
                            srcrec *rec, mesh_t **out, qdc_error *err)
{
    xd x;
    qdc_status st;

    memset(&x, 0, sizeof x);
    x.o = o;
    x.rec = rec;
    st = xd_open(&x, buf, len, err);
    if (st == QDC_OK)
        st = xd_run(&x, err);
    if (st == QDC_OK && x.mode == X_FRAMED)
        st = heavy_fill(&x, err);
    if (st == QDC_OK && x.mode == X_FRAMED && pend_used(&x, H_TTOPO)) {
        x.ts.shares = 1; /* listed only so */
        st = tags_apply(&x, err);
    }
    if (st == QDC_OK && x.mode == X_FRAMED && pend_used(&x, H_FTOPO)) {
        x.fs.shares = 1;
        facets_take(&x, &x.fs);
    }
    if (st == QDC_OK)
        st = xd_mesh(&x, out, err);
    if (st != QDC_OK && rec)
        rec->kind = SRC_NONE;
    xd_free(&x);
    return st;
}

/* ------------------------------------------------------------------------ */
/* Heavy data in HDF5: what the qdc command hands qdc-h5                     */

/* buf read as X_COLLECT: the HDF references in x (xd_free it). */
static qdc_status xd_collect(xd *x, const char *buf, size_t len, int spans,
                             qdc_error *err)
{
    memset(x, 0, sizeof *x);
    x->mode = X_COLLECT;
    x->spans.size = spans ? sizeof(uint64_t) : 0;
    x->s = txt_init(buf, len, 0);
    if (len >= sizeof h5_magic && memcmp(buf, h5_magic, sizeof h5_magic) == 0)
        return fail_bin(err, QDC_EINVAL, 0, "XDMF: the XML, not the framed form");
    return xd_run(x, err);
}

static void copy_span(char *out, size_t size, const char *a, const char *e)
{
    size_t n = (size_t)(e - a) < size - 1 ? (size_t)(e - a) : size - 1;

    memcpy(out, a, n);
    out[n] = '\0';
}

qdc_status meshio_xdmf_h5_refs(const char *buf, size_t len, meshio_xdmf_h5 *h,
                               qdc_error *err)
{
    xd x;
    qdc_status st;

    qdc_error_clear(err);
    memset(h, 0, sizeof *h);
    st = xd_collect(&x, buf, len, 0, err);
    for (int k = 0; st == QDC_OK && k < H_COUNT; k++) {
        const pend *pd = &x.pend[k];
        if (!pend_used(&x, k))
            continue;
        if ((size_t)(x.h5fe - x.h5f) >= sizeof h->file ||
            (size_t)(pd->pe - pd->p) >= sizeof h->set[0].path) {
            st = qdc_fail(err, QDC_EPARSE, "XDMF: an HDF5 reference too long");
            break;
        }
        copy_span(h->file, sizeof h->file, x.h5f, x.h5fe);
        snprintf(h->set[h->n].name, sizeof h->set[0].name, "%s", h5_names[k]);
        h->set[h->n].type = k == H_GEOM ? 'f' : pd->it.integer ? 'i' : 'a';
        copy_span(h->set[h->n].path, sizeof h->set[0].path, pd->p, pd->pe);
        h->set[h->n].ndims = pd->it.ndims;
        memcpy(h->set[h->n].dims, pd->it.dims, sizeof pd->it.dims);
        h->n++;
    }
    xd_free(&x);
    return st;
}

qdc_status meshio_xdmf_h5_rename(const char *buf, size_t len, const char *file,
                                 qdc_write_fn fn, void *ctx, qdc_error *err)
{
    xd x;
    qdc_status st;
    size_t at = 0;
    const uint64_t *sp;

    qdc_error_clear(err);
    if (strpbrk(file, "&<>\"':") || !*file)
        return qdc_fail(err, QDC_EINVAL,
                        "XDMF: \"%s\" cannot name an HDF5 file in XDMF (none of "
                        "&<>\"': in it)",
                        file);
    st = xd_collect(&x, buf, len, 1, err);
    sp = x.spans.a;
    for (size_t i = 0; st == QDC_OK && i < x.spans.n; i += 2) {
        if (fn(ctx, buf + at, (size_t)sp[i] - at) != 0 ||
            fn(ctx, file, strlen(file)) != 0)
            st = qdc_fail(err, QDC_EIO, "XDMF: write failed");
        at = (size_t)sp[i + 1];
    }
    if (st == QDC_OK && fn(ctx, buf + at, len - at) != 0)
        st = qdc_fail(err, QDC_EIO, "XDMF: write failed");
    xd_free(&x);
    return st;
}

size_t meshio_xdmf_h5_room(size_t xml_len)
{
    /* the form: magic, a frame header, the XML padded to 8 bytes, then the
     * frames without their magic, whose place the room's end takes */
    return 32 + xml_len + (8 - xml_len % 8) % 8;
}

qdc_status meshio_xdmf_h5_fill(char *buf, size_t len, const char *xml, size_t xml_len,
                               qdc_error *err)
{
    size_t room, pad = (8 - xml_len % 8) % 8;
    unsigned char *b = (unsigned char *)buf;

    qdc_error_clear(err);
    if (xml_len > SIZE_MAX / 2)
        return qdc_fail(err, QDC_ETOOBIG, "XDMF: input too large");
    room = meshio_xdmf_h5_room(xml_len);
    if (len < room + sizeof h5_magic ||
        memcmp(buf + room, h5_magic, sizeof h5_magic) != 0)
        return qdc_fail(err, QDC_EPARSE, "XDMF: qdc-h5 gave no frames");
    memcpy(b, h5_magic, sizeof h5_magic);
    memset(b + 8, 0, 32);
    memcpy(b + 8, "xdmf", 4);
    b[8 + 16] = 'b';
    for (int k = 0; k < 8; k++)
        b[8 + 24 + k] = (unsigned char)((uint64_t)xml_len >> (8 * k));
    memcpy(b + 40, xml, xml_len);
    memset(b + 40 + xml_len, 0, pad);
    return QDC_OK;
}

qdc_status meshio_xdmf_h5_input(const char *xml, size_t xml_len, const char *frames,
                                size_t frames_len, char **out, size_t *out_len,
                                qdc_error *err)
{
    size_t room = meshio_xdmf_h5_room(xml_len), n;
    char *b;
    qdc_status st;

    qdc_error_clear(err);
    *out = NULL;
    *out_len = 0;
    if (xml_len > SIZE_MAX / 2 || frames_len > SIZE_MAX / 2)
        return qdc_fail(err, QDC_ETOOBIG, "XDMF: input too large");
    n = room + frames_len;
    b = qdc_malloc(n + 1);
    if (!b)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %zu bytes", n);
    memcpy(b + room, frames, frames_len);
    b[n] = 0;
    st = meshio_xdmf_h5_fill(b, n, xml, xml_len, err);
    if (st != QDC_OK) {
        qdc_free(b);
        return st;
    }
    *out = b;
    *out_len = n;
    return QDC_OK;
}

/* ------------------------------------------------------------------------ */
/* Writing: XDMF 3, inline                                                   */

static qdc_status write_xdmf(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                             qdc_error *err)
{
    qdc_status st = check_for_write(m, err);
    int nodes = m->mid ? 10 : 4;

    (void)fmt;
    (void)part;
    if (st != QDC_OK)
        return st;
    wb_str(w, "<?xml version=\"1.0\"?>\n<Xdmf Version=\"3.0\">\n<Domain>\n"
              "<Grid Name=\"mesh\" GridType=\"Uniform\">\n"
              "<Geometry GeometryType=\"XYZ\">\n<DataItem DataType=\"Float\" "
              "Dimensions=\"");
    wb_int(w, m->nv);
    wb_str(w, " 3\" Format=\"XML\" Precision=\"8\">\n");
    for (int32_t v = 0; v < m->nv; v++)
        wb_reals(w, m->xyz + 3 * (size_t)v, 3, " ", "\n");
    wb_str(w, "</DataItem>\n</Geometry>\n<Topology TopologyType=\"");
    wb_str(w, m->mid ? "Tetrahedron_10" : "Tetrahedron");
    wb_str(w, "\" NumberOfElements=\"");
    wb_int(w, m->nt);
    wb_str(w, "\" NodesPerElement=\"");
    wb_int(w, nodes);
    wb_str(w, "\">\n<DataItem DataType=\"Int\" Dimensions=\"");
    wb_int(w, m->nt);
    wb_str(w, m->mid ? " 10" : " 4");
    wb_str(w, "\" Format=\"XML\" Precision=\"4\">\n");
    for (int32_t t = 0; t < m->nt; t++) {
        wb_ints(w, m->tets + 4 * (size_t)t, 4, 0, " ", m->mid ? " " : "\n");
        if (m->mid)
            wb_ints(w, m->mid + 6 * (size_t)t, 6, 0, " ", "\n");
    }
    wb_str(w, "</DataItem>\n</Topology>\n");
    if (m->region) {
        wb_str(w, "<Attribute Name=\"region\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
                  "<DataItem DataType=\"Int\" Dimensions=\"");
        wb_int(w, m->nt);
        wb_str(w, "\" Format=\"XML\" Precision=\"4\">\n");
        for (int32_t t = 0; t < m->nt; t++)
            wb_ints(w, m->region + t, 1, 0, "", "\n");
        wb_str(w, "</DataItem>\n</Attribute>\n");
    }
    wb_str(w, "</Grid>\n</Domain>\n</Xdmf>\n");
    return QDC_OK;
}

/* "<Xdmf" as the first element, after an XML declaration, comments or a
 * DOCTYPE, in the first kB. */
static meshio_format sniff_xdmf(const char *buf, size_t len, size_t i)
{
    static const char tag[] = "<Xdmf";
    size_t lim = len - i < 1024 ? len : i + 1024;

    if (i >= len || buf[i] != '<')
        return MESHIO_AUTO;
    for (size_t k = i; k + sizeof tag - 1 < lim; k++)
        if (buf[k] == '<' && memcmp(buf + k, tag, sizeof tag - 1) == 0 &&
            !is_name((unsigned char)buf[k + sizeof tag - 1]))
            return MESHIO_XDMF;
    return MESHIO_AUTO;
}

const meshio_fmt fmt_xdmf = {
    .name = "xdmf",
    .aliases = "xmf",
    .about = "XDMF 2/3, tetrahedra with the data inline (XML), or in HDF5 through qdc-h5 "
             "(the qdc command, or qdcd as a two-file multipart upload)",
    .ext = "xdmf",
    .input = "input.xdmf",
    .sniff = sniff_xdmf,
    .read = read_xdmf,
    .write = write_xdmf,
    .splices = 1,
    .p2 = 1,
};
