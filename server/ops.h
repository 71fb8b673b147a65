/* ops.h - the operations endpoints (ops.c), dispatched by api.c. */
#ifndef QDCD_OPS_H
#define QDCD_OPS_H

#include "http.h"

/* GET /metrics: counters, gauges and the latency histogram. */
enum MHD_Result ops_metrics(struct MHD_Connection *c, req *r);
/* GET /readyz: 200 with the queue depth, 503 when stopping or the store fails. */
enum MHD_Result ops_readyz(struct MHD_Connection *c, req *r);

#endif
