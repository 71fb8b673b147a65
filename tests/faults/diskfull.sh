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
# a job that finishes while the disk is full: its results (and its row) are
# written once space is back; it is never failed for good
$MT qmesh "$CUBE" "$TMP/c.qmesh"
code=$(submit "$TMP/c.qmesh" application/vnd.qdc.mesh "max_iter=400&finish=0&tol_move=0&mode=literal&ls_halvings=0" "$TMP/u3")
id3=$(jf "$TMP/u3" .id)
curl -s -m 30 "$URL/v1/jobs/$id3/progress?after=0&wait=20" > /dev/null
dd if=/dev/zero of="$MNT/filler" bs=1M count=64 2> /dev/null
sleep 4
st_full=$(curl -s "$URL/v1/jobs/$id3" | jq -r .state)
rm -f "$MNT/filler"
st=$(poll_all "$id3")
code=$(req GET "/v1/jobs/$id3/result?format=medit" "$TMP/r3.mesh")
if [ "$st" = succeeded ] && [ "$code" = 200 ] && [ "$st_full" != failed ] && "$BIN/qdc" quality "$TMP/r3.mesh" > /dev/null 2>&1; then
    pass "diskfull: a job ending on a full disk waited ($st_full) and succeeded once space was freed"
else
    fail "diskfull: job on a full disk" "while full: $st_full, then $st, result $code $(tail -3 "$MNT/d.log" | tr '\n' ' ')"
fi
stop_qdcd || fail "diskfull: stop" "exit $?"
exit 0
