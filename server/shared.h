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

int shared_on(const qdcd *q);
/* DATA/jobs/ID/name, from the store unless the cache has it; its SHA-256 hex
 * (as stored with it) into sha (65 bytes) if not NULL and fetched. QDC_OK
 * (the file is there), QDC_EINVAL (the store has no such file), QDC_EIO. */
qdc_status shared_fetch(qdcd *q, const char *id, const char *name, char *sha);
/* DATA/jobs/ID/name into the store (worker: only while it holds the lease). */
qdc_status shared_put(qdcd *q, const char *id, const char *name, const char *sha,
                      const char *worker);
/* Hear the other nodes (a thread); stop before the worker pool goes away. */
int shared_listen_start(qdcd *q);
void shared_listen_stop(qdcd *q);
/* Remove cached job directories whose job is gone or expired, unchanged for
 * min_age seconds (an upload being committed has a directory before its
 * row). Returns how many. */
int shared_sweep(qdcd *q, double min_age);

#endif
