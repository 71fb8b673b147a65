/* fuzz_vtk.c - libFuzzer target: the legacy VTK and VTU readers on the input
 * and, for what parses, write-then-read through the writers of the family.
 * Seeds: tests/fuzz/seeds/vtk (qdc, Gmsh and meshio files); crashes go to
 * tests/fuzz/crashes/vtk/, which test_formats replays. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    for (int f = MESHIO_VTK; f <= MESHIO_VTU_ASCII; f++)
        fuzz_read((const char *)data, size, (meshio_format)f);
    return 0;
}
