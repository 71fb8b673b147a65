#!/bin/sh
# tests/house/rooms.sh - the shape of server/ and lib/opt/ (issue 30): no two
# files of one folder call or include each other in a loop (calls: the
# symbols each object of the release build defines and uses, by nm; includes:
# the "..." includes of *.c and *.h, in server/ a file and its header
# counting as one), no file over 1,000 lines and no function over 80 (from
# its line "{" to its line "}").
. "$(dirname "$0")/../lib.sh"
rc=0
for DIR in server lib/opt; do
OBJ=$BIN/$DIR
if ! ls "$OBJ"/*.o > /dev/null 2>&1 || ! command -v nm > /dev/null; then
    echo "ok - $DIR: call graph # SKIP no $OBJ/*.o (make all) or no nm"
    OBJ=
fi
"$PY" - "$ROOT" "$DIR" "$OBJ" <<'PYEOF' || rc=1
import glob, os, re, subprocess, sys
root, label, obj = sys.argv[1], sys.argv[2], sys.argv[3]
src = os.path.join(root, label)
layer = os.path.basename(label)
bad = 0

def cycles(g):
    """The strongly connected components of more than one node (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    def visit(n):
        index[n] = low[n] = len(index)
        stack.append(n); on.add(n)
        for w in sorted(g.get(n, ())):
            if w not in index:
                visit(w); low[n] = min(low[n], low[w])
            elif w in on:
                low[n] = min(low[n], index[w])
        if low[n] == index[n]:
            comp = []
            while True:
                w = stack.pop(); on.discard(w); comp.append(w)
                if w == n: break
            if len(comp) > 1: out.append(sorted(comp))
    for n in sorted(g):
        if n not in index: visit(n)
    return out

def report(what, g, n):
    global bad
    c = cycles(g)
    for comp in c:
        print("FAIL - %s: %s in a loop: %s" % (label, what, " ".join(comp)))
        bad = 1
    if not c:
        print("ok - %s: no %s in a loop (%d files)" % (label, what, n))

# In server/ a file and its header count as one; in lib/opt/ the public
# opt.h is implemented by several files, so each file counts alone there.
whole = label == "server"
key = lambda name: name.rsplit(".", 1)[0] if whole else name
mods = {}
for f in glob.glob(os.path.join(src, "*.[ch]")):
    mods.setdefault(key(os.path.basename(f)), []).append(f)
inc = {}
for m, files in mods.items():
    for f in files:
        for h in re.findall(r'#include "(?:%s/)?([^"/]+\.h)"' % layer, open(f).read()):
            h = key(h)
            if h in mods and h != m: inc.setdefault(m, set()).add(h)
report("files that include each other", inc, len(mods))

if obj:
    defs, uses = {}, {}
    objs = sorted(glob.glob(os.path.join(obj, "*.o")))
    for o in objs:
        m = os.path.basename(o)[:-2]
        for line in subprocess.run(["nm", o], capture_output=True, text=True).stdout.splitlines():
            p = line.split()
            if len(p) == 3 and p[1] in "TDBR": defs[p[2]] = m
            elif len(p) == 2 and p[0] == "U": uses.setdefault(m, set()).add(p[1])
    calls = {m: {defs[s] for s in us if s in defs and defs[s] != m} for m, us in uses.items()}
    if len(defs) < 30:
        print("FAIL - %s: only %d symbols defined in %s (the scan is broken)" % (label, len(defs), obj))
        bad = 1
    report("files that call each other", calls, len(objs))

longest = (0, "")
for f in sorted(glob.glob(os.path.join(src, "*.[ch]"))):
    lines = open(f).read().split("\n")
    name = label + "/" + os.path.basename(f)
    if len(lines) - 1 > 1000:
        print("FAIL - " + label + ": %s has %d lines (at most 1,000)" % (name, len(lines) - 1))
        bad = 1
    start = None
    for i, l in enumerate(lines):
        if l == "{" and start is None:
            start = i
        elif l.startswith("}") and start is not None:
            n = i - start + 1
            where = "%s:%d %s" % (name, start, lines[start - 1].split("(")[0])
            longest = max(longest, (n, where))
            if n > 80:
                print("FAIL - " + label + ": %s is %d lines (at most 80)" % (where, n))
                bad = 1
            start = None
if longest[0] < 20:
    print("FAIL - " + label + ": no function found (the scan is broken)")
    bad = 1
elif not bad:
    print("ok - %s: no file over 1,000 lines, no function over 80 (longest: %d, %s)"
          % ((label,) + longest))
sys.exit(bad)
PYEOF
done
exit $rc
