/* read_speed.c - reading speed of qdc's mesh readers on files: each file is
 * read into memory once, then parsed by meshio_read (no source kept) three
 * times; the best time gives MB/s of the (decompressed) file. Built and run
 * by bench/read_speed.sh. usage: read_speed FILE... */
#include "io/meshio.h"

#include <stdio.h>
#include <time.h>

static double now(void)
{
    struct timespec t;

    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv)
{
    int bad = 0;

    for (int i = 1; i < argc; i++) {
        char *buf;
        size_t len;
        qdc_error err;
        double best = 1e30;
        int32_t nt = -1;
        meshio_format f;

        if (meshio_slurp(argv[i], &buf, &len, &err) != QDC_OK) {
            fprintf(stderr, "%s: %s\n", argv[i], err.msg);
            bad = 1;
            continue;
        }
        f = meshio_format_from_name(argv[i]);
        if (f == MESHIO_AUTO || f == MESHIO_GMSH41 || f == MESHIO_VTK ||
            f == MESHIO_VTU || f == MESHIO_MEDIT)
            f = meshio_sniff(buf, len); /* the variant inside */
        for (int rep = 0; rep < 3; rep++) {
            mesh_t *m = NULL;
            double t0 = now();
            if (meshio_read(buf, len, f, &m, &err) != QDC_OK) {
                fprintf(stderr, "%s: %s\n", argv[i], err.msg);
                bad = 1;
                break;
            }
            best = best < now() - t0 ? best : now() - t0;
            nt = m->nt;
            mesh_free(m);
        }
        if (nt >= 0)
            printf("%-12s %-28s %8.1f MB %9d tets %7.3f s %7.0f MB/s\n",
                   meshio_format_name(f), argv[i], (double)len / 1e6, (int)nt, best,
                   (double)len / 1e6 / best);
        qdc_free(buf);
    }
    return bad;
}
