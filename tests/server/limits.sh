#!/bin/sh
# limits.sh - access and limits: bearer tokens (stored hashed; jobs private to
# their token), 429 + Retry-After on a full queue, Idempotency-Key replay and
# misuse, 409 before the result exists, cancel and delete, retention -> 410,
# graceful SIGTERM with a parked long-poll and a running job, and refusing a
# public address without tokens.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

BIG=$(devmesh cube_h0.1_lowq)
SMALL=$(devmesh bunny_low_10k)
$MT qmesh "$BIG" "$TMP/big.qmesh"
$MT qmesh "$SMALL" "$TMP/small.qmesh"
QM=application/vnd.qdc.mesh
{
    echo "# qdcd tokens: SHA-256 of each bearer token"
    "$QDCD" --hash-token alpha-secret
    echo "sha256:$("$QDCD" --hash-token beta-secret)"
} > "$TMP/tokens"
A="Authorization: Bearer alpha-secret"
B="Authorization: Bearer beta-secret"
if ! grep -q alpha "$TMP/tokens" && grep -q "^$(printf %s alpha-secret | sha256sum | cut -c1-64)$" "$TMP/tokens"; then
    pass "tokens file holds only hashes (--hash-token = sha256sum)"
else
    fail "tokens file" "$(cat "$TMP/tokens")"
fi

start_qdcd "$TMP/d" --workers 1 --max-queued 2 --retention 4 --shutdown-grace 1 --tokens "$TMP/tokens" ||
    { fail "start" "$(tail -3 "$TMP/d.log")"; exit 1; }

code=$(submit "$TMP/small.qmesh" $QM "" "$TMP/out")
[ "$code" = 401 ] && [ "$(hdr "$TMP/out" WWW-Authenticate)" = 'Bearer realm="qdcd"' ] &&
    pass "no token -> 401 with WWW-Authenticate" || fail "no token" "$code"
code=$(req GET /v1/jobs "$TMP/out" -H "Authorization: Bearer wrong")
[ "$code" = 401 ] && pass "unknown token -> 401" || fail "unknown token" "$code"
[ "$(req GET /livez "$TMP/out")" = 200 ] && pass "/livez needs no token" || fail "livez" "token required"

# job 1 runs until it is cancelled below (a fixed amount of work could end
# before the checks that need it running on a busy machine); jobs 2 and 3
# wait; job 4 finds the queue full
c1=$(submit "$TMP/big.qmesh" $QM "max_iter=10000&finish=0&tol_move=0&mode=literal" "$TMP/j1" -H "$A")
id1=$(jf "$TMP/j1" .id)
curl -s -m 30 -H "$A" "$URL/v1/jobs/$id1/progress?after=-1&wait=20" > /dev/null
c2=$(submit "$TMP/small.qmesh" $QM "max_iter=2" "$TMP/j2" -H "$A")
c3=$(submit "$TMP/small.qmesh" $QM "max_iter=3" "$TMP/j3" -H "$A")
c4=$(submit "$TMP/small.qmesh" $QM "max_iter=4" "$TMP/j4" -H "$A")
id2=$(jf "$TMP/j2" .id)
id3=$(jf "$TMP/j3" .id)
if [ "$c1$c2$c3" = 202202202 ] && [ "$c4" = 429 ] && [ "$(hdr "$TMP/j4" Retry-After)" = 5 ] &&
    [ "$(jf "$TMP/j4" .max_queued)" = 2 ] && [ "$(hdr "$TMP/j4" Content-Type)" = application/problem+json ]; then
    pass "queue full: 3rd waiting job -> 429, Retry-After: 5, problem with max_queued 2"
else
    fail "429" "codes $c1 $c2 $c3 $c4 $(head -c 200 "$TMP/j4")"
fi

# A refusal decided from the headers reaches a client that sends its whole body
# before reading (Python's http.client and urllib do; so does curl under 1 MB):
# the daemon reads and drops the body first, for a close with bytes unread is
# a reset, seen as "broken pipe" instead of the 429 and its Retry-After.
head -c 16000000 /dev/urandom > "$TMP/junk.bin"
python3 - "$PORT" "$TMP/junk.bin" "$A" > "$TMP/early" 2>&1 << 'EOF'
import http.client, sys
port, body, auth = int(sys.argv[1]), open(sys.argv[2], "rb").read(), sys.argv[3]
for hdrs in ({"Authorization": auth.split(": ", 1)[1]}, {}):
    for _ in range(4):
        hdrs["Content-Type"] = "model/x-medit"
        c = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
        try:
            c.request("POST", "/v1/jobs?max_iter=1", body=body, headers=hdrs)
            r = c.getresponse()
            print(r.status, r.getheader("Retry-After") or "-", r.getheader("Content-Type"))
            r.read()
        except OSError as e:
            print("error", type(e).__name__)
        c.close()
EOF
want=$(printf '429 5 application/problem+json\n%.0s' 1 2 3 4; printf '401 - application/problem+json\n%.0s' 1 2 3 4)
if [ "$(cat "$TMP/early")" = "$want" ]; then
    pass "refused while the 16 MB body was still coming (full queue, no token; Python http.client): 4 x 429 with Retry-After, 4 x 401, no reset"
else
    fail "refusal before the body" "$(tr '\n' ';' < "$TMP/early")"
fi
up=$(curl -s -o "$TMP/j5" -w '%{http_code} %{size_upload}' -H "$A" -H "Content-Type: model/x-medit" \
    -H "Expect: 100-continue" --data-binary "@$TMP/junk.bin" "$URL/v1/jobs?max_iter=1")
[ "$up" = "429 0" ] && pass "with Expect: 100-continue the 429 comes before any byte of the body (curl uploaded 0 bytes)" ||
    fail "Expect: 100-continue" "status and bytes uploaded: $up"

# a long-poll on a queued job with nothing new returns after wait= with the same state
# (the upper bound is 1 s plus 20 times a plain GET of the same job, timed here)
s0=$(date +%s%N)
curl -s -m 10 -H "$A" -o /dev/null "$URL/v1/jobs/$id3"
base=$((($(date +%s%N) - s0) / 1000000))
s0=$(date +%s%N)
curl -s -m 60 -H "$A" "$URL/v1/jobs/$id3/progress?after=-1&wait=1" > "$TMP/p3"
ms=$((($(date +%s%N) - s0) / 1000000))
if [ "$(jf "$TMP/p3" .state)" = queued ] && [ "$(jf "$TMP/p3" .count)" = 0 ] && [ $ms -ge 950 ] &&
    [ $ms -lt $((1500 + 20 * base)) ]; then
    pass "long-poll wait=1 on a queued job: unchanged state after $ms ms (a plain GET: $base ms)"
else
    fail "long-poll timeout" "$ms ms $(cat "$TMP/p3")"
fi
code=$(req GET "/v1/jobs/$id1/result" "$TMP/out" -H "$A")
[ "$code" = 409 ] && [ "$(hdr "$TMP/out" Retry-After)" = 2 ] && [ "$(jf "$TMP/out" .state)" = running ] &&
    pass "result while running -> 409 + Retry-After" || fail "409" "$code $(head -c 200 "$TMP/out")"

# token isolation
cb=$(req GET "/v1/jobs/$id1" "$TMP/b1" -H "$B")
cbp=$(req GET "/v1/jobs/$id1/progress" "$TMP/b2" -H "$B")
cbc=$(req POST "/v1/jobs/$id1:cancel" "$TMP/b3" -H "$B")
cbd=$(req DELETE "/v1/jobs/$id1" "$TMP/b4" -H "$B")
req GET /v1/jobs "$TMP/bl" -H "$B" > /dev/null
req GET /v1/jobs "$TMP/al" -H "$A" > /dev/null
if [ "$cb$cbp$cbc$cbd" = 404404404404 ] && [ "$(jq '.jobs | length' "$TMP/bl")" = 0 ] &&
    [ "$(jq '.jobs | length' "$TMP/al")" = 3 ] && [ "$(req GET "/v1/jobs/$id1" "$TMP/a1" -H "$A")" = 200 ]; then
    pass "token isolation: B gets 404 on A's job (get, progress, cancel, delete) and lists 0; A lists 3"
else
    fail "token isolation" "$cb $cbp $cbc $cbd lists B $(jq '.jobs | length' "$TMP/bl") A $(jq '.jobs | length' "$TMP/al")"
fi

# cancel a queued job: done at once; long-polls on it end
cc=$(req POST "/v1/jobs/$id3:cancel" "$TMP/c3" -H "$A")
curl -s -m 5 -H "$A" "$URL/v1/jobs/$id3/progress?after=-1&wait=4" > "$TMP/p3"
if [ "$cc" = 200 ] && [ "$(jf "$TMP/c3" .state)" = cancelled ] && [ "$(jf "$TMP/c3" .done)" = true ] &&
    [ "$(jf "$TMP/p3" .done)" = true ]; then
    pass "cancel queued job: 200, cancelled and done at once"
else
    fail "cancel queued" "$cc $(head -c 200 "$TMP/c3")"
fi

# Idempotency-Key: same key + same request -> same job; different body -> 422
K="Idempotency-Key: run-42"
ci1=$(submit "$TMP/small.qmesh" $QM "max_iter=2" "$TMP/i1" -H "$A" -H "$K")
ci2=$(submit "$TMP/small.qmesh" $QM "max_iter=2" "$TMP/i2" -H "$A" -H "$K")
ci3=$(submit "$TMP/big.qmesh" $QM "max_iter=2" "$TMP/i3" -H "$A" -H "$K")
ci4=$(submit "$TMP/small.qmesh" $QM "max_iter=3" "$TMP/i4" -H "$A" -H "$K")
ci5=$(submit "$TMP/small.qmesh" $QM "max_iter=2" "$TMP/i5" -H "$B" -H "$K")
idk=$(jf "$TMP/i1" .id)
if [ "$ci1$ci2" = 202202 ] && [ "$(jf "$TMP/i2" .id)" = "$idk" ] && [ "$(hdr "$TMP/i2" Idempotent-Replayed)" = true ] &&
    [ "$ci3$ci4" = 422422 ] && [ "$(jf "$TMP/i3" .job)" = "$idk" ] && [ "$ci5" = 429 ]; then
    pass "Idempotency-Key: replay -> same job $idk (even with the queue full), other body or options -> 422; the key is per token"
else
    fail "Idempotency-Key" "$ci1 $ci2 $ci3 $ci4 $ci5 ids $idk $(jf "$TMP/i2" .id)"
fi

# cancel the running job: the worker stops at the next iteration
cr=$(req POST "/v1/jobs/$id1:cancel" "$TMP/c1" -H "$A")
st1=$(poll_all "$id1" "$A")
if [ "$cr" = 200 ] && [ "$(jf "$TMP/c1" .cancel_requested)" = true ] && [ "$st1" = cancelled ]; then
    pass "cancel running job: cancel_requested, then cancelled after $(wc -l < "$TMP/seqs.$id1") records"
else
    fail "cancel running" "$cr state $st1"
fi

# job 2 runs to the end; its result expires after --retention 4
st2=$(poll_all "$id2" "$A")
r1=$(req GET "/v1/jobs/$id2/result" "$TMP/r2" -H "$A")
[ "$st2" = succeeded ] && [ "$r1" = 200 ] && pass "job 2 succeeded, result 200" || fail "job 2" "$st2 $r1"
# wait for the expiry (polled, up to 120 s), then check every part of it
n=0
while { [ "$(req GET "/v1/jobs/$id2/result" "$TMP/g" -H "$A")" = 200 ] ||
    [ -e "$TMP/d/jobs/$id2/result.qmesh" ]; } && [ $n -lt 1200 ]; do
    sleep 0.1
    n=$((n + 1))
done
r2=$(req GET "/v1/jobs/$id2/result" "$TMP/g" -H "$A")
r3=$(req GET "/v1/jobs/$id2/report" "$TMP/g2" -H "$A")
req GET "/v1/jobs/$id2" "$TMP/g3" -H "$A" > /dev/null
[ "$r2$r3" = 410410 ] && [ "$(jf "$TMP/g3" .expired)" = true ] && [ ! -e "$TMP/d/jobs/$id2/result.qmesh" ] &&
    pass "retention: result and report -> 410 Gone, files removed, job still listed as expired" ||
    fail "retention" "$r2 $r3 $(head -c 200 "$TMP/g")"

cd_=$(req DELETE "/v1/jobs/$id2" "$TMP/del" -H "$A")
cg=$(req GET "/v1/jobs/$id2" "$TMP/del2" -H "$A")
[ "$cd_$cg" = 204404 ] && [ ! -e "$TMP/d/jobs/$id2" ] && pass "DELETE -> 204, then 404, directory gone" || fail "delete" "$cd_ $cg"

# per-job time limit: a job asking for 200 iterations stops at time_limit=1
# with the best mesh so far
ct=$(submit "$TMP/big.qmesh" $QM "max_iter=200&finish=0&tol_move=0&mode=literal&time_limit=1" "$TMP/jt" -H "$A")
idt=$(jf "$TMP/jt" .id)
stt=$(poll_all "$idt" "$A")
req GET "/v1/jobs/$idt" "$TMP/jt2" -H "$A" > /dev/null
if [ "$ct" = 202 ] && [ "$stt" = succeeded ] && [ "$(jf "$TMP/jt2" .stop_reason)" = time-limit ] &&
    [ "$(jf "$TMP/jt2" .options.time_limit)" = 1 ] && [ "$(req GET "/v1/jobs/$idt/result" "$TMP/jt3" -H "$A")" = 200 ]; then
    pass "time_limit=1: stopped by the time limit after $(jf "$TMP/jt2" .iterations) records, result served"
else
    fail "time limit" "$ct $stt $(jq -c '[.stop_reason, .options.time_limit, .iterations]' "$TMP/jt2")"
fi

# DELETE a running job: gone at once; its worker stops and removes the files
cdr=$(submit "$TMP/big.qmesh" $QM "max_iter=200&finish=0&tol_move=0&mode=literal" "$TMP/jd" -H "$A")
idd=$(jf "$TMP/jd" .id)
curl -s -m 30 -H "$A" "$URL/v1/jobs/$idd/progress?after=0&wait=20" > /dev/null
cd1=$(req DELETE "/v1/jobs/$idd" "$TMP/jd1" -H "$A")
cd2=$(req GET "/v1/jobs/$idd" "$TMP/jd2" -H "$A")
n=0
while [ -e "$TMP/d/jobs/$idd" ] && [ $n -lt 100 ]; do sleep 0.1; n=$((n + 1)); done
busy=$(curl -s -H "$A" "$URL/metrics" | awk '$1 == "qdcd_workers_busy" { print $2 }')
if [ "$cdr$cd1$cd2" = 202204404 ] && [ ! -e "$TMP/d/jobs/$idd" ] && [ "$busy" = 0 ]; then
    pass "DELETE running job: 204, then 404; the worker stopped and removed its files"
else
    fail "delete running" "$cdr $cd1 $cd2 dir $(ls "$TMP/d/jobs/$idd" 2>&1 | head -2) busy $busy"
fi

# graceful shutdown: a parked long-poll is answered, the running job goes back to the queue
cj=$(submit "$TMP/big.qmesh" $QM "max_iter=5000&finish=0&tol_move=0&mode=literal" "$TMP/j5" -H "$A")
id5=$(jf "$TMP/j5" .id)
curl -s -m 30 -H "$A" "$URL/v1/jobs/$id5/progress?after=0&wait=20" > /dev/null
curl -s -m 30 -H "$A" "$URL/v1/jobs/$id5/progress?after=100000&wait=25" > "$TMP/parked" &
cpid=$!
n=0
while [ "$(curl -s -H "$A" "$URL/metrics" | awk '$1 == "qdcd_parked_connections" { print $2 }')" != 1 ] && [ $n -lt 600 ]; do
    sleep 0.1
    n=$((n + 1))
done
s0=$(date +%s%N)
curl -s -m 10 -H "$A" -o /dev/null "$URL/v1/jobs/$id5"
base=$((($(date +%s%N) - s0) / 1000000))
s0=$(date +%s%N)
stop_qdcd
rc=$?
ms=$((($(date +%s%N) - s0) / 1000000))
wait $cpid
if [ $rc = 0 ] && [ "$(jf "$TMP/parked" .state)" = running ] && [ $ms -lt $((4000 + 50 * base)) ]; then
    pass "SIGTERM: parked long-poll answered (state running), exit 0 in $ms ms"
else
    fail "SIGTERM" "rc $rc, $ms ms, parked: $(head -c 200 "$TMP/parked")"
fi
t_restart=$(date +%s)
start_qdcd "$TMP/d" --workers 1 --tokens "$TMP/tokens" || { fail "restart" "$(tail -3 "$TMP/d.log")"; exit 1; }
curl -s -m 30 -H "$A" "$URL/v1/jobs/$id5/progress?after=0&wait=20" > /dev/null
req GET "/v1/jobs/$id5" "$TMP/j5b" -H "$A" > /dev/null
# running, or already done on a fast machine: either way started again after the restart
st5=$(jf "$TMP/j5b" .state)
started5=$(jf "$TMP/j5b" .started | cut -d. -f1)
if { [ "$st5" = running ] || [ "$st5" = succeeded ]; } && [ "$(jf "$TMP/j5b" .attempts)" = 1 ] &&
    [ "${started5:-0}" -ge "$t_restart" ]; then
    pass "after restart the released job runs again, attempt count unchanged (1)"
else
    fail "released job" "$(head -c 300 "$TMP/j5b")"
fi
req POST "/v1/jobs/$id5:cancel" "$TMP/c5" -H "$A" > /dev/null
stop_qdcd || fail "SIGTERM 2" "exit status $?"

# uploads in flight together while the queue fills: the limit holds at commit
# (before, each passed the check made when its headers arrived: 6 of 6 accepted)
if start_qdcd "$TMP/q" --workers 1 --max-queued 2; then
    submit "$TMP/big.qmesh" $QM "max_iter=400&finish=0&tol_move=0&mode=literal" "$TMP/q1" > /dev/null
    curl -s -m 30 "$URL/v1/jobs/$(jf "$TMP/q1" .id)/progress?after=-1&wait=20" > /dev/null
    pids=
    for i in 1 2 3 4 5 6; do # ~0.7 MB each at 400 kB/s: all in flight at once
        submit "$TMP/big.qmesh" $QM "max_iter=1" "$TMP/qc$i" --limit-rate 400k > "$TMP/qc$i.code" &
        pids="$pids $!"
    done
    wait $pids # not a bare wait: the daemon is a child too
    n202=0
    n429=0
    for i in 1 2 3 4 5 6; do
        case $(cat "$TMP/qc$i.code") in 202) n202=$((n202 + 1)) ;; 429) n429=$((n429 + 1)) ;; esac
    done
    req GET /metrics "$TMP/qm" > /dev/null
    queued=$(awk '$1 == "qdcd_jobs{state=\"queued\"}" {print $2}' "$TMP/qm")
    if [ "$n202" = 2 ] && [ "$n429" = 4 ] && [ "${queued:-x}" = 2 ]; then
        pass "6 concurrent uploads, max-queued 2: 2 accepted, 4 refused with 429, 2 queued"
    else
        fail "concurrent 429" "202: $n202, 429: $n429, queued: ${queued:-?} ($(grep -h 'qdcd_jobs{' "$TMP/qm" | tr '\n' ' '))"
    fi
    req POST "/v1/jobs/$(jf "$TMP/q1" .id):cancel" "$TMP/qx" > /dev/null
    stop_qdcd || fail "SIGTERM 3" "exit status $?"
else
    fail "start (queue)" "$(tail -3 "$TMP/q.log")"
fi

# public address: refused without tokens, accepted with --insecure
"$QDCD" --listen 0.0.0.0:0 --data "$TMP/p" > "$TMP/pub.out" 2>&1
rc=$?
[ $rc = 2 ] && grep -q -- --insecure "$TMP/pub.out" && pass "non-loopback listen without tokens refused (exit 2, mentions --insecure)" ||
    fail "non-loopback" "rc $rc $(cat "$TMP/pub.out")"
if start_qdcd "$TMP/p" --listen 0.0.0.0:0 --insecure; then
    pass "--insecure: listens on 0.0.0.0"
    stop_qdcd
else
    fail "--insecure" "$(tail -2 "$TMP/p.log")"
fi
"$QDCD" --help > "$TMP/help"
missing=""
for o in listen port-file data workers tokens hash-token insecure max-body max-json max-vertices max-tets \
    max-queued job-time-limit retention max-wait max-attempts max-connections connection-timeout lease \
    shutdown-grace bderr-samples verbose help; do
    grep -q -- "--$o" "$TMP/help" || missing="$missing $o"
done
[ -z "$missing" ] && pass "--help documents every option" || fail "--help" "missing:$missing"
exit $((NFAIL > 0))
