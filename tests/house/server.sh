#!/bin/sh
# tests/house/server.sh - the shape of server/ (issue 30): no two files call
# or include each other in a loop (calls: the symbols each object of the
# release build defines and uses, by nm; includes: the "..." includes of
# server/*.c and *.h, a file and its header counting as one), no file over
# 1,000 lines and no function over 80 (from its line "{" to its line "}").
. "$(dirname "$0")/../lib.sh"
OBJ=$BIN/server
if ! ls "$OBJ"/*.o > /dev/null 2>&1 || ! command -v nm > /dev/null; then
    echo "ok - server: call graph # SKIP no $OBJ/*.o (make all) or no nm"
    OBJ=
fi
"$PY" - "$ROOT/server" "$OBJ" <<'PYEOF'
import glob, os, re, subprocess, sys
src, obj = sys.argv[1], sys.argv[2]
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
        print("FAIL - server: %s in a loop: %s" % (what, " ".join(comp)))
        bad = 1
    if not c:
        print("ok - server: no %s in a loop (%d files)" % (what, n))

mods = {}
for f in glob.glob(os.path.join(src, "*.[ch]")):
    mods.setdefault(os.path.basename(f).rsplit(".", 1)[0], []).append(f)
inc = {}
for m, files in mods.items():
    for f in files:
        for h in re.findall(r'#include "([^"/]+)\.h"', open(f).read()):
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
    if len(defs) < 100:
        print("FAIL - server: only %d symbols defined in %s (the scan is broken)" % (len(defs), obj))
        bad = 1
    report("files that call each other", calls, len(objs))

longest = (0, "")
for f in sorted(glob.glob(os.path.join(src, "*.[ch]"))):
    lines = open(f).read().split("\n")
    name = "server/" + os.path.basename(f)
    if len(lines) - 1 > 1000:
        print("FAIL - server: %s has %d lines (at most 1,000)" % (name, len(lines) - 1))
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
                print("FAIL - server: %s is %d lines (at most 80)" % (where, n))
                bad = 1
            start = None
if longest[0] < 20:
    print("FAIL - server: no function found (the scan is broken)")
    bad = 1
elif not bad:
    print("ok - server: no file over 1,000 lines, no function over 80 (longest: %d, %s)"
          % longest)
sys.exit(bad)
PYEOF
