#!/bin/sh
# nonfinite.sh - every mesh format qdc reads refuses a NaN or infinite
# coordinate and says where: `qdc optimize` exits 2, writes nothing, and its
# message names the file and the line of the bad number (text), the byte of
# its 8 bytes (binary), or the line of the DataArray tag holding it (VTU
# base64 and zlib data, where no line points inside the value).
# The unit cube of tests/data/sample with vertex 3's x set to 0.3125 (a value
# found nowhere else in it) is written by `qdc convert` in every format qdc
# writes, and by meshio as Abaqus, Netgen and base64 / zlib VTU; the test
# finds that value (its text, or its 8 bytes in the file's byte order) and
# replaces it by nan, -inf and 1e999 (text) or the NaN, -Inf, +Inf doubles.
. "$(dirname "$0")/../lib.sh"
cd "$TMP" || exit 1
"$PY" - "$BIN/qdc" "$ROOT/tests/data/sample/cube.mesh" << 'PYEOF'
import re, struct, subprocess, sys
qdc, cube = sys.argv[1], sys.argv[2]
SENT = 0.3125
lines = open(cube).read().split("\n")
i = lines.index("Vertices") + 4  # the count, then vertices 1, 2, 3
f = lines[i].split()
f[0] = "0.3125"
lines[i] = " ".join(f)
open("s.mesh", "w").write("\n".join(lines))
# file, qdc's name for the format (None: written by meshio), binary
files = [("medit.mesh", "medit", 0), ("a.qmesh", "qmesh", 1), ("a.json", "json", 0),
         ("g41.msh", "gmsh", 0), ("g41b.msh", "gmsh-bin", 1), ("g22.msh", "gmsh22", 0),
         ("g22b.msh", "gmsh22-bin", 1), ("g40.msh", "gmsh40", 0),
         ("a.vtk", "vtk-ascii", 0), ("b.vtk", "vtk", 1), ("a.vtu", "vtu-ascii", 0),
         ("raw.vtu", "vtu", 1), ("a.xml", "dolfin", 0), ("a.meshb", "meshb", 1),
         ("t.node", "tetgen", 0)]
for name, fmt, _ in files:
    subprocess.run([qdc, "convert", "s.mesh", name, "--out-format", fmt, "--quiet"],
                   check=True)
try:
    import meshio
    m = meshio.read("s.mesh")
    cells = [("tetra", m.cells_dict["tetra"])]
    meshio.Mesh(m.points, cells).write("a.inp")
    meshio.Mesh(m.points, cells).write("a.vol")
    files += [("a.inp", None, 0), ("a.vol", None, 0), ("b64.vtu", None, 2),
              ("zlib.vtu", None, 2)]
except ImportError:
    m = None
    print("ok - nonfinite: Abaqus, Netgen, base64 and zlib VTU # SKIP python3-meshio missing")
TEXT = re.compile(rb"(?<![0-9.eE+-])(?:0\.3125|3\.1250000000000000e-01)(?![0-9])")
# as text, as a double
BAD = [("nan", "NaN", float("nan")), ("-inf", "-Inf", float("-inf")),
       ("1e999", "+Inf", float("inf"))]


def refused(path, where, what):
    """qdc optimize exits 2, writes nothing, says where (a regex) and why"""
    r = subprocess.run([qdc, "optimize", path, "out.mesh", "--max-iter", "1"],
                       capture_output=True, text=True)
    first = r.stderr.strip().split("\n")[0]
    written = subprocess.run(["test", "-e", "out.mesh"]).returncode == 0
    subprocess.run(["rm", "-f", "out.mesh"])
    if (r.returncode == 2 and not written and
            re.match("qdc: " + re.escape(path) + where, first) and "not finite" in first):
        print("ok - nonfinite: %s %s refused: %s" % (path, what, first[5:][:120]))
    else:
        print("FAIL - nonfinite: %s %s: exit %d%s, expected %s: %s" % (
            path, what, r.returncode, ", out.mesh written" if written else "", where, first))


for name, fmt, binary in files:
    for text, dbl, val in BAD:
        bad = "bad_" + name
        if binary == 2:  # meshio writes the value into its encoded data
            p = m.points.copy()
            p[2][0] = val
            meshio.Mesh(p, cells).write(bad, compression="zlib" if "zlib" in name else None)
            b = open(bad, "rb").read()
            tag = b.find(b'Name="Points"')
            where = ":%d:[0-9]+: " % (b[:tag].count(b"\n") + 1)
            refused(bad, where, dbl + " in encoded Points")
            continue
        b = open(name, "rb").read()
        if binary:
            hits = [(b.count(struct.pack(e + "d", SENT)), e) for e in "<>"]
            order = [e for c, e in hits if c == 1]
            if len(order) != 1:
                print("FAIL - nonfinite: %s: 0.3125 found %s times" % (name, hits))
                continue
            old = struct.pack(order[0] + "d", SENT)
            at = b.find(old)
            b = b.replace(old, struct.pack(order[0] + "d", val))
            where = ": byte %d: " % at
        else:
            hits = TEXT.findall(b)
            if len(hits) != 1:
                print("FAIL - nonfinite: %s: 0.3125 found %d times" % (name, len(hits)))
                continue
            at = b.find(hits[0])
            b = b[:at] + text.encode() + b[at + len(hits[0]):]
            where = ":%d:[0-9]+: " % (b[:at].count(b"\n") + 1)
        open(bad, "wb").write(b)
        if name.endswith(".node"):
            open("bad_t.ele", "wb").write(open("t.ele", "rb").read())
        refused(bad, where, text if not binary else "%s (%s double)" % (
            dbl, "little-endian" if order[0] == "<" else "big-endian"))
PYEOF
exit 0
