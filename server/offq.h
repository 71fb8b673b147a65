/* offq.h - threads that serve suspended requests in their order of arrival,
 * so the HTTP thread never waits on a parse, a conversion or an fsync: the
 * intake (parse, validate and commit uploads, upload.c) and the converter
 * (results and inputs in the formats nobody wrote yet, result.c). Each request
 * is answered on one of them (MHD_queue_response is allowed on a suspended
 * connection), then resumed; the handler sees r->off_done when MHD calls it
 * again. With several threads, requests are served side by side: fn must be
 * thread-safe. */
#ifndef QDCD_OFFQ_H
#define QDCD_OFFQ_H

#include "http.h"

#include <pthread.h>

typedef enum MHD_Result (*offq_fn)(struct MHD_Connection *c, req *r);

#define OFFQ_MAX_THREADS 8

typedef struct offq {
    pthread_mutex_t lock;
    pthread_cond_t cond;
    req *head, *tail;
    int stop, running; /* running: threads started */
    pthread_t th[OFFQ_MAX_THREADS];
    offq_fn fn;
} offq;

/* A static queue served by fn. */
#define OFFQ_INIT(fn)                                                                    \
    {                                                                                    \
        PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, NULL, NULL, 0, 0, {0}, fn   \
    }

/* Start n threads (1..OFFQ_MAX_THREADS). 0 or -1 (none left running). */
int offq_start(offq *o, int n);
/* Answer what is queued, then stop the threads. */
void offq_stop(offq *o);
/* Hand r to o's thread with its connection suspended (HTTP thread); a 503
 * once the queue is stopping. */
enum MHD_Result offq_push(offq *o, struct MHD_Connection *c, req *r);

#endif
