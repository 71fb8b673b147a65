/* jobdir.h - the job directories, DATA/jobs/ID: a job's input, results,
 * report and progress records (jobdir.c). */
#ifndef QDCD_JOBDIR_H
#define QDCD_JOBDIR_H

#include "qdc.h"
#include "server.h"

/* DATA/jobs/ID[/NAME] */
void job_path(const qdcd *q, const char *id, const char *name, char *out, size_t cap);

/* A surface job's tet mesh (TetGen's), kept beside its input once the worker
 * has read it: the mesh the optimizer started from. */
#define JOB_INPUT_TETS "input-tets.qmesh"
/* The upload as the intake parsed it (the library's binary mesh), for the
 * worker: written when it holds all the worker uses of the input
 * (job_intake_keeps); a job without it is parsed from its input. Removed
 * when the job ends. */
#define JOB_INTAKE_QMESH "intake.qmesh"
/* A topology=full result's point data (the upload's arrays, interpolated by
 * the run at the vertices it inserted), as a VTU of the result: written by
 * the worker when the vertices changed and the upload had arrays, read by the
 * conversions, which take the rest from result.qmesh and result.mesh. */
#define JOB_RESULT_PDATA "result-pdata.vtu"
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
/* Whether the worker parses a job's upload itself whatever JOB_INTAKE_QMESH
 * holds: topology=full (options: the job's JSON) of a format with point data
 * (VTK, VTU, Gmsh), whose arrays the run interpolates at the vertices it
 * inserts; the binary mesh has none. The intake writes no JOB_INTAKE_QMESH
 * for it. */
int job_parses_upload(meshio_format fmt, const char *options);
/* Call fn on each job directory DATA/jobs/ID (ID: JOB_ID_LEN lower-case hex
 * digits; anything else there is skipped) with its id and path; returns the
 * sum of what fn returned. */
typedef int (*jobdir_fn)(qdcd *q, const char *id, const char *dir, void *ctx);
int jobdir_each(qdcd *q, jobdir_fn fn, void *ctx);

#endif
