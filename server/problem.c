/* problem.c - the problem type table and the problem+json builder. */
#include "problem.h"

#include <stdio.h>
#include <string.h>

static const problem_type types[] = {
    {"invalid-option", 400, "invalid option",
     "An optimizer option has a value outside its range; the detail "
     "names the valid values (GET the option table with `qdc options`)."},
    {"invalid-parameter", 400, "invalid parameter", NULL},
    {"invalid-mesh", 422, "invalid mesh",
     "The mesh failed validation: the detail names the vertex or tet."},
    {"invalid-argument", 400, "invalid argument", NULL},
    {"malformed-mesh", 400, "malformed mesh", NULL},
    {"invalid-surface", 422, "the surface cannot bound a volume", NULL},
    {"idempotency-key-reused", 422, "Idempotency-Key reused with a different request",
     NULL},
    {"tetgen", 422, "the surface could not be tetrahedralized", NULL},
    {"invalid-idempotency-key", 400, "invalid Idempotency-Key", NULL},
    {"job-failed", 422, "the job failed", NULL},
    {"empty-body", 400, "empty request body", NULL},
    {"ambiguous-framing", 400, "ambiguous request framing",
     "The request had two Content-Length headers, or one with "
     "Transfer-Encoding (400)."},
    {"unauthorized", 401, "unauthorized", "Send Authorization: Bearer <token> (401)."},
    {"host-not-allowed", 403, "unknown host name",
     "The request's Host is not a name this server answers to (a page whose name "
     "was pointed at this machine, DNS rebinding); the operator can allow more with "
     "--allowed-hosts (403)."},
    {"cross-origin", 403, "request from another origin",
     "A POST or DELETE from a web page of another origin (Origin, or "
     "Sec-Fetch-Site: cross-site); the operator can allow an origin with "
     "--allowed-origins (403)."},
    {"not-found", 404, "not found", NULL},
    {"method-not-allowed", 405, "method not allowed", NULL},
    {"not-acceptable", 406, "not acceptable", NULL},
    {"not-ready", 409, "the job has not finished", NULL},
    {"no-result", 409, "the job has no result", NULL},
    {"gone", 410, "result expired", NULL},
    {"too-big", 413, "request body too large",
     "The body or the mesh exceeds the server's limits (413)."},
    {"unsupported-media-type", 415, "unsupported media type", NULL},
    {"queue-full", 429, "too many queued jobs",
     "Too many queued jobs; retry after the Retry-After seconds (429)."},
    {"io", 500, "i/o error",
     "The server could not read or write its data (507 when the disk is full)."},
    {"attempts-exhausted", 500, "job crashed the daemon",
     "The daemon died while running the job on each attempt; it is not retried."},
    {"internal", 500, "internal error", NULL},
    {"optimizer-failed", 500, "optimization failed", NULL},
    {"out-of-memory", 503, "out of memory", NULL},
    {"shutting-down", 503, "shutting down", NULL},
    {"store-unavailable", 503, "job store unavailable", NULL},
};

const problem_type *problem_types(size_t *n)
{
    *n = sizeof types / sizeof types[0];
    return types;
}

const problem_type *problem_type_of(const char *slug)
{
    for (size_t i = 0; slug && i < sizeof types / sizeof types[0]; i++)
        if (!strcmp(slug, types[i].slug))
            return &types[i];
    return NULL;
}

void problem_json(sbuf *b, int status, const char *slug, const char *title,
                  const char *detail, const char *extra)
{
    const problem_type *t = problem_type_of(slug);
    if (!title)
        title = t ? t->title : "problem";
    sb_printf(b, "{\"type\":\"/problems/%s\",\"title\":", slug);
    sb_json_str(b, title);
    sb_printf(b, ",\"status\":%d,\"detail\":", status);
    sb_json_str(b, detail);
    if (extra && *extra)
        sb_printf(b, ",%s", extra);
    sb_puts(b, "}");
}

void problem_attempts(char *out, size_t cap, int max_attempts, const char *who)
{
    sbuf b = {0}, d = {0}, x = {0};
    sb_printf(&d,
              "%s died while running this job on each of its %d attempt(s); it is not "
              "retried",
              who, max_attempts);
    sb_printf(&x, "\"attempts\":%d", max_attempts);
    if (!d.oom && !x.oom)
        problem_json(&b, 500, "attempts-exhausted", NULL, d.buf, x.buf);
    snprintf(out, cap, "%s", b.oom || !b.buf || b.len >= cap ? "" : b.buf);
    sb_free(&b);
    sb_free(&d);
    sb_free(&x);
}
