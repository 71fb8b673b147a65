# tests/lib.sh - helpers for shell tests: source it, then call pass/fail/check.
# Output protocol shared with the C tests: "ok - name" / "FAIL - name: why".
ROOT=${ROOT:-$(cd "$(dirname "$0")/../.." && pwd)}
BIN=${BIN:-$ROOT/build/rel}
DEV=${DEV:-$ROOT/tests/data/dev}
QUALITY=${QUALITY:-$ROOT/tests/tools/evaluate.py}
PY=/usr/bin/python3
# tests/tools for the scripts' inline Python, which reads and writes Medit with
# tests/tools/meditio.py: sys.path.insert(0, os.environ["QDC_TOOLS"])
QDC_TOOLS=$ROOT/tests/tools
export QDC_TOOLS
TMP=$(mktemp -d "${TMPDIR:-/tmp}/qdc-test.XXXXXX")
trap 'rm -rf "$TMP"' EXIT
NFAIL=0
pass() { echo "ok - $1"; }
fail() { echo "FAIL - $1: $2"; NFAIL=$((NFAIL + 1)); }
# verdict NAME WHY: pass "NAME: figures" when WHY is "ok figures" (what a
# check script printed), else fail NAME with WHY as the reason
verdict() {
    case $2 in
    ok*) pass "$1: ${2#ok }" ;;
    *) fail "$1" "$2" ;;
    esac
}
# check NAME COMMAND...: pass if the command exits 0
check() {
    name=$1; shift
    if out=$("$@" 2>&1); then pass "$name"; else fail "$name" "$(printf '%s' "$out" | tail -3 | tr '\n' ' ')"; fi
}
# devmesh NAME: path of an uncompressed copy of a dev mesh in $TMP
devmesh() {
    [ -f "$TMP/$1.mesh" ] || gzip -dc "$DEV/$1.mesh.gz" > "$TMP/$1.mesh"
    echo "$TMP/$1.mesh"
}
# corpus_mesh CHECK NAME TETS [corpus.py options...]: scripts/corpus.py's mesh
# NAME at TETS tets, made in $TMP/c; its path in CORPUS_MESH. Without
# numpy/scipy the script ends here with "ok - CHECK # SKIP ..."; when
# corpus.py fails, CHECK fails and the script ends (exit 1).
corpus_mesh() {
    _check=$1 _name=$2 _tets=$3
    shift 3
    if ! "$PY" -c 'import numpy, scipy' 2> /dev/null; then
        echo "ok - $_check # SKIP python3-numpy/python3-scipy missing"
        exit 0
    fi
    if ! "$PY" "$ROOT/scripts/corpus.py" "$TMP/c" --tets "$_tets" "$@" --only "$_name" > "$TMP/list" 2>&1; then
        fail "$_check" "scripts/corpus.py failed: $(tail -1 "$TMP/list")"
        exit 1
    fi
    CORPUS_MESH=$TMP/c/$_name.mesh
}
