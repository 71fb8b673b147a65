/* fuzz_xdmf.c - libFuzzer target: the XDMF reader (data inline) on the input,
 * named and sniffed; what parses is written by qdc's writer and read back,
 * and, with its source kept, spliced unchanged and with moved coordinates.
 * Seeds: tests/fuzz/seeds/xdmf (hand-made documents in meshio's, DOLFIN's and
 * dolfinx's forms); crashes go to tests/fuzz/crashes/xdmf/, which
 * test_formats replays. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_read((const char *)data, size, MESHIO_XDMF);
    fuzz_read((const char *)data, size, MESHIO_AUTO);
    return 0;
}
