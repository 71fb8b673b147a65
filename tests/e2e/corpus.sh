#!/bin/sh
# corpus.sh - scripts/corpus.py --surface-share F puts that share of a
# generated low-quality mesh's vertices on its surface (the boundary vertices
# counted from the tets' unshared faces, not from the generator), half by
# default; a share outside [0.05, 0.95] is refused with exit status != 0.
. "$(dirname "$0")/../lib.sh"

if ! "$PY" -c 'import numpy, scipy' 2> /dev/null; then
    for n in default 0.3 refused; do echo "ok - corpus: surface share $n # SKIP numpy or scipy missing"; done
    exit 0
fi

# share MESH: boundary vertices / vertices
cat > "$TMP/share.py" << 'PYEOF'
import os, sys
import numpy as np
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio
m = meditio.read(sys.argv[1])
nv, t = len(m.vertices), m.tets
f = np.sort(np.vstack([t[:, [1, 2, 3]], t[:, [0, 2, 3]], t[:, [0, 1, 3]], t[:, [0, 1, 2]]]), axis=1)
u, c = np.unique(f, axis=0, return_counts=True)
print("%.4f" % (len(np.unique(u[c == 1])) / nv))
PYEOF

for s in default 0.3; do
    arg=""
    want=0.5
    [ "$s" = default ] || { arg="--surface-share $s"; want=$s; }
    # shellcheck disable=SC2086
    if ! "$PY" "$ROOT/scripts/corpus.py" "$TMP/$s" --tets 6000 --only ball-lowq $arg > "$TMP/list" 2>&1; then
        fail "corpus: surface share $s" "corpus.py failed: $(tail -1 "$TMP/list")"
        continue
    fi
    got=$("$PY" "$TMP/share.py" "$TMP/$s/ball-lowq.mesh")
    # the ball keeps every surface point; a few interior points fall out with
    # the tets outside the shape, so the share comes out at or a little above
    if awk -v g="$got" -v w="$want" 'BEGIN { exit !(g >= w - 0.01 && g <= w + 0.03) }'; then
        pass "corpus: surface share $s"
    else
        fail "corpus: surface share $s" "boundary vertices $got of all, want $want"
    fi
done

if "$PY" "$ROOT/scripts/corpus.py" "$TMP/bad" --tets 6000 --only ball-lowq --surface-share 1.5 \
    > "$TMP/out" 2>&1; then
    fail "corpus: surface share refused" "--surface-share 1.5 accepted"
elif grep -q "surface-share" "$TMP/out"; then
    pass "corpus: surface share refused"
else
    fail "corpus: surface share refused" "no message naming the option: $(tail -1 "$TMP/out")"
fi
exit $((NFAIL > 0))
