#!/usr/bin/python3
"""surfaces.py - triangle surfaces for the surface-input tests
(tests/server/formats.sh, tests/e2e/tetra.sh).

  surfaces.py stl cube|open|selfx OUT.stl   ASCII STL: the unit cube (closed,
                                            outward), the cube without one
                                            triangle, two overlapping cubes
  surfaces.py off OUT.off                   the unit cube as OFF (indexed)
"""
import sys


def cube(o=(0.0, 0.0, 0.0), s=1.0):
    v = [(o[0] + s * x, o[1] + s * y, o[2] + s * z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    i = lambda x, y, z: 4 * x + 2 * y + z
    quads = [(i(0, 0, 0), i(0, 0, 1), i(0, 1, 1), i(0, 1, 0)), (i(1, 0, 0), i(1, 1, 0), i(1, 1, 1), i(1, 0, 1)),
             (i(0, 0, 0), i(1, 0, 0), i(1, 0, 1), i(0, 0, 1)), (i(0, 1, 0), i(0, 1, 1), i(1, 1, 1), i(1, 1, 0)),
             (i(0, 0, 0), i(0, 1, 0), i(1, 1, 0), i(1, 0, 0)), (i(0, 0, 1), i(1, 0, 1), i(1, 1, 1), i(0, 1, 1))]
    return [t for a, b, c, d in quads for t in ((v[a], v[b], v[c]), (v[a], v[c], v[d]))]


def stl(kind, out):
    tris = {"cube": cube(), "open": cube()[1:], "selfx": cube() + cube((0.5, 0.5, 0.5))}[kind]
    with open(out, "w") as f:
        f.write("solid %s\n" % kind)
        for t in tris:
            f.write(" facet normal 0 0 0\n  outer loop\n")
            f.writelines("   vertex %r %r %r\n" % p for p in t)
            f.write("  endloop\n endfacet\n")
        f.write("endsolid %s\n" % kind)


def off(out):
    tris = cube()
    pts = sorted(set(p for t in tris for p in t))
    with open(out, "w") as f:
        f.write("OFF\n%d %d 0\n" % (len(pts), len(tris)))
        f.writelines("%r %r %r\n" % p for p in pts)
        f.writelines("3 %d %d %d\n" % tuple(pts.index(p) for p in t) for t in tris)


if __name__ == "__main__":
    if sys.argv[1:2] == ["stl"]:
        stl(sys.argv[2], sys.argv[3])
    elif sys.argv[1:2] == ["off"]:
        off(sys.argv[2])
    else:
        sys.exit(__doc__)
