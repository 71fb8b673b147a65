/* jobdir.c - the job directories, DATA/jobs/ID (jobdir.h): their paths, the
 * names of the files in them, and the scan every sweep of them uses. */
#define _GNU_SOURCE
#include "jobdir.h"
#include "jobopt.h"

#include <dirent.h>
#include <stdio.h>
#include <string.h>

void job_path(const qdcd *q, const char *id, const char *name, char *out, size_t cap)
{
    if (name)
        snprintf(out, cap, "%s/jobs/%s/%s", q->cfg.data, id, name);
    else
        snprintf(out, cap, "%s/jobs/%s", q->cfg.data, id);
}

const char *job_input_name(const char *format)
{
    static const char *const surf[] = {NULL,        "input.stl",  "input.off",
                                       "input.obj", "input.poly", "input.smesh"};
    meshio_format_info fi;
    surface_format sf = surface_format_from_name(format);

    if (meshio_format_info_of(meshio_format_from_name(format), &fi) && fi.input)
        return fi.input;
    if (sf > SURFACE_AUTO && (size_t)sf < sizeof surf / sizeof surf[0] && surf[sf])
        return surf[sf];
    return "input.mesh";
}

int job_is_surface(const char *format)
{
    return surface_format_from_name(format) != SURFACE_AUTO;
}

int job_intake_keeps(const mesh_t *m, meshio_format fmt)
{
    return fmt != MESHIO_QMESH && fmt != MESHIO_MEDIT && !m->vref && m->ntri == 0 &&
           !m->source;
}

int job_parses_upload(meshio_format fmt, const char *options)
{
    return meshio_writes_pdata(fmt) && job_topology_full(options);
}

int jobdir_each(qdcd *q, jobdir_fn fn, void *ctx)
{
    char p[sizeof q->cfg.data + 300];
    DIR *d;
    struct dirent *e;
    int n = 0;

    snprintf(p, sizeof p, "%s/jobs", q->cfg.data);
    d = opendir(p);
    if (!d)
        return 0;
    while ((e = readdir(d)) != NULL) {
        if (e->d_name[0] == '.' || strlen(e->d_name) != JOB_ID_LEN ||
            strspn(e->d_name, "0123456789abcdef") != JOB_ID_LEN)
            continue;
        snprintf(p, sizeof p, "%s/jobs/%.*s", q->cfg.data, JOB_ID_LEN, e->d_name);
        n += fn(q, e->d_name, p, ctx);
    }
    closedir(d);
    return n;
}
