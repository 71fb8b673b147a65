/* opt.h - the QDC optimizer (paper Sec. 4-6, docs/method.md §4-§6, §8): moves vertices,
 * never changes connectivity; public (qdc.h; the option words' parsers are
 * in opt_int.h, the passes in the other headers of opt/).
 * Thread-safe: all state lives in the call. */
#ifndef QDC_OPT_H
#define QDC_OPT_H

#include "core/base.h"

#include "core/mesh.h"
#include "geom/metric.h" /* opt_metric */
#include <stdatomic.h>

typedef enum {
    OPT_BOUNDARY_LSQ = 0,
    OPT_BOUNDARY_FIXED,
    OPT_BOUNDARY_SLIDE
} opt_boundary;
typedef enum { OPT_MODE_SAFE = 0, OPT_MODE_LITERAL } opt_mode;
typedef enum { OPT_WEIGHTS_OPTAVG = 0, OPT_WEIGHTS_PAPER } opt_weights;
typedef enum { OPT_SOLVER_AUTO = 0, OPT_SOLVER_CHOLMOD, OPT_SOLVER_PCG } opt_solver;
/* --topology: none keeps the connectivity (every vertex and tet as given); flips
 * alternates the smoother with flips that keep the vertex set, the boundary
 * triangles and the region tags (opt/topology.c); full adds interior vertex
 * insertion (new vertices inside the volume, never on the boundary). */
typedef enum {
    OPT_TOPOLOGY_NONE = 0,
    OPT_TOPOLOGY_FLIPS,
    OPT_TOPOLOGY_FULL
} opt_topology;

/* Why a run stopped. */
typedef enum {
    OPT_STOP_MAX_ITER = 0,
    OPT_STOP_CONVERGED,
    OPT_STOP_NO_DESCENT,
    OPT_STOP_CANCELLED,
    OPT_STOP_TIME_LIMIT,
    OPT_STOP_SOLVER
} opt_stop;

/* Outcome of a run (docs/style.md §3). */
typedef enum {
    OPT_CONVERGED = 0, /* stopping rule met */
    OPT_STOPPED,       /* budget, cancel or solver trouble: best valid mesh returned */
    OPT_FAILED         /* input left untouched */
} opt_outcome;

/* One record per global iteration (and one for the input, one per finishing sweep). */
typedef struct {
    int iteration;     /* 0 = the input; 1.. global iterations, then finish sweeps */
    const char *phase; /* "input", "pre", "global", "finish" */
    double objective;  /* sum of the modified inverse quality */
    double step;       /* global: line-search step taken (1 = full), 0 if rejected;
                        * finish/angles: accepted moves per visited vertex */
    double q_mean, q_std, q_min; /* signed mean ratio */
    double dih_min, dih_max;     /* degrees, over non-inverted tets */
    int32_t n_inverted;          /* tets inverted or degenerate (core/tet.h geom_tet_bad):
                                  * the count every rule of the run compares */
    int32_t n_degenerate;        /* of those, the degenerate (flat) ones */
    int32_t n_folded; /* global: tets valid before this step and inverted after it */
    double max_move;  /* largest vertex move this iteration, in mean edge lengths */
    double elapsed;   /* seconds since opt_run started */
    int solver;       /* opt_solver actually used */
    int cg_iters;     /* PCG iterations (0 for CHOLMOD) */
    /* phase "topology" only (not set in the other records): */
    int32_t n_tets;     /* tets after the round of flips */
    int64_t operations; /* flips the round made (edge removals, 2-3, multi-face) */
} opt_progress;

/* Called after each record, on opt_run's thread; p is valid only during the
 * call. Return non-zero to cancel (the run then stops with OPT_STOPPED and
 * the best mesh so far). */
typedef int (*opt_progress_fn)(void *ctx, const opt_progress *p);

typedef struct {
    opt_metric metric;     /* default MIVL */
    opt_boundary boundary; /* default SLIDE (the shape is kept) */
    opt_mode mode; /* default SAFE; LITERAL = paper as written (Eq. 6, mu = ||G^T g||^2,
                      no line search) */
    opt_weights weights; /* default OPTAVG (docs/method.md §4) */
    opt_solver solver;   /* default AUTO (chosen from the CHOLMOD analysis) */
    int harmonic;        /* harmonic guidance (docs/method.md §6), default 0 */
    int pre_iters;       /* iterations before the harmonic field, default 3 */
    int finish;          /* worst-tet finishing pass (docs/method.md §5a), default 1 */
    int max_iter;        /* global iterations, default 10 */
    int ls_halvings;     /* line search tries 1 .. 2^-ls_halvings, default 10 */
    double mu;           /* semi-implicit damping in normalized units, default 1 */
    int mu_scaled; /* with harmonic guidance, multiply mu by omega_B^2 (docs/method.md §5
                    * open question), default 0 */
    double tol_move;      /* stop when max move < tol_move * mean edge, default 1e-3 */
    double stall;         /* stop the global phase when an iteration (the 3rd or later, on
                           * a valid iterate) raises the mean ratio by less, or the next
                           * one is predicted to; default 2e-3, 0 = never
                           * (docs/defaults.md) */
    double eps_rel;       /* Escobar epsilon relative to a regular tet, default 1e-3 */
    double finish_frac;   /* fraction of worst tets in the finishing pass, default 1 */
    int finish_sweeps;    /* broad sweeps at most, default 32 */
    double finish_gain;   /* ... ending when one raises the mean by less, default 5e-4 */
    int angle_polish;     /* after the finishing pass: max-min of the dihedral sines
                           * on the worst tets' vertices (finish.h), default 1 */
    double feature_angle; /* degrees, for slide, default 30 */
    double hausd;         /* > 0: bound on the Hausdorff distance between the input and
                           * output boundary surfaces, in the mesh's units (lsq and
                           * slide; boundary vertices stay within it of where they
                           * were, or slide on a planar patch or a straight edge);
                           * 0 = none or hausd_rel */
    double hausd_rel;     /* the same relative to the bounding-box diagonal, used when
                           * hausd is 0; 0 = none; OPT_HAUSD_AUTO (default): with
                           * slide, the bound OPT_HAUSD_DEFAULT; else none */
    opt_topology topology; /* default NONE */
    int stall_early;       /* the stall test from the 2nd iteration on, not the 3rd (a
                            * --topology round's held smoothing, topology.c); default 0 */
    int free_fins;         /* under a bound, the corners of tets with three boundary faces
                            * move free within it (the smoothing of --topology, opt.c
                            * free_fins); default 0 */
    double time_limit;     /* seconds, 0 = none: then OPT_STOPPED with the best mesh */
    int threads;           /* OpenMP threads for this run; 0 = all cores. A server running
                            * several jobs at once should give each 1 (no oversubscription) */
    const atomic_int
        *cancel; /* if non-NULL and *cancel != 0: stop (checked every
                  * iteration; set from another thread or a signal handler) */
    opt_progress_fn progress;
    void *progress_ctx;
    qdc_log_fn log;
    void *log_ctx;
} opt_options;

/* Fill *o with the defaults (docs/defaults.md; each field's comment above says
 * its default): no callbacks, no cancel flag, all cores. */
void opt_defaults(opt_options *o);

#define OPT_HAUSD_AUTO (-1.0)
#define OPT_HAUSD_DEFAULT 3e-3 /* of the diagonal (docs/defaults.md) */
/* ... and of the vertices the default frees where tets stay inverted */
#define OPT_HAUSD_STUCK 1e-2

/* The word of the solver a run used (opt_result.solver): "auto", "cholmod",
 * "pcg"; a static string, "?" when out of range. */
const char *opt_solver_name(opt_solver s);
const char *opt_topology_name(opt_topology t);

typedef struct {
    opt_outcome outcome;
    int iterations;      /* global iterations done, over all the runs (reruns, rounds) */
    int best_iteration;  /* the progress record of the returned mesh (0 = input) */
    int last_record;     /* number of the last progress record: the run's iterations
                          * as the report, qdc and qdcd count them (docs/defaults.md,
                          * "One iteration count") */
    opt_solver solver;   /* solver used */
    double solver_flops; /* CHOLMOD analysis estimate (0 if not analysed) */
    double t_setup, t_weights, t_assembly, t_solve, t_linesearch, t_harmonic, t_finish,
        t_total;
    opt_progress before; /* the input's record */
    opt_progress after;  /* the returned mesh's record */
    opt_progress
        before_finish; /* record after the global iterations, before the finishing pass */
    int32_t max_inverted_global; /* largest inverted count of a global iterate (0 on a
                                  * valid input: the global step folds nothing) */
    int32_t folded_global;       /* valid tets the global steps inverted, summed */
    double hausd_bound;          /* the boundary bound applied, mesh units (0: none) */
    int32_t held_back;           /* vertices put back to their input positions so that no
                                  * tet ends below the valid input's worst (opt_run) */
    int32_t tets_in, tets_out;   /* tets of the input and of the result (set with
                                  * --topology; 0 otherwise) */
    int64_t topo_edge_removals;  /* --topology: edges removed (3-2, 4-4, 5-6 ... flips) */
    int64_t topo_by_ring[11];    /* of which with a ring of n tets (n = 3..10) */
    int64_t topo_flips23;        /* 2-3 face flips */
    int64_t topo_multiface;      /* multi-face removals */
    int64_t topo_insertions;     /* --topology full: interior vertices inserted */
    int64_t topo_contractions;   /* --topology full: interior edges contracted */
    int64_t topo_bflips;         /* --topology with --hausd: boundary edge flips */
    int64_t topo_peels;          /* ... and flat tets peeled off the boundary */
    int64_t topo_bcontractions;  /* ... and boundary edges contracted (--topology full;
                                  * counted in topo_contractions too) */
    int32_t topo_tris_removed;   /* ... boundary triangles of the input removed */
    int32_t topo_tris_added;     /* ... and new boundary triangles written */
    int32_t verts_in, verts_out; /* --topology: vertices before and after */
    int topo_rounds;             /* rounds of flips followed by smoothing */
    /* second-order tets (mesh_t.mid, opt/p2.c); all 0 for linear tets: */
    int32_t p2_tets;          /* 10-node tets */
    int32_t p2_mid;           /* mid-edge nodes */
    int32_t p2_mid_moved;     /* of those, moved with their edge */
    int32_t p2_boundary_mid;  /* of those, on the boundary (on the curved surface) */
    int32_t p2_pulled;        /* moved toward the straight midpoint (Jacobian) */
    int32_t p2_bad_in;        /* elements with a Jacobian <= 0 at a node or the */
    int32_t p2_bad_out;       /*   centroid, in the input and the result */
    double p2_jac_min_in;     /* smallest scaled Jacobian (1 = straight), in the */
    double p2_jac_min_out;    /*   input and the result */
    double p2_bd_mid_dist;    /* largest distance of a boundary mid-edge node to the
                               * input's curved boundary (its quadratic triangles) */
    double p2_bd_corner_dist; /* the same, of the boundary corners */
    opt_stop stop;            /* why the run stopped (decides; stop_reason names it) */
    char stop_reason[64]; /* opt_stop_name(stop): "converged", "max-iter", "no-descent",
                           * "cancelled", "time-limit", "solver" */
} opt_result;

/* Optimize m in place (coordinates only; tets, regions, fixed flags untouched;
 * with o->topology FLIPS, m->tets, m->region and m->nt are replaced by the
 * improved connectivity, vertices and boundary triangles kept: opt/topology.c).
 * o may be NULL (opt_defaults); it is only read, and its callbacks are called
 * on the calling thread. res (may be NULL) receives the outcome, timings and
 * the first and last progress records. m stays the caller's: the run keeps
 * no pointer to it, o or res after it returns.
 * On OPT_FAILED (and on any status other than QDC_OK) m is unchanged.
 * During the run m->tets and m->region are lent to the run's renumbered copy
 * (NULL meanwhile: m must not be read from another thread); they come back
 * with the same contents, possibly at other addresses.
 * The returned mesh never has more inverted or degenerate tets (core/tet.h)
 * nor a lower minimum mean ratio than the input, nor, on a valid input, a lower
 * mean ratio. The BLAS's thread count changes CHOLMOD's rounding, hence
 * the bytes of the result (qdc and qdcd run with OPENBLAS_NUM_THREADS=1).
 * QDC_EMESH (m fails mesh_validate or cannot be oriented), QDC_EINVAL (an
 * option out of range), QDC_ENOMEM, QDC_ESOLVE. */
qdc_status opt_run(mesh_t *m, const opt_options *o, opt_result *res, qdc_error *err);
/* opt_run, and in *faces (not NULL) m's faces as the run found them
 * (mesh_faces: each tet's orientation and the boundary, in m's numbering),
 * for the report of the input and of the result (report_quality_faces,
 * bderr_meshes_faces), so that it does not find them again. *faces is the
 * caller's (mesh_faces_free); NULL when the run changed the tets (o->topology
 * not NONE), on second-order tets, or on failure. */
qdc_status opt_run_faces(mesh_t *m, const opt_options *o, opt_result *res,
                         mesh_faces **faces, qdc_error *err);

#endif
