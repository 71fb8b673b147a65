/* procenv.h - what the qdc CLI and qdcd set in their environment before they
 * work: variables that libraries (libgomp, OpenBLAS, glibc's malloc) read
 * before main, each set unless the user set it, and the program started
 * again once so that they take effect. */
#ifndef QDC_PROCENV_H
#define QDC_PROCENV_H

/* name=value unless name is set: 1 when it was set here. */
int procenv_default(const char *name, const char *value);

/* tunables ("glibc.malloc.NAME=VALUE:...") appended to GLIBC_TUNABLES unless
 * the user tuned malloc (a glibc.malloc.* tunable, or one of glibc's MALLOC_*_
 * variables); the user's other tunables kept: 1 when it was set here. */
int procenv_tune_malloc(const char *tunables);

/* The program started again with the same arguments and the environment as
 * it is now (its own path, so that ps and /proc/PID/comm keep its name);
 * returns only when that failed, and the program goes on as it is. */
void procenv_restart(char **argv);

#endif
