/* h5job.c - qdc-h5 in a child process for MED and XDMF+HDF5 jobs (see
 * h5job.h). */
#include "h5job.h"

#include "jobdir.h"
#include "qdc.h"
#include "util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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

/* Run qdc-h5 with the arguments args (after the sandbox options; NULL-ended,
 * at most 12) for job id: what (in messages: "the MED reader") and kind (the
 * file, "MED") say what it did. */
static void h5_child(const qdcd *q, const char *id, char *const args[], const char *what,
                     const char *kind, double deadline, const atomic_int *cancel,
                     h5job_outcome *out)
{
    char prog[4200], log[4200], mem[40], msg[400];
    char *argv[20];
    child_result cr;
    int k = 0;

    memset(out, 0, sizeof *out);
    h5_program(q, prog, sizeof prog);
    job_path(q, id, "qdc-h5.log", log, sizeof log);
    snprintf(mem, sizeof mem, "%lld", (long long)q->cfg.child_memory);
    argv[k++] = prog;
    argv[k++] = "--sandbox";
    argv[k++] = mem;
    argv[k++] = "-n";
    argv[k++] = "the upload";
    for (int i = 0; args[i] && k < 19; i++)
        argv[k++] = args[i];
    argv[k] = NULL;
    child_run(argv, log, deadline, cancel, &cr);
    out->seconds = cr.seconds;
    if (q->cfg.verbose)
        fprintf(stderr,
                "qdcd: job %s: qdc-h5 (%s) %s after %.3f s (exit %d, signal %d)\n", id,
                what, cr.exited && !cr.code ? "succeeded" : "failed", cr.seconds,
                cr.exited ? cr.code : -1, cr.signal);
    if (!cr.spawned) {
        out->status = 500;
        out->slug = "internal";
        snprintf(
            out->detail, sizeof out->detail,
            "cannot run %.400s (it reads HDF5 files; make builds it when libhdf5-dev "
            "is installed): %s",
            prog, strerror(cr.errno_spawn));
    } else if (cr.cancelled) {
        out->status = -1;
    } else if (cr.timed_out) {
        out->status = 422;
        out->slug = "job-failed";
        snprintf(out->detail, sizeof out->detail,
                 "qdc-h5 (%s) did not finish within the job's time limit and "
                 "was killed after %.3g s",
                 what, cr.seconds);
    } else if (cr.signal) {
        out->status = 422;
        out->slug = "job-failed";
        snprintf(out->detail, sizeof out->detail,
                 "qdc-h5 (%s) was killed by signal %d on this file (its "
                 "memory limit: %lld bytes)",
                 what, cr.signal, (long long)q->cfg.child_memory);
    } else if (cr.code) {
        int oom;
        child_last_line(log, "qdc-h5: ", msg, sizeof msg);
        oom = strstr(msg, "out of memory") != NULL;
        out->status = oom ? 422 : 400;
        out->slug = oom ? "job-failed" : "malformed-mesh";
        if (oom)
            snprintf(out->detail, sizeof out->detail,
                     "qdc-h5 (%s) ran out of its memory limit (%lld bytes): %s", what,
                     (long long)q->cfg.child_memory, msg);
        else
            snprintf(out->detail, sizeof out->detail, "%s: %s", kind,
                     msg[0] ? msg : "qdc-h5 could not read the file");
    }
}

void h5job_run(const qdcd *q, const char *id, const char *frames, const char *res,
               double deadline, const atomic_int *cancel, h5job_outcome *out)
{
    char in[4200], fr[4200];

    job_path(q, id, "input.med", in, sizeof in);
    if (!frames)
        job_path(q, id, H5JOB_FRAMES, fr, sizeof fr);
    char *const rd[] = {"-o", fr, "med-read", in, NULL};
    char *const wr[] = {"-i", (char *)frames, "med-write", in, (char *)res, NULL};
    h5_child(q, id, frames ? wr : rd, frames ? "the MED writer" : "the MED reader", "MED",
             deadline, cancel, out);
}

void h5job_med_new(const qdcd *q, const char *id, const char *frames, const char *res,
                   double deadline, const atomic_int *cancel, h5job_outcome *out)
{
    char *const wr[] = {"-i", (char *)frames, "med-new", (char *)res, NULL};

    h5_child(q, id, wr, "the MED writer", "MED", deadline, cancel, out);
}

int h5job_is_xdmf(const qdcd *q, const job_rec *j)
{
    char p[4200];

    if (meshio_format_from_name(j->format) != MESHIO_XDMF)
        return 0;
    if (j->input_h5)
        return 1;
    job_path(q, j->id, JOB_INPUT_H5, p, sizeof p);
    return access(p, F_OK) == 0;
}

/* A failure of the job's own files (not of qdc-h5): a 500. */
static void h5_internal(h5job_outcome *out, const char *msg)
{
    out->status = 500;
    out->slug = "internal";
    snprintf(out->detail, sizeof out->detail, "%s", msg);
}

/* qdc-h5's spec of dataset k of h ("geometry:f:356x3:/data0") into s. */
static void h5_spec(const meshio_xdmf_h5 *h, int k, char *s, size_t cap)
{
    size_t n = (size_t)snprintf(s, cap, "%s:%c:", h->set[k].name, h->set[k].type);

    for (int d = 0; d < h->set[k].ndims && n < cap; d++)
        n += (size_t)snprintf(s + n, cap - n, "%s%lld", d ? "x" : "",
                              (long long)h->set[k].dims[d]);
    if (n < cap)
        snprintf(s + n, cap - n, ":%s", h->set[k].path);
}

/* The input of job id as meshio reads it (H5JOB_FRAMES): qdc-h5's frames in
 * fr read after room for the XML xml[0..xlen), which is filled in place (as
 * the CLI does: no copy of the frames). */
static void h5_xdmf_form(const qdcd *q, const char *id, const char *xml, size_t xlen,
                         const char *fr, h5job_outcome *out)
{
    char path[4300];
    size_t n = 0;
    char *in = file_read_after(fr, meshio_xdmf_h5_room(xlen), &n);
    qdc_error e;
    qdc_status st;

    unlink(fr);
    if (!in) {
        h5_internal(out, "qdc-h5 left no frames");
        return;
    }
    qdc_error_clear(&e);
    st = meshio_xdmf_h5_fill(in, n, xml, xlen, &e);
    job_path(q, id, H5JOB_FRAMES, path, sizeof path);
    if (st == QDC_OK)
        st = meshio_save_bytes(path, in, n, &e);
    free(in);
    if (st != QDC_OK) {
        out->status = st == QDC_EIO ? 500 : 400;
        out->slug = st == QDC_EIO ? "internal" : "malformed-mesh";
        snprintf(out->detail, sizeof out->detail, "%s", e.msg);
    }
}

void h5job_xdmf(const qdcd *q, const char *id, const char *frames, const char *res,
                double deadline, const atomic_int *cancel, h5job_outcome *out)
{
    char xp[4200], h5[4200], fr[4300], spec[7][1200];
    char *args[12];
    size_t xlen = 0;
    char *xml;
    meshio_xdmf_h5 h;
    qdc_error e;
    int k = 0, geom = -1;

    memset(out, 0, sizeof *out);
    job_path(q, id, job_input_name("xdmf"), xp, sizeof xp);
    job_path(q, id, JOB_INPUT_H5, h5, sizeof h5);
    xml = file_read_all(xp, &xlen);
    if (!xml) {
        h5_internal(out, "the job's XDMF file could not be read");
        return;
    }
    qdc_error_clear(&e);
    if (meshio_xdmf_h5_refs(xml, xlen, &h, &e) != QDC_OK || h.n == 0) {
        out->status = 400;
        out->slug = "malformed-mesh";
        snprintf(out->detail, sizeof out->detail, "%s",
                 h.n ? e.msg : "XDMF: no heavy data in HDF5");
        free(xml);
        return;
    }
    for (int s = 0; s < h.n; s++)
        if (!strcmp(h.set[s].name, "geometry"))
            geom = s;
    if (frames) { /* the result's .h5: its geometry replaced */
        char *const wr[] = {"-i",
                            (char *)frames,
                            "h5-write",
                            h5,
                            (char *)res,
                            "geometry",
                            h.set[geom < 0 ? 0 : geom].path,
                            NULL};
        free(xml);
        h5_child(q, id, wr, "the HDF5 writer", "HDF5", deadline, cancel, out);
        return;
    }
    job_path(q, id, "input.h5frames", fr, sizeof fr);
    args[k++] = "-o";
    args[k++] = fr;
    args[k++] = "h5-read";
    args[k++] = h5;
    for (int s = 0; s < h.n; s++) {
        h5_spec(&h, s, spec[s], sizeof spec[s]);
        args[k++] = spec[s];
    }
    args[k] = NULL;
    h5_child(q, id, args, "the HDF5 reader", "HDF5", deadline, cancel, out);
    if (out->status) {
        free(xml);
        unlink(fr);
        return;
    }
    h5_xdmf_form(q, id, xml, xlen, fr, out);
    free(xml);
}
