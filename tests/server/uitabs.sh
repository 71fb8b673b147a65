#!/bin/sh
# uitabs.sh - the web console beyond one job in one tab, in Debian's chromium
# (tests/ui/tabs.mjs, playwright-core and axe-core as for ui.sh): the job list
# found by text, filtered by state and sorted by name, state and date (header
# buttons with aria-sort, a sort menu on a phone); a second tab that follows a
# DELETE by curl (the job page says so, the list drops it), one by another tab
# (BroadcastChannel) and a cancel; two jobs compared side by side (options that
# differ marked, both quality tables, the boundary moved, both histograms),
# axe-core and no column cut at 390 px on the new views; and a job page that
# says the job runs again when its daemon is killed (kill -9) and started again
# on the same port (the SSE stream's `event: restart`).
# UI_BIG=FILE (a ~1M-tet mesh: python3 scripts/corpus.py DIR --tets 1260000
# --only ball-lowq makes one) adds the figures of a finished big job's page:
# first paint, summary and report shown, against a small job's page and
# /livez in the same fresh browser context; its 3D view's first frame and
# frame rates (printed, not judged).
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"
. "$(dirname "$0")/uimods.inc"
SAMPLE=$ROOT/tests/data/sample/cube.mesh
LONG=$(devmesh cube_h0.1_lowq)
SPHERE=$(devmesh sphere_h0.1_lowq)
D=$TMP/d

start_qdcd "$D" --workers 1 || { fail "start" "$(tail -3 "$D.log")"; exit 1; }
P=$PORT
ui_modules || { stop_qdcd; exit $((NFAIL > 0)); }

mkdir -p "$TMP/out"
export UI_MODULES="$MODS" QDC_URL="$URL" UI_OUT="$TMP/out" CHROMIUM SAMPLE LONG SPHERE
node "$ROOT/tests/ui/tabs.mjs" > "$TMP/tabs.out" 2>&1 &
NPID=$!
# the restart: once the page follows a running job (it writes kill-now), the
# daemon dies (kill -9) and comes back on the same port and data directory
i=0
while [ $i -lt 3000 ] && kill -0 $NPID 2> /dev/null && [ ! -e "$TMP/out/kill-now" ]; do
    sleep 0.1
    i=$((i + 1))
done
if [ -e "$TMP/out/kill-now" ]; then
    kill -9 "$QPID"
    wait "$QPID" 2> /dev/null
    "$QDCD" --listen 127.0.0.1:$P --data "$D" --workers 1 >> "$D.log" 2>&1 &
    QPID=$!
    i=0
    while [ $i -lt 150 ] && ! curl -sf -m 2 "$URL/livez" > /dev/null; do
        sleep 0.1
        i=$((i + 1))
    done
    touch "$TMP/out/restarted"
fi
wait $NPID
rc=$?
cat "$TMP/tabs.out"
if [ $rc -ne 0 ] && ! grep -q '^FAIL - ' "$TMP/tabs.out"; then
    fail "tabs.mjs" "exit $rc"
fi
NFAIL=$((NFAIL + $(grep -c '^FAIL - ' "$TMP/tabs.out")))
stop_qdcd || fail "SIGTERM" "exit status $?"

if [ -n "${UI_BIG:-}" ]; then
    start_qdcd "$TMP/b" --workers 1 || { fail "start (big)" "$(tail -3 "$TMP/b.log")"; exit 1; }
    submit "$SAMPLE" model/x-medit "name=cube.mesh" "$TMP/ssub" > /dev/null
    SJ=$(jf "$TMP/ssub" .id)
    code=$(submit "$UI_BIG" model/x-medit "name=$(basename "$UI_BIG")" "$TMP/bsub")
    BJ=$(jf "$TMP/bsub" .id)
    i=0
    while [ $i -lt 1200 ] && [ "$(curl -s "$URL/v1/jobs/$BJ" | jq -r .done)" != true ]; do
        sleep 0.5
        i=$((i + 1))
    done
    st=$(curl -s "$URL/v1/jobs/$BJ" | jq -r .state)
    if [ "$code $st" = "202 succeeded" ]; then
        QDC_URL=$URL UI_MODE=big BIG_ID=$BJ SMALL_ID=$SJ node "$ROOT/tests/ui/tabs.mjs" > "$TMP/big.out" 2>&1 || fail "tabs.mjs big" "exit $?"
        cat "$TMP/big.out"
        NFAIL=$((NFAIL + $(grep -c '^FAIL - ' "$TMP/big.out")))
    else
        fail "big job" "$code $st"
    fi
    stop_qdcd || fail "SIGTERM (big)" "exit status $?"
fi
echo "# figures: $(cat "$TMP/out/figures-tabs.json" 2> /dev/null | tr -d '\n ')"
[ -n "${UI_BIG:-}" ] && echo "# figures (big): $(cat "$TMP/out/figures-big.json" 2> /dev/null | tr -d '\n ')"
exit $((NFAIL > 0))
