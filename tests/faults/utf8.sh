#!/bin/sh
# faults/utf8.sh - problem details are valid UTF-8 whatever the client sent:
# bytes that are not UTF-8 in an unknown ?format=, in a Content-Type, in the
# URL or inside a file are echoed as U+FFFD, never raw (and a cut never splits
# a character), so every problem body parses as strict UTF-8 JSON.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
start_qdcd "$TMP/d" --workers 1 || { fail "utf8: start" "$(tail -3 "$TMP/d.log")"; exit 1; }
CUBE=$ROOT/tests/data/sample/cube.mesh
check_body() { # NAME FILE
    if "$PY" -c 'import json, sys
b = open(sys.argv[1], "rb").read()
d = json.loads(b.decode("utf-8", errors="strict"))
assert "detail" in d' "$2" 2> "$TMP/err"; then
        pass "utf8: $1: valid UTF-8 problem+json ($(head -c 100 "$2" | tr -d '\n'))"
    else
        fail "utf8: $1" "$(head -c 200 "$2" | od -c | head -3 | tr '\n' ' ') $(tail -1 "$TMP/err")"
    fi
}
# a finished job, for ?format=
c=$(submit "$CUBE" model/x-medit "max_iter=2" "$TMP/j")
id=$(jf "$TMP/j" .id)
poll_all "$id" > /dev/null
curl -s -o "$TMP/f1" "$URL/v1/jobs/$id/result?format=%ff%fe%c3"
check_body "unknown ?format= with bytes ff fe c3" "$TMP/f1"
curl -s -o "$TMP/f2" -X POST -H "$(printf 'Content-Type: model/\377\376x')" --data-binary @"$CUBE" "$URL/v1/jobs"
check_body "Content-Type with bytes ff fe" "$TMP/f2"
curl -s -o "$TMP/f3" "$URL/v2/%ff%c3%28"
check_body "URL with bytes ff c3 28" "$TMP/f3"
# a Medit file whose bad token has a multi-byte character across the 60-byte cut
{ sed -n '1,5p' "$CUBE"; printf 'aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa\303\251\303\251\377 0 0 0\n'; sed -n '7,$p' "$CUBE"; } > "$TMP/bad.mesh"
code=$(submit "$TMP/bad.mesh" model/x-medit "" "$TMP/f4")
[ "$code" = 400 ] && check_body "Medit syntax error on non-UTF-8 bytes" "$TMP/f4" || fail "utf8: bad medit" "status $code"
stop_qdcd || fail "utf8: stop" "exit $?"
exit 0
