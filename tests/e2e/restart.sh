#!/bin/sh
# restart.sh - interior tets left inverted around neighbouring vertices a
# tangle pushed past each other are repaired where they are: the local
# repair's last round starts the free corners of the inverted tets from their
# neighbours' mean (lib/opt/local.c). scripts/corpus.py's graded box at 30k
# tets, seed 47, 12% of the interior vertices pushed (1892 tets inverted),
# with the boundary fixed: 5 interior tets (no boundary corner) stayed
# inverted around two vertices pushed 1.4 edges, through every ring and
# every rerun from the input. Now 0 (independent evaluator), the boundary
# where it was, a "from their neighbours' mean" round in the log, and no
# rerun from the input.
. "$(dirname "$0")/../lib.sh"

corpus_mesh "restart: graded-box-tangled" graded-box-tangled 30000 --seed 47 --tangle-frac 0.12
in=$CORPUS_MESH
if ! "$BIN/qdc" optimize "$in" "$TMP/o.mesh" --boundary fixed 2> "$TMP/err"; then
    fail "restart: graded-box-tangled" "exit $?: $(tail -2 "$TMP/err")"
    exit 0
fi
why=$(PYTHONPATH="$ROOT/tests/tools" "$PY" - "$in" "$TMP/o.mesh" << 'EOF2'
import sys
import numpy as np
import evaluate, meditio
a, b = meditio.read(sys.argv[1]), meditio.read(sys.argv[2])
qa, qb = evaluate.evaluate(sys.argv[1]), evaluate.evaluate(sys.argv[2])
why = []
if qa["n_inverted"] < 1000:
    why.append("input: %d inverted (want the harsh tangle)" % qa["n_inverted"])
if qb["n_inverted"] != 0 or qb["n_degenerate"] > qa["n_degenerate"]:
    why.append("%d tets left inverted, %d flat" % (qb["n_inverted"], qb["n_degenerate"]))
bf = evaluate.boundary_faces(a.tets)
bv = np.unique(np.asarray(bf).reshape(-1))
if np.abs(b.vertices[bv] - a.vertices[bv]).max() != 0:
    why.append("a boundary vertex moved")
print("; ".join(why) if why else "ok inverted %d -> 0, mean ratio %.4f -> %.4f"
      % (qa["n_inverted"], qa["eta_mean"], qb["eta_mean"]))
EOF2
)
verdict "restart: graded-box-tangled --boundary fixed" "$why"
if grep -q "neighbours' mean" "$TMP/err" && ! grep -q "again from the input" "$TMP/err"; then
    pass "restart: repaired by the restarted round, no rerun from the input"
else
    fail "restart: the log" "$(grep -E "local repair|again" "$TMP/err" | tail -4)"
fi
