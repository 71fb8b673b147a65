/* job.h - worker threads that claim queued jobs from the store, run the
 * optimizer, publish progress and write results. The option table they share
 * with the HTTP layer is jobopt.h, the job directories jobdir.h. */
#ifndef QDCD_JOB_H
#define QDCD_JOB_H

#include "jobdir.h"
#include "jobopt.h"
#include "qdc.h"
#include "server.h"
#include "util.h"

typedef struct job_pool job_pool;

/* Start cfg.workers threads. NULL on failure. */
job_pool *job_pool_start(qdcd *q);
/* A job was queued: wake a worker. */
void job_pool_notify(job_pool *p);
/* Ask the worker running id (if any here) to stop; returns 1 if it was running. */
int job_pool_cancel(job_pool *p, const char *id);
/* 1 if a worker of this pool is running job id */
int job_pool_has(job_pool *p, const char *id);
/* Renew the lease of every job this pool runs (main loop, every --lease/4):
 * a heartbeat of the node, whatever its jobs do meanwhile (one iteration of
 * a large mesh, or TetGen, can outlast a lease). NULL: nothing. */
void job_pool_heartbeat(job_pool *p);
/* Stop claiming; wait up to grace seconds for running jobs, then stop them and
 * give their leases back (they run again at the next start); join; free. */
void job_pool_stop(job_pool *p, double grace);
int job_pool_busy(job_pool *p);

#endif
