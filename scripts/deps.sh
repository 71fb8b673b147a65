#!/bin/sh
# deps.sh - install the Debian 12 packages qdc builds, tests and benchmarks with.
# Idempotent: only missing packages are installed, and only when run as root.
# Usage: scripts/deps.sh [--build|--runtime] [--check]
#   (--check: list what is missing, exit 1 if any)
set -eu

# --build: what compiling needs; --runtime: the shared libraries qdcd/qdc load
# (the Docker image's stages); default: everything, tests and benchmarks included.
BUILD_PKGS="build-essential pkg-config ca-certificates
libsuitesparse-dev libopenblas0-pthread libopenblas-dev
libmicrohttpd-dev libjansson-dev libsqlite3-dev libpq-dev zlib1g-dev libcurl4-openssl-dev libtet1.5-dev
libhdf5-dev"
RUNTIME_PKGS="ca-certificates curl libcholmod3 libopenblas0-pthread libmicrohttpd12
libjansson4 libsqlite3-0 libpq5 zlib1g libcurl4 libtet1.5 libgomp1 libhdf5-103-1"
TEST_PKGS="curl tetgen clang clang-format libclang-rt-14-dev jq
python3 python3-numpy python3-scipy python3-meshio python3-h5py hdf5-tools python3-gmsh python3-netgen python3-yaml gmsh
libmed-tools
podman debootstrap runc postgresql chromium"
case "${1:-}" in
--build) PKGS=$BUILD_PKGS; shift ;;
--runtime) PKGS=$RUNTIME_PKGS; shift ;;
*) PKGS="$BUILD_PKGS $TEST_PKGS" ;;
esac

missing=""
for p in $PKGS; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
        missing="$missing $p"
    fi
done

# Node.js and npm (the web console's browser tests, tests/server/ui.sh): Debian's packages,
# unless a node with its npm is already installed (e.g. from another source,
# whose nodejs package bundles npm and conflicts with Debian's npm).
case " $PKGS " in
*" podman "*)
    command -v npm > /dev/null 2>&1 || missing="$missing nodejs npm"
    ;;
esac

if [ -z "$missing" ]; then
    exit 0
fi
if [ "${1:-}" = "--check" ]; then
    echo "missing:$missing"
    exit 1
fi
if [ "$(id -u)" -ne 0 ]; then
    echo "deps.sh: missing Debian packages:$missing" >&2
    echo "deps.sh: run as root (or: sudo apt-get install$missing)" >&2
    exit 1
fi
echo "deps.sh: installing:$missing" >&2
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
# shellcheck disable=SC2086
apt-get install -y -qq --no-install-recommends $missing >/dev/null
