/* child.c - helper processes for the workers (see child.h). */
#define _GNU_SOURCE
#include "child.h"

#include "util.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

extern char **environ;

void child_run(char *const argv[], const char *log_path, double deadline,
               const atomic_int *cancel, child_result *out)
{
    posix_spawn_file_actions_t fa;
    posix_spawnattr_t at;
    sigset_t none, dflt;
    pid_t pid;
    int status = 0, rc;
    double t0 = mono_now();

    memset(out, 0, sizeof *out);
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, log_path, O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    posix_spawnattr_init(&at);
    /* The daemon blocks SIGTERM/SIGINT in every thread and ignores SIGPIPE;
     * a child would inherit both across exec. */
    sigemptyset(&none);
    sigemptyset(&dflt);
    sigaddset(&dflt, SIGPIPE);
    sigaddset(&dflt, SIGTERM);
    sigaddset(&dflt, SIGINT);
    posix_spawnattr_setsigmask(&at, &none);
    posix_spawnattr_setsigdefault(&at, &dflt);
    posix_spawnattr_setpgroup(&at, 0);
    posix_spawnattr_setflags(&at, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF |
                                      POSIX_SPAWN_SETPGROUP);
    rc = posix_spawnp(&pid, argv[0], &fa, &at, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    posix_spawnattr_destroy(&at);
    if (rc) {
        out->errno_spawn = rc;
        return;
    }
    out->spawned = 1;

    /* Poll rather than block: the deadline and the cancel flag must be seen
     * while the child runs (waitpid has no timeout). */
    long nap_us = 2000;
    for (;;) {
        pid_t w = waitpid(pid, &status, WNOHANG);
        if (w == pid)
            break;
        if (w < 0 && errno != EINTR) {
            status = 0;
            break;
        }
        if (w == 0 && (mono_now() >= deadline || (cancel && atomic_load(cancel)))) {
            if (cancel && atomic_load(cancel))
                out->cancelled = 1;
            else
                out->timed_out = 1;
            kill(-pid, SIGKILL);
            kill(pid, SIGKILL);
            while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
                ;
            break;
        }
        struct timespec ts = {0, nap_us * 1000};
        nanosleep(&ts, NULL);
        if (nap_us < 50000)
            nap_us *= 2;
    }
    out->seconds = mono_now() - t0;
    if (WIFEXITED(status)) {
        out->exited = 1;
        out->code = WEXITSTATUS(status);
    } else if (WIFSIGNALED(status)) {
        out->signal = WTERMSIG(status);
    }
}

void child_last_line(const char *log_path, const char *prefix, char *out, size_t cap)
{
    size_t len = 0, n = strlen(prefix);
    char *buf = file_read_all(log_path, &len);

    out[0] = 0;
    if (!buf)
        return;
    for (char *p = buf; p < buf + len;) {
        char *nl = memchr(p, '\n', (size_t)(buf + len - p));
        size_t ln = nl ? (size_t)(nl - p) : (size_t)(buf + len - p);
        if (ln >= n && !memcmp(p, prefix, n))
            snprintf(out, cap, "%.*s", (int)(ln - n), p + n);
        p += ln + 1;
    }
    free(buf);
}
