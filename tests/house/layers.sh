#!/bin/sh
# tests/house/layers.sh - the include graph keeps its layers (docs/architecture.md):
#   lib/ never includes server/ or clients/ headers, nor libmicrohttpd/jansson/SQLite;
#   a lib/ file includes only its own layer and lower ones
#   (core < geom < topo < opt, core < geom < io, opt and io < eval < qdc.h; io and
#   opt do not include each other, io does not include topo);
#   server/ and clients/ include the library only through lib/qdc.h;
#   the headers qdc.h reaches are exactly the public ones (PUBLIC below), so an
#   internal header (X_int.h, or any lib/ header qdc.h does not reach) is never
#   reachable through qdc.h; outside lib/ only the unit tests and the fuzz
#   targets (tests of the library's parts) include internal headers: server/,
#   clients/, examples/, bench/ and the other tests include qdc.h alone;
#   no include cycle among the project's headers.
ROOT=${ROOT:-$(cd "$(dirname "$0")/../.." && pwd)}
cd "$ROOT" || exit 1
fail=0
rank() {
    case $1 in
    core) echo 0 ;; geom) echo 1 ;; topo) echo 2 ;; io | opt) echo 3 ;; eval) echo 4 ;;
    *) echo 9 ;;
    esac
}
for f in lib/*/*.c lib/*/*.h lib/*/*.cpp; do
    [ -f "$f" ] || continue
    layer=$(basename "$(dirname "$f")")
    r=$(rank "$layer")
    for inc in $(sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "$f"); do
        dir=${inc%%/*}
        if [ "$dir" = "$inc" ]; then
            echo "FAIL - layers: $f includes \"$inc\" without its layer folder"
            fail=1
            continue
        fi
        ri=$(rank "$dir")
        if [ "$ri" = 9 ]; then
            echo "FAIL - layers: $f includes \"$inc\" (not a lib/ layer)"
            fail=1
        elif [ "$ri" -gt "$r" ] || { [ "$ri" = "$r" ] && [ "$dir" != "$layer" ]; } ||
            { [ "$layer" = io ] && [ "$dir" = topo ]; }; then
            echo "FAIL - layers: $f ($layer) includes $inc: a higher or peer layer"
            fail=1
        fi
    done
    if grep -Eq '#[[:space:]]*include[[:space:]]*<(microhttpd|jansson|sqlite3|libpq-fe|curl/curl)\.h>' "$f"; then
        echo "FAIL - layers: $f includes a server or client library"
        fail=1
    fi
done
[ $fail = 0 ] && echo "ok - layers: lib/ files include only their own and lower layers"

fail=0
for f in server/*.c server/*.h clients/qdc/*.c clients/qdc/*.h common/*.c common/*.h; do
    [ -f "$f" ] || continue
    for inc in $(sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "$f"); do
        case $inc in
        */*) echo "FAIL - layers: $f includes \"$inc\": use qdc.h"; fail=1 ;;
        *) [ -f "lib/$inc" ] && [ "$inc" != qdc.h ] &&
            { echo "FAIL - layers: $f includes lib/$inc"; fail=1; } ;;
        esac
    done
done
[ $fail = 0 ] && echo "ok - layers: server/ and clients/ use the library through qdc.h only"

# Public and internal headers (docs/architecture.md, "Public and internal headers").
PUBLIC="qdc.h core/base.h core/mesh.h geom/metric.h geom/bderr.h io/meshio.h io/formats.h io/surface.h
io/tetra.h io/gz.h opt/opt.h opt/options.h eval/report.h eval/outcome.h"
reach=$(
    todo=qdc.h seen=
    while [ -n "$todo" ]; do
        set -- $todo
        h=$1
        shift
        todo=$*
        case " $seen " in *" $h "*) continue ;; esac
        seen="$seen $h"
        todo="$todo $(sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "lib/$h")"
    done
    echo $seen | tr ' ' '\n' | sort
)
want=$(echo $PUBLIC | tr ' ' '\n' | sort)
extra=$(echo "$reach" | grep -vxF "$want" | tr '\n' ' ')
missing=$(echo "$want" | grep -vxF "$reach" | tr '\n' ' ')
if [ -z "$extra$missing" ]; then
    echo "ok - layers: qdc.h reaches the public headers and no internal one"
else
    echo "FAIL - layers: qdc.h reaches internal headers [ $extra] and misses public [ $missing]"
fi

fail=0
for f in $(git ls-files --cached --others --exclude-standard '*.c' '*.h' '*.cpp' 2> /dev/null); do
    case $f in lib/* | tests/unit/* | tests/fuzz/*) continue ;; esac
    for inc in $(sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "$f"); do
        [ "$inc" != qdc.h ] && [ -f "lib/$inc" ] &&
            { echo "FAIL - layers: $f includes the internal lib/$inc: use qdc.h"; fail=1; }
    done
done
[ $fail = 0 ] && echo "ok - layers: outside lib/, only the unit and fuzz tests include internal headers"

# Include cycles: a depth-first walk over "file -> included project header".
if python3 -c 'pass' 2>/dev/null; then
    if python3 - <<'PY'; then echo "ok - layers: no include cycle"; else echo "FAIL - layers: include cycle"; fi
import glob, os, re, sys
files = [f for pat in ("lib/*.h", "lib/*/*.h", "server/*.h", "clients/qdc/*.h")
         for f in glob.glob(pat)]
def resolve(src, inc):
    for base in (os.path.dirname(src), "lib"):
        p = os.path.normpath(os.path.join(base, inc))
        if os.path.isfile(p):
            return p
    return None
edges = {}
for f in files:
    text = open(f, encoding="utf-8", errors="replace").read()
    edges[f] = [p for p in (resolve(f, i) for i in re.findall(r'#\s*include\s*"([^"]+)"', text)) if p]
state = {}
def visit(f, path):
    state[f] = 1
    for g in edges.get(f, []):
        if state.get(g) == 1:
            print("cycle: " + " -> ".join(path + [g]), file=sys.stderr)
            sys.exit(1)
        if g not in state:
            visit(g, path + [g])
    state[f] = 2
for f in files:
    if f not in state:
        visit(f, [f])
PY
else
    echo "FAIL - layers: python3 missing for the cycle check"
fi
