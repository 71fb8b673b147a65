/* shared.c - the job files of nodes that share a PostgreSQL store (see
 * shared.h). */
#define _GNU_SOURCE
#include "shared.h"

#include "jobdir.h"

#include <dirent.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int shared_on(const qdcd *q)
{
    return q->store && q->store->ops->blob_get != NULL;
}

qdc_status shared_fetch(qdcd *q, const char *id, const char *name, char *sha)
{
    char dir[4200], path[4300];

    qdc_status st;

    job_path(q, id, name, path, sizeof path);
    if (shared_use(q, path) == 0)
        return QDC_OK;
    job_path(q, id, NULL, dir, sizeof dir);
    if (dir_ensure(dir))
        return QDC_EIO;
    st = q->store->ops->blob_get(q->store, id, name, path, sha);
    if (st == QDC_OK)
        (void)shared_use(q, path); /* its atime is when the fetch began */
    return st;
}

qdc_status shared_put(qdcd *q, const char *id, const char *name, const char *sha,
                      const char *worker)
{
    char path[4300];

    job_path(q, id, name, path, sizeof path);
    return q->store->ops->blob_put(q->store, id, name, path, sha, worker);
}

/* The listener thread's news. */
static void on_event(void *ctx, const store_event *ev)
{
    qdcd *q = ctx;
    char dir[4200];

    switch (ev->kind) {
    case STORE_EV_RESYNC:
        poll_kick_all(q->hub);
        q->pool_hooks->wake(q->pool_hooks->ctx);
        break;
    case STORE_EV_PROGRESS:
        poll_kick(q->hub, ev->id);
        break;
    case STORE_EV_JOB:
        if (ev->state == JOB_QUEUED) /* a new job, or one given back */
            q->pool_hooks->wake(q->pool_hooks->ctx);
        if (ev->state < 0) { /* deleted on some node */
            if (!q->pool_hooks->cancel(q->pool_hooks->ctx, ev->id)) {
                job_path(q, ev->id, NULL, dir, sizeof dir);
                dir_remove(dir);
            }
        } else if (ev->cancel && ev->state == JOB_RUNNING) {
            q->pool_hooks->cancel(q->pool_hooks->ctx, ev->id);
        }
        poll_kick(q->hub, ev->id);
        break;
    }
}

int shared_listen_start(qdcd *q)
{
    if (!shared_on(q))
        return 0;
    return q->store->ops->listen(q->store, on_event, q) == QDC_OK ? 0 : -1;
}

void shared_listen_stop(qdcd *q)
{
    if (shared_on(q))
        q->store->ops->listen(q->store, NULL, NULL);
}

/* One job directory of shared_sweep: removed (1) when its job is gone or
 * purged and it is unchanged for min_age seconds (ctx: {now, min_age}). */
static int sweep_one(qdcd *q, const char *id, const char *dir, void *ctx)
{
    const double *now_age = ctx;
    struct stat sb;
    job_rec j;
    qdc_status st;

    if (stat(dir, &sb) || now_age[0] - (double)sb.st_mtime < now_age[1])
        return 0;
    st = q->store->ops->get(q->store, id, &j);
    if (st == QDC_EINVAL || (st == QDC_OK && j.purged)) {
        dir_remove(dir);
        return 1;
    }
    return 0;
}

int shared_sweep(qdcd *q, double min_age)
{
    double now_age[2] = {wall_now(), min_age};
    return jobdir_each(q, sweep_one, now_age);
}

int shared_use(qdcd *q, const char *path)
{
    /* atime now, mtime kept */
    const struct timespec ts[2] = {{0, UTIME_NOW}, {0, UTIME_OMIT}};
    int rc;

    pthread_mutex_lock(&q->cache_lock);
    rc = access(path, R_OK);
    if (rc == 0)
        (void)utimensat(AT_FDCWD, path, ts, 0);
    pthread_mutex_unlock(&q->cache_lock);
    return rc == 0 ? 0 : -1;
}

/* Cached files the database also has, so evicting one only costs a fetch:
 * input.EXT, input-as.EXT, result.EXT (and their .etag), report.json; and
 * intake.qmesh, which only the node that accepted the upload has but whose
 * loss only costs a parse (a worker of another node parses the input; the
 * file would stay here until the job is deleted). Not input-tets.qmesh
 * (TetGen's mesh of a surface: only on its worker's node), nor files being
 * written (.tmp). */
static int evictable(const char *name)
{
    size_t n = strlen(name);
    if ((n >= 4 && !strcmp(name + n - 4, ".tmp")) ||
        (n >= 5 && !strcmp(name + n - 5, ".etag")))
        return 0;
    return !strncmp(name, "input.", 6) || !strncmp(name, "input-as.", 9) ||
           !strncmp(name, "result.", 7) || !strcmp(name, "report.json") ||
           !strcmp(name, JOB_INTAKE_QMESH);
}

typedef struct {
    double atime;
    int64_t size;
    char id[JOB_ID_LEN + 1];
    char name[31]; /* input.EXT, result.EXT, input-as.EXT, report.json */
} cache_file;

static int by_atime(const void *a, const void *b)
{
    double x = ((const cache_file *)a)->atime, y = ((const cache_file *)b)->atime;
    return x < y ? -1 : x > y;
}

static int64_t file_size(const char *path)
{
    struct stat sb;
    return lstat(path, &sb) == 0 && S_ISREG(sb.st_mode) ? (int64_t)sb.st_size : 0;
}

/* What shared_trim's scan finds: every cached file's bytes, and the files it
 * may evict. */
typedef struct {
    cache_file *c;
    size_t nc, capc;
    int64_t total;
} cache_scan;

/* One job directory of the scan (a jobdir_fn). */
static int scan_one(qdcd *q, const char *id, const char *dir, void *ctx)
{
    cache_scan *cs = ctx;
    char p[4400];
    DIR *jd;
    struct dirent *f;
    struct stat sb;
    int running;

    jd = opendir(dir);
    if (!jd)
        return 0;
    running = q->pool_hooks->running(q->pool_hooks->ctx, id);
    while ((f = readdir(jd)) != NULL) {
        if (f->d_name[0] == '.')
            continue;
        if ((size_t)snprintf(p, sizeof p, "%s/%s", dir, f->d_name) >= sizeof p ||
            lstat(p, &sb) || !S_ISREG(sb.st_mode))
            continue;
        cs->total += (int64_t)sb.st_size;
        if (running || !evictable(f->d_name) || strlen(f->d_name) >= sizeof cs->c->name)
            continue;
        if (cs->nc == cs->capc) {
            size_t nn = cs->capc ? 2 * cs->capc : 256;
            cache_file *g = realloc(cs->c, nn * sizeof *cs->c);
            if (!g)
                continue; /* counted, just not a candidate */
            cs->c = g;
            cs->capc = nn;
        }
        cache_file *c = &cs->c[cs->nc++];
        c->atime = (double)sb.st_atim.tv_sec + 1e-9 * (double)sb.st_atim.tv_nsec;
        c->size = (int64_t)sb.st_size;
        memcpy(c->id, id, JOB_ID_LEN + 1);
        memcpy(c->name, f->d_name, strlen(f->d_name) + 1); /* < sizeof name */
    }
    closedir(jd);
    return 0;
}

/* Evict the scan's candidates, least recently used first, while the cache
 * holds more than cap bytes. Returns how many files went. */
static int evict(qdcd *q, cache_scan *cs, int64_t cap, double min_age)
{
    char p[4400];
    struct stat sb;
    int evicted = 0;
    double now = wall_now();

    qsort(cs->c, cs->nc, sizeof *cs->c, by_atime);
    for (size_t i = 0; i < cs->nc && cs->total > cap; i++) {
        char side[4500];
        const cache_file *c = &cs->c[i];
        job_path(q, c->id, c->name, p, sizeof p);
        snprintf(side, sizeof side, "%s.etag", p);
        pthread_mutex_lock(&q->cache_lock);
        /* used since the scan (shared_use), or by a job this node started
         * meanwhile: keep it */
        if (lstat(p, &sb) == 0 &&
            (double)sb.st_atim.tv_sec + 1e-9 * (double)sb.st_atim.tv_nsec <
                now - min_age &&
            !q->pool_hooks->running(q->pool_hooks->ctx, c->id)) {
            int64_t s = file_size(side);
            if (unlink(p) == 0) {
                cs->total -= c->size;
                evicted++;
                if (s && unlink(side) == 0)
                    cs->total -= s;
            }
        }
        pthread_mutex_unlock(&q->cache_lock);
    }
    return evicted;
}

int shared_trim(qdcd *q, int64_t cap, double min_age, int64_t *bytes)
{
    cache_scan cs = {0};
    int evicted = 0;

    jobdir_each(q, scan_one, &cs);
    if (cs.total > cap && cs.nc)
        evicted = evict(q, &cs, cap, min_age);
    free(cs.c);
    *bytes = cs.total;
    return evicted;
}
