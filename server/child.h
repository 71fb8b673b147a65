/* child.h - run a helper program in a child process (TetGen runs in
 * `qdc tetra`, because libtet can crash the process on some inputs and
 * prints to stdout). posix_spawn, never fork without exec: the daemon is
 * multithreaded. The child gets an empty signal mask and default handlers,
 * its own process group, /dev/null as stdin and one log file as stdout and
 * stderr. Thread-safe. */
#ifndef QDCD_CHILD_H
#define QDCD_CHILD_H

#include <stdatomic.h>
#include <stddef.h>

typedef struct {
    int spawned; /* 0: posix_spawn failed (errno_spawn says why) */
    int errno_spawn;
    int exited; /* normal exit: code holds the exit status */
    int code;
    int signal;    /* killed by this signal (0 if it exited) */
    int timed_out; /* we killed it at the deadline */
    int cancelled; /* we killed it because *cancel became non-zero */
    double seconds;
} child_result;

/* Run argv[0] (a path, or a name looked up in PATH) with argv, output to log_path
 * (truncated), and wait. The child is killed (SIGKILL, its whole process group) once
 * mono_now() passes deadline or *cancel (may be NULL) is set. */
void child_run(char *const argv[], const char *log_path, double deadline,
               const atomic_int *cancel, child_result *out);

/* The last line of the log starting with prefix, without it and without the
 * newline, into out (cap bytes); "" if none. */
void child_last_line(const char *log_path, const char *prefix, char *out, size_t cap);

#endif
