/* numfmt.h - doubles as text for the mesh writers. */
#ifndef QDC_NUMFMT_H
#define QDC_NUMFMT_H

#include <stdint.h>

/* x as printf("%.17g") writes it (17 significant digits, correctly rounded:
 * every double reads back as itself), into out (at least 32 bytes, NUL
 * ended); returns the length. Exact integer arithmetic for |x| in [1e-11,
 * 1e16), where mesh coordinates live; snprintf elsewhere and for non-finite
 * values. Thread-safe, no state. */
int numfmt_g17(double x, char *out);

/* m 10^e10 as the nearest double (ties to even, as strtod rounds), exactly,
 * for 0 < m < 2^64 and |e10| <= 27: 1, else 0 (the caller falls back to
 * strtod). The parsers' path for 17-19 significant digits, beyond the
 * double-arithmetic fast path. */
int numfmt_decimal(uint64_t m, int e10, double *out);

#endif
