/* h5job.h - MED uploads: HDF5 is a large parser for untrusted files, so
 * qdcd never links it. The qdc-h5 program (built beside qdc and qdcd) reads
 * and writes MED files in a child process, as TetGen runs in `qdc tetra`:
 * child_run (killed at the job's deadline, on cancel, with the daemon),
 * --child-memory as its address-space limit, and a network namespace of its
 * own (qdc-h5 --sandbox). Thread-safe. */
#ifndef QDCD_H5JOB_H
#define QDCD_H5JOB_H

#include "child.h"
#include "server.h"

/* What the worker leaves beside input.med: the mesh as qdc-h5 read it (the
 * framed form of lib/io/meshio_med.c), the source of a MED result. */
#define H5JOB_FRAMES "input.frames"

/* What a run of qdc-h5 came to: 0 ok; else an HTTP status (400 a file
 * qdc-h5 refused, 422 killed by a limit, 500 not run) with a problem slug
 * and detail for people; -1 cancelled. */
typedef struct {
    int status;
    const char *slug;
    char detail[600];
    double seconds;
} h5job_outcome;

/* Job id's input.med read into its input.frames (frames NULL), or written
 * as res with the coordinates of the frames file frames; qdc-h5's messages
 * in DATA/jobs/ID/qdc-h5.log. */
void h5job_run(const qdcd *q, const char *id, const char *frames, const char *res,
               double deadline, const atomic_int *cancel, h5job_outcome *out);

#endif
