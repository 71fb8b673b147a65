#!/bin/sh
# formats.sh - content negotiation: an upload in every mesh format
# (by Content-Type, ?format= or sniffed) becomes a job with the same sizes and
# notes about skipped elements; the result comes back in every format (by
# ?format= or Accept, with its own strong ETag) with the region tags; 415 and
# 406 list the types. Closed surfaces (STL, OFF) are tetrahedralized by the
# worker through `qdc tetra` in a child process: an open one is a 422 at
# upload, a self-intersecting one a failed job with TetGen's reason, and a
# crashing or hanging child (a stand-in for qdc) fails or cancels its job
# while the daemon goes on serving.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/daemon.inc"

QDC=$BIN/qdc
cat > "$TMP/h.py" << 'EOF'
import os, sys
sys.path.insert(0, os.environ["QDC_TOOLS"])
import meditio

def regions(src, out):
    """src with tet refs 1..4 by the quadrant of the tet's centroid."""
    m = meditio.read(src)
    c = m.vertices[m.tets].mean(axis=1)
    meditio.write(out, m.vertices, m.tets, tet_refs=1 + (c[:, 0] > 0.5) + 2 * (c[:, 1] > 0.5))

def same(a, b):
    """Same vertex and tet counts, same tets with the same tags, in order."""
    ma, mb = meditio.read(a), meditio.read(b)
    xa, ta, ra = ma.vertices, ma.tets, ma.tet_refs
    xb, tb, rb = mb.vertices, mb.tets, mb.tet_refs
    if len(xa) != len(xb) or len(ta) != len(tb):
        sys.exit("%d/%d vertices, %d/%d tets" % (len(xa), len(xb), len(ta), len(tb)))
    if not (ta == tb).all():
        sys.exit("connectivity differs")
    if not (ra == rb).all():
        sys.exit("tags differ")
    print(len(xa), "vertices,", len(ta), "tets, tags", sorted(set(str(r) for r in ra.tolist())))

def point_element(src, out):
    """A MSH 2.2 file with one more element: a point (type 15), which qdc skips."""
    lines = open(src).read().split("\n")
    k = lines.index("$Elements")
    n = int(lines[k + 1])
    lines[k + 1] = str(n + 1)
    lines.insert(k + 2, "%d 15 2 0 1 1" % (n + 1000))
    open(out, "w").write("\n".join(lines))

cmd, a = sys.argv[1], sys.argv[2:]
{"regions": lambda: regions(*a), "same": lambda: same(*a), "point": lambda: point_element(*a)}[cmd]()
EOF
H="$PY $TMP/h.py"

$H regions "$ROOT/tests/data/sample/cube.mesh" "$TMP/in.mesh"
# name:extension:media type of every format, inputs written by qdc itself
FMTS="medit:mesh:model/x-medit qmesh:qmesh:application/vnd.qdc.mesh json:json:application/json
gmsh:msh:model/vnd.gmsh gmsh-bin:msh:model/vnd.gmsh;encoding=binary
gmsh22:msh:model/vnd.gmsh;version=2.2 vtk:vtk:application/vnd.vtk
vtk-ascii:vtk:application/vnd.vtk;encoding=ascii vtu:vtu:application/vnd.vtk.vtu+xml
vtu-ascii:vtu:application/vnd.vtk.vtu+xml;encoding=ascii"
for e in $FMTS; do
    f=${e%%:*}; x=${e#*:}; x=${x%%:*}
    "$QDC" optimize --max-iter 0 --finish off --quiet --out-format "$f" "$TMP/in.mesh" "$TMP/in.$f.$x" ||
        fail "write input $f" "qdc optimize exit $?"
done
$H point "$TMP/in.gmsh22.msh" "$TMP/in.point.msh"
for k in cube open selfx; do $PY "$ROOT/tests/server/surfaces.py" stl $k "$TMP/$k.stl"; done
$PY "$ROOT/tests/server/surfaces.py" off "$TMP/cube.off"

start_qdcd "$TMP/d" --workers 2 || { fail "start" "$(tail -3 "$TMP/d.log")"; exit 1; }
NV=$(awk '/^Vertices/ { getline; print; exit }' "$TMP/in.mesh")
NT=$(awk '/^Tetrahedra/ { getline; print; exit }' "$TMP/in.mesh")


# Uploads: each format by its Content-Type (qmesh also by ?format= and sniffed).
ids=
for e in $FMTS; do
    f=${e%%:*}; x=${e#*:}; t=${x#*:}; x=${x%%:*}
    code=$(submit "$TMP/in.$f.$x" "$t" "max_iter=1" "$TMP/sub.$f")
    if [ "$code" = 202 ] && [ "$(jf "$TMP/sub.$f" .mesh.format)" = "$f" ] &&
        [ "$(jf "$TMP/sub.$f" .mesh.vertices)" = "$NV" ] && [ "$(jf "$TMP/sub.$f" .mesh.tets)" = "$NT" ]; then
        ids="$ids $f:$(jf "$TMP/sub.$f" .id)"
    else
        fail "upload $f as $t" "$code $(head -c 300 "$TMP/sub.$f")"
    fi
done
[ "$(echo $ids | wc -w)" = 10 ] && pass "upload: all 10 formats by Content-Type: 202, format named, $NV vertices, $NT tets"
code=$(submit "$TMP/in.gmsh-bin.msh" application/octet-stream "format=gmsh&max_iter=1" "$TMP/out")
[ "$code" = 202 ] && [ "$(jf "$TMP/out" .mesh.format)" = gmsh-bin ] && [ "$(jf "$TMP/out" .mesh.tets)" = "$NT" ] &&
    pass "upload: ?format=gmsh reads binary MSH 4.1 too, recorded as gmsh-bin (its header's variant)" ||
    fail "?format=gmsh" "$code $(head -c 300 "$TMP/out")"
code=$(submit "$TMP/in.vtu.vtu" application/octet-stream "max_iter=1" "$TMP/out")
[ "$code" = 202 ] && [ "$(jf "$TMP/out" .mesh.format)" = vtu ] &&
    pass "upload: octet-stream VTU sniffed" || fail "sniff vtu" "$code $(head -c 300 "$TMP/out")"
code=$(req POST "/v1/jobs?max_iter=1" "$TMP/out" --data-binary "@$TMP/in.gmsh22.msh")
[ "$code" = 202 ] && [ "$(jf "$TMP/out" .mesh.format)" = gmsh22 ] &&
    pass "upload: no Content-Type, MSH 2.2 sniffed" || fail "sniff msh22" "$code $(head -c 300 "$TMP/out")"
code=$(submit "$TMP/in.point.msh" "model/vnd.gmsh;version=2.2" "max_iter=1" "$TMP/out")
[ "$code" = 202 ] && jq -e '.notes | length >= 1 and (join(" ") | test("skip|type 15|ignored"; "i"))' "$TMP/out" > /dev/null &&
    [ "$(jf "$TMP/out" .mesh.tets)" = "$NT" ] &&
    pass "upload: a point element is skipped with a note: $(jq -c .notes "$TMP/out")" ||
    fail "notes" "$code $(head -c 400 "$TMP/out")"

# 415: unknown type, unknown ?format=, TetGen (two files), garbage sniffed.
ntypes=$(
    n=0
    for e in $FMTS; do n=$((n + 1)); done
    echo $((n + 5))
)
for c in "image/png::in.medit.mesh" "application/octet-stream:format=obj5:in.medit.mesh" \
    "application/octet-stream:format=tetgen:in.medit.mesh" "application/octet-stream::h.py"; do
    t=${c%%:*}; r=${c#*:}; q=${r%%:*}; f=${r#*:}
    code=$(submit "$TMP/$f" "$t" "$q" "$TMP/out")
    if [ "$code" = 415 ] && [ "$(hdr "$TMP/out" Content-Type)" = application/problem+json ] &&
        jq -e --argjson n "$ntypes" '(.accepted | length == $n) and (.accepted | index("model/stl") != null)
            and (.accepted | index("model/vnd.gmsh;encoding=binary") != null)
            and (.accepted | index("application/vnd.qdc.surface+smesh") != null)
            and (.formats | index("vtu-ascii") != null) and (.detail | length > 0)' "$TMP/out" > /dev/null; then
        pass "415 for $t ${q:-(no ?format)} ($f): lists the $ntypes accepted types"
    else
        fail "415 $t $q" "$code $(head -c 400 "$TMP/out")"
    fi
done
code=$(submit "$TMP/in.medit.mesh" model/x-medit "tetgen_quality=1.4" "$TMP/out")
[ "$code" = 400 ] && jq -e '.detail | test("surface")' "$TMP/out" > /dev/null &&
    pass "tetgen_quality on a mesh upload: 400" || fail "tetgen opt on mesh" "$code $(head -c 300 "$TMP/out")"

# Every job succeeds with the same sizes; results of the medit job in every format.
bad=0
for p in $ids; do
    st=$(wait_done "${p#*:}")
    [ "$st" = succeeded ] || { bad=1; fail "job ${p%%:*}" "$st $(head -c 300 "$TMP/job.${p#*:}")"; }
done
[ $bad = 0 ] && pass "all 10 jobs succeeded"
ID=$(echo $ids | tr ' ' '\n' | awk -F: '$1 == "medit" { print $2 }')
for e in $FMTS; do
    f=${e%%:*}; x=${e#*:}; t=${x#*:}; x=${x%%:*}
    code=$(req GET "/v1/jobs/$ID/result?format=$f" "$TMP/res.$f.$x")
    ct=$(hdr "$TMP/res.$f.$x" Content-Type)
    etag=$(hdr "$TMP/res.$f.$x" ETag)
    "$QDC" optimize --max-iter 0 --finish off --quiet "$TMP/res.$f.$x" "$TMP/back.$f.mesh" 2> "$TMP/err"
    if [ "$code" = 200 ] && [ "$ct" = "$t" ] && [ ${#etag} = 66 ] &&
        out=$($H same "$TMP/in.mesh" "$TMP/back.$f.mesh" 2>&1); then
        echo "$etag" >> "$TMP/etags"
        pass "result ?format=$f: $ct, strong ETag, read back: $out"
    else
        fail "result $f" "$code '$ct' '$etag' $(cat "$TMP/err") ${out:-}"
    fi
done
[ "$(sort -u "$TMP/etags" | wc -l)" = 10 ] && pass "10 representations, 10 ETags" ||
    fail "etags" "$(sort -u "$TMP/etags" | wc -l) distinct"
for f in gmsh22.msh vtu.vtu vtk.vtk; do
    nv=$($PY "$QUALITY" "$TMP/res.$f" 2> "$TMP/err" | jq -r '"\(.n_verts) \(.n_tets)"')
    [ "$nv" = "$NV $NT" ] && pass "quality.py reads the $f result: $nv" || fail "quality.py $f" "'$nv' $(tail -2 "$TMP/err")"
done

# Accept: parameters pick variants, the client's order wins, q=0 excludes,
# wildcards get the binary; nothing offered: 406 with the list.
acc() { # ACCEPT WANT-CONTENT-TYPE
    code=$(req GET "/v1/jobs/$ID/result" "$TMP/acc" -H "Accept: $1")
    ct=$(hdr "$TMP/acc" Content-Type)
    [ "$code" = 200 ] && [ "$ct" = "$2" ] && pass "Accept: $1 -> $ct" || fail "Accept: $1" "$code '$ct' (want $2)"
}
acc 'model/vnd.gmsh;version=2.2' 'model/vnd.gmsh;version=2.2'
acc 'image/png, application/vnd.vtk.vtu+xml; encoding=ascii; q=0.2, model/x-medit' 'application/vnd.vtk.vtu+xml;encoding=ascii'
acc 'application/vnd.vtk;q=0, model/vnd.gmsh;encoding=binary' 'model/vnd.gmsh;encoding=binary'
acc '*/*' 'application/vnd.qdc.mesh'
head -c 11 "$TMP/res.gmsh22.msh" | grep -q 'MeshFormat' && sed -n 2p "$TMP/res.gmsh22.msh" | grep -q '^2.2 0' &&
    pass "the gmsh22 result is MSH 2.2 ASCII" || fail "gmsh22 header" "$(head -2 "$TMP/res.gmsh22.msh")"
code=$(req GET "/v1/jobs/$ID/result" "$TMP/out" -H 'Accept: image/png, model/vnd.gmsh;q=0')
[ "$code" = 406 ] && [ "$(hdr "$TMP/out" Content-Type)" = application/problem+json ] &&
    jq -e '(.offered | length == 10) and (.offered | index("application/vnd.vtk.vtu+xml") != null)
        and (.formats | index("gmsh22") != null)' "$TMP/out" > /dev/null &&
    pass "406: lists the 10 offered types" || fail "406" "$code $(head -c 400 "$TMP/out")"
code=$(req GET "/v1/jobs/$ID/result?format=tetgen" "$TMP/out")
[ "$code" = 400 ] && jq -e '.parameter == "format" and (.offered | length == 10)' "$TMP/out" > /dev/null &&
    pass "?format=tetgen: 400 with the offered list" || fail "format=tetgen" "$code $(head -c 300 "$TMP/out")"
etag=$(hdr "$TMP/res.vtu.vtu" ETag)
code=$(req GET "/v1/jobs/$ID/result?format=vtu" "$TMP/out" -H "If-None-Match: $etag")
code2=$(req GET "/v1/jobs/$ID/result?format=vtu" "$TMP/out2")
[ "$code" = 304 ] && [ "$code2" = 200 ] && [ "$(hdr "$TMP/out2" ETag)" = "$etag" ] && cmp -s "$TMP/out2" "$TMP/res.vtu.vtu" &&
    [ "$(hdr "$TMP/out2" Vary)" = Accept ] &&
    pass "converted result: 304 on If-None-Match, same bytes and ETag the second time, Vary: Accept" ||
    fail "vtu etag" "$code $code2"

# Surfaces.
code=$(submit "$TMP/cube.stl" model/stl "max_iter=3&tetgen_quality=1.4&max_volume=0.005" "$TMP/sub.stl")
code2=$(submit "$TMP/cube.off" application/octet-stream "max_iter=3" "$TMP/sub.off")
code3=$(submit "$TMP/selfx.stl" model/stl "" "$TMP/sub.selfx")
if [ "$code" = 202 ] && [ "$code2" = 202 ] && [ "$code3" = 202 ] &&
    jq -e '.mesh.format == "stl" and .mesh.surface and .mesh.vertices == 8 and .options.tetgen_quality == 1.4' "$TMP/sub.stl" > /dev/null &&
    [ "$(jf "$TMP/sub.off" .mesh.format)" = off ]; then
    pass "surfaces: STL (model/stl) and OFF (sniffed) accepted as surface jobs"
else
    fail "surface upload" "$code $code2 $code3 $(head -c 300 "$TMP/sub.stl") $(head -c 200 "$TMP/sub.off")"
fi
code=$(submit "$TMP/open.stl" model/stl "" "$TMP/out")
[ "$code" = 422 ] && jq -e '(.type | endswith("invalid-surface")) and (.detail | test("not closed")) and .format == "stl"' "$TMP/out" > /dev/null &&
    pass "open STL: 422 at upload: $(jf "$TMP/out" .detail)" || fail "open stl" "$code $(head -c 300 "$TMP/out")"
printf 'solid e\nendsolid e\n' > "$TMP/empty.stl"
code=$(submit "$TMP/empty.stl" model/stl "" "$TMP/out")
[ "$code" = 422 ] && pass "empty STL: 422: $(jf "$TMP/out" .detail)" || fail "empty stl" "$code $(head -c 300 "$TMP/out")"
SID=$(jf "$TMP/sub.stl" .id)
st=$(wait_done "$SID")
req GET "/v1/jobs/$SID/result?format=medit" "$TMP/cube_res.mesh" > /dev/null
q=$($PY "$QUALITY" "$TMP/cube_res.mesh" 2> "$TMP/err")
nt=$(echo "$q" | jq -r .n_tets)
if [ "$st" = succeeded ] && [ "$(echo "$q" | jq -r .n_inverted)" = 0 ] && [ "${nt:-0}" -gt 100 ] &&
    [ "$(jf "$TMP/job.$SID" .mesh.tets)" = "$nt" ]; then
    pass "closed STL cube: job succeeded, result $nt tets (job says $(jf "$TMP/job.$SID" .mesh.tets)), 0 inverted, min quality $(echo "$q" | jq -r .eta_min 2> /dev/null)"
else
    fail "stl job" "$st $(head -c 300 "$TMP/job.$SID") $q $(tail -2 "$TMP/err")"
fi
st=$(wait_done "$(jf "$TMP/sub.off" .id)")
[ "$st" = succeeded ] && pass "closed OFF cube: job succeeded" || fail "off job" "$st"
XID=$(jf "$TMP/sub.selfx" .id)
st=$(wait_done "$XID")
[ "$st" = failed ] && jq -e '(.error.type | endswith("/tetgen")) and .error.status == 422 and (.error.detail | test("intersect"))
    and (.error.detail | test("jobs/") | not)' "$TMP/job.$XID" > /dev/null &&
    pass "self-intersecting STL: job failed: $(jf "$TMP/job.$XID" .error.detail)" ||
    fail "selfx job" "$st $(head -c 400 "$TMP/job.$XID")"
code=$(submit "$TMP/in.medit.mesh" model/x-medit "max_iter=1" "$TMP/out")
[ "$code" = 202 ] && [ "$(wait_done "$(jf "$TMP/out" .id)")" = succeeded ] && [ "$(req GET /livez "$TMP/lz")" = 200 ] &&
    pass "after the TetGen failure: /livez 200, a new job succeeds" || fail "after selfx" "$code"
stop_qdcd || fail "SIGTERM" "exit status $?"

# A child that crashes, and one that hangs (time limit; cancel), stand in for qdc.
printf '#!/bin/sh\necho "TetGen says something on stdout"\nkill -SEGV $$\n' > "$TMP/crash.sh"
printf '#!/bin/sh\nexec sleep 30\n' > "$TMP/hang.sh"
chmod +x "$TMP/crash.sh" "$TMP/hang.sh"
start_qdcd "$TMP/c" --workers 2 --qdc "$TMP/crash.sh" || { fail "start crash" "$(tail -3 "$TMP/c.log")"; exit 1; }
submit "$TMP/cube.stl" model/stl "" "$TMP/out" > /dev/null
CID=$(jf "$TMP/out" .id)
st=$(wait_done "$CID")
[ "$st" = failed ] && jq -e '.error.detail == "TetGen crashed (signal 11) on this surface" and (.error.type | endswith("/tetgen"))' "$TMP/job.$CID" > /dev/null &&
    [ "$(req GET /livez "$TMP/lz")" = 200 ] && grep -q 'stdout' "$TMP/c/jobs/$CID/tetgen.log" &&
    pass "crashing child: job failed '$(jf "$TMP/job.$CID" .error.detail)', its output in tetgen.log, /livez 200" ||
    fail "crash" "$st $(head -c 300 "$TMP/job.$CID")"
stop_qdcd
# The limit is long enough that the cancel, sent once the job runs, comes first
# even on a busy machine; the cancelled job must end before the limit would end it.
start_qdcd "$TMP/h" --workers 2 --qdc "$TMP/hang.sh" --job-time-limit 5 || { fail "start hang" "$(tail -3 "$TMP/h.log")"; exit 1; }
submit "$TMP/cube.stl" model/stl "" "$TMP/out" > /dev/null
HID=$(jf "$TMP/out" .id)
submit "$TMP/cube.stl" model/stl "" "$TMP/out" > /dev/null
KID=$(jf "$TMP/out" .id)
wait_running "$KID"
t0=$(date +%s)
req POST "/v1/jobs/$KID:cancel" "$TMP/out" > /dev/null
st=$(wait_done "$KID")
dt=$(($(date +%s) - t0))
st2=$(wait_done "$HID")
[ "$st" = cancelled ] && [ $dt -lt 5 ] && pass "hanging child: cancel kills it, job cancelled in ${dt} s (limit 5 s)" ||
    fail "cancel hang" "$st after ${dt} s: $(head -c 300 "$TMP/job.$KID")"
[ "$st2" = failed ] && jq -e '.error.detail | test("time limit")' "$TMP/job.$HID" > /dev/null &&
    pass "hanging child: killed at the job's time limit: $(jf "$TMP/job.$HID" .error.detail)" ||
    fail "hang" "$st2 $(head -c 300 "$TMP/job.$HID")"
stop_qdcd || fail "SIGTERM" "exit status $?"

# A DOLFIN XML upload (a format without a media type) is taken by sniffing and
# optimized; its result and input come in every format qdc writes, those
# without a media type by name (dolfin, meshb, abaqus, med...), but not in
# TetGen's, which is two files: ?format=tetgen is a 400 naming the offered
# ones, not a dropped connection.
start_qdcd "$TMP/x" --workers 1 || { fail "start x" "$(tail -3 "$TMP/x.log")"; exit 1; }
gzip -dc "$ROOT/tests/data/real/dolfin.xml.gz" > "$TMP/a.xml"
code=$(req POST /v1/jobs "$TMP/dx" --data-binary "@$TMP/a.xml" -H "Content-Type: application/octet-stream")
DX=$(jf "$TMP/dx" .id)
st=$(wait_done "$DX")
[ "$code" = 202 ] && [ "$st" = succeeded ] && pass "DOLFIN XML upload sniffed and optimized ($st)" ||
    fail "DOLFIN XML upload" "$code $st $(head -c 300 "$TMP/dx")"
bad=
for f in tetgen; do
    for what in result input; do
        c=$(req GET "/v1/jobs/$DX/$what?format=$f" "$TMP/fx")
        [ "$c" = 400 ] && jq -e '(.offered | length > 0) and (.formats | index("dolfin"))' "$TMP/fx" > /dev/null 2>&1 ||
            bad="$bad $what:$f=$c"
    done
done
# MED (qdc-h5 med-new), read back through qdc-h5, where it is built
med=
[ -x "$BIN/qdc-h5" ] && med=med
for f in qmesh medit gmsh vtu dolfin meshb gmsh22-bin gmsh40 abaqus netgen msh1 bdf unv $med; do
    c=$(req GET "/v1/jobs/$DX/result?format=$f" "$TMP/fx")
    [ "$c" = 200 ] && "$BIN/qdc" quality "$TMP/fx" > /dev/null 2>&1 || bad="$bad result:$f=$c"
done
[ -z "$bad" ] && pass "a DOLFIN upload: its result in every format qdc writes (by name for dolfin, meshb, gmsh22-bin, gmsh40, abaqus, netgen, msh1, bdf, unv, ${med:-(med: qdc-h5 not built)}; each read back by qdc quality); tetgen: 400 with the offered list" ||
    fail "result formats" "$bad"
# The upload is kept under the name the format table gives dolfin
# (job_input_name used to fall back to input.mesh for six formats).
[ -f "$TMP/x/jobs/$DX/input.xml" ] && [ ! -e "$TMP/x/jobs/$DX/input.mesh" ] &&
    pass "a DOLFIN upload is kept as input.xml (the table's input name)" ||
    fail "input name" "$(ls "$TMP/x/jobs/$DX" | tr '\n' ' ')"
# GET /v1/formats is the library's table, as `qdc formats` prints it.
"$BIN/qdc" formats > "$TMP/formats.cli"
code=$(req GET /v1/formats "$TMP/formats.srv")
[ "$code" = 200 ] && cmp -s "$TMP/formats.cli" "$TMP/formats.srv" &&
    case $(hdr "$TMP/formats.srv" Content-Type) in application/json*) true ;; *) false ;; esac &&
    pass "GET /v1/formats: the $(jq '.formats | length' "$TMP/formats.srv") formats and $(jq '.surfaces | length' "$TMP/formats.srv") surfaces of \`qdc formats\`, byte for byte" ||
    fail "GET /v1/formats" "$code $(head -c 300 "$TMP/formats.srv")"
stop_qdcd || fail "SIGTERM x" "exit status $?"
exit $((NFAIL > 0))
