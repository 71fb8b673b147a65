/* meshio_json.c - the JSON mesh: {"vertices":[[x,y,z],...],"tets":[[a,b,c,d],...],
 * "regions":[...],"fixed":[...],"mid":[[m01,m12,m02,m03,m13,m23],...]}, 0-based
 * ("mid": second-order tets' mid-edge nodes, mesh_p2_edges). */
#include "io/format.h"

#include <string.h>

/* End of a JSON number (or of a bare word such as NaN or true) starting at t. */
static const char *json_tok_end(const txt *s, const char *t)
{
    const char *p = t;

    while (p < s->end &&
           (is_word((unsigned char)*p) || *p == '+' || *p == '-' || *p == '.'))
        p++;
    return p;
}

/* ------------------------------------------------------------------------ */
/* JSON                                                                      */

enum { JSON_MAX_DEPTH = 64 };

static qdc_status json_want(txt *s, char c, const char *what, qdc_error *err)
{
    char q[32];

    skip_ws(s);
    if (s->p < s->end && *s->p == c) {
        s->p++;
        return QDC_OK;
    }
    return fail_txt(err, QDC_EPARSE, s, s->p, "%s: expected '%c', got %s", what, c,
                    quote_tok(q, s, s->p, json_tok_end(s, s->p)));
}

/* 1 if the next character (after whitespace) is c, consumed. */
static int json_eat(txt *s, char c)
{
    skip_ws(s);
    if (s->p < s->end && *s->p == c) {
        s->p++;
        return 1;
    }
    return 0;
}

/* A JSON number token: -?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)? */
static int json_number_ok(const char *t, const char *te, int *is_int)
{
    const char *p = t;

    *is_int = 1;
    if (p < te && *p == '-')
        p++;
    if (p == te || (unsigned)(unsigned char)*p - '0' > 9)
        return 0;
    if (*p == '0')
        p++;
    else
        while (p < te && (unsigned)(unsigned char)*p - '0' <= 9)
            p++;
    if (p < te && *p == '.') {
        *is_int = 0;
        if (++p == te || (unsigned)(unsigned char)*p - '0' > 9)
            return 0;
        while (p < te && (unsigned)(unsigned char)*p - '0' <= 9)
            p++;
    }
    if (p < te && (*p == 'e' || *p == 'E')) {
        *is_int = 0;
        p++;
        if (p < te && (*p == '+' || *p == '-'))
            p++;
        if (p == te || (unsigned)(unsigned char)*p - '0' > 9)
            return 0;
        while (p < te && (unsigned)(unsigned char)*p - '0' <= 9)
            p++;
    }
    return p == te;
}

/* One number; integer in [lo, hi] if is_int, else a finite double. */
static qdc_status json_scalar(txt *s, const char *what, int want_int, int64_t lo,
                              int64_t hi, void *out, qdc_error *err)
{
    const char *t, *te;
    char q[32];
    int is_int;
    int64_t v = 0;
    qdc_status st;

    skip_ws(s);
    t = s->p;
    te = json_tok_end(s, t);
    if (t < te && !json_number_ok(t, te, &is_int)) {
        const char *w = t + (*t == '-');
        if (word_is(w, (size_t)(te - w), "NaN") ||
            word_is(w, (size_t)(te - w), "Infinity") ||
            word_is(w, (size_t)(te - w), "Inf"))
            return fail_txt(err, QDC_EPARSE, s, t, "%s %s is not finite (NaN/Inf)", what,
                            quote_tok(q, s, t, te));
        return fail_txt(err, QDC_EPARSE, s, t, "%s: expected a number, got %s", what,
                        quote_tok(q, s, t, te));
    }
    if (t == te)
        return fail_txt(err, QDC_EPARSE, s, t, "%s: expected a number, got %s", what,
                        quote_tok(q, s, t, te));
    if (!want_int)
        return tok_real(s, t, te, what, (double *)out, err);
    if (!is_int)
        return fail_txt(err, QDC_EPARSE, s, t, "%s: expected an integer, got %s", what,
                        quote_tok(q, s, t, te));
    st = tok_int(s, t, te, 1, what, lo, hi, &v, err);
    if (st == QDC_OK)
        *(int32_t *)out = (int32_t)v;
    return st;
}

/* An array of numbers (width 0) or of arrays of exactly `width` numbers,
 * appended to v (doubles or int32). */
static qdc_status json_array(txt *s, const char *what, int width, int want_int,
                             int64_t lo, int64_t hi, vec *v, qdc_error *err)
{
    int k = width ? width : 1;
    qdc_status st = json_want(s, '[', what, err);

    if (st != QDC_OK || json_eat(s, ']'))
        return st;
    do {
        if (vec_grow(v, (size_t)k) != 0)
            return qdc_fail(err, QDC_ENOMEM, "%s: out of memory", what);
        st = width ? json_want(s, '[', what, err) : QDC_OK;
        for (int j = 0; j < k && st == QDC_OK; j++) {
            if (j)
                st = json_want(s, ',', what, err);
            if (st == QDC_OK)
                st = json_scalar(s, what, want_int, lo, hi, (char *)v->a + v->n * v->size,
                                 err);
            if (st == QDC_OK)
                v->n++;
        }
        if (st == QDC_OK && width)
            st = json_want(s, ']', what, err);
        if (st != QDC_OK) {
            set_index(err, elem_kind(what), (int64_t)(v->n / (size_t)k));
            return st;
        }
    } while (json_eat(s, ','));
    return json_want(s, ']', what, err);
}

/* A string; its decoded text (ASCII only, else '?') goes to key, truncated. */
static qdc_status json_string(txt *s, char *key, size_t keysz, qdc_error *err)
{
    size_t n = 0;
    qdc_status st = json_want(s, '"', "string", err);

    while (st == QDC_OK) {
        unsigned char c;
        if (s->p == s->end)
            return fail_txt(err, QDC_EPARSE, s, s->p, "unterminated string");
        c = (unsigned char)*s->p;
        if (c == '"') {
            s->p++;
            break;
        }
        if (c < 0x20)
            return fail_txt(err, QDC_EPARSE, s, s->p, "control character in a string");
        s->p++;
        if (c == '\\') {
            static const char esc_in[] = "\"\\/bfnrtu", esc_out[] = "\"\\/\b\f\n\r\t";
            const char *e = s->p < s->end && *s->p ? strchr(esc_in, *s->p) : NULL;
            if (!e)
                return fail_txt(err, QDC_EPARSE, s, s->p - 1, "bad escape in a string");
            s->p++;
            c = (unsigned char)esc_out[e - esc_in];
            if (*e == 'u') {
                unsigned u = 0;
                for (int i = 0; i < 4; i++, s->p++) {
                    int h = s->p < s->end ? *s->p : 0;
                    int d = h >= '0' && h <= '9' ? h - '0'
                            : (h | 0x20) >= 'a' && (h | 0x20) <= 'f'
                                ? (h | 0x20) - 'a' + 10
                                : -1;
                    if (d < 0)
                        return fail_txt(err, QDC_EPARSE, s, s->p, "bad \\u escape");
                    u = 16 * u + (unsigned)d;
                }
                c = u && u < 0x80 ? (unsigned char)u : '?';
            }
        }
        if (key && n + 1 < keysz)
            key[n++] = c >= 0x80 ? '?' : (char)c;
    }
    if (key && keysz)
        key[n] = '\0';
    return st;
}

/* Any JSON value, checked and thrown away (unknown keys). */
static qdc_status json_skip(txt *s, int depth, qdc_error *err)
{
    const char *t, *te;
    char q[32];
    int is_int;
    qdc_status st = QDC_OK;

    if (depth > JSON_MAX_DEPTH)
        return fail_txt(err, QDC_EPARSE, s, s->p, "JSON nested too deeply");
    skip_ws(s);
    t = s->p;
    if (t < s->end && *t == '"')
        return json_string(s, NULL, 0, err);
    if (t < s->end && (*t == '[' || *t == '{')) {
        char close = *t == '[' ? ']' : '}';
        s->p++;
        if (json_eat(s, close))
            return QDC_OK;
        do {
            if (close == '}') {
                st = json_string(s, NULL, 0, err);
                if (st == QDC_OK)
                    st = json_want(s, ':', "object", err);
            }
            if (st == QDC_OK)
                st = json_skip(s, depth + 1, err);
        } while (st == QDC_OK && json_eat(s, ','));
        return st == QDC_OK ? json_want(s, close, "value", err) : st;
    }
    te = json_tok_end(s, t);
    if (t < te &&
        (json_number_ok(t, te, &is_int) || word_is(t, (size_t)(te - t), "true") ||
         word_is(t, (size_t)(te - t), "false") || word_is(t, (size_t)(te - t), "null"))) {
        s->p = te;
        return QDC_OK;
    }
    return fail_txt(err, QDC_EPARSE, s, t, "expected a JSON value, got %s",
                    quote_tok(q, s, t, te));
}

/* 1 if the next value is null (consumed). */
static int json_null(txt *s)
{
    skip_ws(s);
    if (s->end - s->p >= 4 && memcmp(s->p, "null", 4) == 0 &&
        json_tok_end(s, s->p) == s->p + 4) {
        s->p += 4;
        return 1;
    }
    return 0;
}

enum { J_VERTICES, J_TETS, J_REGIONS, J_FIXED, J_MID, J_KEYS };

static const char *const json_keys[J_KEYS] = {"vertices", "tets", "regions", "fixed",
                                              "mid"};

typedef struct {
    vec v[J_KEYS];
    txt at[J_KEYS];   /* where each value starts */
    int seen[J_KEYS]; /* 0 absent, 1 present, 2 null */
} json_state;

static qdc_status json_member(txt *s, json_state *js, qdc_error *err)
{
    char key[32];
    const char *kat;
    int k;
    qdc_status st;

    skip_ws(s);
    kat = s->p;
    st = json_string(s, key, sizeof key, err);
    if (st == QDC_OK)
        st = json_want(s, ':', "object", err);
    if (st != QDC_OK)
        return st;
    for (k = 0; k < J_KEYS && strcmp(key, json_keys[k]) != 0; k++)
        ;
    if (k == J_KEYS)
        return json_skip(s, 1, err);
    if (js->seen[k])
        return fail_txt(err, QDC_EPARSE, s, kat, "duplicate key \"%s\"", key);
    js->seen[k] = 1;
    skip_ws(s);
    js->at[k] = *s;
    if (k >= J_REGIONS && json_null(s)) {
        js->seen[k] = 2; /* present, null: as if absent */
        return QDC_OK;
    }
    switch (k) {
    case J_VERTICES:
        return json_array(s, "vertices", 3, 0, 0, 0, &js->v[k], err);
    case J_TETS:
        return json_array(s, "tets", 4, 1, 0, INT32_MAX, &js->v[k], err);
    case J_REGIONS:
        return json_array(s, "regions", 0, 1, INT32_MIN, INT32_MAX, &js->v[k], err);
    case J_MID:
        return json_array(s, "mid", 6, 1, 0, INT32_MAX, &js->v[k], err);
    default:
        return json_array(s, "fixed", 0, 1, 0, INT32_MAX, &js->v[k], err);
    }
}

/* Indices read before "vertices" was known: find a bad one, then rescan its
 * array with the bound to say where it is. */
static qdc_status json_recheck(json_state *js, int k, int width, int64_t nv,
                               qdc_error *err)
{
    txt s = js->at[k];
    vec tmp = {NULL, 0, 0, sizeof(int32_t)};
    qdc_status st;

    if (!js->seen[k] || first_bad_index(js->v[k].a, (int64_t)js->v[k].n, nv) < 0)
        return QDC_OK;
    st = json_array(&s, json_keys[k], width, 1, 0, nv - 1, &tmp, err);
    vec_free(&tmp);
    return st != QDC_OK ? st : qdc_fail(err, QDC_EINTERNAL, "recheck found nothing");
}

static qdc_status read_json(const char *buf, size_t len, const meshio_options *o,
                            srcrec *rec, mesh_t **out, qdc_error *err)
{
    json_state js;
    parsed pm; /* a view of the vectors in js */
    txt s = txt_init(buf, len, 0);
    qdc_status st;
    size_t nv, nt;
    (void)o;
    (void)rec;

    memset(&js, 0, sizeof js);
    js.v[J_VERTICES].size = sizeof(double);
    for (int k = J_TETS; k < J_KEYS; k++)
        js.v[k].size = sizeof(int32_t);
    parsed_init(&pm);
    st = json_want(&s, '{', "mesh", err);
    if (st == QDC_OK && !json_eat(&s, '}')) {
        do
            st = json_member(&s, &js, err);
        while (st == QDC_OK && json_eat(&s, ','));
        if (st == QDC_OK)
            st = json_want(&s, '}', "mesh", err);
    }
    if (st == QDC_OK)
        st = txt_done(&s, "the JSON object", err);
    if (st != QDC_OK)
        goto out;
    nv = js.v[J_VERTICES].n / 3;
    nt = js.v[J_TETS].n / 4;
    if (!js.seen[J_VERTICES] || !js.seen[J_TETS]) {
        st = fail_txt(err, QDC_EPARSE, &s, s.p, "missing \"%s\"",
                      js.seen[J_VERTICES] ? "tets" : "vertices");
        goto out;
    }
    if (nv > MESH_MAX_VERTICES || nt > MESH_MAX_TETS) {
        st = qdc_fail(err, QDC_ETOOBIG, "%zu vertices, %zu tets exceed the limits", nv,
                      nt);
        goto out;
    }
    if (js.seen[J_REGIONS] == 1 && js.v[J_REGIONS].n != nt) {
        st = fail_txt(err, QDC_EPARSE, &js.at[J_REGIONS], js.at[J_REGIONS].p,
                      "regions: %zu entries for %zu tets", js.v[J_REGIONS].n, nt);
        goto out;
    }
    if (js.seen[J_MID] == 1 && js.v[J_MID].n != 6 * nt) {
        st = fail_txt(err, QDC_EPARSE, &js.at[J_MID], js.at[J_MID].p,
                      "mid: %zu entries for %zu tets", js.v[J_MID].n / 6, nt);
        goto out;
    }
    st = json_recheck(&js, J_TETS, 4, (int64_t)nv, err);
    if (st == QDC_OK)
        st = json_recheck(&js, J_FIXED, 0, (int64_t)nv, err);
    if (st == QDC_OK)
        st = json_recheck(&js, J_MID, 6, (int64_t)nv, err);
    if (st != QDC_OK)
        goto out;
    pm.nv = (int64_t)nv;
    pm.nt = (int64_t)nt;
    pm.xyz = js.v[J_VERTICES].a;
    pm.tets = js.v[J_TETS].a;
    pm.region = js.v[J_REGIONS].a;
    pm.fix = js.v[J_FIXED].a;
    pm.nfix = js.seen[J_FIXED] == 1 ? (int64_t)js.v[J_FIXED].n : -1;
    pm.mid = js.seen[J_MID] == 1 ? js.v[J_MID].a : NULL;
    st = parsed_mesh(&pm, out, err);
out:
    for (int k = 0; k < J_KEYS; k++)
        vec_free(&js.v[k]);
    return st;
}

static qdc_status write_json(const mesh_t *m, meshio_format fmt, int part, wbuf *w,
                             qdc_error *err)
{
    (void)fmt;
    (void)part;
    (void)err;
    wb_str(w, "{\"vertices\": [");
    for (int32_t i = 0; i < m->nv; i++) {
        wb_str(w, i ? ",\n[" : "\n[");
        wb_reals(w, m->xyz + 3 * (size_t)i, 3, ", ", "]");
    }
    wb_str(w, "],\n\"tets\": [");
    for (int32_t t = 0; t < m->nt; t++) {
        wb_str(w, t ? ",\n[" : "\n[");
        wb_ints(w, m->tets + 4 * (size_t)t, 4, 0, ", ", "]");
    }
    wb_str(w, "]");
    if (m->region) {
        wb_str(w, ",\n\"regions\": [");
        for (int32_t t = 0; t < m->nt; t++) {
            wb_str(w, t == 0 ? "" : t % 16 ? ", " : ",\n");
            wb_int(w, m->region[t]);
        }
        wb_str(w, "]");
    }
    if (m->fixed) {
        int32_t n = 0;
        wb_str(w, ",\n\"fixed\": [");
        for (int32_t i = 0; i < m->nv; i++) {
            if (!m->fixed[i])
                continue;
            wb_str(w, n == 0 ? "" : n % 16 ? ", " : ",\n");
            wb_int(w, i);
            n++;
        }
        wb_str(w, "]");
    }
    if (m->mid) {
        wb_str(w, ",\n\"mid\": [");
        for (int32_t t = 0; t < m->nt; t++) {
            wb_str(w, t ? ",\n[" : "\n[");
            wb_ints(w, m->mid + 6 * (size_t)t, 6, 0, ", ", "]");
        }
        wb_str(w, "]");
    }
    wb_str(w, "}\n");
    return QDC_OK;
}

static meshio_format sniff_json(const char *buf, size_t len, size_t i)
{
    return i < len && buf[i] == '{' ? MESHIO_JSON : MESHIO_AUTO;
}

const meshio_fmt fmt_json = {
    .name = "json",
    .aliases = "application/json",
    .about = "JSON mesh: vertices, tets, regions, fixed and mid arrays, 0-based",
    .ext = "json",
    .input = "input.json",
    .media = "application/json",
    .sniff = sniff_json,
    .read = read_json,
    .write = write_json,
    .p2 = 1,
};
