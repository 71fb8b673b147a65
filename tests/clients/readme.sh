#!/bin/sh
# readme.sh - run README.md's commands as a newcomer would paste them: every
# line of its ```sh blocks (in order, in one shell, from a directory that looks
# like the top of a clone) and every ```python block, against a qdcd on a free
# port (127.0.0.1:8080 in the text becomes that port). `make run`/`make test`
# are tested by make_run.sh and the suite itself; `docker` lines need an engine
# (docker.sh checks the image outside one). Then every mesh the commands wrote
# must be valid and every report readable, and the figures the README shows
# must be what its commands printed and wrote (tests/tools/readmefigures.py).
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"

start_qdcd "$TMP/d" --workers 2 || { fail "start" "qdcd did not come up: $(tail -3 "$TMP/d.log")"; exit 1; }
W=$TMP/w
mkdir -p "$W"
for d in build tests clients proto scripts docker; do ln -s "$ROOT/$d" "$W/$d"; done

# Split the README: sh blocks into logical lines (backslash continuations
# joined) in $TMP/lines, python blocks into $TMP/py.N.
awk -v tmp="$TMP" -v port="$PORT" '
    function sub_port(s) { gsub(/127\.0\.0\.1:8080/, "127.0.0.1:" port, s); return s }
    /^```sh$/ { lang = "sh"; next }
    /^```python$/ { lang = "py"; npy++; next }
    /^```/ { if (lang == "sh" && cont != "") { print cont > (tmp "/lines"); cont = "" } lang = ""; next }
    lang == "sh" {
        line = sub_port($0)
        if (line ~ /\\$/) { cont = cont substr(line, 1, length(line) - 1); next }
        line = cont line; cont = ""
        if (line ~ /^[ \t]*(#|$)/) next
        print line > (tmp "/lines")
    }
    lang == "py" { print sub_port($0) > (tmp "/py." npy) }
' "$ROOT/README.md"
[ -s "$TMP/lines" ] || { fail "readme" "no \`\`\`sh block found in README.md"; exit 1; }

# One script: each command in braces (state such as JOB persists), its output
# to a log, then an ok/FAIL line naming it.
{
    echo "cd '$W' || exit 1"
    echo "_r() { _l=\$(sed -n \"\$2p\" '$TMP/lines' | cut -c1-110); if [ \$1 = 0 ]; then printf 'ok - readme: %s\\n' \"\$_l\"; else printf 'FAIL - readme: %s: exit %s (%s)\\n' \"\$_l\" \$1 \"\$(tail -2 '$TMP/out.log' | tr '\\n' ' ')\"; fi; }"
    n=0
    nskip=0
    while IFS= read -r line; do
        n=$((n + 1))
        case $line in
        "make run"* | "make test"*) continue ;;
        docker\ *)
            nskip=$((nskip + 1))
            continue
            ;;
        esac
        printf '{\n%s\n} >> "%s/out.log" 2>&1 < /dev/null\n_r $? %d\n' "$line" "$TMP" "$n"
    done < "$TMP/lines"
    echo "echo 'ok - readme: $nskip docker commands not run (no Docker engine here; see docker.sh)'"
} > "$TMP/run.sh"
timeout 300 sh "$TMP/run.sh" || fail "readme run" "the README's commands did not finish (exit $?)"

# the figures shown (the README is the expectation: nothing is copied here)
$PY "$ROOT/tests/tools/readmefigures.py" "$ROOT/README.md" "$TMP/out.log" "$W" > "$TMP/fig.out" 2>&1
cat "$TMP/fig.out"
grep -q '^ok - ' "$TMP/fig.out" || fail "readme figures" "$(tail -3 "$TMP/fig.out" | tr '\n' ' ')"
NFAIL=$((NFAIL + $(grep -c '^FAIL - ' "$TMP/fig.out")))

for p in "$TMP"/py.*; do
    [ -f "$p" ] || continue
    if (cd "$W" && timeout 120 $PY "$p" > "$TMP/py.out" 2>&1); then
        pass "readme: python block $(basename "$p") ($(wc -l < "$p") lines) runs: $(tail -1 "$TMP/py.out")"
    else
        fail "readme: python block $(basename "$p")" "$(tail -3 "$TMP/py.out" | tr '\n' ' ')"
    fi
done

# what the commands wrote: the sample's 750 tets, or the bunny's
"$BIN/qdc" quality "$DEV/bunny_low_10k.mesh.gz" > "$TMP/qb" 2>&1
nbunny=$(sed -n '1s/.* \([0-9]*\) tets.*/\1/p' "$TMP/qb")
meshes=0
bad=
for f in $(cd "$W" && find . -maxdepth 2 \( -name '*.mesh' -o -name '*.qmesh' -o -name '*.json' \) ! -name '*report*' ! -path './build/*' ! -path './tests/*' | sort); do
    meshes=$((meshes + 1))
    case $f in ./bunny*) nt=$nbunny ;; *) nt=750 ;; esac
    "$BIN/qdc" quality "$W/$f" > "$TMP/q" 2>&1 && grep -q " $nt tets, 0 inverted" "$TMP/q" || bad="$bad $f"
done
[ $meshes -ge 5 ] && [ -n "$nbunny" ] && [ -z "$bad" ] && pass "readme: the $meshes meshes the commands wrote are valid, 750 tets ($nbunny for the bunny), none inverted" ||
    fail "readme meshes" "$meshes meshes; bad:$bad"
reports=0
for f in $(cd "$W" && find . -maxdepth 2 -name '*report*.json' | sort); do
    reports=$((reports + 1))
    case $f in ./bunny*) nt=$nbunny ;; *) nt=750 ;; esac
    jq -e ".after.n_tets == $nt" "$W/$f" > /dev/null || bad="$bad $f"
done
[ $reports -ge 3 ] && [ -z "$bad" ] && pass "readme: the $reports reports the commands wrote are readable" ||
    fail "readme reports" "$reports reports; bad:$bad"
stop_qdcd
exit 0
