/* run.h - one optimization run (opt.c), for the rerun policy (rerun.c); the
 * run with its reruns (rerun.c) and the rounds of --topology (topology.c),
 * for opt_run (entry.c). */
#ifndef QDC_RUN_H
#define QDC_RUN_H

#include "core/mesh_int.h"
#include "opt/opt.h"

/* One optimization of m (opts NULL: the defaults) on m's topology tp (built
 * once for a run and its reruns; NULL: the run builds its own). pins (nv flags, may be
 * NULL): extra vertices that keep their input position; loose (may be NULL):
 * sliding vertices that move freely (SLIDE_LOOSE, or SLIDE_LOOSE_UNBOUNDED:
 * slide_release). In slide mode *squashed (if not NULL)
 * receives the corners of the ears this run squashed, and *stuck (if not
 * NULL) the boundary vertices around tets left inverted (hold.h); else NULL.
 * keep_surface: the finishing sweeps fold no tet at the surface (finish.h). */
qdc_status opt_run_once(mesh_t *m, const opt_options *opts, const mesh_topo *tp,
                        const uint8_t *pins, const uint8_t *loose, uint8_t **squashed,
                        uint8_t **stuck, int keep_surface, opt_result *res_out,
                        qdc_error *err);

/* opt_run with the connectivity kept (o->topology ignored): what opt_run does
 * for --topology none, and the smoothing of each round of --topology flips. */
qdc_status opt_run_smooth(mesh_t *m, const opt_options *opts, opt_result *res,
                          qdc_error *err);
/* opt_run_smooth for a round of --topology after the first: no rerun with a
 * wider regularization (rerun.c), which the first run had; the round starts
 * from the mesh its flips left, whose inverted tets that run could not open
 * (on a two-region box whose interface a tangle had pushed through, with the
 * boundary fixed, the reruns in every round took the run from 2.6 to 9 s and
 * left the same tets). */
qdc_status opt_run_smooth_round(mesh_t *m, const opt_options *opts, opt_result *res,
                                qdc_error *err);
/* opt_run_smooth handing out the run's faces (opt_run_faces); *faces NULL
 * on failure. */
qdc_status opt_run_smooth_faces(mesh_t *m, const opt_options *opts, opt_result *res,
                                mesh_faces **faces, qdc_error *err);

/* --topology flips or full on m as numbered (topology.c): the first
 * smoothing, the rounds of flips, each followed by smoothing, and full's
 * round (opt_run gives it m numbered along a space-filling curve). */
qdc_status opt_topology_rounds(mesh_t *m, const opt_options *opts, opt_result *res,
                               qdc_error *err);

#endif
