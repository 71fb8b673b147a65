/* job.h - worker threads that claim queued jobs from the store, run the
 * optimizer, publish progress and write results; and the option table shared
 * by the HTTP layer (query string) and the workers (stored JSON). */
#ifndef QDCD_JOB_H
#define QDCD_JOB_H

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

/* Set one option from its text form (query string or stored JSON).
 * Returns 0, or -1 with a message in why. time_limit is capped by cap_time. */
int job_opt_set(opt_options *o, const char *key, const char *val, double cap_time,
                char *why, size_t why_cap);
/* Canonical JSON of every option the daemon exposes. */
void job_opt_json(const opt_options *o, sbuf *out);
/* Rebuild options from job_opt_json output. */
int job_opt_from_json(opt_options *o, const char *json, double cap_time);

/* GET /v1/options: the option table (names, types, defaults, ranges, help) as
 * `qdc options` prints it, plus tetgen_quality and max_volume ("surface": true),
 * as {"options": [...]}. */
void job_opt_table_json(sbuf *out);

/* A surface job's tet mesh (TetGen's), kept beside its input once the worker
 * has read it: the mesh the optimizer started from. */
#define JOB_INPUT_TETS "input-tets.qmesh"
/* The upload as the intake parsed it (the library's binary mesh), for the
 * worker: written when it holds all the worker uses of the input
 * (job_intake_keeps); a job without it is parsed from its input. Removed
 * when the job ends. */
#define JOB_INTAKE_QMESH "intake.qmesh"
/* Input file name of a job for its format name ("input.qmesh", "input.stl"...). */
const char *job_input_name(const char *format);
/* Is format (a job's) a surface format, tetrahedralized by the worker? */
int job_is_surface(const char *format);
/* Whether JOB_INTAKE_QMESH can stand for an upload in format fmt parsed as m:
 * the binary mesh keeps coordinates, tets, regions and fixed flags (Gmsh
 * periodic pairs, held vertices) but no per-vertex refs, no boundary
 * triangles and no source file, which the worker writes into result.mesh
 * (a Medit upload's is spliced from its source); such uploads are parsed
 * again by the worker. An upload already in the binary format is its own. */
int job_intake_keeps(const mesh_t *m, meshio_format fmt);
/* The TetGen options stored in a surface job's options JSON ("tetgen_quality",
 * "max_volume"); -1 for each one not given. */
void job_tetra_opts(const char *json, double *quality, double *max_volume);

#endif
