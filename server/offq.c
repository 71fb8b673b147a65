/* offq.c - threads serving suspended requests in order (offq.h). */
#define _GNU_SOURCE
#include "offq.h"

#include <omp.h>

static void *offq_main(void *arg)
{
    offq *o = arg;
    /* The library calls made here (parsing and checking an upload,
     * converting a result) stay on this thread: an OpenMP team would keep
     * its threads for the life of the process (nthreads-var is per thread) */
    omp_set_num_threads(1);
    pthread_mutex_lock(&o->lock);
    for (;;) {
        while (!o->head && !o->stop)
            pthread_cond_wait(&o->cond, &o->lock);
        req *r = o->head;
        if (!r)
            break; /* stopping and drained */
        o->head = r->off_next;
        if (!o->head)
            o->tail = NULL;
        pthread_mutex_unlock(&o->lock);
        o->fn(r->conn, r);
        r->off_done = 1;
        MHD_resume_connection(r->conn);
        pthread_mutex_lock(&o->lock);
    }
    pthread_mutex_unlock(&o->lock);
    return NULL;
}

int offq_start(offq *o, int n)
{
    for (o->running = 0; o->running < n && o->running < OFFQ_MAX_THREADS; o->running++)
        if (pthread_create(&o->th[o->running], NULL, offq_main, o)) {
            offq_stop(o);
            return -1;
        }
    return 0;
}

void offq_stop(offq *o)
{
    if (!o->running)
        return;
    pthread_mutex_lock(&o->lock);
    o->stop = 1;
    pthread_cond_broadcast(&o->cond);
    pthread_mutex_unlock(&o->lock);
    for (int i = 0; i < o->running; i++)
        pthread_join(o->th[i], NULL);
    o->running = 0;
}

enum MHD_Result offq_push(offq *o, struct MHD_Connection *c, req *r)
{
    pthread_mutex_lock(&o->lock);
    if (o->stop) {
        pthread_mutex_unlock(&o->lock);
        static const char *const h[] = {MHD_HTTP_HEADER_RETRY_AFTER, "5", NULL};
        return http_problem(c, r, 503, "shutting-down", NULL,
                            "the server is stopping; retry later", NULL, h);
    }
    r->off_next = NULL;
    if (o->tail)
        o->tail->off_next = r;
    else
        o->head = r;
    o->tail = r;
    /* Suspended before the thread can see it, so its resume always follows
     * this suspend. */
    MHD_suspend_connection(c);
    pthread_cond_signal(&o->cond);
    pthread_mutex_unlock(&o->lock);
    return MHD_YES;
}
