/* numfmt.h - doubles as text for the mesh writers. */
#ifndef QDC_NUMFMT_H
#define QDC_NUMFMT_H

/* x as printf("%.17g") writes it (17 significant digits, correctly rounded:
 * every double reads back as itself), into out (at least 32 bytes, NUL
 * ended); returns the length. Exact integer arithmetic for |x| in [1e-11,
 * 1e16), where mesh coordinates live; snprintf elsewhere and for non-finite
 * values. Thread-safe, no state. */
int numfmt_g17(double x, char *out);

#endif
