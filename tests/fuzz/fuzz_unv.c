/* fuzz_unv.c - libFuzzer target: the I-DEAS universal reader on the input, named
 * and sniffed; what parses is refused by meshio_write without a source
 * (written only spliced) and, with its source kept, spliced unchanged and
 * with moved coordinates. Seeds: tests/fuzz/seeds/unv (hand-made files);
 * crashes go to tests/fuzz/crashes/unv/, which test_formats replays. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_read((const char *)data, size, MESHIO_UNV);
    fuzz_read((const char *)data, size, MESHIO_AUTO);
    return 0;
}
