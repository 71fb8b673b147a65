/* read_speed.c - reading speed of qdc's mesh readers on files: each file is
 * read into memory once, then parsed by meshio_read (no source kept) three
 * times; the best time gives MB/s of the (decompressed) file, by the wall
 * clock and by the thread's CPU time (steadier on a shared machine, where
 * the wall clock of the same parse varies twofold). Built and run by
 * bench/read_speed.sh. usage: read_speed FILE... */
#include "qdc.h"

#include <stdio.h>
#include <time.h>

static double now(clockid_t c)
{
    struct timespec t;

    clock_gettime(c, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv)
{
    int bad = 0;

    for (int i = 1; i < argc; i++) {
        char *buf;
        size_t len;
        qdc_error err;
        double best = 1e30, best_cpu = 1e30;
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
            double t0 = now(CLOCK_MONOTONIC), c0 = now(CLOCK_THREAD_CPUTIME_ID), t, c;
            if (meshio_read(buf, len, f, &m, &err) != QDC_OK) {
                fprintf(stderr, "%s: %s\n", argv[i], err.msg);
                bad = 1;
                break;
            }
            c = now(CLOCK_THREAD_CPUTIME_ID) - c0;
            t = now(CLOCK_MONOTONIC) - t0;
            best = best < t ? best : t;
            best_cpu = best_cpu < c ? best_cpu : c;
            nt = m->nt;
            mesh_free(m);
        }
        if (nt >= 0)
            printf("%-12s %-14s %6.1f MB %7d tets %6.3f s %6.0f MB/s, cpu %6.3f s %6.0f "
                   "MB/s\n",
                   meshio_format_name(f), argv[i], (double)len / 1e6, (int)nt, best,
                   (double)len / 1e6 / best, best_cpu, (double)len / 1e6 / best_cpu);
        qdc_free(buf);
    }
    return bad;
}
