/* job.c - the worker pool. A worker claims a job (lease), runs opt_run on its
 * input (the mesh the intake parsed, intake.qmesh, when it kept one; else the
 * upload parsed) with a progress callback that publishes every record to the poll hub
 * and appends it to DATA/jobs/ID/progress.jsonl, then writes the result in the
 * three formats plus report.json (each written, fsynced and renamed) and only
 * then marks the row done: a crash at any point leaves a running row that the
 * next start re-queues. With a PostgreSQL store (shared.h) the input comes
 * from the database when this node's cache lacks it, the records go to the
 * database (behind the local ones) and the results are stored there before
 * the row is marked done. */
#define _GNU_SOURCE
#include "job.h"
#include "problem.h"

#include "child.h"
#include "h5job.h"
#include "qdc.h"
#include "sha256.h"
#include "shared.h"

#include <errno.h>
#include <jansson.h>
#include <omp.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

typedef struct worker {
    struct job_pool *pool;
    pthread_t th;
    int idx;
    char name[64];
    /* Guarded by pool->lock. */
    char job[JOB_ID_LEN + 1]; /* "" when idle */
    atomic_int cancel;        /* read by opt_run through opts.cancel */
    int release;              /* shutdown: give the lease back instead of finishing */
} worker;

struct job_pool {
    qdcd *q;
    pthread_mutex_t lock;
    pthread_cond_t cond;
    int stopping;
    int pending; /* notifications not yet consumed */
    int n;
    worker *w;
};

/* ---------------------------------------------------------------- running -- */

typedef struct {
    worker *w;
    qdcd *q;
    const char *id;
    FILE *progress;
    double checked; /* last read of the row for a cancel from another node */
    int attempt;    /* the run's: each record says which run it belongs to */
    int iterations;
    char last[768];
} run_ctx;

static int on_progress(void *ctx, const opt_progress *p)
{
    run_ctx *r = ctx;
    sbuf js = {0}, line = {0}, rec = {0};

    /* the run's attempt first, then the record's members: a reader that
     * resumes across a takeover can tell the new run's records from the old */
    report_progress_json(p, sb_writer, &rec);
    if (!rec.oom && rec.len > 2 && rec.buf[0] == '{') {
        sb_printf(&js, "{\"attempt\":%d,", r->attempt);
        sb_add(&js, rec.buf + 1, rec.len - 1);
    }
    sb_free(&rec);
    if (!js.oom && js.len) {
        long seq = poll_publish(r->q->hub, r->id, js.buf, js.len, &line);
        if (seq >= 0) {
            r->iterations = (int)seq; /* the last record's: docs/defaults.md */
            if (line.len < sizeof r->last)
                memcpy(r->last, line.buf, line.len + 1);
            if (r->progress) {
                fwrite(line.buf, 1, line.len, r->progress);
                fputc('\n', r->progress);
                fflush(r->progress);
            }
            /* other nodes' readers: queued, written by the store's thread */
            if (shared_on(r->q))
                r->q->store->ops->progress_add(r->q->store, r->id, r->w->name, seq,
                                               line.buf, line.len);
        }
    }
    sb_free(&js);
    sb_free(&line);
    atomic_fetch_add(&r->q->m.iterations, 1);
    /* Several nodes on one database: a cancel or a DELETE sent to another
     * node is only in the row; read it at most twice a second. */
    if (store_pg_uri(r->q->cfg.store) && mono_now() - r->checked > 0.5) {
        job_rec row;
        qdc_status st = r->q->store->ops->get(r->q->store, r->id, &row);
        if (st == QDC_EINVAL || (st == QDC_OK && row.cancel_requested))
            atomic_store(&r->w->cancel, 1);
        r->checked = mono_now();
    }
    return atomic_load(&r->w->cancel);
}

/* A store write that must not be lost (the end of a job, a job given back):
 * tried again with a growing pause (0.1 s doubling to 5 s) while it fails,
 * for up to `limit` seconds; a full disk or a database that went away is
 * usually back by then. Returns QDC_OK once it succeeded. */
typedef qdc_status (*store_write_fn)(qdcd *q, worker *w, const job_rec *j);

static qdc_status store_finish_once(qdcd *q, worker *w, const job_rec *j)
{
    (void)w;
    /* every record of the run is stored before the row says it is over */
    if (shared_on(q) && q->store->ops->progress_sync(q->store, 5.0) != QDC_OK)
        return QDC_EIO;
    return q->store->ops->finish(q->store, j);
}

static qdc_status store_release_once(qdcd *q, worker *w, const job_rec *j)
{
    return q->store->ops->release(q->store, j->id, w->name);
}

static qdc_status retry_store(qdcd *q, const char *what, const char *id,
                              store_write_fn fn, worker *w, const job_rec *j,
                              double limit)
{
    double pause = 0.1, t0 = mono_now();
    qdc_status st;

    while ((st = fn(q, w, j)) != QDC_OK && mono_now() - t0 < limit) {
        if (pause == 0.1)
            fprintf(stderr, "qdcd: cannot %s job %s; trying again\n", what, id);
        struct timespec ts = {(time_t)pause, (long)((pause - (time_t)pause) * 1e9)};
        nanosleep(&ts, NULL);
        pause = pause * 2 > 5.0 ? 5.0 : pause * 2;
    }
    return st;
}

/* The end of a run, recorded for sure: retried; if it still cannot be
 * written, the job is handed back to the queue (another run, or another node,
 * will finish it); a job is never left running without a worker. */
static void record_end(qdcd *q, worker *w, job_rec *j)
{
    if (retry_store(q, "record the end of", j->id, store_finish_once, w, j, 600.0) ==
        QDC_OK)
        return;
    fprintf(stderr, "qdcd: cannot record the end of job %s: giving it back\n", j->id);
    (void)retry_store(q, "give back", j->id, store_release_once, w, j, 600.0);
}

static void problem(job_rec *j, int status, const char *slug, const char *title,
                    const char *detail)
{
    sbuf b = {0};
    problem_json(&b, status, slug, title, detail, NULL);
    snprintf(j->error, sizeof j->error, "%s", b.oom ? "" : b.buf);
    sb_free(&b);
}

static qdc_status write_report(const char *path, const report_t *rep, qdc_error *err)
{
    char tmp[4400];
    qdc_status st;
    FILE *f;

    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    f = fopen(tmp, "wb");
    if (!f)
        return qdc_fail(err, QDC_EIO, "cannot create %s", tmp);
    st = report_write_json(rep, report_file_writer, f, err);
    if (fflush(f) || fsync(fileno(f)))
        st = st == QDC_OK ? qdc_fail(err, QDC_EIO, "cannot write %s", tmp) : st;
    fclose(f);
    if (st == QDC_OK && rename(tmp, path))
        st = qdc_fail(err, QDC_EIO, "cannot rename %s", tmp);
    if (st != QDC_OK)
        unlink(tmp);
    return st;
}

/* Results, report and etags of a finished optimization. faces (may be NULL):
 * ref's, and out's too (opt_run_faces). */
static qdc_status save_outputs(qdcd *q, job_rec *j, const mesh_t *out, const mesh_t *ref,
                               const mesh_faces *faces, const opt_options *opts,
                               const opt_result *res, const report_quality *before,
                               qdc_error *err)
{
    static const struct {
        meshio_format fmt;
        const char *name;
        size_t etag_off;
    } outs[] = {
        {MESHIO_QMESH, "result.qmesh", offsetof(job_rec, etag_qmesh)},
        {MESHIO_JSON, "result.json", offsetof(job_rec, etag_json)},
        {MESHIO_MEDIT, "result.mesh", offsetof(job_rec, etag_medit)},
    };
    char path[4200];
    report_quality after;
    bderr_result bd;
    qdc_status st;
    int have_bd;

    for (size_t i = 0; i < sizeof outs / sizeof outs[0]; i++) {
        job_path(q, j->id, outs[i].name, path, sizeof path);
        st = meshio_save(path, outs[i].fmt, out, err);
        if (st != QDC_OK)
            return st;
        if (sha256_file_hex(path, (char *)j + outs[i].etag_off))
            return qdc_fail(err, QDC_EIO, "cannot hash %s", path);
        if (shared_on(q) &&
            (st = shared_put(q, j->id, outs[i].name, (char *)j + outs[i].etag_off,
                             j->lease_owner)) != QDC_OK)
            return qdc_fail(err, st, "cannot store %s in the database", outs[i].name);
    }
    /* topology=full changed the vertices of a mesh with point data: the
     * arrays as the run interpolated them, for the conversions (result.qmesh
     * holds none) */
    if (out->pdata && out->nv != ref->nv) {
        job_path(q, j->id, JOB_RESULT_PDATA, path, sizeof path);
        st = meshio_save(path, MESHIO_VTU, out, err);
        if (st != QDC_OK)
            return st;
        if (shared_on(q) &&
            (st = shared_put(q, j->id, JOB_RESULT_PDATA, "", j->lease_owner)) != QDC_OK)
            return qdc_fail(err, st, "cannot store %s in the database", JOB_RESULT_PDATA);
    }
    /* a MED or XDMF+HDF5 job's results are written from qdc-h5's frames of
     * the upload: into the store with them, for the other nodes */
    if (shared_on(q) &&
        (meshio_format_from_name(j->format) == MESHIO_MED || h5job_is_xdmf(q, j)) &&
        (st = shared_put(q, j->id, H5JOB_FRAMES, "", j->lease_owner)) != QDC_OK)
        return qdc_fail(err, st, "cannot store %s in the database", H5JOB_FRAMES);
    st = report_quality_faces(out, faces, &after, err);
    if (st != QDC_OK)
        return st;
    have_bd =
        bderr_meshes_faces(out, ref, faces, q->cfg.bderr_samples, &bd, NULL) == QDC_OK;
    report_t rep = {before, &after, res, opts, have_bd ? &bd : NULL};
    job_path(q, j->id, "report.json", path, sizeof path);
    st = write_report(path, &rep, err);
    if (st == QDC_OK && fsync_parent(path))
        st = qdc_fail(err, QDC_EIO, "cannot sync the job directory");
    if (st == QDC_OK && shared_on(q) &&
        (st = shared_put(q, j->id, "report.json", "", j->lease_owner)) != QDC_OK)
        qdc_fail(err, st, "cannot store the report in the database");
    return st;
}

/* The command line of `qdc tetra` for job j (argv: 16 slots; num: the text
 * of its numbers). */
static void tetra_argv(const qdcd *q, const job_rec *j, char *in, char *res,
                       char *argv[16], char num[4][40])
{
    double tq, tv;
    int k = 0;

    job_tetra_opts(j->options, &tq, &tv);
    argv[k++] = (char *)q->cfg.qdc_path;
    argv[k++] = "tetra";
    argv[k++] = in;
    argv[k++] = res;
    argv[k++] = "--die-with-parent"; /* no orphan TetGen after a daemon crash */
    if (tq >= 0) {
        snprintf(num[0], 40, "%.17g", tq);
        argv[k++] = "--tetgen-quality";
        argv[k++] = num[0];
    }
    if (tv >= 0) {
        snprintf(num[1], 40, "%.17g", tv);
        argv[k++] = "--max-volume";
        argv[k++] = num[1];
    }
    /* refused at once when the volume bound alone exceeds the tet limit, and
     * TetGen bounded in memory (it grows ~70 MB/s on a tiny max_volume) */
    snprintf(num[2], 40, "%lld", (long long)q->cfg.max_tets);
    argv[k++] = "--max-tets";
    argv[k++] = num[2];
    snprintf(num[3], 40, "%lld", (long long)q->cfg.child_memory);
    argv[k++] = "--max-memory";
    argv[k++] = num[3];
    argv[k] = NULL;
}

/* What the child's end means for the job: 0 it made a mesh, 1 the job failed
 * (j->error set), 2 it was cancelled. */
static int tetra_outcome(const qdcd *q, job_rec *j, const child_result *cr,
                         const char *in, const char *log, double budget)
{
    char msg[400], detail[600];

    if (!cr->spawned) {
        snprintf(detail, sizeof detail, "cannot run %.400s: %s", q->cfg.qdc_path,
                 strerror(cr->errno_spawn));
        problem(j, 500, "internal", "the surface could not be tetrahedralized", detail);
        return 1;
    }
    if (cr->cancelled)
        return 2;
    if (cr->timed_out) {
        snprintf(detail, sizeof detail,
                 "TetGen did not finish within the job's time limit (%g s)", budget);
        problem(j, 422, "tetgen", NULL, detail);
        return 1;
    }
    if (cr->signal) {
        snprintf(detail, sizeof detail, "TetGen crashed (signal %d) on this surface",
                 cr->signal);
        problem(j, 422, "tetgen", NULL, detail);
        return 1;
    }
    if (!cr->code)
        return 0;
    /* "qdc: DATA/jobs/ID/input.stl:3:1: message": the client knows its file as
     * the upload, not by our path. */
    child_last_line(log, "qdc: ", msg, sizeof msg);
    const char *m = msg;
    size_t n = strlen(in);
    if (!strncmp(m, in, n) && (m[n] == ':' || m[n] == 0))
        m += n + (m[n] == ':') + (m[n] == ':' && m[n + 1] == ' ');
    if (cr->code == 2 || cr->code == 3) {
        snprintf(detail, sizeof detail, "%s",
                 *m ? m : "TetGen could not tetrahedralize this surface");
        problem(j, 422, "tetgen", NULL, detail);
    } else {
        snprintf(detail, sizeof detail, "qdc tetra exited with status %d: %s", cr->code,
                 *m ? m : "no message");
        problem(j, 500, "internal", "the surface could not be tetrahedralized", detail);
    }
    return 1;
}

/* TetGen's mesh (res) read, within the server's limits and valid: 0 with
 * *out, or 1 with j->error set. */
static int tetra_read(const qdcd *q, job_rec *j, const char *res, mesh_t **out)
{
    char detail[600];
    size_t len = 0;
    char *buf = file_read_all(res, &len);
    qdc_error err;
    qdc_status st;

    qdc_error_clear(&err);
    st = buf ? meshio_read(buf, len, MESHIO_QMESH, out, &err)
             : qdc_fail(&err, QDC_EIO, "qdc tetra left no mesh");
    free(buf);
    if (st == QDC_OK &&
        ((*out)->nv > q->cfg.max_vertices || (*out)->nt > q->cfg.max_tets))
        st = qdc_fail(&err, QDC_ETOOBIG,
                      "TetGen made %d vertices and %d tets; this server accepts %lld and "
                      "%lld at most (raise max_volume or lower tetgen_quality)",
                      (*out)->nv, (*out)->nt, (long long)q->cfg.max_vertices,
                      (long long)q->cfg.max_tets);
    if (st == QDC_OK)
        st = mesh_validate(*out, NULL, &err);
    if (st == QDC_OK)
        return 0;
    mesh_free(*out);
    *out = NULL;
    snprintf(detail, sizeof detail, "%s: %s", qdc_status_str(st), err.msg);
    problem(j, st == QDC_ETOOBIG ? 413 : 500, st == QDC_ETOOBIG ? "too-big" : "internal",
            "the surface could not be tetrahedralized", detail);
    return 1;
}

/* A surface job's mesh: `qdc tetra` turns DATA/jobs/ID/input.EXT into
 * tetra.qmesh in a child process (libtet can crash on some surfaces and
 * prints to stdout; both stay in the child and its tetgen.log). TetGen's time
 * comes out of the job's budget. Returns 0 with *out set, 1 when the job
 * failed (j->error set), 2 when it was cancelled or handed back (w->cancel). */
static int tetrahedralize(worker *w, job_rec *j, opt_options *opts, mesh_t **out)
{
    qdcd *q = w->pool->q;
    char in[4200], res[4200], log[4200], num[4][40];
    char *argv[16];
    double budget;
    child_result cr;
    int t;

    job_path(q, j->id, job_input_name(j->format), in, sizeof in);
    job_path(q, j->id, "tetra.qmesh", res, sizeof res);
    job_path(q, j->id, "tetgen.log", log, sizeof log);
    tetra_argv(q, j, in, res, argv, num);
    budget = opts->time_limit > 0 ? opts->time_limit : q->cfg.job_time_limit;
    child_run(argv, log, mono_now() + budget, &w->cancel, &cr);
    if (q->cfg.verbose)
        fprintf(stderr, "qdcd: job %s: qdc tetra %s after %.3f s (exit %d, signal %d)\n",
                j->id, cr.exited && !cr.code ? "succeeded" : "failed", cr.seconds,
                cr.exited ? cr.code : -1, cr.signal);
    t = tetra_outcome(q, j, &cr, in, log, budget);
    if (t || (t = tetra_read(q, j, res, out)) != 0)
        return t;
    /* kept as the job's input mesh (GET /v1/jobs/{id}/input) */
    job_path(q, j->id, JOB_INPUT_TETS, in, sizeof in);
    if (rename(res, in))
        unlink(res);
    j->nv = (*out)->nv;
    j->nt = (*out)->nt;
    opts->time_limit = budget - cr.seconds > 0.001 ? budget - cr.seconds : 0.001;
    return 0;
}

/* A MED or XDMF+HDF5 job's mesh: qdc-h5 reads its upload (DATA/jobs/ID/
 * input.med, or input.xdmf's datasets in input.h5) into input.frames in a
 * child process (h5job.h), whose time comes out of the job's budget; the
 * mesh is then checked as an upload is at intake. 0 with *out set, 1 when
 * the job failed (j->error set), 2 when it was cancelled. */
static int h5_load(worker *w, job_rec *j, meshio_format fin, opt_options *opts,
                   mesh_t **out)
{
    qdcd *q = w->pool->q;
    char fr[4200], detail[600];
    double budget = opts->time_limit > 0 ? opts->time_limit : q->cfg.job_time_limit;
    const char *what = fin == MESHIO_MED ? "the MED file could not be read"
                                         : "the XDMF+HDF5 upload could not be read";
    h5job_outcome ho;
    size_t len = 0;
    char *buf;
    qdc_error err;
    qdc_status st;

    if (fin == MESHIO_MED)
        h5job_run(q, j->id, NULL, NULL, mono_now() + budget, &w->cancel, &ho);
    else
        h5job_xdmf(q, j->id, NULL, NULL, mono_now() + budget, &w->cancel, &ho);
    if (ho.status < 0)
        return 2;
    if (ho.status) {
        problem(j, ho.status, ho.slug, what, ho.detail);
        return 1;
    }
    job_path(q, j->id, H5JOB_FRAMES, fr, sizeof fr);
    buf = file_read_all(fr, &len);
    qdc_error_clear(&err);
    st = buf ? meshio_read(buf, len, fin, out, &err)
             : qdc_fail(&err, QDC_EIO, "qdc-h5 left no mesh");
    free(buf);
    if (st == QDC_OK &&
        ((*out)->nv > q->cfg.max_vertices || (*out)->nt > q->cfg.max_tets))
        st =
            qdc_fail(&err, QDC_ETOOBIG,
                     "%d vertices and %d tets; this server accepts %lld and %lld at most",
                     (*out)->nv, (*out)->nt, (long long)q->cfg.max_vertices,
                     (long long)q->cfg.max_tets);
    if (st == QDC_OK)
        st = mesh_validate(*out, NULL, &err);
    if (st != QDC_OK) {
        mesh_free(*out);
        *out = NULL;
        snprintf(detail, sizeof detail, "%s", err.msg);
        problem(j, qdc_status_http(st) < 500 ? qdc_status_http(st) : 500,
                st == QDC_ETOOBIG  ? "too-big"
                : st == QDC_EMESH  ? "invalid-mesh"
                : st == QDC_EPARSE ? "malformed-mesh"
                                   : "internal",
                what, detail);
        return 1;
    }
    j->nv = (*out)->nv;
    j->nt = (*out)->nt;
    opts->time_limit = budget - ho.seconds > 0.001 ? budget - ho.seconds : 0.001;
    return 0;
}

/* One run of a job: what its steps share. */
typedef struct {
    worker *w;
    qdcd *q;
    job_rec *j;
    run_ctx ctx; /* the progress callback's */
    mesh_t *m, *ref;
    mesh_faces *faces; /* the run's (opt_run_faces), for the report */
    opt_options opts;
    opt_result res;
    report_quality before;
    qdc_error err;
    qdc_status st; /* of the step that failed (RUN_ERROR) */
} run_state;

/* What a step of a run leads to. */
typedef enum {
    RUN_ON,       /* on to the next step */
    RUN_ERROR,    /* s->st and s->err say why: the job fails */
    RUN_FAILED,   /* the job failed, j->error says why */
    RUN_STOPPED,  /* cancelled, or to be handed back (w->cancel) */
    RUN_DONE,     /* the job ended (j->state set): record it */
    RUN_RELEASED, /* handed back to the queue: nothing to record */
} run_step;

/* Shared store: the input, from the database unless this node received it. */
static run_step run_fetch(run_state *s)
{
    if (!shared_on(s->q))
        return RUN_ON;
    s->st = shared_fetch(s->q, s->j->id, job_input_name(s->j->format), NULL);
    if (s->st == QDC_OK && s->j->input_h5) /* an XDMF file's .h5 */
        s->st = shared_fetch(s->q, s->j->id, JOB_INPUT_H5, NULL);
    if (s->st == QDC_EINVAL) {
        s->st = qdc_fail(&s->err, QDC_EIO, "the job's input is missing from the store");
        return RUN_ERROR;
    }
    if (s->st != QDC_OK) {
        fprintf(stderr, "qdcd: job %s: cannot fetch its input: back to the queue\n",
                s->j->id);
        (void)retry_store(s->q, "give back", s->j->id, store_release_once, s->w, s->j,
                          60.0);
        poll_drop(s->q->hub, s->j->id);
        return RUN_RELEASED;
    }
    return RUN_ON;
}

/* The mesh the intake parsed (JOB_INTAKE_QMESH), when it wrote one: 0 with
 * s->m set, -1 to parse the input (no such file: a Medit upload, one with
 * boundary triangles or vertex refs, a job accepted by an older qdcd or by
 * another node of a shared store; or a file that does not read back). */
static int read_intake(run_state *s, meshio_format fin)
{
    char path[4200];
    size_t len = 0;
    char *buf;
    qdc_error e;
    mesh_t *m = NULL;

    /* (a job accepted by a qdcd that wrote the QMESH for such an upload too) */
    if (fin == MESHIO_QMESH || fin == MESHIO_MEDIT ||
        job_parses_upload(fin, s->j->options))
        return -1;
    job_path(s->q, s->j->id, JOB_INTAKE_QMESH, path, sizeof path);
    buf = file_read_all(path, &len);
    if (!buf)
        return -1;
    qdc_error_clear(&e);
    qdc_status st = meshio_read(buf, len, MESHIO_QMESH, &m, &e);
    free(buf);
    if (st == QDC_OK && (m->nv != s->j->nv || m->nt != s->j->nt))
        st = qdc_fail(&e, QDC_EINTERNAL, "%d vertices and %d tets, not the job's", m->nv,
                      m->nt);
    if (st != QDC_OK) {
        fprintf(stderr, "qdcd: job %s: %s unusable (%s): parsing the input\n", s->j->id,
                JOB_INTAKE_QMESH, e.msg);
        mesh_free(m);
        return -1;
    }
    s->m = m;
    return 0;
}

/* The job's options and its mesh: the upload, or TetGen's mesh of a surface. */
static run_step run_load(run_state *s)
{
    char path[4200];
    size_t len = 0;
    char *buf;

    job_opt_from_json(&s->opts, s->j->options, s->q->cfg.job_time_limit);
    if (job_is_surface(s->j->format)) {
        int t = tetrahedralize(s->w, s->j, &s->opts, &s->m);
        return t == 1 ? RUN_FAILED : t == 2 ? RUN_STOPPED : RUN_ON;
    }
    meshio_format fin = meshio_format_from_name(s->j->format);
    double t0 = mono_now();
    if (fin == MESHIO_MED || h5job_is_xdmf(s->q, s->j)) {
        int t = h5_load(s->w, s->j, fin, &s->opts, &s->m);
        return t == 1 ? RUN_FAILED : t == 2 ? RUN_STOPPED : RUN_ON;
    }
    if (read_intake(s, fin) == 0) {
        if (s->q->cfg.verbose)
            fprintf(stderr, "qdcd: job %s: input read from %s in %.3f s\n", s->j->id,
                    JOB_INTAKE_QMESH, mono_now() - t0);
        return RUN_ON;
    }
    job_path(s->q, s->j->id, job_input_name(s->j->format), path, sizeof path);
    buf = file_read_all(path, &len);
    if (!buf) {
        s->st = qdc_fail(&s->err, QDC_EIO, "cannot read the job's input file");
        return RUN_ERROR;
    }
    /* A Medit upload keeps its file: result.mesh is then written as it, with
     * only the coordinates replaced (as `qdc optimize` writes OUT in IN's
     * format); the conversion thread does the same for the other formats
     * (result.c). */
    meshio_options mo = {
        .log = NULL, .log_ctx = NULL, .source = fin == MESHIO_MEDIT ? 1 : -1};
    s->st = meshio_read_ex(buf, len, fin, &mo, &s->m, &s->err);
    free(buf);
    if (s->st == QDC_OK && s->q->cfg.verbose)
        fprintf(stderr, "qdcd: job %s: input parsed from %s in %.3f s\n", s->j->id,
                job_input_name(s->j->format), mono_now() - t0);
    return s->st == QDC_OK ? RUN_ON : RUN_ERROR;
}

/* The mesh as it came (boundary reference), opt_run, then the quality before
 * measured on the faces the run found. */
static run_step run_optimize(run_state *s)
{
    s->ref = mesh_dup(s->m);
    if (!s->ref) {
        s->st = qdc_fail(&s->err, QDC_ENOMEM, "out of memory");
        return RUN_ERROR;
    }
    /* Workers already run side by side: split the cores instead of letting
     * every job's OpenMP team take them all. */
    long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
    s->opts.threads = ncpu > s->q->cfg.workers ? (int)(ncpu / s->q->cfg.workers) : 1;
    s->opts.cancel = &s->w->cancel;
    s->opts.progress = on_progress;
    s->opts.progress_ctx = &s->ctx;
    s->st = opt_run_faces(s->m, &s->opts, &s->res, &s->faces, &s->err);
    if (s->st == QDC_OK)
        s->st = report_quality_faces(s->ref, s->faces, &s->before, &s->err);
    return s->st == QDC_OK ? RUN_ON : RUN_ERROR;
}

/* Results, report and etags written. A full disk (or an I/O error) is a
 * passing condition: the result is in memory, so writing it is tried again
 * with a growing pause (up to 10 min); then the job goes back to the queue
 * rather than failing an accepted job for good. */
static run_step run_save(run_state *s)
{
    worker *w = s->w;

    s->st = save_outputs(s->q, s->j, s->m, s->ref, s->faces, &s->opts, &s->res,
                         &s->before, &s->err);
    for (double pause = 0.5, t0 = mono_now();
         s->st == QDC_EIO && mono_now() - t0 < 600.0 && !atomic_load(&w->cancel) &&
         !w->pool->stopping;
         pause = pause * 2 > 10.0 ? 10.0 : pause * 2) {
        if (pause == 0.5)
            fprintf(stderr, "qdcd: job %s: cannot write its results (%s); trying again\n",
                    s->j->id, s->err.msg);
        struct timespec ts = {(time_t)pause, (long)((pause - (time_t)pause) * 1e9)};
        nanosleep(&ts, NULL);
        qdc_error_clear(&s->err);
        s->st = save_outputs(s->q, s->j, s->m, s->ref, s->faces, &s->opts, &s->res,
                             &s->before, &s->err);
    }
    if (s->st == QDC_EIO) {
        fprintf(stderr,
                "qdcd: job %s: still cannot write its results: back to the queue\n",
                s->j->id);
        (void)retry_store(s->q, "give back", s->j->id, store_release_once, w, s->j, 60.0);
        poll_drop(s->q->hub, s->j->id);
        return RUN_RELEASED;
    }
    if (s->st != QDC_OK)
        return RUN_ERROR;
    s->j->state = JOB_SUCCEEDED;
    snprintf(s->j->stop_reason, sizeof s->j->stop_reason, "%s", s->res.stop_reason);
    return RUN_DONE;
}

/* Cancelled while the optimizer ran: the best mesh so far is the job's result,
 * with its report, as `qdc optimize` writes it on Ctrl-C. Not for a job
 * deleted meanwhile (its row is gone), nor when the optimizer had not started
 * or failed; when the files cannot be written the job ends without them. */
static void keep_best(run_state *s)
{
    job_rec row;
    qdc_error err;

    if (!s->ref || s->st != QDC_OK || s->res.outcome == OPT_FAILED ||
        s->q->store->ops->get(s->q->store, s->j->id, &row) != QDC_OK)
        return;
    qdc_error_clear(&err);
    if (save_outputs(s->q, s->j, s->m, s->ref, s->faces, &s->opts, &s->res, &s->before,
                     &err) != QDC_OK) {
        fprintf(stderr, "qdcd: job %s: cancelled; its best mesh was not kept: %s\n",
                s->j->id, err.msg);
        s->j->etag_qmesh[0] = s->j->etag_json[0] = s->j->etag_medit[0] = 0;
    }
}

/* After the run (or a stop before it): handed back at shutdown, cancelled,
 * failed in the optimizer, or its results saved. */
static run_step run_conclude(run_state *s)
{
    worker *w = s->w;
    job_rec *j = s->j;
    char detail[512];
    int release;

    pthread_mutex_lock(&w->pool->lock);
    release = w->release;
    pthread_mutex_unlock(&w->pool->lock);
    if (release) {
        /* Back to the queue: this run's records are not the job's history.
         * At shutdown: briefly (an expired lease is reclaimed anyway). */
        (void)retry_store(s->q, "give back", j->id, store_release_once, w, j, 5.0);
        poll_drop(s->q->hub, j->id);
        return RUN_RELEASED;
    }
    if (atomic_load(&w->cancel)) {
        j->state = JOB_CANCELLED;
        snprintf(j->stop_reason, sizeof j->stop_reason, "cancelled");
        keep_best(s);
        return RUN_DONE;
    }
    if (s->res.outcome == OPT_FAILED) {
        snprintf(detail, sizeof detail,
                 "the optimizer failed (%s); the input is unchanged",
                 s->res.stop_reason[0] ? s->res.stop_reason : "no detail");
        problem(j, 500, "optimizer-failed", NULL, detail);
        j->state = JOB_FAILED;
        snprintf(j->stop_reason, sizeof j->stop_reason, "%s", s->res.stop_reason);
        return RUN_DONE;
    }
    return run_save(s);
}

/* The end of the run recorded in the row (and the progress file synced). */
static void run_record(run_state *s)
{
    qdcd *q = s->q;
    job_rec *j = s->j, chk;
    char path[4200];

    if (s->ctx.progress)
        fsync(fileno(s->ctx.progress));
    j->finished = wall_now();
    j->expires = j->finished + q->cfg.retention;
    j->iterations = s->ctx.iterations;
    snprintf(j->last_progress, sizeof j->last_progress, "%s", s->ctx.last);
    record_end(q, s->w, j);
    atomic_fetch_add(&q->m.finished[j->state], 1);
    /* Deleted while running: nothing refers to the files any more. */
    if (q->store->ops->get(q->store, j->id, &chk) == QDC_EINVAL) {
        job_path(q, j->id, NULL, path, sizeof path);
        dir_remove(path);
    }
    poll_end(q->hub, j->id);
}

static void run_job(worker *w, job_rec *j)
{
    qdcd *q = w->pool->q;
    char path[4200], detail[512];
    run_state s;
    run_step k;

    memset(&s, 0, sizeof s);
    s.w = w;
    s.q = q;
    s.j = j;
    s.ctx = (run_ctx){w, q, j->id, NULL, mono_now(), j->attempts, 0, ""};
    qdc_error_clear(&s.err);
    poll_begin(q->hub, j->id);
    job_path(q, j->id, "progress.jsonl", path, sizeof path);
    s.ctx.progress = shared_on(q) ? NULL : fopen(path, "w"); /* shared: in the store */

    k = run_fetch(&s);
    if (k == RUN_ON)
        k = run_load(&s);
    if (k == RUN_ON)
        k = run_optimize(&s);
    if (k == RUN_ON || k == RUN_STOPPED)
        k = run_conclude(&s);
    if (k == RUN_ERROR) {
        snprintf(detail, sizeof detail, "%s: %s", qdc_status_str(s.st), s.err.msg);
        problem(j, qdc_status_http(s.st) >= 500 ? qdc_status_http(s.st) : 422,
                "job-failed", NULL, detail);
    }
    if (k == RUN_ERROR || k == RUN_FAILED)
        j->state = JOB_FAILED;
    if (k != RUN_RELEASED) {
        run_record(&s);
        /* read once: a job handed back keeps it for its next run */
        job_path(q, j->id, JOB_INTAKE_QMESH, path, sizeof path);
        unlink(path);
    }
    if (s.ctx.progress)
        fclose(s.ctx.progress);
    mesh_faces_free(s.faces);
    mesh_free(s.m);
    mesh_free(s.ref);
}

static void *worker_main(void *arg)
{
    worker *w = arg;
    job_pool *p = w->pool;
    qdcd *q = p->q;
    job_rec j;
    int found;

    /* Below the HTTP thread: optimizing is throughput work, answering is
     * latency work. Linux nice values are per thread, and the OpenMP threads
     * a job starts inherit this one. */
    if (setpriority(PRIO_PROCESS, (id_t)syscall(SYS_gettid), 10))
        fprintf(stderr, "qdcd: %s: cannot lower its priority\n", w->name);
    /* This worker's share of the cores for everything it runs in parallel
     * (the optimizer gets it as opts.threads; the boundary error and the
     * other library calls of a job use this thread's OpenMP setting). */
    {
        long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
        omp_set_num_threads(ncpu > q->cfg.workers ? (int)(ncpu / q->cfg.workers) : 1);
    }
    for (;;) {
        pthread_mutex_lock(&p->lock);
        while (!p->stopping && !p->pending) {
            struct timespec ts;
            clock_gettime(CLOCK_REALTIME, &ts);
            ts.tv_sec += 2; /* also picks up jobs whose lease expired elsewhere */
            if (pthread_cond_timedwait(&p->cond, &p->lock, &ts))
                break;
        }
        if (p->stopping) {
            pthread_mutex_unlock(&p->lock);
            break;
        }
        if (p->pending)
            p->pending--;
        pthread_mutex_unlock(&p->lock);

        if (q->store->ops->claim(q->store, w->name, q->cfg.lease, &j, &found) != QDC_OK ||
            !found)
            continue;
        pthread_mutex_lock(&p->lock);
        snprintf(w->job, sizeof w->job, "%s", j.id);
        atomic_store(&w->cancel, j.cancel_requested);
        w->release = 0;
        pthread_mutex_unlock(&p->lock);
        /* A DELETE removes the row and then cancels the job's worker: a worker
         * registered before that cancel is cancelled; one registered after it
         * finds the row gone here. Either way a deleted job does not run. */
        {
            job_rec chk;
            if (q->store->ops->get(q->store, j.id, &chk) == QDC_EINVAL) {
                char path[4200];
                job_path(q, j.id, NULL, path, sizeof path);
                dir_remove(path);
                pthread_mutex_lock(&p->lock);
                w->job[0] = 0;
                pthread_mutex_unlock(&p->lock);
                continue;
            }
        }
        if (q->cfg.verbose)
            fprintf(stderr, "qdcd: %s runs job %s (attempt %d)\n", w->name, j.id,
                    j.attempts);
        run_job(w, &j);
        pthread_mutex_lock(&p->lock);
        w->job[0] = 0;
        /* There may be more queued work than notifications (restart). */
        p->pending++;
        pthread_mutex_unlock(&p->lock);
    }
    return NULL;
}

job_pool *job_pool_start(qdcd *q)
{
    job_pool *p = calloc(1, sizeof *p);

    if (!p)
        return NULL;
    p->q = q;
    p->n = q->cfg.workers;
    p->w = calloc((size_t)p->n, sizeof *p->w);
    if (!p->w) {
        free(p);
        return NULL;
    }
    pthread_mutex_init(&p->lock, NULL);
    pthread_cond_init(&p->cond, NULL);
    p->pending = p->n; /* look for work left by a previous run */
    for (int i = 0; i < p->n; i++) {
        worker *w = &p->w[i];
        w->pool = p;
        w->idx = i;
        snprintf(w->name, sizeof w->name, "%s/w%d", q->instance, i);
        if (pthread_create(&w->th, NULL, worker_main, w)) {
            p->n = i;
            job_pool_stop(p, 0);
            return NULL;
        }
    }
    return p;
}

void job_pool_notify(job_pool *p)
{
    pthread_mutex_lock(&p->lock);
    p->pending++;
    pthread_cond_signal(&p->cond);
    pthread_mutex_unlock(&p->lock);
}

int job_pool_cancel(job_pool *p, const char *id)
{
    int hit = 0;
    pthread_mutex_lock(&p->lock);
    for (int i = 0; i < p->n; i++) {
        if (!strcmp(p->w[i].job, id)) {
            atomic_store(&p->w[i].cancel, 1);
            hit = 1;
        }
    }
    pthread_mutex_unlock(&p->lock);
    return hit;
}

void job_pool_heartbeat(job_pool *p)
{
    char(*ids)[JOB_ID_LEN + 1], (*names)[64];
    int n = 0;

    if (!p)
        return;
    ids = calloc((size_t)p->n, sizeof *ids);
    names = calloc((size_t)p->n, sizeof *names);
    if (ids && names) {
        /* copied out: the store is not called with the pool locked */
        pthread_mutex_lock(&p->lock);
        for (int i = 0; i < p->n; i++)
            if (p->w[i].job[0]) {
                memcpy(ids[n], p->w[i].job, sizeof ids[n]);
                memcpy(names[n++], p->w[i].name, sizeof names[0]);
            }
        pthread_mutex_unlock(&p->lock);
    }
    /* a job that ended meanwhile is no longer running: renewing its lease
     * changes nothing that matters (only running rows are taken over) */
    for (int i = 0; i < n; i++)
        p->q->store->ops->renew(p->q->store, ids[i], names[i], p->q->cfg.lease);
    free(ids);
    free(names);
}

int job_pool_has(job_pool *p, const char *id)
{
    int hit = 0;
    if (!p)
        return 0;
    pthread_mutex_lock(&p->lock);
    for (int i = 0; i < p->n && !hit; i++)
        hit = !strcmp(p->w[i].job, id);
    pthread_mutex_unlock(&p->lock);
    return hit;
}

int job_pool_busy(job_pool *p)
{
    int n = 0;
    pthread_mutex_lock(&p->lock);
    for (int i = 0; i < p->n; i++)
        n += p->w[i].job[0] != 0;
    pthread_mutex_unlock(&p->lock);
    return n;
}

void job_pool_stop(job_pool *p, double grace)
{
    if (!p)
        return;
    pthread_mutex_lock(&p->lock);
    p->stopping = 1;
    pthread_cond_broadcast(&p->cond);
    pthread_mutex_unlock(&p->lock);
    double until = mono_now() + grace, beat = mono_now() + p->q->cfg.lease / 4;
    while (job_pool_busy(p) && mono_now() < until) {
        /* the main loop's heartbeat has stopped: the jobs finishing in
         * their grace keep their leases from here */
        if (mono_now() >= beat) {
            job_pool_heartbeat(p);
            beat = mono_now() + p->q->cfg.lease / 4;
        }
        usleep(50 * 1000);
    }
    pthread_mutex_lock(&p->lock);
    for (int i = 0; i < p->n; i++) {
        if (p->w[i].job[0]) {
            p->w[i].release = 1;
            atomic_store(&p->w[i].cancel, 1);
        }
    }
    pthread_mutex_unlock(&p->lock);
    for (int i = 0; i < p->n; i++)
        pthread_join(p->w[i].th, NULL);
    pthread_cond_destroy(&p->cond);
    pthread_mutex_destroy(&p->lock);
    free(p->w);
    free(p);
}
