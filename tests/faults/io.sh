#!/bin/sh
# faults/io.sh - transient I/O faults (tests/faults/iofault.c, preloaded into
# qdcd): writes that fail with ENOSPC or EIO, short writes, fsync failures,
# on the upload's file, the SQLite job store, the worker's results and the
# conversions. Each answer is problem+json (507 + Retry-After for a full
# disk, 500 for another I/O error, 503 + Retry-After when the store cannot
# commit), the same request succeeds once the fault is gone, and nothing
# accepted is lost: every 202 ends succeeded with the same result bytes as a
# run without faults; a refused upload leaves no job, no directory and no
# temporary file. Part of `make fault` and `make test`.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"

CC=${CC:-cc}
if ! $CC -shared -fPIC -O2 -o "$TMP/libiofault.so" "$ROOT/tests/faults/iofault.c" -ldl 2> "$TMP/cc.err"; then
    echo "ok - io faults # SKIP cannot build the preload library: $(head -c 100 "$TMP/cc.err")"
    exit 0
fi
CTL=$TMP/ctl
echo off > "$CTL"
cat > "$TMP/qdcd" << EOF
#!/bin/sh
LD_PRELOAD=$TMP/libiofault.so IOFAULT_CTL=$CTL exec $BIN/qdcd "\$@"
EOF
chmod +x "$TMP/qdcd"
QDCD=$TMP/qdcd
D=$TMP/d
CUBE=$ROOT/tests/data/sample/cube.mesh
OPTS="max_iter=3"

# arm MODE TEXT COUNT | arm off: the next faults (a new file, renamed over)
arm() {
    printf '%s\n' "$*" > "$CTL.new" && mv "$CTL.new" "$CTL"
    : > "$CTL.hits"
}
hits() { wc -l < "$CTL.hits" | tr -d ' '; }
# up NAME: submit the cube; prints the status; a 202's job id is added to
# $TMP/accepted
: > "$TMP/accepted"
up() {
    _c=$(submit "$CUBE" model/x-medit "$OPTS" "$TMP/$1")
    [ "$_c" = 202 ] && jf "$TMP/$1" .id >> "$TMP/accepted"
    echo "$_c"
}
# problem FILE STATUS: FILE is a problem+json body of that status
problem() {
    [ "$(hdr "$1" Content-Type)" = application/problem+json ] &&
        [ "$(jf "$1" .status)" = "$2" ] && ! grep -q "$D" "$1"
}

start_qdcd "$D" --workers 1 || { fail "io: start" "$(tail -3 "$D.log")"; exit 1; }

# the reference: a run without faults
c=$(up ref)
ref=$(jf "$TMP/ref" .id)
st=$(wait_done "$ref")
req GET "/v1/jobs/$ref/result" "$TMP/ref.qmesh" > /dev/null
req GET "/v1/jobs/$ref/result?format=vtu" "$TMP/ref.vtu" > /dev/null
if [ "$c" != 202 ] || [ "$st" != succeeded ] || [ ! -s "$TMP/ref.qmesh" ]; then
    fail "io: reference job" "submit $c, state $st"
    exit 1
fi

# 1. the upload's file: ENOSPC is 507 + Retry-After, EIO 500; fsync fails: 500
for f in "enospc upload- 1 507" "eio upload- 1 500" "fsync upload- 1 500"; do
    set -- $f
    arm "$1" "$2" "$3"
    c=$(up "u$1")
    if [ "$c" = "$4" ] && problem "$TMP/u$1" "$4" && [ "$(hits)" = 1 ] &&
        { [ "$4" != 507 ] || [ -n "$(hdr "$TMP/u$1" Retry-After)" ]; }; then
        pass "io: upload, $1 on its file: $c problem+json ($(jf "$TMP/u$1" .detail))"
    else
        fail "io: upload, $1" "status $c (want $4), $(hits) faults: $(head -c 300 "$TMP/u$1")"
    fi
done

# 2. the job store: a commit whose write or fsync fails is a 503 + Retry-After
for f in "fsync qdcd.db" "eio qdcd.db"; do
    set -- $f
    arm "$1" "$2" 1
    c=$(up "s$1")
    n=$(hits)
    arm off
    c2=$(up "s$1.again")
    # the worker writes this job's states to the same store: let it finish
    # before the next fault is armed, or the fault may land on its write
    [ "$c2" = 202 ] && wait_done "$(jf "$TMP/s$1.again" .id)" > /dev/null
    if [ "$c" = 503 ] && problem "$TMP/s$1" 503 && [ -n "$(hdr "$TMP/s$1" Retry-After)" ] &&
        [ "$n" = 1 ] && [ "$c2" = 202 ]; then
        pass "io: job store, $1 at commit: 503 problem+json with Retry-After, then 202"
    else
        fail "io: job store, $1" "status $c, $n faults, then $c2: $(head -c 300 "$TMP/s$1")"
    fi
done

# 3. short writes everywhere in the data directory: callers loop, nothing changes
arm short "$D/" 1000000
c=$(up short)
id=$(jf "$TMP/short" .id)
st=$(wait_done "$id")
req GET "/v1/jobs/$id/result" "$TMP/short.qmesh" > /dev/null
req GET "/v1/jobs/$id/result?format=vtu" "$TMP/short.vtu" > /dev/null
n=$(hits)
arm off
if [ "$c" = 202 ] && [ "$st" = succeeded ] && [ "$n" -gt 10 ] &&
    cmp -s "$TMP/short.qmesh" "$TMP/ref.qmesh" && cmp -s "$TMP/short.vtu" "$TMP/ref.vtu"; then
    pass "io: $n short writes (upload, store, results, conversion): 202, succeeded, the same result bytes"
else
    fail "io: short writes" "submit $c, state $st, $n short writes, $(cmp "$TMP/short.qmesh" "$TMP/ref.qmesh" 2>&1)"
fi

# 4. the worker's results: a write or fsync that fails is tried again; the
# job succeeds with the same result
for f in "enospc result.qmesh 2" "fsync report.json 1"; do
    set -- $f
    arm "$1" "$2" "$3"
    c=$(up "w$1")
    id=$(jf "$TMP/w$1" .id)
    st=$(wait_done "$id")
    n=$(hits)
    arm off
    req GET "/v1/jobs/$id/result" "$TMP/w$1.qmesh" > /dev/null
    if [ "$c" = 202 ] && [ "$st" = succeeded ] && [ "$n" = "$3" ] &&
        cmp -s "$TMP/w$1.qmesh" "$TMP/ref.qmesh"; then
        pass "io: worker, $1 on $2 ($3 times): written again, succeeded, the same result"
    else
        fail "io: worker, $1 on $2" "submit $c, state $st, $n faults"
    fi
done

# 5. a conversion: ENOSPC is 507 + Retry-After, EIO 500; then the file
for f in "enospc 507 gmsh" "eio 500 vtk"; do
    set -- $f
    arm "$1" "result.$3" 1
    c=$(req GET "/v1/jobs/$ref/result?format=$3" "$TMP/c$1")
    n=$(hits)
    arm off
    c2=$(req GET "/v1/jobs/$ref/result?format=$3" "$TMP/c$1.again")
    if [ "$c" = "$2" ] && problem "$TMP/c$1" "$2" && [ "$n" = 1 ] && [ "$c2" = 200 ] &&
        [ -s "$TMP/c$1.again" ]; then
        pass "io: conversion to $3, $1: $c problem+json, then 200"
    else
        fail "io: conversion to $3, $1" "status $c (want $2), $n faults, then $c2: $(head -c 300 "$TMP/c$1")"
    fi
done

# nothing accepted is lost, nothing refused is left
arm off
bad=
for id in $(cat "$TMP/accepted"); do
    [ "$(wait_done "$id")" = succeeded ] || bad="$bad $id:$(jf "$TMP/job.$id" .state)"
done
listed=$(curl -s "$URL/v1/jobs?limit=100" | jq -r '.jobs[].id' | sort)
dirs=$(ls "$D/jobs" | sort)
acc=$(sort "$TMP/accepted")
if [ -z "$bad" ] && [ "$listed" = "$acc" ] && [ "$dirs" = "$acc" ] && [ -z "$(ls "$D/tmp")" ]; then
    pass "io: the $(echo "$acc" | wc -l) accepted jobs succeeded and are the only jobs and directories; no temporary file left"
else
    fail "io: accounting" "not succeeded:$bad; listed $(echo $listed) vs accepted $(echo $acc); dirs $(echo $dirs); tmp $(ls "$D/tmp")"
fi
stop_qdcd || fail "io: SIGTERM" "exit status $?"
exit $((NFAIL > 0))
