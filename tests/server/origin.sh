#!/bin/sh
# origin.sh - a local qdcd is not open to every web page: a foreign Host
# (DNS rebinding) gets 403 on every request, a POST or DELETE from a page of
# another origin (Origin, Sec-Fetch-Site: cross-site; a text/plain POST needs
# no preflight) gets 403 and creates nothing, the daemon's own origin and
# the ones named with --allowed-origins / --allowed-hosts pass, every reply
# says nosniff, control bytes in query values get 400, and a public address
# without tokens needs --insecure and is warned about.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

CUBE=$ROOT/tests/data/sample/cube.mesh

start_qdcd "$TMP/d" --workers 1 --allowed-hosts qdc.example.com \
    --allowed-origins https://console.example ||
    { fail "start" "$(tail -3 "$TMP/d.log")"; exit 1; }

# expect403 NAME SLUG STATUS
expect403() {
    if [ "$3" = 403 ] && [ "$(hdr "$TMP/out" Content-Type)" = application/problem+json ] &&
        [ "$(jf "$TMP/out" .type)" = "/problems/$2" ] && [ "$(jf "$TMP/out" .status)" = 403 ]; then
        pass "$1: 403 $2"
    else
        fail "$1" "status $3, body $(head -c 300 "$TMP/out")"
    fi
}
njobs() { curl -s "$URL/v1/jobs" | jq '.jobs | length'; }

# --- Host ----------------------------------------------------------------
code=$(req GET /v1/jobs "$TMP/out" -H "Host: evil.example:$PORT")
expect403 "GET /v1/jobs with Host: evil.example (DNS rebinding)" host-not-allowed "$code"
code=$(req GET /livez "$TMP/out" -H "Host: localhost.evil.example:$PORT")
expect403 "GET /livez with Host: localhost.evil.example" host-not-allowed "$code"
code=$(req GET / "$TMP/out" -H "Host: evil.example")
expect403 "the console's page with a foreign Host" host-not-allowed "$code"
ok=1
for h in "127.0.0.1:$PORT" "localhost:$PORT" "LOCALHOST" "qdc.example.com" "qdc.example.com:443" "[::1]:$PORT" "10.0.0.7:$PORT"; do
    c=$(req GET /v1/jobs "$TMP/out" -H "Host: $h")
    [ "$c" = 200 ] || { ok=0; fail "Host: $h" "$c"; }
done
[ $ok = 1 ] && pass "Host: loopback names, IP addresses and --allowed-hosts names get 200"

# --- Origin ----------------------------------------------------------------
before=$(njobs)
for h in "Origin: https://evil.example|cross-origin text/plain POST (no preflight in a browser)" \
    "Origin: http://127.0.0.1:$((PORT + 1))|POST from another port of the same host" \
    "Origin: null|POST with Origin: null (sandboxed page, file://)" \
    "Sec-Fetch-Site: cross-site|POST with Sec-Fetch-Site: cross-site and no Origin"; do
    code=$(req POST /v1/jobs "$TMP/out" --data-binary @"$CUBE" -H "Content-Type: text/plain" -H "${h%%|*}")
    expect403 "${h#*|}" cross-origin "$code"
done
after=$(njobs)
[ "$before" = "$after" ] && pass "no job was created by the refused POSTs ($after jobs)" ||
    fail "refused POSTs created jobs" "$before -> $after"

code=$(req POST "/v1/jobs?max_iter=1" "$TMP/out" --data-binary @"$CUBE" -H "Content-Type: text/plain" \
    -H "Origin: http://127.0.0.1:$PORT" -H "Sec-Fetch-Site: same-origin")
id=$(jf "$TMP/out" .id)
[ "$code" = 202 ] && pass "POST from the daemon's own origin (the console): 202" ||
    fail "same-origin POST" "$code $(head -c 300 "$TMP/out")"
code=$(req POST "/v1/jobs?max_iter=1" "$TMP/out" --data-binary @"$CUBE" -H "Content-Type: text/plain" \
    -H "Origin: https://qdc.example.com" -H "Host: qdc.example.com")
[ "$code" = 202 ] && pass "POST through a TLS proxy that keeps the Host (https://qdc.example.com): 202" ||
    fail "proxied POST" "$code $(head -c 300 "$TMP/out")"
code=$(req POST "/v1/jobs?max_iter=1" "$TMP/out" --data-binary @"$CUBE" -H "Content-Type: text/plain" \
    -H "Origin: https://console.example" -H "Sec-Fetch-Site: cross-site")
[ "$code" = 202 ] && pass "POST from an origin named with --allowed-origins: 202" ||
    fail "allowed origin" "$code $(head -c 300 "$TMP/out")"
[ "$(wait_done "$id")" = succeeded ] || fail "job" "$id did not succeed"
code=$(req DELETE "/v1/jobs/$id" "$TMP/out" -H "Origin: https://evil.example")
expect403 "cross-origin DELETE" cross-origin "$code"
code=$(req POST "/v1/jobs/$id:cancel" "$TMP/out" -H "Sec-Fetch-Site: cross-site" -H "Origin: https://evil.example")
expect403 "cross-origin cancel" cross-origin "$code"
code=$(req GET "/v1/jobs/$id" "$TMP/out" -H "Origin: https://evil.example")
[ "$code" = 200 ] && pass "a cross-origin GET is answered (the browser keeps the body from the page: no CORS)" ||
    fail "cross-origin GET" "$code"
code=$(req DELETE "/v1/jobs/$id" "$TMP/out" -H "Origin: http://localhost:$PORT" -H "Host: localhost:$PORT")
[ "$code" = 204 ] && pass "DELETE from the daemon's own origin: 204" || fail "same-origin DELETE" "$code"

# --- nosniff and query values ---------------------------------------------
ok=1
for p in /livez /v1/jobs /v1/options /nope / /metrics "/v1/jobs/$id"; do
    req GET "$p" "$TMP/out" > /dev/null
    [ "$(hdr "$TMP/out" X-Content-Type-Options)" = nosniff ] || { ok=0; fail "nosniff on $p" "$(cat "$TMP/out.h")"; }
done
[ $ok = 1 ] && pass "X-Content-Type-Options: nosniff on API, problem and console replies"
code=$(req POST "/v1/jobs?max_iter=1" "$TMP/out" --data-binary @"$CUBE" -H "Content-Type: model/x-medit")
id=$(jf "$TMP/out" .id)
[ "$(wait_done "$id")" = succeeded ] || fail "job" "$id did not succeed"
for q in "format=json%00medit" "format=json%0Amedit" "x%00y=1" "format=%7F"; do
    code=$(req GET "/v1/jobs/$id/result?$q" "$TMP/out")
    if [ "$code" = 400 ] && [ "$(jf "$TMP/out" .type)" = /problems/invalid-parameter ]; then
        pass "/result?$q: 400 ($(jf "$TMP/out" .detail))"
    else
        fail "/result?$q" "$code $(head -c 200 "$TMP/out")"
    fi
done
code=$(req POST "/v1/jobs?max_iter=5%00abc" "$TMP/out" --data-binary @"$CUBE" -H "Content-Type: model/x-medit")
[ "$code" = 400 ] && pass "upload option with %00: 400" || fail "upload %00" "$code"
stop_qdcd

# --- a public address without tokens ----------------------------------------
"$QDCD" --listen 0.0.0.0:0 --data "$TMP/p" > "$TMP/p.log" 2>&1
rc=$?
[ $rc = 2 ] && grep -q -- "--insecure" "$TMP/p.log" &&
    pass "--listen 0.0.0.0 without --tokens refused (exit 2, names --insecure)" ||
    fail "public address" "rc $rc $(cat "$TMP/p.log")"
"$QDCD" --listen 0.0.0.0:0 --port-file "$TMP/i.port" --data "$TMP/i" --insecure --workers 1 > "$TMP/i.log" 2>&1 &
QPID=$!
i=0
while [ $i -lt 150 ] && ! [ -s "$TMP/i.port" ]; do sleep 0.1; i=$((i + 1)); done
if grep -q "warning: listening on 0.0.0.0 without --tokens" "$TMP/i.log"; then
    pass "--insecure on 0.0.0.0: started with a warning"
else
    fail "--insecure warning" "$(cat "$TMP/i.log")"
fi
stop_qdcd

exit $((NFAIL > 0))
