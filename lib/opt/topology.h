/* topology.h - --topology flips: the QDC smoother alternated with the flips of
 * lib/topo (edge removal and 2-3 flips), after Stellar's schedule (Klingner and
 * Shewchuk 2007): smooth; then flips, worst tets first; then smooth again where
 * the flips opened room, a few rounds while the quality rises. The vertex set
 * never changes (point data stays valid); boundary triangles and region tags
 * come back as sets exactly as they went in; new tets are written in the vertex
 * order convention of the tets they replace. Thread-safe: state lives in the call. */
#ifndef QDC_TOPOLOGY_H
#define QDC_TOPOLOGY_H

#include "core/mesh.h"
#include "opt/opt.h"

/* opt_run with o->topology != NONE (opt_run calls it): m's coordinates, tets,
 * regions and tet count replaced by the result; res->tets_in/out and the topo_*
 * counts filled, res->before the input's record, res->after the result's.
 * Fails as opt_run does (m unchanged when the first smoothing fails). */
qdc_status opt_topology_run(mesh_t *m, const opt_options *o, opt_result *res,
                            qdc_error *err);

#endif
