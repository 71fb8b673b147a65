#!/bin/sh
# sweep.sh - every mode over a corpus the project has not tuned on, each
# result checked by tests/tools/invariants.py (no tet inverted or flattened,
# never worse than a valid input, tags kept, a fixed boundary kept). Not part
# of `make test` (minutes per corpus): run it with a new seed before a change
# to the optimizer is called done; a BAD line is a bug or a documented limit.
# Usage: scripts/sweep.sh DIR [--tets N] [--seed S] [--tangle-frac P]
#                             [--only CLASSES] [--modes "MODE;MODE;..."]
#   DIR: where the corpus (DIR/corpus) and the outputs go.
#   MODE: qdc optimize options, e.g. "--topology flips --boundary fixed";
#   default: none, flips and full, each with and without --boundary fixed.
# e.g. scripts/sweep.sh /tmp/sw --tets 20000 --seed 7 --tangle-frac 0.05
# Prints one line per run and a count; exits 1 if any run failed or broke a
# promise.
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
QDC=${QDC:-$ROOT/build/rel/qdc}
PY=/usr/bin/python3
[ $# -ge 1 ] || { sed -n '2,14p' "$0" >&2; exit 2; }
dir=$1
shift
modes="default;--boundary fixed;--topology flips;--topology flips --boundary fixed;--topology full;--topology full --boundary fixed"
gen=
while [ $# -gt 0 ]; do
    case $1 in
    --modes) modes=$2; shift 2 ;;
    --tets | --seed | --tangle-frac | --only) gen="$gen $1 $2"; shift 2 ;;
    *) echo "sweep.sh: unknown option $1" >&2; exit 2 ;;
    esac
done
[ -x "$QDC" ] || { echo "sweep.sh: no $QDC (make, or set QDC)" >&2; exit 2; }
mkdir -p "$dir/corpus" "$dir/out" || exit 2
# shellcheck disable=SC2086 # the corpus options split into words
"$PY" "$ROOT/scripts/corpus.py" "$dir/corpus" $gen > "$dir/corpus.log" 2>&1 ||
    { tail -3 "$dir/corpus.log" >&2; exit 2; }
n=0 bad=0
for m in "$dir"/corpus/*.mesh; do
    old_ifs=$IFS
    IFS=';'
    # shellcheck disable=SC2086 # split on ';' into the modes
    set -- $modes
    IFS=$old_ifs
    for mode in "$@"; do
        opts=$mode
        [ "$mode" = default ] && opts=
        out=$dir/out/$(basename "$m" .mesh).mesh
        n=$((n + 1))
        # shellcheck disable=SC2086 # the options split into words
        if ! "$QDC" optimize "$m" "$out" $opts --quiet 2> "$dir/err"; then
            echo "$(basename "$m") [$mode] FAIL: exit $?: $(tail -1 "$dir/err")"
            bad=$((bad + 1))
            continue
        fi
        # shellcheck disable=SC2086
        "$PY" "$ROOT/tests/tools/invariants.py" "$m" "$out" $opts || bad=$((bad + 1))
    done
done
echo "$n runs, $bad failed"
[ "$bad" = 0 ]
