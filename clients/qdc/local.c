/* local.c - `qdc optimize` and `qdc quality`: thin layers over libqdc. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "qdc.h"

#include <errno.h>
#include <math.h>
#include <omp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif

static volatile sig_atomic_t interrupted;
static atomic_int cancel_flag; /* read by opt_run on its thread */

static void on_signal(int sig)
{
    (void)sig;
    interrupted = 1;
    atomic_store(&cancel_flag, 1);
}

void cli_error(const char *path, const qdc_error *err, qdc_status st)
{
    fprintf(stderr, "qdc: %s", path ? path : "");
    if (err && err->line > 0) {
        fprintf(stderr, ":%lld", (long long)err->line);
        if (err->col > 0)
            fprintf(stderr, ":%lld", (long long)err->col);
    } else if (err && err->offset >= 0) {
        fprintf(stderr, ": byte %lld", (long long)err->offset);
    }
    fprintf(stderr, ": %s\n", err && err->msg[0] ? err->msg : qdc_status_str(st));
}

typedef struct {
    int quiet;
    int tty;
    int last_len;
} progress_state;

static int on_progress(void *ctx, const opt_progress *p)
{
    progress_state *ps = ctx;
    char line[200];
    int n;

    if (ps->quiet)
        return atomic_load(&cancel_flag);
    n = snprintf(line, sizeof line,
                 "%-6s %3d  q mean %.4f min %+.4f  dihedral %6.2f..%6.2f  inverted %d  "
                 "step %.3g  cg %d  %.1fs",
                 p->phase, p->iteration, p->q_mean, p->q_min, p->dih_min, p->dih_max,
                 (int)(p->n_inverted - p->n_degenerate), p->step, p->cg_iters,
                 p->elapsed);
    if (p->n_degenerate > 0 && n > 0 && (size_t)n < sizeof line)
        n += snprintf(line + n, sizeof line - (size_t)n, "  degenerate %d",
                      (int)p->n_degenerate);
    if (ps->tty) {
        fprintf(stderr, "\r%s%*s", line, ps->last_len > n ? ps->last_len - n : 0, "");
        ps->last_len = n;
    } else {
        fprintf(stderr, "%s\n", line);
    }
    fflush(stderr);
    return atomic_load(&cancel_flag);
}

static void on_log(void *ctx, int level, const char *msg)
{
    progress_state *ps = ctx;

    if (ps->quiet && level == 0)
        return;
    if (ps->tty && ps->last_len) {
        fputc('\n', stderr);
        ps->last_len = 0;
    }
    fprintf(stderr, "qdc: %s%s\n", level ? "warning: " : "", msg);
}

static void json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++) {
        if (*s == '"' || *s == '\\')
            fputc('\\', f);
        fputc(*s, f);
    }
    fputc('"', f);
}

int cli_options(int argc, char **argv)
{
    static const char *const types[] = {"word", "bool", "integer", "number", "hausd"};
    size_t n;
    const opt_desc *t = opt_table(&n);
    opt_options d;

    (void)argv;
    if (argc > 1) {
        fprintf(stderr, "usage: qdc options\n");
        return CLI_EUSAGE;
    }
    opt_defaults(&d);
    printf("[");
    for (size_t i = 0; i < n; i++) {
        char def[64], range[200];
        opt_value_text(&t[i], &d, def, sizeof def);
        opt_range_text(&t[i], range, sizeof range);
        printf("%s\n {\"name\": ", i ? "," : "");
        json_str(stdout, t[i].name);
        printf(", \"type\": \"%s\", \"default\": ", types[t[i].type]);
        json_str(stdout, def);
        printf(", \"valid\": ");
        json_str(stdout, range);
        if (t[i].type == OPT_T_INT || t[i].type == OPT_T_REAL)
            printf(", \"min\": %.17g, \"max\": %.17g, \"min_excluded\": %s", t[i].lo,
                   t[i].hi, t[i].lo_open ? "true" : "false");
        if (t[i].type == OPT_T_WORD) {
            printf(", \"values\": [");
            for (int w = 0; w < t[i].nwords; w++) {
                printf("%s", w ? ", " : "");
                json_str(stdout, t[i].words[w]);
            }
            printf("]");
        }
        printf(", \"help\": ");
        json_str(stdout, t[i].help);
        printf("}");
    }
    printf("\n]\n");
    return CLI_OK;
}

/* What qdc's writer of fmt keeps of m, for a note: vertices, tets, triangles
 * and their region tags, and the point data when the writer has it (kept,
 * or interpolated at N new vertices by --topology full), else the point data
 * said to be dropped. */
static const char *kept_words(const mesh_t *m, meshio_format fmt, char *b, size_t n)
{
    const mesh_pdata *p = m->pdata;
    int k = p ? (int)p->n : 0;
    const char *s = k == 1 ? "" : "s";

    if (!k)
        snprintf(b, n, "only vertices, tets, triangles and their region tags are kept");
    else if (!meshio_writes_pdata(fmt))
        snprintf(b, n,
                 "only vertices, tets, triangles and their region tags are kept; point "
                 "data dropped (%d array%s: qdc's %s writer has none)",
                 k, s, meshio_format_name(fmt) ? meshio_format_name(fmt) : "?");
    else if (p->ninterp > 0)
        snprintf(b, n,
                 "only vertices, tets, triangles, their region tags and the point data "
                 "are kept (%d array%s, interpolated at %d new vert%s)",
                 k, s, (int)p->ninterp, p->ninterp == 1 ? "ex" : "ices");
    else
        snprintf(b, n,
                 "only vertices, tets, triangles, their region tags and the point data "
                 "are kept (%d array%s)",
                 k, s);
    return b;
}

/* Before writing m to out in fmt: say in one note line when the input's
 * extra data (tags, names, arrays) cannot come along, or that float32
 * coordinates stay float32. */
static void source_note(const mesh_t *m, const char *out, meshio_format fmt, int quiet)
{
    const char *why = NULL;
    int f32 = 0;
    char kept[240];

    if (quiet || meshio_source_format(m) == MESHIO_AUTO)
        return;
    fmt = meshio_save_format(out, fmt, m);
    meshio_source_bytes(m, &f32);
    if (!meshio_splices(m, fmt, &why) && (fmt == MESHIO_AUTO || meshio_has_writer(fmt)))
        fprintf(stderr, "qdc: note: %s: written by qdc's %s writer (%s): %s\n", out,
                meshio_format_name(fmt) ? meshio_format_name(fmt) : "?", why,
                kept_words(m, fmt, kept, sizeof kept));
    else if (f32)
        fprintf(stderr,
                "qdc: note: %s: coordinates written as float32, as in the input\n", out);
}

static int positional(const char *a, const char **in, const char **out);
static qdc_status load_input(const char *path, meshio_format fin, surface_format sin,
                             const tetra_options *to, progress_state *ps, int keep,
                             mesh_t **m, qdc_error *err);

/* OUT named in a format qdc reads but does not write (a surface: .stl, .off,
 * .obj, .poly, .smesh, gzipped or not): said before anything is read, and 1.
 * --out-format or "-" decides otherwise. */
static int read_only_out(const char *out, meshio_format fout)
{
    char name[4096], upper[16];
    const char *base = strrchr(out, '/');
    size_t n;
    surface_format sf;

    if (fout != MESHIO_AUTO || !strcmp(out, "-"))
        return 0;
    snprintf(name, sizeof name, "%s", base ? base + 1 : out);
    n = strlen(name);
    if (n > 3 && !strcmp(name + n - 3, ".gz"))
        name[n - 3] = 0;
    if (!strchr(name, '.') || (sf = surface_format_from_name(name)) == SURFACE_AUTO)
        return 0;
    snprintf(upper, sizeof upper, "%s", surface_format_name(sf));
    for (char *c = upper; *c; c++)
        *c = (char)(*c >= 'a' && *c <= 'z' ? *c - 'a' + 'A' : *c);
    fprintf(stderr,
            "qdc: %s: %s is a surface format qdc reads but does not write: name a tet "
            "mesh (.mesh, .meshb, .msh, .vtk, .vtu, .node, .json, .qmesh, .xml, .inp, "
            ".vol, .bdf, .unv, .xdmf, .med) or give --out-format; nothing was done\n",
            out, upper);
    return 1;
}

/* qdc convert IN OUT: read, then write (spliced when OUT is in IN's format). */
int cli_convert(int argc, char **argv)
{
    const char *in = NULL, *out = NULL;
    meshio_format fin = MESHIO_AUTO, fout = MESHIO_AUTO;
    progress_state ps = {0, 0, 0};
    int keep = 1;
    mesh_t *m = NULL;
    qdc_error err;
    qdc_status st;
    int rc = CLI_OK;

    qdc_error_clear(&err);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            puts("usage: qdc convert IN OUT [--in-format F] [--out-format F] "
                 "[--no-keep-source] [--quiet]\n"
                 "  OUT in IN's format: IN with only the coordinates replaced (here: "
                 "unchanged)");
            return CLI_OK;
        } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
            ps.quiet = 1;
        } else if (!strcmp(a, "--no-keep-source")) {
            keep = 0;
        } else if ((!strcmp(a, "--in-format") || !strcmp(a, "--out-format")) && v) {
            meshio_format f = meshio_format_from_name(v);
            if (f == MESHIO_AUTO) {
                fprintf(stderr, "qdc: bad value '%s' for %s\n", v, a);
                return CLI_EUSAGE;
            }
            *(a[2] == 'i' ? &fin : &fout) = f;
            i++;
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "qdc: convert: unexpected argument '%s'\n", a);
            return CLI_EUSAGE;
        } else if (positional(a, &in, &out)) {
            return CLI_EUSAGE;
        }
    }
    if (!in || !out) {
        fputs("usage: qdc convert IN OUT [--in-format F] [--out-format F] "
              "[--no-keep-source] [--quiet]\n",
              stderr);
        return CLI_EUSAGE;
    }
    if (read_only_out(out, fout))
        return CLI_EINPUT;
    st = load_input(in, fin, SURFACE_AUTO, NULL, &ps, keep, &m, &err);
    if (st != QDC_OK) {
        cli_error(in, &err, st);
        rc = st == QDC_ENOMEM ? CLI_EOPT : CLI_EINPUT;
        goto out;
    }
    source_note(m, out, fout, ps.quiet);
    st = cli_save_mesh(out, fout, m, &err);
    if (st != QDC_OK) {
        cli_error(out, &err, st);
        rc = CLI_EOUTPUT;
    } else if (!ps.quiet) {
        fprintf(stderr, "qdc: %s -> %s: %d vertices, %d tets\n", in, out, (int)m->nv,
                (int)m->nt);
    }
out:
    mesh_free(m);
    return rc;
}

static int on_off(const char *s, int *out)
{
    if (!strcmp(s, "on") || !strcmp(s, "1") || !strcmp(s, "yes"))
        *out = 1;
    else if (!strcmp(s, "off") || !strcmp(s, "0") || !strcmp(s, "no"))
        *out = 0;
    else
        return -1;
    return 0;
}

/* --fix FILE: vertex indices (0-based, whitespace separated, '#' comments) that
 * must not move. Sets m->fixed; one-line error with file:line on bad input. */
static int load_fix(const char *path, mesh_t *m)
{
    FILE *f = fopen(path, "r");
    char line[4096];
    long lineno = 0;

    if (!f) {
        fprintf(stderr, "qdc: %s: cannot open\n", path);
        return CLI_EINPUT;
    }
    if (!m->fixed) {
        m->fixed = qdc_calloc((size_t)m->nv, 1);
        if (!m->fixed) {
            fclose(f);
            fprintf(stderr, "qdc: out of memory\n");
            return CLI_EOPT;
        }
    }
    while (fgets(line, sizeof line, f)) {
        char *p = line, *hash = strchr(line, '#');
        lineno++;
        if (hash)
            *hash = 0;
        for (;;) {
            char *end;
            long v;
            while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r' || *p == ',')
                p++;
            if (!*p)
                break;
            v = strtol(p, &end, 10);
            if (end == p || v < 0 || v >= m->nv) {
                fprintf(stderr,
                        "qdc: %s:%ld: expected a vertex index in [0, %d), got '%.20s'\n",
                        path, lineno, (int)m->nv, p);
                fclose(f);
                return CLI_EINPUT;
            }
            m->fixed[v] = 1;
            p = end;
        }
    }
    fclose(f);
    return CLI_OK;
}

static int write_report(const char *path, const report_t *r)
{
    FILE *f = strcmp(path, "-") ? fopen(path, "w") : stdout;
    qdc_error err;
    qdc_status st;

    qdc_error_clear(&err);
    if (!f) {
        fprintf(stderr, "qdc: %s: cannot open for writing\n", path);
        return CLI_EOUTPUT;
    }
    st = report_write_json(r, report_file_writer, f, &err);
    if ((f != stdout && fclose(f) != 0) || st != QDC_OK) {
        fprintf(stderr, "qdc: %s: write failed\n", path);
        return CLI_EOUTPUT;
    }
    return CLI_OK;
}

/* A mesh, or a closed surface tetrahedralized with TetGen: a surface format
 * named by --in-format or the extension, else a file no mesh reader claims
 * whose content looks like a surface. to (NULL: defaults) only applies to
 * surfaces; giving it for a mesh is an error. */
/* "-" is standard input; a pipe, a device or /dev/stdin is read once (its
 * format told by --in-format, its name, or its contents). */
static int is_stream(const char *path)
{
    struct stat sb;

    return !strcmp(path, "-") ||
           (stat(path, &sb) == 0 && !S_ISREG(sb.st_mode) && !S_ISDIR(sb.st_mode));
}

static const char *sys_path(const char *path)
{
    return strcmp(path, "-") ? path : "/dev/stdin";
}

qdc_status cli_slurp(const char *path, char **buf, size_t *len, qdc_error *err)
{
    return meshio_slurp_plain(sys_path(path), buf, len, err);
}

surface_format cli_input_surface(const char *path, char **buf, size_t *len)
{
    surface_format sf = surface_format_from_name(path);
    qdc_error e;

    *buf = NULL;
    *len = 0;
    if (sf == SURFACE_AUTO && meshio_format_from_name(path) == MESHIO_AUTO &&
        cli_slurp(path, buf, len, &e) == QDC_OK &&
        meshio_sniff(*buf, *len) == MESHIO_AUTO)
        sf = surface_sniff(*buf, *len);
    return sf;
}

qdc_status cli_read_mesh(const char *path, meshio_format fin, const meshio_options *mo,
                         mesh_t **m, char **raw, size_t *rawlen, qdc_error *err)
{
    meshio_format f = fin != MESHIO_AUTO ? fin : meshio_format_from_name(path);
    char *buf = NULL;
    size_t len = 0;
    qdc_status st;

    *raw = NULL;
    *rawlen = 0;
    if (!is_stream(path) && cli_h5_wanted(path, f))
        return cli_h5_read(path, mo, m, err); /* no bytes to send as they are */
    if (!is_stream(path) &&
        (f == MESHIO_TETGEN || (f == MESHIO_AUTO && access(path, F_OK))))
        return meshio_load_ex(path, fin, mo, m, err); /* TetGen's two files */
    st = cli_slurp(path, &buf, &len, err);
    if (st == QDC_OK && (f == MESHIO_AUTO || f == MESHIO_MED) && cli_h5_bytes(buf, len)) {
        st = cli_h5_read_bytes(path, buf, len, mo, m, err); /* MED on standard input */
        qdc_free(buf);
        return st;
    }
    if (st == QDC_OK)
        st = meshio_read_ex(buf, len, f, mo, m, err);
    if (st != QDC_OK) {
        qdc_free(buf);
        return st;
    }
    *raw = buf;
    *rawlen = len;
    return QDC_OK;
}

qdc_status cli_load_mesh(const char *path, meshio_format fin, const meshio_options *mo,
                         mesh_t **m, qdc_error *err)
{
    char *raw;
    size_t len;
    qdc_status st;

    if (!is_stream(path) &&
        cli_h5_wanted(path, fin != MESHIO_AUTO ? fin : meshio_format_from_name(path)))
        return cli_h5_read(path, mo, m, err);
    if (!is_stream(path)) {
        st = meshio_load_ex(path, fin, mo, m, err);
        return cli_xdmf_h5_retry(path, st, mo, m, err);
    }
    st = cli_read_mesh(path, fin, mo, m, &raw, &len, err);
    qdc_free(raw);
    return st;
}

static qdc_status load_input(const char *path, meshio_format fin, surface_format sin,
                             const tetra_options *to, progress_state *ps, int keep,
                             mesh_t **m, qdc_error *err)
{
    meshio_options mo = {.log = on_log, .log_ctx = ps, .source = keep ? 1 : -1};
    char *buf = NULL;
    size_t len = 0;
    int stream = is_stream(path);
    qdc_status st;

    if (fin == MESHIO_AUTO && sin == SURFACE_AUTO) {
        sin = cli_input_surface(path, &buf, &len);
        if (!stream && sin == SURFACE_AUTO) { /* a file: read again with its source */
            qdc_free(buf);
            buf = NULL;
        }
    }
    if (sin == SURFACE_AUTO) {
        if (to) {
            qdc_free(buf);
            return qdc_fail(
                err, QDC_EINVAL,
                "--tetgen-quality and --max-volume apply to surface input only");
        }
        if (!buf)
            return cli_load_mesh(path, fin, &mo, m, err);
        if (cli_h5_bytes(buf, len)) /* a stream, read above */
            st = cli_h5_read_bytes(path, buf, len, &mo, m, err);
        else
            st = meshio_read_ex(buf, len, fin, &mo, m, err);
        qdc_free(buf);
        return st;
    }
    st = buf ? QDC_OK : cli_slurp(path, &buf, &len, err);
    if (st == QDC_OK)
        st = tetra_from_buffer(buf, len, sin, to, m, err);
    qdc_free(buf);
    if (st == QDC_OK)
        on_log(ps, 0, "tetrahedralized the surface with TetGen");
    return st;
}

static int stdout_write(void *ctx, const void *data, size_t len)
{
    (void)ctx;
    return fwrite(data, 1, len, stdout) == len ? 0 : -1;
}

qdc_status cli_save_mesh(const char *out, meshio_format fout, const mesh_t *m,
                         qdc_error *err)
{
    meshio_format f;
    qdc_status st;

    f = meshio_save_format(out, fout, m);
    if (f == MESHIO_MED)
        return cli_h5_write(out, m, err);
    if (f == MESHIO_XDMF && cli_xdmf_h5_source(m))
        return cli_xdmf_h5_write(out, m, err);
    if (strcmp(out, "-"))
        return meshio_save(out, fout, m, err);
    if (f == MESHIO_AUTO) /* not read from a mesh file (a surface) */
        f = MESHIO_MEDIT;
    if (f == MESHIO_TETGEN)
        return qdc_fail(err, QDC_EINVAL,
                        "TetGen's format is two files (.node and .ele): give their name, "
                        "or another --out-format");
    st = meshio_write(m, f, stdout_write, NULL, err);
    if (fflush(stdout) != 0 && st == QDC_OK)
        st = qdc_fail(err, QDC_EIO, "cannot write to standard output: %s",
                      strerror(errno));
    return st;
}

/* --tetgen-quality Q (0 or >= 1) or --max-volume V (>= 0) into to; -1 if v is
 * not such a number. Shared by optimize and tetra. */
static int tetgen_opt(const char *a, const char *v, tetra_options *to)
{
    char *end;
    int q = !strcmp(a, "--tetgen-quality");
    double x = strtod(v, &end);

    if (*end || !(x >= 0) || x > 1e300 || (q && x > 0 && x < 1))
        return -1;
    *(q ? &to->quality : &to->max_volume) = x;
    return 0;
}

/* IN, then OUT; -1 (message said) for a third. */
static int positional(const char *a, const char **in, const char **out)
{
    if (!*in) {
        *in = a;
    } else if (!*out) {
        *out = a;
    } else {
        fprintf(stderr, "qdc: unexpected argument '%s'\n", a);
        return -1;
    }
    return 0;
}

/* What `qdc optimize` was asked to do. */
typedef struct {
    const char *in, *out, *report_path, *fix_path;
    meshio_format fin, fout;
    surface_format sin;
    tetra_options to;
    int tetgen_opts, reorient, keep;
    opt_options o;
    progress_state ps;
} optimize_args;

/* One --NAME VALUE of `qdc optimize`: the library's option table first,
 * then the CLI's own. CLI_OK, or CLI_EUSAGE with the message said. */
static int optimize_option(optimize_args *x, const char *a, const char *v)
{
    qdc_error err;
    int bad = 0;

    qdc_error_clear(&err);
    if (opt_find(a + 2)) {
        /* the library's option table: its names, ranges and messages */
        if (opt_set(&x->o, a + 2, v, &err) != QDC_OK) {
            fprintf(stderr, "qdc: %s\n", err.msg);
            return CLI_EUSAGE;
        }
    } else if (!strcmp(a, "--tetgen-quality") || !strcmp(a, "--max-volume")) {
        bad = tetgen_opt(a, v, &x->to);
        x->tetgen_opts = 1;
    } else if (!strcmp(a, "--in-format") || !strcmp(a, "--format")) {
        x->fin = meshio_format_from_name(v);
        x->sin = x->fin == MESHIO_AUTO ? surface_format_from_name(v) : SURFACE_AUTO;
        bad = x->fin == MESHIO_AUTO && x->sin == SURFACE_AUTO;
        if (!strcmp(a, "--format") && !bad)
            bad = (x->fout = x->fin) == MESHIO_AUTO;
    } else if (!strcmp(a, "--out-format"))
        bad = (x->fout = meshio_format_from_name(v)) == MESHIO_AUTO;
    else if (!strcmp(a, "--report"))
        x->report_path = v;
    else if (!strcmp(a, "--fix"))
        x->fix_path = v;
    else if (!strcmp(a, "--reorient"))
        bad = on_off(v, &x->reorient);
    else if (!strcmp(a, "--threads")) {
        char *end;
        long n = strtol(v, &end, 10);
        bad = !*v || *end || n < 1 || n > 1024;
        x->o.threads = bad ? 0 : (int)n;
    } else {
        char near[64];
        if (cli_optimize_suggest(a, near, sizeof near))
            fprintf(stderr,
                    "qdc: unknown option %s: did you mean %s? (qdc optimize --help)\n", a,
                    near);
        else
            fprintf(stderr, "qdc: unknown option %s (see qdc optimize --help)\n", a);
        return CLI_EUSAGE;
    }
    if (bad) {
        fprintf(stderr, "qdc: bad value '%s' for %s\n", v, a);
        return CLI_EUSAGE;
    }
    return CLI_OK;
}

/* The command line into x: -1 to go on, else the exit status (--help
 * printed, or the usage error said). */
static int optimize_parse(int argc, char **argv, optimize_args *x)
{
    memset(x, 0, sizeof *x);
    x->keep = 1;
    opt_defaults(&x->o);
    tetra_defaults(&x->to);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            cli_optimize_usage(stdout);
            return CLI_OK;
        } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
            x->ps.quiet = 1;
        } else if (!strcmp(a, "--no-keep-source")) {
            x->keep = 0;
        } else if (a[0] == '-' && a[1] == '-') {
            if (!v) {
                fprintf(stderr, "qdc: %s needs a value\n", a);
                return CLI_EUSAGE;
            }
            i++;
            int rc = optimize_option(x, a, v);
            if (rc != CLI_OK)
                return rc;
        } else if (positional(a, &x->in, &x->out)) {
            return CLI_EUSAGE;
        }
    }
    if (!x->in || !x->out) {
        fputs(
            "usage: qdc optimize IN OUT [options]   (the options: qdc optimize --help)\n",
            stderr);
        return CLI_EUSAGE;
    }
    if (!strcmp(x->out, "-") && x->report_path && !strcmp(x->report_path, "-")) {
        fputs("qdc: OUT and --report cannot both be standard output ('-')\n", stderr);
        return CLI_EUSAGE;
    }
    return -1;
}

/* OUT written: with --reorient every tet in the order that is positive
 * under the mesh's orientation (*rewrote: 1 if that rewrote a tet of m),
 * spliced when OUT is in IN's format. */
static int optimize_write(const optimize_args *x, mesh_t *m, int *rewrote)
{
    qdc_error err;
    qdc_status st;

    qdc_error_clear(&err);
    /* the input file, parked during the run, is read again for a spliced
     * write; if it changed meanwhile, qdc's own writer writes OUT */
    if (meshio_unpark_source(m, &err) != QDC_OK) {
        char kept[240];
        if (!x->ps.quiet)
            fprintf(
                stderr,
                "qdc: note: %s (read again to write %s in its layout): %s is "
                "written by qdc's own writer: %s\n",
                err.msg, x->out, x->out,
                kept_words(m, meshio_save_format(x->out, x->fout, m), kept, sizeof kept));
        meshio_drop_source(m);
        qdc_error_clear(&err);
    }
    if (x->reorient) {
        mesh_orientation mo;
        st = mesh_reorient(m, &mo, &err);
        if (st != QDC_OK) {
            cli_error(x->in, &err, st);
            return CLI_EOPT;
        }
        *rewrote = mo.flipped > 0;
        if (!x->ps.quiet && mo.flipped)
            fprintf(stderr,
                    "qdc: note: %d of %d tets written in the other vertex order "
                    "(--reorient): positive under the mesh's orientation\n",
                    (int)mo.flipped, (int)m->nt);
    }
    source_note(m, x->out, x->fout, x->ps.quiet);
    st = cli_save_mesh(x->out, x->fout, m, &err);
    if (st != QDC_OK) {
        cli_error(x->out, &err, st);
        return CLI_EOUTPUT;
    }
    return CLI_OK;
}

/* The two summary lines: quality before and after, where the time went. */
static void optimize_summary(const optimize_args *x, const opt_result *res)
{
    char deg[64] = "";

    if (x->ps.quiet)
        return;
    if (res->before.n_degenerate > 0 || res->after.n_degenerate > 0)
        snprintf(deg, sizeof deg, "degenerate %d -> %d, ", (int)res->before.n_degenerate,
                 (int)res->after.n_degenerate);
    fprintf(stderr,
            "qdc: %s -> %s: mean ratio %.4f -> %.4f, min %+.4f -> %+.4f, inverted %d "
            "-> %d, %s"
            "dihedral %.2f..%.2f -> %.2f..%.2f (%s, %d iterations, %s, %.2fs)\n",
            x->in, x->out, res->before.q_mean, res->after.q_mean, res->before.q_min,
            res->after.q_min, (int)(res->before.n_inverted - res->before.n_degenerate),
            (int)(res->after.n_inverted - res->after.n_degenerate), deg,
            res->before.dih_min, res->before.dih_max, res->after.dih_min,
            res->after.dih_max, res->stop_reason, res->last_record,
            opt_solver_name(res->solver), res->t_total);
    fprintf(stderr,
            "qdc: seconds: setup %.2f, weights %.2f, assembly %.2f, solve %.2f, "
            "line search %.2f, harmonic %.2f, finish %.2f\n",
            res->t_setup, res->t_weights, res->t_assembly, res->t_solve,
            res->t_linesearch, res->t_harmonic, res->t_finish);
    if (res->tets_in > 0)
        fprintf(stderr,
                "qdc: topology %s: tets %d -> %d, vertices %d -> %d (%lld inserted); "
                "%lld edges removed "
                "(rings of 3: %lld, 4: %lld, 5: %lld, 6: %lld, 7-10: %lld), %lld 2-3 "
                "flips, %lld multi-face removals; rounds: %d\n",
                opt_topology_name(x->o.topology), (int)res->tets_in, (int)res->tets_out,
                (int)res->verts_in, (int)res->verts_out, (long long)res->topo_insertions,
                (long long)res->topo_edge_removals, (long long)res->topo_by_ring[3],
                (long long)res->topo_by_ring[4], (long long)res->topo_by_ring[5],
                (long long)res->topo_by_ring[6],
                (long long)(res->topo_by_ring[7] + res->topo_by_ring[8] +
                            res->topo_by_ring[9] + res->topo_by_ring[10]),
                (long long)res->topo_flips23, (long long)res->topo_multiface,
                res->topo_rounds);
    if (res->topo_contractions > 0)
        fprintf(stderr, "qdc: topology: %lld interior edges contracted\n",
                (long long)res->topo_contractions);
    if (res->topo_bflips + res->topo_peels + res->topo_bcontractions > 0)
        fprintf(
            stderr,
            "qdc: topology: %lld boundary edge flips, %lld tets peeled, %lld boundary "
            "edges contracted within the bound: boundary triangles %d removed, %d "
            "added\n",
            (long long)res->topo_bflips, (long long)res->topo_peels,
            (long long)res->topo_bcontractions, (int)res->topo_tris_removed,
            (int)res->topo_tris_added);
}

/* The outcome in words (docs/defaults.md), the last lines: from the report when
 * there is one (the same words as its "outcome"), else from a scan of the result. */
static void print_outcome(const report_t *r)
{
    outcome_t o;

    if (outcome_compute(r, &o) != QDC_OK)
        return;
    fprintf(stderr, "qdc: outcome: %s\n", o.summary);
    for (int i = 0; i < o.n_warnings; i++)
        fprintf(stderr, "qdc: warning: %s\n", o.warnings[i]);
    for (int i = 0; i < o.n_suggestions; i++)
        fprintf(stderr, "qdc: suggestion: %s\n", o.suggestions[i]);
}

/* 1 (said on stderr) when m has second-order tets and OUT's format would
 * write them only spliced over a source it cannot splice: refused before the
 * run, which would otherwise end with OUT unwritten (exit 4). */
static int p2_out_refused(const char *out, meshio_format fout, const mesh_t *m)
{
    meshio_format f = meshio_save_format(out, fout, m);
    const char *why = NULL;

    if (!m->mid || f == MESHIO_AUTO || meshio_splices(m, f, &why) ||
        meshio_writes_p2(f) || !meshio_format_name(f))
        return 0;
    fprintf(
        stderr,
        "qdc: %s: %s: second-order (10-node) tets are written only as the input file "
        "with new coordinates, and here %s (qdc's %s writer writes linear tets): name "
        "OUT in IN's format or one whose writer writes them (.msh, .vtk, .vtu, .mesh, "
        ".inp, .vol, .bdf, .unv, .xdmf, .med, .json, .qmesh) or give --out-format; "
        "nothing was done\n",
        out, meshio_format_name(f), why ? why : "no source is kept",
        meshio_format_name(f));
    return 1;
}

int cli_topology_out_refused(const char *out, meshio_format fout, const mesh_t *m,
                             const char *topology, const char *what)
{
    meshio_format f = meshio_save_format(out, fout, m);

    if (f == MESHIO_AUTO || meshio_has_writer(f))
        return 0;
    fprintf(stderr,
            "qdc: %s: %s is written only as the input file with new coordinates, and "
            "--topology %s changes the tets: name OUT in a format qdc writes (.mesh, "
            ".meshb, .msh, .vtk, .vtu, .json, .qmesh, .xml, .inp, .vol, .bdf, .unv, "
            ".xdmf) or give --out-format; nothing was %s\n",
            out, meshio_format_name(f) ? meshio_format_name(f) : "?", topology, what);
    return 1;
}

/* The outcome and --report FILE.json: quality of the input (orig, NULL without
 * --report) and of the result (m), the boundary error between them, the run.
 * faces (may be NULL): the input's faces as the run found them (opt_run_faces);
 * out_faces: they are m's too (--reorient rewrote none of its tets). */
static int optimize_report(const optimize_args *x, const mesh_t *orig, const mesh_t *m,
                           const opt_result *res, const mesh_faces *faces, int out_faces)
{
    report_quality qb, qa;
    bderr_result be;
    report_t r = {orig ? &qb : NULL, &qa, res, &x->o, orig ? &be : NULL};
    qdc_error err;
    qdc_status st;

    if (x->ps.quiet && !orig)
        return CLI_OK;
    qdc_error_clear(&err);
    st = report_quality_faces(m, out_faces ? faces : NULL, &qa, &err);
    if (st == QDC_OK && orig)
        st = report_quality_faces(orig, faces, &qb, &err);
    if (st == QDC_OK && orig)
        st = bderr_meshes_faces(m, orig, out_faces ? faces : NULL, 200000, &be, &err);
    if (st != QDC_OK && !orig)
        return CLI_OK; /* no outcome (out of memory): the result is written */
    if (st != QDC_OK) {
        cli_error(x->report_path, &err, st);
        return CLI_EOUTPUT;
    }
    if (!x->ps.quiet)
        print_outcome(&r);
    return orig ? write_report(x->report_path, &r) : CLI_OK;
}

int cli_optimize(int argc, char **argv)
{
    optimize_args x;
    opt_result res;
    mesh_t *m = NULL, *orig = NULL;
    mesh_faces *faces = NULL;
    qdc_error err;
    qdc_status st;
    int rewrote = 0, rc = optimize_parse(argc, argv, &x);
    struct sigaction sa;

    if (rc >= 0)
        return rc;
    if (x.o.threads > 0) /* the reading and the report too, not only the run */
        omp_set_num_threads(x.o.threads);
    if (read_only_out(x.out, x.fout))
        return CLI_EINPUT;
    rc = CLI_OK;
    qdc_error_clear(&err);
    x.ps.tty = isatty(STDERR_FILENO);
    x.o.progress = on_progress;
    x.o.progress_ctx = &x.ps;
    x.o.log = on_log;
    x.o.log_ctx = &x.ps;
    x.o.cancel = &cancel_flag;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);

    /* no mesh_validate here: opt_run checks the mesh as it builds its topology
     * (the same checks and messages, in the file's numbering; QDC_EMESH is an
     * input error below), and the face matching is not done twice (0.15 s of
     * an 800k-tet run) */
    st = load_input(x.in, x.fin, x.sin, x.tetgen_opts ? &x.to : NULL, &x.ps, x.keep, &m,
                    &err);
    if (st != QDC_OK) {
        cli_error(x.in, &err, st);
        rc = st == QDC_ENOMEM ? CLI_EOPT : CLI_EINPUT;
        goto out;
    }
    if (x.fix_path && (rc = load_fix(x.fix_path, m)) != CLI_OK)
        goto out;
    /* said before the run: written only over its source, OUT could not be
     * written after it (the run was the whole wait, then exit 4) */
    if (x.o.topology != OPT_TOPOLOGY_NONE &&
        cli_topology_out_refused(x.out, x.fout, m, opt_topology_name(x.o.topology),
                                 "done")) {
        rc = CLI_EUSAGE;
        goto out;
    }
    if (p2_out_refused(x.out, x.fout, m)) {
        rc = CLI_EUSAGE;
        goto out;
    }
    orig = x.report_path ? mesh_dup(m) : NULL;
    if (x.report_path && !orig) {
        fprintf(stderr, "qdc: out of memory\n");
        rc = CLI_EOPT;
        goto out;
    }
    /* the input file's bytes (kept for a spliced write) are freed during the
     * run and read again at writing: a 5M-tet Medit file is 215 MB, 15% of
     * the run's peak memory */
    meshio_park_source(m);
    /* the run's faces serve the report (no second face matching) */
    st = opt_run_faces(m, &x.o, &res, x.ps.quiet && !orig ? NULL : &faces, &err);
    if (x.ps.tty && x.ps.last_len)
        fputc('\n', stderr);
    if (st != QDC_OK) {
        cli_error(x.in, &err, st);
        rc = st == QDC_EMESH || st == QDC_EINVAL ? CLI_EINPUT : CLI_EOPT;
        goto out;
    }
    rc = optimize_write(&x, m, &rewrote);
    if (rc != CLI_OK)
        goto out;
    optimize_summary(&x, &res);
    rc = optimize_report(&x, orig, m, &res, faces, !rewrote);
    if (rc == CLI_OK && interrupted)
        rc = CLI_EINTR;
out:
    mesh_faces_free(faces);
    mesh_free(m);
    mesh_free(orig);
    return rc;
}

static const char tetra_use[] =
    "usage: qdc tetra IN OUT [--tetgen-quality Q] [--max-volume V] [--max-tets N]\n"
    "                 [--max-memory BYTES] [--out-format F] [--quiet]\n"
    "  IN: closed triangle surface (.stl .off .obj .poly .smesh); OUT: any mesh "
    "format\n"
    "  (by its extension or --out-format; '-': standard input or output)\n"
    "  --max-tets N: refuse at once when the volume bound alone makes more tets\n"
    "  (the enclosed volume / V); --max-memory: address-space limit of the run\n"
    "  exit 0 ok, 1 usage, 2 bad surface, 3 TetGen failed, 4 OUT not written\n";

/* What `qdc tetra` was asked to do. */
typedef struct {
    const char *in, *out;
    tetra_options to;
    long long max_tets, max_memory;
    meshio_format fout;
    int quiet;
} tetra_args;

/* The command line into x: -1 to go on, else the exit status (--help
 * printed, the usage error said, or the parent already gone). */
static int tetra_parse(int argc, char **argv, tetra_args *x)
{
    memset(x, 0, sizeof *x);
    tetra_defaults(&x->to);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            fputs(tetra_use, stdout);
            return CLI_OK;
        } else if (!strcmp(a, "--tetgen-quality") || !strcmp(a, "--max-volume")) {
            if (i + 1 >= argc || tetgen_opt(a, argv[i + 1], &x->to)) {
                fprintf(stderr, "qdc: bad value for %s\n", a);
                return CLI_EUSAGE;
            }
            i++;
        } else if (!strcmp(a, "--max-tets") || !strcmp(a, "--max-memory")) {
            char *end;
            long long v = i + 1 < argc ? strtoll(argv[i + 1], &end, 10) : -1;
            if (i + 1 >= argc || *end || v <= 0) {
                fprintf(stderr, "qdc: bad value for %s\n", a);
                return CLI_EUSAGE;
            }
            *(!strcmp(a, "--max-tets") ? &x->max_tets : &x->max_memory) = v;
            i++;
        } else if (!strcmp(a, "--out-format") && i + 1 < argc) {
            x->fout = meshio_format_from_name(argv[++i]);
            if (x->fout == MESHIO_AUTO) {
                fprintf(stderr, "qdc: bad value '%s' for --out-format\n", argv[i]);
                return CLI_EUSAGE;
            }
        } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
            x->quiet = 1;
        } else if (!strcmp(a, "--die-with-parent")) {
            /* qdcd's child: end with the worker that waits for us. */
#ifdef __linux__
            prctl(PR_SET_PDEATHSIG, SIGKILL);
            if (getppid() == 1)
                return CLI_EOPT;
#endif
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "qdc: tetra: unknown option %s\n%s", a, tetra_use);
            return CLI_EUSAGE;
        } else if (positional(a, &x->in, &x->out)) {
            return CLI_EUSAGE;
        }
    }
    if (!x->in || !x->out) {
        fputs(tetra_use, stderr);
        return CLI_EUSAGE;
    }
    return -1;
}

/* --max-tets with --max-volume: the enclosed volume (divergence theorem over
 * the closed surface) over the volume bound is a floor of TetGen's tet
 * count. 0, or -1 (message said) when that floor exceeds the limit. */
static int tetra_volume_bound(const tetra_args *x, const surface_t *s)
{
    double vol = 0;

    if (x->max_tets <= 0 || x->to.max_volume <= 0)
        return 0;
    for (int32_t t = 0; t < s->ntri; t++) {
        const double *a = s->xyz + 3 * (size_t)s->tris[3 * (size_t)t];
        const double *b = s->xyz + 3 * (size_t)s->tris[3 * (size_t)t + 1];
        const double *c = s->xyz + 3 * (size_t)s->tris[3 * (size_t)t + 2];
        vol += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
               a[2] * (b[0] * c[1] - b[1] * c[0]);
    }
    vol = fabs(vol) / 6.0;
    if (vol / x->to.max_volume <= (double)x->max_tets)
        return 0;
    fprintf(stderr,
            "qdc: %s: the volume bound %g would make at least %.3g tets (enclosed "
            "volume %g / %g), more than the %lld allowed: raise max_volume\n",
            x->in, x->to.max_volume, vol / x->to.max_volume, vol, x->to.max_volume,
            x->max_tets);
    return -1;
}

/* qdc tetra IN OUT: a closed surface tetrahedralized with TetGen, no
 * optimization. qdcd runs it in a child process for surface uploads, so
 * exit codes are part of its contract: 2 bad surface, 3 TetGen failed, with
 * one "qdc: " line on stderr saying why. */
int cli_tetra(int argc, char **argv)
{
    tetra_args x;
    surface_t *s = NULL;
    mesh_t *m = NULL;
    qdc_error err;
    qdc_status st;
    int rc = tetra_parse(argc, argv, &x);

    if (rc >= 0)
        return rc;
    rc = CLI_OK;
    qdc_error_clear(&err);
    if (x.max_memory > 0) {
        /* TetGen asked for 1e-9 volumes grows by ~70 MB/s: bound the process so
         * that it fails with out-of-memory instead of eating the machine */
        struct rlimit rl = {(rlim_t)x.max_memory, (rlim_t)x.max_memory};
        if (setrlimit(RLIMIT_AS, &rl)) {
            fprintf(stderr, "qdc: cannot limit memory: %s\n", strerror(errno));
            return CLI_EOPT;
        }
    }
    st = surface_load(sys_path(x.in), SURFACE_AUTO, &s, &err);
    if (st == QDC_OK)
        st = surface_check(s, &err);
    if (st == QDC_OK && tetra_volume_bound(&x, s)) {
        surface_free(s);
        return CLI_EINPUT;
    }
    if (st == QDC_OK)
        st = tetra_from_surface_t(s, &x.to, &m, &err);
    if (st == QDC_ENOMEM && x.max_memory > 0)
        fprintf(stderr,
                "qdc: %s: TetGen ran out of its %lld-byte memory limit (raise "
                "max_volume, or the daemon's --child-memory)\n",
                x.in, x.max_memory);
    if (st != QDC_OK) {
        cli_error(x.in, &err, st);
        rc = st == QDC_ETETGEN || st == QDC_ENOMEM || st == QDC_EINTERNAL ? CLI_EOPT
                                                                          : CLI_EINPUT;
        goto out;
    }
    st = cli_save_mesh(x.out, x.fout, m, &err);
    if (st != QDC_OK) {
        cli_error(x.out, &err, st);
        rc = CLI_EOUTPUT;
        goto out;
    }
    if (!x.quiet)
        fprintf(stderr, "qdc: %s -> %s: %d vertices, %d tets\n", x.in, x.out, (int)m->nv,
                (int)m->nt);
out:
    surface_free(s);
    mesh_free(m);
    return rc;
}

/* `qdc quality` as text: counts, mean ratio, dihedral angles, the other
 * measures, and the boundary error against ref (be) when given. */
static void quality_print(const char *in, const report_quality *q, const char *ref,
                          const bderr_result *be)
{
    printf("%s: %d vertices, %d tets, %d inverted, %d degenerate\n", in, (int)q->nv,
           (int)q->nt, (int)q->n_inverted, (int)q->n_degenerate);
    printf("mean ratio: mean %.4f std %.4f min %+.4f\n", q->q_mean, q->q_std, q->q_min);
    printf("dihedral: min %.2f max %.2f deg; tets with min < 5/15/30/40: %d/%d/%d/%d; "
           "max > 175/165/150/140: %d/%d/%d/%d\n",
           q->dih_min, q->dih_max, (int)q->n_dmin_lt[0], (int)q->n_dmin_lt[1],
           (int)q->n_dmin_lt[2], (int)q->n_dmin_lt[3], (int)q->n_dmax_gt[0],
           (int)q->n_dmax_gt[1], (int)q->n_dmax_gt[2], (int)q->n_dmax_gt[3]);
    printf("volume-length: mean %.4f min %+.4f; condition number: mean %.4f max %.4g\n",
           q->vl_mean, q->vl_min, q->cn_mean, q->cn_max);
    if (q->n_surf_lt5 >= 0)
        printf("surface: smallest solid angle at an edge %.2f deg (%d edges under 5: no "
               "tet on one has a larger dihedral there)\n",
               q->surf_angle_min, (int)q->n_surf_lt5);
    if (ref)
        printf("boundary error vs %s: Hausdorff %.6g (%.3g%% of diagonal), mean %.3g, "
               "RMS %.3g\n",
               ref, be->hausdorff, 100 * be->hausdorff_rel, be->mean, be->rms);
}

int cli_quality(int argc, char **argv)
{
    const char *in = NULL, *ref = NULL;
    int json = 0, rc = CLI_OK;
    mesh_t *m = NULL, *r = NULL;
    meshio_options nokeep = {
        .log = NULL, .log_ctx = NULL, .source = -1}; /* nothing is written back */
    report_quality q;
    bderr_result be;
    qdc_error err;
    qdc_status st;

    qdc_error_clear(&err);
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--json"))
            json = 1;
        else if ((!strcmp(argv[i], "--ref") || !strcmp(argv[i], "--orig")) &&
                 i + 1 < argc)
            ref = argv[++i];
        else if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
            puts("usage: qdc quality IN [--ref ORIG] [--json]");
            return CLI_OK;
        } else if ((argv[i][0] != '-' || !argv[i][1]) && !in)
            in = argv[i];
        else {
            fprintf(stderr, "qdc: quality: unexpected argument '%s'\n", argv[i]);
            return CLI_EUSAGE;
        }
    }
    if (!in) {
        fputs("usage: qdc quality IN [--ref ORIG] [--json]\n", stderr);
        return CLI_EUSAGE;
    }
    st = cli_load_mesh(in, MESHIO_AUTO, &nokeep, &m, &err);
    if (st == QDC_OK)
        st = report_quality_compute(m, &q, &err);
    if (st != QDC_OK) {
        cli_error(in, &err, st);
        rc = CLI_EINPUT;
        goto out;
    }
    if (ref) {
        st = cli_load_mesh(ref, MESHIO_AUTO, &nokeep, &r, &err);
        if (st != QDC_OK) {
            cli_error(ref, &err, st);
            rc = CLI_EINPUT;
            goto out;
        }
        st = bderr_meshes(m, r, 200000, &be, &err);
        if (st != QDC_OK) {
            cli_error(ref, &err, st);
            rc = CLI_EINPUT;
            goto out;
        }
    }
    if (json) {
        report_t rep = {NULL, &q, NULL, NULL, ref ? &be : NULL};
        st = report_write_json(&rep, report_file_writer, stdout, &err);
        rc = st == QDC_OK ? CLI_OK : CLI_EOUTPUT;
    } else {
        quality_print(in, &q, ref, &be);
    }
out:
    mesh_free(m);
    mesh_free(r);
    return rc;
}

int cli_formats(int argc, char **argv)
{
    qdc_error err;

    (void)argv;
    if (argc > 1) {
        fprintf(stderr, "usage: qdc formats\n");
        return CLI_EUSAGE;
    }
    if (meshio_formats_json(stdout_write, NULL, &err) != QDC_OK || fflush(stdout)) {
        fprintf(stderr, "qdc: formats: %s\n", err.msg[0] ? err.msg : "write failed");
        return CLI_EOUTPUT;
    }
    return 0;
}
