#!/bin/sh
# format.sh - the C sources are laid out as .clang-format says (docs/style.md §9).
. "$(dirname "$0")/../lib.sh"
cd "$ROOT" || exit 1
if ! command -v clang-format > /dev/null 2>&1; then
    echo "ok - format # SKIP clang-format missing (apt-get install clang-format)"
    exit 0
fi
bad=
for f in $(git ls-files 'lib/*.c' 'lib/*.h' 'lib/*.cpp' 'server/*.c' 'server/*.h' 'clients/qdc/*.c' 'common/*.c' 'common/*.h' \
    'clients/qdc/*.h' 'tests/unit/*.c' 'tests/unit/*.h' 'tests/fuzz/*.c' 'tests/fuzz/*.h' \
    'examples/*.c' 2> /dev/null); do
    clang-format --dry-run -Werror "$f" > /dev/null 2>&1 || bad="$bad $f"
done
[ -z "$bad" ] && pass "format: every C/C++ source as clang-format lays it out" ||
    fail "format" "run make format; differ:$bad"
exit 0
