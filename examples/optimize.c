/* optimize.c - optimize a tetrahedral mesh file through libqdc alone: read it,
 * optimize it with the default options, report its quality before and after,
 * write it. It includes only qdc.h, as any program outside the repository
 * would (build: cc -Ilib optimize.c build/rel/libqdc.a and the libraries the
 * Makefile's LIB_LIBS names).
 *   optimize IN OUT     IN and OUT in any format qdc reads and writes, by
 *                       their extensions (OUT in IN's format: IN with only the
 *                       coordinates replaced)
 * Exit status 0 ok, 1 usage, 2 IN not read, 3 optimization failed, 4 OUT not
 * written. Run with OPENBLAS_NUM_THREADS=1, as qdc and qdcd run themselves,
 * it writes the bytes `qdc optimize IN OUT` writes (tests/e2e/example.sh). */
#include "qdc.h"

#include <stdio.h>

static void print_quality(const char *when, const report_quality *q)
{
    printf("%s: %d vertices, %d tets, mean ratio mean %.4f min %.4f, "
           "dihedral %.2f..%.2f deg, %d inverted\n",
           when, (int)q->nv, (int)q->nt, q->q_mean, q->q_min, q->dih_min, q->dih_max,
           (int)q->n_inverted);
}

int main(int argc, char **argv)
{
    mesh_t *m = NULL;
    opt_options o;
    opt_result res;
    report_quality before, after;
    qdc_error err;
    qdc_status st;
    int rc = 0;

    if (argc != 3) {
        fprintf(stderr, "usage: %s IN OUT\n", argv[0]);
        return 1;
    }
    qdc_error_clear(&err);
    /* the format from the extension, else from the content; m is ours */
    st = meshio_load(argv[1], MESHIO_AUTO, &m, &err);
    if (st == QDC_OK)
        st = mesh_validate(m, NULL, &err);
    if (st == QDC_OK)
        st = report_quality_compute(m, &before, &err);
    if (st != QDC_OK) {
        fprintf(stderr, "%s: %s: %s\n", argv[1], qdc_status_str(st), err.msg);
        rc = 2;
        goto out;
    }
    print_quality("before", &before);

    opt_defaults(&o);
    st = opt_run(m, &o, &res, &err);
    if (st == QDC_OK && res.outcome == OPT_FAILED)
        st = QDC_EINTERNAL;
    if (st == QDC_OK)
        st = report_quality_compute(m, &after, &err);
    if (st != QDC_OK) {
        fprintf(stderr, "%s: optimization failed: %s: %s\n", argv[1], qdc_status_str(st),
                err.msg);
        rc = 3;
        goto out;
    }
    printf("run: %d global iterations, stopped: %s, solver %s, %.2f s\n", res.iterations,
           res.stop_reason, opt_solver_name(res.solver), res.t_total);
    print_quality("after", &after);

    st = meshio_save(argv[2], MESHIO_AUTO, m, &err);
    if (st != QDC_OK) {
        fprintf(stderr, "%s: %s: %s\n", argv[2], qdc_status_str(st), err.msg);
        rc = 4;
    }
out:
    mesh_free(m);
    return rc;
}
