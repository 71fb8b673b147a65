/* trash.c - job directories renamed into DATA/trash and removed by a thread
 * of their own (trash.h). Unlinking a big job's files (inputs, results in
 * several formats, progress records) took ~3 s, on the HTTP thread for a
 * DELETE and on the main loop (which renews leases) for a purge. */
#define _GNU_SOURCE
#include "trash.h"

#include "util.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

static struct {
    pthread_mutex_t lock;
    pthread_cond_t cond;
    pthread_t th;
    int running, stop, pending;
    unsigned long seq; /* makes each name in the trash unique */
    char dir[4200];    /* DATA/trash */
} t = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, 0, 0, 0, 0, 0, {0}};

/* Every directory in the trash removed (one level of files each, as
 * dir_remove); stray files too. */
static void empty_trash(void)
{
    dir_clear(t.dir, 1);
}

int trash_open(const qdcd *q)
{
    snprintf(t.dir, sizeof t.dir, "%.4090s/trash", q->cfg.data);
    if (dir_ensure(t.dir))
        return -1;
    empty_trash();
    return 0;
}

static void *trash_main(void *arg)
{
    (void)arg;
    pthread_mutex_lock(&t.lock);
    for (;;) {
        while (!t.pending && !t.stop)
            pthread_cond_wait(&t.cond, &t.lock);
        if (!t.pending)
            break;
        t.pending = 0;
        pthread_mutex_unlock(&t.lock);
        empty_trash();
        pthread_mutex_lock(&t.lock);
    }
    pthread_mutex_unlock(&t.lock);
    return NULL;
}

int trash_start(void)
{
    pthread_mutex_lock(&t.lock);
    t.stop = 0;
    t.running = t.dir[0] && !pthread_create(&t.th, NULL, trash_main, NULL);
    pthread_mutex_unlock(&t.lock);
    return t.running ? 0 : -1;
}

void trash_put(const char *dir)
{
    const char *base = strrchr(dir, '/');
    char to[4500];
    int why = EAGAIN; /* 0 once moved */

    pthread_mutex_lock(&t.lock);
    if (t.running) {
        snprintf(to, sizeof to, "%s/%.64s.%lu", t.dir, base ? base + 1 : dir, t.seq++);
        why = rename(dir, to) ? errno : 0;
        if (!why) {
            t.pending = 1;
            pthread_cond_signal(&t.cond);
        }
    }
    pthread_mutex_unlock(&t.lock);
    /* not moved: gone already (ENOENT), or removed here */
    if (why && why != ENOENT)
        dir_remove(dir);
}

void trash_stop(void)
{
    pthread_mutex_lock(&t.lock);
    if (!t.running) {
        pthread_mutex_unlock(&t.lock);
        return;
    }
    t.stop = 1;
    pthread_cond_signal(&t.cond);
    pthread_mutex_unlock(&t.lock);
    pthread_join(t.th, NULL);
    t.running = 0;
}
