#!/bin/sh
# tests/house/commitmsg.sh - the commit-msg hook (scripts/commit-msg) takes a
# subject of at most 72 characters followed by a blank line and refuses a
# longer or an empty one; `make hooks` installs it in a git checkout and does
# nothing (and does not fail) without one.
. "$(dirname "$0")/../lib.sh"
HOOK=$ROOT/scripts/commit-msg
# msg NAME TEXT: a message file
msg() { printf '%s' "$2" > "$TMP/$1"; echo "$TMP/$1"; }
s72=$(printf '%072d' 0 | tr 0 a)
s73=${s72}b
expect() { # NAME WANT(0|1) FILE
    sh "$HOOK" "$3" 2> "$TMP/err"
    rc=$?
    if [ "$2" = 0 ] && [ $rc = 0 ]; then pass "commit-msg: $1 accepted"
    elif [ "$2" = 1 ] && [ $rc != 0 ] && [ -s "$TMP/err" ]; then pass "commit-msg: $1 refused"
    else fail "commit-msg: $1" "exit $rc, wanted $( [ "$2" = 0 ] && echo 0 || echo non-zero): $(cat "$TMP/err")"
    fi
}
expect "a short subject and a body" 0 "$(msg good "Split finish.c by pass

The details, with figures, go here; body lines may be as long as they need to be, longer than 72.
")"
expect "a subject of exactly 72 characters" 0 "$(msg s72 "$s72
")"
expect "a subject with git's comment lines after it" 0 "$(msg comments "Fix the route table

# Please enter the commit message for your changes.
")"
expect "a subject of 73 characters" 1 "$(msg s73 "$s73
")"
expect "an empty message" 1 "$(msg empty "")"
expect "a message of comments and blanks only" 1 "$(msg blank "
# nothing

")"
expect "a body without the blank line" 1 "$(msg noblank "Subject
body right under it
")"

# make hooks: a fresh git repository gets the hook; a directory without .git
# is left alone and make still succeeds.
if command -v git > /dev/null; then
    mkdir -p "$TMP/repo/scripts" "$TMP/tar/scripts"
    for d in repo tar; do
        cp "$ROOT/Makefile" "$TMP/$d/" && cp "$HOOK" "$TMP/$d/scripts/"
    done
    (cd "$TMP/repo" && git init -q . && make -s hooks > /dev/null 2>&1)
    if cmp -s "$HOOK" "$TMP/repo/.git/hooks/commit-msg" && [ -x "$TMP/repo/.git/hooks/commit-msg" ]; then
        pass "make hooks: installed in a git checkout"
    else
        fail "make hooks" "no executable .git/hooks/commit-msg in a fresh repository"
    fi
    if (cd "$TMP/tar" && GIT_CEILING_DIRECTORIES=$TMP make -s hooks > "$TMP/tar.log" 2>&1); then
        pass "make hooks: nothing to do without .git"
    else
        fail "make hooks" "failed without .git: $(tail -2 "$TMP/tar.log")"
    fi
else
    echo "ok - make hooks # SKIP no git"
fi
[ $NFAIL = 0 ]
