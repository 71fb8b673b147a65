/* options.c - the optimizer options: defaults, words, parsers and table (options.h). */
#include "opt/options.h"
#include "opt/opt_int.h"

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void opt_defaults(opt_options *o)
{
    memset(o, 0, sizeof *o);
    o->metric = OPT_METRIC_MIVL;
    o->boundary = OPT_BOUNDARY_SLIDE;
    o->hausd_rel = OPT_HAUSD_AUTO;
    o->mode = OPT_MODE_SAFE;
    o->weights = OPT_WEIGHTS_OPTAVG;
    o->solver = OPT_SOLVER_AUTO;
    o->harmonic = 0;
    o->pre_iters = 3;
    o->finish = 1;
    o->max_iter = 10;
    o->ls_halvings = 10;
    o->mu = 1.0;
    o->tol_move = 1e-3;
    o->stall = 2e-3;
    o->eps_rel = 1e-3;
    o->finish_frac = 1.0;
    o->finish_sweeps = 32;
    o->finish_gain = 5e-4;
    o->angle_polish = 1;
    o->feature_angle = 30.0;
}

static const char *const metric_names[] = {"mivl", "mimr", "micn"};
static const char *const boundary_names[] = {"lsq", "fixed", "slide"};
static const char *const mode_names[] = {"safe", "literal"};
static const char *const weights_names[] = {"optavg", "paper"};
static const char *const solver_names[] = {"auto", "cholmod", "pcg"};
static const char *const topology_names[] = {"none", "flips", "full"};

static qdc_status parse_word(const char *s, const char *const *names, int n, int *out)
{
    for (int i = 0; s && i < n; i++)
        if (strcmp(s, names[i]) == 0) {
            *out = i;
            return QDC_OK;
        }
    return QDC_EINVAL;
}

#define PARSER(fn, type, names)                                                          \
    qdc_status fn(const char *s, type *out)                                              \
    {                                                                                    \
        int v;                                                                           \
        qdc_status st = parse_word(s, names, (int)(sizeof names / sizeof names[0]), &v); \
        if (st == QDC_OK)                                                                \
            *out = (type)v;                                                              \
        return st;                                                                       \
    }
PARSER(opt_parse_metric, opt_metric, metric_names)
PARSER(opt_parse_boundary, opt_boundary, boundary_names)
PARSER(opt_parse_mode, opt_mode, mode_names)
PARSER(opt_parse_weights, opt_weights, weights_names)
PARSER(opt_parse_solver, opt_solver, solver_names)
PARSER(opt_parse_topology, opt_topology, topology_names)

/* A finite number filling all of s: no leading space, nothing after it. */
static int whole_number(const char *s, double *out)
{
    char *end;
    double v;

    if (!*s || isspace((unsigned char)*s))
        return -1;
    errno = 0;
    v = strtod(s, &end);
    if (end == s || *end || errno == ERANGE || !isfinite(v))
        return -1;
    *out = v;
    return 0;
}

/* A finite, non-negative number filling all of s. */
static int parse_nonneg(const char *s, double *out)
{
    return !s || whole_number(s, out) || *out < 0 ? -1 : 0;
}

qdc_status opt_parse_hausd(const char *s, opt_options *o)
{
    size_t n = s ? strlen(s) : 0;
    double v;
    char buf[64];

    if (!n || n >= sizeof buf)
        return QDC_EINVAL;
    if (!strcmp(s, "auto") || !strcmp(s, "none")) {
        o->hausd = 0;
        o->hausd_rel = s[0] == 'a' ? OPT_HAUSD_AUTO : 0.0;
        return QDC_OK;
    }
    if (!strncmp(s, "rel:", 4)) {
        if (parse_nonneg(s + 4, &v))
            return QDC_EINVAL;
        o->hausd = 0;
        o->hausd_rel = v;
        return QDC_OK;
    }
    if (s[n - 1] == '%') {
        memcpy(buf, s, n - 1);
        buf[n - 1] = 0;
        if (parse_nonneg(buf, &v))
            return QDC_EINVAL;
        o->hausd = 0;
        o->hausd_rel = v / 100.0;
        return QDC_OK;
    }
    if (parse_nonneg(s, &v))
        return QDC_EINVAL;
    o->hausd = v;
    o->hausd_rel = 0;
    return QDC_OK;
}

#define NAMER(fn, type, names)                                                           \
    const char *fn(type v)                                                               \
    {                                                                                    \
        return (unsigned)v < sizeof names / sizeof names[0] ? names[v] : "?";            \
    }
NAMER(opt_metric_name, opt_metric, metric_names)
NAMER(opt_boundary_name, opt_boundary, boundary_names)
NAMER(opt_mode_name, opt_mode, mode_names)
NAMER(opt_weights_name, opt_weights, weights_names)
NAMER(opt_solver_name, opt_solver, solver_names)
NAMER(opt_topology_name, opt_topology, topology_names)

/* In words, for --help (docs/method.md §2): each metric is 1 on a regular tet
 * and grows without bound as a tet flattens; an inverted tet keeps a finite
 * cost (Escobar's regularization), which is what lets the flow untangle. */
static const char *const metric_say[] = {
    "volume-length: the cube of the rms edge length over the volume",
    "mean ratio: the sum of squared edge lengths over the volume to the 2/3 (1 over "
    "the mean ratio the reports show)",
    "condition number of the map from the regular tet (|S| |adj S| / det S)"};
static const char *const boundary_say[] = {
    "boundary vertices kept near their input positions in a least-squares sense "
    "(the paper): the best quality, but the shape changes",
    "boundary vertices do not move",
    "boundary vertices slide on the input surface, along feature lines; corners stay"};
static const char *const mode_say[] = {
    "damping in normalized units and a line search (docs/method.md §5)",
    "the paper as written: no line search; it drifts (for comparison)"};
static const char *const weights_say[] = {
    "rows aim at the weighted mean of the per-tet optimal positions",
    "the paper's Eq. 6 weights"};
static const char *const solver_say[] = {
    "the cheaper of the two for this system", "sparse Cholesky (CHOLMOD)",
    "matrix-free Jacobi-preconditioned conjugate gradients"};
static const char *const topology_say[] = {
    "vertices move, the tets stay as they are (point and cell data map one to one)",
    "tets are also flipped where that raises the worst quality around them: "
    "vertices, boundary triangles and region tags kept, the tet count changes (with "
    "--hausd given, boundary edges flipped and flat tets peeled off within it)",
    "flips, then a round that also contracts interior edges and inserts vertices "
    "inside where tets stay bad, kept when better: boundary triangles and region "
    "tags kept, vertices added and removed inside"};

#define OFF(f) offsetof(opt_options, f)
#define WORDS(w) w, (int)(sizeof w / sizeof w[0])

/* Ranges are those opt_run accepts (run_once checks them again), so that a
 * value accepted here never fails later. */
static const opt_desc table[] = {
    {"metric", OPT_T_WORD, OFF(metric), 0, 0, 0, WORDS(metric_names),
     "quality metric the optimizer improves (each is 1 on a regular tet, larger is "
     "worse)",
     OPT_G_EVERYDAY, metric_say},
    {"boundary", OPT_T_WORD, OFF(boundary), 0, 0, 0, WORDS(boundary_names),
     "boundary handling", OPT_G_BOUNDARY, boundary_say},
    {"hausd", OPT_T_HAUSD, OFF(hausd), 0, 0, 0, NULL, 0,
     "bound on the boundary's Hausdorff distance: H, P%, rel:F of the diagonal, none, "
     "auto (with slide: 0.003 of the diagonal)",
     OPT_G_BOUNDARY, NULL},
    {"feature_angle", OPT_T_REAL, OFF(feature_angle), 0, 180, 0, NULL, 0,
     "slide: sharper boundary edges are features (degrees)", OPT_G_BOUNDARY, NULL},
    {"mode", OPT_T_WORD, OFF(mode), 0, 0, 0, WORDS(mode_names),
     "safeguarded method or the paper as written", OPT_G_ADVANCED, mode_say},
    {"weights", OPT_T_WORD, OFF(weights), 0, 0, 0, WORDS(weights_names), "QDC weights",
     OPT_G_ADVANCED, weights_say},
    {"solver", OPT_T_WORD, OFF(solver), 0, 0, 0, WORDS(solver_names), "linear solver",
     OPT_G_ADVANCED, solver_say},
    {"harmonic", OPT_T_BOOL, OFF(harmonic), 0, 1, 0, NULL, 0,
     "harmonic guidance, paper Sec. 5.1", OPT_G_ADVANCED, NULL},
    {"pre_iters", OPT_T_INT, OFF(pre_iters), 0, 10000, 0, NULL, 0,
     "iterations before the harmonic field", OPT_G_ADVANCED, NULL},
    {"finish", OPT_T_BOOL, OFF(finish), 0, 1, 0, NULL, 0, "worst-tet finishing pass",
     OPT_G_EVERYDAY, NULL},
    {"finish_sweeps", OPT_T_INT, OFF(finish_sweeps), 0, 1000, 0, NULL, 0,
     "broad finishing sweeps", OPT_G_ADVANCED, NULL},
    {"finish_frac", OPT_T_REAL, OFF(finish_frac), 0, 1, 0, NULL, 0,
     "share of worst tets visited per sweep", OPT_G_ADVANCED, NULL},
    {"finish_gain", OPT_T_REAL, OFF(finish_gain), 0, 1, 0, NULL, 0,
     "broad sweeps end when one gains less mean ratio (0: all of them)", OPT_G_ADVANCED,
     NULL},
    {"angle_polish", OPT_T_BOOL, OFF(angle_polish), 0, 1, 0, NULL, 0,
     "then raise the smallest dihedral angles", OPT_G_EVERYDAY, NULL},
    {"max_iter", OPT_T_INT, OFF(max_iter), 0, 10000, 0, NULL, 0, "global iterations",
     OPT_G_EVERYDAY, NULL},
    {"ls_halvings", OPT_T_INT, OFF(ls_halvings), 0, 60, 0, NULL, 0,
     "line search: steps 1 .. 2^-N", OPT_G_ADVANCED, NULL},
    {"mu", OPT_T_REAL, OFF(mu), 0, 1e12, 1, NULL, 0, "damping in normalized units",
     OPT_G_ADVANCED, NULL},
    {"mu_scaled", OPT_T_BOOL, OFF(mu_scaled), 0, 1, 0, NULL, 0,
     "with harmonic guidance, scale mu by omega_B^2", OPT_G_ADVANCED, NULL},
    {"stall", OPT_T_REAL, OFF(stall), 0, 1, 0, NULL, 0,
     "global phase done when an iteration gains less mean ratio, or the next is "
     "predicted to (0: never)",
     OPT_G_EVERYDAY, NULL},
    {"tol_move", OPT_T_REAL, OFF(tol_move), 0, 1, 0, NULL, 0,
     "stop when the largest move < this x mean edge", OPT_G_ADVANCED, NULL},
    {"eps_rel", OPT_T_REAL, OFF(eps_rel), 0, 1, 1, NULL, 0,
     "Escobar epsilon relative to a regular tet", OPT_G_ADVANCED, NULL},
    {"topology", OPT_T_WORD, OFF(topology), 0, 0, 0, WORDS(topology_names),
     "none: connectivity kept; flips: the smoother alternated with edge removal, 2-3 "
     "flips and multi-face removal (vertices, boundary triangles and region tags kept); "
     "full: flips, then interior edge contraction and vertex insertion when better, "
     "then contraction of clustered interior vertices (vertices added and removed "
     "inside, boundary triangles and region tags kept)",
     OPT_G_EVERYDAY, topology_say},
    {"time_limit", OPT_T_REAL, OFF(time_limit), 0, 1e9, 0, NULL, 0,
     "seconds of optimizing, then the best mesh so far: no iteration or sweep is "
     "started that would end past them (0: none)",
     OPT_G_EVERYDAY, NULL},
};
#define N_TABLE (sizeof table / sizeof table[0])

const opt_desc *opt_table(size_t *n)
{
    *n = N_TABLE;
    return table;
}

static int same_key(const char *a, const char *b)
{
    for (; *a && *b; a++, b++)
        if (*a != *b && !((*a == '-' || *a == '_') && (*b == '-' || *b == '_')))
            return 0;
    return *a == *b;
}

const opt_desc *opt_find(const char *key)
{
    for (size_t i = 0; key && i < N_TABLE; i++)
        if (same_key(key, table[i].name))
            return &table[i];
    return NULL;
}

void opt_range_text(const opt_desc *d, char *buf, size_t n)
{
    size_t k = 0;

    switch (d->type) {
    case OPT_T_WORD:
        buf[0] = 0;
        for (int i = 0; i < d->nwords && k < n; i++)
            k += (size_t)snprintf(buf + k, n - k, "%s%s", i ? "|" : "", d->words[i]);
        break;
    case OPT_T_BOOL:
        snprintf(buf, n, "on|off");
        break;
    case OPT_T_HAUSD:
        snprintf(buf, n, "H >= 0 (mesh units), P%% or rel:F (of the bbox diagonal)");
        break;
    default:
        snprintf(buf, n, "%c%.17g, %.17g]", d->lo_open ? '(' : '[', d->lo, d->hi);
    }
}

/* The shortest "%g" text of v that reads back as v (0.2, not 0.20000000000000001). */
static void shortest(char *buf, size_t n, const char *prefix, double v)
{
    for (int prec = 6; prec <= 17; prec++) {
        snprintf(buf, n, "%s%.*g", prefix, prec, v);
        if (strtod(buf + strlen(prefix), NULL) == v)
            return;
    }
}

qdc_status opt_set(opt_options *o, const char *key, const char *text, qdc_error *err)
{
    const opt_desc *d = opt_find(key);
    void *f;
    double v = 0;
    int ok = 0;
    char range[160];

    if (!d)
        return qdc_fail(err, QDC_EINVAL, "unknown option '%.60s'", key ? key : "");
    if (!text)
        text = "";
    f = (char *)o + d->off;
    switch (d->type) {
    case OPT_T_WORD:
        for (int i = 0; i < d->nwords; i++)
            if (!strcmp(text, d->words[i])) {
                *(int *)f = i;
                ok = 1;
            }
        break;
    case OPT_T_BOOL:
        if (!strcmp(text, "on") || !strcmp(text, "1") || !strcmp(text, "true") ||
            !strcmp(text, "yes"))
            *(int *)f = 1, ok = 1;
        else if (!strcmp(text, "off") || !strcmp(text, "0") || !strcmp(text, "false") ||
                 !strcmp(text, "no"))
            *(int *)f = 0, ok = 1;
        break;
    case OPT_T_HAUSD:
        ok = opt_parse_hausd(text, o) == QDC_OK;
        break;
    case OPT_T_INT:
        /* digits only (a sign allowed): 5.0, 0x5 and 5e0 are not integers */
        ok = !whole_number(text, &v) && v == floor(v) && v >= d->lo && v <= d->hi &&
             strspn(text + (*text == '-' || *text == '+'), "0123456789") ==
                 strlen(text + (*text == '-' || *text == '+'));
        if (ok)
            *(int *)f = (int)v;
        break;
    case OPT_T_REAL:
        ok = !whole_number(text, &v) && (d->lo_open ? v > d->lo : v >= d->lo) &&
             v <= d->hi;
        if (ok)
            *(double *)f = v;
        break;
    }
    if (ok)
        return QDC_OK;
    opt_range_text(d, range, sizeof range);
    return qdc_fail(err, QDC_EINVAL,
                    "option '%s': '%.40s' is not one of the valid values: %s", d->name,
                    text, range);
}

void opt_value_text(const opt_desc *d, const opt_options *o, char *buf, size_t n)
{
    const void *f = (const char *)o + d->off;

    switch (d->type) {
    case OPT_T_WORD: {
        int i = *(const int *)f;
        snprintf(buf, n, "%s", i >= 0 && i < d->nwords ? d->words[i] : "?");
        break;
    }
    case OPT_T_BOOL:
        snprintf(buf, n, "%s", *(const int *)f ? "on" : "off");
        break;
    case OPT_T_INT:
        snprintf(buf, n, "%d", *(const int *)f);
        break;
    case OPT_T_HAUSD:
        if (o->hausd > 0)
            shortest(buf, n, "", o->hausd);
        else if (o->hausd_rel > 0)
            shortest(buf, n, "rel:", o->hausd_rel);
        else if (o->hausd_rel == OPT_HAUSD_AUTO)
            snprintf(buf, n, "auto");
        else
            snprintf(buf, n, "none");
        break;
    default:
        shortest(buf, n, "", *(const double *)f);
    }
}
