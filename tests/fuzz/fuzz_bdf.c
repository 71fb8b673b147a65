/* fuzz_bdf.c - libFuzzer target: the Nastran bulk data reader on the input, named
 * and sniffed; what parses is refused by meshio_write without a source
 * (written only spliced) and, with its source kept, spliced unchanged and
 * with moved coordinates. Seeds: tests/fuzz/seeds/bdf (hand-made files);
 * crashes go to tests/fuzz/crashes/bdf/, which test_formats replays. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_read((const char *)data, size, MESHIO_BDF);
    fuzz_read((const char *)data, size, MESHIO_AUTO);
    return 0;
}
