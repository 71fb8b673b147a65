#!/bin/sh
# make_run.sh - a fresh clone of HEAD: `make run` (deps check, release build,
# scripts/run.sh) serves /livez within 60 s of qdcd's start (the build is
# not timed: it takes what the machine gives it), prints where it listens and a
# ready-to-paste curl command, and that command submits the bundled sample;
# the web console it prints the address of is served.
. "$(dirname "$0")/../lib.sh"
MPID=
trap 'if [ -n "$MPID" ]; then kill -TERM -"$MPID" 2> /dev/null; fi; rm -rf "$TMP"' EXIT

# a free port (run.sh takes QDCD_LISTEN; port 0 would not print a usable URL)
P=$($PY -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
git clone -q "$ROOT" "$TMP/clone" || { fail "clone" "git clone failed"; exit 1; }
cd "$TMP/clone" || exit 1
t0=$(date +%s)
# its own process group (setsid), so the whole make -> run.sh -> qdcd tree stops
QDCD_LISTEN=127.0.0.1:$P setsid make run > "$TMP/run.log" 2>&1 &
MPID=$!
# The build takes as long as the machine lets it: no clock runs on it, only
# make must stay alive. run.sh prints "qdcd listens on" just before it execs
# qdcd; the start-up clock starts there.
while ! grep -q "^qdcd listens on" "$TMP/run.log" 2> /dev/null; do
    if ! kill -0 "$MPID" 2> /dev/null; then
        fail "make run" "make ended before qdcd started: $(tail -5 "$TMP/run.log" | tr '\n' ' ')"
        exit 1
    fi
    sleep 0.2
done
t1=$(date +%s)
build=$((t1 - t0))
up=
while [ $(($(date +%s) - t1)) -lt 60 ]; do
    if curl -sf -m 2 "http://127.0.0.1:$P/livez" > /dev/null 2>&1; then
        up=$(($(date +%s) - t1))
        break
    fi
    kill -0 "$MPID" 2> /dev/null || break
    sleep 0.2
done
if [ -n "$up" ]; then
    pass "make run in a fresh clone: /livez answers $up s after qdcd starts (build $build s)"
else
    fail "make run" "no /livez within 60 s of qdcd's start: $(tail -5 "$TMP/run.log" | tr '\n' ' ')"
    exit 1
fi
if grep -q "listens on http://127.0.0.1:$P" "$TMP/run.log"; then
    pass "make run prints where qdcd listens"
else
    fail "make run address" "$(grep -v '^cc ' "$TMP/run.log" | head -5)"
fi
# the printed submit command, pasted as is (from the clone's top directory)
cmd=$(grep -m 1 "curl .*POST.*/v1/jobs" "$TMP/run.log" | sed 's/^ *//')
code=$(eval "$cmd" 2> /dev/null | head -1 | awk '{ print $2 }')
if [ "$code" = 202 ]; then
    pass "make run's curl command submits the sample mesh: 202"
else
    fail "make run curl" "'$cmd' -> '$code'"
fi
# the web console, compiled in: the page it prints, and its script
url=$(sed -n 's/^Web console: //p' "$TMP/run.log")
if [ "$url" = "http://127.0.0.1:$P/" ] &&
    curl -sf -m 5 "$url" | grep -q '<script src="/ui/app.js"' &&
    curl -sf -m 5 "${url}ui/app.js" | cmp -s - web/app.js; then
    pass "make run prints the web console's address, which serves web/ (compiled in)"
else
    fail "make run web console" "'$url'"
fi
kill -TERM -"$MPID" 2> /dev/null
wait "$MPID"
MPID=
exit 0
