"""meditio.py - the test scripts' one reader and writer of ASCII Medit (.mesh).

    import meditio
    m = meditio.read("a.mesh")          # or "a.mesh.gz"
    m.vertices, m.tets, m.tet_refs ...  # numpy arrays, indices 0-based
    meditio.write("b.mesh", m.vertices, m.tets, tet_refs=regions)
    m.write("c.mesh")                   # the same sections again

read(path) -> Mesh, whose attributes are
  vertices (n x 3 float), vertex_refs (n int), tets (m x 4 int, 0-based),
  tet_refs (m int), triangles (k x 3 int, 0-based), triangle_refs (k int)
  (empty arrays when the file has no such section), version and dimension,
  and sections: every other section ({keyword: rows}, each row a list of
  its tokens as text, as in the file: Edges, Corners, RequiredVertices,
  Ridges...).
The file is read as tokens: a keyword and its count on one line or on two,
any blank lines, comments from # to the end of the line, End (optional).
A section this module does not know is read up to the next keyword.
gzip files (by their magic bytes) are read too.

write(path, vertices, tets=None, triangles=None, vertex_refs=None,
      tet_refs=None, triangle_refs=None, sections=None)
writes MeshVersionFormatted 2, Dimension 3, Vertices (%.17g: the doubles
exactly), Tetrahedra, Triangles, then the sections given ({keyword: rows}),
End. Indices are given 0-based; refs default to 0 for vertices, 1 for tets
and triangles. An empty or missing section other than Vertices is left out.

Broken or unusual files that a test writes on purpose (a NaN, a bad token,
exact bytes) are written by the test itself, not here.
"""
import gzip
import re

import numpy as np

# tokens per row of the sections read here ("Vertices": the dimension + 1)
WIDTH = {"Edges": 3, "Triangles": 4, "Quadrilaterals": 5, "Tetrahedra": 5, "Prisms": 7,
         "Hexahedra": 9, "Corners": 1, "RequiredVertices": 1, "Ridges": 1,
         "RequiredEdges": 1, "RequiredTriangles": 1, "NormalAtVertices": 2,
         "TangentAtVertices": 2}
SCALARS = ("MeshVersionFormatted", "Dimension")


class Mesh:
    """The sections of one Medit file (see the module's documentation)."""

    def __init__(self):
        self.version, self.dimension = 2, 3
        self.vertices = np.zeros((0, 3))
        self.vertex_refs = np.zeros(0, np.int64)
        self.tets = np.zeros((0, 4), np.int64)
        self.tet_refs = np.zeros(0, np.int64)
        self.triangles = np.zeros((0, 3), np.int64)
        self.triangle_refs = np.zeros(0, np.int64)
        self.sections = {}

    def write(self, path):
        write(path, self.vertices, self.tets, self.triangles, self.vertex_refs,
              self.tet_refs, self.triangle_refs, self.sections)


def _keyword(tok):
    """True for a keyword, False for a number (nan and inf included)."""
    if not tok[:1].isalpha():
        return False
    try:
        float(tok)
        return False
    except ValueError:
        return True


def _text(path):
    with open(path, "rb") as f:
        b = f.read()
    if b[:2] == b"\x1f\x8b":
        b = gzip.decompress(b)
    s = b.decode()
    return re.sub(r"#[^\n]*", "", s) if "#" in s else s


def read(path):
    """The Medit file at path (ASCII, or gzip of it) as a Mesh."""
    tok = _text(path).split()
    m = Mesh()
    i = 0
    while i < len(tok):
        k = tok[i]
        if k == "End":
            break
        if not _keyword(k):
            raise ValueError("%s: token %d: %r where a keyword should be" % (path, i, k))
        if k in SCALARS:
            setattr(m, "version" if k == SCALARS[0] else "dimension", int(tok[i + 1]))
            i += 2
            continue
        n = int(tok[i + 1])
        i += 2
        w = m.dimension + 1 if k == "Vertices" else WIDTH.get(k)
        if w is None:  # unknown: its rows run to the next keyword
            e = i
            while e < len(tok) and not _keyword(tok[e]):
                e += 1
            w = (e - i) // n if n else 0
        rows = tok[i:i + w * n]
        if n < 0 or len(rows) != w * n:
            raise ValueError("%s: %s: %d rows of %d tokens announced, %d tokens left"
                             % (path, k, n, w, len(tok) - i))
        i += w * n
        if k == "Vertices":
            a = np.array(rows, float).reshape(n, w)
            m.vertices, m.vertex_refs = a[:, :w - 1], a[:, w - 1].astype(np.int64)
        elif k in ("Tetrahedra", "Triangles"):
            a = np.array(rows, np.int64).reshape(n, w)
            if k == "Tetrahedra":
                m.tets, m.tet_refs = a[:, :4] - 1, a[:, 4]
            else:
                m.triangles, m.triangle_refs = a[:, :3] - 1, a[:, 3]
        else:
            m.sections[k] = [rows[r * w:(r + 1) * w] for r in range(n)]
    return m


def _rows(a, refs, default, one):
    """Text rows of the index array a (0-based; +one) and their refs."""
    a = np.asarray(a)
    refs = np.full(len(a), default) if refs is None else np.asarray(refs)
    fmt = " ".join(["%d"] * (a.shape[1] + 1)) + "\n"
    return "".join(fmt % (*row, r) for row, r in zip((a + one).tolist(), refs.tolist()))


def write(path, vertices, tets=None, triangles=None, vertex_refs=None, tet_refs=None,
          triangle_refs=None, sections=None):
    """Write an ASCII Medit file (see the module's documentation)."""
    x = np.asarray(vertices, float).reshape(-1, 3)
    vr = np.zeros(len(x), np.int64) if vertex_refs is None else np.asarray(vertex_refs)
    out = ["MeshVersionFormatted 2\nDimension 3\nVertices\n%d\n" % len(x)]
    out += ["%.17g %.17g %.17g %d\n" % (*p, r) for p, r in zip(x.tolist(), vr.tolist())]
    for k, a, refs in (("Tetrahedra", tets, tet_refs), ("Triangles", triangles, triangle_refs)):
        if a is not None and len(a):
            out.append("%s\n%d\n" % (k, len(a)) + _rows(a, refs, 1, 1))
    for k, rows in (sections or {}).items():
        rows = list(rows)
        if rows:
            out.append("%s\n%d\n" % (k, len(rows)))
            out += [" ".join(str(v) for v in r) + "\n" for r in rows]
    out.append("End\n")
    with open(path, "w") as f:
        f.write("".join(out))
