#!/bin/sh
# gmsh_versions.sh - MSH versions qdc does not read are refused by the CLI
# with `file:line:col: message` and exit 2, the message naming the version
# found and the versions read (4.1 ASCII/binary, 4.0 ASCII, 2.x
# ASCII/binary, and MSH 1 by its own reader): 3.0, 4.2, 4.0 binary (Gmsh >=
# 4.1 cannot write it) and big-endian binary. MSH 1 ($NOD) is read, as a .msh
# and when found by sniffing. The versions read are round-tripped by
# roundtrip.sh (tests/data/real).
. "$(dirname "$0")/../lib.sh"
cd "$TMP" || exit 1
printf '$NOD\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$ENDNOD\n$ELM\n1\n1 4 1 1 4 1 2 3 4\n$ENDELM\n' > msh1.msh
cp msh1.msh msh1.dat
printf '$MeshFormat\n3.0 0 8\n$EndMeshFormat\n' > v30.msh
printf '$MeshFormat\n4.2 0 8\n$EndMeshFormat\n' > v42.msh
printf '$MeshFormat\n4 1 8\n\001\000\000\000\n$EndMeshFormat\n' > b40.msh
printf '$MeshFormat\n4.1 1 8\n\000\000\000\001\n$EndMeshFormat\n' > be41.msh
refused() { # FILE LINE:COL TEXT...
    f=$1 at=$2
    shift 2
    "$BIN/qdc" convert "$f" out.mesh 2> err
    rc=$?
    if [ $rc = 2 ] && grep -q "^qdc: $f:$at: $*" err; then
        pass "gmsh versions: $f refused (exit 2, $f:$at: $(printf "%s" "$*" | tr -d "\\\\"))"
    else
        fail "gmsh versions: $f" "exit $rc: $(head -2 err)"
    fi
}
for f in msh1.msh msh1.dat; do
    "$BIN/qdc" convert "$f" out.mesh 2> err && grep -q '^Tetrahedra' out.mesh &&
        "$BIN/qdc" quality out.mesh | grep -q '4 vertices, 1 tets' &&
        pass "gmsh versions: MSH 1 $f read (its own reader)" ||
        fail "gmsh versions: MSH 1 $f" "$(head -2 err)"
done
refused v30.msh 2:1 '\$MeshFormat: version 3 not supported (4.1, 4.0, 2.2, 2.1 or 2.0)'
refused v42.msh 2:1 '\$MeshFormat: version 4.2 not supported (4.1, 4.0, 2.2, 2.1 or 2.0)'
refused b40.msh 2:1 'MSH 4.0 binary is not supported (4.0 ASCII, 4.1 ASCII or binary, 2.2 ASCII or binary)'
"$BIN/qdc" convert be41.msh out.mesh 2> err
rc=$?
[ $rc = 2 ] && grep -q '^qdc: be41.msh: byte 20: \$MeshFormat: big-endian binary files are not supported' err &&
    pass "gmsh versions: big-endian binary refused at its byte offset" ||
    fail "gmsh versions: big-endian" "exit $rc: $(head -2 err)"
exit 0
