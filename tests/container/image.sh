#!/bin/sh
# tests/container/image.sh - the qdcd image, built and run by a real container
# engine (Podman; Docker if its engine answers): the base image from
# docker/base-image.sh (no registry here), `build` of docker/Dockerfile, then
# a container that takes a job, is stopped with SIGTERM (exit 0, promptly),
# and a second container on the same volume that still has the job and its
# result. Without a working engine every check is reported as a skip.
. "$(dirname "$0")/../lib.sh"
. "$(dirname "$0")/engine.inc"

engine_or_skip "container: base image|container: image build|container: job in a container|container: SIGTERM stop|container: restart on the same volume"

# 1. base image (debootstrap into the local store; kept between runs)
if base_image; then
    pass "container: base image debian:bookworm-slim in the local store ($ENGINE)"
else
    fail "container: base image" "$(tail -3 "$TMP/base.log" | tr '\n' ' ')"
    exit 1
fi

# 2. the image, from the repository as it is (a context of tracked files only),
# under a tag kept between runs (engine.inc: the layer cache makes a rebuild of
# an unchanged tree quick, and tests/container/replicas.sh reuses it)
IMG=$IMG_QDC
repo_context "$TMP/ctx"
cleanup() {
    "$ENGINE" rm -f qdc-test-a-$$ qdc-test-b-$$ > /dev/null 2>&1
    "$ENGINE" volume rm -f qdc-test-vol-$$ > /dev/null 2>&1
    rm -rf "$TMP"
}
trap cleanup EXIT
trap 'exit 1' INT TERM HUP PIPE # so that cleanup runs then too
if build_image "$IMG" "$TMP/ctx/docker/Dockerfile" "$TMP/ctx"; then
    pass "container: image $IMG built in $BUILD_S s ($BUILD_MB MB; layers of an unchanged tree come from the cache)"
else
    fail "container: image build" "$(tail -5 "$TMP/build.log" | tr '\n' ' ')"
    exit 1
fi

# 3. a container on a named volume takes a job and finishes it
free_port() {
    /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'
}
PORT=$(free_port)
URL=http://127.0.0.1:$PORT
"$ENGINE" volume create qdc-test-vol-$$ > /dev/null
run_ctr() { # NAME
    "$ENGINE" run -d $NOHC --name "$1" --network host -v qdc-test-vol-$$:/var/lib/qdc "$IMG" \
        --listen "127.0.0.1:$PORT" --data /var/lib/qdc > /dev/null
}
wait_live() {
    i=0
    while [ $i -lt 100 ]; do
        [ "$(curl -s -o /dev/null -w '%{http_code}' "$URL/livez")" = 200 ] && return 0
        sleep 0.2
        i=$((i + 1))
    done
    return 1
}
run_ctr qdc-test-a-$$ && wait_live || {
    fail "container: start" "$("$ENGINE" logs qdc-test-a-$$ 2>&1 | tail -3 | tr '\n' ' ')"
    exit 1
}
id=$(curl -s -X POST -H 'Content-Type: model/x-medit' --data-binary "@$ROOT/tests/data/sample/cube.mesh" \
    "$URL/v1/jobs?max_iter=5" | jq -r .id)
i=0
while [ $i -lt 300 ] && [ "$(curl -s "$URL/v1/jobs/$id" | jq -r .done)" != true ]; do
    sleep 0.2
    i=$((i + 1))
done
curl -s -o "$TMP/a.mesh" "$URL/v1/jobs/$id/result?format=medit"
state=$(curl -s "$URL/v1/jobs/$id" | jq -r .state)
if [ "$state" = succeeded ] && "$BIN/qdc" quality "$TMP/a.mesh" > "$TMP/qa" 2>&1; then
    pass "container: job $id succeeded, its result is a valid mesh"
else
    fail "container: job in a container" "state '$state': $(tail -2 "$TMP/qa" | tr '\n' ' ')"
fi

# 4. SIGTERM (docker/podman stop) ends qdcd cleanly and quickly
t0=$(date +%s%N)
"$ENGINE" stop -t 20 qdc-test-a-$$ > /dev/null
ms=$((($(date +%s%N) - t0) / 1000000))
rc=$("$ENGINE" inspect qdc-test-a-$$ --format '{{.State.ExitCode}}')
if [ "$rc" = 0 ] && [ $ms -lt 10000 ]; then
    pass "container: stop (SIGTERM) -> exit 0 in $ms ms"
else
    fail "container: SIGTERM stop" "exit code $rc after $ms ms"
fi

# 5. a new container on the same volume still has the job and its result
run_ctr qdc-test-b-$$ && wait_live || {
    fail "container: restart" "$("$ENGINE" logs qdc-test-b-$$ 2>&1 | tail -3 | tr '\n' ' ')"
    exit 1
}
state=$(curl -s "$URL/v1/jobs/$id" | jq -r .state)
curl -s -o "$TMP/b.mesh" "$URL/v1/jobs/$id/result?format=medit"
if [ "$state" = succeeded ] && cmp -s "$TMP/a.mesh" "$TMP/b.mesh"; then
    pass "container: restart on the same volume: job still there, same result bytes"
else
    fail "container: restart on the same volume" "state '$state', result $(cmp "$TMP/a.mesh" "$TMP/b.mesh" 2>&1)"
fi
"$ENGINE" stop -t 20 qdc-test-b-$$ > /dev/null
exit 0
