/* fuzz_surface.c - libFuzzer target: every surface reader (STL, OFF, OBJ,
 * .poly, .smesh) and surface_check on the input: a valid status, a surface
 * exactly on success, every index in range. TetGen is not run here.
 * Seeds: tests/fuzz/seeds/surface; crashes go to tests/fuzz/crashes/surface/,
 * which test_surface replays. */
#include "qdc.h"

#include <stdint.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    for (int f = SURFACE_AUTO; f < SURFACE_FORMAT_COUNT; f++) {
        surface_t *s = NULL;
        qdc_error err;
        qdc_status st =
            surface_read((const char *)data, size, (surface_format)f, &s, &err);
        if ((unsigned)st >= QDC_STATUS_COUNT || (st == QDC_OK) != (s != NULL) ||
            (st != QDC_OK && err.status != st))
            __builtin_trap();
        if (!s)
            continue;
        for (int64_t i = 0; i < 3 * (int64_t)s->ntri; i++)
            if (s->tris[i] < 0 || s->tris[i] >= s->nv)
                __builtin_trap();
        st = surface_check(s, &err);
        if ((unsigned)st >= QDC_STATUS_COUNT || (st != QDC_OK && err.status != st))
            __builtin_trap();
        surface_free(s);
    }
    return 0;
}
