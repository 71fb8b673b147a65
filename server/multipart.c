/* multipart.c - multipart/form-data bodies (see multipart.h). */
#include "multipart.h"

#include <stdio.h>
#include <string.h>
#include <strings.h>

/* RFC 2046's bchars, the characters a boundary may hold (a space only
 * inside). */
static int bchar(char c)
{
    return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
           strchr("'()+_,-./:=? ", c) != NULL;
}

int mp_boundary(const char *ct, char out[MP_BOUNDARY_MAX + 1])
{
    static const char type[] = "multipart/form-data";
    const char *p;
    size_t n = 0;

    if (!ct || strncasecmp(ct, type, sizeof type - 1))
        return -1;
    p = ct + sizeof type - 1;
    while (*p) {
        while (*p == ' ' || *p == '\t')
            p++;
        if (*p != ';')
            return -1;
        p++;
        while (*p == ' ' || *p == '\t')
            p++;
        if (strncasecmp(p, "boundary=", 9)) { /* another parameter: skipped */
            while (*p && *p != ';')
                p += *p == '"' && strchr(p + 1, '"') ? strchr(p + 1, '"') - p + 1 : 1;
            continue;
        }
        p += 9;
        int quoted = *p == '"';
        p += quoted;
        while (*p && (quoted ? *p != '"' : *p != ';' && *p != ' ' && *p != '\t')) {
            if (n == MP_BOUNDARY_MAX || !bchar(*p))
                return -1;
            out[n++] = *p++;
        }
        if (quoted && *p != '"')
            return -1;
        out[n] = 0;
        return n > 0 && out[n - 1] != ' ' ? 0 : -1;
    }
    return -1;
}

/* The first occurrence of s[0..sn) in buf[from..len), or len. */
static size_t find(const char *buf, size_t len, size_t from, const char *s, size_t sn)
{
    while (from < len && len - from >= sn) {
        const char *c = memchr(buf + from, s[0], len - from - sn + 1);
        if (!c)
            break;
        if (!memcmp(c, s, sn))
            return (size_t)(c - buf);
        from = (size_t)(c - buf) + 1;
    }
    return len;
}

/* A parameter key="value" of a Content-Disposition value v[0..n) into out
 * (cap bytes): 1 found, 0 not there, -1 malformed or too long. */
static int disp_param(const char *v, size_t n, const char *key, char *out, size_t cap)
{
    size_t kn = strlen(key);

    for (size_t i = 0; i < n; i++) {
        if (v[i] == '"') { /* skip a quoted value: a key inside is not one */
            i++;
            while (i < n && v[i] != '"')
                i++;
            continue;
        }
        if (v[i] != ';')
            continue;
        size_t k = i + 1;
        while (k < n && (v[k] == ' ' || v[k] == '\t'))
            k++;
        if (n - k < kn + 2 || strncasecmp(v + k, key, kn) || v[k + kn] != '=')
            continue;
        k += kn + 1;
        if (v[k] != '"')
            return -1; /* browsers and curl quote every value */
        size_t e = k + 1;
        while (e < n && v[e] != '"')
            e++;
        if (e == n || e - k - 1 >= cap)
            return -1;
        memcpy(out, v + k + 1, e - k - 1);
        out[e - k - 1] = 0;
        return 1;
    }
    return 0;
}

/* The header block h[0..n) of a part (CRLF-separated lines, without the
 * blank line) into p: 0, or -1 with why. */
static int part_headers(const char *h, size_t n, mp_part *p, char *why, size_t cap)
{
    int disp = 0;
    size_t i = 0;

    for (size_t k = 0; k < n; k++)
        if ((unsigned char)h[k] < 32 && h[k] != '\r' && h[k] != '\n' && h[k] != '\t') {
            snprintf(why, cap, "a control byte in a part's headers");
            return -1;
        }
    while (i < n) {
        size_t e = find(h, n, i, "\r\n", 2), c;
        const char *l = h + i;
        size_t ln = e - i;
        i = e + 2;
        for (c = 0; c < ln && l[c] != ':'; c++)
            ;
        if (c == ln || c == 0) {
            snprintf(why, cap, "a part's header line has no name");
            return -1;
        }
        if (c != 19 || strncasecmp(l, "Content-Disposition", 19))
            continue; /* Content-Type and others: the formats say what the part is */
        if (disp++) {
            snprintf(why, cap, "a part has two Content-Disposition headers");
            return -1;
        }
        const char *v = l + c + 1;
        size_t vn = ln - c - 1;
        while (vn && (*v == ' ' || *v == '\t'))
            v++, vn--;
        if (vn < 9 || strncasecmp(v, "form-data", 9) ||
            (vn > 9 && v[9] != ';' && v[9] != ' ')) {
            snprintf(why, cap, "a part is not form-data");
            return -1;
        }
        int r = disp_param(v, vn, "name", p->name, sizeof p->name);
        if (r <= 0 || !p->name[0]) {
            snprintf(why, cap, "a part has %s name",
                     r < 0 ? "a malformed or too long" : "no");
            return -1;
        }
        if (disp_param(v, vn, "filename", p->filename, sizeof p->filename) < 0) {
            snprintf(why, cap, "part '%s': a malformed or too long filename", p->name);
            return -1;
        }
    }
    if (!disp) {
        snprintf(why, cap, "a part has no Content-Disposition header");
        return -1;
    }
    return 0;
}

int mp_parse(const char *buf, size_t len, const char *boundary, mp_part *parts, int max,
             int *n, char *why, size_t cap)
{
    char delim[MP_BOUNDARY_MAX + 5];
    size_t bn = strlen(boundary), dn, pos;

    *n = 0;
    if (bn == 0 || bn > MP_BOUNDARY_MAX) {
        snprintf(why, cap, "no valid boundary");
        return -1;
    }
    /* "\r\n--B": the first one may open the body without its CRLF */
    memcpy(delim, "\r\n--", 4);
    memcpy(delim + 4, boundary, bn);
    dn = bn + 4;
    if (len >= dn - 2 && !memcmp(buf, delim + 2, dn - 2))
        pos = dn - 2;
    else {
        pos = find(buf, len, 0, delim, dn); /* after a preamble */
        if (pos == len) {
            snprintf(why, cap,
                     "the body does not hold the boundary its Content-Type names");
            return -1;
        }
        pos += dn;
    }
    for (;;) {
        /* after a delimiter: "--" closes the body, CRLF opens a part */
        if (len - pos >= 2 && !memcmp(buf + pos, "--", 2))
            return 0; /* the epilogue is ignored */
        if (len - pos < 2 || memcmp(buf + pos, "\r\n", 2)) {
            snprintf(why, cap, "a boundary line is not ended by CRLF");
            return -1;
        }
        pos += 2;
        if (*n == max) {
            snprintf(why, cap, "more than %d parts", max);
            return -1;
        }
        mp_part *p = &parts[*n];
        memset(p, 0, sizeof *p);
        size_t he;
        if (len - pos >= 2 && !memcmp(buf + pos, "\r\n", 2))
            he = pos; /* no header at all: refused below */
        else {
            size_t lim = len - pos > MP_HEADERS_MAX + 4 ? pos + MP_HEADERS_MAX + 4 : len;
            he = find(buf, lim, pos, "\r\n\r\n", 4);
            if (he == lim) {
                snprintf(why, cap, "a part's headers are %s",
                         lim < len ? "too long" : "not ended by a blank line");
                return -1;
            }
            he += 2; /* the last header's CRLF belongs to it */
        }
        if (part_headers(buf + pos, he > pos ? he - pos - 2 : 0, p, why, cap))
            return -1;
        pos = he + 2;
        size_t end = find(buf, len, pos, delim, dn);
        if (end == len) {
            snprintf(why, cap, "part '%s' is not ended by the boundary (a cut body?)",
                     p->name);
            return -1;
        }
        p->off = pos;
        p->len = end - pos;
        (*n)++;
        pos = end + dn;
    }
}
