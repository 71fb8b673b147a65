/* test_http.c - the daemon's pure HTTP parsers: the router (server/route.c),
 * job ids, query integers, If-None-Match, Accept, query values, Host and
 * Origin (server/parse.c). */
#include "parse.h"
#include "problem.h"
#include "route.h"
#include "store.h"
#include "testio.h"
#include "testlib.h"

/* the fuzz target itself, replayed on its seeds and crashes below */
#include "../fuzz/fuzz_http.c"

#include <limits.h>
#include <string.h>

#define ID "0123456789abcdef0123456789abcdef"

TEST(router_paths)
{
    static const struct {
        const char *url;
        int route;
    } cases[] = {
        {"/livez", R_LIVEZ},
        {"/readyz", R_READYZ},
        {"/metrics", R_METRICS},
        {"/v1/jobs", R_JOBS},
        {"/v1/jobs/", R_JOBS},
        {"/v1/options", R_OPTIONS},
        {"/v1/jobs/" ID, R_JOB},
        {"/v1/jobs/" ID "/progress", R_PROGRESS},
        {"/v1/jobs/" ID "/events", R_EVENTS},
        {"/v1/jobs/" ID "/result", R_RESULT},
        {"/v1/jobs/" ID "/report", R_REPORT},
        {"/v1/jobs/" ID "/input", R_INPUT},
        {"/v1/jobs/" ID ":cancel", R_CANCEL},
        {"/problems/not-found", R_PROBLEM},
        /* a job route's shape with an id that cannot exist */
        {"/v1/jobs/"
         "0123456789ABCDEF0123456789abcdef",
         R_BAD_ID},
        {"/v1/jobs/xyz/progress", R_BAD_ID},
        {"/v1/jobs//result", R_BAD_ID},
        {"/v1/jobs/" ID "0", R_BAD_ID},
        /* nothing there */
        {"/", R_NONE},
        {"", R_NONE},
        {"/livez/", R_NONE},
        {"/LIVEZ", R_NONE},
        {"/v1/jobs/" ID "/progress/", R_NONE},
        {"/v1/jobs/" ID "/nope", R_NONE},
        {"/v1/jobs/" ID ":stop", R_NONE},
        {"/v1/job", R_NONE},
        {"/problems/", R_NONE},
        {"/problems/Not-Found", R_NONE},
        {"/problems/a/b", R_NONE},
        {"/problems/a:b", R_NONE},
        {"/problems/abcdefghijklmnopqrstuvwxyzabcdefg", R_NONE}, /* 33 characters */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char id[JOB_ID_LEN + 1] = "";
        int got = route_match(cases[i].url, id);
        if (got != cases[i].route)
            printf("  url '%s'\n", cases[i].url);
        ASSERT_EQ_INT(got, cases[i].route);
        if (got > R_NONE && got != R_PROBLEM && got != R_JOBS && got != R_OPTIONS &&
            got != R_LIVEZ && got != R_READYZ && got != R_METRICS)
            ASSERT_TRUE(!strcmp(id, ID));
    }
    char id[JOB_ID_LEN + 1];
    ASSERT_EQ_INT(route_match("/problems/queue-full", id), R_PROBLEM);
    ASSERT_TRUE(!strcmp(id, "queue-full"));
}

TEST(router_methods_exact)
{
    ASSERT_EQ_INT(route_method_bit("GET"), M_GET);
    ASSERT_EQ_INT(route_method_bit("DELETE"), M_DELETE);
    /* exact comparison: no substrings, no case folding */
    static const char *const other[] = {"ET",    "GE",        "get", "POS",
                                        "GET ",  "",          "PUT", "OPTIONS",
                                        "DELET", "GET, POST", NULL};
    for (int i = 0; other[i]; i++)
        ASSERT_EQ_INT(route_method_bit(other[i]), M_OTHER);
    ASSERT_EQ_INT(route_method_bit(NULL), M_OTHER);

    ASSERT_TRUE(route_method_ok(R_JOBS, "GET"));
    ASSERT_TRUE(route_method_ok(R_JOBS, "HEAD"));
    ASSERT_TRUE(route_method_ok(R_JOBS, "POST"));
    ASSERT_TRUE(!route_method_ok(R_JOBS, "DELETE"));
    ASSERT_TRUE(!route_method_ok(R_JOBS, "OST"));
    ASSERT_TRUE(route_method_ok(R_JOB, "DELETE"));
    ASSERT_TRUE(!route_method_ok(R_JOB, "POST"));
    ASSERT_TRUE(route_method_ok(R_CANCEL, "POST"));
    ASSERT_TRUE(!route_method_ok(R_CANCEL, "GET"));
    ASSERT_TRUE(!route_method_ok(R_CANCEL, "HEAD"));
    ASSERT_TRUE(route_method_ok(R_UI, "HEAD"));
    ASSERT_TRUE(!route_method_ok(R_NONE, "GET"));
    ASSERT_TRUE(!route_method_ok(R_BAD_ID, "GET"));
}

TEST(router_table_is_consistent)
{
    /* every route has one Allow header, which names exactly its methods
     * (HEAD implied by GET), and an auth class */
    for (int r = R_JOBS; r < R_COUNT; r++) {
        const route_desc *d = route_desc_of(r);
        ASSERT_TRUE(d != NULL);
        unsigned from_allow = 0;
        char a[64];
        route_allow(r, a, sizeof a);
        for (char *t = strtok(a, ", "); t; t = strtok(NULL, ", "))
            from_allow |= route_method_bit(t);
        if (from_allow & M_GET)
            from_allow |= M_HEAD;
        ASSERT_EQ_INT(from_allow, route_methods(r));
    }
    ASSERT_TRUE(route_desc_of(R_NONE) == NULL);
    ASSERT_TRUE(route_desc_of(R_COUNT) == NULL);
    ASSERT_EQ_INT(route_desc_of(R_LIVEZ)->auth, AUTH_NONE);
    ASSERT_EQ_INT(route_desc_of(R_METRICS)->auth, AUTH_OPS);
    ASSERT_EQ_INT(route_desc_of(R_OPTIONS)->auth, AUTH_TOKEN);
}

TEST(job_ids)
{
    ASSERT_TRUE(parse_is_job_id(ID, 32));
    ASSERT_TRUE(!parse_is_job_id(ID, 31));
    ASSERT_TRUE(!parse_is_job_id("0123456789ABCDEF0123456789abcdef", 32));
    ASSERT_TRUE(!parse_is_job_id("0123456789abcdeg0123456789abcdef", 32));
    ASSERT_TRUE(!parse_is_job_id("", 0));
}

TEST(query_integers)
{
    long v = 7;
    ASSERT_EQ_INT(parse_long("0", 0, 10, &v), 0);
    ASSERT_EQ_INT(v, 0);
    ASSERT_EQ_INT(parse_long("-1", -1, 10, &v), 0);
    ASSERT_EQ_INT(v, -1);
    ASSERT_EQ_INT(parse_long("1000", 1, 1000, &v), 0);
    ASSERT_EQ_INT(v, 1000);
    v = 7;
    static const char *const bad[] = {"",    "1001", "0x10", "1 ",
                                      "1x",  "abc",  "-2",   "99999999999999999999999",
                                      "1.5", NULL};
    for (int i = 0; bad[i]; i++)
        ASSERT_EQ_INT(parse_long(bad[i], -1, 1000, &v), -1);
    ASSERT_EQ_INT(v, 7); /* untouched on failure */
    ASSERT_EQ_INT(parse_long("9223372036854775807", 0, LONG_MAX, &v), 0);
    ASSERT_EQ_INT(parse_long("9223372036854775807", 0, LONG_MAX - 1, &v), -1);
}

TEST(etags)
{
    const char *e = "\"abc\"";
    ASSERT_TRUE(etag_matches("\"abc\"", e));
    ASSERT_TRUE(etag_matches("W/\"abc\"", e)); /* weak comparison */
    ASSERT_TRUE(etag_matches("*", e));
    ASSERT_TRUE(etag_matches("\"x\", \"abc\"", e));
    ASSERT_TRUE(etag_matches("\"x\",W/\"abc\" ", e));
    ASSERT_TRUE(etag_matches(" , ,\"abc\"", e));
    ASSERT_TRUE(!etag_matches(NULL, e));
    ASSERT_TRUE(!etag_matches("", e));
    ASSERT_TRUE(!etag_matches("abc", e)); /* unquoted */
    ASSERT_TRUE(!etag_matches("\"abcd\"", e));
    ASSERT_TRUE(!etag_matches("\"ab\"", e));
    ASSERT_TRUE(!etag_matches("\"x\", \"y\"", e));
    ASSERT_TRUE(!etag_matches("w/\"abc\"", e)); /* the weak prefix is case-sensitive */
    ASSERT_TRUE(!etag_matches(",,,", e));
}

TEST(accept_negotiation)
{
    meshio_format f = MESHIO_AUTO;
    ASSERT_EQ_INT(parse_accept("*/*", &f), 0);
    ASSERT_EQ_INT(f, MESHIO_QMESH);
    ASSERT_EQ_INT(parse_accept("application/*", &f), 0);
    ASSERT_EQ_INT(f, MESHIO_QMESH);
    ASSERT_EQ_INT(parse_accept("text/plain", &f), 0);
    ASSERT_EQ_INT(f, MESHIO_MEDIT);
    ASSERT_EQ_INT(parse_accept("Model/*", &f), 0);
    ASSERT_EQ_INT(f, MESHIO_MEDIT);
    /* the client's order decides; q values other than 0 are not weighed */
    ASSERT_EQ_INT(parse_accept("text/plain;q=0.1, */*;q=1", &f), 0);
    ASSERT_EQ_INT(f, MESHIO_MEDIT);
    /* q=0 entries are refused, in any spelling */
    ASSERT_EQ_INT(parse_accept("text/plain;q=0, */*", &f), 0);
    ASSERT_EQ_INT(f, MESHIO_QMESH);
    ASSERT_EQ_INT(parse_accept("text/plain; Q=0.000, application/*", &f), 0);
    ASSERT_EQ_INT(f, MESHIO_QMESH);
    f = MESHIO_AUTO;
    ASSERT_EQ_INT(parse_accept("*/*;q=0", &f), -1);
    ASSERT_EQ_INT(f, MESHIO_AUTO); /* untouched */
    /* unknown, empty and junk entries are skipped */
    ASSERT_EQ_INT(parse_accept("image/png", &f), -1);
    ASSERT_EQ_INT(parse_accept("", &f), -1);
    ASSERT_EQ_INT(parse_accept(",,, ;;", &f), -1);
    ASSERT_EQ_INT(parse_accept("image/png, ,text/plain", &f), 0);
    ASSERT_EQ_INT(f, MESHIO_MEDIT);
    /* a media type the library knows, with its parameters */
    meshio_format g = meshio_format_from_media_type("application/vnd.qdc.mesh");
    ASSERT_TRUE(g != MESHIO_AUTO);
    ASSERT_EQ_INT(parse_accept("image/png, application/vnd.qdc.mesh", &f), 0);
    ASSERT_EQ_INT(f, g);
    /* an entry longer than the parser's buffer is cut, not overrun */
    char big[600];
    memset(big, 'a', sizeof big - 1);
    big[sizeof big - 1] = 0;
    ASSERT_EQ_INT(parse_accept(big, &f), -1);
}

static int replay_http(const char *buf, size_t len)
{
    return LLVMFuzzerTestOneInput((const uint8_t *)buf, len); /* aborts on a bug */
}

TEST(problem_table)
{
    size_t n;
    const problem_type *t = problem_types(&n);
    ASSERT_TRUE(n >= 20);
    for (size_t i = 0; i < n; i++) {
        /* slugs are unique, [a-z-], routable as /problems/<slug> */
        char url[80], id[JOB_ID_LEN + 1];
        ASSERT_TRUE(problem_type_of(t[i].slug) == &t[i]);
        ASSERT_TRUE(t[i].status >= 400 && t[i].status < 600);
        ASSERT_TRUE(t[i].title && *t[i].title);
        snprintf(url, sizeof url, "/problems/%s", t[i].slug);
        ASSERT_EQ_INT(route_match(url, id), R_PROBLEM);
    }
    ASSERT_TRUE(problem_type_of("no-such-type") == NULL);
    ASSERT_TRUE(problem_type_of(NULL) == NULL);
}

TEST(problem_bodies)
{
    sbuf b = {0};
    problem_json(&b, 404, "not-found", NULL, "no \"x\"\n", NULL);
    ASSERT_TRUE(!b.oom);
    ASSERT_TRUE(!strcmp(b.buf,
                        "{\"type\":\"/problems/not-found\",\"title\":\"not found\","
                        "\"status\":404,\"detail\":\"no \\\"x\\\"\\u000a\"}"));
    sb_free(&b);
    problem_json(&b, 507, "io", "insufficient storage", "d", "\"index\":3");
    ASSERT_TRUE(!strcmp(b.buf, "{\"type\":\"/problems/io\",\"title\":\"insufficient "
                               "storage\",\"status\":507,\"detail\":\"d\",\"index\":3}"));
    sb_free(&b);
    char e[512], small[40];
    problem_attempts(e, sizeof e, 3, "the daemon");
    ASSERT_TRUE(!strcmp(e,
                        "{\"type\":\"/problems/attempts-exhausted\",\"title\":\"job "
                        "crashed the daemon\",\"status\":500,\"detail\":\"the daemon "
                        "died while running this job on each of its 3 attempt(s); it is "
                        "not retried\",\"attempts\":3}"));
    problem_attempts(small, sizeof small, 3, "a daemon");
    ASSERT_TRUE(!strcmp(small, "")); /* never a cut, invalid JSON text */
}

TEST(fuzz_replay)
{
    int n, bad = replay_fuzz("http", replay_http, &n);

    printf("  # %d fuzz inputs replayed\n", n);
    ASSERT_TRUE(n > 0);
    ASSERT_EQ_INT(bad, 0);
}

TEST(query_values)
{
    ASSERT_TRUE(parse_query_ok("medit", 5));
    ASSERT_TRUE(parse_query_ok("", 0));
    ASSERT_TRUE(parse_query_ok("caf\xc3\xa9 1", 6));
    ASSERT_TRUE(!parse_query_ok("json\0medit", 10));
    ASSERT_TRUE(!parse_query_ok("a\nb", 3));
    ASSERT_TRUE(!parse_query_ok("\x7f", 1));
    ASSERT_TRUE(!parse_query_ok("tab\t", 4));
}

TEST(host_header)
{
    static const struct {
        const char *host, *listen, *allowed;
        int ok;
    } c[] = {
        {NULL, "127.0.0.1", "", 1}, /* HTTP/1.0 without Host */
        {"127.0.0.1:8080", "127.0.0.1", "", 1},
        {"10.1.2.3:80", "0.0.0.0", "", 1}, /* an address cannot be rebound */
        {"[::1]:8080", "::1", "", 1},
        {"[::1]", "127.0.0.1", "", 1},
        {"localhost:8080", "127.0.0.1", "", 1},
        {"LocalHost.:8080", "127.0.0.1", "", 1},
        {"app.localhost:8080", "127.0.0.1", "", 1},
        {"evil.example:8080", "127.0.0.1", "", 0},
        {"evil.example", "127.0.0.1", "", 0},
        {"localhost.evil.example", "127.0.0.1", "", 0},
        {"127.0.0.1.evil.example", "127.0.0.1", "", 0},
        {"[evil]:80", "127.0.0.1", "", 0},
        {"[::1]x", "127.0.0.1", "", 0},
        {"", "127.0.0.1", "", 0},
        {":8080", "127.0.0.1", "", 0},
        {"box.lan:8080", "box.lan", "", 1}, /* --listen box.lan:8080 */
        {"qdc.example.com", "127.0.0.1", "a.example, qdc.example.com", 1},
        {"QDC.example.com:443", "127.0.0.1", "qdc.example.com", 1},
        {"x.example.com", "127.0.0.1", "example.com", 0},
        {"anything", "127.0.0.1", "*", 1},
    };
    for (size_t i = 0; i < sizeof c / sizeof c[0]; i++)
        ASSERT_EQ_INT(parse_host_allowed(c[i].host, c[i].listen, c[i].allowed), c[i].ok);
}

TEST(origin_header)
{
    static const struct {
        const char *origin, *host, *allowed;
        int ok;
    } c[] = {
        {NULL, "127.0.0.1:8080", "", 1}, /* not a browser */
        {"http://127.0.0.1:8080", "127.0.0.1:8080", "", 1},
        {"http://localhost:8080", "LOCALHOST:8080", "", 1},
        {"https://qdc.example.com", "qdc.example.com", "", 1}, /* TLS proxy */
        {"http://127.0.0.1:9999", "127.0.0.1:8080", "", 0},    /* another port */
        {"http://localhost:8080", "127.0.0.1:8080", "", 0},
        {"https://evil.example", "127.0.0.1:8080", "", 0},
        {"null", "127.0.0.1:8080", "", 0},
        {"ftp://127.0.0.1:8080", "127.0.0.1:8080", "", 0},
        {"http://127.0.0.1:8080", NULL, "", 0},
        {"https://ui.example", "10.0.0.5:8080", "https://ui.example", 1},
        {"https://ui.example", "10.0.0.5:8080",
         "https://other.example,https://ui.example", 1},
        {"https://ui.example.evil", "10.0.0.5:8080", "https://ui.example", 0},
        {"https://evil.example", "127.0.0.1:8080", "*", 1},
    };
    for (size_t i = 0; i < sizeof c / sizeof c[0]; i++)
        ASSERT_EQ_INT(parse_origin_allowed(c[i].origin, c[i].host, c[i].allowed),
                      c[i].ok);
}

TEST_MAIN("http", T(router_paths), T(router_methods_exact), T(router_table_is_consistent),
          T(job_ids), T(query_integers), T(etags), T(accept_negotiation),
          T(problem_table), T(problem_bodies), T(query_values), T(host_header),
          T(origin_header), T(fuzz_replay))
