/* report.h - mesh quality evaluation and the JSON report (docs/method.md §9).
 * Quality convention: signed mean ratio eta = 12 (3|V|)^(2/3) / sum l^2, negative
 * for tets against the mesh's majority orientation; dihedral angles in degrees.
 * Public (qdc.h). Thread-safe: no global state. */
#ifndef QDC_REPORT_H
#define QDC_REPORT_H

#include "core/base.h"
#include "core/mesh.h"
#include "geom/bderr.h"
#include "opt/opt.h"

#define REPORT_HIST_BINS 180

typedef struct {
    int32_t nv, nt;
    int32_t n_inverted;          /* against the majority orientation */
    int32_t n_degenerate;        /* not inverted but flat (core/tet.h) */
    double q_mean, q_std, q_min; /* signed mean ratio */
    double vl_mean, vl_min;      /* volume-length 6 sqrt2 V / l_rms^3, signed */
    double cn_mean, cn_max;  /* condition number ||S|| ||S^-1|| / 3 (>= 1), valid tets */
    double dih_min, dih_max; /* over all tets (an inverted tet counts 0 and 180) */
    int32_t n_dmin_lt[4];    /* tets with min dihedral < 5, 15, 30, 40 deg */
    int32_t n_dmax_gt[4];    /* tets with max dihedral > 175, 165, 150, 140 deg */
    int64_t hist[REPORT_HIST_BINS]; /* every dihedral angle of every tet, 1 deg bins */
    int32_t worst_tet;              /* the (first) tet of q_min, from 0 */
    double worst_centroid[3];       /* its centroid */
    double diag;                    /* bounding-box diagonal */
    /* The solid's angle at each boundary edge (two boundary triangles on it):
     * a tet on that edge has no larger dihedral angle there, so with the
     * surface kept it bounds the smallest dihedral any mesh can reach.
     * Measured when the boundary is known (report_quality_faces with faces),
     * else surf_angle_min -1 and n_surf_lt5 -1. */
    double surf_angle_min; /* degrees; 360 for no two-triangle edge */
    int32_t n_surf_lt5;    /* boundary edges with a solid angle under 5 deg */
} report_quality;

extern const int report_dmin_thresholds[4]; /* 5, 15, 30, 40 */
extern const int report_dmax_thresholds[4]; /* 175, 165, 150, 140 */

/* Measure every tet of m (only read) into *q: counts, mean ratio, volume-
 * length, condition number, dihedral angles and their histogram, each tet in
 * the vertex order of its component's orientation (mesh_orient). QDC_EMESH
 * (an empty mesh, a vertex index out of range), QDC_ENOMEM. */
qdc_status report_quality_compute(const mesh_t *m, report_quality *q, qdc_error *err);
/* The same with each tet's orientation from f (mesh_faces of m's tets, from
 * the run: opt_run_faces) instead of finding it again; f NULL:
 * report_quality_compute. QDC_EINVAL (f for another tet count), and the
 * statuses of report_quality_compute. */
qdc_status report_quality_faces(const mesh_t *m, const mesh_faces *f, report_quality *q,
                                qdc_error *err);

/* Everything the CLI and the daemon hand back about a run. Any pointer may be NULL
 * (that section is left out); all are the caller's, only read. */
typedef struct {
    const report_quality *before;
    const report_quality *after;
    const opt_result *run;
    const opt_options *options;
    const bderr_result *boundary;
} report_t;

/* Stream the report as one JSON object through fn(ctx, ...), reading only r
 * and what it points to. QDC_EIO when fn fails (the output is then cut). */
qdc_status report_write_json(const report_t *r, qdc_write_fn fn, void *ctx,
                             qdc_error *err);
/* JSON of one progress record p (one line, no newline), as the daemon streams
 * it, through fn(ctx, ...). QDC_EIO when fn fails. */
qdc_status report_progress_json(const opt_progress *p, qdc_write_fn fn, void *ctx);

/* qdc_write_fn that appends to a FILE* (ctx, the caller's, left open):
 * non-zero when fwrite writes less than len. */
int report_file_writer(void *ctx, const void *data, size_t len);

#endif
