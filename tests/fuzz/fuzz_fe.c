/* fuzz_fe.c - libFuzzer target: the DOLFIN XML, Medit binary, Abaqus .inp and
 * Netgen .vol readers on the input; what parses is written back through
 * DOLFIN's and Medit binary's writers
 * (Abaqus and Netgen: refused without a source) and, with its source kept,
 * spliced unchanged and with moved coordinates. Seeds: tests/fuzz/seeds/fe
 * (files written by meshio and by qdc); crashes go to tests/fuzz/crashes/fe/,
 * which test_formats replays. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_read((const char *)data, size, MESHIO_DOLFIN);
    fuzz_read((const char *)data, size, MESHIO_MESHB);
    fuzz_read((const char *)data, size, MESHIO_ABAQUS);
    fuzz_read((const char *)data, size, MESHIO_NETGEN);
    return 0;
}
