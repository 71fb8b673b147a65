#!/bin/sh
# streams.sh - qdc in a pipeline: "-" for standard input and output, pipes,
# /dev/stdout and /dev/fd/1, devices, and OUT given as a symbolic link. A pipe
# or device is written straight into (a rename would replace /dev/stdout's
# link with a file, as qdc once did); a link to a file keeps being a link, the
# file it names is replaced (atomically, with its permissions).
. "$(dirname "$0")/../lib.sh"
Q=$BIN/qdc
IN=$ROOT/tests/data/sample/cube.mesh
cd "$TMP" || exit 1

# the same run written to a file: what every stream form must give, byte for byte
"$Q" optimize "$IN" ref.mesh --quiet || fail "reference run" "exit $?"
"$Q" convert "$IN" in.msh --quiet && "$Q" optimize in.msh ref.msh --quiet || fail "reference .msh run" "exit $?"

# 1. - and - (Medit, the input's format, spliced)
if "$Q" optimize - - --quiet < "$IN" > out1.mesh && cmp -s out1.mesh ref.mesh; then
    pass "optimize - - (Medit through standard input and output): the file-to-file result, byte for byte"
else
    fail "optimize - -" "$(cmp out1.mesh ref.mesh 2>&1)"
fi
# 2. gzip-compressed on standard input; 3. Gmsh 4.1 through a pipe both ways
gzip -c "$IN" > in.mesh.gz
if "$Q" optimize - out2.mesh --quiet < in.mesh.gz && cmp -s out2.mesh ref.mesh; then
    pass "gzip-compressed Medit on standard input: read once, same result"
else
    fail "gzip stdin" "$(cmp out2.mesh ref.mesh 2>&1)"
fi
if cat in.msh | "$Q" optimize - - --quiet | cat > out3.msh && cmp -s out3.msh ref.msh; then
    pass "Gmsh 4.1 piped in and out: told by its contents, written back spliced like the file-to-file run"
else
    fail "msh pipe" "$(head -2 out3.msh | tr '\n' ' ')"
fi
# 4. convert - - is the identity (spliced); quality - reads standard input
if "$Q" convert - - --quiet < in.msh | cmp -s - in.msh; then
    pass "convert - -: the input, byte for byte"
else
    fail "convert - -" "differs"
fi
if "$Q" quality - < ref.mesh | grep -q '^-: 216 vertices, 750 tets, 0 inverted'; then
    pass "quality - reads standard input"
else
    fail "quality -" "$("$Q" quality - < ref.mesh 2>&1 | head -2 | tr '\n' ' ')"
fi
# 5. a named pipe as IN
mkfifo fifo.mesh
cat "$IN" > fifo.mesh &
if "$Q" optimize fifo.mesh out5.vtu --quiet && "$Q" convert out5.vtu out5.mesh --quiet --no-keep-source &&
    "$Q" quality out5.mesh | grep -q ' 0 inverted'; then
    pass "a named pipe as IN (read once), written as .vtu"
else
    fail "fifo" "no valid output"
fi
wait

# a closed surface (OFF) on standard input: tetrahedralized by TetGen, as from a file
"$Q" tetra "$ROOT/tests/data/sample/cube.off" tf.mesh --max-volume 0.01 --quiet
"$Q" tetra - ts.mesh --max-volume 0.01 --quiet < "$ROOT/tests/data/sample/cube.off"
"$Q" optimize - os.mesh --max-volume 0.01 --quiet < "$ROOT/tests/data/sample/cube.off"
"$Q" optimize "$ROOT/tests/data/sample/cube.off" of.mesh --max-volume 0.01 --quiet
"$Q" tetra - - --max-volume 0.01 --quiet < "$ROOT/tests/data/sample/cube.off" > tp.mesh
if [ -s tf.mesh ] && cmp -s tf.mesh ts.mesh && [ -s of.mesh ] && cmp -s of.mesh os.mesh && cmp -s tp.mesh tf.mesh; then
    pass "a closed surface on standard input: tetra and optimize give what they give from the file, tetra - - writes Medit ($(grep -A1 '^Tetrahedra' ts.mesh | tail -1) tets)"
else
    fail "surface stdin" "$(ls -l tf.mesh ts.mesh of.mesh os.mesh 2>&1 | tr '\n' ' ')"
fi

# 6. /dev/stdout and /dev/fd/1, redirected to a file and to a pipe
link_before=$(ls -l /dev/stdout)
"$Q" optimize "$IN" /dev/stdout --quiet > out6.mesh
rc=$?
if [ $rc = 0 ] && cmp -s out6.mesh ref.mesh && [ -L /dev/stdout ] && [ "$(ls -l /dev/stdout)" = "$link_before" ]; then
    pass "OUT /dev/stdout redirected to a file: the result there, /dev/stdout still a link"
else
    fail "/dev/stdout" "exit $rc, $(wc -c < out6.mesh) bytes, $(ls -l /dev/stdout)"
fi
if [ "$("$Q" optimize "$IN" /dev/stdout --quiet | cksum)" = "$(cksum < ref.mesh)" ]; then
    pass "OUT /dev/stdout into a pipe"
else
    fail "/dev/stdout pipe" "differs"
fi
if "$Q" optimize "$IN" /dev/fd/1 --quiet > out6b.mesh && cmp -s out6b.mesh ref.mesh; then
    pass "OUT /dev/fd/1 redirected to a file"
else
    fail "/dev/fd/1" "$(wc -c < out6b.mesh) bytes"
fi
ls "$TMP" | grep -q '\.tmp\.' && fail "temporary files" "$(ls "$TMP" | grep '\.tmp\.')"
# 7. /dev/null: written into, still a device
if "$Q" optimize "$IN" /dev/null --quiet && [ -c /dev/null ]; then
    pass "OUT /dev/null: exit 0, /dev/null still a character device"
else
    fail "/dev/null" "$(ls -l /dev/null)"
fi

# 8. OUT a link to a file (relative, mode 600): the file replaced, the link kept
mkdir res
echo old > res/t.mesh
chmod 600 res/t.mesh
ln -s res/t.mesh link.mesh
if "$Q" optimize "$IN" link.mesh --quiet && [ -L link.mesh ] && cmp -s res/t.mesh ref.mesh &&
    [ "$(stat -c %a res/t.mesh)" = 600 ] && [ "$(ls res)" = t.mesh ]; then
    pass "OUT a symbolic link: still a link, the file it names holds the result with its mode 600"
else
    fail "symlink OUT" "$(ls -l link.mesh res/)"
fi
# a link to a link to nothing yet: the file is created where it points
ln -s res/new.mesh dangling.mesh
ln -s dangling.mesh chain.mesh
if "$Q" optimize "$IN" chain.mesh --quiet && [ -L chain.mesh ] && [ -L dangling.mesh ] && cmp -s res/new.mesh ref.mesh; then
    pass "OUT a chain of links to nothing: the file created at its end, the links kept"
else
    fail "dangling link" "$(ls -l chain.mesh dangling.mesh res/)"
fi
# an existing file keeps its permissions when replaced
echo old > plain.mesh
chmod 640 plain.mesh
if "$Q" optimize "$IN" plain.mesh --quiet && [ "$(stat -c %a plain.mesh)" = 640 ] && cmp -s plain.mesh ref.mesh; then
    pass "an existing OUT replaced keeps its permissions (640)"
else
    fail "mode kept" "$(ls -l plain.mesh)"
fi

# 9. errors: empty or unreadable standard input (exit 2, says what), TetGen to
# standard output (exit 4), an output format that cannot be told
"$Q" optimize - o.mesh < /dev/null 2> err9
rc=$?
if [ $rc = 2 ] && grep -q '^qdc: -' err9; then
    pass "empty standard input: exit 2, '$(head -1 err9)'"
else
    fail "empty stdin" "exit $rc: $(cat err9)"
fi
echo hello | "$Q" optimize - o.mesh 2> err9b
rc=$?
if [ $rc = 2 ] && grep -q 'unrecognized mesh format' err9b; then
    pass "text that is no mesh on standard input: exit 2, '$(head -1 err9b)'"
else
    fail "garbage stdin" "exit $rc: $(cat err9b)"
fi
"$Q" optimize "$IN" - --out-format tetgen --quiet > o.txt 2> err9c
rc=$?
if [ $rc = 4 ] && grep -q 'two files' err9c && [ ! -s o.txt ]; then
    pass "TetGen to standard output: exit 4, '$(head -1 err9c)'"
else
    fail "tetgen stdout" "exit $rc: $(cat err9c)"
fi
"$Q" optimize "$IN" /dev/stdout --out-format tetgen --quiet > o.txt 2> err9d
rc=$?
if [ $rc = 4 ] && grep -q 'two files' err9d && [ ! -e /dev/stdout.node ]; then
    pass "TetGen to /dev/stdout: exit 4, no /dev/stdout.node"
else
    fail "tetgen /dev/stdout" "exit $rc: $(cat err9d)"
fi

"$Q" optimize "$IN" - --report - > o.txt 2> err9e
rc=$?
if [ $rc = 1 ] && grep -q 'cannot both be standard output' err9e && [ ! -s o.txt ]; then
    pass "OUT - with --report -: exit 1 (usage), nothing written"
else
    fail "out and report on stdout" "exit $rc: $(cat err9e)"
fi

[ "$NFAIL" = 0 ]
