#!/bin/sh
# docker/base-image.sh - make the base image the Dockerfile starts FROM
# (debian:bookworm-slim) without a container registry: debootstrap a minimal
# Debian 12 from the machine's own apt mirror and import it into the local
# image store. Needs root and Debian's debootstrap (scripts/deps.sh installs it).
#   usage: docker/base-image.sh [ENGINE]     (ENGINE: podman (default) or docker)
# Does nothing if the image is already there (QDC_REBUILD_BASE=1 to redo it).
set -eu
engine=${1:-podman}
tag=docker.io/library/debian:bookworm-slim
if [ -z "${QDC_REBUILD_BASE:-}" ] && "$engine" image inspect "$tag" > /dev/null 2>&1; then
    exit 0
fi
# The mirror the host uses (deb822 .sources or a one-line sources.list).
mirror=$(sed -n 's/^URIs:[[:space:]]*\([^[:space:]]*\).*/\1/p' /etc/apt/sources.list.d/*.sources 2>/dev/null |
    grep -v security | head -1)
[ -n "$mirror" ] || mirror=$(sed -n 's/^deb[[:space:]]\{1,\}\(http[^[:space:]]*\)[[:space:]]\{1,\}bookworm[[:space:]].*/\1/p' \
    /etc/apt/sources.list 2>/dev/null | head -1)
[ -n "$mirror" ] || mirror=http://deb.debian.org/debian
root=$(mktemp -d "${TMPDIR:-/tmp}/qdc-rootfs.XXXXXX")
trap 'rm -rf "$root"' EXIT
echo "base-image: debootstrap --variant=minbase bookworm from $mirror" >&2
debootstrap --variant=minbase bookworm "$root" "$mirror" > "$root.log" 2>&1 || {
    tail -20 "$root.log" >&2
    rm -f "$root.log"
    exit 1
}
rm -f "$root.log"
# What a slim image leaves out: downloaded packages and package lists.
rm -rf "$root"/var/cache/apt/archives/*.deb "$root"/var/lib/apt/lists/*
tar -C "$root" -c . | "$engine" import --change 'CMD ["bash"]' - "$tag" > /dev/null
echo "base-image: $tag imported" >&2
