/* options.h - the optimizer's options, defined once: name, type, valid range,
 * default and help text of every field of opt_options that a user may set.
 * The CLI (its flags and --help), the daemon (query parameters, refused at
 * submit time with the valid range), the stored canonical options of a job and
 * the API documentation all read this table, so an option means the same thing
 * and takes the same values everywhere. Public (qdc.h).
 * Thread-safe: the table is constant. */
#ifndef QDC_OPTIONS_H
#define QDC_OPTIONS_H

#include "core/base.h"
#include "opt/opt.h"

#include <stddef.h>

typedef enum {
    OPT_T_WORD, /* one of words[] (stored as an int-sized enum) */
    OPT_T_BOOL, /* on/off, true/false, yes/no, 1/0 (int) */
    OPT_T_INT,  /* decimal integer in [lo, hi] (int) */
    OPT_T_REAL, /* finite real in [lo, hi], or (lo, hi] when lo_open (double) */
    OPT_T_HAUSD /* opt_parse_hausd's forms (hausd / hausd_rel) */
} opt_type;

/* Where `qdc optimize --help` lists an option: what most runs may set, what
 * says how the boundary may move, the method's own knobs. */
typedef enum { OPT_G_EVERYDAY, OPT_G_BOUNDARY, OPT_G_ADVANCED } opt_group;

typedef struct {
    const char *name; /* query parameter and JSON key; the CLI flag is --name with '-' */
    opt_type type;
    size_t off; /* offset of the field in opt_options */
    double lo, hi;
    int lo_open;
    const char *const *words; /* OPT_T_WORD */
    int nwords;
    const char *help;
    opt_group group;
    const char *const *word_help; /* OPT_T_WORD: what each word means, or NULL */
} opt_desc;

/* The table, static and constant; *n (not NULL) receives its entry count. */
const opt_desc *opt_table(size_t *n);
/* The table's entry named key ('-' and '_' alike), or NULL if none (or key
 * is NULL). */
const opt_desc *opt_find(const char *key);

/* Set one option from its text. The whole text must be the value: no spaces,
 * no trailing bytes, no NaN or infinity, inside the range. QDC_EINVAL with a
 * message that names the option and its valid values otherwise (an unknown key
 * too). Reads key and text; writes only the field in o, which is unchanged on
 * failure. */
qdc_status opt_set(opt_options *o, const char *key, const char *text, qdc_error *err);

/* The value of d's field in o as text ("mivl", "on", "10", "0.001"; hausd as
 * its absolute or "rel:" form): written into buf (n bytes, the caller's),
 * always NUL-terminated, cut if too short (64 bytes is enough). */
void opt_value_text(const opt_desc *d, const opt_options *o, char *buf, size_t n);
/* The valid values of d as text ("mivl|mimr|micn", "(0, 1e+12]", ...), into
 * buf (n bytes, the caller's) as opt_value_text. */
void opt_range_text(const opt_desc *d, char *buf, size_t n);

#endif
