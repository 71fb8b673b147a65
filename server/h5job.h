/* h5job.h - MED and XDMF+HDF5 uploads: HDF5 is a large parser for untrusted
 * files, so qdcd never links it. The qdc-h5 program (built beside qdc and
 * qdcd) reads and writes MED files and XDMF's HDF5 heavy data in a child
 * process, as TetGen runs in `qdc tetra`: child_run (killed at the job's
 * deadline, on cancel, with the daemon), --child-memory as its address-space
 * limit, and a network namespace of its own (qdc-h5 --sandbox). Thread-safe. */
#ifndef QDCD_H5JOB_H
#define QDCD_H5JOB_H

#include "child.h"
#include "server.h"

/* What the worker leaves beside the upload: the mesh as qdc-h5 read it, the
 * source of the job's results. A MED job's: the framed form of
 * lib/io/meshio_med.c, read as MED; an XDMF+HDF5 job's: the XML and the
 * frames of its datasets (meshio_xdmf_h5_fill), read as XDMF. */
#define H5JOB_FRAMES "input.frames"
/* An XDMF+HDF5 job's two files (upload.c stores them so): the XML, whose
 * references name JOB_INPUT_H5, and the .h5 file as it was sent. */
#define JOB_INPUT_H5 "input.h5"

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

/* A MED file of its own written as res (qdc-h5 med-new) from the frames
 * file frames, which qdc's MED writer wrote for a whole mesh (a result whose
 * tets changed, or a job uploaded in another format: no splice of an
 * uploaded MED file); qdc-h5's messages as for h5job_run. */
void h5job_med_new(const qdcd *q, const char *id, const char *frames, const char *res,
                   double deadline, const atomic_int *cancel, h5job_outcome *out);

/* Is job j an XDMF+HDF5 job: XDMF with JOB_INPUT_H5 stored with its input
 * (its record says so; a job recorded before it did: the file is there)? */
int h5job_is_xdmf(const qdcd *q, const job_rec *j);
/* An XDMF+HDF5 job's datasets read by qdc-h5 and put with its XML into its
 * input.frames (frames NULL); or (frames: an XDMF file written from a mesh
 * read from input.frames, that is, XML and frames again) a copy of its
 * JOB_INPUT_H5 written as res with only the geometry's dataset replaced. */
void h5job_xdmf(const qdcd *q, const char *id, const char *frames, const char *res,
                double deadline, const atomic_int *cancel, h5job_outcome *out);

#endif
