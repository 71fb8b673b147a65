/* help.c - `qdc optimize --help` in groups, from the library's option table
 * (lib/opt/options.h) and the CLI's own options, and the nearest option to a
 * mistyped one. */
#include "cli.h"

#include <stdio.h>
#include <string.h>

/* The CLI's own options of `qdc optimize`: flag (no dashes), argument, group
 * (-1: files), help. */
static const struct {
    const char *flag, *arg;
    int group;
    const char *help;
} own[] = {
    {"report", "FILE.json", OPT_G_EVERYDAY,
     "write the report: quality before and after, 1-degree dihedral histograms, "
     "counts of bad angles, boundary error, timings"},
    {"quiet", NULL, OPT_G_EVERYDAY, "no progress output"},
    {"threads", "N", OPT_G_EVERYDAY,
     "threads for the reading, the run and the report, 1 to 1024 (default: "
     "OMP_NUM_THREADS, else every core); the same result whatever the count"},
    {"fix", "FILE", OPT_G_BOUNDARY,
     "vertices that must not move: 0-based indices, whitespace or comma separated, "
     "'#' comments"},
    {"in-format", "F", -1, NULL}, /* the format table: format_help */
    {"out-format", "F", -1,
     "one of the mesh formats above (default: by extension, else "
     "the input's)"},
    {"format", "F", -1, "both of the above"},
    {"tetgen-quality", "Q", -1, "surface input: TetGen radius-edge bound (default 2)"},
    {"max-volume", "V", -1, "surface input: TetGen maximum tet volume"},
    {"reorient", "on|off", -1,
     "write every tet in the vertex order that is positive under the mesh's "
     "orientation (default off: the input's vertex order)"},
    {"no-keep-source", NULL, -1,
     "OUT is written by qdc's writer even in the input's format (default: the input "
     "file, read again and checked unchanged, with only the coordinates replaced)"},
};
#define N_OWN (sizeof own / sizeof own[0])

/* text wrapped at 80 columns (at a space, or after a '|'): the first line
 * indented by first, the others by rest */
static void wrap(FILE *f, const char *text, int first, int rest)
{
    const char *p = text;

    for (int indent = first; *p; indent = rest) {
        int width = 80 - indent, n = (int)strlen(p);
        if (n > width) {
            n = width;
            while (n > 0 && p[n] != ' ' && p[n - 1] != '|')
                n--;
            if (!n)
                n = width;
        }
        fprintf(f, "%*s%.*s\n", indent, "", n, p);
        p += n;
        while (*p == ' ')
            p++;
    }
}

static void table_option(FILE *f, const opt_desc *d, const opt_options *def)
{
    static const char *const arg[] = {NULL, "on|off", "N", "X", "H"};
    char flag[48], range[200], value[64], text[1200];

    snprintf(flag, sizeof flag, "--%s", d->name);
    for (char *c = flag; *c; c++)
        *c = *c == '_' ? '-' : *c;
    opt_range_text(d, range, sizeof range);
    opt_value_text(d, def, value, sizeof value);
    fprintf(f, "  %s %s\n", flag, d->type == OPT_T_WORD ? range : arg[d->type]);
    if (d->type == OPT_T_WORD || d->type == OPT_T_BOOL)
        snprintf(text, sizeof text, "%s; default %s", d->help, value);
    else
        snprintf(text, sizeof text, "%s; %s; default %s", d->help, range, value);
    wrap(f, text, 6, 6);
    for (int w = 0; d->word_help && w < d->nwords; w++) {
        snprintf(text, sizeof text, "%-7s %s%s", d->words[w], d->word_help[w],
                 strcmp(d->words[w], value) ? "" : " (the default)");
        wrap(f, text, 8, 16);
    }
}

/* The --in-format help: the names of the library's format table
 * (lib/io/formats.h), then the surfaces. */
static void format_help(char *text, size_t cap)
{
    size_t n = 0;

    for (int k = 1; meshio_format_name((meshio_format)k) && n < cap; k++)
        n += (size_t)snprintf(text + n, cap - n, "%s%s", k > 1 ? "|" : "",
                              meshio_format_name((meshio_format)k));
    for (int k = 1; surface_format_name((surface_format)k) && n < cap; k++)
        n += (size_t)snprintf(text + n, cap - n, "%s%s", k > 1 ? "|" : ", or a surface: ",
                              surface_format_name((surface_format)k));
    if (n < cap)
        snprintf(text + n, cap - n, " (default: by extension, then content)");
}

static void own_option(FILE *f, size_t i)
{
    char text[1024];

    fprintf(f, "  --%s%s%s\n", own[i].flag, own[i].arg ? " " : "",
            own[i].arg ? own[i].arg : "");
    if (!own[i].help)
        format_help(text, sizeof text);
    wrap(f, own[i].help ? own[i].help : text, 6, 6);
}

void cli_optimize_usage(FILE *f)
{
    static const char *const heading[] = {
        "Everyday:",
        "Boundary (how far the surface may move):",
        "Advanced (the method's own knobs; docs/method.md):",
    };
    size_t n;
    const opt_desc *t = opt_table(&n);
    opt_options d;

    opt_defaults(&d);
    fputs("usage: qdc optimize IN OUT [options]\n"
          "  IN and OUT are mesh files, the format told by the extension, then the\n"
          "  contents (.gz read and written); '-' is standard input or output. A closed\n"
          "  surface (.stl .off .obj .poly .smesh) as IN is tetrahedralized by TetGen\n"
          "  first. Options take their value as the next argument (--max-iter 20).\n",
          f);
    for (int g = OPT_G_EVERYDAY; g <= OPT_G_ADVANCED; g++) {
        fprintf(f, "\n%s\n", heading[g]);
        for (size_t i = 0; i < n; i++)
            if ((int)t[i].group == g)
                table_option(f, &t[i], &d);
        for (size_t i = 0; i < N_OWN; i++)
            if (own[i].group == g)
                own_option(f, i);
        if (g == OPT_G_BOUNDARY) {
            fputs("\nFiles:\n", f);
            for (size_t i = 0; i < N_OWN; i++)
                if (own[i].group < 0)
                    own_option(f, i);
        }
    }
}

int cli_optimize_suggest(const char *flag, char *buf, size_t len)
{
    const char *cands[128];
    const char *near;
    size_t n, k = 0;
    const opt_desc *t = opt_table(&n);

    while (*flag == '-')
        flag++;
    for (size_t i = 0; i < n && k < 100; i++)
        cands[k++] = t[i].name; /* cli_suggest takes '_' for '-' */
    for (size_t i = 0; i < N_OWN; i++)
        cands[k++] = own[i].flag;
    cands[k++] = "help";
    near = cli_suggest(flag, cands, k);
    if (!near)
        return 0;
    snprintf(buf, len, "--%s", near);
    for (char *c = buf; *c; c++)
        *c = *c == '_' ? '-' : *c;
    return 1;
}
