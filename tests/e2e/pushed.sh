#!/bin/sh
# pushed.sh - a tangle whose pushed vertices went through the surface is
# untangled in every mode. scripts/corpus.py's thin torus at 20k tets with 5%
# of its interior vertices pushed (seed 7: 507 tets inverted) kept 3 tets
# inverted (5 with the boundary fixed, 2-3 with --topology) around one vertex
# left 1.8 edges outside, its neighbours dragged along: no move of one vertex
# opened its star, and the reruns of slide mode did not either. Checked by the
# independent evaluator (tests/tools/evaluate.py): no tet inverted, none flat,
# the worst usable tet no worse than the input's.
. "$(dirname "$0")/../lib.sh"

corpus_mesh "pushed: torus-lowq-tangled" torus-lowq-tangled 20000 --seed 7 --tangle-frac 0.05
in=$CORPUS_MESH
if ! "$PY" "$QUALITY" "$in" > "$TMP/qi.json" 2> "$TMP/e"; then
    fail "pushed: evaluator on the input" "$(tail -2 "$TMP/e")"
    exit 0
fi
for mode in default "--boundary fixed" "--topology flips" "--topology full --boundary fixed"; do
    case $mode in default) opts= ;; *) opts=$mode ;; esac
    t0=$(date +%s%N)
    # shellcheck disable=SC2086 # the options split into words
    if ! "$BIN/qdc" optimize "$in" "$TMP/o.mesh" $opts --quiet 2> "$TMP/err"; then
        fail "pushed: $mode" "exit $?: $(tail -2 "$TMP/err")"
        continue
    fi
    [ "$mode" = default ] && full_ns=$(($(date +%s%N) - t0))
    if ! "$PY" "$QUALITY" "$TMP/o.mesh" > "$TMP/qo.json" 2> "$TMP/e"; then
        fail "pushed: $mode: evaluator" "$(tail -2 "$TMP/e")"
        continue
    fi
    why=$("$PY" - "$TMP/qi.json" "$TMP/qo.json" << 'EOF'
import json, sys
qi, qo = (json.load(open(f)) for f in sys.argv[1:3])
why = []
if qi["n_inverted"] < 400:
    why.append("input: %d inverted (want the harsh tangle)" % qi["n_inverted"])
if qo["n_inverted"] != 0:
    why.append("%d tets left inverted" % qo["n_inverted"])
if qo["n_degenerate"] > qi["n_degenerate"]:
    why.append("%d tets flat (input %d)" % (qo["n_degenerate"], qi["n_degenerate"]))
if qo["eta_min_valid"] < qi["eta_min_valid"]:
    why.append("worst usable tet %.3g < the input's %.3g"
               % (qo["eta_min_valid"], qi["eta_min_valid"]))
print("; ".join(why) if why else "ok inverted %d -> 0, mean ratio %.4f -> %.4f"
      % (qi["n_inverted"], qi["eta_mean"], qo["eta_mean"]))
EOF
)
    verdict "pushed: $mode" "$why"
done
# --time-limit is the whole call's: the reruns share it. Each used to have
# all of it, so a limit that the first run kept to took as long as no limit
# (3 s: 7.9 s). Three pairs, each a default run and right after it a run
# limited to 45% of that one's time (the first run is about 40% of it): the
# limited runs take at most 80% of their pair's default run (the median of
# the three ratios, so that one pair slowed by other work on the machine
# does not decide; before: 104%).
ratios=
for _ in 1 2 3; do
    t0=$(date +%s%N)
    "$BIN/qdc" optimize "$in" "$TMP/t.mesh" --quiet 2> "$TMP/err"
    rc=$?
    full_ns=$(($(date +%s%N) - t0))
    lim=$(awk -v n="$full_ns" 'BEGIN { printf "%.3f", n * 0.45 / 1e9 }')
    t0=$(date +%s%N)
    [ "$rc" = 0 ] && "$BIN/qdc" optimize "$in" "$TMP/t.mesh" --time-limit "$lim" --quiet \
        2> "$TMP/err"
    rc=$?
    lim_ns=$(($(date +%s%N) - t0))
    if [ "$rc" != 0 ] && [ "$rc" != 3 ]; then
        ratios=
        break
    fi
    ratios="$ratios $((lim_ns / 1000000))/$((full_ns / 1000000))"
done
if [ -z "$ratios" ]; then
    fail "pushed: --time-limit" "exit $rc: $(tail -2 "$TMP/err")"
else
    why=$(echo "$ratios" | tr ' ' '\n' | awk -F/ 'NF == 2 { print $1 / $2 }' | sort -g |
        awk -v r="$ratios" 'NR == 2 { m = $1 }
            END { if (m <= 0.8) print "ok"; else print "median ratio " m " > 0.8:" r }')
    if [ "$why" = ok ]; then
        pass "pushed: --time-limit at 45% shared by the reruns (ms limited/default:$ratios)"
    else
        fail "pushed: --time-limit at 45%" "$why"
    fi
fi
exit 0
