#!/usr/bin/python3
"""meshtool.py - mesh conversions and bad inputs for the daemon tests.

  meshtool.py qmesh IN.mesh OUT.qmesh        Medit -> binary (proto/mesh-binary.md)
  meshtool.py json IN.mesh OUT.json          Medit -> JSON mesh
  meshtool.py medit IN.qmesh OUT.mesh        binary -> Medit (for quality.py)
  meshtool.py jsonmedit IN.json OUT.mesh     JSON mesh -> Medit
  meshtool.py same A B                       exit 0 if A and B (any of the formats)
                                             have the same connectivity, print the
                                             largest coordinate difference
  meshtool.py bad KIND IN.mesh OUT           one bad input (see BAD below)
  meshtool.py bigjson N OUT                  a syntactically valid JSON mesh of ~N bytes
  meshtool.py grid N OUT.qmesh               structured cube mesh with 6*N^3 tets
  meshtool.py sample OUT.mesh                tests/data/sample/cube.mesh: a 5^3 grid
                                             (750 tets) with its interior vertices
                                             jittered (fixed seed), so there is
                                             something to optimize
"""
import json
import os
import struct
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
import meditio  # noqa: E402

MAGIC = b"QDCMESH\0"


def read_medit(path):
    m = meditio.read(path)
    return (m.vertices.tolist(), [tuple(t) for t in m.tets.tolist()], m.tet_refs.tolist())


def read_qmesh(path):
    b = open(path, "rb").read()
    assert b[:8] == MAGIC, "bad magic"
    ver, flags, nv, nt = struct.unpack_from("<IIQQ", b, 8)
    off = 32
    c = struct.unpack_from("<%dd" % (3 * nv), b, off)
    off += 24 * nv
    t = struct.unpack_from("<%di" % (4 * nt), b, off)
    off += 16 * nt
    reg = [0] * nt
    if flags & 1:
        reg = list(struct.unpack_from("<%di" % nt, b, off))
        off += 4 * nt
    if flags & 2:
        off += nv
    assert off == len(b), "size mismatch"
    xyz = [c[3 * k:3 * k + 3] for k in range(nv)]
    tets = [t[4 * k:4 * k + 4] for k in range(nt)]
    return xyz, tets, reg


def read_json(path):
    d = json.load(open(path))
    return ([tuple(v) for v in d["vertices"]], [tuple(t) for t in d["tets"]],
            d.get("regions") or [0] * len(d["tets"]))


def read_any(path):
    head = open(path, "rb").read(8)
    if head == MAGIC:
        return read_qmesh(path)
    if head.lstrip()[:1] == b"{":
        return read_json(path)
    return read_medit(path)


def qmesh_bytes(xyz, tets, reg=None, flags=None):
    nv, nt = len(xyz), len(tets)
    if flags is None:
        flags = 1 if reg else 0
    out = [MAGIC, struct.pack("<IIQQ", 1, flags, nv, nt)]
    out.append(struct.pack("<%dd" % (3 * nv), *[c for v in xyz for c in v]))
    out.append(struct.pack("<%di" % (4 * nt), *[i for t in tets for i in t]))
    if flags & 1:
        out.append(struct.pack("<%di" % nt, *reg))
    return b"".join(out)


def write_medit(path, xyz, tets, reg):
    meditio.write(path, xyz, tets, tet_refs=reg)


def json_text(xyz, tets, reg):
    return json.dumps({"vertices": [list(v) for v in xyz], "tets": [list(t) for t in tets],
                       "regions": list(reg)})


def grid(n):
    """Cube [0,1]^3 split into n^3 cells of 6 positive tets (Kuhn subdivision)."""
    idx = lambda i, j, k: (i * (n + 1) + j) * (n + 1) + k
    xyz = [(i / n, j / n, k / n) for i in range(n + 1) for j in range(n + 1)
           for k in range(n + 1)]
    tets = []
    perms = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    for i in range(n):
        for j in range(n):
            for k in range(n):
                for p in perms:
                    cur = [i, j, k]
                    path = [idx(*cur)]
                    for ax in p:
                        cur[ax] += 1
                        path.append(idx(*cur))
                    a, b, c, d = path
                    # orient positively: det[b-a, c-a, d-a] > 0
                    va, vb, vc, vd = xyz[a], xyz[b], xyz[c], xyz[d]
                    e1 = [vb[q] - va[q] for q in range(3)]
                    e2 = [vc[q] - va[q] for q in range(3)]
                    e3 = [vd[q] - va[q] for q in range(3)]
                    det = (e1[0] * (e2[1] * e3[2] - e2[2] * e3[1]) -
                           e1[1] * (e2[0] * e3[2] - e2[2] * e3[0]) +
                           e1[2] * (e2[0] * e3[1] - e2[1] * e3[0]))
                    tets.append((a, b, c, d) if det > 0 else (a, c, b, d))
    return xyz, tets


BAD = ["truncated", "magic", "sizes", "index", "nan", "empty", "badjson", "jsonindex",
       "mediterr", "garbage"]


def bad(kind, src, out):
    xyz, tets, reg = read_medit(src)
    good = qmesh_bytes(xyz, tets, reg)
    if kind == "truncated":
        data = good[:len(good) - 7]
    elif kind == "magic":
        data = b"QDCMESX\0" + good[8:]
    elif kind == "sizes":  # header says one tet more than the body holds
        data = good[:24] + struct.pack("<Q", len(tets) + 1) + good[32:]
    elif kind == "index":  # tet 5 names a vertex that does not exist
        t = list(tets)
        t[5] = (t[5][0], len(xyz) + 10, t[5][2], t[5][3])
        data = qmesh_bytes(xyz, t, reg)
    elif kind == "nan":  # vertex 3 has a NaN coordinate
        v = list(xyz)
        v[3] = (float("nan"), v[3][1], v[3][2])
        data = qmesh_bytes(v, tets, reg)
    elif kind == "empty":
        data = qmesh_bytes([], [], [], flags=0)
    elif kind == "badjson":
        data = json_text(xyz[:10], tets[:2], reg[:2])[:-7].encode() + b",,]"
    elif kind == "jsonindex":
        data = json.dumps({"vertices": [list(v) for v in xyz[:4]],
                           "tets": [[0, 1, 2, 3], [0, 1, 2, 9]]}).encode()
    elif kind == "mediterr":  # a non-number at a known line
        lines = open(src).read().split("\n")
        k = lines.index("Vertices") + 4
        lines[k] = "0.5 zebra 0.5 1"
        data = "\n".join(lines).encode()
    elif kind == "garbage":
        data = b"\x89PNG\r\n\x1a\n" + bytes(200)
    else:
        sys.exit("unknown kind " + kind)
    open(out, "wb").write(data)


def main(a):
    if a[0] == "qmesh":
        open(a[2], "wb").write(qmesh_bytes(*read_medit(a[1])))
    elif a[0] == "json":
        open(a[2], "w").write(json_text(*read_medit(a[1])))
    elif a[0] == "medit":
        write_medit(a[2], *read_qmesh(a[1]))
    elif a[0] == "jsonmedit":
        write_medit(a[2], *read_json(a[1]))
    elif a[0] == "same":
        x1, t1, _ = read_any(a[1])
        x2, t2, _ = read_any(a[2])
        if len(x1) != len(x2) or list(map(tuple, t1)) != list(map(tuple, t2)):
            print("connectivity differs")
            return 1
        print(max(abs(p - q) for u, v in zip(x1, x2) for p, q in zip(u, v)))
    elif a[0] == "bad":
        bad(a[1], a[2], a[3])
    elif a[0] == "bigjson":
        n = int(a[1])
        xyz, tets = grid(4)
        base = json.loads(json_text(xyz, tets, [0] * len(tets)))
        # pad with extra unreferenced vertices until the text is ~n bytes
        extra = max(0, (n - len(json.dumps(base))) // 40 + 1)
        base["vertices"] += [[0.123456789, 0.123456789, 0.123456789]] * extra
        open(a[2], "w").write(json.dumps(base))
    elif a[0] == "sample":
        import random
        n = 5
        xyz, tets = grid(n)
        rnd = random.Random(3)
        h = 1.0 / n
        xyz = [tuple(c + (rnd.uniform(-0.3, 0.3) * h if 0 < c < 1 else 0) for c in v)
               if all(0 < c < 1 for c in v) else v for v in xyz]
        write_medit(a[1], xyz, tets, [1] * len(tets))
    elif a[0] == "grid":
        xyz, tets = grid(int(a[1]))
        open(a[2], "wb").write(qmesh_bytes(xyz, tets, None, flags=0))
    else:
        print(__doc__)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
