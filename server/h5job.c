/* h5job.c - qdc-h5 in a child process for MED jobs (see h5job.h). */
#include "h5job.h"

#include "jobdir.h"

#include <stdio.h>
#include <string.h>

/* qdc-h5 beside the qdc that --qdc names (or on PATH, as it is). */
static void h5_program(const qdcd *q, char *out, size_t cap)
{
    const char *slash = strrchr(q->cfg.qdc_path, '/');

    if (!slash)
        snprintf(out, cap, "qdc-h5");
    else
        snprintf(out, cap, "%.*s/qdc-h5", (int)(slash - q->cfg.qdc_path),
                 q->cfg.qdc_path);
}

void h5job_run(const qdcd *q, const char *id, const char *frames, const char *res,
               double deadline, const atomic_int *cancel, h5job_outcome *out)
{
    char prog[4200], in[4200], log[4200], fr[4200], mem[40], msg[400];
    char *argv[12];
    child_result cr;
    int k = 0;

    memset(out, 0, sizeof *out);
    h5_program(q, prog, sizeof prog);
    job_path(q, id, "input.med", in, sizeof in);
    job_path(q, id, "qdc-h5.log", log, sizeof log);
    if (!frames)
        job_path(q, id, H5JOB_FRAMES, fr, sizeof fr);
    snprintf(mem, sizeof mem, "%lld", (long long)q->cfg.child_memory);
    argv[k++] = prog;
    argv[k++] = "--sandbox";
    argv[k++] = mem;
    argv[k++] = "-n";
    argv[k++] = "the upload";
    argv[k++] = frames ? "-i" : "-o";
    argv[k++] = frames ? (char *)frames : fr;
    argv[k++] = frames ? "med-write" : "med-read";
    argv[k++] = in;
    if (frames)
        argv[k++] = (char *)res;
    argv[k] = NULL;
    child_run(argv, log, deadline, cancel, &cr);
    out->seconds = cr.seconds;
    if (q->cfg.verbose)
        fprintf(stderr, "qdcd: job %s: qdc-h5 %s %s after %.3f s (exit %d, signal %d)\n",
                id, argv[7], cr.exited && !cr.code ? "succeeded" : "failed", cr.seconds,
                cr.exited ? cr.code : -1, cr.signal);
    if (!cr.spawned) {
        out->status = 500;
        out->slug = "internal";
        snprintf(out->detail, sizeof out->detail,
                 "cannot run %.400s (it reads MED files; make builds it when libhdf5-dev "
                 "is installed): %s",
                 prog, strerror(cr.errno_spawn));
    } else if (cr.cancelled) {
        out->status = -1;
    } else if (cr.timed_out) {
        out->status = 422;
        out->slug = "job-failed";
        snprintf(out->detail, sizeof out->detail,
                 "qdc-h5 (the MED reader) did not finish within the job's time limit and "
                 "was killed after %.3g s",
                 cr.seconds);
    } else if (cr.signal) {
        out->status = 422;
        out->slug = "job-failed";
        snprintf(out->detail, sizeof out->detail,
                 "qdc-h5 (the MED reader) was killed by signal %d on this file (its "
                 "memory limit: %lld bytes)",
                 cr.signal, (long long)q->cfg.child_memory);
    } else if (cr.code) {
        int oom;
        child_last_line(log, "qdc-h5: ", msg, sizeof msg);
        oom = strstr(msg, "out of memory") != NULL;
        out->status = oom ? 422 : 400;
        out->slug = oom ? "job-failed" : "malformed-mesh";
        if (oom)
            snprintf(out->detail, sizeof out->detail,
                     "qdc-h5 (the MED reader) ran out of its memory limit (%lld bytes): "
                     "%s",
                     (long long)q->cfg.child_memory, msg);
        else
            snprintf(out->detail, sizeof out->detail, "MED: %s",
                     msg[0] ? msg : "qdc-h5 could not read the file");
    }
}
