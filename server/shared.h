/* shared.h - nodes that share nothing but the database (PostgreSQL store).
 * The job files (input, results, report) are blobs in the store and the
 * progress records are rows; DATA/jobs/ID on a node holds the files it used,
 * as a cache: fetched from the store when missing, removed when the job is
 * deleted or purged (shared_sweep). The node's listener (LISTEN/NOTIFY) wakes
 * its parked readers, idle workers and cancelled jobs when another node
 * changes something. With SQLite nothing here applies: shared_on() is 0 and
 * the files in DATA/jobs are the only copy. */
#ifndef QDCD_SHARED_H
#define QDCD_SHARED_H

#include "server.h"

/* The worker pool as the listener and the cache see it: main.c wires it
 * (qdcd.pool_hooks) so that this file never calls the pool, which calls it. */
typedef struct shared_hooks {
    void (*wake)(void *ctx);                   /* a job was queued: wake a worker */
    int (*cancel)(void *ctx, const char *id);  /* stop id if running here: 1 if it was */
    int (*running)(void *ctx, const char *id); /* 1 if a worker here runs id */
    void *ctx;
} shared_hooks;

int shared_on(const qdcd *q);
/* DATA/jobs/ID/name, from the store unless the cache has it; its SHA-256 hex
 * (as stored with it) into sha (65 bytes) if not NULL and fetched. QDC_OK
 * (the file is there), QDC_EINVAL (the store has no such file), QDC_EIO. */
qdc_status shared_fetch(qdcd *q, const char *id, const char *name, char *sha);
/* DATA/jobs/ID/name into the store (worker: only while it holds the lease). */
qdc_status shared_put(qdcd *q, const char *id, const char *name, const char *sha,
                      const char *worker);
/* Hear the other nodes (a thread; q->pool_hooks set); stop before the worker
 * pool goes away. */
int shared_listen_start(qdcd *q);
void shared_listen_stop(qdcd *q);
/* Remove cached job directories whose job is gone or expired, unchanged for
 * min_age seconds (an upload being committed has a directory before its
 * row). Returns how many. */
int shared_sweep(qdcd *q, double min_age);

/* The node-local cache's size cap (--cache-max). Its clock is each cached
 * file's atime, set by shared_use whenever the file is about to be read
 * (relatime and noatime mounts do not matter: it is set explicitly). */
#define SHARED_CACHE_MIN_AGE 10.0 /* seconds: a file used since is never evicted */
/* 0 (and marks the file as used now) if path is in the cache, else -1. A reader
 * calls it before it opens a cached file: the file then stays for at least
 * SHARED_CACHE_MIN_AGE seconds. */
int shared_use(qdcd *q, const char *path);
/* Evict the least recently used cached files until DATA/jobs holds at most
 * cap bytes: only files the database also has (inputs, results in every
 * format with their .etag, reports), never those of a job running on this
 * node, nor files used in the last min_age seconds. *bytes: the size after.
 * Returns the number of files evicted. */
int shared_trim(qdcd *q, int64_t cap, double min_age, int64_t *bytes);

#endif
