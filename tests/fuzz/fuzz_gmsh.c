/* fuzz_gmsh.c - libFuzzer target: the Gmsh reader (4.1 ASCII/binary, 4.0,
 * 2.2 ASCII/binary) on
 * the input and, for what parses, write-then-read through each Gmsh writer.
 * Seeds: tests/fuzz/seeds/gmsh (files written by qdc and by Gmsh); crashes go
 * to tests/fuzz/crashes/gmsh/, which test_formats replays. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_read((const char *)data, size, MESHIO_GMSH41);
    fuzz_read((const char *)data, size, MESHIO_GMSH41_BIN);
    fuzz_read((const char *)data, size, MESHIO_GMSH22);
    fuzz_read((const char *)data, size, MESHIO_GMSH22_BIN);
    fuzz_read((const char *)data, size, MESHIO_GMSH40);
    return 0;
}
