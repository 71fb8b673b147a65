/* test_numfmt.c - numfmt_g17 (io/numfmt.h) against the C library's own
 * printf("%.17g") on doubles of every kind, rounding ties included, and the
 * text read back as the same double; numfmt_decimal against strtod. */
#include "io/numfmt.h"
#include "testlib.h"

#include <stdint.h>

static uint64_t rng_state = 88172645463325252ULL;

static uint64_t rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}

/* numfmt_g17(x) equals snprintf's text and reads back as x */
static int same_as_printf(double x, char *got, char *want)
{
    int n = numfmt_g17(x, got);
    snprintf(want, 64, "%.17g", x);
    if (strcmp(got, want) || n != (int)strlen(got))
        return 0;
    return !isfinite(x) || strtod(got, NULL) == x;
}

TEST(matches_printf_on_random_doubles)
{
    char got[64], want[64];

    for (long i = 0; i < 1000000; i++) {
        double x;
        uint64_t u = rnd();
        switch (i % 4) {
        case 0: /* any bit pattern: NaN, Inf, subnormal, huge */
            memcpy(&x, &u, sizeof x);
            break;
        case 1: /* mesh-like magnitudes, 1e-13 .. 1e16 */
            x = ldexp((double)(u >> 11), -53) *
                pow(10.0, (double)((int)(rnd() % 30) - 13));
            break;
        case 2: /* few mantissa bits: decimal expansions that end in a tie */
            x = ldexp((double)(u >> 40), (int)(rnd() % 60) - 40);
            break;
        default: /* integers and binary fractions */
            x = (double)(int64_t)(u >> 12) / (double)(1 << (rnd() % 20));
        }
        if (rnd() & 1)
            x = -x;
        if (!same_as_printf(x, got, want)) {
            printf("  %a: got %s, printf %s\n", x, got, want);
            ASSERT_TRUE(0);
        }
    }
}

TEST(ties_round_to_even_and_edges)
{
    /* 1234567890123456.25 and .75 are exact doubles whose 18th digit is a
     * tie; 9.99..95e-5 rounds up to the next power of ten; 1e-11 and 1e16 are
     * the ends of the exact range; 0, -0 and 5e-324 go to printf */
    const double xs[] = {1234567890123456.25,
                         1234567890123456.75,
                         0.1,
                         0.30000000000000004,
                         9.9999999999999995e-5,
                         1e-5,
                         1e-4,
                         1e15,
                         9999999999999998.0,
                         1e16,
                         1e-11,
                         9.9999999999999994e-12,
                         0.0,
                         -0.0,
                         5e-324,
                         1.7976931348623157e308,
                         -123.456};
    char got[64], want[64];

    for (size_t i = 0; i < sizeof xs / sizeof *xs; i++) {
        if (!same_as_printf(xs[i], got, want)) {
            printf("  %a: got %s, printf %s\n", xs[i], got, want);
            ASSERT_TRUE(0);
        }
    }
    /* the tie goes to the even digit: ...56.2 and ...56.8 */
    numfmt_g17(1234567890123456.25, got);
    ASSERT_TRUE(got[strlen(got) - 1] == '2');
    numfmt_g17(1234567890123456.75, got);
    ASSERT_TRUE(got[strlen(got) - 1] == '8');
}

/* numfmt_decimal(m, e) is strtod("<m>e<e>"): random 1-19 digit mantissas
 * over the exponents it takes, and mantissas near halfway between doubles */
TEST(decimal_matches_strtod)
{
    char buf[64];

    for (long i = 0; i < 1000000; i++) {
        uint64_t m = rnd() % 10000000000000000000ULL;
        int e = (int)(rnd() % 55) - 27;
        double got = 0, want;
        if (i % 3 == 1)
            m >>= rnd() % 60; /* shorter mantissas too */
        if (i % 3 == 2) {     /* 2 x the midpoint of two doubles, as an integer */
            double x = ldexp((double)((rnd() >> 11) | 1), -(int)(rnd() % 12));
            m = (uint64_t)(2 * x) + 1;
            e = 0;
        }
        if (m == 0)
            continue;
        snprintf(buf, sizeof buf, "%llue%d", (unsigned long long)m, e);
        want = strtod(buf, NULL);
        ASSERT_TRUE(numfmt_decimal(m, e, &got) == 1);
        if (memcmp(&got, &want, sizeof got)) {
            printf("  %s: got %a, strtod %a\n", buf, got, want);
            ASSERT_TRUE(0);
        }
    }
    /* out of its range: left to strtod */
    {
        double x;
        ASSERT_TRUE(numfmt_decimal(1, 28, &x) == 0);
        ASSERT_TRUE(numfmt_decimal(1, -28, &x) == 0);
        ASSERT_TRUE(numfmt_decimal(0, 0, &x) == 0);
    }
}

TEST_MAIN("numfmt", T(matches_printf_on_random_doubles), T(ties_round_to_even_and_edges),
          T(decimal_matches_strtod))
