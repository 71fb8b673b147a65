/* main.c - the qdc command: local optimization and quality reports
 * (remote subcommands: see remote.c when present). */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "procenv.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static void usage(FILE *f)
{
    fputs(
        "usage: qdc COMMAND [ARGS]\n"
        "\n"
        "Local commands:\n"
        "  optimize IN OUT [options]   optimize a tet mesh (qdc optimize --help)\n"
        "  quality IN [--ref ORIG] [--json]   quality report of a mesh\n"
        "  convert IN OUT [--out-format F]   another format (OUT in IN's format: IN\n"
        "                              with only the coordinates replaced)\n"
        "  options                     the optimizer's options as JSON (names, types,\n"
        "                              valid values, defaults, help)\n"
        "  formats                     the mesh formats as JSON (names, extensions,\n"
        "                              media types, what is read and written)\n"
        "  tetra SURFACE OUT [--tetgen-quality Q] [--max-volume V]   tetrahedralize\n"
        "                              a closed surface with TetGen (no optimization)\n"
        "  IN or OUT '-': standard input or output (the input's format unless\n"
        "  --out-format says another)\n"
        "\n"
        "Remote commands (qdcd at --server URL or $QDC_SERVER; token $QDC_TOKEN):\n"
        "  submit IN [--wait] [-o OUT] [--report R.json] [options]   new job; prints its "
        "id\n"
        "  status JOB | watch JOB | cancel JOB | jobs\n"
        "  fetch JOB -o OUT [--report R.json]   download the result (qdc submit --help)\n"
        "\n"
        "Exit codes: 0 ok, 1 usage, 2 bad input file, 3 optimization failed,\n"
        "  4 output not written, 5 interrupted (best mesh so far written),\n"
        "  10 server rejected the request, 11 job failed, 12 network failure.\n",
        f);
}

/* OpenMP threads that spin while they wait steal the cores of whatever else
 * runs (a server, a second qdc, a container's CPU quota): measured on 2 busy
 * cores, a 100k-tet run took 2.4-3.1 CPU s spinning and 0.8 sleeping, and
 * 6-9 s wall against 2.3-3.9. libgomp reads OMP_WAIT_POLICY when it is loaded,
 * before main, so unless the user chose a policy, qdc sets PASSIVE and starts
 * itself again (once: the variable is then set). If that fails, it goes on.
 * The same for CHOLMOD's BLAS: one OpenBLAS thread (OPENBLAS_NUM_THREADS=1)
 * unless the user chose a count, as qdcd runs it (server/main.c), so that the
 * CLI and the daemon give the same bytes whatever the core count (a BLAS
 * thread count changes the factor's rounding); beside OpenMP's threads it was
 * faster too (bunny_tangled-low_10k 0.50 against 0.59 s). */
/* The most threads the run uses: --threads N, else OMP_NUM_THREADS's first
 * value, else the cores online (OpenMP's default is one thread per core it
 * may run on, never more). 0 if unknown. */
static long thread_count(char **argv)
{
    const char *env = getenv("OMP_NUM_THREADS");
    char *end;
    long n = 0;

    for (int i = 1; argv[i] && argv[i + 1]; i++)
        if (!strcmp(argv[i], "--threads")) {
            long t = strtol(argv[i + 1], &end, 10);
            n = *end ? 0 : t;
        }
    if (n <= 0 && env && *env)
        n = strtol(env, NULL, 10);
    if (n <= 0)
        n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 && n <= 1024 ? n : 0;
}

/* glibc's malloc hands every freed block of 128 KiB or more back to the kernel
 * (each its own mmap), and the top of the heap above 128 KiB, so the
 * optimizer's arrays, allocated and freed at each pass and round, came back
 * as zeroed 4 KiB pages, a fault each. Unless the user tuned malloc, qdc runs
 * with blocks up to 1 GiB taken from the heap, the heap never trimmed (the
 * process ends with the run) and its memory in transparent huge pages where
 * the kernel allows them (madvise): --topology full on 100k tets (one
 * thread) took 31,500 faults and 0.26-0.30 s of system time, 15,400 and
 * 0.13-0.19 s with the heap kept; on the 1M-tet ball with --report, 70,800
 * faults and 8.7-9.3 CPU s, 2,000 and 8.3-8.6 with huge pages too. Like the
 * variables above, glibc reads these before main: 1 when it set them. */
#define QDC_MALLOC_TUNABLES                                                              \
    "glibc.malloc.hugetlb=1:glibc.malloc.mmap_threshold=1073741824:"                     \
    "glibc.malloc.trim_threshold=1073741824"

static void wait_passive(char **argv)
{
    long nth;
    int reexec = 0;

    reexec |= procenv_default("OMP_WAIT_POLICY", "PASSIVE");
    reexec |= procenv_default("OPENBLAS_NUM_THREADS", "1");
    reexec |= procenv_tune_malloc(QDC_MALLOC_TUNABLES);
    /* CHOLMOD's supernodal factorization opens OpenMP teams of its own size
     * (4 threads in Debian 12's, whatever qdc's count), so a run on 2 cores
     * or with --threads 1 woke and put to sleep threads it had not asked
     * for: 20,000 context switches in a 3 s --topology full run on 100k tets
     * with --threads 1, 100 with the limit. The limit is never below the
     * threads qdc itself runs (thread_count). Not in qdcd: libgomp counts
     * the limit over the whole process, across its workers' jobs. */
    nth = getenv("OMP_THREAD_LIMIT") ? 0 : thread_count(argv);
    if (nth > 0) {
        char v[24];
        snprintf(v, sizeof v, "%ld", nth);
        reexec |= procenv_default("OMP_THREAD_LIMIT", v);
    }
    if (reexec)
        procenv_restart(argv);
}

int main(int argc, char **argv)
{
    wait_passive(argv);
    if (argc < 2) {
        usage(stderr);
        return CLI_EUSAGE;
    }
    if (!strcmp(argv[1], "-h") || !strcmp(argv[1], "--help") ||
        !strcmp(argv[1], "help")) {
        usage(stdout);
        return CLI_OK;
    }
    if (!strcmp(argv[1], "optimize"))
        return cli_optimize(argc - 1, argv + 1);
    if (!strcmp(argv[1], "quality"))
        return cli_quality(argc - 1, argv + 1);
    if (!strcmp(argv[1], "convert"))
        return cli_convert(argc - 1, argv + 1);
    if (!strcmp(argv[1], "options"))
        return cli_options(argc - 1, argv + 1);
    if (!strcmp(argv[1], "formats"))
        return cli_formats(argc - 1, argv + 1);
    if (!strcmp(argv[1], "tetra"))
        return cli_tetra(argc - 1, argv + 1);
    if (!strcmp(argv[1], "submit") || !strcmp(argv[1], "status") ||
        !strcmp(argv[1], "watch") || !strcmp(argv[1], "fetch") ||
        !strcmp(argv[1], "cancel") || !strcmp(argv[1], "jobs"))
        return cli_remote(argc - 1, argv + 1);
    {
        static const char *const commands[] = {
            "optimize", "quality", "convert", "options", "tetra", "submit",
            "status",   "watch",   "fetch",   "cancel",  "jobs",  "help"};
        const char *near =
            cli_suggest(argv[1], commands, sizeof commands / sizeof commands[0]);
        if (near)
            fprintf(stderr, "qdc: unknown command '%s': did you mean '%s'?\n", argv[1],
                    near);
        else
            fprintf(stderr, "qdc: unknown command '%s'\n", argv[1]);
    }
    usage(stderr);
    return CLI_EUSAGE;
}
