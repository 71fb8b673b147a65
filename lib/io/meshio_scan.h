/* meshio_scan.h - internal to the meshio_* modules: the text scanner, number
 * parsers, error helpers, growable arrays, the parsed-mesh builder and the
 * buffered writer shared by every format. Not a public header.
 *
 * Text numbers take an exact fast path (Clinger: an integer mantissa below
 * 2^53 times or divided by an exact power of ten is one correctly rounded
 * operation) and fall back to strtod otherwise; writers print %.17g. Together
 * these make write-then-read the identity on every double.
 *
 * Everything is static inline so the hot scanners inline into each parser. */
#ifndef QDC_MESHIO_SCAN_H
#define QDC_MESHIO_SCAN_H

#include "core/base.h"
#include "core/mesh_int.h"
#include "io/meshio.h"
#include "io/numfmt.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static inline int is_space(unsigned char c)
{
    return c == ' ' || c == '\n' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

static inline int is_alpha(unsigned char c)
{
    return (c | 0x20) >= 'a' && (c | 0x20) <= 'z';
}

static inline int is_word(unsigned char c)
{
    return is_alpha(c) || (c >= '0' && c <= '9') || c == '_';
}

static inline int word_is(const char *w, size_t n, const char *kw)
{
    return strlen(kw) == n && strncasecmp(w, kw, n) == 0;
}

/* ------------------------------------------------------------------------ */
/* Errors                                                                    */

static inline qdc_status vfail_at(qdc_error *err, qdc_status st, int64_t line,
                                  int64_t col, int64_t offset, const char *fmt,
                                  va_list ap)
{
    char msg[sizeof err->msg];

    if (!err)
        return st;
    vsnprintf(msg, sizeof msg, fmt, ap);
    qdc_fail(err, st, "%s", msg);
    err->line = line;
    err->col = col;
    err->offset = offset;
    return st;
}

/* A binary input failed at byte offset `off`. */
static inline qdc_status fail_bin(qdc_error *err, qdc_status st, int64_t off,
                                  const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static inline qdc_status fail_bin(qdc_error *err, qdc_status st, int64_t off,
                                  const char *fmt, ...)
{
    va_list ap;

    va_start(ap, fmt);
    vfail_at(err, st, -1, -1, off, fmt, ap);
    va_end(ap);
    return st;
}

/* What err->kind calls an entry of section sect. */
static inline const char *elem_kind(const char *sect)
{
    if (strcmp(sect, "Tetrahedra") == 0 || strcmp(sect, "TetrahedraP2") == 0 ||
        strcmp(sect, "tets") == 0)
        return "tet";
    if (strcmp(sect, "Triangles") == 0)
        return "triangle";
    if (strcmp(sect, "vertices") == 0)
        return "vertex";
    return "entry";
}

static inline void set_index(qdc_error *err, const char *kind, int64_t index)
{
    if (!err)
        return;
    err->index = index;
    snprintf(err->kind, sizeof err->kind, "%s", kind);
}

/* ------------------------------------------------------------------------ */
/* Text scanning                                                             */

typedef struct {
    const char *base, *p, *end;
    const char *bol; /* beginning of the current line */
    int64_t line;    /* 1-based */
    int hash;        /* '#' starts a comment (Medit, TetGen; not JSON) */
} txt;

static inline txt txt_init(const char *buf, size_t len, int hash)
{
    txt s;

    s.base = s.p = s.bol = buf;
    s.end = buf + len;
    s.line = 1;
    s.hash = hash;
    return s;
}

static inline void skip_ws(txt *s)
{
    const char *p = s->p, *end = s->end;

    while (p < end) {
        char c = *p;
        if (c == '\n') {
            s->line++;
            s->bol = ++p;
        } else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
            p++;
        } else if (c == '#' && s->hash) {
            while (p < end && *p != '\n')
                p++;
        } else {
            break;
        }
    }
    s->p = p;
}

/* End of the whitespace-delimited token starting at t. */
static inline const char *tok_end(const txt *s, const char *t)
{
    const char *p = t;

    while (p < s->end && !is_space((unsigned char)*p) && !(*p == '#' && s->hash))
        p++;
    return p;
}

/* Printable copy of a token for messages: at most 24 bytes, non-ASCII as '?'
 * (messages end up in JSON replies, which must be valid UTF-8). */
static inline const char *quote_tok(char out[32], const txt *s, const char *t,
                                    const char *te)
{
    size_t n = 0;

    if (t >= s->end)
        return "end of input";
    if (te <= t)
        te = t + 1;
    out[n++] = '\'';
    for (; t < te && n < 25; t++)
        out[n++] = (*t >= 0x20 && *t < 0x7f) ? *t : '?';
    if (t < te) {
        out[n++] = '.';
        out[n++] = '.';
    }
    out[n++] = '\'';
    out[n] = '\0';
    return out;
}

static inline qdc_status fail_txt(qdc_error *err, qdc_status st, const txt *s,
                                  const char *at, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));

static inline qdc_status fail_txt(qdc_error *err, qdc_status st, const txt *s,
                                  const char *at, const char *fmt, ...)
{
    va_list ap;

    va_start(ap, fmt);
    vfail_at(err, st, s->line, at - s->bol + 1, at - s->base, fmt, ap);
    va_end(ap);
    return st;
}

/* strtod on a NUL-terminated copy of [t, te). */
static inline int slow_double(const char *t, const char *te, double *out)
{
    char tmp[512];
    char *endp;
    size_t n = (size_t)(te - t);

    if (n == 0 || n >= sizeof tmp)
        return -1;
    memcpy(tmp, t, n);
    tmp[n] = '\0';
    *out = strtod(tmp, &endp);
    return endp == tmp + n ? 0 : -1;
}

/* Decimal [t, te) to double, correctly rounded. Returns 0, or -1 on bad syntax.
 * Trailing zeros of the mantissa are held back (5.0000000000000000e-01 is 5e-1),
 * which keeps most printed values on the exact fast path. */
static inline int parse_double(const char *t, const char *te, double *out)
{
    static const double pow10_exact[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                           1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                           1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
    const char *p = t;
    uint64_t m = 0;
    int neg = 0, nd = 0, ndig = 0, frac = 0, pend = 0, pend_frac = 0;
    int64_t e10 = 0, ex = 0;

    if (p < te && (*p == '+' || *p == '-'))
        neg = *p++ == '-';
    for (; p < te; p++) {
        unsigned d = (unsigned)(unsigned char)*p - '0';
        if (d > 9) {
            if (*p == '.' && !frac) {
                frac = 1;
                continue;
            }
            break;
        }
        ndig++;
        if (d == 0) {
            if (m) {
                pend++;
                pend_frac += frac;
            } else {
                e10 -= frac;
            }
            continue;
        }
        if (nd + pend >= 19)
            return slow_double(t, te, out);
        nd += pend + 1;
        for (; pend; pend--)
            m *= 10;
        e10 -= pend_frac + frac;
        pend_frac = 0;
        m = m * 10 + d;
    }
    if (ndig == 0)
        return slow_double(t, te, out); /* "inf", "nan", hex: strtod decides */
    e10 += pend - pend_frac;
    if (p < te && (*p == 'e' || *p == 'E')) {
        int eneg = 0, edig = 0;
        p++;
        if (p < te && (*p == '+' || *p == '-'))
            eneg = *p++ == '-';
        for (; p < te && (unsigned)(unsigned char)*p - '0' <= 9; p++, edig++)
            if (ex < 100000)
                ex = ex * 10 + (*p - '0');
        if (!edig)
            return -1;
        e10 += eneg ? -ex : ex;
    }
    if (p != te)
        return -1;
    if (m == 0) {
        *out = neg ? -0.0 : 0.0;
        return 0;
    }
    if (m > (UINT64_C(1) << 53) || e10 < -22 || e10 > 22) {
        /* 17-19 digits (a coordinate printed with %.17g): exact integer
         * arithmetic (numfmt.h) where strtod took 60% of a large file's parse */
        if (e10 < -27 || e10 > 27 || !numfmt_decimal(m, (int)e10, out))
            return slow_double(t, te, out);
        if (neg)
            *out = -*out;
        return 0;
    }
    *out = e10 < 0 ? (double)m / pow10_exact[-e10] : (double)m * pow10_exact[e10];
    if (neg)
        *out = -*out;
    return 0;
}

/* A Fortran or Nastran real [t, te) (no blanks): an exponent after D as
 * after E ("1.5D-03"), or after a bare sign ("1.-3" = 1e-3, "-.5+2" = -50).
 * Returns 0, or -1 on bad syntax. */
static inline int parse_fortran_real(const char *t, const char *te, double *out)
{
    char tmp[64];
    size_t n = (size_t)(te - t), k = 0;

    for (size_t i = 0; i < n; i++) {
        char c = t[i];
        if (c == 'D' || c == 'd' ||
            ((c == '+' || c == '-') && i > 0 &&
             ((t[i - 1] >= '0' && t[i - 1] <= '9') || t[i - 1] == '.')))
            break;
        if (i + 1 == n)
            return parse_double(t, te, out); /* no D, no bare-sign exponent */
    }
    if (n + 2 > sizeof tmp)
        return -1;
    /* one exponent marker at most: a second is left as it is and fails the
     * syntax check, so tmp holds n + 1 characters at most */
    for (size_t i = 0, marked = 0; i < n; i++) {
        char c = t[i];
        if ((c == 'D' || c == 'd') && !marked) {
            c = 'e';
            marked = 1;
        } else if ((c == '+' || c == '-') && i > 0 && !marked &&
                   ((t[i - 1] >= '0' && t[i - 1] <= '9') || t[i - 1] == '.')) {
            tmp[k++] = 'e';
            marked = 1;
        }
        tmp[k++] = c;
    }
    return parse_double(tmp, tmp + k, out);
}

/* Integer [t, te). strict (JSON): no '+', no leading zeros. Returns 0, -1 on
 * bad syntax, -2 when the magnitude is beyond any count or index. */
static inline int parse_int(const char *t, const char *te, int strict, int64_t *out)
{
    const char *p = t;
    uint64_t u = 0;
    int neg = 0, big = 0;

    if (p < te && (*p == '-' || (*p == '+' && !strict)))
        neg = *p++ == '-';
    if (p == te || (strict && *p == '0' && te - p > 1))
        return -1;
    for (; p < te; p++) {
        unsigned d = (unsigned)(unsigned char)*p - '0';
        if (d > 9)
            return -1;
        if (u > UINT64_C(100000000000000000))
            big = 1;
        else
            u = u * 10 + d;
    }
    if (big)
        return -2;
    *out = neg ? -(int64_t)u : (int64_t)u;
    return 0;
}

/* The token [t, te) as an integer in [lo, hi]; on success the scanner moves past it. */
static inline qdc_status tok_int(txt *s, const char *t, const char *te, int strict,
                                 const char *what, int64_t lo, int64_t hi, int64_t *v,
                                 qdc_error *err)
{
    char q[32];
    int rc;

    if (t == s->end)
        return fail_txt(err, QDC_EPARSE, s, t, "%s: unexpected end of input", what);
    rc = parse_int(t, te, strict, v);
    if (rc == -1)
        return fail_txt(err, QDC_EPARSE, s, t, "%s: expected an integer, got %s", what,
                        quote_tok(q, s, t, tok_end(s, t)));
    if (rc == -2 || *v < lo || *v > hi) /* the token is digits: print it as is */
        return fail_txt(err, QDC_EPARSE, s, t, "%s %.*s%s out of range [%lld, %lld]",
                        what, te - t > 24 ? 24 : (int)(te - t), t,
                        te - t > 24 ? ".." : "", (long long)lo, (long long)hi);
    s->p = te;
    return QDC_OK;
}

static inline qdc_status tok_real(txt *s, const char *t, const char *te, const char *what,
                                  double *v, qdc_error *err)
{
    char q[32];

    if (t == s->end)
        return fail_txt(err, QDC_EPARSE, s, t, "%s: unexpected end of input", what);
    if (parse_double(t, te, v) != 0)
        return fail_txt(err, QDC_EPARSE, s, t, "%s: expected a number, got %s", what,
                        quote_tok(q, s, t, tok_end(s, t)));
    if (!isfinite(*v))
        return fail_txt(err, QDC_EPARSE, s, t, "%s %s is not finite (NaN/Inf)", what,
                        quote_tok(q, s, t, te));
    s->p = te;
    return QDC_OK;
}

/* txt_int's common case in one pass (txt_int tries it first): up to 9 plain digits after
 * the white space, then white space or the end, within [lo, hi]: *v set, the scanner past
 * them, 1. Anything else (a sign, more digits, a comment or another character right after
 * them, out of range): 0, the scanner at the token, for txt_int to read or explain.
 * (Reading a 5M-tet Medit file: 0.6 s of integers token by token.) */
static inline int txt_uint_fast(txt *s, int64_t lo, int64_t hi, int64_t *v)
{
    const char *p, *t;
    int64_t u = 0;

    skip_ws(s);
    p = t = s->p;
    while (p < s->end && p - t < 9 && (unsigned)(*p - '0') <= 9)
        u = u * 10 + (*p++ - '0');
    if (p == t || (p < s->end && !is_space((unsigned char)*p)) || u < lo || u > hi)
        return 0;
    *v = u;
    s->p = p;
    return 1;
}

static inline qdc_status txt_int(txt *s, const char *what, int64_t lo, int64_t hi,
                                 int64_t *v, qdc_error *err)
{
    if (txt_uint_fast(s, lo, hi, v))
        return QDC_OK;
    return tok_int(s, s->p, tok_end(s, s->p), 0, what, lo, hi, v, err);
}

static inline qdc_status txt_real(txt *s, const char *what, double *v, qdc_error *err)
{
    skip_ws(s);
    return tok_real(s, s->p, tok_end(s, s->p), what, v, err);
}

/* c entries of `tokens` tokens each still to come: every token needs a
 * separator and one character, so the count is checked against the bytes left
 * before the caller allocates anything. */
static inline qdc_status txt_fits(txt *s, const char *at, const char *what, int64_t c,
                                  uint64_t tokens, qdc_error *err)
{
    size_t left = (size_t)(s->end - s->p);

    if ((uint64_t)c > left / 2 / tokens)
        return fail_txt(err, QDC_EPARSE, s, at,
                        "%s: count %lld does not fit in the %zu bytes left (truncated?)",
                        what, (long long)c, left);
    return QDC_OK;
}

/* A count of entries of at least `tokens` tokens each (see txt_fits). */
static inline qdc_status txt_count(txt *s, const char *what, int tokens, int64_t max,
                                   int64_t *c, qdc_error *err)
{
    const char *at;
    qdc_status st;

    skip_ws(s);
    at = s->p;
    st = tok_int(s, at, tok_end(s, at), 0, what, INT64_MIN, INT64_MAX, c, err);
    if (st != QDC_OK)
        return st;
    if (*c < 0)
        return fail_txt(err, QDC_EPARSE, s, at, "%s: negative count %lld", what,
                        (long long)*c);
    st = txt_fits(s, at, what, *c, (uint64_t)tokens, err);
    if (st != QDC_OK)
        return st;
    if (*c > max)
        return fail_txt(err, QDC_ETOOBIG, s, at, "%s: count %lld exceeds the limit %lld",
                        what, (long long)*c, (long long)max);
    return QDC_OK;
}

/* Nothing but whitespace and comments may follow the mesh. */
static inline qdc_status txt_done(txt *s, const char *after, qdc_error *err)
{
    char q[32];

    skip_ws(s);
    if (s->p != s->end)
        return fail_txt(err, QDC_EPARSE, s, s->p, "trailing data after %s: %s", after,
                        quote_tok(q, s, s->p, tok_end(s, s->p)));
    return QDC_OK;
}

/* ------------------------------------------------------------------------ */
/* Growable arrays (JSON, Medit sections)                                    */

typedef struct {
    void *a;
    size_t n, cap, size; /* elements used, allocated, element size */
} vec;

static inline int vec_grow(vec *v, size_t more)
{
    size_t cap;
    void *a;

    if (v->cap - v->n >= more)
        return 0;
    cap = v->cap ? v->cap : 256;
    while (cap - v->n < more) {
        if (cap > SIZE_MAX / 2 / v->size)
            return -1;
        cap *= 2;
    }
    a = qdc_realloc(v->a, cap * v->size);
    if (!a)
        return -1;
    v->a = a;
    v->cap = cap;
    return 0;
}

static inline void vec_free(vec *v)
{
    qdc_free(v->a);
    v->a = NULL;
    v->n = v->cap = 0;
}

/* ------------------------------------------------------------------------ */
/* Building the mesh                                                         */

/* Parsed arrays before they become a mesh_t; counts -1 = section absent. */
typedef struct {
    int64_t nv, nt, ntri, nfix;
    double *xyz;
    int32_t *vref, *tets, *region, *tris, *tri_ref;
    int32_t *fix; /* nfix indices of fixed vertices */
    int32_t *mid; /* second-order tets: 6*nt mid-edge nodes (mesh_p2_edges), or NULL */
} parsed;

static inline void parsed_init(parsed *pm)
{
    memset(pm, 0, sizeof *pm);
    pm->nv = pm->nt = pm->ntri = pm->nfix = -1;
}

static inline void parsed_free(parsed *pm)
{
    qdc_free(pm->xyz);
    qdc_free(pm->vref);
    qdc_free(pm->tets);
    qdc_free(pm->region);
    qdc_free(pm->tris);
    qdc_free(pm->tri_ref);
    qdc_free(pm->fix);
    qdc_free(pm->mid);
    parsed_init(pm);
}

static inline void copy_opt(void *dst, const void *src, size_t bytes)
{
    if (dst && src && bytes)
        memcpy(dst, src, bytes);
}

static inline qdc_status parsed_mesh(const parsed *pm, mesh_t **out, qdc_error *err)
{
    unsigned flags = 0;
    int64_t nt = pm->nt < 0 ? 0 : pm->nt;
    mesh_t *m;

    if (pm->vref)
        flags |= MESH_WITH_VREF;
    if (pm->region)
        flags |= MESH_WITH_REGION;
    if (pm->nfix >= 0)
        flags |= MESH_WITH_FIXED;
    m = mesh_new((int32_t)pm->nv, (int32_t)nt, flags);
    if (!m)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for a mesh of %lld vertices",
                        (long long)pm->nv);
    copy_opt(m->xyz, pm->xyz, (size_t)pm->nv * 3 * sizeof(double));
    copy_opt(m->vref, pm->vref, (size_t)pm->nv * sizeof(int32_t));
    copy_opt(m->tets, pm->tets, (size_t)nt * 4 * sizeof(int32_t));
    copy_opt(m->region, pm->region, (size_t)nt * sizeof(int32_t));
    for (int64_t i = 0; i < pm->nfix && m->fixed; i++)
        m->fixed[pm->fix[i]] = 1;
    if (pm->ntri > 0) {
        if (mesh_set_tris(m, (int32_t)pm->ntri, pm->tri_ref != NULL) != QDC_OK) {
            mesh_free(m);
            return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld triangles",
                            (long long)pm->ntri);
        }
        memcpy(m->tris, pm->tris, (size_t)pm->ntri * 3 * sizeof(int32_t));
        copy_opt(m->tri_ref, pm->tri_ref, (size_t)pm->ntri * sizeof(int32_t));
    }
    if (pm->mid) {
        if (mesh_set_mid(m) != QDC_OK) {
            mesh_free(m);
            return qdc_fail(err, QDC_ENOMEM, "out of memory for the mid-edge nodes");
        }
        memcpy(m->mid, pm->mid, (size_t)nt * 6 * sizeof(int32_t));
    }
    *out = m;
    return QDC_OK;
}

/* parsed_mesh without the copies: xyz, tets, region, vref, tris and tri_ref
 * move into the mesh (pm's pointers are NULL afterwards, also on failure,
 * when they are freed). Each must come from qdc_malloc* and hold at least
 * what the mesh needs. Without xyz or tets (a file with no tets) there is
 * nothing to hand over: parsed_mesh makes the mesh, and pm is freed. */
static inline qdc_status parsed_mesh_move(parsed *pm, mesh_t **out, qdc_error *err)
{
    mesh_t *m;
    int64_t nt = pm->nt < 0 ? 0 : pm->nt;

    if (!pm->xyz || !pm->tets) {
        qdc_status st = parsed_mesh(pm, out, err);
        parsed_free(pm);
        return st;
    }
    m = qdc_calloc(1, sizeof *m);

    if (m && pm->nfix >= 0 && !(m->fixed = qdc_calloc((size_t)pm->nv, 1))) {
        qdc_free(m);
        m = NULL;
    }
    if (!m) {
        parsed_free(pm);
        return qdc_fail(err, QDC_ENOMEM, "out of memory for a mesh of %lld vertices",
                        (long long)pm->nv);
    }
    m->nv = (int32_t)pm->nv;
    m->nt = (int32_t)nt;
    m->xyz = pm->xyz;
    m->tets = pm->tets;
    m->region = pm->region;
    m->vref = pm->vref;
    m->mid = pm->mid;
    for (int64_t i = 0; i < pm->nfix; i++)
        m->fixed[pm->fix[i]] = 1;
    if (pm->ntri > 0) {
        m->ntri = (int32_t)pm->ntri;
        m->tris = pm->tris;
        m->tri_ref = pm->tri_ref;
    } else {
        qdc_free(pm->tris);
        qdc_free(pm->tri_ref);
    }
    pm->xyz = NULL;
    pm->tets = pm->region = pm->vref = pm->tris = pm->tri_ref = pm->mid = NULL;
    *out = m;
    return QDC_OK;
}

/* Index of the first entry of idx[n] outside [0, nv), or -1. */
static inline int64_t first_bad_index(const int32_t *idx, int64_t n, int64_t nv)
{
    for (int64_t i = 0; i < n; i++)
        if (idx[i] < 0 || idx[i] >= nv)
            return i;
    return -1;
}

static inline uint32_t get_le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 |
           (uint32_t)p[3] << 24;
}

static inline uint64_t get_le64(const unsigned char *p)
{
    return (uint64_t)get_le32(p) | (uint64_t)get_le32(p + 4) << 32;
}

static inline void put_le32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static inline void put_le64(unsigned char *p, uint64_t v)
{
    put_le32(p, (uint32_t)v);
    put_le32(p + 4, (uint32_t)(v >> 32));
}

enum { WB_CAP = 65536 };

typedef struct {
    qdc_write_fn fn;
    void *ctx;
    char *b;
    size_t n;
    int bad;
} wbuf;

static inline void wb_flush(wbuf *w)
{
    if (w->n && !w->bad && w->fn(w->ctx, w->b, w->n) != 0)
        w->bad = 1;
    w->n = 0;
}

static inline void wb_put(wbuf *w, const void *d, size_t len)
{
    if (len > WB_CAP - w->n) {
        wb_flush(w);
        if (len >= WB_CAP) {
            if (!w->bad && w->fn(w->ctx, d, len) != 0)
                w->bad = 1;
            return;
        }
    }
    memcpy(w->b + w->n, d, len);
    w->n += len;
}

static inline void wb_str(wbuf *w, const char *s)
{
    wb_put(w, s, strlen(s));
}

static inline void wb_int(wbuf *w, int64_t v)
{
    char tmp[24];
    int n = sizeof tmp;
    uint64_t u = v < 0 ? 0 - (uint64_t)v : (uint64_t)v;

    do {
        tmp[--n] = (char)('0' + u % 10);
        u /= 10;
    } while (u);
    if (v < 0)
        tmp[--n] = '-';
    wb_put(w, tmp + n, sizeof tmp - (size_t)n);
}

/* x as %.17g writes it (numfmt.h: 5x faster than snprintf, the same text) */
static inline void wb_real(wbuf *w, double x)
{
    if (WB_CAP - w->n < 32)
        wb_flush(w);
    w->n += (size_t)numfmt_g17(x, w->b + w->n);
}

/* Values separated by sep, ended by end. */
static inline void wb_ints(wbuf *w, const int32_t *v, int n, int64_t add, const char *sep,
                           const char *end)
{
    for (int i = 0; i < n; i++) {
        wb_int(w, v[i] + add);
        wb_str(w, i + 1 < n ? sep : end);
    }
}

static inline void wb_reals(wbuf *w, const double *v, int n, const char *sep,
                            const char *end)
{
    for (int i = 0; i < n; i++) {
        wb_real(w, v[i]);
        wb_str(w, i + 1 < n ? sep : end);
    }
}

/* Writers refuse what no reader would take back. */
static inline qdc_status check_for_write(const mesh_t *m, qdc_error *err)
{
    if (!m || m->nv < 0 || m->nt < 0 || m->ntri < 0 || (m->nv && !m->xyz) ||
        (m->nt && !m->tets) || (m->ntri && !m->tris))
        return qdc_fail(err, QDC_EINVAL, "meshio_write: invalid mesh");
    for (int64_t i = 0; i < 3 * (int64_t)m->nv; i++)
        if (!isfinite(m->xyz[i])) {
            qdc_fail(err, QDC_EINVAL, "vertex %lld has a non-finite coordinate",
                     (long long)(i / 3));
            set_index(err, "vertex", i / 3);
            return QDC_EINVAL;
        }
    if (first_bad_index(m->tets, 4 * (int64_t)m->nt, m->nv) >= 0 ||
        first_bad_index(m->tris, 3 * (int64_t)m->ntri, m->nv) >= 0)
        return qdc_fail(err, QDC_EINVAL, "meshio_write: vertex index out of range");
    return QDC_OK;
}

/* ------------------------------------------------------------------------ */
/* Notes and skipped element types                                           */

static inline void note(const meshio_options *o, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static inline void note(const meshio_options *o, const char *fmt, ...)
{
    char msg[256];
    va_list ap;

    if (!o || !o->log)
        return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    o->log(o->log_ctx, 0, msg);
}

/* A point-data array a reader read: nv tuples of ncomp values v (from
 * qdc_malloc*, taken over) appended to *pd for the mesh (mesh.h, "Point
 * data"). An array with a NaN/Inf value is dropped with a note, not an
 * error: such files read as they did before point data was kept; an integer
 * type holding 1.5 (text) makes a floating array. An empty name or ncomp < 1:
 * dropped silently. QDC_ENOMEM. */
static inline qdc_status pdata_take(mesh_pdata **pd, int64_t nv, const char *name,
                                    size_t nlen, int64_t ncomp, int integer,
                                    const char *type, double *v, const meshio_options *o,
                                    const char *fmtname, qdc_error *err)
{
    size_t n = (size_t)nv * (size_t)(ncomp > 0 ? ncomp : 0);
    mesh_t shell;
    qdc_error e;
    qdc_status st;

    if (!nlen || ncomp < 1 || ncomp > INT32_MAX || nv < 0 || nv > INT32_MAX) {
        qdc_free(v);
        return QDC_OK;
    }
    /* 1.5 in the text of an int array: a floating one (NaN too: refused below) */
    for (size_t i = 0; integer && i < n; i++)
        integer = v[i] == floor(v[i]);
    for (size_t i = 0; integer && i < n; i++)
        v[i] += 0.0; /* -0 read from text: the integer 0 */
    memset(&shell, 0, sizeof shell);
    shell.nv = (int32_t)nv;
    shell.pdata = *pd;
    qdc_error_clear(&e);
    st = mesh_pdata_add(&shell, name, nlen, (int32_t)ncomp, integer, type, v, &e);
    *pd = shell.pdata;
    if (st == QDC_EINVAL) { /* a value NaN or Inf (v freed): e.msg says which */
        const char *why = strstr(e.msg, ": value ");
        note(o, "%s: point data %.*s dropped%s", fmtname, (int)(nlen > 64 ? 64 : nlen),
             name, why ? why : "");
        return QDC_OK;
    }
    return st == QDC_OK ? QDC_OK : qdc_fail(err, st, "%s", e.msg);
}

/* Point-data array i's name as a writer puts it in a file whose names are
 * one word: bytes other than [A-Za-z0-9_.:+-] become '_' (at most 255). */
static inline void pdata_word(const mesh_parray *a, char out[256])
{
    size_t k = 0;

    for (const char *c = a->name; *c && k < 255; c++, k++) {
        char x = *c;
        int ok = (x >= 'a' && x <= 'z') || (x >= 'A' && x <= 'Z') ||
                 (x >= '0' && x <= '9') || x == '_' || x == '.' || x == ':' || x == '+' ||
                 x == '-';
        out[k] = ok ? x : '_';
    }
    out[k] = 0;
    if (!strcmp(out, "NULL") || !strcmp(out, "METADATA") || !k) /* keywords of FIELD */
        snprintf(out + k, 256 - k, "_");
}

/* How a writer writes array a's values: 4 (int32) or 8 (int64) bytes for an
 * integer array whose every value fits, 0 as doubles (a float array, or
 * integers beyond int64). */
static inline int pdata_ikind(const mesh_parray *a, int64_t nv)
{
    int k = a->integer ? 4 : 0;

    for (size_t i = 0; k && i < (size_t)nv * (size_t)a->ncomp; i++) {
        double x = a->v[i];
        if (x >= INT32_MIN && x <= INT32_MAX)
            continue;
        k = x >= -9223372036854775808.0 && x < 9223372036854775808.0 ? 8 : 0;
    }
    return k;
}

/* Element or cell types a reader skipped, counted for one note at the end. */
enum { SKIP_TYPES = 128 };

typedef struct {
    int64_t n[SKIP_TYPES + 1]; /* last slot: types >= SKIP_TYPES or negative */
} skipped;

static inline void skip_count(skipped *sk, int64_t type, int64_t count)
{
    sk->n[type >= 0 && type < SKIP_TYPES ? type : SKIP_TYPES] += count;
}

/* "skipped 12 elements of type 15, 40 of type 1" through o->log. */
static inline void skip_note(const meshio_options *o, const skipped *sk,
                             const char *fmtname, const char *what)
{
    char msg[200];
    size_t n = 0;

    for (int t = 0; t <= SKIP_TYPES && n < sizeof msg - 40; t++) {
        if (!sk->n[t])
            continue;
        n += (size_t)snprintf(msg + n, sizeof msg - n, "%s%lld %s of type %s%d",
                              n ? ", " : "", (long long)sk->n[t], n ? "" : what,
                              t == SKIP_TYPES ? ">=" : "", t);
    }
    if (n)
        note(o, "%s: skipped %s (only tetrahedra and triangles are read)", fmtname, msg);
}

/* Regions from per-element physical tags phys[] (0 = none) and entity tags
 * ent[]: the physical tags if any is non-zero, else the entity tags if they
 * differ, else none (NULL). Returns the array to keep (phys or ent) and frees
 * the other; *out NULL when neither is kept. */
static inline void pick_regions(int32_t *phys, int32_t *ent, int64_t n, int32_t **out)
{
    int any = 0, differ = 0;

    for (int64_t i = 0; i < n && !any; i++)
        any = phys[i] != 0;
    for (int64_t i = 1; i < n && !any && !differ; i++)
        differ = ent[i] != ent[0];
    *out = any ? phys : differ ? ent : NULL;
    if (*out != phys)
        qdc_free(phys);
    if (*out != ent)
        qdc_free(ent);
}

/* ------------------------------------------------------------------------ */
/* Node tag -> index (Gmsh, Abaqus) */

typedef struct {
    int64_t lo;      /* dense: index of tag t is dense[t - lo] (-1 = none) */
    int64_t n;       /* entries of dense or of sorted */
    int32_t *dense;  /* either this ... */
    int64_t *sorted; /* ... or (tag << 31 | index) pairs sorted by tag */
} tagmap;

static inline int cmp_i64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;

    return (x > y) - (x < y);
}

/* Build the map of tags[nv] (each in [1, 2^31)); the index of a duplicate
 * tag in *dup (or -1). */
static inline qdc_status tagmap_build(tagmap *tm, const int64_t *tags, int64_t nv,
                                      int64_t *dup, qdc_error *err)
{
    int64_t lo = INT64_MAX, hi = 0;

    *dup = -1;
    for (int64_t i = 0; i < nv; i++) {
        lo = tags[i] < lo ? tags[i] : lo;
        hi = tags[i] > hi ? tags[i] : hi;
    }
    if (nv && hi - lo < 4 * nv + 16) {
        tm->lo = lo;
        tm->n = hi - lo + 1;
        tm->dense = qdc_mallocn((size_t)tm->n, sizeof(int32_t));
        if (!tm->dense)
            return qdc_fail(err, QDC_ENOMEM, "out of memory for the node tags");
        memset(tm->dense, 0xff, (size_t)tm->n * sizeof(int32_t));
        for (int64_t i = 0; i < nv; i++) {
            if (tm->dense[tags[i] - lo] >= 0) {
                *dup = i;
                return QDC_OK;
            }
            tm->dense[tags[i] - lo] = (int32_t)i;
        }
        return QDC_OK;
    }
    tm->n = nv;
    tm->sorted = qdc_mallocn((size_t)nv + 1, sizeof(int64_t));
    if (!tm->sorted)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the node tags");
    for (int64_t i = 0; i < nv; i++)
        tm->sorted[i] = tags[i] << 31 | i;
    qsort(tm->sorted, (size_t)nv, sizeof(int64_t), cmp_i64);
    for (int64_t i = 1; i < nv; i++)
        if (tm->sorted[i] >> 31 == tm->sorted[i - 1] >> 31) {
            *dup = tm->sorted[i] & INT32_MAX;
            return QDC_OK;
        }
    return QDC_OK;
}

/* Index of node tag t, or -1. */
static inline int64_t tagmap_find(const tagmap *tm, int64_t t)
{
    int64_t a = 0, b = tm->n;

    if (tm->dense)
        return t >= tm->lo && t - tm->lo < tm->n ? tm->dense[t - tm->lo] : -1;
    while (a < b) {
        int64_t mid = a + (b - a) / 2, mt = tm->sorted[mid] >> 31;
        if (mt == t)
            return tm->sorted[mid] & INT32_MAX;
        if (mt < t)
            a = mid + 1;
        else
            b = mid;
    }
    return -1;
}

/* ids[n] to indices out[n]; the position of the first id no node has, or -1. */
static inline int64_t tagmap_indices(const tagmap *tm, const int64_t *ids, size_t n,
                                     int32_t *out)
{
    for (size_t i = 0; i < n; i++) {
        int64_t v = tagmap_find(tm, ids[i]);
        if (v < 0)
            return (int64_t)i;
        out[i] = (int32_t)v;
    }
    return -1;
}

/* s->line and s->bol of the byte at (for an error found after the scan). */
static inline void txt_locate(txt *s, const char *at)
{
    s->line = 1;
    s->bol = s->base;
    for (const char *p = s->base; p < at && p < s->end; p++)
        if (*p == '\n') {
            s->line++;
            s->bol = p + 1;
        }
}

static inline void tagmap_free(tagmap *tm)
{
    qdc_free(tm->dense);
    qdc_free(tm->sorted);
    memset(tm, 0, sizeof *tm);
}

/* ------------------------------------------------------------------------ */
/* Where the coordinates are (splice.c)                                      */

/* What a reader records, when asked (rec not NULL), so that the file can be
 * written back with only the coordinates replaced. Offsets are bytes into
 * the buffer the reader was given. */
enum {
    SRC_NONE = 0, /* nothing recorded (or a layout that cannot be spliced: why) */
    SRC_TEXT,     /* off[v]: first byte of vertex v's x token; y, z follow as
                     tokens (whitespace, '#' comments if hash, '<' ends a
                     token if lt) */
    SRC_BIN,      /* off[v]: first byte of x; y, z follow, `width` bytes each */
    SRC_TEXT3,    /* off[3v + a]: first byte of coordinate a of vertex v, in
                     increasing order; a token ends at whitespace, ',', a quote
                     or '<' (XML attributes, Abaqus comma lists) */
    SRC_BLOCK,    /* VTU base64 or zlib Points: bytes [blk_a, blk_b) re-encoded */
    SRC_FIELD     /* off[3v + a]: coordinate a of vertex v in a field of the
                     line, increasing: FIELD_AT(off) its first byte,
                     FIELD_WIDTH(off) its width; FIELD_FREE: the field is the
                     token there (ends at blank, ',' or '$') and the new text
                     replaces it unpadded, at most the width; else the new
                     text, right-aligned, fills the width (Nastran fixed
                     fields, I-DEAS columns); FIELD_EXP: Fortran form
                     (1.2500000000000000D-01, the letter kept), else Nastran's
                     (a '.' always, "1.25-1" if that is what fits) */
};
#define FIELD_FREE (UINT64_C(1) << 62)
#define FIELD_EXP (UINT64_C(1) << 61)
#define FIELD_AT(o) ((size_t)((o) & ((UINT64_C(1) << 48) - 1)))
#define FIELD_WIDTH(o) ((int)(((o) >> 48) & 0xff))
#define FIELD(at, width, flags) ((uint64_t)(at) | (uint64_t)(width) << 48 | (flags))
/* SRC_TEXT3 offsets with SRC_BLANK: the coordinate is not in the file (a
 * blank field, read as 0) and the offset is where its value goes if it is not
 * 0 when written; with SRC_COMMA too, a field left out at the end of the line:
 * ", value" goes there, after those left out before it. */
#define SRC_BLANK (UINT64_C(1) << 63)
#define SRC_COMMA (UINT64_C(1) << 62)

/* Values in the file that are derived from the coordinates, recomputed by a
 * spliced write (splice.c): Gmsh 4.x $Entities bounding boxes (DV_BOXES),
 * VTU Points RangeMin/RangeMax, the range of the point norms (DV_NORMS). */
enum { DV_NONE = 0, DV_BOXES, DV_NORMS };

typedef struct {
    int32_t dim, nval; /* nval: 3 (a 4.1 point: its coordinates) or 6 */
    int64_t tag, val;  /* val: index of its first value */
    int64_t bnd, nbnd; /* its bounding entities: bnd.a[bnd .. bnd + nbnd) */
} dv_ent;

typedef struct {
    int kind, bin;      /* bin: float64 little-endian values, else text tokens */
    vec off;            /* uint64: byte offset of each value, increasing */
    vec file;           /* double: each value as in the file */
    vec ref;            /* double: each computed from the coordinates read (dv_finish) */
    vec ent;            /* DV_BOXES: dv_ent per $Entities entity */
    vec bnd;            /* int64: bounding entity tags, then (dv_finish) indices */
    vec blk;            /* int64 quadruples: $Nodes block dim, tag (then: entity
                           index), first vertex, count */
    int64_t imin, imax; /* DV_NORMS: value index of RangeMin, RangeMax or -1 */
} derived;

static inline void dv_init(derived *d)
{
    memset(d, 0, sizeof *d);
    d->off.size = d->bnd.size = d->blk.size = sizeof(int64_t);
    d->file.size = d->ref.size = sizeof(double);
    d->ent.size = sizeof(dv_ent);
    d->imin = d->imax = -1;
}

static inline void dv_free(derived *d)
{
    vec_free(&d->off);
    vec_free(&d->file);
    vec_free(&d->ref);
    vec_free(&d->ent);
    vec_free(&d->bnd);
    vec_free(&d->blk);
    dv_init(d);
}

/* One more value at byte offset off, as read (file). QDC_ENOMEM. */
static inline qdc_status dv_value(derived *d, uint64_t off, double file, qdc_error *err)
{
    if (vec_grow(&d->off, 1) != 0 || vec_grow(&d->file, 1) != 0)
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    ((uint64_t *)d->off.a)[d->off.n++] = off;
    ((double *)d->file.a)[d->file.n++] = file;
    return QDC_OK;
}

/* Check and resolve what the reader recorded and compute the values from
 * the coordinates read; what does not hold together (offsets out of order,
 * a tag of no entity) is dropped: the file's values are then kept as read.
 * QDC_ENOMEM only. */
qdc_status dv_finish(derived *d, const double *xyz, int64_t nv, qdc_error *err);

typedef struct {
    int kind;
    meshio_format fmt; /* the file's own variant (version, encoding) */
    int64_t nv;
    uint64_t *off;   /* nv offsets (SRC_TEXT, SRC_BIN) */
    int hash, lt;    /* SRC_TEXT tokenizing */
    int width, big;  /* value size 4 (float32) or 8, byte order (BIN, BLOCK) */
    const char *why; /* SRC_NONE: why the layout is not kept */
    /* SRC_BLOCK */
    uint64_t blk_a, blk_b;
    int b64, b64_sep; /* base64, header and data encoded separately */
    int zlib, hdr8;   /* vtkZLibDataCompressor blocks; header words of 8 bytes */
    uint64_t zhdr[3]; /* zlib: block count, block size, last block size as read */
    int appended;     /* in AppendedData: later arrays' offsets shift */
    uint64_t app_off; /* the Points' offset="" */
    vec appoff;       /* uint64 triples: [start, end) of each appended DataArray's
                         offset value in the file, and the value */
    derived dv;       /* values derived from the coordinates */
} srcrec;

static inline void srcrec_init(srcrec *r)
{
    memset(r, 0, sizeof *r);
    r->appoff.size = sizeof(uint64_t);
    dv_init(&r->dv);
}

static inline void srcrec_free(srcrec *r)
{
    qdc_free(r->off);
    r->off = NULL;
    vec_free(&r->appoff);
    dv_free(&r->dv);
}

/* Room for nv vertex offsets; QDC_ENOMEM. */
static inline qdc_status srcrec_alloc(srcrec *r, int64_t nv, qdc_error *err)
{
    qdc_free(r->off);
    r->nv = nv;
    r->off = qdc_mallocn((size_t)nv + 1, sizeof(uint64_t));
    if (!r->off)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for %lld vertex offsets",
                        (long long)nv);
    return QDC_OK;
}

/* The layout read cannot be written back in place: no splicing, and why. */
static inline void srcrec_refuse(srcrec *r, const char *why)
{
    if (!r)
        return;
    r->kind = SRC_NONE;
    if (!r->why)
        r->why = why;
}

/* Attach the file (buf, owned if own, else copied; TetGen: ele too) and the
 * record (moved) to m; on failure m is unchanged and the record freed. */
qdc_status splice_attach(mesh_t *m, srcrec *r, char *buf, size_t len, int own,
                         const char *ele, size_t ele_len, qdc_error *err);
/* 1 if m's source can be written in fmt with only the coordinates replaced
 * (same variant, connectivity and tags unchanged since reading); else 0 and
 * *why (static). */
int splice_ok(const mesh_t *m, meshio_format fmt, const char **why);
/* The file m's source was read from (kept for meshio_unpark_source). */
qdc_status splice_set_path(mesh_t *m, const char *path, qdc_error *err);
/* Write the source with m's coordinates; part 1 = TetGen's .ele. */
qdc_status splice_write(const mesh_t *m, int part, wbuf *w, qdc_error *err);

/* ------------------------------------------------------------------------ */
/* Nodes and elements by label, in any order (Nastran, I-DEAS)               */

/* Nodes with their labels and coordinate fields (SRC_FIELD offsets), tets
 * and triangles by node label with two tags each and where they are in the
 * file; turned into a mesh once everything is read (a node may come after
 * the elements that use it). A tet is 4 labels, or 10 for a second-order
 * one: its corners, then its mid-edge nodes in the order of mesh_p2_edges
 * (the reader maps its format's order); all tets of a file have the same. */
typedef struct {
    vec tags, xyz, off;                /* int64 labels; 3 doubles; 3 uint64 FIELD()s */
    vec el[2], tag[2], tag2[2], at[2]; /* [0] tets, [1] triangles: int64 labels,
                                         int32 tags, int64 byte offsets */
    int tet_nodes;                     /* 4 or 10; 0 before the first tet */
    const char *node, *elem[2];        /* names in messages: "GRID", "CTETRA" */
} labelled;

static inline void lab_init(labelled *l, const char *node, const char *tet,
                            const char *tri)
{
    memset(l, 0, sizeof *l);
    l->tags.size = sizeof(int64_t);
    l->xyz.size = sizeof(double);
    l->off.size = sizeof(uint64_t);
    for (int k = 0; k < 2; k++) {
        l->el[k].size = l->at[k].size = sizeof(int64_t);
        l->tag[k].size = l->tag2[k].size = sizeof(int32_t);
    }
    l->node = node;
    l->elem[0] = tet;
    l->elem[1] = tri;
}

static inline void lab_free(labelled *l)
{
    vec_free(&l->tags);
    vec_free(&l->xyz);
    vec_free(&l->off);
    for (int k = 0; k < 2; k++) {
        vec_free(&l->el[k]);
        vec_free(&l->tag[k]);
        vec_free(&l->tag2[k]);
        vec_free(&l->at[k]);
    }
}

static inline qdc_status lab_node(labelled *l, int64_t label, const double x[3],
                                  const uint64_t off[3], qdc_error *err)
{
    if (l->tags.n >= MESH_MAX_VERTICES || vec_grow(&l->tags, 1) != 0 ||
        vec_grow(&l->xyz, 3) != 0 || vec_grow(&l->off, 3) != 0)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the nodes");
    ((int64_t *)l->tags.a)[l->tags.n++] = label;
    memcpy((double *)l->xyz.a + l->xyz.n, x, 3 * sizeof(double));
    memcpy((uint64_t *)l->off.a + l->off.n, off, 3 * sizeof(uint64_t));
    l->xyz.n += 3;
    l->off.n += 3;
    return QDC_OK;
}

/* 1 if a tet of n nodes (4 or 10) cannot join the tets read so far (the
 * other order); else 0, and the tets are of n nodes from now on. */
static inline int lab_mixed(labelled *l, int n)
{
    if (l->tet_nodes && l->tet_nodes != n)
        return 1;
    l->tet_nodes = n;
    return 0;
}

/* A tet (k 0, 4 labels, or 10 after lab_mixed(l, 10)) or a triangle (k 1,
 * 3), its tags, where it starts. */
static inline qdc_status lab_elem(labelled *l, int k, const int64_t *g, int32_t tag,
                                  int32_t tag2, int64_t at, qdc_error *err)
{
    size_t n = k ? 3 : l->tet_nodes == 10 ? 10 : 4;

    if ((!k && l->tag[0].n >= MESH_MAX_TETS) || vec_grow(&l->el[k], n) != 0 ||
        vec_grow(&l->tag[k], 1) != 0 || vec_grow(&l->tag2[k], 1) != 0 ||
        vec_grow(&l->at[k], 1) != 0)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the elements");
    memcpy((int64_t *)l->el[k].a + l->el[k].n, g, n * sizeof(int64_t));
    l->el[k].n += n;
    ((int32_t *)l->tag[k].a)[l->tag[k].n++] = tag;
    ((int32_t *)l->tag2[k].a)[l->tag2[k].n++] = tag2;
    ((int64_t *)l->at[k].a)[l->at[k].n++] = at;
    return QDC_OK;
}

/* Second-order tets: idx[10 nt] (corners, mid-edge nodes) split into its
 * first 4 nt (the corners) and *mid (6 nt); QDC_ENOMEM. */
static inline qdc_status lab_split_mid(int32_t *idx, int64_t nt, int32_t **mid,
                                       qdc_error *err)
{
    *mid = qdc_mallocn(6 * (size_t)nt + 1, sizeof(int32_t));
    if (!*mid)
        return qdc_fail(err, QDC_ENOMEM, "out of memory for the mid-edge nodes");
    for (int64_t t = 0; t < nt; t++) { /* in place: 4t + 3 < 10t + 4 */
        memcpy(*mid + 6 * t, idx + 10 * t + 4, 6 * sizeof(int32_t));
        memmove(idx + 4 * t, idx + 10 * t, 4 * sizeof(int32_t));
    }
    return QDC_OK;
}

/* The mesh: labels to indices (a label twice, or one no node has, is an
 * error at its line in s), regions and triangle refs from the tags
 * (pick_regions: the first tags if any is set, else the second if they
 * differ), second-order tets' mid-edge nodes; rec (or NULL) gets the
 * coordinate fields as fmt's. */
static inline qdc_status lab_mesh(labelled *l, txt *s, meshio_format fmt, srcrec *rec,
                                  mesh_t **out, qdc_error *err)
{
    parsed pm;
    tagmap tm;
    int64_t dup, bad = -1;
    int32_t *idx[2] = {NULL, NULL};
    qdc_status st;
    int k = 0, per[2] = {l->tet_nodes == 10 ? 10 : 4, 3};

    memset(&tm, 0, sizeof tm);
    parsed_init(&pm);
    st = tagmap_build(&tm, l->tags.a, (int64_t)l->tags.n, &dup, err);
    if (st == QDC_OK && dup >= 0) {
        txt_locate(s, s->base + FIELD_AT(((uint64_t *)l->off.a)[3 * dup]));
        st = fail_txt(err, QDC_EPARSE, s, s->bol, "%s %lld appears twice", l->node,
                      (long long)((int64_t *)l->tags.a)[dup]);
    }
    for (k = 0; k < 2 && st == QDC_OK && bad < 0; k++) {
        idx[k] = qdc_mallocn(l->el[k].n + 1, sizeof(int32_t));
        if (!idx[k])
            st = qdc_fail(err, QDC_ENOMEM, "out of memory for the elements");
        else
            bad = tagmap_indices(&tm, l->el[k].a, l->el[k].n, idx[k]);
    }
    if (st == QDC_OK && bad >= 0) {
        k--;
        txt_locate(s, s->base + ((const int64_t *)l->at[k].a)[bad / per[k]]);
        st = fail_txt(err, QDC_EPARSE, s, s->bol, "%s: unknown %s %lld", l->elem[k],
                      l->node, (long long)((const int64_t *)l->el[k].a)[bad]);
    }
    tagmap_free(&tm);
    if (st != QDC_OK) {
        qdc_free(idx[0]);
        qdc_free(idx[1]);
        return st;
    }
    pm.nv = (int64_t)l->tags.n;
    pm.nt = (int64_t)l->tag[0].n;
    pm.ntri = (int64_t)l->tag[1].n;
    pm.tets = idx[0];
    pm.tris = idx[1];
    if (per[0] == 10 && lab_split_mid(idx[0], pm.nt, &pm.mid, err) != QDC_OK) {
        parsed_free(&pm);
        return QDC_ENOMEM;
    }
    pm.xyz = l->xyz.a ? l->xyz.a : qdc_malloc(sizeof(double));
    l->xyz.a = NULL;
    pick_regions(l->tag[0].a, l->tag2[0].a, pm.nt, &pm.region);
    pick_regions(l->tag[1].a, l->tag2[1].a, pm.ntri, &pm.tri_ref);
    l->tag[0].a = l->tag2[0].a = l->tag[1].a = l->tag2[1].a = NULL;
    if (!pm.xyz) {
        parsed_free(&pm);
        return qdc_fail(err, QDC_ENOMEM, "out of memory");
    }
    if (rec) {
        rec->fmt = fmt;
        rec->kind = SRC_FIELD;
        rec->nv = pm.nv;
        rec->off = l->off.a ? l->off.a : qdc_malloc(sizeof(uint64_t));
        l->off.a = NULL;
        if (!rec->off) {
            parsed_free(&pm);
            return qdc_fail(err, QDC_ENOMEM, "out of memory");
        }
    }
    return parsed_mesh_move(&pm, out, err);
}

#endif
