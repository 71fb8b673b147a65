/* h5upload.c - uploads whose data is HDF5: a MED body, and an XDMF file with
 * its .h5 file sent together as multipart/form-data (curl -F, a browser's
 * FormData). qdcd checks what it reads itself (the parts, the XML's
 * references to one .h5 file, the HDF5 signature) and never opens HDF5: the
 * worker's qdc-h5 child reads it (h5job.h). */
#include "h5upload.h"

#include "h5job.h"
#include "multipart.h"
#include "util.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

int h5up_check(const char *buf, size_t len, meshio_format f, job_rec *j, qdc_status *st,
               qdc_error *e)
{
    meshio_xdmf_h5 refs;

    *st = QDC_OK;
    if (f == MESHIO_MED) {
        if (!meshio_is_hdf5(buf, len)) {
            *st = qdc_fail(e, QDC_EPARSE, "MED: not an HDF5 file");
            return 1;
        }
        j->nv = j->nt = 0; /* known once qdc-h5 read it */
        snprintf(j->notes, sizeof j->notes,
                 "MED (HDF5): read by qdc-h5 in a child process before the optimization");
        return 1;
    }
    if (f != MESHIO_XDMF)
        return 0;
    if (meshio_xdmf_h5_refs(buf, len, &refs, e) == QDC_OK && refs.n) {
        *st =
            qdc_fail(e, QDC_EFORMAT,
                     "XDMF with its heavy data in %.200s (HDF5): send the .xdmf and the "
                     ".h5 file together as multipart/form-data (curl -F "
                     "xdmf=@mesh.xdmf -F h5=@mesh.h5), or `qdc submit mesh.xdmf`",
                     refs.file);
        return 1;
    }
    qdc_error_clear(e);
    return 0;
}

int h5up_form(const char *ct, const char *fq, char *boundary, char *why, size_t cap)
{
    if (!ct || strncasecmp(ct, "multipart/form-data", 19))
        return 0;
    if (mp_boundary(ct, boundary)) {
        snprintf(why, cap, "multipart/form-data without a valid boundary");
        return -1;
    }
    if (fq && meshio_format_from_name(fq) != MESHIO_XDMF) {
        snprintf(
            why, cap,
            "multipart/form-data is taken for XDMF and its .h5 file, not format '%.60s'",
            fq);
        return -1;
    }
    return 1;
}

/* The role of part p of a multipart upload: 'x' the XDMF file, 'h' its .h5,
 * by its name ("xdmf", "h5") or else its file name's extension; 0 neither. */
static char part_role(const mp_part *p)
{
    const char *dot = strrchr(p->filename, '.');

    if (!strcmp(p->name, "xdmf"))
        return 'x';
    if (!strcmp(p->name, "h5"))
        return 'h';
    if (dot && (!strcasecmp(dot, ".xdmf") || !strcasecmp(dot, ".xmf")))
        return 'x';
    if (dot && (!strcasecmp(dot, ".h5") || !strcasecmp(dot, ".hdf5")))
        return 'h';
    return 0;
}

/* The XDMF part *x and the .h5 part *h of the n parts p, or why not. */
static void pick_parts(const mp_part *p, int n, const mp_part **x, const mp_part **h,
                       char *why, size_t cap)
{
    for (int k = 0; k < n && !why[0]; k++) {
        char role = part_role(&p[k]);
        const mp_part **slot = role == 'x' ? x : h;
        if (!role)
            snprintf(why, cap,
                     "part '%.60s' (file '%.100s') is neither the XDMF file (name "
                     "\"xdmf\") nor its .h5 file (name \"h5\")",
                     p[k].name, p[k].filename);
        else if (*slot)
            snprintf(why, cap, "two %s parts ('%.60s' and '%.60s')",
                     role == 'x' ? "XDMF" : ".h5", (*slot)->name, p[k].name);
        else
            *slot = &p[k];
    }
    if (!why[0] && !*x)
        snprintf(why, cap, "no XDMF part (send it as -F xdmf=@mesh.xdmf)");
    else if (!why[0] && !*h)
        snprintf(why, cap, "no .h5 part (send it as -F h5=@mesh.h5)");
}

/* The XDMF part (xml, xlen) read as far as its references (*refs), and the
 * .h5 part's signature, or why they are not an XDMF+HDF5 pair. */
static void check_pair(const char *xml, size_t xlen, const char *h5, size_t hlen,
                       const char *hname, const char *xname, meshio_xdmf_h5 *refs,
                       char *why, size_t cap, qdc_error *e)
{
    int geom = 0;

    if (meshio_sniff(xml, xlen) != MESHIO_XDMF) {
        snprintf(why, cap, "part '%.60s' is not an XDMF file", xname);
        return;
    }
    if (meshio_xdmf_h5_refs(xml, xlen, refs, e) != QDC_OK) {
        snprintf(why, cap, "%s", e->msg);
        return;
    }
    if (refs->n == 0) {
        snprintf(
            why, cap,
            "the XDMF file holds its data inline: upload it alone, without a .h5 file");
        return;
    }
    for (int k = 0; k < refs->n; k++)
        geom |= !strcmp(refs->set[k].name, "geometry");
    if (!geom)
        snprintf(why, cap,
                 "XDMF: the Geometry inline, the rest of the mesh in HDF5: not read (qdc "
                 "writes the coordinates back into the .h5 file)");
    else if (!meshio_is_hdf5(h5, hlen))
        snprintf(why, cap, "part '%.60s' is not an HDF5 file", hname);
}

qdc_status h5up_multipart(const char *buf, size_t len, const char *boundary,
                          const char *tmp, char *xtmp, char *htmp, size_t cap, job_rec *j,
                          char *why, size_t whycap, int *nparts, qdc_error *e)
{
    mp_part p[4];
    const mp_part *x = NULL, *h = NULL;
    meshio_xdmf_h5 refs;
    sbuf xml = {0};

    why[0] = 0;
    *nparts = 0;
    if (mp_parse(buf, len, boundary, p, 4, nparts, why, whycap) == 0)
        pick_parts(p, *nparts, &x, &h, why, whycap);
    if (!why[0])
        check_pair(buf + x->off, x->len, buf + h->off, h->len, h->name, x->name, &refs,
                   why, whycap, e);
    if (why[0])
        return QDC_EPARSE;
    /* the XML naming the job's copy of the .h5, and that copy */
    snprintf(xtmp, cap, "%s.xdmf", tmp);
    snprintf(htmp, cap, "%s.h5", tmp);
    qdc_status st =
        meshio_xdmf_h5_rename(buf + x->off, x->len, JOB_INPUT_H5, sb_writer, &xml, e);
    if (st == QDC_OK && xml.oom)
        st = qdc_fail(e, QDC_ENOMEM, "out of memory");
    if (st == QDC_OK)
        st = meshio_save_bytes(xtmp, xml.buf, xml.len, e);
    if (st == QDC_OK)
        st = meshio_save_bytes(htmp, buf + h->off, h->len, e);
    sb_free(&xml);
    if (st != QDC_OK)
        return st;
    j->nv = j->nt = 0; /* known once qdc-h5 read it */
    j->input_h5 = 1;
    snprintf(
        j->notes, sizeof j->notes,
        "XDMF with its heavy data in HDF5 (%.200s): read by qdc-h5 in a child process "
        "before the optimization",
        refs.file);
    return QDC_OK;
}

int h5up_commit(char *xtmp, char *htmp, const char *dir, const char *path, const char *h5)
{
    if (dir_ensure(dir) || rename(xtmp, path) || (xtmp[0] = 0, 0) || rename(htmp, h5) ||
        (htmp[0] = 0, fsync_parent(path)) || fsync_parent(dir)) {
        int e = errno ? errno : EIO;
        dir_remove(dir);
        return e;
    }
    return 0;
}
