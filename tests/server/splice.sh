#!/bin/sh
# splice.sh - a result asked in the upload's own format is the uploaded file
# with only the coordinates replaced, as `qdc optimize IN OUT` writes OUT in
# IN's format: files written by other tools (tests/data/real: MSH 4.1 with
# $PhysicalNames, point and line elements, ASCII and binary; VTU with point
# and cell arrays, zlib-compressed inline and appended, and ascii; Medit with Edges and
# vertex refs) come back from qdcd byte for byte as the CLI writes them,
# with the same strong ETag on every request; the same result in another format is written by qdc's own writer;
# GET /input in the upload's format is the upload itself. With a PostgreSQL
# store, a node that did not receive the upload reads the input from the
# database and answers the same bytes.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

REAL=$ROOT/tests/data/real
PIDS=
trap 'if [ -n "$QPID" ]; then kill -9 $QPID 2>/dev/null; fi; for p in $PIDS; do kill -9 $p 2>/dev/null; done; [ -n "${PGDIR:-}" ] && pg_cleanup; rm -rf "$TMP"' EXIT

# name  file in tests/data/real  ?format= of the upload's own variant  text only that file has
# (the formats after medit have no media type: asked by name; Abaqus,
# Netgen, Nastran and I-DEAS are served only to a job uploaded in them)
CASES="gmsh41:gmsh41.msh:gmsh:\$PhysicalNames
gmsh41bin:gmsh41_bin.msh:gmsh-bin:\$PhysicalNames
vtu:meshio_zlib.vtu:vtu:temperature
vtuapp:vtk_appended_zlib.vtu:vtu:RangeMin
vtuascii:meshio_ascii.vtu:vtu-ascii:velocity
medit:gmsh.mesh:medit:Edges
gmsh22bin:gmsh22_bin.msh:gmsh22-bin:\$PhysicalNames
gmsh40:gmsh40.msh:gmsh40:\$PhysicalNames
dolfin:dolfin.xml:dolfin:nsmap
meshb:meshio.meshb:meshb:
abaqus:calculix.inp:abaqus:MATERIAL
netgen:meshio.vol:netgen:Generated
gmsh41p2:gmsh41_p2.msh:gmsh:skin
bdf:gmsh.bdf:bdf:CBAR
bdffree:meshio_free.bdf:bdf:BULK
unv:gmsh.unv:unv:2477
xdmf:meshio.xdmf:xdmf:velocity
xdmfp2:meshio_p2.xdmf:xdmf:Tetrahedron_10"

for c in $CASES; do
    f=$(echo "$c" | cut -d: -f2)
    if [ ! -f "$REAL/$f.gz" ]; then
        echo "ok - splice: $f # SKIP tests/data/real/$f.gz is missing"
        continue
    fi
    n=$(echo "$c" | cut -d: -f1)
    ext=${f##*.}
    gzip -dc "$REAL/$f.gz" > "$TMP/$n.$ext"
    # the CLI's output: OUT in IN's format
    "$BIN/qdc" optimize "$TMP/$n.$ext" "$TMP/$n.cli.$ext" --quiet 2> "$TMP/$n.cli.err" ||
        fail "splice: $n: qdc optimize" "$(cat "$TMP/$n.cli.err")"
done

start_qdcd "$TMP/d" --workers 1 || { fail "splice: qdcd starts" "$(tail -3 "$TMP/d.log")"; exit 1; }

for c in $CASES; do
    n=$(echo "$c" | cut -d: -f1)
    fmt=$(echo "$c" | cut -d: -f3)
    mark=$(echo "$c" | cut -d: -f4)
    ext=$(echo "$c" | cut -d: -f2)
    ext=${ext##*.}
    [ -f "$TMP/$n.cli.$ext" ] || continue
    code=$(submit "$TMP/$n.$ext" application/octet-stream "" "$TMP/$n.job")
    id=$(jf "$TMP/$n.job" .id)
    st=$(wait_done "$id")
    if [ "$code" != 202 ] || [ "$st" != succeeded ]; then
        fail "splice: $n: job" "submit $code, state $st: $(head -c 300 "$TMP/$n.job")"
        continue
    fi
    echo "$n $id" >> "$TMP/ids"
    got=$(jf "$TMP/job.$id" .mesh.format)
    c1=$(req GET "/v1/jobs/$id/result?format=$fmt" "$TMP/$n.d.$ext")
    etag=$(hdr "$TMP/$n.d.$ext" ETag)
    if [ "$got" = "$fmt" ] && [ "$c1" = 200 ] && cmp -s "$TMP/$n.d.$ext" "$TMP/$n.cli.$ext" &&
        ! cmp -s "$TMP/$n.d.$ext" "$TMP/$n.$ext" && grep -aq "$mark" "$TMP/$n.d.$ext"; then
        pass "splice: $n: /result?format=$fmt is the CLI's output byte for byte ($(wc -c < "$TMP/$n.d.$ext") bytes, '$mark' kept, coordinates moved)"
    else
        fail "splice: $n: /result?format=$fmt" "sniffed '$got', status $c1, $(cmp "$TMP/$n.d.$ext" "$TMP/$n.cli.$ext" 2>&1 | head -1)"
    fi
    # the ETag is the file's SHA-256; asked again (by Accept this time) the
    # same file and ETag, and If-None-Match gives a 304
    c2=$(req GET "/v1/jobs/$id/result?format=$fmt" "$TMP/$n.d2")
    c3=$(req GET "/v1/jobs/$id/result?format=$fmt" "$TMP/$n.d3" -H "If-None-Match: $etag")
    if [ "$etag" = "\"$(sha256sum < "$TMP/$n.d.$ext" | cut -c1-64)\"" ] && [ "$c2" = 200 ] &&
        cmp -s "$TMP/$n.d2" "$TMP/$n.d.$ext" && [ "$(hdr "$TMP/$n.d2" ETag)" = "$etag" ] &&
        [ "$c3" = 304 ]; then
        pass "splice: $n: ETag is the spliced file's SHA-256, the same on a second request, 304 on If-None-Match"
    else
        fail "splice: $n: ETag" "etag $etag, second $c2 $(hdr "$TMP/$n.d2" ETag), conditional $c3"
    fi
    # /input in the upload's own format: the upload itself
    c4=$(req GET "/v1/jobs/$id/input?format=$fmt" "$TMP/$n.in")
    if [ "$c4" = 200 ] && cmp -s "$TMP/$n.in" "$TMP/$n.$ext"; then
        pass "splice: $n: /input?format=$fmt is the upload byte for byte"
    else
        fail "splice: $n: /input" "status $c4, $(cmp "$TMP/$n.in" "$TMP/$n.$ext" 2>&1 | head -1)"
    fi
done

# Another format: qdc's own writer, the same coordinates (the CLI writes the
# same file when asked for that format); the upload's extra data is gone.
if grep -q '^gmsh41 ' "$TMP/ids" 2> /dev/null; then
    id=$(awk '$1 == "gmsh41" {print $2}' "$TMP/ids")
    c1=$(req GET "/v1/jobs/$id/result?format=vtu" "$TMP/g.vtu")
    "$BIN/qdc" optimize "$TMP/gmsh41.msh" "$TMP/g.cli.vtu" --quiet 2> /dev/null
    note=$(hdr "$TMP/g.vtu" Qdc-Note)
    if [ "$c1" = 200 ] && cmp -s "$TMP/g.vtu" "$TMP/g.cli.vtu" && ! grep -q PhysicalNames "$TMP/g.vtu"; then
        pass "splice: gmsh41 upload, /result?format=vtu: qdc's own VTU writer, as the CLI's gmsh41 -> vtu"
    else
        fail "splice: gmsh41 -> vtu" "status $c1, $(cmp "$TMP/g.vtu" "$TMP/g.cli.vtu" 2>&1 | head -1)"
    fi
    # the conversion says what it could not keep; the spliced result says nothing
    same=$(hdr "$TMP/gmsh41.d2" Qdc-Note)
    case $note in
    *"vtu writer"*"only vertices, tets, triangles, their region tags and the point data are kept")
        if [ -z "$same" ]; then
            pass "splice: gmsh41 -> vtu carries Qdc-Note: $note; the spliced gmsh41 result none"
        else
            fail "splice: Qdc-Note" "the spliced result has one: $same"
        fi
        ;;
    *) fail "splice: Qdc-Note" "the vtu conversion's note: '$note'" ;;
    esac
    # a format without a media type, by name: qdc's own writer (the CLI's
    # gmsh41 -> meshb), served as application/octet-stream; TetGen's two
    # files are not offered (400, with the formats that are: Abaqus and MED
    # among them, by qdc's own writers)
    c1=$(req GET "/v1/jobs/$id/result?format=meshb" "$TMP/g.meshb")
    "$BIN/qdc" optimize "$TMP/gmsh41.msh" "$TMP/g.cli.meshb" --quiet 2> /dev/null
    c2=$(req GET "/v1/jobs/$id/result?format=tetgen" "$TMP/g.inp")
    if [ "$c1" = 200 ] && cmp -s "$TMP/g.meshb" "$TMP/g.cli.meshb" &&
        [ "$(hdr "$TMP/g.meshb" Content-Type)" = application/octet-stream ] && [ "$c2" = 400 ] &&
        jq -e '(.formats | index("abaqus")) and (.formats | index("med")) and (.formats | index("tetgen") | not)' "$TMP/g.inp" > /dev/null; then
        pass "splice: gmsh41 upload, /result?format=meshb: qdc's Medit binary writer (octet-stream), as the CLI's; ?format=tetgen: 400, not offered (abaqus and med are)"
    else
        fail "splice: gmsh41 -> meshb/tetgen" "meshb $c1 $(hdr "$TMP/g.meshb" Content-Type) $(cmp "$TMP/g.meshb" "$TMP/g.cli.meshb" 2>&1 | head -1); tetgen $c2 $(head -c 300 "$TMP/g.inp")"
    fi
fi
# A binary MSH 4.1 file sent as "model/vnd.gmsh" (the family, no
# encoding=binary): recorded as gmsh-bin, the variant its header says, so that
# the result in it is the CLI's output (it was recorded as gmsh, and then
# neither ?format=gmsh nor gmsh-bin kept $PhysicalNames)
if [ -f "$TMP/gmsh41bin.cli.msh" ]; then
    code=$(submit "$TMP/gmsh41bin.msh" model/vnd.gmsh "" "$TMP/fam.job")
    id=$(jf "$TMP/fam.job" .id)
    st=$(wait_done "$id")
    got=$(jf "$TMP/job.$id" .mesh.format)
    c1=$(req GET "/v1/jobs/$id/result?format=gmsh-bin" "$TMP/fam.msh")
    if [ "$code" = 202 ] && [ "$st" = succeeded ] && [ "$got" = gmsh-bin ] && [ "$c1" = 200 ] &&
        cmp -s "$TMP/fam.msh" "$TMP/gmsh41bin.cli.msh"; then
        pass "splice: binary MSH 4.1 sent as model/vnd.gmsh: recorded as gmsh-bin, /result?format=gmsh-bin is the CLI's output"
    else
        fail "splice: model/vnd.gmsh binary" "submit $code, $st, recorded '$got', result $c1, $(cmp "$TMP/fam.msh" "$TMP/gmsh41bin.cli.msh" 2>&1 | head -1)"
    fi
fi
stop_qdcd

# PostgreSQL: the upload sent to node a, the result asked from node b (its own
# --data, so the input and result.qmesh come from the database).
. "$(dirname "$0")/pg.inc"
QDCD=${QDCD:-$BIN/qdcd}
QM=application/octet-stream
if ! pg_available; then
    pg_skip splice "pg: the result spliced on another node"
    exit $((NFAIL > 0))
fi
pg_started "splice: pg" || exit 1
node a "$TMP/pa" --workers 1 || { fail "splice: pg: node a" "$(tail -3 "$TMP/a.log")"; exit 1; }
for n in gmsh41 vtu; do
    ext=msh
    [ $n = vtu ] && ext=vtu
    [ -f "$TMP/$n.cli.$ext" ] || continue
    c=$(post "$URL_a" "$TMP/$n.$ext" "" "$TMP/p$n.job")
    id=$(jf "$TMP/p$n.job" .id)
    echo "$n $ext $id $c $(wait_done "$URL_a" "$id")" >> "$TMP/pids"
done
# node b starts once the jobs are over: it neither received nor ran them
node b "$TMP/pb" --workers 1 || { fail "splice: pg: node b" "$(tail -3 "$TMP/b.log")"; exit 1; }
while read -r n ext id c st; do
    fmt=gmsh
    [ $n = vtu ] && fmt=vtu
    had=$(ls "$TMP/pb/jobs/$id" 2> /dev/null | tr '\n' ' ')
    cb=$(curl -s -o "$TMP/p$n.b.$ext" -w '%{http_code}' "$URL_b/v1/jobs/$id/result?format=$fmt")
    ca=$(curl -s -o "$TMP/p$n.a.$ext" -w '%{http_code}' "$URL_a/v1/jobs/$id/result?format=$fmt")
    if [ "$c" = 202 ] && [ "$st" = succeeded ] && [ "$cb" = 200 ] && [ "$ca" = 200 ] &&
        [ -z "$had" ] && [ -f "$TMP/pb/jobs/$id/$(ls "$TMP/pa/jobs/$id" | grep '^input')" ] &&
        cmp -s "$TMP/p$n.b.$ext" "$TMP/$n.cli.$ext" && cmp -s "$TMP/p$n.a.$ext" "$TMP/$n.cli.$ext"; then
        pass "splice: pg: $n: node b (input fetched from the database) and node a answer the CLI's bytes"
    else
        fail "splice: pg: $n" "submit $c, state $st, b $cb (cache before: '$had'), a $ca, $(cmp "$TMP/p$n.b.$ext" "$TMP/$n.cli.$ext" 2>&1 | head -1)"
    fi
done < "$TMP/pids"
stop "$PID_b"
stop "$PID_a"
exit $((NFAIL > 0))
