/* jobopt.h - the job options: the library's option table (lib/opt/options.h)
 * as the HTTP layer reads it (query string) and the workers read it back
 * (stored JSON), jobopt.c. */
#ifndef QDCD_JOBOPT_H
#define QDCD_JOBOPT_H

#include "qdc.h"
#include "util.h"

/* Set one option from its text form (query string or stored JSON).
 * Returns 0, or -1 with a message in why. time_limit is capped by cap_time. */
int job_opt_set(opt_options *o, const char *key, const char *val, double cap_time,
                char *why, size_t why_cap);
/* Canonical JSON of every option the daemon exposes. */
void job_opt_json(const opt_options *o, sbuf *out);
/* Rebuild options from job_opt_json output. */
int job_opt_from_json(opt_options *o, const char *json, double cap_time);

/* GET /v1/options: the option table (names, types, defaults, ranges, help) as
 * `qdc options` prints it, plus tetgen_quality and max_volume ("surface": true),
 * as {"options": [...]}. */
void job_opt_table_json(sbuf *out);

/* The TetGen options stored in a surface job's options JSON ("tetgen_quality",
 * "max_volume"); -1 for each one not given. */
void job_tetra_opts(const char *json, double *quality, double *max_volume);

/* Whether a job's options JSON asks for a topology mode other than none: its
 * result has other tets than its upload (result.c writes it with qdc's own
 * writer, not spliced into the upload). */
int job_changes_tets(const char *json);
/* 1 if the options (JSON) ask for topology=full, which may insert and
 * contract vertices. */
int job_topology_full(const char *json);

#endif
