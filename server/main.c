/* main.c - qdcd: command line, start-up (data directory and its lock, the
 * port, store recovery, workers, HTTP) and graceful shutdown on
 * SIGTERM/SIGINT. */
#define _GNU_SOURCE
#include "api.h"
#include "http.h"
#include "job.h"
#include "procenv.h"
#include "route.h"
#include "server.h"
#include "sha256.h"
#include "shared.h"
#include "trash.h"

#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <pthread.h>
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

static qdcd g;

static void usage(FILE *f)
{
    fputs(
        "usage: qdcd [options]\n"
        "Tetrahedral mesh optimization daemon (HTTP API: proto/openapi.yaml).\n\n"
        "  --listen HOST:PORT        address to listen on (default 127.0.0.1:8080;\n"
        "                            port 0 picks a free port)\n"
        "  --port-file FILE          write the bound port to FILE once listening\n"
        "  --data DIR                data directory: qdcd.db (SQLite, WAL), jobs/, tmp/\n"
        "                            and trash/ (deleted jobs' files being removed;\n"
        "                            default ./var)\n"
        "  --store URI               job store: sqlite:DIR (the same as --data DIR, the\n"
        "                            default) or a PostgreSQL connection URI\n"
        "                            postgresql://USER@HOST:PORT/DB (jobs and their\n"
        "                            files in the database: nodes share nothing else;\n"
        "                            --data is this node's cache and scratch space)\n"
        "  --cache-max BYTES         PostgreSQL store: cap of this node's cache of job\n"
        "                            files in --data; the least recently used are\n"
        "                            evicted (fetched again when needed; default 0:\n"
        "                            no cap)\n"
        "  --workers N               optimizer threads (default: number of cores)\n"
        "  --tokens FILE             bearer tokens, one SHA-256 hex hash per line\n"
        "                            (make one with --hash-token); each job is visible\n"
        "                            only to the token that created it\n"
        "  --hash-token TOKEN        print the line to put in the tokens file, exit\n"
        "  --insecure                allow a non-loopback address without --tokens\n"
        "                            (a warning is printed: anyone who reaches the\n"
        "                            port can submit, read and delete jobs)\n"
        "  --allowed-hosts NAMES     Host names served besides IP addresses,\n"
        "                            localhost and the --listen name (comma-separated;\n"
        "                            '*' any): other names get 403 (DNS rebinding)\n"
        "  --allowed-origins ORIGINS origins (https://ui.example) whose pages may POST\n"
        "                            or DELETE, besides the daemon's own (comma-\n"
        "                            separated; '*' any): others get 403\n"
        "  --public-metrics          with --tokens, serve /metrics and /readyz without "
        "a\n"
        "                            token (they count the jobs of every owner)\n",
        f);
    fputs(
        "  --max-body BYTES          largest request body (default 1073741824)\n"
        "  --max-json BYTES          largest JSON mesh body (default 16777216); larger\n"
        "                            meshes must use application/vnd.qdc.mesh\n"
        "  --max-ratio N             a gzip body (or the zlib arrays of a VTU body)\n"
        "                            inflates to at most N times its size (default\n"
        "                            100; meshes compress 2-3x); --max-body and\n"
        "                            --max-json apply to the inflated bytes\n"
        "  --max-vertices N          largest mesh accepted (default 20000000)\n"
        "  --max-tets N              (default 100000000)\n"
        "  --max-queued N            queued jobs before 429 (default 64)\n"
        "  --job-time-limit SECONDS  optimizer time budget per job (default 3600)\n"
        "  --retention SECONDS       results kept after a job ends, then 410 (default "
        "86400)\n"
        "  --max-wait SECONDS        cap of the long-poll 'wait' (default 60)\n"
        "  --sse-keepalive SECONDS   comment line sent on an idle event stream\n"
        "                            (default 15)\n"
        "  --max-attempts N          runs of a job interrupted by crashes before it\n"
        "                            fails (default 3)\n"
        "  --max-connections N       concurrent connections (default 4096)\n"
        "  --connection-timeout S    idle connection timeout (default 120)\n"
        "  --lease SECONDS           job lease, renewed every SECONDS/4 while the job\n"
        "                            runs; the job of a node that died runs again on\n"
        "                            another within about SECONDS + 4 (default 10)\n"
        "  --shutdown-grace SECONDS  on SIGTERM, wait this long for running jobs before\n"
        "                            giving them back to the queue (default 10)\n"
        "  --child-memory BYTES      address-space limit of a TetGen child (surface\n"
        "                            uploads; default: the machine's memory / (workers + "
        "1))\n"
        "  --bderr-samples N         random samples per surface for the boundary error\n"
        "                            (default 20000)\n"
        "  --qdc PATH                the qdc program that tetrahedralizes surface\n"
        "                            uploads in a child process (`qdc tetra`; default:\n"
        "                            qdc next to this qdcd)\n"
        "  -v, --verbose             log jobs and HTTP errors to stderr\n"
        "  -h, --help                this text\n",
        f);
}

static int parse_i64(const char *s, int64_t lo, int64_t hi, int64_t *out)
{
    char *end;
    errno = 0;
    long long v = strtoll(s, &end, 10);
    if (!*s || *end || errno || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

static int parse_dbl(const char *s, double lo, double hi, double *out)
{
    char *end;
    double v = strtod(s, &end);
    if (!*s || *end || !(v >= lo && v <= hi))
        return -1;
    *out = v;
    return 0;
}

static int parse_listen(const char *s, qdcd_config *c)
{
    const char *colon = strrchr(s, ':');
    int64_t port;
    size_t n;

    if (!colon || parse_i64(colon + 1, 0, 65535, &port))
        return -1;
    n = (size_t)(colon - s);
    if (n >= 2 && s[0] == '[' && s[n - 1] == ']') { /* [::1]:8080 */
        s++;
        n -= 2;
    }
    if (!n || n >= sizeof c->host)
        return -1;
    memcpy(c->host, s, n);
    c->host[n] = 0;
    c->port = (int)port;
    return 0;
}

static int is_loopback(const char *h)
{
    return !strncmp(h, "127.", 4) || !strcmp(h, "::1") || !strcasecmp(h, "localhost");
}

static int load_tokens(qdcd *q, const char *path)
{
    FILE *f = fopen(path, "r");
    char line[512];
    int lineno = 0;
    struct stat sb;

    if (!f) {
        fprintf(stderr, "qdcd: cannot open %s: %s\n", path, strerror(errno));
        return -1;
    }
    /* a regular file of sane size: --tokens /dev/zero used to hang here */
    if (fstat(fileno(f), &sb) || !S_ISREG(sb.st_mode) || sb.st_size > (1 << 20)) {
        fprintf(stderr,
                "qdcd: %s: not a regular file of at most 1 MiB (a tokens file has "
                "one hashed token per line)\n",
                path);
        fclose(f);
        return -1;
    }
    while (fgets(line, sizeof line, f)) {
        char *p = line + strspn(line, " \t");
        lineno++;
        p[strcspn(p, " \t\r\n#")] = 0;
        if (!*p)
            continue;
        if (!strncmp(p, "sha256:", 7))
            p += 7;
        size_t n = strlen(p);
        int ok = n == 64;
        for (size_t i = 0; ok && i < n; i++)
            ok = (p[i] >= '0' && p[i] <= '9') || (p[i] >= 'a' && p[i] <= 'f');
        if (!ok) {
            fprintf(stderr,
                    "qdcd: %s:%d: not a SHA-256 hex hash (tokens are stored hashed; "
                    "use qdcd --hash-token TOKEN)\n",
                    path, lineno);
            fclose(f);
            return -1;
        }
        char(*t)[65] = realloc(q->tokens, (size_t)(q->ntokens + 1) * sizeof *t);
        if (!t) {
            fclose(f);
            return -1;
        }
        q->tokens = t;
        memcpy(q->tokens[q->ntokens++], p, 65);
    }
    fclose(f);
    if (!q->ntokens) {
        fprintf(stderr, "qdcd: %s holds no token\n", path);
        return -1;
    }
    return 0;
}

/* Options with a value: where it goes and its range. 'i' int, 'l' int64,
 * 'd' double, 's' string (path), 'h' host:port. */
typedef struct {
    const char *name;
    char kind;
    size_t off;
    double lo, hi;
    double def; /* default (numbers) */
} cli_opt;

#define CFG(f) offsetof(qdcd_config, f)
static const cli_opt cli_opts[] = {
    {"listen", 'h', 0, 0, 0, 0},
    {"port-file", 's', CFG(port_file), 0, 0, 0},
    {"data", 's', CFG(data), 0, 0, 0},
    {"store", 's', CFG(store), 0, 0, 0},
    {"tokens", 's', CFG(tokens_file), 0, 0, 0},
    {"allowed-hosts", 's', CFG(allowed_hosts), 0, 0, 0},
    {"allowed-origins", 's', CFG(allowed_origins), 0, 0, 0},
    {"qdc", 's', CFG(qdc_path), 0, 0, 0},
    {"workers", 'i', CFG(workers), 1, 1024, 0},
    {"max-body", 'l', CFG(max_body), 1, 9.2e18, 1073741824},
    {"max-json", 'l', CFG(max_json), 1, 9.2e18, 16777216},
    {"max-ratio", 'i', CFG(max_ratio), 1, 1e6, 100},
    {"max-vertices", 'l', CFG(max_vertices), 1, 2e9, 2e7},
    {"max-tets", 'l', CFG(max_tets), 1, 5e8, 1e8},
    {"max-queued", 'i', CFG(max_queued), 0, 1e6, 64},
    {"job-time-limit", 'd', CFG(job_time_limit), 0.001, 1e9, 3600},
    {"retention", 'd', CFG(retention), 0, 1e10, 86400},
    {"max-wait", 'd', CFG(wait_cap), 0, 3600, 60},
    {"sse-keepalive", 'd', CFG(sse_keepalive), 0.1, 3600, 15},
    {"max-attempts", 'i', CFG(max_attempts), 1, 1000, 3},
    {"max-connections", 'i', CFG(max_connections), 1, 1e6, 4096},
    {"connection-timeout", 'i', CFG(conn_timeout), 1, 86400, 120},
    {"lease", 'd', CFG(lease), 1, 86400, 10},
    {"shutdown-grace", 'd', CFG(grace), 0, 86400, 10},
    {"bderr-samples", 'l', CFG(bderr_samples), 0, 1e8, 20000},
    {"child-memory", 'l', CFG(child_memory), 1 << 26, 9.2e18, 0},
    {"cache-max", 'l', CFG(cache_max), 0, 9.2e18, 0},
};
#define N_CLI (sizeof cli_opts / sizeof cli_opts[0])

static int set_cli(const cli_opt *o, const char *arg, qdcd_config *c)
{
    void *f = (char *)c + o->off;
    double v;
    int64_t iv;

    switch (o->kind) {
    case 'h':
        return parse_listen(arg, c);
    case 's':
        if (strlen(arg) >= sizeof c->data)
            return -1;
        snprintf(f, sizeof c->data, "%s", arg);
        return 0;
    case 'd':
        if (parse_dbl(arg, o->lo, o->hi, &v))
            return -1;
        *(double *)f = v;
        return 0;
    default:
        if (parse_i64(arg, (int64_t)o->lo, (int64_t)o->hi, &iv))
            return -1;
        if (o->kind == 'i')
            *(int *)f = (int)iv;
        else
            *(int64_t *)f = iv;
        return 0;
    }
}

static int parse_args(int argc, char **argv, qdcd_config *c)
{
    enum { O_HASH = 1000, O_INSECURE, O_PUBLIC_METRICS, O_ROUTES };
    struct option lo[N_CLI + 7];
    int o, n = 0;

    for (size_t i = 0; i < N_CLI; i++)
        lo[n++] = (struct option){cli_opts[i].name, required_argument, NULL, (int)i};
    lo[n++] = (struct option){"hash-token", required_argument, NULL, O_HASH};
    lo[n++] = (struct option){"insecure", no_argument, NULL, O_INSECURE};
    lo[n++] = (struct option){"public-metrics", no_argument, NULL, O_PUBLIC_METRICS};
    /* not in --help: the route table, for tests/server/openapi.sh */
    lo[n++] = (struct option){"print-routes", no_argument, NULL, O_ROUTES};
    lo[n++] = (struct option){"verbose", no_argument, NULL, 'v'};
    lo[n++] = (struct option){"help", no_argument, NULL, 'h'};
    lo[n] = (struct option){NULL, 0, NULL, 0};
    while ((o = getopt_long(argc, argv, "vh", lo, NULL)) != -1) {
        if (o >= 0 && o < (int)N_CLI) {
            if (set_cli(&cli_opts[o], optarg, c)) {
                fprintf(stderr, "qdcd: bad value for --%s: '%s'\n", cli_opts[o].name,
                        optarg);
                return -1;
            }
        } else if (o == O_HASH) {
            char hex[65];
            sha256_hex(optarg, strlen(optarg), hex);
            printf("%s\n", hex);
            exit(0);
        } else if (o == O_ROUTES) {
            route_print(stdout);
            exit(0);
        } else if (o == O_PUBLIC_METRICS) {
            c->public_metrics = 1;
        } else if (o == O_INSECURE) {
            c->insecure = 1;
        } else if (o == 'v') {
            c->verbose = 1;
        } else if (o == 'h') {
            usage(stdout);
            exit(0);
        } else {
            usage(stderr);
            return -1;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "qdcd: unexpected argument '%s'\n", argv[optind]);
        return -1;
    }
    if (!strncmp(c->store, "sqlite:", 7) && c->store[7]) {
        snprintf(c->data, sizeof c->data, "%s", c->store + 7);
    } else if (c->store[0] && !store_pg_uri(c->store)) {
        fprintf(stderr,
                "qdcd: --store takes sqlite:DIR or postgresql://USER@HOST:PORT/DB, "
                "not '%s'\n",
                c->store);
        return -1;
    }
    if (c->cache_max && !store_pg_uri(c->store)) {
        fprintf(stderr, "qdcd: --cache-max needs a PostgreSQL --store (with SQLite the "
                        "files in --data are the only copy)\n");
        return -1;
    }
    return 0;
}

static void defaults(qdcd_config *c)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);

    for (size_t i = 0; i < N_CLI; i++) {
        void *f = (char *)c + cli_opts[i].off;
        if (cli_opts[i].kind == 'd')
            *(double *)f = cli_opts[i].def;
        else if (cli_opts[i].kind == 'i')
            *(int *)f = (int)cli_opts[i].def;
        else if (cli_opts[i].kind == 'l')
            *(int64_t *)f = (int64_t)cli_opts[i].def;
    }
    snprintf(c->host, sizeof c->host, "127.0.0.1");
    c->port = 8080;
    snprintf(c->data, sizeof c->data, "./var");
    c->workers = n > 0 ? (int)n : 1;
}

/* Remove results whose retention passed; the rows stay so clients get 410. */
static void purge_expired(qdcd *q)
{
    char ids[64][JOB_ID_LEN + 1], dir[4200];
    int n = 0;

    if (q->store->ops->expired(q->store, wall_now(), ids, 64, &n) != QDC_OK)
        return;
    for (int i = 0; i < n; i++) {
        job_path(q, ids[i], NULL, dir, sizeof dir);
        trash_put(dir);
        q->store->ops->mark_purged(q->store, ids[i]);
    }
}

/* Without --qdc: the qdc built beside this qdcd (both land in build/rel, and
 * an install puts them in one bin directory). */
static void default_qdc_path(qdcd_config *c)
{
    char exe[4096];
    ssize_t n;

    if (c->qdc_path[0])
        return;
    n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0) {
        snprintf(c->qdc_path, sizeof c->qdc_path, "qdc");
        return;
    }
    exe[n] = 0;
    char *slash = strrchr(exe, '/'); /* the link is an absolute path */
    if (slash)
        *slash = 0;
    snprintf(c->qdc_path, sizeof c->qdc_path, "%.4090s/qdc", slash ? exe : ".");
}

/* One qdcd per data directory: an exclusive lock on
 * DATA/qdcd.lock, held until the process ends (the kernel drops it even on
 * kill -9). A second daemon on the same directory would re-queue the first
 * one's running jobs and run them again. Returns the locked fd, -1 if another
 * process holds it (its pid in *holder), -2 on other errors. */
static int lock_data_dir(const char *dir, long *holder)
{
    char p[4200], buf[32];
    int fd;
    ssize_t n;

    snprintf(p, sizeof p, "%.4096s/qdcd.lock", dir);
    fd = open(p, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0)
        return -2;
    if (flock(fd, LOCK_EX | LOCK_NB)) {
        int busy = errno == EWOULDBLOCK;
        n = pread(fd, buf, sizeof buf - 1, 0);
        buf[n > 0 ? n : 0] = 0;
        *holder = strtol(buf, NULL, 10);
        close(fd);
        return busy ? -1 : -2;
    }
    n = snprintf(buf, sizeof buf, "%ld\n", (long)getpid());
    if (ftruncate(fd, 0) || pwrite(fd, buf, (size_t)n, 0) != n) {
        close(fd);
        return -2;
    }
    return fd;
}

static int prepare_data_dir(qdcd *q, int shared)
{
    char p[4200];

    if (dir_ensure(q->cfg.data))
        return -1;
    snprintf(p, sizeof p, "%s/jobs", q->cfg.data);
    if (dir_ensure(p))
        return -1;
    snprintf(p, sizeof p, "%s/tmp", q->cfg.data);
    /* Uploads cut short by a crash: never committed, never acknowledged.
     * Not when nodes share the directory (PostgreSQL store): another node
     * may be receiving one right now. */
    if (!shared)
        dir_remove(p);
    if (dir_ensure(p))
        return -1;
    return trash_open(q);
}

/* One job directory of remove_orphans: removed (1) when its row is gone. */
static int remove_orphan(qdcd *q, const char *id, const char *dir, void *ctx)
{
    job_rec j;
    (void)ctx;
    if (q->store->ops->get(q->store, id, &j) != QDC_EINVAL)
        return 0;
    dir_remove(dir);
    return 1;
}

/* Job directories without a row: a crash between the input's rename and its
 * INSERT, or between a DELETE's row removal and its directory removal. The
 * job was never acknowledged (or is gone): its files go. */
static int remove_orphans(qdcd *q)
{
    return jobdir_each(q, remove_orphan, NULL);
}

/* The configuration from the command line and what follows from it; 0, or
 * the exit status (2: bad usage, message said). */
static int configure(qdcd *q, int argc, char **argv)
{
    defaults(&q->cfg);
    pthread_mutex_init(&q->cache_lock, NULL);
    if (parse_args(argc, argv, &q->cfg))
        return 2;
    if (!q->cfg.child_memory) {
        /* the machine's memory shared by the workers and the daemon */
        long pages = sysconf(_SC_PHYS_PAGES), psize = sysconf(_SC_PAGESIZE);
        int64_t phys = pages > 0 && psize > 0 ? (int64_t)pages * psize : (int64_t)4 << 30;
        q->cfg.child_memory = phys / (q->cfg.workers + 1);
        if (q->cfg.child_memory < ((int64_t)256 << 20))
            q->cfg.child_memory = (int64_t)256 << 20;
    }
    if (q->cfg.tokens_file[0] && load_tokens(q, q->cfg.tokens_file))
        return 2;
    default_qdc_path(&q->cfg);
    if (strchr(q->cfg.qdc_path, '/') && access(q->cfg.qdc_path, X_OK))
        fprintf(stderr,
                "qdcd: warning: %s is not executable: surface uploads will fail "
                "(--qdc PATH)\n",
                q->cfg.qdc_path);
    if (!is_loopback(q->cfg.host) && !q->ntokens && !q->cfg.insecure) {
        fprintf(stderr,
                "qdcd: refusing to listen on %s without --tokens (anyone could "
                "submit jobs); pass --insecure to do it anyway\n",
                q->cfg.host);
        return 2;
    }
    if (!is_loopback(q->cfg.host) && !q->ntokens)
        fprintf(stderr,
                "qdcd: warning: listening on %s without --tokens (--insecure): anyone "
                "who reaches the port can submit, read and delete jobs\n",
                q->cfg.host);
    return 0;
}

/* The data directory locked for this process (one daemon per directory, in
 * every store mode: with PostgreSQL it is the node's cache and scratch
 * space, and a second node would sweep the first one's uploads) and made
 * ready; the instance name. 0 or -1 (message said). */
static int claim_data_dir(qdcd *q)
{
    char host[64];
    long holder = 0;
    int lk = dir_ensure(q->cfg.data) ? -2 : lock_data_dir(q->cfg.data, &holder);

    if (lk == -1) {
        fprintf(stderr,
                "qdcd: data directory %s is in use by another qdcd (pid %ld); one "
                "daemon per directory (nodes of a PostgreSQL store share the database, "
                "each with its own --data)\n",
                q->cfg.data, holder);
        return -1;
    }
    if (lk < 0) {
        fprintf(stderr, "qdcd: cannot lock data directory %s: %s\n", q->cfg.data,
                strerror(errno));
        return -1;
    }
    /* lk stays open (and locked) until the process ends; only then is the
     * directory touched (tmp/ of a running daemon is not swept) */
    if (prepare_data_dir(q, store_pg_uri(q->cfg.store))) {
        fprintf(stderr, "qdcd: cannot use data directory %s: %s\n", q->cfg.data,
                strerror(errno));
        return -1;
    }
    gethostname(host, sizeof host);
    host[sizeof host - 1] = 0;
    snprintf(q->instance, sizeof q->instance, "%.24s:%ld:%lx", host, (long)getpid(),
             (unsigned long)wall_now());
    return 0;
}

/* Open the job store and recover what a crash left: running jobs re-queued
 * (or failed), job directories without a row removed. 0 or -1. */
static int open_store(qdcd *q)
{
    qdc_error err;
    int requeued = 0, failed = 0;

    qdc_error_clear(&err);
    if (store_pg_uri(q->cfg.store)
            ? store_pg_open(q->cfg.store, &q->store, &err) != QDC_OK
            : store_sqlite_open(q->cfg.data, &q->store, &err) != QDC_OK) {
        fprintf(stderr, "qdcd: %s\n", err.msg);
        return -1;
    }
    if (q->store->ops->recover(q->store, q->cfg.max_attempts, q->cfg.retention, &requeued,
                               &failed) != QDC_OK) {
        fprintf(stderr, "qdcd: cannot recover the job store\n");
        return -1;
    }
    if (requeued || failed)
        fprintf(stderr,
                "qdcd: recovered after a crash: %d job(s) re-queued, %d failed "
                "(attempts exhausted)\n",
                requeued, failed);
    if (!store_pg_uri(q->cfg.store)) {
        int orphans = remove_orphans(q);
        if (orphans)
            fprintf(stderr, "qdcd: removed %d job director%s without a job\n", orphans,
                    orphans == 1 ? "y" : "ies");
    } else {
        shared_sweep(q, 60); /* cached files of jobs deleted or expired meanwhile */
    }
    return 0;
}

/* The worker pool as shared.c sees it (the listener's news, the cache's
 * eviction): wired here so that shared.c and job.c do not call each other. */
static void pool_wake(void *ctx)
{
    job_pool_notify(((qdcd *)ctx)->pool);
}

static int pool_cancel(void *ctx, const char *id)
{
    return job_pool_cancel(((qdcd *)ctx)->pool, id);
}

static int pool_running(void *ctx, const char *id)
{
    return job_pool_has(((qdcd *)ctx)->pool, id);
}

static const shared_hooks pool_hooks = {pool_wake, pool_cancel, pool_running, &g};

/* The threads, in the order they depend on each other: poll timer, workers,
 * database listener, intake and conversion, then HTTP (on the socket bound
 * before the store was opened). 0 or -1. */
static int start_services(qdcd *q)
{
    qdc_error err;

    qdc_error_clear(&err);
    q->hub = poll_new();
    if (!q->hub || poll_start(q->hub)) {
        fprintf(stderr, "qdcd: cannot start the poll timer\n");
        return -1;
    }
    q->pool_hooks = &pool_hooks;
    q->pool = job_pool_start(q);
    if (!q->pool) {
        fprintf(stderr, "qdcd: cannot start workers\n");
        return -1;
    }
    if (shared_listen_start(q)) {
        fprintf(stderr, "qdcd: cannot start the database listener\n");
        return -1;
    }
    if (api_start(q)) {
        fprintf(stderr, "qdcd: cannot start the intake thread\n");
        return -1;
    }
    if (trash_start()) {
        fprintf(stderr, "qdcd: cannot start the trash thread\n");
        return -1;
    }
    if (http_start(q, &api_handlers, &err) != QDC_OK) {
        fprintf(stderr, "qdcd: %s\n", err.msg);
        return -1;
    }
    if (q->cfg.port_file[0]) {
        char buf[16];
        int n = snprintf(buf, sizeof buf, "%d\n", q->cfg.port);
        if (file_write_atomic(q->cfg.port_file, buf, (size_t)n))
            fprintf(stderr, "qdcd: cannot write %s\n", q->cfg.port_file);
    }
    fprintf(stderr, "qdcd: listening on http://%s%s%s:%d (data %s, %d workers%s)\n",
            strchr(q->cfg.host, ':') ? "[" : "", q->cfg.host,
            strchr(q->cfg.host, ':') ? "]" : "", q->cfg.port, q->cfg.data, q->cfg.workers,
            q->ntokens ? ", tokens on" : "");
    return 0;
}

/* --cache-max (PostgreSQL store): the least recently used cached files out,
 * every 2 s. */
static void trim_cache(qdcd *q, double *next)
{
    int64_t bytes = 0;
    int n;

    if (!shared_on(q) || !q->cfg.cache_max || mono_now() < *next)
        return;
    n = shared_trim(q, q->cfg.cache_max, SHARED_CACHE_MIN_AGE, &bytes);
    atomic_store(&q->m.cache_bytes, bytes);
    atomic_fetch_add(&q->m.cache_evicted, n);
    if (n && q->cfg.verbose)
        fprintf(stderr, "qdcd: cache: %d file(s) evicted, %lld bytes left\n", n,
                (long long)bytes);
    *next = mono_now() + 2;
}

/* The main loop until SIGTERM or SIGINT: the leases of running jobs renewed
 * every --lease/4; expired jobs purged every second;
 * with a shared store, jobs of a node that died recovered every 2 s, the
 * cache swept every minute and kept under --cache-max. */
static void serve(qdcd *q, const sigset_t *stopset)
{
    const struct timespec tick = {0, 100 * 1000 * 1000};
    double next_purge = 0, next_sweep = mono_now() + 60, next_recover = mono_now() + 2,
           next_trim = mono_now() + 1, next_beat = mono_now() + q->cfg.lease / 4;

    while (!q->stop) {
        if (mono_now() >= next_beat) {
            job_pool_heartbeat(q->pool);
            next_beat = mono_now() + q->cfg.lease / 4;
        }
        if (mono_now() >= next_purge) {
            purge_expired(q);
            next_purge = mono_now() + 1;
        }
        if (shared_on(q) && mono_now() >= next_recover) {
            /* jobs of a node that died: back to the queue, or failed after
             * --max-attempts (the claims leave those alone) */
            int rq = 0, fl = 0;
            if (q->store->ops->recover(q->store, q->cfg.max_attempts, q->cfg.retention,
                                       &rq, &fl) == QDC_OK &&
                (rq || fl))
                fprintf(stderr,
                        "qdcd: jobs of a node that stopped: %d re-queued, %d failed "
                        "(attempts exhausted)\n",
                        rq, fl);
            next_recover = mono_now() + 2;
        }
        if (shared_on(q) && mono_now() >= next_sweep) {
            /* other nodes deleted or expired jobs this node has files of */
            shared_sweep(q, 60);
            next_sweep = mono_now() + 60;
        }
        trim_cache(q, &next_trim);
        int sig = sigtimedwait(stopset, NULL, &tick);
        if (sig == SIGTERM || sig == SIGINT)
            q->stop = 1;
    }
}

/* Graceful shutdown: stop accepting, answer parked clients and queued
 * uploads, give running jobs --shutdown-grace, let the last answers go out. */
static void drain(qdcd *q)
{
    fprintf(stderr, "qdcd: shutting down\n");
    http_quiesce(q);
    poll_shutdown(q->hub);
    api_stop(); /* uploads already received are answered (202 or 4xx) */
    /* the listener calls into the pool; a cancel from another node still
     * reaches a running job through its row (job.c) */
    shared_listen_stop(q);
    job_pool_stop(q->pool, q->cfg.grace);
    q->pool = NULL;
    /* Let the answers of resumed long-polls and streams go out. */
    for (double until = mono_now() + 2; mono_now() < until;) {
        const union MHD_DaemonInfo *i =
            MHD_get_daemon_info(q->mhd, MHD_DAEMON_INFO_CURRENT_CONNECTIONS);
        if (!i || !i->num_connections)
            break;
        poll_shutdown(q->hub); /* anything that parked meanwhile */
        usleep(20 * 1000);
    }
}

/* Whatever was started, stopped and freed (each step copes with a part
 * that never started). */
static void teardown(qdcd *q)
{
    if (q->hub)
        poll_shutdown(q->hub);
    api_stop();
    http_stop(q);
    trash_stop(); /* after the last DELETE */
    if (q->store)
        shared_listen_stop(q);
    job_pool_stop(q->pool, 0);
    poll_free(q->hub);
    if (q->store)
        q->store->ops->close(q->store);
    free(q->tokens);
}

/* A stop signal that reached a thread other than the main one (a thread
 * started before main() blocked the signals, see main) is passed on to the
 * main thread, where it waits blocked for sigtimedwait. */
static pthread_t main_thread;
/* A job's memory is in transparent huge pages where the kernel gives them on
 * request (the qdc CLI's reasons and figures: clients/qdc/main.c), unless the
 * operator tuned malloc. Not the CLI's thresholds, which keep freed blocks in
 * the process: the daemon's memory must follow its limits, and an upload's
 * buffers, grown by realloc, then stayed beside their copies (a 1 MB gzip bomb
 * stopped at its 100 MB cap left a peak of 251 MB against 100-164 MB,
 * tests/server/bombs.sh). glibc reads it before main: main starts again. */
#define QDCD_MALLOC_TUNABLES "glibc.malloc.hugetlb=1"

static void forward_stop(int sig)
{
    pthread_kill(main_thread, sig);
}

int main(int argc, char **argv)
{
    qdcd *q = &g;
    sigset_t stopset;
    struct sigaction sa;
    qdc_error err;
    int rc, reexec = 0;

    /* The workers' OpenMP threads must sleep, not spin, while they wait: they
     * share the cores with the HTTP threads and the other jobs (the qdc CLI
     * measured 0.8 CPU s sleeping against 2.4-3.1 spinning on 2 busy cores).
     * libgomp reads the policy before main: set it and start again, once,
     * unless the operator chose one. */
    reexec |= procenv_default("OMP_WAIT_POLICY", "PASSIVE");
    /* OpenBLAS (CHOLMOD's BLAS) starts its thread pool before main, with no
     * signal blocked: a SIGTERM the kernel handed to one of those threads
     * while the main loop was busy killed the daemon without its drain (exit
     * 143, seen once in tests/server/longpoll.sh on a loaded machine). One
     * BLAS thread per job starts none, and the jobs run side by side anyway;
     * the qdc CLI runs one too, so that both give the same bytes. */
    reexec |= procenv_default("OPENBLAS_NUM_THREADS", "1");
    reexec |= procenv_tune_malloc(QDCD_MALLOC_TUNABLES);
    if (reexec)
        procenv_restart(argv);
    /* and where the operator set more BLAS threads (or another library
     * started threads early), the signal is forwarded to the main thread */
    main_thread = pthread_self();
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = forward_stop;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    q->listen_fd = -1;
    rc = configure(q, argc, argv);
    if (rc)
        return rc;
    if (claim_data_dir(q))
        return 1;
    /* The port first: a daemon that cannot have it stops here, before the
     * store is opened (recovery re-queues jobs) or a worker claims a job. */
    qdc_error_clear(&err);
    if (http_bind(q, &err) != QDC_OK) {
        fprintf(stderr, "qdcd: %s\n", err.msg);
        return 1;
    }
    /* SIGTERM and SIGINT are blocked in every thread and taken synchronously
     * by the main loop (sigtimedwait), so no handler ever runs. A handler
     * would not be safe anyway: METIS (inside CHOLMOD, on worker threads)
     * swaps in its own SIGTERM handler that longjmps into the worker's stack
     * and, with two jobs analysing at once, can leave it installed. */
    sigemptyset(&stopset);
    sigaddset(&stopset, SIGTERM);
    sigaddset(&stopset, SIGINT);
    pthread_sigmask(SIG_BLOCK, &stopset, NULL);
    signal(SIGPIPE, SIG_IGN);

    rc = 1;
    if (open_store(q) == 0 && start_services(q) == 0) {
        serve(q, &stopset);
        drain(q);
        rc = 0;
    }
    teardown(q);
    if (!rc)
        fprintf(stderr, "qdcd: stopped\n");
    return rc;
}
