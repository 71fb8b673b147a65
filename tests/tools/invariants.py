#!/usr/bin/python3
"""invariants.py - the promises of one qdc result, checked from the files.

usage: invariants.py IN OUT MODE...
  IN, OUT: Medit meshes (the input and `qdc optimize IN OUT` of it); MODE: the
  options the run had (words: "--topology flips", "--boundary fixed", ...).
Prints one line: the input's and output's mean ratio / smallest dihedral /
inverted count (tests/tools/evaluate.py), the boundary Hausdorff distance
(relative), then OK or BAD with the reasons; exits 1 on BAD. Checked:
  - with --topology: no tet inverted out; without: no more than in;
  - no more degenerate (flat) tets than in;
  - a valid input: worst mean ratio and smallest dihedral not below its own,
    and without --topology the mean ratio not below its own;
  - the region tags as a set;
  - with --boundary fixed: the boundary triangles and the faces between
    regions as sets of coordinate triples (any vertex numbering), each region's
    volume within 1e-9.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import evaluate as ev  # noqa: E402
import meditio  # noqa: E402


def interface_faces(t, reg):
    """Faces shared by two tets of different regions."""
    fs = np.sort(t[:, ev.FACES].reshape(-1, 3), axis=1)
    rr = np.repeat(reg, 4)
    o = np.lexsort(fs.T[::-1])
    fs, rr = fs[o], rr[o]
    same = np.all(fs[1:] == fs[:-1], axis=1)
    return fs[1:][same & (rr[1:] != rr[:-1])]


def geometric(x, faces):
    """Faces as a set of coordinate triples (any vertex numbering)."""
    return set(tuple(sorted(tuple(x[v]) for v in f)) for f in faces)


def main():
    if len(sys.argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    inp, out, mode = sys.argv[1], sys.argv[2], " ".join(sys.argv[3:])
    a, b = meditio.read(inp), meditio.read(out)
    ea, eb = ev.evaluate(inp, samples=2000), ev.evaluate(out, inp, samples=2000)
    topo = "flips" in mode or "full" in mode
    bad = []
    if eb["n_inverted"] > (0 if topo else ea["n_inverted"]):
        bad.append("inverted %d (in %d)" % (eb["n_inverted"], ea["n_inverted"]))
    if eb["n_degenerate"] > ea["n_degenerate"]:
        bad.append("degenerate %d > %d" % (eb["n_degenerate"], ea["n_degenerate"]))
    if ea["n_inverted"] == 0 and ea["n_degenerate"] == 0:
        if eb["eta_min"] < ea["eta_min"] - 1e-9:
            bad.append("worst mean ratio %.4g < %.4g" % (eb["eta_min"], ea["eta_min"]))
        if eb["dihedral_min"] < ea["dihedral_min"] - 1e-9:
            bad.append("smallest dihedral %.4g < %.4g" % (eb["dihedral_min"], ea["dihedral_min"]))
        if not topo and eb["eta_mean"] < ea["eta_mean"] - 1e-9:
            bad.append("mean ratio %.5f < %.5f" % (eb["eta_mean"], ea["eta_mean"]))
    ra, rb = set(np.unique(a.tet_refs).tolist()), set(np.unique(b.tet_refs).tolist())
    if ra != rb:
        bad.append("region tags %s -> %s" % (sorted(ra), sorted(rb)))
    if "fixed" in mode:
        ga = geometric(a.vertices, ev.boundary_tris(a.tets))
        gb = geometric(b.vertices, ev.boundary_tris(b.tets))
        if ga != gb:
            bad.append("boundary triangles changed (%d gone, %d new)" % (len(ga - gb), len(gb - ga)))
        if len(ra) > 1 and (geometric(a.vertices, interface_faces(a.tets, a.tet_refs)) !=
                            geometric(b.vertices, interface_faces(b.tets, b.tet_refs))):
            bad.append("faces between regions changed")
        for r in sorted(ra):
            va = abs(ev.signed_vol6(a.vertices, a.tets[a.tet_refs == r]).sum()) / 6
            vb = abs(ev.signed_vol6(b.vertices, b.tets[b.tet_refs == r]).sum()) / 6
            if abs(va - vb) > 1e-9 * max(va, 1e-300):
                bad.append("region %d volume %.12g -> %.12g" % (r, va, vb))
    print("%-28s %-30s in %.4f/%.2f inv %d -> out %.4f/%.2f inv %d H %.2e  %s" % (
        os.path.basename(inp), mode or "default", ea["eta_mean"], ea["dihedral_min"],
        ea["n_inverted"], eb["eta_mean"], eb["dihedral_min"], eb["n_inverted"],
        eb.get("boundary_hausdorff_rel", -1), "OK" if not bad else "BAD: " + "; ".join(bad)))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
