/* fuzz_med.c - libFuzzer target: the MED reader (the frames qdc-h5 writes)
 * on the input, named and sniffed; what parses is written whole by qdc's MED
 * writer and read back the same (families mapped back to the tags) and,
 * with its source kept, spliced unchanged and with moved coordinates. Seeds:
 * tests/fuzz/seeds/med (what qdc-h5 med-read prints for two small meshes); crashes go to
 * tests/fuzz/crashes/med/, which test_formats replays. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_read((const char *)data, size, MESHIO_MED);
    fuzz_read((const char *)data, size, MESHIO_AUTO);
    return 0;
}
