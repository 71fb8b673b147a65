/* base_int.h - the internal part of base.h: what every lib/ module shares
 * and no caller of the library needs (timing, thread ranges, prefetch).
 * Included only inside lib/ and by the unit tests (docs/architecture.md,
 * "Public and internal headers"). Thread-safe: no global state. */
#ifndef QDC_BASE_INT_H
#define QDC_BASE_INT_H

#include "core/base.h"

#include <stddef.h>
#include <stdint.h>

/* A hint to fetch the cache line of p ahead of a read (none where the
 * compiler has no such builtin). */
#if defined(__GNUC__)
#define QDC_PREFETCH(p) __builtin_prefetch(p)
#else
#define QDC_PREFETCH(p) ((void)(p))
#endif

/* The first item of part p of n items cut into parts nearly equal parts (p =
 * parts: n): the fixed ranges that parallel loops give their threads. */
static inline int32_t qdc_part(int32_t n, int p, int parts)
{
    return (int32_t)((int64_t)n * p / parts);
}

/* Monotonic wall clock in seconds. */
double qdc_now(void);

/* The caller's OpenMP thread count, at most cap: the team size of a loop that
 * gives each thread its own scratch array of the mesh's size. */
int qdc_threads_upto(int cap);

/* A counting sort's counts made by nth threads over consecutive ranges of the
 * items (cnt: nth rows of w entries, bucket b of thread i at cnt[i * w + b])
 * into each thread's first place in each of the n buckets: bucket by bucket,
 * thread by thread, so the placed items keep their serial order. start (n + 1
 * entries, may be NULL) receives each bucket's first place and the total. */
void qdc_count_places(int32_t *cnt, int nth, size_t w, int32_t n, int32_t *start);

#endif
