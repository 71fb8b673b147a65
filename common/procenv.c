/* procenv.c - the environment of the qdc CLI and qdcd (procenv.h). */
#include "procenv.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int procenv_default(const char *name, const char *value)
{
    return !getenv(name) && setenv(name, value, 1) == 0;
}

int procenv_tune_malloc(const char *tunables)
{
    const char *t = getenv("GLIBC_TUNABLES");
    char v[2048];

    if ((t && strstr(t, "glibc.malloc.")) || getenv("MALLOC_MMAP_THRESHOLD_") ||
        getenv("MALLOC_TRIM_THRESHOLD_") || getenv("MALLOC_TOP_PAD_") ||
        getenv("MALLOC_ARENA_MAX"))
        return 0;
    if (snprintf(v, sizeof v, "%s%s%s", t ? t : "", t && *t ? ":" : "", tunables) >=
        (int)sizeof v)
        return 0;
    return setenv("GLIBC_TUNABLES", v, 1) == 0;
}

void procenv_restart(char **argv)
{
    char self[4096];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);

    if (n > 0) {
        self[n] = 0;
        execv(self, argv);
    }
}
