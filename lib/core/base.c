/* base.c - status strings, error detail, allocation wrappers. */
#define _POSIX_C_SOURCE 200809L
#include "core/base_int.h"

#include <omp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const char *const status_text[] = {
#define QDC_X_TEXT(name, text, http) text,
    QDC_STATUS_LIST(QDC_X_TEXT)
#undef QDC_X_TEXT
};
static const char *const status_names[] = {
#define QDC_X_NAME(name, text, http) #name,
    QDC_STATUS_LIST(QDC_X_NAME)
#undef QDC_X_NAME
};
static const int status_http[] = {
#define QDC_X_HTTP(name, text, http) http,
    QDC_STATUS_LIST(QDC_X_HTTP)
#undef QDC_X_HTTP
};

const char *qdc_status_str(qdc_status st)
{
    if ((unsigned)st >= QDC_STATUS_COUNT)
        return "unknown status";
    return status_text[st];
}

const char *qdc_status_name(qdc_status st)
{
    if ((unsigned)st >= QDC_STATUS_COUNT)
        return "QDC_EUNKNOWN";
    return status_names[st];
}

int qdc_status_http(qdc_status st)
{
    if ((unsigned)st >= QDC_STATUS_COUNT)
        return 500;
    return status_http[st];
}

void qdc_error_clear(qdc_error *err)
{
    if (!err)
        return;
    memset(err, 0, sizeof *err);
    err->line = err->col = err->offset = err->index = -1;
}

qdc_status qdc_fail(qdc_error *err, qdc_status st, const char *fmt, ...)
{
    va_list ap;

    if (!err)
        return st;
    err->status = st;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    va_end(ap);
    return st;
}

#ifdef QDC_FAULT_INJECTION
static _Thread_local long fault_after;
static _Thread_local long fault_count;

void qdc_fault_set(long fail_after)
{
    fault_after = fail_after;
    fault_count = 0;
}

long qdc_fault_count(void)
{
    return fault_count;
}

static int fault_hit(void)
{
    fault_count++;
    return fault_after > 0 && fault_count >= fault_after;
}
#else
static int fault_hit(void)
{
    return 0;
}
#endif

void *qdc_malloc(size_t size)
{
    if (fault_hit())
        return NULL;
    return malloc(size ? size : 1);
}

void *qdc_calloc(size_t n, size_t size)
{
    if (fault_hit())
        return NULL;
    if (n == 0 || size == 0)
        return calloc(1, 1);
    return calloc(n, size);
}

void *qdc_mallocn(size_t n, size_t size)
{
    if (size && n > SIZE_MAX / size)
        return NULL;
    return qdc_malloc(n * size);
}

void *qdc_realloc(void *p, size_t size)
{
    if (fault_hit())
        return NULL;
    return realloc(p, size ? size : 1);
}

void qdc_free(void *p)
{
    free(p);
}

int qdc_threads_upto(int cap)
{
    int n = omp_get_max_threads();

    return n < 1 ? 1 : n > cap ? cap : n;
}

void qdc_count_places(int32_t *cnt, int nth, size_t w, int32_t n, int32_t *start)
{
    int32_t run = 0;

    for (int32_t b = 0; b < n; b++) {
        if (start)
            start[b] = run;
        for (int i = 0; i < nth; i++) {
            int32_t k = cnt[(size_t)i * w + b];
            cnt[(size_t)i * w + b] = run;
            run += k;
        }
    }
    if (start)
        start[n] = run;
}

double qdc_now(void)
{
    struct timespec ts;

    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
