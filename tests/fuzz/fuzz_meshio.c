/* fuzz_meshio.c - libFuzzer target: every reader on the input, and for what
 * parses, write-then-read must give the same mesh back.
 *
 *   make fuzz FUZZ_SECONDS=60    (builds and runs every tests/fuzz/fuzz_*.c)
 *
 * TetGen takes the first half of the input as .node and the second as .ele.
 * Crashes go to tests/fuzz/crashes/meshio/, which test_meshio replays. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    for (int f = MESHIO_AUTO; f < MESHIO_FORMAT_COUNT; f++)
        fuzz_read((const char *)data, size, (meshio_format)f);
    return 0;
}
