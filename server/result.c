/* result.c - GET /v1/jobs/{id}/result, /input and /report. The format of a
 * result or input representation is negotiated (?format=, else Accept, else
 * the binary); a file that exists is served from the MHD thread with its
 * strong ETag, any other format is written once by the conversion thread
 * (with the hash beside it) and served from then on. With a PostgreSQL store
 * (shared.h) a file this node's cache lacks is fetched from the database,
 * and a conversion is stored there for the other nodes. */
#define _GNU_SOURCE
#include "endpoints.h"
#include "h5job.h"
#include "handler.h"

#include "job.h"
#include "offq.h"
#include "parse.h"
#include "qdc.h"
#include "route.h"
#include "shared.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

static const char *const no_headers[] = {NULL};

static enum MHD_Result process_convert(struct MHD_Connection *c, req *r);

/* The conversion thread: one, so two requests never write the same file. */
static offq convert = OFFQ_INIT(process_convert);

int result_start(void)
{
    return offq_start(&convert, 1);
}

void result_stop(void)
{
    offq_stop(&convert);
}

/* The input mesh of a job as the optimizer read it: the upload, or TetGen's
 * mesh of a surface once the worker has made it. */
static meshio_format input_source(req *r, const job_rec *j, char *path, size_t cap)
{
    int surf = job_is_surface(j->format);
    meshio_format f = surf ? MESHIO_QMESH : meshio_format_from_name(j->format);

    /* MED, XDMF+HDF5: the frames qdc-h5 read the upload into (h5job.h),
     * not HDF5 */
    job_path(r->q, j->id,
             surf                                        ? JOB_INPUT_TETS
             : f == MESHIO_MED || h5job_is_xdmf(r->q, j) ? H5JOB_FRAMES
                                                         : job_input_name(j->format),
             path, cap);
    return f;
}

/* A MED or XDMF+HDF5 job's frames (what qdc-h5 read its upload into: its
 * input mesh, and what its results are written from) from the store, unless
 * cached here, and an XDMF+HDF5 job's .h5 when r asks for the result's .h5
 * (written into a copy of it); QDC_OK for any other job. */
static qdc_status fetch_frames(req *r, const job_rec *j)
{
    qdc_status st;

    if (!shared_on(r->q) || job_is_surface(j->format) ||
        (meshio_format_from_name(j->format) != MESHIO_MED && !h5job_is_xdmf(r->q, j)))
        return QDC_OK;
    st = shared_fetch(r->q, j->id, H5JOB_FRAMES, NULL);
    if (st == QDC_OK && r->res_h5)
        st = shared_fetch(r->q, j->id, JOB_INPUT_H5, NULL);
    return st;
}

/* m saved as path in fmt (MESHIO_MED, MESHIO_XDMF: an XDMF+HDF5 job's .h5):
 * its frames written beside it, and qdc-h5, in a child process (h5job.h),
 * puts their coordinates into a copy of the upload (the .med; the .h5), or,
 * for a MED mesh that is no splice of an uploaded MED file (new tets, a job
 * uploaded in another format), makes a new MED file of qdc's writer's
 * frames. */
static meshio_format upload_mesh_format(const job_rec *j);

static qdc_status save_h5(req *r, const job_rec *j, const mesh_t *m, meshio_format fmt,
                          const char *path, qdc_error *e)
{
    char fr[4400];
    h5job_outcome ho;
    qdc_status st;

    snprintf(fr, sizeof fr, "%s.frames", path);
    st = meshio_save(fr, fmt, m, e);
    if (st != QDC_OK)
        return st;
    if (fmt == MESHIO_MED && upload_mesh_format(j) == MESHIO_MED &&
        meshio_source_format(m) == MESHIO_MED && meshio_splices(m, MESHIO_MED, NULL))
        h5job_run(r->q, j->id, fr, path, mono_now() + r->q->cfg.job_time_limit, NULL,
                  &ho);
    else if (fmt == MESHIO_MED)
        h5job_med_new(r->q, j->id, fr, path, mono_now() + r->q->cfg.job_time_limit, NULL,
                      &ho);
    else
        h5job_xdmf(r->q, j->id, fr, path, mono_now() + r->q->cfg.job_time_limit, NULL,
                   &ho);
    unlink(fr);
    return ho.status ? qdc_fail(e, QDC_EIO, "%s", ho.detail) : QDC_OK;
}

/* An XDMF+HDF5 job's .xdmf result, as path: the upload's XML naming
 * "result.h5" (the only change: the coordinates are in the .h5, the
 * result in ?format=h5). */
static qdc_status save_xdmf_xml(req *r, const job_rec *j, const char *path, qdc_error *e)
{
    char in[4400];
    size_t len = 0;
    char *xml;
    sbuf out = {0};
    qdc_status st;

    job_path(r->q, j->id, job_input_name(j->format), in, sizeof in);
    xml = file_read_all(in, &len);
    if (!xml)
        return qdc_fail(e, QDC_EIO, "cannot read %s", in);
    st = meshio_xdmf_h5_rename(xml, len, "result.h5", sb_writer, &out, e);
    free(xml);
    if (st == QDC_OK && out.oom)
        st = qdc_fail(e, QDC_ENOMEM, "out of memory");
    if (st == QDC_OK)
        st = meshio_save_bytes(path, out.buf, out.len, e);
    sb_free(&out);
    return st;
}

/* 409 / 410 for a job without a result (or, GET /input, an input mesh) to
 * give; 0 if it has one. */
static int not_servable(struct MHD_Connection *c, req *r, const job_rec *j,
                        enum MHD_Result *ret)
{
    char d[200], extra[1200], src[4300];
    int gone = j->purged || j->expires < wall_now();

    if (r->route == R_INPUT && !(job_state_done(j->state) && gone)) {
        input_source(r, j, src, sizeof src);
        if (shared_on(r->q) && !job_is_surface(j->format)) {
            (void)shared_fetch(r->q, j->id, job_input_name(j->format), NULL); /* or use */
            (void)fetch_frames(r, j);
        }
        if (access(src, R_OK) == 0)
            return 0;
        if (job_state_done(j->state)) { /* a surface TetGen could not mesh */
            snprintf(d, sizeof d, "job %s %s before its surface was tetrahedralized",
                     j->id, job_state_name(j->state));
            *ret = http_problem(c, r, 409, "no-result", "the job has no input mesh", d,
                                NULL, NULL);
            return 1;
        }
    }
    if (!job_state_done(j->state)) {
        static const char *const h[] = {MHD_HTTP_HEADER_RETRY_AFTER, "2", NULL};
        snprintf(d, sizeof d, "job %s is %s; poll /v1/jobs/%s/progress", j->id,
                 job_state_name(j->state), j->id);
        snprintf(extra, sizeof extra, "\"state\":\"%s\"", job_state_name(j->state));
        *ret = http_problem(c, r, 409, "not-ready", NULL, d, extra, h);
        return 1;
    }
    if (!job_has_result(j) && r->route != R_INPUT) {
        snprintf(d, sizeof d, "job %s %s and has no result", j->id,
                 job_state_name(j->state));
        snprintf(extra, sizeof extra, "\"state\":\"%s\"%s%s", job_state_name(j->state),
                 j->error[0] ? ",\"error\":" : "", j->error);
        *ret = http_problem(c, r, 409, "no-result", NULL, d, extra, NULL);
        return 1;
    }
    if (gone) {
        snprintf(d, sizeof d, "the %s of job %s expired and was deleted",
                 r->route == R_INPUT ? "input" : "result", j->id);
        snprintf(extra, sizeof extra, "\"expired\":%.3f", j->expires);
        *ret = http_problem(c, r, 410, "gone", NULL, d, extra, NULL);
        return 1;
    }
    return 0;
}

/* The mesh format of a job's upload; AUTO for a surface. */
static meshio_format upload_mesh_format(const job_rec *j)
{
    return job_is_surface(j->format) ? MESHIO_AUTO : meshio_format_from_name(j->format);
}

/* Whether a job uploaded in format own has its result and input served in
 * format k: every format qdc writes (those without a media type by ?format=
 * name: Gmsh 2.2 binary and 4.0, DOLFIN, Medit binary, Abaqus, MED...), and
 * one written only over its own source file (none today), for a job
 * uploaded in it. TetGen is two files. */
static int offerable(meshio_format k, meshio_format own)
{
    return k != MESHIO_TETGEN && (meshio_has_writer(k) || (k != MESHIO_AUTO && k == own));
}

/* The offered list for a 400/406 about the result's format. */
static void offered(sbuf *x)
{
    sb_puts(x, "\"offered\":[");
    media_list(x, 0);
    sb_puts(x, "],\"formats\":[");
    format_names(x, 0);
    sb_puts(x, "]");
}

/* The format of a result representation a GET asks for: ?format= (a name or a
 * media type), else the first entry of Accept that is offered (parameters
 * like ";encoding=binary" and ";version=2.2" pick variants; entries with q=0
 * are skipped, other q values ignored: the client's order decides), else the
 * binary. 0, or -1 with the 400/406 answered in *ret. */
static int result_format(struct MHD_Connection *c, req *r, const job_rec *j,
                         meshio_format *out, enum MHD_Result *ret)
{
    const char *f = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "format");
    const char *acc =
        MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_ACCEPT);
    meshio_format k = MESHIO_AUTO;
    sbuf x = {0};
    char d[300];

    r->res_h5 = 0;
    if (f && (!strcasecmp(f, "h5") || !strcasecmp(f, "application/x-hdf5")) &&
        r->route == R_RESULT && h5job_is_xdmf(r->q, j) && !job_changes_tets(j->options)) {
        /* an XDMF+HDF5 job's .h5 with the new coordinates */
        r->res_h5 = 1;
        *out = MESHIO_XDMF;
        return 0;
    }
    if (f) {
        if (!strcasecmp(f, "text/plain"))
            k = MESHIO_MEDIT;
        else
            k = strchr(f, '/') ? meshio_format_from_media_type(f)
                               : meshio_format_from_name(f);
        if (offerable(k, upload_mesh_format(j)) &&
            (r->route != R_RESULT || meshio_has_writer(k) ||
             !job_changes_tets(j->options))) {
            *out = k;
            return 0;
        }
        sb_puts(&x, "\"parameter\":\"format\",");
        offered(&x);
        snprintf(d, sizeof d,
                 "'format' must name one of the offered formats, not '%.60s'", f);
        *ret = http_problem(c, r, 400, "invalid-parameter", NULL, d, x.oom ? NULL : x.buf,
                            NULL);
        sb_free(&x);
        return -1;
    }
    if (!acc || !*acc) {
        *out = MESHIO_QMESH;
        return 0;
    }
    if (!parse_accept(acc, out))
        return 0;
    offered(&x);
    snprintf(d, sizeof d,
             "no offered type matches Accept: %.150s (or name one with ?format=)", acc);
    *ret = http_problem(c, r, 406, "not-acceptable", NULL, d, x.oom ? NULL : x.buf, NULL);
    sb_free(&x);
    return -1;
}

/* The file of the result in format f and its SHA-256 (the strong ETag) when
 * the file exists: the worker writes the binary, JSON and Medit results and
 * their hashes are in the row; other formats are written on first request
 * (process_convert) with the hash beside them in FILE.etag, and so is the
 * input mesh (GET /input) in every format, as input-as.FORMAT. */
static void result_file(req *r, const job_rec *j, meshio_format f, char *path, size_t cap,
                        char hex[65])
{
    char name[64], side[4400];
    const char *known = NULL;

    hex[0] = 0;
    switch (r->route == R_INPUT ? MESHIO_AUTO : f) {
    case MESHIO_QMESH:
        snprintf(name, sizeof name, "result.qmesh");
        known = j->etag_qmesh;
        break;
    case MESHIO_JSON:
        snprintf(name, sizeof name, "result.json");
        known = j->etag_json;
        break;
    case MESHIO_MEDIT:
        snprintf(name, sizeof name, "result.mesh");
        known = j->etag_medit;
        break;
    default:
        snprintf(name, sizeof name, "%s.%s", r->route == R_INPUT ? "input-as" : "result",
                 r->res_h5 ? "h5" : meshio_format_name(f));
        break;
    }
    job_path(r->q, j->id, name, path, cap);
    if (known) {
        snprintf(hex, 65, "%s", known);
        return;
    }
    snprintf(side, sizeof side, "%s.etag", path);
    size_t len = 0;
    char *b = file_read_all(side, &len);
    if (b && len == 64 && access(path, R_OK) == 0)
        snprintf(hex, 65, "%s", b);
    free(b);
}

/* What a result written by qdc's writer of f keeps, for its Qdc-Note:
 * vertices, tets, triangles and their region tags, and the upload's point
 * data (VTK, VTU, Gmsh arrays) when f's writer has it (after topology=full,
 * interpolated at the vertices the run inserted). */
static const char *kept_note(const job_rec *j, meshio_format f)
{
    if (!meshio_writes_pdata(f))
        return "only vertices, tets, triangles and their region tags are kept";
    return job_topology_full(j->options)
               ? "only vertices, tets, triangles, their region tags and the point "
                 "data are kept (topology=full: interpolated linearly at the "
                 "vertices the run inserted)"
               : "only vertices, tets, triangles, their region tags and the point "
                 "data are kept";
}

static enum MHD_Result serve_result(struct MHD_Connection *c, req *r, const job_rec *j,
                                    meshio_format f, const char *path, const char *hex)
{
    char etag[80], note[300] = "";
    meshio_format sf = upload_mesh_format(j);

    snprintf(etag, sizeof etag, "\"%s\"", hex);
    /* a result in another format than the upload's: say what it cannot hold
     * (the CLI says the same in a note line) */
    if (r->res_h5)
        ; /* the upload's .h5 with its coordinates replaced: nothing lost */
    else if (r->route == R_RESULT && sf != MESHIO_AUTO && sf != f)
        snprintf(note, sizeof note,
                 "written by qdc's %s writer, not the uploaded %s file with new "
                 "coordinates: %s",
                 meshio_format_name(f) ? meshio_format_name(f) : "?",
                 meshio_format_name(sf) ? meshio_format_name(sf) : "?", kept_note(j, f));
    /* the upload's own format, but the run changed the tets: not spliced */
    else if (r->route == R_RESULT && sf == f && sf != MESHIO_QMESH && sf != MESHIO_JSON &&
             job_changes_tets(j->options))
        snprintf(note, sizeof note,
                 "written by qdc's %s writer, not the uploaded file with new "
                 "coordinates (topology changed the tets): %s",
                 meshio_format_name(f) ? meshio_format_name(f) : "?", kept_note(j, f));
    const char *const h[] = {MHD_HTTP_HEADER_ETAG,
                             etag,
                             MHD_HTTP_HEADER_VARY,
                             "Accept",
                             MHD_HTTP_HEADER_CACHE_CONTROL,
                             "private, max-age=3600",
                             note[0] ? "Qdc-Note" : NULL,
                             note,
                             NULL};
    if (etag_matches(MHD_lookup_connection_value(c, MHD_HEADER_KIND,
                                                 MHD_HTTP_HEADER_IF_NONE_MATCH),
                     etag))
        return http_reply(c, r, 304, NULL, "", 0, h);
    return http_reply_file(c, r, 200, path,
                           r->res_h5              ? "application/x-hdf5"
                           : meshio_media_type(f) ? meshio_media_type(f)
                                                  : "application/octet-stream",
                           h);
}

/* Whether a result is written from the job's upload: a mesh upload (a
 * surface's result is TetGen's mesh, result.qmesh alone). */
static int from_upload(const req *r, const job_rec *j)
{
    return r->route == R_RESULT && !job_is_surface(j->format);
}

static int any_nonzero(const int32_t *a, int32_t n)
{
    for (int32_t i = 0; a && i < n; i++)
        if (a[i])
            return 1;
    return 0;
}

/* res (the result of a job whose topology mode changed the tets) given the
 * boundary triangles, their refs and the vertex refs of result.mesh, the
 * worker's Medit result, written from the same mesh: result.qmesh keeps
 * neither, and the upload's no longer hold when topology=full changed the
 * vertices or a bound let the flips change the boundary. QDC_EINTERNAL when
 * the two do not match. */
static qdc_status run_surface(req *r, const job_rec *j, mesh_t *res, qdc_error *e)
{
    char path[4300];
    mesh_t *md = NULL;
    qdc_status st;

    job_path(r->q, j->id, "result.mesh", path, sizeof path);
    st = meshio_load(path, MESHIO_MEDIT, &md, e);
    if (st == QDC_OK && (md->nv != res->nv || md->nt != res->nt))
        st = qdc_fail(e, QDC_EINTERNAL, "result.mesh does not match result.qmesh");
    if (st == QDC_OK) {
        int32_t *tris = res->tris, *ref = res->tri_ref, n = res->ntri;
        /* Medit always has refs: taken when some are not 0 (or res had them) */
        int refs = ref || any_nonzero(md->tri_ref, md->ntri);
        res->tris = md->tris;
        res->ntri = md->ntri;
        md->tris = tris;
        md->ntri = n;
        if (refs) {
            res->tri_ref = md->tri_ref;
            md->tri_ref = ref;
        } else {
            qdc_free(res->tri_ref);
            res->tri_ref = NULL;
        }
        if (res->vref || any_nonzero(md->vref, md->nv)) {
            int32_t *v = res->vref;
            res->vref = md->vref;
            md->vref = v;
        }
    }
    mesh_free(md);
    return st;
}

/* res (a topology=full result whose vertices changed) given the point data
 * of JOB_RESULT_PDATA, which the worker wrote when the upload had arrays (none
 * when it did not: res stays without). QDC_EINTERNAL when it does not match. */
static qdc_status run_pdata(req *r, const job_rec *j, mesh_t *res, qdc_error *e)
{
    char path[4300];
    mesh_t *pd = NULL;
    qdc_status st;

    job_path(r->q, j->id, JOB_RESULT_PDATA, path, sizeof path);
    if (access(path, R_OK) != 0)
        return QDC_OK;
    st = meshio_load(path, MESHIO_VTU, &pd, e);
    if (st == QDC_OK && pd->nv != res->nv)
        st = qdc_fail(e, QDC_EINTERNAL, "%s does not match result.qmesh",
                      JOB_RESULT_PDATA);
    if (st == QDC_OK) {
        mesh_pdata_free(res->pdata);
        res->pdata = pd->pdata;
        pd->pdata = NULL;
    }
    mesh_free(pd);
    return st;
}

/* The mesh to write for r (a job whose topology mode changed the tets: the
 * upload read without its source, with the result's coordinates, tets and
 * regions put in). The input: its file, read with its source kept
 * (the input in its own format is the upload itself). A result: the upload
 * with the result's coordinates put in, so that every format holds what the
 * CLI's output holds (the boundary triangles and their refs too, which
 * result.qmesh does not keep); asked in the upload's own format (its
 * variant: MSH 4.1 ASCII, VTU appended...), the upload is read with its
 * source kept and the library writes it back as the uploaded file with only
 * the coordinates replaced, the way `qdc optimize` writes OUT in IN's
 * format: tags, names, arrays and comments survive. */
static qdc_status convert_source(req *r, const job_rec *j, mesh_t **out, qdc_error *e)
{
    char src[4300];
    meshio_format sf = input_source(r, j, src, sizeof src);
    int tets = from_upload(r, j) && job_changes_tets(j->options);
    meshio_options keep = {
        .log = NULL, .log_ctx = NULL, .source = sf == r->res_fmt && !tets ? 1 : -1};
    mesh_t *res = NULL, *in = NULL;
    qdc_status st;

    *out = NULL;
    if (r->route == R_INPUT)
        return meshio_load(src, sf, out, e);
    if (from_upload(r, j)) {
        st = meshio_load_ex(src, sf, &keep, &in, e);
        if (st != QDC_OK)
            return st;
    }
    job_path(r->q, j->id, "result.qmesh", src, sizeof src);
    st = meshio_load(src, MESHIO_QMESH, &res, e);
    if (st == QDC_OK && in && tets && in->nv != res->nv) {
        /* topology=full inserted or contracted vertices: the upload's
         * numbering no longer holds; the result with the run's own boundary
         * triangles and vertex refs, and the point data as the run
         * interpolated them */
        mesh_free(in);
        in = NULL;
        st = run_pdata(r, j, res, e);
    }
    if (st == QDC_OK && in && (in->nv != res->nv || (!tets && in->nt != res->nt)))
        st = qdc_fail(e, QDC_EINTERNAL, "the result does not match its input");
    if (st == QDC_OK && in && tets) {
        /* the run's tets and their regions, the upload's boundary triangles
         * and vertex refs (kept as sets by the flips), qdc's own writer */
        mesh_swap_tets(in, res);
    }
    if (st == QDC_OK && in) {
        memcpy(in->xyz, res->xyz, 3 * sizeof(double) * (size_t)in->nv);
        mesh_free(res);
        res = in;
        in = NULL;
    }
    mesh_free(in);
    if (st == QDC_OK && tets)
        st = run_surface(r, j, res, e);
    if (st != QDC_OK) {
        mesh_free(res);
        res = NULL;
    }
    *out = res;
    return st;
}

/* Converter thread: write the result in r->res_fmt from result.qmesh (or the
 * input from its file), hash it, serve it. One thread, so two requests never
 * write the same file. */
/* What a conversion reads, from the store unless cached here: the result
 * (or the input), the upload it is written into, a MED job's frames.
 * QDC_EIO when the store could not be read. */
static qdc_status fetch_sources(req *r, const job_rec *j)
{
    if (shared_fetch(r->q, j->id,
                     r->route == R_INPUT ? job_input_name(j->format) : "result.qmesh",
                     NULL) == QDC_EIO ||
        (from_upload(r, j) &&
         shared_fetch(r->q, j->id, job_input_name(j->format), NULL) == QDC_EIO) ||
        (from_upload(r, j) && job_changes_tets(j->options) &&
         shared_fetch(r->q, j->id, "result.mesh", NULL) == QDC_EIO) ||
        (from_upload(r, j) && job_topology_full(j->options) &&
         meshio_writes_pdata(upload_mesh_format(j)) &&
         shared_fetch(r->q, j->id, JOB_RESULT_PDATA, NULL) == QDC_EIO))
        return QDC_EIO;
    return fetch_frames(r, j);
}

static enum MHD_Result process_convert(struct MHD_Connection *c, req *r)
{
    job_rec j;
    enum MHD_Result ret;
    char path[4300], side[4400], hex[65], d[400];
    mesh_t *m = NULL;
    qdc_error e;
    qdc_status st;

    if (!load_job(c, r, &j, &ret) || not_servable(c, r, &j, &ret))
        return ret;
    result_file(r, &j, r->res_fmt, path, sizeof path, hex);
    snprintf(side, sizeof side, "%s.etag", path);
    if (shared_on(r->q) && shared_use(r->q, path) != 0) {
        /* not in this node's cache: the stored file (the worker's formats,
         * or a conversion another node stored), with the same ETag */
        char sha[65] = "";
        qdc_status fs = shared_fetch(r->q, j.id, strrchr(path, '/') + 1, sha);
        if (fs == QDC_EIO)
            return store_unavailable(c, r, "the result could not be read");
        if (fs == QDC_OK && !hex[0] && strlen(sha) == 64 &&
            file_write_atomic(side, sha, 64) == 0)
            snprintf(hex, sizeof hex, "%s", sha);
        if (fs == QDC_OK && hex[0])
            return serve_result(c, r, &j, r->res_fmt, path, hex);
        hex[0] = 0;
        if (fetch_sources(r, &j) == QDC_EIO)
            return store_unavailable(c, r, "the result could not be read");
    }
    if (hex[0]) /* written for a request queued before this one */
        return serve_result(c, r, &j, r->res_fmt, path, hex);
    qdc_error_clear(&e);
    double t0 = mono_now();
    st = convert_source(r, &j, &m, &e);
    /* an XDMF+HDF5 job's .h5 (r->res_h5), or its .xdmf naming it */
    if (st == QDC_OK && (r->res_fmt == MESHIO_MED || r->res_h5))
        st = save_h5(r, &j, m, r->res_fmt, path, &e);
    else if (st == QDC_OK && r->res_fmt == MESHIO_XDMF && from_upload(r, &j) &&
             h5job_is_xdmf(r->q, &j) && !job_changes_tets(j.options))
        st = save_xdmf_xml(r, &j, path, &e);
    else if (st == QDC_OK)
        st = meshio_save(path, r->res_fmt, m, &e);
    mesh_free(m);
    if (st == QDC_OK && sha256_file_hex(path, hex))
        st = qdc_fail(&e, QDC_EIO, "cannot hash the result");
    if (st == QDC_OK && file_write_atomic(side, hex, 64))
        st = qdc_fail(&e, QDC_EIO, "cannot store the result's hash");
    if (st != QDC_OK) {
        int full = disk_full(errno) || strstr(e.msg, strerror(ENOSPC)) != NULL;
        /* Deleted or expired meanwhile: say that rather than an i/o error. */
        if (!load_job(c, r, &j, &ret) || not_servable(c, r, &j, &ret))
            return ret;
        unlink(path);
        snprintf(d, sizeof d, "the %s could not be written as %s",
                 r->route == R_INPUT ? "input" : "result",
                 meshio_format_name(r->res_fmt));
        /* the library's message names our files: it goes to the log, not out */
        if (r->q->cfg.verbose)
            fprintf(stderr, "qdcd: job %s: %s: %s\n", j.id, d, e.msg);
        if (full)
            return storage_full(c, r, d);
        return http_problem(c, r, 500, "io", NULL, d, NULL, NULL);
    }
    /* Deleted (or purged) while converting: the directory may have been
     * emptied before our file landed in it; remove what is left. */
    if (r->q->store->ops->get(r->q->store, j.id, &j) == QDC_EINVAL || j.purged) {
        job_path(r->q, j.id, NULL, d, sizeof d);
        dir_remove(d);
        if (!load_job(c, r, &j, &ret) || not_servable(c, r, &j, &ret))
            return ret;
    }
    if (r->q->cfg.verbose)
        fprintf(stderr, "qdcd: job %s: %s written as %s in %.3f s\n", j.id,
                r->route == R_INPUT ? "input" : "result", meshio_format_name(r->res_fmt),
                mono_now() - t0);
    /* the other nodes serve this conversion from the store (best effort:
     * converting again gives the same bytes) */
    if (shared_on(r->q))
        (void)shared_put(r->q, j.id, strrchr(path, '/') + 1, hex, NULL);
    return serve_result(c, r, &j, r->res_fmt, path, hex);
}

enum MHD_Result do_result(struct MHD_Connection *c, req *r)
{
    job_rec j;
    enum MHD_Result ret;
    meshio_format f;
    char path[4300], hex[65];

    if (r->off_done) /* resumed without a reply: queueing it failed */
        return MHD_NO;
    if (!load_job(c, r, &j, &ret))
        return ret;
    if (result_format(c, r, &j, &f, &ret))
        return ret;
    if (not_servable(c, r, &j, &ret))
        return ret;
    result_file(r, &j, f, path, sizeof path, hex);
    /* shared: a file missing from this node's cache is fetched off-thread */
    if (hex[0] && (!shared_on(r->q) || shared_use(r->q, path) == 0))
        return serve_result(c, r, &j, f, path, hex);
    r->res_fmt = f;
    return offq_push(&convert, c, r);
}

enum MHD_Result do_report(struct MHD_Connection *c, req *r)
{
    job_rec j;
    enum MHD_Result ret;
    char path[4300];

    if (!load_job(c, r, &j, &ret))
        return ret;
    if (not_servable(c, r, &j, &ret))
        return ret;
    job_path(r->q, j.id, "report.json", path, sizeof path);
    /* shared: from the store when this node's cache lacks it (a few kB) */
    if (shared_on(r->q) && shared_fetch(r->q, j.id, "report.json", NULL) == QDC_EIO)
        return store_unavailable(c, r, "the report could not be read");
    return http_reply_file(c, r, 200, path, "application/json", no_headers);
}
