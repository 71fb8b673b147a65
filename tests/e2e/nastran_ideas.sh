#!/bin/sh
# nastran_ideas.sh - Nastran bulk data and I-DEAS universal files are read by
# extension (.bdf, .nas, .unv) and by sniffing; what qdc does not read is
# refused by the CLI with `file:line:col: message` and exit 2: a malformed
# number, a GRID in another coordinate system, a CTETRA of 5 nodes (4 or 10)
# or an FE 118 tet of 4, NaN, an unknown node. The files of other tools
# (10-node CTETRA and FE 118 too) are round-tripped by roundtrip.sh
# (tests/data/real).
. "$(dirname "$0")/../lib.sh"
cd "$TMP" || exit 1
printf '$ two tets\nBEGIN BULK\nGRID    1       0       0.      0.      0.\nGRID    2       0       1.      0.      0.\nGRID    3       0       0.      1.      0.\nGRID    4       0       0.      0.      1.\nGRID,5,,1.,1.,1.-0\nCTETRA  1       1       1       2       3       4\nCTETRA  2       2       5       2       4       3\nENDDATA\n' > ok.bdf
node() { printf '%10d%10d%10d%10d\n%25s%25s%25s\n' "$1" 1 1 11 "$2" "$3" "$4"; }
{
    printf '    -1\n  2411\n'
    node 1 0.0000000000000000D+00 0.0000000000000000D+00 0.0000000000000000D+00
    node 2 1.0000000000000000D+00 0.0000000000000000D+00 0.0000000000000000D+00
    node 3 0.0000000000000000D+00 1.0000000000000000D+00 0.0000000000000000D+00
    node 4 0.0000000000000000D+00 0.0000000000000000D+00 1.0000000000000000D+00
    printf '    -1\n    -1\n  2412\n%10d%10d%10d%10d%10d%10d\n%10d%10d%10d%10d\n    -1\n' \
        1 111 1 1 7 4 1 2 3 4
} > ok.unv
cp ok.bdf ok.nas
cp ok.bdf ok.dat
cp ok.unv unv.dat
for f in ok.bdf ok.nas ok.dat ok.unv unv.dat; do
    n=$(grep -c CTETRA "$f")
    [ "$n" = 0 ] && n=1
    if "$BIN/qdc" convert "$f" out.mesh 2> err && "$BIN/qdc" quality out.mesh 2>&1 |
        grep -q "vertices, $n tets"; then
        pass "nastran/ideas: $f read ($n tets)"
    else
        fail "nastran/ideas: $f" "$(head -2 err)"
    fi
done
refused() { # NAME FILE LINE:COL TEXT
    "$BIN/qdc" convert "$2" out.mesh 2> err
    rc=$?
    if [ $rc = 2 ] && grep -q "^qdc: $2:$3: .*$4" err && [ "$(wc -l < err)" = 1 ]; then
        pass "nastran/ideas: $1: exit 2, $(cat err)"
    else
        fail "nastran/ideas: $1" "exit $rc: $(head -2 err)"
    fi
}
sed 's/1\.-0$/1.x/' ok.bdf > num.bdf
refused "malformed number" num.bdf 7:15 "expected a number, got '1.x'"
sed 's/^GRID    3       0 /GRID    3       2 /' ok.bdf > cp.bdf
refused "coordinate system" cp.bdf 5:17 "coordinate system 2 (CP) is not supported"
sed "s/^\\(CTETRA  2 .*\\)$/\\1       6/" ok.bdf > tet10.bdf
refused "CTETRA of 5 nodes" tet10.bdf 9:57 "the mid-side nodes G5-G10 must be all given (10 nodes) or all left out"
sed 's/1\.-0$/nan/' ok.bdf > nan.bdf
refused "NaN" nan.bdf 7:15 "not finite"
sed 's/       5       2       4       3/       5       2       4       9/' ok.bdf > node.bdf
refused "unknown GRID" node.bdf 9:1 "CTETRA: unknown GRID 9"
sed 's/       111/       118/' ok.unv > tet10.unv
refused "FE 118 of 4 nodes" tet10.unv 14:10 "element 1 (FE descriptor 118) has 4 nodes"
sed 's/^   1.0000000000000000D+00/                      nan/' ok.unv > nan.unv
refused "NaN (I-DEAS)" nan.unv 6:23 "not finite"
