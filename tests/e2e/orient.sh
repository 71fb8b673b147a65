#!/bin/sh
# orient.sh - meshes whose tets come in mixed vertex order are valid meshes:
# the bundled cube written the DOLFIN way (each tet's vertices sorted by index),
# the GetFEM way (every third tet with two vertices swapped) and all inverted
# the same way. qdc orients the tets from the connectivity, so each variant is
# optimized as the original: the same coordinates (to rounding), the
# tets written back in the user's vertex order, no valid tet folded (checked
# with numpy, independently of the library), through the CLI and the daemon.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
CUBE=$ROOT/tests/data/sample/cube.mesh

# variant MODE OUT: rewrite the Tetrahedra section of the cube
variant() {
    awk -v mode="$1" '
        state == 1 { print; n = $1; state = 2; next }
        state == 2 && n > 0 {
            a = $1; b = $2; c = $3; d = $4
            if (mode == "sorted") {
                v[1] = a; v[2] = b; v[3] = c; v[4] = d
                for (i = 2; i <= 4; i++)
                    for (j = i; j > 1 && v[j - 1] + 0 > v[j] + 0; j--) { x = v[j]; v[j] = v[j - 1]; v[j - 1] = x }
                a = v[1]; b = v[2]; c = v[3]; d = v[4]
            } else if (mode == "inverted" || (mode == "getfem" && k % 3 == 0)) {
                x = a; a = b; b = x
            }
            print a, b, c, d, $5; k++; n--; next
        }
        $1 == "Tetrahedra" { state = 1 }
        { print }' "$CUBE" > "$2"
}

# close A B: coordinate files equal to 1e-6 (of the unit cube): a tet whose
# vertices are listed in another order sums the same terms in another order
close() {
    "$PY" -c 'import sys, numpy as np
a, b = (np.array(open(f).read().split()[2:], float) for f in sys.argv[1:3])
sys.exit(0 if a.shape == b.shape and np.abs(a - b).max() < 1e-6 else 1)' "$1" "$2"
}

# coords FILE: the Vertices section only; tets FILE: the Tetrahedra section only
coords() { sed -n '/^Vertices/,/^Tetrahedra/p' "$1" | sed '$d'; }
tets() { sed -n '/^Tetrahedra/,/^End/p' "$1"; }

# folded IN OUT: how many tets change the sign of their volume (as written)
# from IN to OUT. Written without the library: numpy.
folded() {
    "$PY" - "$1" "$2" << 'EOF'
import os, sys
import numpy as np
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio
def load(p):
    m = meditio.read(p)
    return m.vertices, m.tets
def vol(x, t):
    a, b, c, d = (x[t[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))
xi, t = load(sys.argv[1]); xo, t2 = load(sys.argv[2])
assert (t == t2).all()
vi, vo = vol(xi, t), vol(xo, t)
print(int(np.sum(np.sign(vi) != np.sign(vo))))
EOF
}

"$BIN/qdc" optimize "$CUBE" "$TMP/orig.out.mesh" > "$TMP/orig.log" 2>&1 || fail "orient: original" "$(tail -2 "$TMP/orig.log")"
coords "$TMP/orig.out.mesh" > "$TMP/orig.xyz"
for mode in sorted getfem inverted; do
    variant $mode "$TMP/$mode.mesh"
    "$BIN/qdc" quality "$TMP/$mode.mesh" > "$TMP/$mode.qin" 2>&1
    inv_in=$(sed -n 's/.* \([0-9]*\) inverted.*/\1/p' "$TMP/$mode.qin")
    "$BIN/qdc" optimize "$TMP/$mode.mesh" "$TMP/$mode.out.mesh" > "$TMP/$mode.log" 2>&1
    rc=$?
    "$BIN/qdc" quality "$TMP/$mode.out.mesh" > "$TMP/$mode.qout" 2>&1
    inv_out=$(sed -n 's/.* \([0-9]*\) inverted.*/\1/p' "$TMP/$mode.qout")
    dmin_in=$(sed -n 's/^dihedral: min \([0-9.]*\) .*/\1/p' "$TMP/$mode.qin")
    dmin_out=$(sed -n 's/^dihedral: min \([0-9.]*\) .*/\1/p' "$TMP/$mode.qout")
    coords "$TMP/$mode.out.mesh" > "$TMP/$mode.xyz"
    why=
    [ $rc = 0 ] || why="$why exit $rc"
    [ "$inv_in" = 1 ] || why="$why input inverted '$inv_in' (the cube has one)"
    [ "$inv_out" = 0 ] || why="$why output inverted '$inv_out'"
    close "$TMP/orig.xyz" "$TMP/$mode.xyz" || why="$why coordinates differ from the original's run"
    [ "$(tets "$TMP/$mode.mesh" | cksum)" = "$(tets "$TMP/$mode.out.mesh" | cksum)" ] ||
        why="$why tets not written back in the user's vertex order"
    awk -v a="$dmin_in" -v b="$dmin_out" 'BEGIN { exit !(b + 0 >= a + 0 && b + 0 > 5) }' ||
        why="$why smallest dihedral $dmin_in -> $dmin_out"
    if [ -z "$why" ]; then
        pass "orient: cube written $mode: 1 inverted -> 0, smallest dihedral $dmin_in -> $dmin_out, the original's coordinates (to 1e-6), tets as written"
    else
        fail "orient: cube written $mode" "$why"
    fi
done

# Independent of the library: tets valid in the input never change sign. The
# one inverted tet of the cube is the only sign change allowed.
n=$(folded "$TMP/sorted.mesh" "$TMP/sorted.out.mesh")
[ "$n" = 1 ] && pass "orient: numpy: of the sorted cube's 750 tets only the inverted one changed sign (0 folded)" ||
    fail "orient: numpy sign changes" "$n tets changed sign (expected 1: the inverted one)"

# --reorient on: the tets are written in their positive vertex order instead
"$BIN/qdc" optimize "$TMP/sorted.mesh" "$TMP/re.mesh" --reorient on > "$TMP/re.log" 2>&1
npos=$("$PY" - "$TMP/re.mesh" << 'EOF'
import os, sys
import numpy as np
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio
m = meditio.read(sys.argv[1])
x, t = m.vertices, m.tets
a, b, c, d = (x[t[:, k]] for k in range(4))
print(int((np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) > 0).sum()))
EOF
)
if [ "$npos" = 750 ] && grep -q 'note: 375 of 750 tets written in the other vertex order' "$TMP/re.log"; then
    pass "orient: --reorient on: all 750 tets written positive, with a note (375 rewritten)"
else
    fail "orient: --reorient" "$npos positive; $(tail -2 "$TMP/re.log" | tr '\n' ' ')"
fi

# The daemon: the same result for the sorted cube.
start_qdcd "$TMP/d" --workers 1 || { fail "orient: start qdcd" "$(tail -3 "$TMP/d.log")"; exit 1; }
c=$(submit "$TMP/sorted.mesh" model/x-medit "" "$TMP/j")
id=$(jf "$TMP/j" .id)
poll_all "$id" > /dev/null
req GET "/v1/jobs/$id/result?format=medit" "$TMP/srv.mesh" > /dev/null
coords "$TMP/srv.mesh" > "$TMP/srv.xyz"
inv=$(req GET "/v1/jobs/$id/report" "$TMP/rep" > /dev/null; jf "$TMP/rep" .before.n_inverted)
if [ "$c" = 202 ] && close "$TMP/orig.xyz" "$TMP/srv.xyz" && [ "$inv" = 1 ]; then
    pass "orient: qdcd: the sorted cube is optimized like the original (report: 1 inverted in the input)"
else
    fail "orient: qdcd" "submit $c, report before.n_inverted '$inv', coordinates $(cmp "$TMP/orig.xyz" "$TMP/srv.xyz" 2>&1)"
fi
stop_qdcd || fail "orient: qdcd stop" "exit status $?"
exit 0
