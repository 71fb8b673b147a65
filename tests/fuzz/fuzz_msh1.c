/* fuzz_msh1.c - libFuzzer target: the Gmsh MSH 1 reader on the input, named
 * and sniffed; what parses is refused by meshio_write without a source (MSH 1
 * is written only spliced) and, with its source kept, spliced unchanged and
 * with moved coordinates. Seeds: tests/fuzz/seeds/msh1 (Gmsh's output and
 * hand-made files); crashes go to tests/fuzz/crashes/msh1/, which
 * test_formats replays. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_read((const char *)data, size, MESHIO_MSH1);
    fuzz_read((const char *)data, size, MESHIO_AUTO);
    return 0;
}
