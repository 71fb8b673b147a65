/* jobopt.c - the job options (jobopt.h): the library's option table read
 * from a query string or a job's stored JSON, and written back as JSON. */
#define _GNU_SOURCE
#include "jobopt.h"

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* The options are the library's table (lib/opt/options.h): the same names,
 * ranges and defaults as the CLI; a value accepted at submit time is one the
 * optimizer accepts. */
int job_opt_set(opt_options *o, const char *key, const char *val, double cap_time,
                char *why, size_t why_cap)
{
    qdc_error err;

    qdc_error_clear(&err);
    if (opt_set(o, key, val, &err) != QDC_OK) {
        snprintf(why, why_cap, "%.*s", (int)(why_cap > 0 ? why_cap - 1 : 0), err.msg);
        return -1;
    }
    if (cap_time > 0 && (o->time_limit <= 0 || o->time_limit > cap_time))
        o->time_limit = cap_time;
    return 0;
}

/* Canonical options JSON: every option of the table, in its order. */
void job_opt_json(const opt_options *o, sbuf *out)
{
    size_t n;
    const opt_desc *t = opt_table(&n);
    char v[64];

    sb_puts(out, "{");
    for (size_t i = 0; i < n; i++) {
        sb_printf(out, "%s\"%s\":", i ? "," : "", t[i].name);
        opt_value_text(&t[i], o, v, sizeof v);
        switch (t[i].type) {
        case OPT_T_BOOL:
            sb_puts(out, strcmp(v, "on") ? "false" : "true");
            break;
        case OPT_T_INT:
        case OPT_T_REAL:
            sb_puts(out, v);
            break;
        default:
            sb_json_str(out, v);
        }
    }
    sb_puts(out, "}");
}

/* GET /v1/options: the table as `qdc options` prints it (the same members),
 * then the daemon's two surface options with TetGen's defaults. */
void job_opt_table_json(sbuf *out)
{
    static const char *const types[] = {"word", "bool", "integer", "number", "hausd"};
    size_t n;
    const opt_desc *t = opt_table(&n);
    opt_options d;
    tetra_options td;
    char def[64], range[200];

    opt_defaults(&d);
    tetra_defaults(&td);
    sb_puts(out, "{\"options\":[");
    for (size_t i = 0; i < n; i++) {
        opt_value_text(&t[i], &d, def, sizeof def);
        opt_range_text(&t[i], range, sizeof range);
        sb_printf(out, "%s\n{\"name\":", i ? "," : "");
        sb_json_str(out, t[i].name);
        sb_printf(out, ",\"type\":\"%s\",\"default\":", types[t[i].type]);
        sb_json_str(out, def);
        sb_puts(out, ",\"valid\":");
        sb_json_str(out, range);
        if (t[i].type == OPT_T_INT || t[i].type == OPT_T_REAL)
            sb_printf(out, ",\"min\":%.17g,\"max\":%.17g,\"min_excluded\":%s", t[i].lo,
                      t[i].hi, t[i].lo_open ? "true" : "false");
        if (t[i].type == OPT_T_WORD) {
            sb_puts(out, ",\"values\":[");
            for (int w = 0; w < t[i].nwords; w++) {
                sb_puts(out, w ? "," : "");
                sb_json_str(out, t[i].words[w]);
            }
            sb_puts(out, "]");
        }
        sb_puts(out, ",\"help\":");
        sb_json_str(out, t[i].help);
        sb_puts(out, "}");
    }
    sb_printf(
        out,
        ",\n{\"name\":\"tetgen_quality\",\"type\":\"number\",\"default\":\"%g\","
        "\"valid\":\"0 or >= 1\",\"min\":0,\"max\":1e300,\"min_excluded\":false,"
        "\"surface\":true,\"help\":\"surfaces: TetGen radius-edge bound (-q); 0: no "
        "refinement\"}",
        td.quality);
    sb_printf(out,
              ",\n{\"name\":\"max_volume\",\"type\":\"number\",\"default\":\"%g\","
              "\"valid\":\">= 0\",\"min\":0,\"max\":1e300,\"min_excluded\":false,"
              "\"surface\":true,\"help\":\"surfaces: TetGen largest tet volume (-a); 0: "
              "none\"}",
              td.max_volume);
    sb_puts(out, "\n]}\n");
}

int job_opt_from_json(opt_options *o, const char *json, double cap_time)
{
    json_error_t jerr;
    json_t *root = json_loads(json, 0, &jerr);
    const char *key;
    json_t *v;
    char buf[64], why[160];
    int rc = 0;

    opt_defaults(o);
    if (!json_is_object(root)) {
        json_decref(root);
        return -1;
    }
    json_object_foreach(root, key, v)
    {
        if (!strcmp(key, "tetgen_quality") || !strcmp(key, "max_volume"))
            continue; /* the surface's options: job_tetra_opts */
        if (json_is_string(v))
            snprintf(buf, sizeof buf, "%s", json_string_value(v));
        else if (json_is_boolean(v))
            snprintf(buf, sizeof buf, "%d", json_is_true(v));
        else if (json_is_integer(v))
            snprintf(buf, sizeof buf, "%lld", (long long)json_integer_value(v));
        else if (json_is_real(v))
            snprintf(buf, sizeof buf, "%.17g", json_real_value(v));
        else
            continue;
        if (job_opt_set(o, key, buf, cap_time, why, sizeof why))
            rc = -1;
    }
    json_decref(root);
    return rc;
}

void job_tetra_opts(const char *json, double *quality, double *max_volume)
{
    json_t *root = json_loads(json, 0, NULL);
    json_t *v;

    *quality = *max_volume = -1;
    v = json_object_get(root, "tetgen_quality");
    if (json_is_number(v))
        *quality = json_number_value(v);
    v = json_object_get(root, "max_volume");
    if (json_is_number(v))
        *max_volume = json_number_value(v);
    json_decref(root);
}

int job_changes_tets(const char *json)
{
    json_t *root = json_loads(json, 0, NULL);
    json_t *v = json_object_get(root, "topology");
    int r = json_is_string(v) && strcmp(json_string_value(v), "none") != 0;

    json_decref(root);
    return r;
}

int job_topology_full(const char *json)
{
    json_t *root = json_loads(json, 0, NULL);
    json_t *v = json_object_get(root, "topology");
    int r = json_is_string(v) && strcmp(json_string_value(v), "full") == 0;

    json_decref(root);
    return r;
}
