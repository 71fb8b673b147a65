/* ops.h - the operations endpoints and constant documents (ops.c), named
 * by the route table (route.h). */
#ifndef QDCD_OPS_H
#define QDCD_OPS_H

#include "http.h"

/* GET /metrics: counters, gauges and the latency histogram. */
enum MHD_Result ops_metrics(struct MHD_Connection *c, req *r);
/* GET /readyz: 200 with the queue depth, 503 when stopping or the store fails. */
enum MHD_Result ops_readyz(struct MHD_Connection *c, req *r);
/* GET /livez: 200 while the process answers. */
enum MHD_Result ops_livez(struct MHD_Connection *c, req *r);
/* GET /v1/options: the option table (job_opt_table_json). */
enum MHD_Result ops_options(struct MHD_Connection *c, req *r);
/* GET /v1/formats: the library's format table (meshio_formats_json), which
 * the console, the Python client and the batch script read. */
enum MHD_Result ops_formats(struct MHD_Connection *c, req *r);
/* GET /problems/{type}: the page of a problem type, as text. */
enum MHD_Result ops_problem_page(struct MHD_Connection *c, req *r);

#endif
