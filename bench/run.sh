#!/bin/sh
# qdc benchmark: qdc (default, --boundary lsq and --boundary fixed) against Gmsh Relocate3D and
# Gmsh's default tet optimizer, on the dev meshes and generated ~100k/~1M-tet
# cubes. Progress on stderr, one Markdown table on stdout; raw JSON in
# bench/out/ and the table in bench/RESULTS.md (full run). See bench/README.md.
#
#   bench/run.sh                  full run (dev meshes + ~100k + ~1M tets)
#   bench/run.sh --no-large       without the ~1M-tet mesh
#   bench/run.sh --quick          3 small dev meshes, no Gmsh default optimizer
#   bench/run.sh --help           all options (--only REGEX, --resume, ...)
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
py=/usr/bin/python3   # Debian's python3 (numpy, scipy, meshio, gmsh), not pyenv's

for need in "$py" timeout; do
    command -v "$need" >/dev/null 2>&1 || { echo "bench: $need not found (make deps)" >&2; exit 1; }
done
"$py" -c 'import numpy, scipy, meshio, gmsh' 2>/dev/null ||
    { echo "bench: $py lacks numpy/scipy/meshio/gmsh (make deps)" >&2; exit 1; }

# build/rel/qdc: `make bench` has just run `make all`; when run directly, build
# it if missing. Others edit the tree concurrently, so retry a broken build.
case " $* " in *" -h "*|*" --help "*) exec "$py" "$here/bench.py" --help ;; esac
if [ ! -x "$root/build/rel/qdc" ]; then
    tries=0
    until make -C "$root" all >&2; do
        tries=$((tries + 1))
        [ "$tries" -lt 5 ] || { echo "bench: make all keeps failing" >&2; exit 1; }
        echo "bench: build failed, retrying in 60 s ($tries/4)" >&2
        sleep 60
    done
fi

cmdline="bench/run.sh${*:+ $*}"
[ -n "${MAKELEVEL:-}" ] && cmdline="make bench (bench/run.sh${*:+ $*})"
mkdir -p "$here/out"
exec "$py" "$here/bench.py" --cmdline "$cmdline" "$@"
