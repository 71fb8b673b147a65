/* qdc.h - the public interface of libqdc: what the qdc CLI, the qdcd daemon
 * and other programs include (examples/optimize.c: a whole program on it).
 * The headers below are the public ones; each function in them says what it
 * reads, writes and returns and who frees what. Every other header under
 * lib/ (X_int.h beside a public X.h, and the internal modules' headers) is
 * internal: tests/house/layers.sh checks that none is reachable from here
 * (docs/architecture.md, "Public and internal headers").
 *
 * The library is in layers; a header includes only its own layer and lower ones:
 *   core/  status codes, allocation, the mesh container
 *   geom/  per-tet metrics, the boundary BVH and boundary error
 *   io/    mesh and surface file formats, the TetGen bridge
 *   opt/   the optimizer (QDC encoding, linear solve, harmonic guidance,
 *          boundary sliding, finishing pass, driver)
 *   eval/  quality and boundary-error reports
 * (io/ and opt/ are peers: neither includes the other.) */
#ifndef QDC_H
#define QDC_H

#include "core/base.h"
#include "core/mesh.h"
#include "eval/outcome.h"
#include "eval/report.h"
#include "geom/bderr.h"
#include "io/gz.h"
#include "io/meshio.h"
#include "io/surface.h"
#include "io/tetra.h"
#include "opt/opt.h"
#include "opt/options.h"

#endif
