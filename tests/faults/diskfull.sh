#!/bin/sh
# faults/diskfull.sh - a full disk is a temporary condition: with --data on a
# small tmpfs filled up, an upload and a conversion of a result answer 507
# with a Retry-After (a conversion answered 500 before, with the server's
# absolute paths in the detail); no answer names a server path; once space
# is freed the same requests succeed. Needs root (mount -t tmpfs).
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
if [ "$(id -u)" != 0 ]; then
    echo "ok - diskfull # SKIP not root (mount -t tmpfs)"
    exit 0
fi
MNT=$TMP/mnt
mkdir -p "$MNT"
if ! mount -t tmpfs -o size=24m tmpfs "$MNT" 2> "$TMP/merr"; then
    echo "ok - diskfull # SKIP cannot mount a tmpfs here: $(head -c 80 "$TMP/merr")"
    exit 0
fi
trap 'if [ -n "$QPID" ]; then kill -9 $QPID 2>/dev/null; fi; umount "$MNT" 2>/dev/null; rm -rf "$TMP"' EXIT
start_qdcd "$MNT/d" --workers 1 || { fail "diskfull: start" "$(tail -3 "$MNT/d.log")"; exit 1; }
CUBE=$ROOT/tests/data/sample/cube.mesh
c=$(submit "$CUBE" model/x-medit "max_iter=2" "$TMP/j")
id=$(jf "$TMP/j" .id)
st=$(poll_all "$id")
# fill the disk
dd if=/dev/zero of="$MNT/filler" bs=1M count=64 2> /dev/null
code=$(req GET "/v1/jobs/$id/result?format=vtu" "$TMP/r1")
ra=$(hdr "$TMP/r1" Retry-After)
if [ "$code" = 507 ] && [ -n "$ra" ] && ! grep -q "$MNT" "$TMP/r1"; then
    pass "diskfull: conversion on a full disk: 507, Retry-After $ra, no server path: $(jf "$TMP/r1" .detail)"
else
    fail "diskfull: conversion" "$code Retry-After '$ra' $(head -c 300 "$TMP/r1")"
fi
code=$(submit "$CUBE" model/x-medit "" "$TMP/u1")
ra=$(hdr "$TMP/u1" Retry-After)
if [ "$code" = 507 ] && [ -n "$ra" ] && ! grep -q "$MNT" "$TMP/u1"; then
    pass "diskfull: upload on a full disk: 507, Retry-After $ra"
else
    fail "diskfull: upload" "$code Retry-After '$ra' $(head -c 300 "$TMP/u1")"
fi
rm -f "$MNT/filler"
code=$(req GET "/v1/jobs/$id/result?format=vtu" "$TMP/r2")
code2=$(submit "$CUBE" model/x-medit "max_iter=2" "$TMP/u2")
[ "$code$code2" = 200202 ] && pass "diskfull: space freed: the conversion (200) and a new upload (202) succeed" ||
    fail "diskfull: after freeing" "conversion $code upload $code2"
stop_qdcd || fail "diskfull: stop" "exit $?"
exit 0
