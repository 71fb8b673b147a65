/* trash.h - job directories removed off the request thread: a DELETE (or the
 * purge of an expired job) renames DATA/jobs/ID into DATA/trash/ (one
 * rename, however big the job) and a thread of its own removes the files.
 * Nothing is lost on a crash: a job's directory is either still in jobs/ or
 * in trash/, and trash_open empties trash/ before the daemon serves.
 * trash_put may be called from any thread once trash_start returned. */
#ifndef QDCD_TRASH_H
#define QDCD_TRASH_H

#include "server.h"

/* DATA/trash made, and emptied of what a crash left there (at start-up,
 * before any thread runs). 0 or -1 (errno set). */
int trash_open(const qdcd *q);
/* Start the remover thread. 0 or -1. */
int trash_start(void);
/* Move dir (a job directory) into the trash and wake the remover; removed at
 * once on this thread when it cannot be moved (or the remover is not
 * running). */
void trash_put(const char *dir);
/* Remove what is in the trash, then stop the thread (no-op if not started). */
void trash_stop(void);

#endif
