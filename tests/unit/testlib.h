/* testlib.h - tiny unit-test harness. Each TEST prints "ok - name",
 * "FAIL - name: detail" or, when it could not run (SKIP(reason)),
 * "ok - name # SKIP reason"; tests/run.sh counts skips apart from passes.
 * main() comes from TEST_MAIN(list of tests). */
#ifndef QDC_TESTLIB_H
#define QDC_TESTLIB_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int tl_failed_now;
static int tl_total_failed;
static const char *tl_skip_reason;

/* The test cannot run here (a build option or a tool is missing): reported
 * as a skip, never as a pass. */
#define SKIP(reason)                                                                     \
    do {                                                                                 \
        tl_skip_reason = (reason);                                                       \
        return;                                                                          \
    } while (0)

#define ASSERT_TRUE(c)                                                                   \
    do {                                                                                 \
        if (!(c)) {                                                                      \
            printf("  %s:%d: assertion failed: %s\n", __FILE__, __LINE__, #c);           \
            tl_failed_now = 1;                                                           \
            return;                                                                      \
        }                                                                                \
    } while (0)

#define ASSERT_EQ_INT(a, b)                                                              \
    do {                                                                                 \
        long long a_ = (long long)(a), b_ = (long long)(b);                              \
        if (a_ != b_) {                                                                  \
            printf("  %s:%d: %s == %lld, expected %s == %lld\n", __FILE__, __LINE__, #a, \
                   a_, #b, b_);                                                          \
            tl_failed_now = 1;                                                           \
            return;                                                                      \
        }                                                                                \
    } while (0)

#define ASSERT_NEAR(a, b, tol)                                                           \
    do {                                                                                 \
        double a_ = (double)(a), b_ = (double)(b);                                       \
        if (!(fabs(a_ - b_) <= (tol))) {                                                 \
            printf("  %s:%d: %s = %.17g, expected %s = %.17g (tol %g)\n", __FILE__,      \
                   __LINE__, #a, a_, #b, b_, (double)(tol));                             \
            tl_failed_now = 1;                                                           \
            return;                                                                      \
        }                                                                                \
    } while (0)

#define ASSERT_OK(expr)                                                                  \
    do {                                                                                 \
        qdc_error e_;                                                                    \
        qdc_error_clear(&e_);                                                            \
        (void)e_;                                                                        \
        int st_ = (int)(expr);                                                           \
        if (st_ != 0) {                                                                  \
            printf("  %s:%d: %s returned %d (%s)\n", __FILE__, __LINE__, #expr, st_,     \
                   qdc_status_str((qdc_status)st_));                                     \
            tl_failed_now = 1;                                                           \
            return;                                                                      \
        }                                                                                \
    } while (0)

typedef void (*tl_fn)(void);
typedef struct {
    const char *name;
    tl_fn fn;
} tl_case;

#define TEST(name) static void name(void)
#define T(name)                                                                          \
    {                                                                                    \
#name, name                                                                      \
    }

static int tl_run(const char *suite, const tl_case *cases, int n)
{
    for (int i = 0; i < n; i++) {
        tl_failed_now = 0;
        tl_skip_reason = NULL;
        cases[i].fn();
        if (tl_skip_reason && !tl_failed_now) {
            printf("ok - %s.%s # SKIP %s\n", suite, cases[i].name, tl_skip_reason);
        } else if (tl_failed_now) {
            printf("FAIL - %s.%s\n", suite, cases[i].name);
            tl_total_failed++;
        } else {
            printf("ok - %s.%s\n", suite, cases[i].name);
        }
        fflush(stdout);
    }
    return tl_total_failed ? 1 : 0;
}

#define TEST_MAIN(suite, ...)                                                            \
    int main(void)                                                                       \
    {                                                                                    \
        static const tl_case cases_[] = {__VA_ARGS__};                                   \
        return tl_run(suite, cases_, (int)(sizeof cases_ / sizeof cases_[0]));           \
    }

#endif
