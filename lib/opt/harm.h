/* harm.h - harmonic guidance field (paper Sec. 5.1, docs/method.md §6).
 * h = 1 on boundary vertices, 0 on approximate medial-axis vertices, harmonic
 * (uniform graph Laplacian) elsewhere, clipped to [0, 1]. Thread-safe. */
#ifndef QDC_HARM_H
#define QDC_HARM_H

#include "core/mesh_int.h"

/* x: coordinates (3 per vertex) of the pre-optimized mesh; h_out: nv values.
 * *n_medial receives the number of medial vertices (may be NULL). */
qdc_status harm_field(const mesh_topo *tp, const double *x, double *h_out,
                      int32_t *n_medial, qdc_error *err);

#endif
