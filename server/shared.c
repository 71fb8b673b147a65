/* shared.c - the job files of nodes that share a PostgreSQL store (see
 * shared.h). */
#define _GNU_SOURCE
#include "shared.h"

#include "job.h"

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
        job_pool_notify(q->pool);
        break;
    case STORE_EV_PROGRESS:
        poll_kick(q->hub, ev->id);
        break;
    case STORE_EV_JOB:
        if (ev->state == JOB_QUEUED) /* a new job, or one given back */
            job_pool_notify(q->pool);
        if (ev->state < 0) { /* deleted on some node */
            if (!job_pool_cancel(q->pool, ev->id)) {
                job_path(q, ev->id, NULL, dir, sizeof dir);
                dir_remove(dir);
            }
        } else if (ev->cancel && ev->state == JOB_RUNNING) {
            job_pool_cancel(q->pool, ev->id);
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

int shared_sweep(qdcd *q, double min_age)
{
    char p[4400];
    DIR *d;
    struct dirent *e;
    struct stat sb;
    int n = 0;
    double now = wall_now();

    snprintf(p, sizeof p, "%s/jobs", q->cfg.data);
    d = opendir(p);
    if (!d)
        return 0;
    while ((e = readdir(d))) {
        job_rec j;
        qdc_status st;
        if (e->d_name[0] == '.' || strlen(e->d_name) != JOB_ID_LEN ||
            strspn(e->d_name, "0123456789abcdef") != JOB_ID_LEN)
            continue;
        snprintf(p, sizeof p, "%s/jobs/%s", q->cfg.data, e->d_name);
        if (stat(p, &sb) || now - (double)sb.st_mtime < min_age)
            continue;
        st = q->store->ops->get(q->store, e->d_name, &j);
        if (st == QDC_EINVAL || (st == QDC_OK && j.purged)) {
            dir_remove(p);
            n++;
        }
    }
    closedir(d);
    return n;
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

int shared_trim(qdcd *q, int64_t cap, double min_age, int64_t *bytes)
{
    char p[4400];
    DIR *d, *jd;
    struct dirent *e, *f;
    struct stat sb;
    cache_file *c = NULL;
    size_t nc = 0, capc = 0;
    int64_t total = 0;
    int evicted = 0;

    snprintf(p, sizeof p, "%s/jobs", q->cfg.data);
    d = opendir(p);
    if (!d) {
        *bytes = 0;
        return 0;
    }
    while ((e = readdir(d))) {
        char dir[4400];
        int running;
        if (e->d_name[0] == '.' || strlen(e->d_name) != JOB_ID_LEN ||
            strspn(e->d_name, "0123456789abcdef") != JOB_ID_LEN)
            continue;
        snprintf(dir, sizeof dir, "%s/jobs/%.32s", q->cfg.data, e->d_name);
        jd = opendir(dir);
        if (!jd)
            continue;
        running = job_pool_has(q->pool, e->d_name);
        while ((f = readdir(jd))) {
            if (f->d_name[0] == '.')
                continue;
            if ((size_t)snprintf(p, sizeof p, "%s/%s", dir, f->d_name) >= sizeof p ||
                lstat(p, &sb) || !S_ISREG(sb.st_mode))
                continue;
            total += (int64_t)sb.st_size;
            if (running || !evictable(f->d_name) || strlen(f->d_name) >= sizeof c->name)
                continue;
            if (nc == capc) {
                size_t nn = capc ? 2 * capc : 256;
                cache_file *g = realloc(c, nn * sizeof *c);
                if (!g)
                    continue; /* counted, just not a candidate */
                c = g;
                capc = nn;
            }
            c[nc].atime = (double)sb.st_atim.tv_sec + 1e-9 * (double)sb.st_atim.tv_nsec;
            c[nc].size = (int64_t)sb.st_size;
            memcpy(c[nc].id, e->d_name, JOB_ID_LEN + 1);
            memcpy(c[nc].name, f->d_name, strlen(f->d_name) + 1); /* < sizeof name */
            nc++;
        }
        closedir(jd);
    }
    closedir(d);
    if (total > cap && nc) {
        double now = wall_now();
        qsort(c, nc, sizeof *c, by_atime);
        for (size_t i = 0; i < nc && total > cap; i++) {
            char side[4500];
            job_path(q, c[i].id, c[i].name, p, sizeof p);
            snprintf(side, sizeof side, "%s.etag", p);
            pthread_mutex_lock(&q->cache_lock);
            /* used since the scan (shared_use), or by a job this node started
             * meanwhile: keep it */
            if (lstat(p, &sb) == 0 &&
                (double)sb.st_atim.tv_sec + 1e-9 * (double)sb.st_atim.tv_nsec <
                    now - min_age &&
                !job_pool_has(q->pool, c[i].id)) {
                int64_t s = file_size(side);
                if (unlink(p) == 0) {
                    total -= c[i].size;
                    evicted++;
                    if (s && unlink(side) == 0)
                        total -= s;
                }
            }
            pthread_mutex_unlock(&q->cache_lock);
        }
    }
    free(c);
    *bytes = total;
    return evicted;
}
