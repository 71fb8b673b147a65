#!/bin/sh
# gzip.sh - gzip-compressed mesh files of any format: qdc reads FILE.gz (by
# content, whatever the name), writes FILE.gz compressed when asked, refuses a
# truncated one with file:message and exit 2; qdcd takes a gzip body.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
in=$DEV/cube_h0.1_good.mesh.gz
if "$BIN/qdc" optimize "$in" "$TMP/o.vtu.gz" --quiet 2> "$TMP/err" &&
    gzip -t "$TMP/o.vtu.gz" && gzip -dc "$TMP/o.vtu.gz" > "$TMP/o.vtu" &&
    "$PY" -c 'import meshio, sys; m = meshio.read(sys.argv[1]); assert len(m.cells_dict["tetra"]) == 24118' "$TMP/o.vtu"; then
    pass "gzip: qdc reads a .mesh.gz and writes a .vtu.gz that gzip and meshio read (24118 tets)"
else
    fail "gzip: round trip" "$(tail -2 "$TMP/err")"
fi
cp "$in" "$TMP/noext"
"$BIN/qdc" quality "$TMP/noext" > "$TMP/q" 2>&1 && grep -q '24118 tets' "$TMP/q" &&
    pass "gzip: recognized by content without a .gz name" || fail "gzip: by content" "$(head -2 "$TMP/q")"
head -c 2000 "$in" > "$TMP/cut.mesh.gz"
"$BIN/qdc" quality "$TMP/cut.mesh.gz" > /dev/null 2> "$TMP/err"
rc=$?
[ $rc = 2 ] && grep -q "cut.mesh.gz: gzip: the compressed data end too early" "$TMP/err" &&
    pass "gzip: a truncated file: exit 2, $(cat "$TMP/err")" || fail "gzip: truncated" "exit $rc $(cat "$TMP/err")"
start_qdcd "$TMP/d" --workers 1 || { fail "gzip: start qdcd" "$(tail -3 "$TMP/d.log")"; exit 1; }
gzip -c "$ROOT/tests/data/sample/cube.mesh" > "$TMP/c.mesh.gz"
code=$(submit "$TMP/c.mesh.gz" model/x-medit "max_iter=2" "$TMP/j")
st=$(poll_all "$(jf "$TMP/j" .id)")
[ "$code:$st" = 202:succeeded ] && pass "gzip: qdcd takes a gzip-compressed Medit body (202, succeeded)" ||
    fail "gzip: qdcd" "$code $st $(head -c 200 "$TMP/j")"
stop_qdcd || fail "gzip: stop" "exit $?"
exit 0
