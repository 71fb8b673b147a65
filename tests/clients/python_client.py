"""python_client.py - end-to-end checks of clients/python/qdc_client.py against
the daemon at $URL (started by python.sh). Prints ok/FAIL lines."""
import array
import gzip
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.environ["ROOT"], "clients", "python"))
import qdc_client  # noqa: E402
from qdc_client import Client, JobFailed, Mesh, QdcError  # noqa: E402

URL, TMP, MESH, QDC = os.environ["URL"], os.environ["TMP"], os.environ["MESH"], os.environ["QDC"]
ROOT = os.environ["ROOT"]
NT = int(os.environ["NT"])
nfail = 0


def check(name, cond, why=""):
    global nfail
    if cond:
        print("ok - python: " + name)
    else:
        nfail += 1
        print("FAIL - python: %s: %s" % (name, why))


def valid(path, nt):
    out = subprocess.run([QDC, "quality", path], capture_output=True, text=True)
    return out.returncode == 0 and (" %d tets, 0 inverted" % nt) in out.stdout, out.stdout + out.stderr


c = Client(URL)

# 1. a Medit path, wait with on_progress, result as a Mesh, report
recs = []
job = c.submit(MESH, {"max_iter": 3})
final = c.wait(job, on_progress=recs.append)
seqs = [r.get("seq") for r in recs]
its = [r["iteration"] for r in recs]
check("submit(path) + wait: %d records, in order" % len(recs),
      final["state"] == "succeeded" and len(recs) >= 3 and its == sorted(its) and
      (None in seqs or seqs == list(range(len(recs)))), "%s %s" % (final["state"], seqs))
m = c.result(job)
check("result() -> Mesh with %d vertices, %d tets" % (m.nv, m.nt),
      isinstance(m, Mesh) and m.nt == NT and m.regions is None or m.nt == NT, m.nt)
rep = c.report(job)
check("report(): before/after quality, boundary error",
      rep["after"]["n_tets"] == NT and rep["after"]["mean_ratio_min"] >= rep["before"]["mean_ratio_min"]
      and "hausdorff_rel" in rep["boundary_error"], json.dumps(rep)[:200])
# the file's name by default and a label: in the job
j = c.job(job)
check("submit(path): the job's file_name is the path's last part (%s)" % j.get("file_name"),
      j.get("file_name") == os.path.basename(MESH) and "label" not in j, json.dumps(j)[:300])
jl = c.submit(MESH, {"max_iter": 1}, name="bunny_low_10k.mesh.gz", label="py run é")
jl = c.wait(jl)
check("submit(name=, label=): GET /v1/jobs/ID carries them",
      jl.get("file_name") == "bunny_low_10k.mesh.gz" and jl.get("label") == "py run é",
      json.dumps(jl)[:300])
# the outcome in words: the report's texts, nothing made up here
lines = qdc_client.outcome_lines(rep)
o = c.outcome(job)
check("outcome_lines(report): %d lines, the report's summary, warnings and suggestions" % len(lines),
      lines and lines[0] == "outcome: " + o["summary"] and "left: " in o["summary"] and
      lines[1:] == ["warning: " + w for w in o["warnings"]] + ["suggestion: " + t for t in o["suggestions"]],
      "%s %s" % (lines, o))

# 2. the binary format: round trip through to_bytes/from_bytes and a .qmesh file
m.save(os.path.join(TMP, "py.qmesh"))
ok, out = valid(os.path.join(TMP, "py.qmesh"), NT)
check("Mesh.save(.qmesh) is read by qdc (binary writer matches the C reader)", ok, out)
same = Mesh.from_bytes(m.to_bytes())
check("to_bytes/from_bytes round trip", same.xyz == m.xyz and same.tets == m.tets, "")
srv = open(os.path.join(TMP, "srv.qmesh"), "wb")
srv.write(c._request("GET", "/v1/jobs/%s/result?format=qmesh" % job["id"])[2])
srv.close()
check("to_bytes() is byte-identical to the server's binary result",
      m.to_bytes() == open(os.path.join(TMP, "srv.qmesh"), "rb").read(), "")

# 3. arrays (plain lists), with regions and fixed vertices; result to files
m0 = Mesh.load(os.environ["MESHQ"])  # the input, converted by meshtool.py
xyz = [list(m0.xyz[3 * i:3 * i + 3]) for i in range(m0.nv)]
tets = [list(m0.tets[4 * i:4 * i + 4]) for i in range(m0.nt)]
regions = [7] * m0.nt
fixed = [i % 2 == 0 for i in range(m0.nv)]
job2 = c.submit((xyz, tets, regions, fixed), {"max_iter": 2, "finish": False})
c.wait(job2)
r2 = c.result(job2)
moved_fixed = max(abs(r2.xyz[3 * i + k] - m0.xyz[3 * i + k]) for i in range(0, m0.nv, 2) for k in range(3))
moved_free = max(abs(r2.xyz[3 * i + k] - m0.xyz[3 * i + k]) for i in range(1, m0.nv, 2) for k in range(3))
check("submit(lists + regions + fixed): regions and flags kept, fixed vertices still (moved %g, free %g)"
      % (moved_fixed, moved_free),
      list(r2.regions or []) == regions and list(r2.fixed or []) == [1 if f else 0 for f in fixed]
      and moved_fixed == 0 and moved_free > 0, "regions %s fixed moved %g" % (r2.regions is not None, moved_fixed))
for ext in ("mesh", "json", "qmesh"):
    p = os.path.join(TMP, "py2." + ext)
    c.result(job2, p)
    ok, out = valid(p, NT)
    check("result(job, '.%s'): valid file" % ext, ok, out)
# a descriptor's name (/dev/fd/N: /dev/stdout is one) is written into, not
# replaced; a symbolic link stays one, the file it names replaced (mode kept)
ref = os.path.join(TMP, "py2.mesh")
with open(os.path.join(TMP, "fd.mesh"), "wb") as f:
    c.result(job2, "/dev/fd/%d" % f.fileno(), "medit")
ln, tgt = os.path.join(TMP, "ln.mesh"), os.path.join(TMP, "target.mesh")
with open(tgt, "w") as f:
    f.write("old")
os.chmod(tgt, 0o600)
os.symlink("target.mesh", ln)
c.result(job2, ln)
same = lambda a, b: open(a, "rb").read() == open(b, "rb").read()
check("result(job, '/dev/fd/N'): written into the descriptor's file; result(job, link): link kept, mode 600 kept",
      same(os.path.join(TMP, "fd.mesh"), ref) and os.path.islink(ln) and same(tgt, ref)
      and (os.stat(tgt).st_mode & 0o777) == 0o600 and not [n for n in os.listdir(TMP) if ".tmp" in n],
      "fd %s link %s mode %o" % (same(os.path.join(TMP, "fd.mesh"), ref), os.path.islink(ln), os.stat(tgt).st_mode & 0o777))

# files of other tools (Gmsh 4.1 binary with $PhysicalNames, ascii VTU with
# arrays, Gmsh 2.2 binary, and formats without a media type, named in the
# query: Abaqus with its materials, Netgen, Medit binary, DOLFIN) sent as they
# are: the result in their format is what `qdc optimize` writes, byte for byte
for name in ("gmsh41_bin.msh", "meshio_ascii.vtu", "gmsh22_bin.msh", "calculix.inp",
             "meshio.vol", "meshio.meshb", "dolfin.xml"):
    src = os.path.join(TMP, name)
    with gzip.open(os.path.join(ROOT, "tests", "data", "real", name + ".gz")) as g, open(src, "wb") as f:
        f.write(g.read())
    local = os.path.join(TMP, "local." + name)
    subprocess.run([QDC, "optimize", src, local, "--max-iter", "2", "--quiet"], check=True)
    j = c.submit(src, {"max_iter": 2})
    c.wait(j)
    out = c.result(j, os.path.join(TMP, "py." + name))
    check("submit(%s) and result(job, '%s'): the local run's file byte for byte (job format %s)"
          % (name, os.path.splitext(name)[1], c.job(j)["mesh"]["format"]),
          open(out, "rb").read() == open(local, "rb").read(), "differs")

# 4. numpy arrays, when numpy is there
if qdc_client._np is not None:
    np = qdc_client._np
    X, T, _, _ = m.as_numpy()
    job3 = c.submit((X, T), {"max_iter": 1})
    c.wait(job3)
    X3, T3, _, _ = c.result(job3).as_numpy()
    check("numpy: submit((xyz, tets)) and as_numpy(): shapes %s %s" % (X3.shape, T3.shape),
          X3.shape == (m.nv, 3) and T3.shape == (NT, 4) and (T3 == T).all(), "")
else:
    print("ok - python: numpy not installed, array.array path only")

# 6. XDMF whose heavy data is in HDF5: the .xdmf and its .h5 in one
# multipart/form-data request; the result written as out.xdmf + out.h5
if os.environ.get("H5") == "1":
    xdir = os.path.join(TMP, "xin")
    os.makedirs(xdir, exist_ok=True)
    for name in ("meshio_h5.xdmf", "meshio_h5.h5"):
        with gzip.open(os.path.join(ROOT, "tests", "data", "real", name + ".gz")) as g, \
                open(os.path.join(xdir, name), "wb") as f:
            f.write(g.read())
    xin = os.path.join(xdir, "meshio_h5.xdmf")
    check("xdmf_h5_file(): the .h5 file named by the .xdmf, beside it",
          qdc_client.xdmf_h5_file(xin) == os.path.join(xdir, "meshio_h5.h5"),
          qdc_client.xdmf_h5_file(xin))
    jx = c.submit(xin, {"max_iter": 5})
    fx = c.wait(jx)
    check("submit(.xdmf naming an .h5): both sent, job succeeded with %s tets"
          % fx.get("mesh", {}).get("tets"),
          fx["state"] == "succeeded" and fx["mesh"]["tets"] == 1228, json.dumps(fx)[:300])
    check("the XDMF+HDF5 job's record says so (mesh.h5 true)",
          fx["mesh"].get("h5") is True, json.dumps(fx.get("mesh")))
    # .xmf as well as .xdmf, both ways
    xmf = os.path.join(xdir, "m.xmf")
    with open(xmf, "wb") as f:
        f.write(open(xin, "rb").read())
    fm = c.wait(c.submit(xmf, {"max_iter": 2}))
    mdir = os.path.join(TMP, "xmfout")
    os.makedirs(mdir, exist_ok=True)
    c.result(fm, os.path.join(mdir, "o.xmf"))
    check("submit(m.xmf) sends its .h5 too; result(job, 'o.xmf'): o.xmf + o.h5 (%s)"
          % sorted(os.listdir(mdir)),
          fm["state"] == "succeeded" and fm["mesh"].get("h5") is True
          and sorted(os.listdir(mdir)) == ["o.h5", "o.xmf"]
          and b"o.h5:/" in open(os.path.join(mdir, "o.xmf"), "rb").read(),
          json.dumps(fm)[:300])
    # a job sent inline (no "h5" in its record) written to a .xdmf path: one file
    idir = os.path.join(TMP, "xinline")
    os.makedirs(idir, exist_ok=True)
    fi = c.wait(c.submit(os.environ["MESHQ"], {"max_iter": 1}))
    c.result(fi, os.path.join(idir, "inline.xdmf"))
    check("a job without \"h5\" written to inline.xdmf: that one file, inline XML",
          "h5" not in fi["mesh"] and os.listdir(idir) == ["inline.xdmf"]
          and b'Format="XML"' in open(os.path.join(idir, "inline.xdmf"), "rb").read(),
          "%s %s" % (fi.get("mesh"), os.listdir(idir)))
    odir = os.path.join(TMP, "xout")
    os.makedirs(odir, exist_ok=True)
    xo = c.result(jx, os.path.join(odir, "pyx.xdmf"))
    xml = open(xo, "rb").read()
    check("result(job, 'pyx.xdmf'): pyx.xdmf naming pyx.h5, and pyx.h5 beside it",
          sorted(os.listdir(odir)) == ["pyx.h5", "pyx.xdmf"] and b"pyx.h5:/" in xml
          and b"result.h5" not in xml, "%s %s" % (os.listdir(odir), xml[:300]))
    conv = subprocess.run([QDC, "convert", xo, os.path.join(odir, "pyx.mesh")],
                          capture_output=True, text=True)
    ok, out = valid(os.path.join(odir, "pyx.mesh"), 1228)
    check("qdc convert reads the written pyx.xdmf + pyx.h5 (1228 tets, none inverted)",
          conv.returncode == 0 and ok, conv.stderr + out)
    if os.environ.get("H5PY") == "1":
        chk = subprocess.run([sys.executable, os.path.join(ROOT, "tests", "tools", "medcoo.py"),
                              os.path.join(xdir, "meshio_h5.h5"), os.path.join(odir, "pyx.h5"),
                              "python: result pyx.h5 is the upload's .h5 but for the coordinates",
                              "data0"], capture_output=True, text=True)
        print(chk.stdout.strip() or "FAIL - python: medcoo.py: " + chk.stderr[-300:])
        nfail += 0 if chk.stdout.startswith("ok") else 1
    # the .h5 missing, an .h5 outside the .xdmf's folder: refused before sending
    alone = os.path.join(TMP, "alone.xdmf")
    with open(alone, "wb") as f:
        f.write(open(xin, "rb").read())
    try:
        c.submit(alone)
        check("submit(.xdmf without its .h5): refused", False, "no exception")
    except OSError as e:
        check("submit(.xdmf without its .h5): OSError naming it (%s)" % e,
              "meshio_h5.h5" in str(e), str(e))
    up = os.path.join(xdir, "up.xdmf")
    with open(up, "wb") as f:
        f.write(open(xin, "rb").read().replace(b"meshio_h5.h5:", b"../meshio_h5.h5:"))
    try:
        c.submit(up)
        check("submit(.xdmf naming ../x.h5): refused", False, "no exception")
    except ValueError as e:
        check("submit(.xdmf naming ../x.h5): ValueError (%s)" % e, "folder" in str(e), str(e))
else:
    print("ok - python: XDMF+HDF5 # SKIP qdc-h5 not built")

# 5. errors, idempotency, cancel, list
try:
    c.submit(MESH, {"metric": "nope"})
    check("bad option raises QdcError(400)", False, "no exception")
except QdcError as e:
    check("bad option raises QdcError(400): %s" % e, e.status == 400 and "metric" in str(e), str(e))
try:
    c.job("0123456789abcdef0123456789abcdef")
    check("unknown job raises QdcError(404)", False, "no exception")
except QdcError as e:
    check("unknown job raises QdcError(404)", e.status == 404, str(e))
a = c.submit(MESH, {"max_iter": 1}, idempotency_key="py-%d" % os.getpid())
b = c.submit(MESH, {"max_iter": 1}, idempotency_key="py-%d" % os.getpid())
check("same Idempotency-Key: same job", a["id"] == b["id"], "%s %s" % (a["id"], b["id"]))
# no early stop (stall, tol_move 0): a run of 1000 global iterations, which
# the cancel stops, however late it comes on a busy machine
big = c.submit(os.environ["BIG"], {"max_iter": 1000, "stall": 0, "tol_move": 0})
c.cancel(big)
try:
    c.wait(big)
    check("cancelled job: wait raises JobFailed", False, "no exception")
except JobFailed as e:
    check("cancelled job: wait raises JobFailed (%s)" % e, e.job["state"] == "cancelled", str(e))
ids = {j["id"] for j in c.jobs()}
check("jobs(): lists them all", {job["id"], job2["id"], a["id"], big["id"]} <= ids, ids)
dead = Client("http://127.0.0.1:1", retries=1)
dead.on_retry = None
try:
    dead.jobs()
    check("unreachable server raises QdcError(0)", False, "no exception")
except QdcError as e:
    check("unreachable server raises QdcError(0) after retries", e.status == 0, str(e))
sys.exit(1 if nfail else 0)
