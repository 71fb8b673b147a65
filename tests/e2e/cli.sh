# tests/e2e/cli.sh - the qdc CLI: its numbers agree with the independent evaluator
# (shared/tools/quality.py), errors are one line with file:line, exit codes hold.
. "$(dirname "$0")/../lib.sh"

in=$(devmesh cube_h0.1_noisy)
"$BIN/qdc" optimize "$in" "$TMP/out.mesh" --quiet --max-iter 4 --report "$TMP/r.json"
rc=$?
[ $rc -eq 0 ] && pass "cli.optimize exit 0" || fail "cli.optimize exit 0" "exit $rc"

# qdc quality --json vs quality.py on the same output
"$BIN/qdc" quality "$TMP/out.mesh" --ref "$in" --json > "$TMP/q.json" 2>"$TMP/err" ||
    fail "cli.quality" "$(cat "$TMP/err")"
$PY "$QUALITY" "$TMP/out.mesh" --orig "$in" --samples 50000 > "$TMP/ref.json"
if $PY - "$TMP/q.json" "$TMP/ref.json" "$TMP/r.json" > "$TMP/cmp" 2>&1 <<'PYEOF'
import json, sys
q = json.load(open(sys.argv[1])); r = json.load(open(sys.argv[2])); rep = json.load(open(sys.argv[3]))
a = q["after"]; b = q["boundary_error"]
checks = [
    ("mean", a["mean_ratio_mean"], r["eta_mean"], 1e-9),
    ("std", a["mean_ratio_std"], r["eta_std"], 1e-9),
    ("min", a["mean_ratio_min"], r["eta_min"], 1e-9),
    ("dihedral_min", a["dihedral_min"], r["dihedral_min"], 1e-6),
    ("dihedral_max", a["dihedral_max"], r["dihedral_max"], 1e-6),
    ("inverted", a["n_inverted"], r["n_inverted"], 0),
    ("degenerate", a["n_degenerate"], r["n_degenerate"], 0),
    ("dmin<5", a["n_dmin_lt_5"], r["n_dmin_lt_5"], 0),
    ("dmax>165", a["n_dmax_gt_165"], r["n_dmax_gt_165"], 0),
    ("vl_mean", a["volume_length_mean"], r["vlq_mean"], 1e-9),
    # sampled Hausdorff: both are lower bounds of the true value from dense samples
    ("hausdorff", b["hausdorff"], r["boundary_hausdorff"], 0.05 * r["boundary_hausdorff"] + 1e-12),
    ("report=quality", rep["after"]["mean_ratio_mean"], a["mean_ratio_mean"], 1e-12),
]
bad = [f"{n}: qdc {x} vs quality.py {y}" for n, x, y, tol in checks if abs(x - y) > tol]
print("; ".join(bad))
sys.exit(1 if bad else 0)
PYEOF
then pass "cli.quality agrees with tools/quality.py"; else fail "cli.quality agrees with tools/quality.py" "$(cat "$TMP/cmp")"; fi

# the histogram counts every dihedral angle of every tet
n=$($PY -c "import json; q=json.load(open('$TMP/q.json'))['after']; print(sum(q['dihedral_histogram']) == 6*q['n_tets'])")
[ "$n" = True ] && pass "cli.histogram covers 6 angles per tet" || fail "cli.histogram" "sum != 6 nt"

# the solid's angle at the surface's edges: a cube's 90 degrees at its 12 edges
cube=$(devmesh cube_h0.1_good)
a=$("$BIN/qdc" quality "$cube" --json | $PY -c "import json,sys; q=json.load(sys.stdin)['after']; print(abs(q['surface_angle_min'] - 90) < 1e-6 and q['n_surface_edges_lt_5'] == 0 and q['dihedral_min'] <= q['surface_angle_min'])")
t=$("$BIN/qdc" quality "$cube" | grep -c '^surface: smallest solid angle at an edge 90.00 deg (0 edges under 5')
[ "$a" = True ] && [ "$t" = 1 ] && pass "cli.quality surface angle 90 on a cube" ||
    fail "cli.quality surface angle" "json check $a, text lines $t"

# bad input: one line, file:line, exit code 2, no crash
printf 'MeshVersionFormatted 2\nDimension 3\nVertices\n2\n0 0 0 1\n1 0 nan 1\nEnd\n' > "$TMP/bad.mesh"
"$BIN/qdc" optimize "$TMP/bad.mesh" "$TMP/x.mesh" 2>"$TMP/err"
rc=$?
lines=$(wc -l < "$TMP/err")
if [ $rc -eq 2 ] && [ "$lines" -eq 1 ] && grep -q "bad.mesh:[0-9]" "$TMP/err"; then
    pass "cli.bad file: exit 2, one line with file:line"
else
    fail "cli.bad file" "exit $rc, $(cat "$TMP/err")"
fi
"$BIN/qdc" optimize "$TMP/missing.mesh" "$TMP/x.mesh" 2>/dev/null
[ $? -eq 2 ] && pass "cli.missing file exit 2" || fail "cli.missing file" "wrong exit code"
"$BIN/qdc" optimize "$in" 2>/dev/null
[ $? -eq 1 ] && pass "cli.usage exit 1" || fail "cli.usage" "wrong exit code"
"$BIN/qdc" optimize "$in" "$TMP/x.mesh" --metric nope 2>/dev/null
[ $? -eq 1 ] && pass "cli.bad option exit 1" || fail "cli.bad option" "wrong exit code"

# literal mode and harmonic guidance run end to end and never make things worse
for opts in "--mode literal --finish off" "--harmonic on"; do
    # shellcheck disable=SC2086
    if "$BIN/qdc" optimize "$in" "$TMP/o.mesh" --quiet $opts --report "$TMP/o.json"; then
        ok=$($PY -c "import json; r=json.load(open('$TMP/o.json')); print(r['after']['n_inverted'] <= r['before']['n_inverted'] and r['after']['mean_ratio_min'] >= r['before']['mean_ratio_min'])")
        [ "$ok" = True ] && pass "cli.$opts never worse" || fail "cli.$opts" "worse than input"
    else
        fail "cli.$opts" "qdc failed"
    fi
done

# --fix FILE: the listed vertices keep their exact coordinates
printf '# locked\n10 11 12\n500, 501\n' > "$TMP/fix.txt"
if "$BIN/qdc" optimize "$in" "$TMP/fx.mesh" --quiet --max-iter 3 --fix "$TMP/fix.txt"; then
    same=$($PY - "$in" "$TMP/fx.mesh" <<'PYEOF'
import os, sys
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio
a, b = (meditio.read(p).vertices.tolist() for p in sys.argv[1:3])
fixed = [10, 11, 12, 500, 501]
moved = sum(a[k] != b[k] for k in range(len(a)))
print(all(a[k] == b[k] for k in fixed) and moved > 100)
PYEOF
)
    [ "$same" = True ] && pass "cli.--fix vertices do not move" || fail "cli.--fix" "locked vertices moved"
else
    fail "cli.--fix" "qdc failed"
fi
printf '3 99999999\n' > "$TMP/badfix.txt"
"$BIN/qdc" optimize "$in" "$TMP/fx.mesh" --quiet --fix "$TMP/badfix.txt" 2>"$TMP/err"
[ $? -eq 2 ] && grep -q "badfix.txt:1:" "$TMP/err" && pass "cli.--fix bad index: exit 2 with file:line" ||
    fail "cli.--fix bad index" "$(cat "$TMP/err")"
# --threads: the same bytes from 1 and 2 threads; a count out of range is a
# usage error that writes nothing
for th in 1 2; do
    "$BIN/qdc" optimize "$in" "$TMP/th$th.mesh" --quiet --threads $th 2> "$TMP/err" ||
        fail "cli.--threads $th" "exit $?: $(cat "$TMP/err")"
done
cmp -s "$TMP/th1.mesh" "$TMP/th2.mesh" && pass "cli.--threads 1 and 2: the same bytes" ||
    fail "cli.--threads" "1 and 2 threads differ"
for bad in 0 1025 two; do
    "$BIN/qdc" optimize "$in" "$TMP/thb.mesh" --quiet --threads $bad 2> "$TMP/err"
    rc=$?
    if [ $rc -eq 1 ] && grep -q "bad value '$bad' for --threads" "$TMP/err" &&
        [ ! -e "$TMP/thb.mesh" ]; then
        pass "cli.--threads $bad: usage error, nothing written"
    else
        fail "cli.--threads $bad" "exit $rc: $(cat "$TMP/err")"
    fi
done
exit 0
