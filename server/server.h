/* server.h - the daemon's configuration and the context every module shares. */
#ifndef QDCD_SERVER_H
#define QDCD_SERVER_H

#include "poll.h"
#include "store.h"

#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>

typedef struct {
    char host[256]; /* --listen HOST:PORT */
    int port;
    char data[4096];            /* --data DIR */
    char store[4096];           /* --store URI: "" or sqlite:DIR (SQLite in data), or
                                 * postgresql://... */
    char port_file[4096];       /* --port-file FILE: the bound port is written there */
    char tokens_file[4096];     /* --tokens FILE */
    char qdc_path[4096];        /* --qdc PATH: runs `qdc tetra` for surface jobs */
    int insecure;               /* --insecure: allow a public address without tokens */
    char allowed_hosts[4096];   /* --allowed-hosts: more Host names served */
    char allowed_origins[4096]; /* --allowed-origins: origins allowed to POST/DELETE */
    int public_metrics;    /* --public-metrics: /metrics and /readyz without a token */
    int64_t child_memory;  /* --child-memory: address-space limit of a TetGen child */
    int workers;           /* --workers N */
    int64_t max_body;      /* --max-body BYTES (any format) */
    int64_t max_json;      /* --max-json BYTES (JSON meshes) */
    int max_ratio;         /* --max-ratio N: a gzip body inflates at most N times */
    int64_t max_vertices;  /* --max-vertices N */
    int64_t max_tets;      /* --max-tets N */
    int max_queued;        /* --max-queued N: then 429 */
    double job_time_limit; /* --job-time-limit S */
    double retention;      /* --retention S: results are then 410 Gone */
    double wait_cap;       /* --max-wait S: long-poll cap */
    double sse_keepalive;  /* --sse-keepalive S: comment on an idle event stream */
    int max_attempts;      /* --max-attempts N */
    int max_connections;   /* --max-connections N */
    int conn_timeout;      /* --connection-timeout S */
    double lease;          /* --lease S */
    double grace;          /* --shutdown-grace S */
    int64_t bderr_samples; /* --bderr-samples N: random samples per side */
    int64_t cache_max;     /* --cache-max BYTES: node-local cache cap (PostgreSQL
                            * store), 0 = none */
    int verbose;
} qdcd_config;

/* Prometheus histogram buckets of request latency (seconds). */
#define LAT_BUCKETS 12
extern const double lat_bounds[LAT_BUCKETS];

typedef struct {
    atomic_llong http_by_class[6]; /* 1xx..5xx by first digit */
    atomic_llong lat_count[LAT_BUCKETS + 1];
    atomic_llong lat_sum_us;
    atomic_llong upload_bytes;
    atomic_llong iterations;
    atomic_llong submitted;
    atomic_llong rejected;
    atomic_llong finished[JOB_STATE_COUNT];
    atomic_llong cache_bytes;   /* DATA/jobs at the last cache scan (--cache-max) */
    atomic_llong cache_evicted; /* files evicted from it */
} qdcd_metrics;

struct job_pool;
struct shared_hooks;
struct MHD_Daemon;

typedef struct qdcd {
    qdcd_config cfg;
    job_store *store;
    poll_hub *hub;
    struct job_pool *pool;
    const struct shared_hooks *pool_hooks; /* the pool for shared.c (main.c wires it) */
    struct MHD_Daemon *mhd;
    int listen_fd;      /* bound by http_bind, until libmicrohttpd takes it; or -1 */
    int listen_v6;      /* it is an IPv6 socket */
    char (*tokens)[65]; /* SHA-256 hex of each accepted bearer token */
    int ntokens;
    char instance[48]; /* this process: lease owner prefix */
    qdcd_metrics m;
    volatile sig_atomic_t stop;
    /* orders cache readers (shared_use) against eviction (shared_trim) */
    pthread_mutex_t cache_lock;
} qdcd;

#endif
