#!/bin/sh
# tests/e2e/help.sh - what a newcomer meets first: `qdc optimize --help` in
# groups with every word of a word option explained, "did you mean" for a
# mistyped command or option, `convert` to a format qdc only reads refused
# before anything is read, and scripts that print their help without their
# heavy imports.
. "$(dirname "$0")/../lib.sh"
Q=$BIN/qdc

# --help: the groups in order, every option of `qdc options` in one of them
"$Q" optimize --help > "$TMP/help" 2>&1
rc=$?
groups=$(grep -E '^(Everyday|Boundary|Files|Advanced)' "$TMP/help" | cut -d' ' -f1 | tr -d ':\n' )
missing=
for name in $("$Q" options | jq -r '.[].name'); do
    grep -q -- "^  --$(echo "$name" | tr _ -) " "$TMP/help" || missing="$missing $name"
done
[ $rc = 0 ] && [ "$groups" = EverydayBoundaryFilesAdvanced ] && [ -z "$missing" ] &&
    pass "optimize --help: groups Everyday, Boundary, Files, Advanced; all $("$Q" options | jq length) options of the table listed" ||
    fail "optimize --help groups" "exit $rc, groups '$groups', missing:$missing"
# the everyday group holds the metric and max-iter; the advanced one mu and
# the solver (what the groups are for)
ev=$(sed -n '/^Everyday/,/^Boundary/p' "$TMP/help")
adv=$(sed -n '/^Advanced/,$p' "$TMP/help")
echo "$ev" | grep -q -- '--metric ' && echo "$ev" | grep -q -- '--max-iter ' &&
    echo "$adv" | grep -q -- '--mu ' && echo "$adv" | grep -q -- '--solver ' &&
    ! echo "$ev" | grep -q -- '--mu ' &&
    pass "optimize --help: --metric and --max-iter are everyday, --mu and --solver advanced" ||
    fail "optimize --help placement" "$(echo "$ev" | grep -- '^  --' | tr '\n' ' ')"
# each metric in words: a line starting with the word, then an explanation
for w in mivl mimr micn; do
    line=$(grep -E "^ +$w +[a-z]" "$TMP/help")
    words=$(echo "$line" | wc -w)
    [ "$words" -ge 6 ] && pass "optimize --help explains $w: $(echo "$line" | sed 's/^ *//')" ||
        fail "optimize --help $w" "'$line'"
done
long=$(awk 'length > 80' "$TMP/help" | head -1)
[ -z "$long" ] && pass "optimize --help fits 80 columns" || fail "optimize --help width" "$long"

# did you mean
in=$ROOT/tests/data/sample/cube.mesh
for pair in "--bondary lsq:--boundary" "--max_itr 3:--max-iter" "--metrc mimr:--metric" "--time-limt 5:--time-limit" "--reprot r.json:--report"; do
    args=${pair%%:*}
    want=${pair#*:}
    # shellcheck disable=SC2086
    msg=$("$Q" optimize "$in" "$TMP/o.mesh" $args 2>&1)
    rc=$?
    case "$rc $msg" in
    "1 "*"unknown option "*"did you mean $want?"*) pass "qdc optimize ... $args: exit 1, \"$msg\"" ;;
    *) fail "suggest $args" "exit $rc: $msg" ;;
    esac
done
[ ! -e "$TMP/o.mesh" ] && pass "a mistyped option writes nothing" || fail "mistyped option" "OUT written"
msg=$("$Q" optimize "$in" "$TMP/o.mesh" --zzzzzz 1 2>&1)
case $msg in
*"did you mean"*) fail "no suggestion for --zzzzzz" "$msg" ;;
*"unknown option --zzzzzz"*) pass "an option far from every name gets no suggestion: \"$msg\"" ;;
*) fail "--zzzzzz" "$msg" ;;
esac
for pair in optimze:optimize qualty:quality subimt:submit convrt:convert; do
    msg=$("$Q" "${pair%%:*}" 2>&1 | head -1)
    case $msg in
    *"unknown command '${pair%%:*}': did you mean '${pair#*:}'?"*) pass "qdc ${pair%%:*}: \"$msg\"" ;;
    *) fail "suggest command ${pair%%:*}" "$msg" ;;
    esac
done

# convert / optimize to a format qdc reads but does not write
for out in cube.stl cube.OFF cube.obj.gz; do
    msg=$(cd "$TMP" && "$Q" convert "$in" "$out" 2>&1)
    rc=$?
    nl=$(printf '%s\n' "$msg" | wc -l)
    case "$rc $nl $msg" in
    "2 1 qdc: $out: "*"reads but does not write"*"nothing was done") [ ! -e "$TMP/$out" ] &&
        pass "qdc convert cube.mesh $out: exit 2, one line: \"$msg\"" || fail "convert $out" "file written" ;;
    *) fail "convert $out" "exit $rc, $nl lines: $msg" ;;
    esac
done
# said before reading: the input need not exist
msg=$("$Q" convert "$TMP/no-such.mesh" "$TMP/x.stl" 2>&1)
rc=$?
case "$rc $msg" in
"2 "*"does not write"*) pass "convert to .stl is refused before IN is read (IN missing: the format is what is said)" ;;
*) fail "convert .stl first" "exit $rc: $msg" ;;
esac
msg=$("$Q" optimize "$in" "$TMP/x.stl" --quiet 2>&1)
rc=$?
case "$rc $msg" in
"2 "*"STL is a surface format"*) pass "optimize to .stl: the same refusal, exit 2, before the run" ;;
*) fail "optimize .stl" "exit $rc: $msg" ;;
esac
# --out-format says otherwise: written (read back as VTK by qdc convert)
"$Q" convert "$in" "$TMP/x.stl" --out-format vtk --quiet > "$TMP/cv" 2>&1
rc=$?
"$Q" convert "$TMP/x.stl" "$TMP/back.mesh" --in-format vtk --quiet >> "$TMP/cv" 2>&1
[ $rc = 0 ] && "$Q" quality "$TMP/back.mesh" 2>&1 | grep -q ' 750 tets' &&
    pass "--out-format vtk with an .stl name: written as VTK (the name does not decide)" ||
    fail "--out-format over .stl" "exit $rc: $(cat "$TMP/cv")"

# scripts: --help before numpy (a numpy that cannot be imported shadows any installed one)
mkdir -p "$TMP/nonumpy"
echo 'raise ImportError("numpy is not here (test)")' > "$TMP/nonumpy/numpy.py"
cp "$TMP/nonumpy/numpy.py" "$TMP/nonumpy/scipy.py"
out=$(PYTHONPATH="$TMP/nonumpy" $PY "$ROOT/scripts/corpus.py" --help 2>&1)
rc=$?
case "$rc $out" in
"0 usage: corpus.py"*"--tets"*) pass "scripts/corpus.py --help without numpy: exit 0, $(printf '%s\n' "$out" | wc -l) lines of help" ;;
*) fail "corpus.py --help" "exit $rc: $(printf '%s' "$out" | tail -2 | tr '\n' ' ')" ;;
esac
out=$(PYTHONPATH="$TMP/nonumpy" $PY "$ROOT/scripts/corpus.py" "$TMP/c" 2>&1)
rc=$?
case "$rc $out" in
"1 corpus.py: numpy is missing"*) pass "scripts/corpus.py without numpy: one line saying so ($out)" ;;
*) fail "corpus.py no numpy" "exit $rc: $out" ;;
esac
exit $((NFAIL > 0))
