#!/bin/sh
# faults/http.sh - smaller protocol faults: HEAD of an event stream has no
# body; with --tokens, /metrics and /readyz (job counts of every owner) need a
# token unless --public-metrics; a tokens file that is not a small regular
# file (/dev/zero used to hang the start) is refused at once; two
# Content-Lengths, or Content-Length with Transfer-Encoding, are refused with
# 400; problem types are URIs this daemon serves.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
"$QDCD" --hash-token tok > "$TMP/tokens"
A='Authorization: Bearer tok'
start_qdcd "$TMP/d" --workers 1 --tokens "$TMP/tokens" || { fail "http: start" "$(tail -3 "$TMP/d.log")"; exit 1; }
raw() { # raw REQUEST-TEXT: the whole answer, read until the server closes (3 s max)
    "$PY" - "$PORT" "$1" << 'PYEOF'
import socket, sys
s = socket.create_connection(("127.0.0.1", int(sys.argv[1])), timeout=3)
s.sendall(sys.argv[2].replace("\\r\\n", "\r\n").encode())
data = b""
try:
    while True:
        b = s.recv(65536)
        if not b:
            break
        data += b
except socket.timeout:
    pass
sys.stdout.write(data.decode("latin-1"))
PYEOF
}
c=$(submit "$ROOT/tests/data/sample/cube.mesh" model/x-medit "max_iter=2" "$TMP/j" -H "$A")
id=$(jf "$TMP/j" .id)
poll_all "$id" "$A" > /dev/null
out=$(raw "HEAD /v1/jobs/$id/events HTTP/1.1\r\nHost: 127.0.0.1\r\nAuthorization: Bearer tok\r\nConnection: close\r\n\r\n")
body=$(printf '%s' "$out" | tr -d '\r' | sed '1,/^$/d')
case $out in
"HTTP/1.1 200"*) [ -z "$body" ] && pass "http: HEAD /v1/jobs/ID/events: 200, no body" ||
    fail "http: HEAD events" "a body: $(printf '%s' "$body" | head -c 100)" ;;
*) fail "http: HEAD events" "$(printf '%s' "$out" | head -1)" ;;
esac
m1=$(curl -s -o /dev/null -w '%{http_code}' "$URL/metrics")
r1=$(curl -s -o /dev/null -w '%{http_code}' "$URL/readyz")
m2=$(curl -s -o /dev/null -w '%{http_code}' -H "$A" "$URL/metrics")
l1=$(curl -s -o /dev/null -w '%{http_code}' "$URL/livez")
[ "$m1$r1$m2$l1" = 401401200200 ] && pass "http: with --tokens, /metrics and /readyz need a token (401 without, 200 with); /livez stays open" ||
    fail "http: metrics behind tokens" "metrics $m1 readyz $r1 with token $m2 livez $l1"
for h in "Content-Length: 5\r\nContent-Length: 6" "Content-Length: 5\r\nTransfer-Encoding: chunked"; do
    out=$(raw "POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nAuthorization: Bearer tok\r\nContent-Type: model/x-medit\r\n$h\r\n\r\nhello")
    case $out in
    "HTTP/1.1 400"*) pass "http: $(printf '%s' "$h" | sed 's/\\r\\n/ + /'): 400" ;;
    *) fail "http: framing $h" "$(printf '%s' "$out" | head -1)" ;;
    esac
done
code=$(submit "$ROOT/tests/data/sample/cube.mesh" model/x-medit "mu=0" "$TMP/bad" -H "$A")
type=$(jf "$TMP/bad" .type)
page=$(curl -s -w ' %{http_code}' "$URL$type")
case $type:$page in
/problems/invalid-option:*"200") pass "http: problem type $type is served by the daemon (200)" ;;
*) fail "http: problem type" "type '$type': $(printf '%s' "$page" | tail -c 80)" ;;
esac
stop_qdcd || fail "http: stop" "exit $?"
start_qdcd "$TMP/d2" --workers 1 --tokens "$TMP/tokens" --public-metrics ||
    { fail "http: start --public-metrics" "$(tail -3 "$TMP/d2.log")"; exit 1; }
m=$(curl -s -o /dev/null -w '%{http_code}' "$URL/metrics")
j=$(curl -s -o /dev/null -w '%{http_code}' "$URL/v1/jobs")
[ "$m$j" = 200401 ] && pass "http: --public-metrics: /metrics open, /v1/jobs still needs the token" ||
    fail "http: --public-metrics" "metrics $m jobs $j"
# Clients gone in the middle of a body, their FIN sent with their last bytes:
# each connection (and its upload file) is closed at once, not after the idle
# timeout (120 s): half a mesh and close, 5 kB of a refused 100 kB body and
# close, headers alone and close; 100 of each.
gzip -dc "$DEV/cube_h0.1_good.mesh.gz" > "$TMP/half.mesh"
"$PY" - "$PORT" "$QPID" "$TMP/half.mesh" "$A" > "$TMP/cut" << 'PYEOF'
import os, socket, sys, time
port, pid, body, auth = int(sys.argv[1]), sys.argv[2], open(sys.argv[3], "rb").read(), sys.argv[4]
fds = lambda: len(os.listdir("/proc/%s/fd" % pid))
base = fds()
heads = {
    "half a mesh": (b"model/x-medit", len(body), body[:len(body) // 2]),
    "5 kB of a refused body": (b"image/png", 100000, b"x" * 5000),
    "headers only": (b"model/x-medit", 1000, b""),
}
for what, (ctype, n, part) in heads.items():
    for _ in range(100):
        s = socket.create_connection(("127.0.0.1", port))
        s.sendall(b"POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\n%s\r\nContent-Type: %s\r\n"
                  b"Content-Length: %d\r\n\r\n" % (auth.encode(), ctype, n) + part)
        s.close()
        time.sleep(0.01)
    t0 = time.time()
    # closed long before the idle timeout (120 s): allow 30 s on a busy machine
    while fds() > base and time.time() - t0 < 30:
        time.sleep(0.05)
    print("%s: fds %d -> %d in %.1f s" % (what, base, fds(), time.time() - t0))
PYEOF
if [ "$(grep -c 'fds \([0-9]*\) -> \1 ' "$TMP/cut")" = 3 ]; then
    pass "http: 300 uploads cut short (FIN with the last bytes): every connection closed at once ($(tr '\n' ';' < "$TMP/cut"))"
else
    fail "http: uploads cut short" "$(tr '\n' ';' < "$TMP/cut")"
fi
stop_qdcd
t0=$(date +%s)
timeout 10 "$QDCD" --listen 127.0.0.1:0 --data "$TMP/d3" --tokens /dev/zero > "$TMP/z.log" 2>&1
rc=$?
[ $rc = 2 ] && [ $(($(date +%s) - t0)) -le 2 ] && grep -q 'not a regular file' "$TMP/z.log" &&
    pass "http: --tokens /dev/zero: refused at once (exit 2): $(head -c 100 "$TMP/z.log")" ||
    fail "http: --tokens /dev/zero" "exit $rc after $(($(date +%s) - t0)) s: $(head -c 200 "$TMP/z.log")"
exit 0
