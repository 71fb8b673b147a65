/* offq.h - a thread that serves suspended requests one at a time, so the HTTP
 * thread never waits on a parse, a conversion or an fsync: the intake (parse,
 * validate and commit uploads, upload.c) and the converter (results and
 * inputs in the formats nobody wrote yet, result.c). Each request is answered
 * on that thread (MHD_queue_response is allowed on a suspended connection),
 * then resumed; the handler sees r->off_done when MHD calls it again. */
#ifndef QDCD_OFFQ_H
#define QDCD_OFFQ_H

#include "http.h"

#include <pthread.h>

typedef enum MHD_Result (*offq_fn)(struct MHD_Connection *c, req *r);

typedef struct offq {
    pthread_mutex_t lock;
    pthread_cond_t cond;
    req *head, *tail;
    int stop, running;
    pthread_t th;
    offq_fn fn;
} offq;

/* A static queue served by fn. */
#define OFFQ_INIT(fn)                                                                    \
    {                                                                                    \
        PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, NULL, NULL, 0, 0, 0, fn     \
    }

/* Start the thread. 0 or -1. */
int offq_start(offq *o);
/* Answer what is queued, then stop the thread. */
void offq_stop(offq *o);
/* Hand r to o's thread with its connection suspended (HTTP thread); a 503
 * once the queue is stopping. */
enum MHD_Result offq_push(offq *o, struct MHD_Connection *c, req *r);

#endif
