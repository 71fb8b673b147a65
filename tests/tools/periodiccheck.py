#!/usr/bin/python3
"""periodiccheck.py IN OUT: do the $Periodic node pairs of the Gmsh file IN
keep their transform in OUT (the same file with new coordinates)?

Reads the node tags and coordinates ($Nodes) and the periodic links
($Periodic: node pairs and their 4x4 affine transform) of MSH 4.1
ASCII/binary, 4.0 ASCII and 2.x ASCII/binary with its own small parser (no
meshio: it reads neither 4.0 nor parametric nodes). For every pair
(slave, master) of a link with transform A, the residual
r = x_slave - A x_master must be the same in OUT as in IN to 1e-12 (pairs
never move apart), and must be below 1e-9 in IN (the parser pairs the right
nodes). Also checks that OUT has the same links and that some vertex moved.
Prints one line per finding; exit 0 if all hold, 1 otherwise.
"""
import struct
import sys

import numpy as np


def section(b, name):
    name = name.encode()
    a = b.index(b"$" + name)
    a = b.index(b"\n", a) + 1
    return a, b.index(b"\n$End" + name, a - 1)


class Reader:
    """Values of either encoding from offset at."""

    def __init__(self, b, at, end, binary, dsize):
        self.b, self.at, self.end, self.bin = b, at, end, binary
        self.sz = "<Q" if dsize == 8 else "<I"
        if not binary:
            self.toks = b[at:end].split()
            self.k = 0

    def tok(self):
        t = self.toks[self.k]
        self.k += 1
        return t

    def _bin(self, fmt):
        v = struct.unpack_from(fmt, self.b, self.at)[0]
        self.at += struct.calcsize(fmt)
        return v

    def size(self):
        return self._bin(self.sz) if self.bin else int(self.tok())

    def i32(self):
        return self._bin("<i") if self.bin else int(self.tok())

    def f64(self):
        return self._bin("<d") if self.bin else float(self.tok())

    def peek_affine(self):
        if self.toks[self.k] == b"Affine":
            self.k += 1
            return True
        return False


def read(path):
    b = open(path, "rb").read()
    fa, fe = section(b, "MeshFormat")
    ver, ftype, dsize = b[fa:fe].split()[:3]
    ver, binary, dsize = float(ver), ftype == b"1", int(dsize)
    tags, xyz = [], []
    a, e = section(b, "Nodes")
    r = Reader(b, a, e, binary and ver >= 4, dsize)
    if ver >= 4.1:
        nblk = r.size()
        for _ in range(3):
            r.size()
        for _ in range(nblk):
            dim, _, par = r.i32(), r.i32(), r.i32()
            c = r.size()
            t = [r.size() for _ in range(c)]
            for _ in range(c):
                xyz.append([r.f64() for _ in range(3)])
                for _ in range(par * dim):
                    r.f64()
            tags += t
    elif ver >= 4.0:
        nblk = r.size()
        r.size()
        for _ in range(nblk):
            _, dim, par, c = r.i32(), r.i32(), r.i32(), r.size()
            for _ in range(c):
                tags.append(r.size())
                xyz.append([r.f64() for _ in range(3)])
                for _ in range(par * dim):
                    r.f64()
    else:
        nl = b.index(b"\n", a)
        n = int(b[a:nl])
        if binary:
            at = nl + 1
            for _ in range(n):
                t, x, y, z = struct.unpack_from("<i3d", b, at)
                tags.append(t)
                xyz.append([x, y, z])
                at += 28
        else:
            toks = b[nl + 1:e].split()
            for i in range(n):
                tags.append(int(toks[4 * i]))
                xyz.append([float(v) for v in toks[4 * i + 1:4 * i + 4]])
    index = {t: i for i, t in enumerate(tags)}
    links = []
    a, e = section(b, "Periodic")
    r = Reader(b, a, e, binary and ver >= 4.1, dsize)
    for _ in range(r.size()):
        head = (r.i32(), r.i32(), r.i32())
        aff = None
        if ver >= 4.1:
            na = r.size()
            aff = [r.f64() for _ in range(na)]
        elif r.peek_affine():
            aff = [r.f64() for _ in range(16)]
        pairs = [(r.size(), r.size()) for _ in range(r.size())]
        links.append((head, aff, pairs))
    return np.array(xyz), index, links


def main():
    xi, ti, li = read(sys.argv[1])
    xo, to, lo = read(sys.argv[2])
    ok = True

    def say(good, what):
        nonlocal ok
        ok &= good
        print(("ok - " if good else "FAIL - ") + what)

    say([(h, a) for h, a, _ in li] == [(h, a) for h, a, _ in lo] and
        [p for _, _, p in li] == [p for _, _, p in lo] and ti == to,
        "periodic: %s: the same %d links, node pairs and node tags" % (sys.argv[2], len(li)))
    worst_in = worst = 0.0
    npairs = 0
    for (_, aff, pairs) in li:
        A = np.eye(4) if not aff else np.array(aff).reshape(4, 4)
        for s, m in pairs:
            if s not in ti or m not in ti:
                continue
            npairs += 1
            rin = xi[ti[s]] - (A[:3, :3] @ xi[ti[m]] + A[:3, 3])
            rout = xo[to[s]] - (A[:3, :3] @ xo[to[m]] + A[:3, 3])
            worst_in = max(worst_in, np.abs(rin).max())
            worst = max(worst, np.abs(rout - rin).max())
    say(npairs > 0 and worst_in < 1e-9,
        "periodic: %s: %d pairs read, each slave = A master in the input (max %.1e)" %
        (sys.argv[1], npairs, worst_in))
    say(worst <= 1e-12, "periodic: %s: every pair keeps its transform (max change %.1e)"
        % (sys.argv[2], worst))
    moved = int(np.sum(np.any(xi != xo, axis=1)))
    say(moved > 0, "periodic: %s: %d of %d vertices moved" % (sys.argv[2], moved, len(xi)))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
