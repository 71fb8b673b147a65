#!/usr/bin/python3
"""splicecheck.py IN OUT [REF.mesh]: is OUT the file IN with only the vertex
coordinates changed?

Finds the coordinate fields of both files with its own small parsers (Medit
.mesh, TetGen .node, Gmsh MSH 2.x ASCII/binary, 4.0 ASCII and 4.1 ASCII/binary,
DOLFIN XML, XDMF inline, Medit binary, Abaqus .inp, Netgen .vol, legacy VTK
ASCII/binary, VTU ascii/base64/appended, zlib or not), masks them and compares
what is left byte for byte (for VTU, the offset="" of appended arrays may
differ too; Gmsh 4.x $Entities bounding boxes and VTU Points
RangeMin/RangeMax are checked to be recomputed from the new coordinates). Then, with meshio: both files read with the same cells, cell,
point and field data, OUT's coordinates are the numbers in its coordinate
fields, some of them changed, and, given REF (the same optimization written
as Medit by qdc), equal to REF's (rounded to float32 if the file stores
float32). Prints one line per finding; exit 0 if all hold, 1 otherwise.
"""
import base64
import re
import struct
import sys
import zlib

import numpy as np

TOKEN = re.compile(rb"[^\s#]+|#[^\n]*")
TOKEN_NOHASH = re.compile(rb"\S+")


def tokens(b, start=0, hash_comments=True):
    """(start, end) of each token from start; '#' comments skipped."""
    for m in (TOKEN if hash_comments else TOKEN_NOHASH).finditer(b, start):
        if hash_comments and b[m.start()] == ord("#"):
            continue
        yield m.start(), m.end()


class Fields:
    def __init__(self):
        self.ranges = []  # (start, end) of each masked field, in order
        self.coords = []  # (start, end, kind) of each coordinate: 'text', '<f8', '>f4'...
        self.width = 8
        # values derived from the coordinates, recomputed by a spliced write:
        self.derived = []  # (start, end, kind) of each
        self.entities = []  # Gmsh 4.x: (dim, tag, first value, count, bounding tags)
        self.blocks = []  # Gmsh 4.x: (dim, tag, node count) of each $Nodes block
        self.ranges_at = None  # VTU: value index of RangeMin, RangeMax (or None)
        self.tol = 0  # Nastran: fields of 8 or 16 characters hold fewer digits


def gmsh_entities(b, f, ver, binary, dsize):
    """$Entities of MSH 4.x: where the bounding boxes are, what bounds what."""
    if b.find(b"\n$Entities") < 0:
        return
    at = b.index(b"\n$Entities") + len(b"\n$Entities")
    at = b.index(b"\n", at) + 1
    sz = "<Q" if dsize == b"8" else "<I"
    ds = struct.calcsize(sz)
    if binary:
        def size():
            nonlocal at
            at += ds
            return struct.unpack_from(sz, b, at - ds)[0]

        def i32():
            nonlocal at
            at += 4
            return struct.unpack_from("<i", b, at - 4)[0]

        def real():
            nonlocal at
            at += 8
            return (at - 8, at, "<f8")
    else:
        it = tokens(b, at, False)

        def size():
            return int(b[slice(*next(it))])
        i32 = size

        def real():
            s, e = next(it)
            return (s, e, "text")
    counts = [size() for _ in range(4)]
    for dim in range(4):
        for _ in range(counts[dim]):
            tag = i32()
            nval = 6 if dim or ver in (b"4", b"4.0") else 3
            first = len(f.derived)
            f.derived += [real() for _ in range(nval)]
            for _ in range(size()):
                i32()
            bounds = [abs(i32()) for _ in range(size())] if dim else []
            f.entities.append((dim, tag, first, nval, bounds))


def entity_boxes(f, xyz):
    """Each entity's box over the nodes of its blocks and its closure."""
    box, at = {}, 0
    for dim, tag, c in f.blocks:
        if c:
            p = xyz[at:at + c]
            lo, hi = p.min(axis=0), p.max(axis=0)
            if (dim, tag) in box:
                lo = np.minimum(lo, box[dim, tag][0])
                hi = np.maximum(hi, box[dim, tag][1])
            box[dim, tag] = (lo, hi)
        at += c
    for d in (1, 2, 3):
        for dim, tag, _, _, bounds in f.entities:
            if dim != d:
                continue
            for bt in bounds:
                if (d - 1, bt) in box:
                    lo, hi = box[d - 1, bt]
                    if (d, tag) in box:
                        lo = np.minimum(lo, box[d, tag][0])
                        hi = np.maximum(hi, box[d, tag][1])
                    box[d, tag] = (lo, hi)
    return box


def medit(b):
    f = Fields()
    it = tokens(b)
    for s, e in it:
        if b[s:e] == b"Vertices":
            s, e = next(it)
            n = int(b[s:e])
            for _ in range(n):
                for k in range(4):
                    s, e = next(it)
                    if k < 3:
                        f.coords.append((s, e, "text"))
            break
    return f


def tetgen_node(b):
    f = Fields()
    it = tokens(b)
    head = [int(b[s:e]) for s, e in (next(it) for _ in range(4))]
    n, _, nattr, nbm = head
    for _ in range(n):
        for k in range(4 + nattr + nbm):
            s, e = next(it)
            if 1 <= k <= 3:
                f.coords.append((s, e, "text"))
    return f


def gmsh(b):
    f = Fields()
    fmt = b.index(b"$MeshFormat") + len(b"$MeshFormat")
    ver, ftype, dsize = b[fmt:b.index(b"$EndMeshFormat")].split()[:3]
    at = b.index(b"\n$Nodes") + len(b"\n$Nodes")
    at = b.index(b"\n", at) + 1
    if ver.startswith(b"2") and ftype == b"1":
        e = b.index(b"\n", at)
        n, at = int(b[at:e]), e + 1
        for _ in range(n):  # int32 tag, 3 float64
            for k in range(3):
                f.coords.append((at + 4 + 8 * k, at + 12 + 8 * k, "<f8"))
            at += 28
        return f
    if ver.startswith(b"4"):
        gmsh_entities(b, f, ver, ftype == b"1", dsize)
    if ver in (b"4", b"4.0"):
        it = tokens(b, at, False)
        nblk = int(b[slice(*next(it))])
        next(it)
        for _ in range(nblk):
            tag, dim, par, c = (int(b[slice(*next(it))]) for _ in range(4))
            f.blocks.append((dim, tag, c))
            for _ in range(c):
                for k in range(4 + par * dim):
                    s, e = next(it)
                    if 1 <= k <= 3:
                        f.coords.append((s, e, "text"))
        return f
    if ver.startswith(b"2"):
        it = tokens(b, at, False)
        s, e = next(it)
        for _ in range(int(b[s:e])):
            for k in range(4):
                s, e = next(it)
                if k:
                    f.coords.append((s, e, "text"))
        return f
    if ftype == b"0":
        it = tokens(b, at, False)
        nblk = int(b[slice(*next(it))])
        for _ in range(3):
            next(it)
        for _ in range(nblk):
            dim, tag, par, c = (int(b[slice(*next(it))]) for _ in range(4))
            f.blocks.append((dim, tag, c))
            for _ in range(c):
                next(it)
            for _ in range(c):
                for k in range(3 + par * dim):
                    s, e = next(it)
                    if k < 3:
                        f.coords.append((s, e, "text"))
        return f
    sz = "<Q" if dsize == b"8" else "<I"
    ds = struct.calcsize(sz)
    nblk = struct.unpack_from(sz, b, at)[0]
    at += 4 * ds
    for _ in range(nblk):
        dim, tag, par = struct.unpack_from("<3i", b, at)
        c = struct.unpack_from(sz, b, at + 12)[0]
        f.blocks.append((dim, tag, c))
        at += 12 + ds + c * ds
        for _ in range(c):
            for k in range(3):
                f.coords.append((at + 8 * k, at + 8 * k + 8, "<f8"))
            at += 8 * (3 + par * dim)
    return f


def dolfin(b):
    f = Fields()
    for m in re.finditer(rb"<vertex\b[^>]*>", b):
        for a in (b"x", b"y", b"z"):
            v = re.search(rb"\s" + a + rb"\s*=\s*[\"']\s*([^\"'\s]+)", m.group(0))
            f.coords.append((m.start() + v.start(1), m.start() + v.end(1), "text"))
    f.coords.sort()
    return f


def xdmf(b):
    """XDMF, data inline: the numbers of the first Geometry's DataItem."""
    f = Fields()
    m = re.search(rb"<Geometry\b[^>]*>\s*<DataItem\b[^>]*>", b)
    end = b.index(b"<", m.end())
    for s, e in tokens(b[:end], m.end(), hash_comments=False):
        f.coords.append((s, e, "text"))
    return f


def abaqus(b):
    f = Fields()
    node = False
    for m in re.finditer(rb"[^\n]*\n?", b):
        line, at = m.group(0), m.start()
        t = line.strip()
        if t.startswith(b"*"):
            node = not t.startswith(b"**") and re.match(rb"\*node\b", t, re.I) is not None
            continue
        if not node or not t:
            continue
        fields = list(re.finditer(rb"[^,\s]+", line))
        for v in fields[1:4]:
            f.coords.append((at + v.start(), at + v.end(), "text"))
    return f


def bdf(b):
    """Nastran GRID cards: small (8), large (16, GRID* with a '*' line) and
    free (comma) fields; a fixed field masked whole, a free one as its token."""
    f = Fields()
    lines = [(m.start(), m.group(1)) for m in re.finditer(rb"([^\n]*)\n?", b)]
    bulk = any(re.match(rb"\s*BEGIN\s+BULK", t, re.I) for _, t in lines)
    i = 0
    while i < len(lines):
        at, t = lines[i]
        i += 1
        if bulk:
            bulk = not re.match(rb"\s*BEGIN\s+BULK", t, re.I)
            continue
        if not re.match(rb"GRID\*?[ ,]", t, re.I):
            continue
        card = [(at, t)]
        while i < len(lines) and lines[i][1][:1] in (b"+", b"*", b","):
            card.append(lines[i])
            i += 1
        spans = []
        for at, t in card:
            large = t[:5].upper() == b"GRID*" or t[:1] == b"*"
            t = t.rstrip(b"\r").split(b"$")[0]
            if b"," in t:
                pos = [m.start() for m in re.finditer(rb",", t)] + [len(t)]
                for a, e in list(zip(pos, pos[1:]))[:4 if large else 8]:
                    tok = re.search(rb"[^ ,]*", t[a + 1:e].lstrip(b" "))
                    s = a + 1 + (len(t[a + 1:e]) - len(t[a + 1:e].lstrip(b" ")))
                    spans.append((at + s, at + s + len(tok.group(0)), 16))
            else:
                w = 16 if large else 8
                for k in range(4 if large else 8):
                    a = 8 + k * w
                    spans.append((at + a, at + min(a + w, len(t)), w))
        for s, e, w in spans[2:5]:
            f.coords.append((s, e, "nastran"))
            # "-1.00389" keeps 5 decimals of -1.0038915, 16 characters 13
            f.tol = max(f.tol, 1e-5 if w == 8 else 1e-13)
    return f


def unv(b):
    """I-DEAS dataset 2411: the three coordinates after each node record, each
    its 25 columns when the line is three such fields (a sign may take a
    blank of its field), else its token."""
    f = Fields()
    for m in re.finditer(rb"(?:^|\n)\s*-1\r?\n\s*2411\s*\n(.*?)\n\s*-1\s*\n", b, re.S):
        lines = list(re.finditer(rb"[^\n]*\n?", b[m.start(1):m.end(1)]))
        for k in range(1, len(lines), 2):
            at = m.start(1) + lines[k].start()
            line = lines[k].group(0).rstrip(b"\r\n")
            cols = [(c, c + 25) for c in (0, 25, 50)]
            if len(line) != 75 or any(not line[a:e].strip() or b" " in line[a:e].strip()
                                      for a, e in cols):
                cols = [v.span() for v in re.finditer(rb"\S+", line)]
            for a, e in cols:
                f.coords.append((at + a, at + e, "fortran"))
    f.tol = 0
    return f


def netgen(b):
    f = Fields()
    it = tokens(b)
    for s, e in it:
        if b[s:e] == b"points":
            s, e = next(it)
            for _ in range(int(b[s:e])):
                for k in range(3):
                    s, e = next(it)
                    f.coords.append((s, e, "text"))
            break
    return f


def meshb(b):
    f = Fields()
    end = "<" if struct.unpack_from("<i", b, 0)[0] == 1 else ">"
    ver = struct.unpack_from(end + "i", b, 4)[0]
    rs, isz, ps = (4 if ver == 1 else 8), (8 if ver == 4 else 4), (8 if ver >= 3 else 4)
    at = 8
    while at < len(b):
        kw = struct.unpack_from(end + "i", b, at)[0]
        nxt = struct.unpack_from(end + ("q" if ps == 8 else "i"), b, at + 4)[0]
        if kw == 54:
            break
        if kw == 4:
            n = struct.unpack_from(end + ("q" if isz == 8 else "i"), b, at + 4 + ps)[0]
            p = at + 4 + ps + isz
            for _ in range(n):
                for k in range(3):
                    f.coords.append((p + rs * k, p + rs * (k + 1), end + "f%d" % rs))
                p += 3 * rs + isz
        at = nxt
    return f


def vtk(b):
    f = Fields()
    m = re.search(rb"\nPOINTS\s+(\d+)\s+(\w+)[^\n]*\n", b)
    n, t = int(m.group(1)), m.group(2)
    binary = re.search(rb"^BINARY", b.split(b"\n", 3)[2]) is not None
    w = 4 if t == b"float" else 8
    f.width = w
    if not binary:
        it = tokens(b, m.end(), False)
        for _ in range(3 * n):
            s, e = next(it)
            f.coords.append((s, e, "text"))
        return f
    for i in range(3 * n):
        f.coords.append((m.end() + w * i, m.end() + w * (i + 1), ">f%d" % w))
    return f


def attr(tag, key):
    m = re.search(rb"\s" + key + rb'\s*=\s*"([^"]*)"', tag)
    return m.group(1) if m else None


def vtu(b):
    f = Fields()
    head = re.search(rb"<VTKFile[^>]*>", b).group(0)
    big = attr(head, b"byte_order") == b"BigEndian"
    hsz = 8 if attr(head, b"header_type") == b"UInt64" else 4
    zl = attr(head, b"compressor") is not None
    app = b.find(b"<AppendedData")
    app_data = b.index(b"_", app) + 1 if app >= 0 else -1
    pts = b.index(b"<Points")
    tag = re.compile(rb"<DataArray[^>]*>").search(b, pts)
    t = tag.group(0)
    w = 4 if attr(t, b"type") == b"Float32" else 8
    f.width = w
    kind = (">f%d" if big else "<f%d") % w
    fmt = attr(t, b"format") or b"ascii"
    at = {}
    for key in (b"RangeMin", b"RangeMax"):
        m = re.search(rb"\s" + key + rb'\s*=\s*"\s*([^"\s]+)\s*"', t)
        if m:
            at[key] = (tag.start() + m.start(1), tag.start() + m.end(1), "text")
    if at:
        order = sorted(at, key=lambda k: at[k][0])
        f.derived = [at[k] for k in order]
        f.ranges_at = tuple(order.index(k) if k in at else None
                            for k in (b"RangeMin", b"RangeMax"))
    # every appended offset="" may shift
    for m in re.finditer(rb"<DataArray[^>]*>", b[:app if app >= 0 else len(b)]):
        if attr(m.group(0), b"format") == b"appended":
            o = re.search(rb'\soffset\s*=\s*"\s*(\d+)\s*"', m.group(0))
            f.ranges.append((m.start() + o.start(1), m.start() + o.end(1)))
    if fmt == b"ascii":
        end = b.index(b"<", tag.end())
        for m in TOKEN_NOHASH.finditer(b, tag.end(), end):
            f.coords.append((m.start(), m.end(), "text"))
        return f
    word = (">" if big else "<") + ("Q" if hsz == 8 else "I")
    if fmt == b"binary":
        end = b.index(b"<", tag.end())
        s = tag.end()
        while b[s:s + 1].isspace():
            s += 1
        e = end
        while b[e - 1:e].isspace():
            e -= 1
        f.ranges.append((s, e))
        f.block = ("b64", s, e, hsz, word, zl, kind)
        return f
    off = int(attr(t, b"offset").strip())
    s = app_data + off
    if attr(re.compile(rb"<AppendedData[^>]*>").search(b, app).group(0),
            b"encoding") == b"base64":
        # VTK's default: each array base64 (header and data encoded
        # apart), up to the next array's offset or the end of the data
        offs = [int(o) for o in re.findall(rb'\soffset\s*=\s*"\s*(\d+)\s*"', b[:app])]
        nxt = [o for o in offs if o > off]
        e = app_data + min(nxt) if nxt else b.index(b"<", s)
        while b[e - 1:e].isspace():
            e -= 1
        f.ranges.append((s, e))
        f.block = ("b64", s, e, hsz, word, zl, kind)
        return f
    if zl:
        nb = struct.unpack_from(word, b, s)[0]
        sizes = struct.unpack_from(word[0] + word[1] * (3 + nb), b, s)
        e = s + (3 + nb) * hsz + sum(sizes[3:])
    else:
        e = s + hsz + struct.unpack_from(word, b, s)[0]
    f.ranges.append((s, e))
    f.block = ("raw", s, e, hsz, word, zl, kind)
    return f


def block_values(b, blk):
    """The coordinates of a VTU Points block, decoded."""
    how, s, e, hsz, word, zl, kind = blk
    data = base64.b64decode(b[s:e]) if how == "raw" else None
    if how == "b64":
        # header and data may be encoded separately, each padded
        raw = b[s:e]
        parts = re.findall(rb"[A-Za-z0-9+/]+=*", raw)
        data = b"".join(base64.b64decode(p + b"=" * (-len(p) % 4)) for p in parts)
    else:
        data = b[s:e]
    if zl:
        nb = struct.unpack_from(word, data, 0)[0]
        sizes = struct.unpack_from(word[0] + word[1] * (3 + nb), data, 0)
        at = (3 + nb) * hsz
        out = b""
        for c in sizes[3:]:
            out += zlib.decompress(data[at:at + c])
            at += c
    else:
        out = data[hsz:hsz + struct.unpack_from(word, data, 0)[0]]
    return np.frombuffer(out, dtype=np.dtype(kind))


def fields(path, b):
    p = path[:-3] if path.endswith(".gz") else path
    if p.endswith(".mesh"):
        return medit(b)
    if p.endswith(".meshb"):
        return meshb(b)
    if p.endswith(".node"):
        return tetgen_node(b)
    if p.endswith(".msh"):
        return gmsh(b)
    if p.endswith(".vtk"):
        return vtk(b)
    if p.endswith(".xml"):
        return dolfin(b)
    if p.endswith(".inp"):
        return abaqus(b)
    if p.endswith(".vol"):
        return netgen(b)
    if p.endswith(".vtu"):
        return vtu(b)
    if p.endswith(".bdf") or p.endswith(".nas"):
        return bdf(b)
    if p.endswith(".unv"):
        return unv(b)
    if p.endswith((".xdmf", ".xmf")):
        return xdmf(b)
    raise SystemExit("splicecheck: unknown format: " + path)


def masked(b, f):
    """The bytes between the masked fields."""
    spans = sorted([(s, e) for s, e, _ in f.coords + f.derived] + f.ranges)
    out, pos = [], 0
    for s, e in spans:
        assert s >= pos, "overlapping fields"
        out.append(b[pos:s])
        pos = e
    out.append(b[pos:])
    return out


def derived_values(b, f):
    return np.array([float(b[s:e]) if k == "text" else np.frombuffer(b[s:e], k)[0]
                     for s, e, k in f.derived], dtype=float)


def check_derived(fi, fo, di, do, xi, xo):
    """(ok, message): the derived values of OUT are those of IN where the
    coordinates they come from did not change, else recomputed: Gmsh
    bounding boxes shifted as far as their nodes' bounds moved, VTU
    RangeMin/RangeMax the range of the point norms."""
    want = di.copy()
    if fi.entities:
        bi, bo = entity_boxes(fi, xi), entity_boxes(fo, xo)
        for dim, tag, first, nval, _ in fi.entities:
            if (dim, tag) not in bi:
                continue
            old = np.concatenate(bi[dim, tag])[:nval]
            new = np.concatenate(bo[dim, tag])[:nval]
            for k in range(nval):
                if new[k] != old[k]:
                    want[first + k] = di[first + k] + (new[k] - old[k])
        what = "%d $Entities bounding box values" % len(di)
    else:
        ni, no = np.linalg.norm(xi, axis=1), np.linalg.norm(xo, axis=1)
        for k, (a, c) in zip(fi.ranges_at, ((ni.min(), no.min()), (ni.max(), no.max()))):
            if k is not None and a != c:
                want[k] = c
        what = "RangeMin/RangeMax"
    err = np.abs(want - do).max() if len(do) else 0.0
    changed = int(np.sum(di != do))
    return (len(di) == len(do) and err <= 1e-12 * max(1.0, np.abs(want).max()),
            "%s recomputed (%d changed, max error %.1e)" % (what, changed, err))


def real(t, kind):
    """A number as text: Fortran's D exponent, Nastran's "1.-3" and blanks (0)."""
    t = t.strip().upper().replace(b"D", b"E")
    if kind == "nastran" and t and b"E" not in t:
        t = re.sub(rb"(?<=[0-9.])([+-])", rb"E\1", t)
    return float(t) if t else 0.0


def values(b, f):
    """The coordinates as a reader takes them: the text of a float32 field
    (VTK's `float`, VTU's Float32 as ascii) rounded to float32."""
    vals = []
    for s, e, kind in f.coords:
        if kind in ("text", "nastran", "fortran"):
            x = real(b[s:e], kind)
            vals.append(float(np.float32(x)) if kind == "text" and f.width == 4 else x)
        else:
            vals.append(np.frombuffer(b[s:e], kind)[0])
    if not f.coords:
        vals = block_values(b, f.block)
    return np.array(vals, dtype=float)


def meshio_read(path):
    import meshio
    if path.endswith(".node"):
        return meshio.read(path, file_format="tetgen")
    if path.endswith(".msh"):
        b = open(path, "rb").read()
        if re.match(rb"\s*\$MeshFormat\s+4\s", b):
            # Gmsh writes MSH 4.0 as "4 0 8", which meshio takes for 4.1:
            # give it the version spelled out (a copy, the file is unchanged)
            import tempfile
            with tempfile.NamedTemporaryFile(suffix=".msh") as t:
                t.write(re.sub(rb"^(\s*\$MeshFormat\s+)4(\s)", rb"\g<1>4.0\2", b, 1))
                t.flush()
                return meshio.read(t.name)
    return meshio.read(path)


def main():
    inp, outp = sys.argv[1], sys.argv[2]
    ref = sys.argv[3] if len(sys.argv) > 3 else None
    bi, bo = open(inp, "rb").read(), open(outp, "rb").read()
    fi, fo = fields(inp, bi), fields(outp, bo)
    bad = 0

    def check(ok, msg):
        nonlocal bad
        print(("ok - " if ok else "FAIL - ") + msg)
        bad += not ok

    mi, mo = masked(bi, fi), masked(bo, fo)
    same = len(mi) == len(mo) and all(x == y for x, y in zip(mi, mo))
    where = ""
    if not same:
        k = next((i for i, (x, y) in enumerate(zip(mi, mo)) if x != y), min(len(mi), len(mo)))
        where = ": segment %d of %d/%d differs: %r vs %r" % (
            k, len(mi), len(mo), mi[k][:60] if k < len(mi) else b"", mo[k][:60] if k < len(mo) else b"")
    check(same, "%s: all but the %d coordinate fields byte-identical (%d bytes compared)%s"
          % (outp, len(fo.coords) or 1, sum(len(x) for x in mo), where))
    vi, vo = values(bi, fi), values(bo, fo)
    check(len(vi) == len(vo) and np.any(vi != vo),
          "%s: %d of %d coordinates changed" % (outp, int(np.sum(vi != vo)) if len(vi) == len(vo) else -1, len(vo)))
    if fi.derived:
        ok, msg = check_derived(fi, fo, derived_values(bi, fi), derived_values(bo, fo),
                                vi.reshape(-1, 3), vo.reshape(-1, 3))
        check(ok, "%s: %s" % (outp, msg))
    if inp.endswith(".unv") or (inp.endswith((".bdf", ".nas")) and
                                not re.search(rb"BEGIN\s+BULK", bi, re.I)):
        # meshio reads no I-DEAS file, and Nastran only after BEGIN BULK
        print("ok - %s: meshio comparison # SKIP meshio does not read it" % outp)
        check_ref(ref, fo, vo, outp, check)
        return 1 if bad else 0
    try:
        a, c = meshio_read(inp), meshio_read(outp)
    except (Exception, SystemExit) as e:  # an element type meshio lacks (Abaqus CPS6)
        print("ok - %s: meshio comparison # SKIP meshio cannot read %s: %s"
              % (outp, inp, "it exits" if isinstance(e, SystemExit) else str(e).splitlines()[0]))
        check_ref(ref, fo, vo, outp, check)  # the fields' values against qdc's own output
        return 1 if bad else 0
    pts = c.points.astype(float).ravel()
    want, how = vo, ""
    if c.points.dtype == np.float32 and re.match(rb"\s*MeshVersionFormatted\s+1\s", bo):
        # meshio reads a Medit ASCII file of version 1 (CGAL's) as float32
        want, how = vo.astype(np.float32).astype(float), " (meshio: as float32)"
    check(np.array_equal(pts, want), "%s: meshio reads the coordinates in the fields%s" % (outp, how))
    cells_same = len(a.cells) == len(c.cells) and all(
        x.type == y.type and np.array_equal(x.data, y.data) for x, y in zip(a.cells, c.cells))
    check(cells_same, "%s: meshio reads the same %d cell blocks (%s)" % (
        outp, len(c.cells), ", ".join("%d %s" % (len(x.data), x.type) for x in c.cells)))

    def same_dict(x, y):
        if sorted(x) != sorted(y):
            return False
        for k in x:
            u, v = x[k], y[k]
            if isinstance(u, list):
                if len(u) != len(v) or not all(np.array_equal(p, q) for p, q in zip(u, v)):
                    return False
            elif not np.array_equal(u, v):
                return False
        return True
    check(same_dict(a.cell_data, c.cell_data) and same_dict(a.point_data, c.point_data)
          and same_dict(a.field_data, c.field_data),
          "%s: same cell data %s, point data %s, field data %s" % (
              outp, sorted(c.cell_data), sorted(c.point_data), sorted(c.field_data)))
    check_ref(ref, fo, vo, outp, check)
    return 1 if bad else 0


def check_ref(ref, fo, vo, outp, check):
    """OUT's coordinates are those of REF (as float32 or as the field's
    digits when the file holds no more)."""
    if ref:
        r = meshio_read(ref).points.astype(float).ravel()
        if fo.width == 4:
            r = r.astype(np.float32).astype(float)
        err = np.abs(r - vo).max() / max(1.0, np.abs(r).max()) if len(r) == len(vo) else 1
        check(len(r) == len(vo) and err <= fo.tol,
              "%s: coordinates equal to qdc's own %s%s" % (
                  outp, ref, " (as float32)" if fo.width == 4 else
                  " (to %.0e, the field's digits)" % fo.tol if fo.tol else ""))


if __name__ == "__main__":
    sys.exit(main())
