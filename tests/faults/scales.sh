#!/bin/sh
# faults/scales.sh - extreme coordinates and duplicate tets. A mesh scaled by
# 1e150, 1e200 or 1e-160 is the same mesh: it is optimized and reported as the
# unscaled one, to rounding (its coordinates times the factor are not exactly
# the unscaled ones; the finishing sweeps moved the mean ratio by a few 1e-9,
# but the angle pass's joint moves on the worst mean ratios choose among tets
# that tie to the last bits, and those choices follow the rounding: up to 6e-4
# on the sample cube, so 1e-3 is allowed) (before, it "succeeded" with
# mean_ratio null); one scaled by
# 1e-310 (denormal), or with one coordinate at 1e308, cannot be computed with
# and is refused (CLI exit 2, daemon 422) with the reason; a duplicate tet is
# refused naming both indices.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
CUBE=$ROOT/tests/data/sample/cube.mesh
scale() { # IN OUT FACTOR: Medit vertices times FACTOR
    awk -v f="$3" '
        st == 1 { print; n = $1; st = 2; next }
        st == 2 && n > 0 { printf "%.17g %.17g %.17g %s\n", $1 * f, $2 * f, $3 * f, $4; n--; next }
        $1 == "Vertices" { st = 1 }
        { print }' "$1" > "$2"
}
"$BIN/qdc" optimize "$CUBE" "$TMP/ref.mesh" --report "$TMP/ref.json" --quiet
ref=$(jf "$TMP/ref.json" .after.mean_ratio_mean)
for f in 1e150 1e200 1e-160; do
    scale "$CUBE" "$TMP/s.mesh" $f
    if "$BIN/qdc" optimize "$TMP/s.mesh" "$TMP/s.out.mesh" --report "$TMP/s.json" --quiet 2> "$TMP/err"; then
        got=$(jf "$TMP/s.json" .after.mean_ratio_mean)
        h=$(jf "$TMP/s.json" .boundary_error.hausdorff_rel)
        if awk -v a="$got" -v b="$ref" -v h="$h" 'BEGIN { d = a - b; exit !(d < 1e-3 && d > -1e-3 && h + 0 >= 0 && h != "null") }'; then
            pass "scales: cube x $f: mean ratio $got (unscaled $ref), Hausdorff $h of the diagonal"
        else
            fail "scales: cube x $f" "mean ratio $got vs $ref, Hausdorff $h"
        fi
    else
        fail "scales: cube x $f" "exit $?: $(cat "$TMP/err")"
    fi
done
scale "$CUBE" "$TMP/tiny.mesh" 1e-310
awk 'done == 0 && prev == "Vertices" { print; getline; $1 = "1e308"; print; done = 1; next } { prev = $1; print }' "$CUBE" > "$TMP/far.mesh"
awk 'st == 1 { n = $1 + 1; print n; st = 2; next } st == 2 && k == 5 { dup = $0 } st == 2 { k++; print; if (k == n - 1) { print dup; st = 3 }; next }
     $1 == "Tetrahedra" { st = 1 } { print }' "$CUBE" > "$TMP/dup.mesh"
for c in "tiny:too small" "far:far from the others" "dup:tets 5 and 750 have the same four vertices"; do
    f=${c%%:*} want=${c#*:}
    "$BIN/qdc" optimize "$TMP/$f.mesh" "$TMP/x.mesh" --quiet 2> "$TMP/err"
    rc=$?
    if [ $rc = 2 ] && grep -q "$want" "$TMP/err"; then
        pass "scales: CLI refuses the $f mesh: exit 2, $(head -c 150 "$TMP/err")"
    else
        fail "scales: CLI $f" "exit $rc: $(cat "$TMP/err")"
    fi
done
start_qdcd "$TMP/d" --workers 1 || { fail "scales: start qdcd" "$(tail -3 "$TMP/d.log")"; exit 1; }
for c in "tiny:too small" "far:far from the others" "dup:tets 5 and 750"; do
    f=${c%%:*} want=${c#*:}
    code=$(submit "$TMP/$f.mesh" model/x-medit "" "$TMP/o")
    if [ "$code" = 422 ] && jf "$TMP/o" .detail | grep -q "$want"; then
        pass "scales: qdcd answers 422 for the $f mesh: $(jf "$TMP/o" .detail | head -c 120)"
    else
        fail "scales: qdcd $f" "$code $(head -c 200 "$TMP/o")"
    fi
done
scale "$CUBE" "$TMP/big.mesh" 1e200
code=$(submit "$TMP/big.mesh" model/x-medit "" "$TMP/o")
id=$(jf "$TMP/o" .id)
st=$(poll_all "$id")
req GET "/v1/jobs/$id/report" "$TMP/rep" > /dev/null
got=$(jf "$TMP/rep" .after.mean_ratio_mean)
awk -v a="$got" -v b="$ref" 'BEGIN { d = a - b; exit !(d < 1e-3 && d > -1e-3) }' &&
    pass "scales: qdcd optimizes the cube x 1e200 like the cube (mean ratio $got)" ||
    fail "scales: qdcd x 1e200" "$code $st mean ratio '$got' vs $ref"
stop_qdcd || fail "scales: stop" "exit $?"
exit 0
