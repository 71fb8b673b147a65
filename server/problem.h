/* problem.h - the problem types of RFC 9457 problem+json bodies: one table
 * (slug, usual status, title, the text GET /problems/<slug> serves) and the
 * one builder of problem bodies, used by the HTTP replies (http_problem),
 * the workers (a failed job's error) and both stores (attempts-exhausted). */
#ifndef QDCD_PROBLEM_H
#define QDCD_PROBLEM_H

#include "util.h"

typedef struct problem_type {
    const char *slug;
    int status;        /* the usual status (some types have several: io 500/507) */
    const char *title; /* the usual title; a reply may say it more precisely */
    const char *page;  /* served at /problems/<slug>, or NULL for the generic text */
} problem_type;

/* The table entry of slug, or NULL. */
const problem_type *problem_type_of(const char *slug);
/* The whole table; *n entries. */
const problem_type *problem_types(size_t *n);
/* Append {"type":"/problems/SLUG","title":..,"status":..,"detail":..[,extra]}
 * to b. title NULL: the table's. extra: further members as JSON text without
 * braces ("\"index\": 3"), or NULL. */
void problem_json(sbuf *b, int status, const char *slug, const char *title,
                  const char *detail, const char *extra);
/* The error of a job given up after max_attempts runs that each died with
 * the daemon (who: "the daemon", "a daemon"), into out (cap bytes; "" if it
 * does not fit). */
void problem_attempts(char *out, size_t cap, int max_attempts, const char *who);

#endif
