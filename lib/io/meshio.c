/* meshio.c - the format table at work: names, extensions, media types and
 * sniffing looked up in the descriptors of formats.h; reading, writing,
 * loading and saving dispatched to them.
 *
 * Each format is one file (meshio_<format>.c) with one descriptor
 * (format.h) and one line in formats.h; nothing here names a format but
 * TetGen, whose two files load and save as a pair. Whole files are read and
 * saved by file.c; spliced writing (the input with new coordinates) is
 * splice.c. */
#include "io/meshio.h"
#include "io/file.h"
#include "io/format.h"
#include "io/gz.h"
#include "io/surface.h"

#include <stdint.h>
#include <string.h>
#include <strings.h>

/* ------------------------------------------------------------------------ */
/* The table                                                                 */

static const meshio_fmt *const table[MESHIO_FORMAT_COUNT] = {
    NULL, /* MESHIO_AUTO */
#define MESHIO_FORMAT(id, desc) &desc,
#include "io/formats.h"
#undef MESHIO_FORMAT
};

const meshio_fmt *meshio_fmt_of(meshio_format f)
{
    return (unsigned)f < MESHIO_FORMAT_COUNT ? table[f] : NULL;
}

/* The first format of f's family (f itself if it has no other variant). */
static int family_of(int f)
{
    return table[f]->family != MESHIO_AUTO ? (int)table[f]->family : f;
}

const char *meshio_format_name(meshio_format f)
{
    if (f == MESHIO_AUTO)
        return "auto";
    return meshio_fmt_of(f) ? table[f]->name : NULL;
}

int meshio_format_info_of(meshio_format f, meshio_format_info *info)
{
    const meshio_fmt *d = meshio_fmt_of(f);

    if (!d || !info)
        return 0;
    info->name = d->name;
    info->aliases = d->aliases;
    info->about = d->about;
    info->ext = d->ext;
    info->input = d->input;
    info->media = d->media;
    info->family = d->family != MESHIO_AUTO ? d->family : f;
    info->writes = d->write != NULL;
    info->splices = d->splices;
    return 1;
}

/* A JSON string of s (static text of the table: quotes and backslashes
 * escaped, control characters dropped). */
static void json_text(wbuf *w, const char *s, size_t n)
{
    wb_str(w, "\"");
    for (size_t i = 0; i < n; i++) {
        if (s[i] == '"' || s[i] == '\\')
            wb_put(w, "\\", 1);
        if ((unsigned char)s[i] >= 0x20)
            wb_put(w, s + i, 1);
    }
    wb_str(w, "\"");
}

static void json_member(wbuf *w, const char *key, const char *val)
{
    wb_str(w, ",\"");
    wb_str(w, key);
    wb_str(w, "\":");
    if (val)
        json_text(w, val, strlen(val));
    else
        wb_str(w, "null");
}

static void json_flag(wbuf *w, const char *key, int on)
{
    wb_str(w, ",\"");
    wb_str(w, key);
    wb_str(w, on ? "\":true" : "\":false");
}

qdc_status meshio_formats_json(qdc_write_fn fn, void *ctx, qdc_error *err)
{
    wbuf w = {fn, ctx, NULL, 0, 0};

    qdc_error_clear(err);
    if (!fn)
        return qdc_fail(err, QDC_EINVAL, "meshio_formats_json: NULL write function");
    w.b = qdc_malloc(WB_CAP);
    if (!w.b)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the write buffer");
    wb_str(&w, "{\"formats\":[");
    for (int f = 1; f < MESHIO_FORMAT_COUNT; f++) {
        const meshio_fmt *d = table[f];
        const char *a = d->aliases;
        wb_str(&w, f > 1 ? ",\n{\"name\":" : "\n{\"name\":");
        json_text(&w, d->name, strlen(d->name));
        wb_str(&w, ",\"aliases\":[");
        for (int n = 0; a && *a; n++) {
            size_t k = strcspn(a, " ");
            wb_str(&w, n ? "," : "");
            json_text(&w, a, k);
            a += k + (a[k] == ' ');
        }
        wb_str(&w, "]");
        json_member(&w, "about", d->about);
        json_member(&w, "extension", d->ext);
        json_member(&w, "family", table[family_of(f)]->name);
        json_member(&w, "media_type", d->media);
        json_flag(&w, "upload", d->input != NULL);
        json_flag(&w, "result", d->write && d->input);
        json_flag(&w, "splice", d->splices);
        wb_str(&w, "}");
    }
    wb_str(&w, "],\n\"surfaces\":[");
    for (int f = 1; f < SURFACE_FORMAT_COUNT; f++) {
        wb_str(&w, f > 1 ? ",\n{\"name\":" : "\n{\"name\":");
        json_text(&w, surface_format_name((surface_format)f),
                  strlen(surface_format_name((surface_format)f)));
        json_member(&w, "extension", surface_format_name((surface_format)f));
        json_member(&w, "media_type", surface_media_type((surface_format)f));
        wb_str(&w, "}");
    }
    wb_str(&w, "]}\n");
    wb_flush(&w);
    qdc_free(w.b);
    return w.bad ? qdc_fail(err, QDC_EIO, "write failed") : QDC_OK;
}

/* Is [s, s + n) one of the words of list (space-separated), case aside? */
static int in_list(const char *list, const char *s, size_t n)
{
    while (list && *list) {
        size_t k = strcspn(list, " ");
        if (k == n && strncasecmp(list, s, n) == 0)
            return 1;
        list += k;
        list += *list == ' ';
    }
    return 0;
}

/* The format of a name or alias [s, s + n), case aside; MESHIO_AUTO if none. */
static meshio_format named(const char *s, size_t n)
{
    for (int f = 1; f < MESHIO_FORMAT_COUNT; f++)
        if ((strlen(table[f]->name) == n && strncasecmp(table[f]->name, s, n) == 0) ||
            in_list(table[f]->aliases, s, n))
            return (meshio_format)f;
    return MESHIO_AUTO;
}

/* The format of an extension that ends at the first '.' or the end ("mesh"
 * in "mesh.gz"). */
static meshio_format ext_format(const char *ext)
{
    return named(ext, strcspn(ext, "."));
}

meshio_format meshio_format_from_name(const char *s)
{
    meshio_format f;
    const char *ext;

    if (!s)
        return MESHIO_AUTO;
    f = named(s, strlen(s));
    if (f != MESHIO_AUTO)
        return f;
    ext = file_path_ext(s);
    return ext ? ext_format(ext) : MESHIO_AUTO;
}

meshio_format meshio_sniff(const char *buf, size_t len)
{
    size_t i = 0;

    if (!buf)
        return MESHIO_AUTO;
    for (int f = 1; f < MESHIO_FORMAT_COUNT; f++) {
        meshio_format got;
        if (table[f]->magic && table[f]->sniff &&
            (got = table[f]->sniff(buf, len, 0)) != MESHIO_AUTO)
            return got;
    }
    while (i < len) { /* blanks and '#' comment lines */
        if (is_space((unsigned char)buf[i])) {
            i++;
        } else if (buf[i] == '#') {
            while (i < len && buf[i] != '\n')
                i++;
        } else {
            break;
        }
    }
    for (int f = 1; f < MESHIO_FORMAT_COUNT; f++) {
        meshio_format got;
        if (!table[f]->magic && table[f]->sniff &&
            (got = table[f]->sniff(buf, len, i)) != MESHIO_AUTO)
            return got;
    }
    return MESHIO_AUTO;
}

/* ------------------------------------------------------------------------ */
/* Media types                                                               */

const char *meshio_media_type(meshio_format f)
{
    return meshio_fmt_of(f) ? table[f]->media : NULL;
}

int meshio_has_writer(meshio_format f)
{
    return meshio_fmt_of(f) && table[f]->write != NULL;
}

int meshio_writes_p2(meshio_format f)
{
    return meshio_has_writer(f) && table[f]->p2;
}

int meshio_writes_pdata(meshio_format f)
{
    return meshio_has_writer(f) && table[f]->pdata;
}

/* Does the parameter list [p, e) (";a=b; c=d") hold want ("a=b")? Spaces
 * around ';' and '=' and the case are ignored, quotes around the value too. */
static int has_param(const char *p, const char *e, const char *want, size_t wn)
{
    const char *eq = memchr(want, '=', wn);
    size_t kl, vl;

    if (!eq)
        return 0;
    kl = (size_t)(eq - want);
    vl = wn - kl - 1;
    while (p < e) {
        const char *k, *ke, *v, *ve;
        while (p < e && (*p == ';' || *p == ' ' || *p == '\t'))
            p++;
        for (k = p; p < e && *p != '=' && *p != ';'; p++)
            ;
        for (ke = p; ke > k && (ke[-1] == ' ' || ke[-1] == '\t'); ke--)
            ;
        if (p < e && *p == '=')
            p++;
        while (p < e && (*p == ' ' || *p == '\t' || *p == '"'))
            p++;
        for (v = p; p < e && *p != ';'; p++)
            ;
        for (ve = p; ve > v && (ve[-1] == ' ' || ve[-1] == '\t' || ve[-1] == '"'); ve--)
            ;
        if ((size_t)(ke - k) == kl && strncasecmp(k, want, kl) == 0 &&
            (size_t)(ve - v) == vl && strncasecmp(v, eq + 1, vl) == 0)
            return 1;
    }
    return 0;
}

/* Does the media type entry [m, m + n) ("type" or "type;param=value") match
 * the content type [ct, te) with parameters [semi, e)? with_param: only
 * entries with a parameter, else only those without. */
static int media_match(const char *m, size_t n, const char *ct, const char *te,
                       const char *semi, const char *e, int with_param)
{
    const char *ms = memchr(m, ';', n);
    size_t tn = ms ? (size_t)(ms - m) : n;

    if ((ms != NULL) != with_param || tn != (size_t)(te - ct) ||
        strncasecmp(ct, m, tn) != 0)
        return 0;
    return !ms || (semi && has_param(semi, e, ms + 1, n - tn - 1));
}

/* The format one of whose media types matches (see media_match). */
static meshio_format media_format(const char *ct, const char *te, const char *semi,
                                  const char *e, int with_param)
{
    for (int f = 1; f < MESHIO_FORMAT_COUNT; f++) {
        const char *l = table[f]->media_alt;
        if (table[f]->media && media_match(table[f]->media, strlen(table[f]->media), ct,
                                           te, semi, e, with_param))
            return (meshio_format)f;
        while (l && *l) {
            size_t k = strcspn(l, " ");
            if (media_match(l, k, ct, te, semi, e, with_param))
                return (meshio_format)f;
            l += k;
            l += *l == ' ';
        }
    }
    return MESHIO_AUTO;
}

meshio_format meshio_format_from_media_type(const char *ct)
{
    const char *semi, *e, *te;
    meshio_format f;

    if (!ct)
        return MESHIO_AUTO;
    while (*ct == ' ' || *ct == '\t')
        ct++;
    e = ct + strlen(ct);
    semi = memchr(ct, ';', (size_t)(e - ct));
    te = semi ? semi : e;
    while (te > ct && (te[-1] == ' ' || te[-1] == '\t'))
        te--;
    /* a variant's parameter first ("model/vnd.gmsh;version=2.2"), then the type */
    f = media_format(ct, te, semi, e, 1);
    return f != MESHIO_AUTO ? f : media_format(ct, te, semi, e, 0);
}

/* ------------------------------------------------------------------------ */
/* Reading                                                                   */

qdc_status meshio_read(const char *buf, size_t len, meshio_format fmt, mesh_t **out,
                       qdc_error *err)
{
    return meshio_read_ex(buf, len, fmt, NULL, out, err);
}

/* One plain (not gzip) buffer in format fmt; rec NULL or to be filled. */
static qdc_status read_plain(const char *buf, size_t len, meshio_format fmt,
                             const meshio_options *o, srcrec *rec, mesh_t **out,
                             qdc_error *err)
{
    const meshio_fmt *d;

    if (fmt == MESHIO_AUTO)
        fmt = meshio_sniff(buf, len);
    if (fmt == MESHIO_AUTO)
        return qdc_fail(err, QDC_EFORMAT, "unrecognized mesh format");
    d = meshio_fmt_of(fmt);
    if (!d)
        return qdc_fail(err, QDC_EINVAL, "unknown format %d", (int)fmt);
    return d->read(buf, len, o, d->splices ? rec : NULL, out, err);
}

qdc_status meshio_gunzip(const char *buf, size_t len, const meshio_options *o,
                         char **plain, size_t *plen, qdc_error *err)
{
    qdc_status st;

    *plain = NULL;
    *plen = 0;
    st = gz_inflate_max(buf, len,
                        gz_budget(len, o ? o->max_bytes : 0, o ? o->max_ratio : 0), plain,
                        plen, err);
    if (st == QDC_OK && gz_is_gzip(*plain, *plen))
        st = qdc_fail(err, QDC_EPARSE, "gzip: compressed twice");
    if (st != QDC_OK) {
        qdc_free(*plain);
        *plain = NULL;
        *plen = 0;
    }
    return st;
}

/* buf (gzip or not) into *out; keep: attach the (decompressed) buffer as the
 * mesh's source. own: buf is qdc_malloc'ed and ours to take (it is then
 * always consumed, freed or kept). */
static qdc_status read_buf(char *buf, size_t len, int own, meshio_format fmt,
                           const meshio_options *o, int keep, mesh_t **out,
                           qdc_error *err)
{
    srcrec rec;
    qdc_status st;

    if (gz_is_gzip(buf, len)) {
        /* a gzip-compressed file of any format: read what it holds */
        char *plain = NULL;
        size_t plen = 0;
        st = meshio_gunzip(buf, len, o, &plain, &plen, err);
        if (own)
            qdc_free(buf);
        if (st != QDC_OK)
            return st;
        return read_buf(plain, plen, 1, fmt, o, keep, out, err);
    }
    srcrec_init(&rec);
    st = read_plain(buf, len, fmt, o, keep ? &rec : NULL, out, err);
    if (st == QDC_OK && keep && rec.fmt != MESHIO_AUTO) { /* a format that splices */
        st = splice_attach(*out, &rec, buf, len, own, NULL, 0, err);
        if (st == QDC_OK && own)
            own = 0; /* the source has it */
        if (st != QDC_OK) {
            mesh_free(*out);
            *out = NULL;
        }
    }
    srcrec_free(&rec);
    if (own)
        qdc_free(buf);
    return st;
}

qdc_status meshio_read_ex(const char *buf, size_t len, meshio_format fmt,
                          const meshio_options *o, mesh_t **out, qdc_error *err)
{
    qdc_error_clear(err);
    if (!out || (!buf && len))
        return qdc_fail(err, QDC_EINVAL, "meshio_read: NULL argument");
    *out = NULL;
    if (!buf)
        buf = "";
    /* not ours: never freed or kept (a source is a copy) */
    return read_buf((char *)(uintptr_t)buf, len, 0, fmt, o, o && o->source > 0, out, err);
}

/* ------------------------------------------------------------------------ */
/* Writing                                                                   */

/* part: for TetGen, 0 = .node, 1 = .ele. */
static qdc_status write_fmt(const mesh_t *m, meshio_format fmt, int part, qdc_write_fn fn,
                            void *ctx, qdc_error *err)
{
    wbuf w = {fn, ctx, NULL, 0, 0};
    qdc_status st = check_for_write(m, err);
    const meshio_fmt *d = meshio_fmt_of(fmt);
    const char *why = NULL;

    if (st != QDC_OK)
        return st;
    if (d && !d->write && !splice_ok(m, fmt, &why))
        return qdc_fail(err, QDC_EINVAL,
                        "%s: written only as the input file with new coordinates, and "
                        "here %s (qdc has no %s writer of its own)",
                        d->name, why, d->name);
    if (d && d->write && m->mid && !d->p2 && !splice_ok(m, fmt, &why))
        return qdc_fail(err, QDC_EINVAL,
                        "%s: second-order (10-node) tets are written only as the input "
                        "file with new coordinates, and here %s (qdc's %s writer writes "
                        "linear tets)",
                        d->name, why, d->name);
    if (!fn)
        return qdc_fail(err, QDC_EINVAL, "meshio_write: NULL write function");
    w.b = qdc_malloc(WB_CAP);
    if (!w.b)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the write buffer");
    if (splice_ok(m, fmt, NULL))
        st = splice_write(m, part, &w, err);
    else if (d)
        st = d->write(m, fmt, part, &w, err);
    else
        st = qdc_fail(err, QDC_EINVAL, "cannot write format %d", (int)fmt);
    wb_flush(&w);
    qdc_free(w.b);
    if (st == QDC_OK && w.bad)
        st = qdc_fail(err, QDC_EIO, "write failed");
    return st;
}

qdc_status meshio_write(const mesh_t *m, meshio_format fmt, qdc_write_fn fn, void *ctx,
                        qdc_error *err)
{
    qdc_error_clear(err);
    if (fmt == MESHIO_AUTO)
        fmt = meshio_source_format(m);
    if (fmt == MESHIO_TETGEN)
        return qdc_fail(err, QDC_EINVAL, "TetGen is two files: use meshio_save");
    if (fmt == MESHIO_AUTO)
        return qdc_fail(err, QDC_EINVAL, "meshio_write: no format and no source file");
    return write_fmt(m, fmt, 0, fn, ctx, err);
}

/* ------------------------------------------------------------------------ */
/* Files                                                                     */

/* What a save writes: m in fmt (part 1: TetGen's .ele), or len bytes. */
typedef struct {
    const mesh_t *m;
    meshio_format fmt;
    int part;
    const void *bytes;
    size_t len;
} payload;

static qdc_status emit_payload(const void *arg, qdc_write_fn fn, void *ctx,
                               qdc_error *err)
{
    const payload *p = arg;

    if (!p->bytes)
        return write_fmt(p->m, p->fmt, p->part, fn, ctx, err);
    return fn(ctx, p->bytes, p->len) == 0 ? QDC_OK : QDC_EIO;
}

/* path with its extension replaced by ext (".node"), a .gz kept after it
 * (x.ele.gz -> x.node.gz: the two files compressed alike); a new string. */
static char *with_ext(const char *path, const char *ext)
{
    const char *e = file_path_ext(path);
    size_t len = strlen(path), keep = len, gz = file_path_gz(path) ? 3 : 0;
    size_t n = e ? (size_t)(path + len - gz - e) : 0; /* the extension's length */
    char *s;

    if ((n == 4 && strncasecmp(e, "node", 4) == 0) ||
        (n == 3 && strncasecmp(e, "ele", 3) == 0))
        keep = (size_t)(e - 1 - path);
    else
        gz = 0; /* no TetGen extension: ext appended to the whole name */
    s = qdc_malloc(keep + strlen(ext) + gz + 1);
    if (!s)
        return NULL;
    memcpy(s, path, keep);
    strcpy(s + keep, ext);
    if (gz)
        strcat(s, path + len - gz);
    return s;
}

/* The file at path, decompressed when it is gzip (within o's budget). */
static qdc_status slurp_unzipped(const char *path, const meshio_options *o, char **buf,
                                 size_t *len, qdc_error *err)
{
    char *plain = NULL;
    size_t plen = 0;
    qdc_status st = meshio_slurp(path, buf, len, err);

    if (st != QDC_OK || !gz_is_gzip(*buf, *len))
        return st;
    st = meshio_gunzip(*buf, *len, o, &plain, &plen, err);
    qdc_free(*buf);
    *buf = plain;
    *len = plen;
    return st;
}

static qdc_status load_tetgen(const char *path, const meshio_options *o, int keep,
                              mesh_t **out, qdc_error *err)
{
    char *np = with_ext(path, ".node"), *ep = with_ext(path, ".ele");
    char *nb = NULL, *eb = NULL;
    size_t nl = 0, el = 0;
    qdc_status st;

    if (!np || !ep)
        st = qdc_fail(err, QDC_ENOMEM, "out of memory");
    else
        st = slurp_unzipped(np, o, &nb, &nl, err);
    if (st == QDC_OK)
        st = slurp_unzipped(ep, o, &eb, &el, err);
    if (st == QDC_OK) {
        srcrec rec;
        srcrec_init(&rec);
        *out = NULL;
        st = meshio_tetgen_read2(nb, nl, eb, el, keep ? &rec : NULL, out, err);
        if (st == QDC_OK && keep) {
            st = splice_attach(*out, &rec, nb, nl, 1, eb, el, err);
            if (st == QDC_OK)
                nb = NULL; /* the source has it */
            else {
                mesh_free(*out);
                *out = NULL;
            }
        }
        srcrec_free(&rec);
    }
    qdc_free(nb);
    qdc_free(eb);
    qdc_free(np);
    qdc_free(ep);
    return st;
}

qdc_status meshio_load(const char *path, meshio_format fmt, mesh_t **out, qdc_error *err)
{
    return meshio_load_ex(path, fmt, NULL, out, err);
}

qdc_status meshio_load_ex(const char *path, meshio_format fmt, const meshio_options *o,
                          mesh_t **out, qdc_error *err)
{
    char *buf = NULL;
    size_t len = 0;
    const char *ext;
    int keep = !o || o->source >= 0;
    qdc_status st;

    qdc_error_clear(err);
    if (!path || !out)
        return qdc_fail(err, QDC_EINVAL, "meshio_load: NULL argument");
    *out = NULL;
    ext = file_path_ext(path);
    if (fmt == MESHIO_AUTO && ext)
        fmt = ext_format(ext);
    if (fmt == MESHIO_AUTO && !file_exists(path)) {
        char *np = with_ext(path, ".node");
        if (np && file_exists(np))
            fmt = MESHIO_TETGEN;
        qdc_free(np);
    }
    if (fmt == MESHIO_TETGEN)
        return load_tetgen(path, o, keep, out, err);
    st = meshio_slurp(path, &buf, &len, err);
    if (st == QDC_OK)
        st = read_buf(buf, len, 1, fmt, o, keep, out, err); /* takes buf */
    if (st == QDC_OK && keep) {
        st = splice_set_path(*out, path, err);
        if (st != QDC_OK) {
            mesh_free(*out);
            *out = NULL;
        }
    }
    return st;
}

/* The format an extension stands for: the first of its family. */
static meshio_format family(meshio_format f)
{
    return meshio_fmt_of(f) ? (meshio_format)family_of(f) : f;
}

meshio_format meshio_format_variant(meshio_format named, meshio_format src)
{
    return named != MESHIO_AUTO && family(named) == family(src) ? src : named;
}

meshio_format meshio_save_format(const char *path, meshio_format fmt, const mesh_t *m)
{
    const char *ext = path ? file_path_ext(path) : NULL;
    meshio_format src = meshio_source_format(m);

    if (fmt != MESHIO_AUTO)
        return fmt;
    if (!ext) /* /dev/stdout, a pipe, a name without one: the input's format */
        return src;
    return meshio_format_variant(ext_format(ext), src);
}

qdc_status meshio_save(const char *path, meshio_format fmt, const mesh_t *m,
                       qdc_error *err)
{
    char *np, *ep;
    qdc_status st;

    qdc_error_clear(err);
    if (!path || !m)
        return qdc_fail(err, QDC_EINVAL, "meshio_save: NULL argument");
    fmt = meshio_save_format(path, fmt, m);
    if (fmt == MESHIO_AUTO)
        return qdc_fail(err, QDC_EFORMAT, "cannot tell the format of %s", path);
    if (fmt != MESHIO_TETGEN)
        return file_save(path, emit_payload, &(payload){m, fmt, 0, NULL, 0}, err);
    {
        char *target;
        int route = file_save_route(path, &target);
        qdc_free(target);
        if (route != 0)
            return qdc_fail(err, route < 0 ? QDC_ENOMEM : QDC_EINVAL,
                            "TetGen's format is two files (.node and .ele): give "
                            "their name, or another format");
    }
    np = with_ext(path, ".node");
    ep = with_ext(path, ".ele");
    if (!np || !ep)
        st = qdc_fail(err, QDC_ENOMEM, "out of memory");
    else
        st = file_save(np, emit_payload, &(payload){m, fmt, 0, NULL, 0}, err);
    if (st == QDC_OK)
        st = file_save(ep, emit_payload, &(payload){m, fmt, 1, NULL, 0}, err);
    qdc_free(np);
    qdc_free(ep);
    return st;
}

qdc_status meshio_save_bytes(const char *path, const void *buf, size_t len,
                             qdc_error *err)
{
    qdc_error_clear(err);
    if (!path || (!buf && len))
        return qdc_fail(err, QDC_EINVAL, "meshio_save_bytes: NULL argument");
    return file_save(path, emit_payload,
                     &(payload){NULL, MESHIO_AUTO, 0, buf ? buf : "", len}, err);
}
