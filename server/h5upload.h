/* h5upload.h - uploads whose data is HDF5 (MED; XDMF with its .h5 file as
 * multipart/form-data), checked as far as qdcd reads them: the worker's
 * qdc-h5 child reads the HDF5 (h5job.h). Called by upload.c. */
#ifndef QDCD_H5UPLOAD_H
#define QDCD_H5UPLOAD_H

#include "qdc.h"
#include "store.h"

#include <stddef.h>

/* A body (buf, len) of format f: 1 when this settles it (a MED body taken,
 * j's sizes and notes set, *st QDC_OK; or a MED or XDMF body refused, *st
 * and *e say why: an XDMF whose heavy data is in HDF5 sent alone), 0 when
 * it is to be read as any mesh (inline XDMF, every other format). */
int h5up_check(const char *buf, size_t len, meshio_format f, job_rec *j, qdc_status *st,
               qdc_error *e);

/* The Content-Type ct of an upload (fq: its ?format=, or NULL): 1 when it is
 * multipart/form-data for XDMF and its .h5 (the boundary, MP_BOUNDARY_MAX + 1
 * bytes, in boundary), -1 when such a form is refused (why), 0 when it is
 * not multipart/form-data. */
int h5up_form(const char *ct, const char *fq, char *boundary, char *why, size_t cap);

/* A multipart/form-data body (buf, len) with boundary: an XDMF file whose
 * heavy data is in HDF5 and that .h5 file, each a part (by its name "xdmf",
 * "h5", or its file name's extension). Refused with why (a 400's detail) and
 * *nparts set when a part is missing, doubled or not what it says; else the
 * XML naming JOB_INPUT_H5 is written to xtmp and the .h5 to htmp (each of cap
 * bytes, made from tmp), and j's notes set. why[0] is 0 unless refused;
 * QDC_EIO: a file could not be written. */
qdc_status h5up_multipart(const char *buf, size_t len, const char *boundary,
                          const char *tmp, char *xtmp, char *htmp, size_t cap, job_rec *j,
                          char *why, size_t whycap, int *nparts, qdc_error *e);

/* The files a multipart upload was cut into (xtmp, htmp: already synced,
 * each name cleared once moved) moved to path and h5 in the job's directory
 * dir, which is removed if one fails: 0, or the errno of what failed. */
int h5up_commit(char *xtmp, char *htmp, const char *dir, const char *path,
                const char *h5);

#endif
