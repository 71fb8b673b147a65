#!/usr/bin/python3
# medcoo.py A B WHAT [DATASET] - h5py: is MED file B the same file as A but
# for the coordinates (NOE/COO; or DATASET, an XDMF's geometry in its .h5:
# "data0")? Every other dataset and every attribute equal, none added or
# missing, some coordinates changed. Prints one "ok - " or "FAIL - " line
# naming WHAT.
import sys
import h5py, numpy as np
a, b = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
coo = sys.argv[4] if len(sys.argv) > 4 else None
bad, names = [], []
def walk(name, obj):
    o = b.get(name)
    if o is None or type(o) != type(obj):
        bad.append("missing " + name)
        return
    if sorted(obj.attrs) != sorted(o.attrs) or any(
            not np.array_equal(obj.attrs[k], o.attrs[k]) for k in obj.attrs):
        bad.append("attributes of " + name)
    if isinstance(obj, h5py.Dataset):
        if name == coo if coo else name.endswith("/NOE/COO"):
            names.append(name)
        elif obj.dtype != o.dtype or not np.array_equal(obj[()], o[()]):
            bad.append("dataset " + name)
a.visititems(walk)
b.visititems(lambda n, o: None if n in a else bad.append("added " + n))
ca, cb = a[names[0]][()], b[names[0]][()]
moved = int(np.sum(ca != cb))
print(("ok" if not bad and ca.dtype == cb.dtype and ca.shape == cb.shape and moved else "FAIL")
      + " - %s: only %s changed (%d of %d values) %s"
      % (sys.argv[3], coo or "NOE/COO", moved, ca.size, bad[:3]))
