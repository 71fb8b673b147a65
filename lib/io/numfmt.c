/* numfmt.c - doubles as text (numfmt.h).
 *
 * printf("%.17g") spends most of a large text mesh's write time (0.6 s of
 * an 800k-tet Medit file with every coordinate changed). For |x| in
 * [1e-11, 1e16) the 17 significant digits are found exactly with integer
 * arithmetic: x = m 2^q, and N = x 10^k = m 5^k 2^(q+k) with k = 16 - E
 * (E the decimal exponent of x) lies in [1e16, 1e17); m 5^k has at most 53 +
 * 63 bits, so one 128-bit product and a shift give N's integer part and the
 * exact remainder, rounded half to even as glibc's printf rounds. */
#include "io/numfmt.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

__extension__ typedef unsigned __int128 u128;

#define P5_MAX 27 /* 5^27 < 2^63 */

static const uint64_t pow5[P5_MAX + 1] = {1ULL,
                                          5ULL,
                                          25ULL,
                                          125ULL,
                                          625ULL,
                                          3125ULL,
                                          15625ULL,
                                          78125ULL,
                                          390625ULL,
                                          1953125ULL,
                                          9765625ULL,
                                          48828125ULL,
                                          244140625ULL,
                                          1220703125ULL,
                                          6103515625ULL,
                                          30517578125ULL,
                                          152587890625ULL,
                                          762939453125ULL,
                                          3814697265625ULL,
                                          19073486328125ULL,
                                          95367431640625ULL,
                                          476837158203125ULL,
                                          2384185791015625ULL,
                                          11920928955078125ULL,
                                          59604644775390625ULL,
                                          298023223876953125ULL,
                                          1490116119384765625ULL,
                                          7450580596923828125ULL};

#define TEN16 10000000000000000ULL
#define TEN17 100000000000000000ULL

/* The 17 digits D (1e16 <= D < 1e17) and exponent E of x > 0 (x = D 10^(E-16)
 * to within half a unit of D's last digit); 0 if out of the exact range. */
static int digits17(double x, uint64_t *D, int *E)
{
    uint64_t bits, m;
    int q, e;

    memcpy(&bits, &x, sizeof bits);
    m = (bits & ((1ULL << 52) - 1)) | (1ULL << 52);
    q = (int)((bits >> 52) & 0x7ff) - 1075; /* x = m 2^q (x is normal here) */
    /* a guess from the binary exponent (off by one at most), corrected below */
    e = (int)floor((q + 52) * 0.30102999566398120);
    for (int tries = 0; tries < 4; tries++) {
        int k = 16 - e, s;
        u128 M, F, rem = 0, half = 0;
        int up = 0;
        if (k < 0 || k > P5_MAX)
            return 0;
        M = (u128)m * pow5[k];
        s = q + k;
        if (s >= 0) {
            if (s > 60)
                return 0;
            F = M << s;
        } else {
            int sh = -s;
            if (sh > 120)
                return 0;
            F = M >> sh;
            rem = M - (F << sh);
            half = (u128)1 << (sh - 1);
            up = rem > half || (rem == half && (F & 1));
        }
        if (F >= TEN17) {
            e++;
            continue;
        }
        if (F < TEN16) {
            e--;
            continue;
        }
        F += (u128)up;
        if (F == TEN17) { /* 99..9.5 rounds up to the next power of ten */
            F = TEN16;
            e++;
        }
        *D = (uint64_t)F;
        *E = e;
        return 1;
    }
    return 0;
}

int numfmt_g17(double x, char *out)
{
    char dig[17];
    uint64_t D;
    int E, n = 0, nd = 17;
    double ax = fabs(x);

    if (!(ax >= 1e-11 && ax < 1e16) || !digits17(ax, &D, &E))
        return snprintf(out, 32, "%.17g", x);
    for (int i = 16; i >= 0; i--) {
        dig[i] = (char)('0' + D % 10);
        D /= 10;
    }
    while (nd > 1 && dig[nd - 1] == '0') /* %g drops trailing zeros */
        nd--;
    if (x < 0)
        out[n++] = '-';
    if (E < -4) { /* %e style: d.ddd e-XX */
        int ex = -E;
        out[n++] = dig[0];
        if (nd > 1) {
            out[n++] = '.';
            memcpy(out + n, dig + 1, (size_t)nd - 1);
            n += nd - 1;
        }
        out[n++] = 'e';
        out[n++] = '-';
        out[n++] = (char)('0' + ex / 10);
        out[n++] = (char)('0' + ex % 10);
    } else if (E >= 0) { /* ddd.ddd */
        int ni = E + 1;  /* integer digits, at most 16 */
        memcpy(out + n, dig, (size_t)ni);
        n += ni;
        if (nd > ni) {
            out[n++] = '.';
            memcpy(out + n, dig + ni, (size_t)(nd - ni));
            n += nd - ni;
        }
    } else { /* 0.000ddd */
        out[n++] = '0';
        out[n++] = '.';
        for (int i = 0; i < -E - 1; i++)
            out[n++] = '0';
        memcpy(out + n, dig, (size_t)nd);
        n += nd;
    }
    out[n] = '\0';
    return n;
}

/* Q 2^e2 (plus a nonzero fraction of Q's last unit if sticky) to the nearest
 * double, ties to even. Q > 0; sticky only with Q of 54 bits or more (the
 * quotient of numfmt_decimal has 64). */
static double round_to_double(u128 Q, int sticky, int e2)
{
    uint64_t hi = (uint64_t)(Q >> 64);
    int L = hi ? 128 - __builtin_clzll(hi) : 64 - __builtin_clzll((uint64_t)Q);
    uint64_t top;

    if (L <= 53)
        return ldexp((double)(uint64_t)Q, e2);
    {
        int sh = L - 53;
        u128 rest = Q & (((u128)1 << sh) - 1), half = (u128)1 << (sh - 1);
        int up;
        top = (uint64_t)(Q >> sh);
        up = rest > half || (rest == half && (sticky || (top & 1)));
        top += (uint64_t)up; /* 2^53 at most: still exact */
        return ldexp((double)top, e2 + sh);
    }
}

int numfmt_decimal(uint64_t m, int e10, double *out)
{
    if (m == 0 || e10 < -P5_MAX || e10 > P5_MAX)
        return 0;
    if (e10 >= 0) { /* m 5^e 2^e: below 2^127 */
        *out = round_to_double((u128)m * pow5[e10], 0, e10);
        return 1;
    }
    {
        /* m / (5^k 2^k): m shifted to the top of 127 bits, divided by 5^k
         * (< 2^63): a quotient of 64 bits or more and its remainder */
        int k = -e10, j = 127 - (64 - __builtin_clzll(m));
        u128 num = (u128)m << j, d = pow5[k];
        u128 Q = num / d, R = num - Q * d;
        *out = round_to_double(Q, R != 0, -j - k);
        return 1;
    }
}
