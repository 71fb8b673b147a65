#!/bin/sh
# docker.sh - docker/ without a Docker engine: lint the Dockerfile
# (dockerfile-utils from npm), check its structure (bookworm-slim build and
# runtime stages, deps.sh, numeric USER, VOLUME, HEALTHCHECK on /livez, exec'd
# entrypoint), run the build stage's make on exactly what the Dockerfile
# copies, check the runtime stage installs every shared library the binaries
# need, and run the entrypoint: it execs qdcd, which stops on SIGTERM.
. "$(dirname "$0")/../lib.sh"
DF=$ROOT/docker/Dockerfile
EP=$ROOT/docker/entrypoint.sh
CF=$ROOT/docker/compose.single.yaml

# 1. linter
if command -v npx > /dev/null 2>&1; then
    for df in Dockerfile postgres.Dockerfile haproxy.Dockerfile; do
        out=$(cd "$ROOT" && timeout 180 npx --yes dockerfile-utils lint "docker/$df" 2>&1)
        rc=$?
        if [ $rc = 0 ]; then
            pass "dockerfile-utils lint docker/$df: no problem"
        else
            fail "dockerfile-utils lint docker/$df" "rc $rc: $(printf '%s' "$out" | grep -v 'npm warn' | head -8 | tr '\n' ' ')"
        fi
    done
else
    echo "ok - dockerfile-utils lint # SKIP no npx here (apt-get install npm)"
fi
if command -v shellcheck > /dev/null 2>&1; then
    check "shellcheck docker/*entrypoint.sh clients/batch/qdc-batch.sh" shellcheck -s sh "$EP" \
        "$ROOT/docker/postgres-entrypoint.sh" "$ROOT/docker/haproxy-entrypoint.sh" "$ROOT/clients/batch/qdc-batch.sh"
fi

# 2. structure
ins() { grep -E "^$1( |$)" "$DF"; } # instructions of one kind
bad=
[ "$(ins FROM | grep -c 'debian:bookworm-slim')" = 2 ] && [ "$(ins FROM | wc -l)" = 2 ] || bad="$bad two-bookworm-slim-stages"
ins FROM | head -1 | grep -q ' AS build$' || bad="$bad build-stage-first"
grep -q '^RUN scripts/deps.sh' "$DF" || bad="$bad deps.sh"
grep -q '^COPY scripts/deps.sh ' "$DF" || bad="$bad copy-deps.sh"
ins USER | tail -1 | grep -Eq '^USER [0-9]+:[0-9]+$' || bad="$bad numeric-user"
vol=$(ins VOLUME | sed 's/^VOLUME \["\(.*\)"\]$/\1/')
[ -n "$vol" ] && ins CMD | grep -q "\"--data\", \"$vol\"" || bad="$bad volume=data"
ins HEALTHCHECK | grep -q '/livez' || sed -n '/^HEALTHCHECK/,/[^\\]$/p' "$DF" | grep -q '/livez' || bad="$bad healthcheck"
ins STOPSIGNAL | grep -q SIGTERM || bad="$bad stopsignal"
ins ENTRYPOINT | grep -q '^ENTRYPOINT \["' || bad="$bad exec-form-entrypoint"
ins CMD | grep -q '"0.0.0.0:8080"' && ins EXPOSE | grep -q 8080 || bad="$bad port"
grep -q 'libopenblas0-pthread' "$DF" || bad="$bad openblas"
grep -q "^ *- qdc-data:$vol$" "$CF" && grep -q '^  qdc-data:' "$CF" || bad="$bad compose-named-volume"
grep -q 'dockerfile: docker/Dockerfile' "$CF" && grep -q '"127.0.0.1:8080:8080"' "$CF" || bad="$bad compose-build-ports"
[ -z "$bad" ] && pass "Dockerfile/compose structure: 2 bookworm-slim stages, deps.sh, USER numeric, VOLUME $vol = --data, HEALTHCHECK /livez, named volume" ||
    fail "Dockerfile structure" "missing:$bad"

# 2b. docker/compose.yaml: PostgreSQL and 3 qdcd replicas on it behind one
# published (loopback) port; every image built here from debian:bookworm-slim
if out=$($PY - "$ROOT/docker/compose.yaml" << 'PYEOF' 2>&1
import os, re, sys
import yaml
path = sys.argv[1]
d = yaml.safe_load(open(path))
svc = d["services"]
bad = []
qdcd = [n for n, s in svc.items() if "--store" in s.get("command", [])]
uris = [s["command"][s["command"].index("--store") + 1] for s in (svc[n] for n in qdcd)]
if len(qdcd) != 3 or not all(u.startswith("postgresql://") for u in uris) or len(set(uris)) != 1:
    bad.append("3 replicas on one postgresql:// store: %s" % uris)
for n in qdcd:
    c = svc[n]["command"]
    if "--cache-max" not in c or "--data" not in c:
        bad.append(n + ": --data and --cache-max")
    vols = [v.split(":")[0] for v in svc[n].get("volumes", [])]
    if len(vols) != 1:
        bad.append(n + ": one volume of its own")
cache_vols = [svc[n]["volumes"][0].split(":")[0] for n in qdcd]
if len(set(cache_vols)) != 3:
    bad.append("each replica its own cache volume")
pub = {n: s["ports"] for n, s in svc.items() if s.get("ports")}
if len(pub) != 1 or not all(p.startswith("127.0.0.1:") for ps in pub.values() for p in ps):
    bad.append("one service publishes one loopback port: %s" % pub)
lb = list(pub)[0] if pub else None
if lb and sorted(h.split(":")[0] for h in svc[lb]["environment"]["QDC_BACKENDS"].split()) != sorted(qdcd):
    bad.append("the balancer's backends are the replicas")
for n, s in svc.items():
    b = s.get("build")
    if not b:
        bad.append(n + ": built here")
        continue
    df = os.path.normpath(os.path.join(os.path.dirname(path), b["context"], b["dockerfile"]))
    stages = set()
    for line in open(df):
        m = re.match(r"FROM\s+(\S+)(?:\s+AS\s+(\S+))?", line)
        if m:
            if m.group(1) != "debian:bookworm-slim" and m.group(1) not in stages:
                bad.append(n + ": FROM " + m.group(1))
            if m.group(2):
                stages.add(m.group(2))
pg = [n for n, s in svc.items() if "postgres" in s["build"]["dockerfile"]]
if not pg or any(svc[n].get("depends_on", {}).get(pg[0], {}).get("condition") != "service_healthy" for n in qdcd):
    bad.append("replicas wait for a healthy postgres")
print("; ".join(bad))
sys.exit(1 if bad else 0)
PYEOF
); then
    pass "compose.yaml: postgres + 3 replicas ($(grep -c '^  qdcd[0-9]:' "$ROOT/docker/compose.yaml") services on one postgresql:// store, own cache volumes, --cache-max) behind one loopback port, every image from debian:bookworm-slim"
else
    fail "compose.yaml structure" "$out"
fi

# 3. the build stage on exactly what it copies (COPY lines of the build stage)
mkdir -p "$TMP/ctx"
(cd "$ROOT" && git ls-files -co --exclude-standard) > "$TMP/files"
sed -n '/ AS build$/,/^FROM /p' "$DF" | awk '$1 == "COPY" && $2 !~ /^--/ { for (i = 2; i < NF; i++) print $i }' |
    while read -r src; do
        grep -E "^$src(/|$)" "$TMP/files" | while read -r f; do
            [ -f "$ROOT/$f" ] || continue
            mkdir -p "$TMP/ctx/$(dirname "$f")" && cp "$ROOT/$f" "$TMP/ctx/$f"
        done
    done
# (-O0: this checks the file set, not the code, and compiles 3x faster)
cmd=$(sed -n '/ AS build$/,/^FROM /p' "$DF" | grep '^RUN make' | sed 's/^RUN //; s/-j"$(nproc)"/-j2/')
if (cd "$TMP/ctx" && sh scripts/deps.sh --check > /dev/null && eval "$cmd OPTFLAGS=-O0" > "$TMP/make.log" 2>&1) &&
    [ -x "$TMP/ctx/build/rel/qdcd" ] && [ -x "$TMP/ctx/build/rel/qdc" ]; then
    pass "build stage: '$cmd' succeeds on the copied files alone"
else
    fail "build stage" "$(tail -3 "$TMP/make.log")"
fi

# 4. the runtime stage installs the package of every library qdcd/qdc need
pkgs=$(sed -n '/ AS runtime$/,$p' "$DF" | sed -n '/apt-get install/,/rm -rf/p')
missing=
for lib in $(readelf -d "$TMP/ctx/build/rel/qdcd" "$TMP/ctx/build/rel/qdc" 2> /dev/null | sed -n 's/.*NEEDED.*\[\(.*\)\]/\1/p' | sort -u); do
    path=$(ldd "$TMP/ctx/build/rel/qdcd" "$TMP/ctx/build/rel/qdc" | awk -v l="$lib" '$1 == l { print $3; exit }')
    pkg=$(dpkg -S "$(readlink -f "$path")" 2> /dev/null | head -1 | cut -d: -f1)
    [ -n "$pkg" ] || pkg=$(dpkg -S "$path" 2> /dev/null | head -1 | cut -d: -f1)
    case $pkg in libc6 | libgcc-s1 | libstdc++6 | zlib1g) continue ;; esac # in bookworm-slim
    printf '%s\n' "$pkgs" | grep -qw -- "$pkg" || missing="$missing $lib($pkg)"
done
[ -z "$missing" ] && pass "runtime stage installs every shared library the binaries link" ||
    fail "runtime libraries" "not installed:$missing"

# 5. the entrypoint execs qdcd (PID 1 gets SIGTERM) with or without tokens
QDCD=$TMP/ctx/build/rel/qdcd QDC_TOKENS_FILE=$TMP/none sh "$EP" --listen 127.0.0.1:0 --port-file "$TMP/port" --data "$TMP/data" 2> "$TMP/ep.log" &
EPID=$!
i=0
while [ $i -lt 600 ] && ! [ -s "$TMP/port" ]; do sleep 0.1; i=$((i + 1)); done
URL=http://127.0.0.1:$(cat "$TMP/port" 2> /dev/null)
live=$(curl -s -m 5 -o /dev/null -w '%{http_code}' "$URL/livez")
comm=$(cat "/proc/$EPID/comm" 2> /dev/null)
kill -TERM "$EPID" 2> /dev/null
t0=$(date +%s)
wait "$EPID"
rc=$?
if [ "$live" = 200 ] && [ "$comm" = qdcd ] && [ $rc = 0 ] && [ $(($(date +%s) - t0)) -le 12 ] && grep -q 'API open' "$TMP/ep.log"; then
    pass "entrypoint: execs qdcd (pid $EPID is qdcd), /livez 200, SIGTERM -> exit 0"
else
    fail "entrypoint" "livez $live comm '$comm' rc $rc: $(tail -2 "$TMP/ep.log")"
fi
"$TMP/ctx/build/rel/qdcd" --hash-token tok > "$TMP/tokens"
rm -f "$TMP/port"
QDCD=$TMP/ctx/build/rel/qdcd QDC_TOKENS_FILE=$TMP/tokens sh "$EP" --listen 127.0.0.1:0 --port-file "$TMP/port" --data "$TMP/data" 2> "$TMP/ep2.log" &
EPID=$!
i=0
while [ $i -lt 600 ] && ! [ -s "$TMP/port" ]; do sleep 0.1; i=$((i + 1)); done
URL=http://127.0.0.1:$(cat "$TMP/port" 2> /dev/null)
c1=$(curl -s -o /dev/null -w '%{http_code}' "$URL/v1/jobs")
c2=$(curl -s -o /dev/null -w '%{http_code}' -H 'Authorization: Bearer tok' "$URL/v1/jobs")
kill -TERM "$EPID" 2> /dev/null
wait "$EPID"
[ "$c1$c2" = 401200 ] && pass "entrypoint with a tokens secret: 401 without the token, 200 with it" ||
    fail "entrypoint tokens" "$c1 $c2 $(tail -2 "$TMP/ep2.log")"
exit 0
