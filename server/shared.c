/* shared.c - the job files of nodes that share a PostgreSQL store (see
 * shared.h). */
#define _GNU_SOURCE
#include "shared.h"

#include "job.h"

#include <dirent.h>
#include <stdio.h>
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

    job_path(q, id, name, path, sizeof path);
    if (access(path, R_OK) == 0)
        return QDC_OK;
    job_path(q, id, NULL, dir, sizeof dir);
    if (dir_ensure(dir))
        return QDC_EIO;
    return q->store->ops->blob_get(q->store, id, name, path, sha);
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
