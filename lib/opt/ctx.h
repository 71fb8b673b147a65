/* ctx.h - the state of one optimizer run (ctx_t: normalized coordinates,
 * the system's weights, the solver, the best iterate) and what every phase
 * does with it: quality scans, the best-iterate rule (docs/method.md §5),
 * progress records, the stop tests. Internal to lib/opt: the phases (global.c,
 * finishing.c, hold.c), the run (opt.c) and the reruns (rerun.c) share it. */
#ifndef QDC_CTX_H
#define QDC_CTX_H

#include "core/mesh_int.h"
#include "opt/encode.h"
#include "opt/opt.h"
#include "opt/slide.h"
#include "opt/solve.h"

typedef struct {
    const opt_options *o;
    const mesh_topo *tp;
    int32_t nv, nt;
    double center[3], scale; /* x = (X - center) / scale */
    double lbar, eps;
    double *x, *x0, *xn, *xbest, *trial, *tmp, *rhs;
    uint8_t *locked;       /* not an unknown of the linear system */
    double *vfac;          /* nv: share of the step each vertex takes (feasible step) */
    double hbound;         /* --hausd in normalized units (0: none) */
    int autob;             /* the default bound (--hausd auto under slide) */
    int rerun_stuck;       /* tets left inverted get a rerun (run_once's stuck): no angle
                            * pass on such a result, the rerun's own does it */
    int keep_surface;      /* the finishing pass folds no tet at the surface (finish.h) */
    const int32_t *region; /* the mesh's region tags (NULL: none), for local.c */
    int hold_flat; /* local.c's regions hold the vertices sliding on a plane or a line
                    * (but the corners of the unusable tets): a region classifies its
                    * surface where it starts, where a fold looks like an edge */
    /* Optimizes a mesh of its own (local.c's regions, in normalized units):
     * set by opt_run_once on the runs it makes for its callers, NULL on the
     * regions' own runs (so a region is not repaired inside itself).
     * loose (m->nv flags, may be NULL): boundary vertices that leave their
     * surface within the bound (run_once's loose). */
    qdc_status (*repair)(mesh_t *m, const opt_options *o, int keep_surface,
                         const uint8_t *loose, opt_result *r, qdc_error *err);
    uint8_t *vmark; /* nv: scratch marks */
    int32_t *vlist; /* nv: scratch list of vertices */
    double *wq2;    /* squared QDC row weights */
    double *bw2;    /* squared boundary row weights (0: no row) */
    double *dg;     /* bw2 + mu */
    double *qt, *qval, *d;
    uint8_t *fslot; /* encode_face_slots (NULL: searched) */
    double *eta; /* nt: mean ratio per tet at the x of the last evaluate() that asked */
    double eta_delta; /* and the delta of that x */
    /* ctx_evaluate_x's pass for the objective at x, eta_delta (when it took
     * one): q~ per tet in qt, its sum and what encode_objective_scan found */
    int xscan_ok;
    double xscan_f;
    encode_scan xscan;
    double mu_factor;   /* omega_B^2 once harmonic guidance is on and mu_scaled */
    const double *bref; /* targets of the boundary rows: x0 (lsq) or x_k (slide) */
    slide_ctx *sl;      /* slide mode only */
    solve_ctx *sol;
    double t0;
    double t_check, t_unit; /* the last ctx_should_stop, the time since the one before */
    opt_progress input, best;
    int best_it;
    int last_record; /* number of the last progress record */
} ctx_t;

/* The run's log callback (if any) with a printf-style message. */
void ctx_log(const ctx_t *c, int level, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* The context of a run of o on m with topology tp (clears c first). */
qdc_status ctx_init(ctx_t *c, const mesh_t *m, const mesh_topo *tp, const opt_options *o);
void ctx_free(ctx_t *c);

/* The quality record of x into r, each tet's mean ratio into eta_out (may be
 * NULL); returns the delta of x. */
double ctx_evaluate(const ctx_t *c, const double *x, opt_progress *r, double *eta_out);
/* ctx_evaluate of c->x into r and c->eta, its delta into c->eta_delta; where
 * the objective takes a pass of its own (delta > 0, or micn), that pass also
 * leaves q~ per tet in c->qt and c->xscan* (c->xscan_ok): what the next
 * global iteration starts from at this x. */
void ctx_evaluate_x(ctx_t *c, opt_progress *r);
/* Each tet's mean ratio into eta and the fields of r the best-iterate rule
 * reads; returns the delta of x. */
double ctx_scan_light(const ctx_t *c, const double *x, double *eta, opt_progress *r);

/* Whether record a is a better iterate than b (docs/method.md §5). */
int ctx_better(const opt_progress *a, const opt_progress *b);
/* Whether r may become the best iterate at all (no worse than the input). */
int ctx_eligible(const ctx_t *c, const opt_progress *r);
/* x with record r becomes the best iterate if eligible and better. */
void ctx_consider(ctx_t *c, const double *x, const opt_progress *r);
/* Send r to the progress callback; nonzero: the caller asked to stop. */
int ctx_report(ctx_t *c, opt_progress *r);
/* What a time limit (0: none, which stays 0) leaves after `spent` seconds: at
 * least a millisecond (whether to start at all is the caller's decision). */
double ctx_time_left(double limit, double spent);
/* The reason the run stops (its name into res->stop_reason). */
void ctx_set_stop(opt_result *res, opt_stop s);
/* Cancelled or out of time: sets the reason, returns 1. Out of time also when
 * the work since the last call, done once more, would end past the limit:
 * each loop calls it once a unit of work (an iteration, a sweep), and a
 * 1M-tet iteration is 0.7 s, which the limit was overrun by. */
int ctx_should_stop(ctx_t *c, opt_result *res);
/* The record of a finishing or angle pass, whose result is in c->trial:
 * copied to c->x, evaluated, numbered *next (then incremented). */
void ctx_pass_record(ctx_t *c, opt_progress *r, int *next, const char *phase);

/* The cube of tet tt's mean ratio at y (signed). */
double ctx_tet_eta3(const double *y, const int32_t *tt);
/* Mark tt's corners in c->vmark (safe in a parallel loop). */
void ctx_mark_corners(ctx_t *c, const int32_t *tt);

#endif
