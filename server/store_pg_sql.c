/* store_pg_sql.c - the PostgreSQL store's statement runners
 * (store_pg_int.h): connecting, and running a statement on the row
 * connection or on any other. */
#define _GNU_SOURCE
#include "store_pg_int.h"

#include <string.h>

/* A connection with a bounded connect time and quiet NOTICEs ("relation
 * already exists"); the URI may set either itself. PQreset keeps both. */
PGconn *pg_connect(const char *uri)
{
    const char *const keys[] = {"connect_timeout", "options", "dbname", NULL};
    const char *const vals[] = {"5", "-c client_min_messages=warning", uri, NULL};
    return PQconnectdbParams(keys, vals, 1);
}

/* Run sql with p on the connection (lock held). A connection found broken is
 * reset once and the statement retried: a statement that failed on a broken
 * connection never reached the server's commit, so running it again is safe.
 * NULL (logged) if it still fails. The caller PQclear()s the result. */
PGresult *pg_run(pg_store *s, const char *sql, const params *p)
{
    for (int attempt = 0; attempt < 2; attempt++) {
        /* without parameters: the simple protocol, which also takes a script
         * of several statements (the migrations) */
        PGresult *r = p ? PQexecParams(s->conn, sql, p->n, NULL, p->v, NULL, NULL, 0)
                        : PQexec(s->conn, sql);
        if (r && result_ok(r))
            return r;
        if (PQstatus(s->conn) == CONNECTION_BAD && attempt == 0) {
            PQclear(r);
            PQreset(s->conn);
            continue;
        }
        fprintf(stderr, "qdcd: postgresql: %s",
                r ? PQresultErrorMessage(r) : PQerrorMessage(s->conn));
        PQclear(r);
        return NULL;
    }
    return NULL;
}

/* sql with p on c (any connection); NULL if it failed, with the SQLSTATE in
 * state ("" when the connection broke). Foreign-key violations (the job was
 * deleted meanwhile) are expected and not logged. */
PGresult *pg_cx(PGconn *c, const char *sql, const params *p, char state[6])
{
    PGresult *r =
        p ? PQexecParams(c, sql, p->n, NULL, p->v, NULL, NULL, 0) : PQexec(c, sql);
    const char *f;

    if (r && result_ok(r))
        return r;
    f = r ? PQresultErrorField(r, PG_DIAG_SQLSTATE) : NULL;
    snprintf(state, 6, "%s", f ? f : "");
    if (strcmp(state, "23503"))
        fprintf(stderr, "qdcd: postgresql: %s",
                r ? PQresultErrorMessage(r) : PQerrorMessage(c));
    PQclear(r);
    return NULL;
}
