#!/bin/sh
# qdc-batch.sh - optimize every mesh of a folder through qdcd with plain curl.
#
# usage: qdc-batch.sh [options] DIR
#   -s URL     server (default $QDC_SERVER, else http://127.0.0.1:8080)
#   -t TOKEN   bearer token (default $QDC_TOKEN)
#   -j N       jobs submitted and followed at once (default 4)
#   -o OUTDIR  results, reports and summary.csv (default ./qdc-out; not DIR)
#   -f FORMAT  result format: same (the default: each mesh's own format, the
#              file written back with only its coordinates replaced), or one
#              the server writes (GET /v1/formats: "result": true)
#   -q QUERY   optimizer options as a query string, e.g. 'max_iter=20&boundary=fixed'
#   -l LABEL   a label for every job of the run (each job also gets its file's name)
#   -Q         quiet: no progress lines
#
# Meshes: DIR/* with the extension of a format the server reads (its format
# table, GET /v1/formats: *.mesh, *.msh, *.vtu, *.inp...), each may be gzipped
# (.gz). Each one is submitted as it is with an Idempotency-Key (so curl's
# retries on 429/503, which honor Retry-After, never make a second job),
# followed by long-poll (one progress line per iteration on stderr), and its
# result and report are downloaded into OUTDIR. OUTDIR/summary.csv gets one
# row per mesh, in file order. jq is used when present (QDC_BATCH_JQ=0: never),
# else sed.
# Exit status: 0 when every job succeeded, 1 otherwise, 2 on a bad command line.
set -u

SERVER=${QDC_SERVER:-http://127.0.0.1:8080}
TOKEN=${QDC_TOKEN:-}
PAR=4
OUT=./qdc-out
FORMAT=same
QUERY=
QUIET=
LABEL=
WAIT=30

usage() { sed -n '3,14s/^# \{0,1\}//p' "$0" >&2; exit 2; }

while getopts s:t:j:o:f:q:l:Qh opt; do
    case $opt in
    s) SERVER=$OPTARG ;;
    t) TOKEN=$OPTARG ;;
    j) PAR=$OPTARG ;;
    o) OUT=$OPTARG ;;
    f) FORMAT=$OPTARG ;;
    q) QUERY=$OPTARG ;;
    l) LABEL=$OPTARG ;;
    Q) QUIET=1 ;;
    *) usage ;;
    esac
done
shift $((OPTIND - 1))
if [ $# -ne 1 ] || [ ! -d "$1" ]; then usage; fi
DIR=$1
SERVER=${SERVER%/}
case $PAR in '' | *[!0-9]* | 0) echo "qdc-batch: -j needs a positive count" >&2; exit 2 ;; esac
mkdir -p "$OUT" || exit 2
if [ "$(cd "$DIR" && pwd -P)" = "$(cd "$OUT" && pwd -P)" ]; then
    echo "qdc-batch: OUTDIR must not be DIR (results would overwrite inputs)" >&2
    exit 2
fi
HAVE_JQ=
[ "${QDC_BATCH_JQ:-1}" != 0 ] && command -v jq > /dev/null 2>&1 && HAVE_JQ=1
WORK=$(mktemp -d "${TMPDIR:-/tmp}/qdc-batch.XXXXXX") || exit 2
trap 'rm -rf "$WORK"' EXIT
trap 'exit 130' INT TERM
RUN=$(date +%s)-$$

# curl with the token and retries: 429 and 503 (Retry-After honored), 5xx,
# refused connections and timeouts.
qcurl() {
    if [ -n "$TOKEN" ]; then
        curl -sS --retry 8 --retry-connrefused --retry-max-time 600 \
            -H "Authorization: Bearer $TOKEN" "$@"
    else
        curl -sS --retry 8 --retry-connrefused --retry-max-time 600 "$@"
    fi
}

# urlenc TEXT: every byte as %XX (a query value of any bytes)
urlenc() { printf '%s' "$1" | od -An -tx1 -v | tr -d ' \n' | sed 's/../%&/g'; }

# field FILE KEY [OBJECT]: a string or number member of a one-line JSON reply;
# with OBJECT, inside the object member OBJECT (one without nested objects).
field() {
    if [ -n "$HAVE_JQ" ]; then
        jq -r "(${3:+.$3 | }.$2) // empty | tostring" "$1" 2> /dev/null
        return
    fi
    if [ -n "${3:-}" ]; then
        sed -n "s/.*\"$3\":{\([^}]*\)}.*/{\1}/p" "$1"
    else
        cat "$1"
    fi | sed -n "s/.*[{,]\"$2\":\"\{0,1\}\([^\",}]*\)\"\{0,1\}[,}].*/\1/p" | head -n 1
}

log() { [ -n "$QUIET" ] || printf '%s\n' "$*" >&2; }

# The server's format table, one format a line: name extension media-type
# (- for none) upload result (1/0), in the table's order.
code=$(qcurl -o "$WORK/formats.json" -w '%{http_code}' "$SERVER/v1/formats") || code=000
if [ "$code" != 200 ]; then
    echo "qdc-batch: cannot read the server's formats (GET /v1/formats: HTTP $code)" >&2
    exit 1
fi
if [ -n "$HAVE_JQ" ]; then
    jq -r '.formats[] | [.name, .extension, (.media_type // "-"),
        (if .upload then 1 else 0 end), (if .result then 1 else 0 end)] | join(" ")' \
        "$WORK/formats.json"
else
    tr -d '\n' < "$WORK/formats.json" | sed 's/"surfaces":.*//; s/},{/}\
{/g' | while IFS= read -r l; do
        printf '%s\n' "$l" > "$WORK/f1"
        m=$(field "$WORK/f1" media_type)
        up=$(field "$WORK/f1" upload)
        res=$(field "$WORK/f1" result)
        printf '%s %s %s %s %s\n' "$(field "$WORK/f1" name)" "$(field "$WORK/f1" extension)" \
            "$([ "$m" = null ] || [ -z "$m" ] && echo - || echo "$m")" \
            "$([ "$up" = true ] && echo 1 || echo 0)" "$([ "$res" = true ] && echo 1 || echo 0)"
    done
fi > "$WORK/formats"
# ext_of FORMAT: the file extension of a format
ext_of() { awk -v f="$1" '$1 == f { print $2; exit }' "$WORK/formats"; }
# upload_of EXT: the first format read from files of extension EXT, with its
# media type: "name media" (empty if none)
upload_of() { awk -v e="$1" '$2 == e && $4 == 1 { print $1, $3; exit }' "$WORK/formats"; }
if [ "$FORMAT" != same ] && ! awk -v f="$FORMAT" '$1 == f && $5 == 1 { ok = 1 } END { exit !ok }' "$WORK/formats"; then
    echo "qdc-batch: -f same|$(awk '$5 == 1 { printf "%s%s", s, $1; s = "|" }' "$WORK/formats")" >&2
    exit 2
fi

# one FILE ROWFILE: submit, follow, download; writes the CSV row.
one() {
    f=$1
    row=$2
    name=$(basename "$f")
    base=${name%.gz}
    w=$WORK/$(printf '%s' "$name" | tr -c 'A-Za-z0-9._-' _)
    body=$f
    case $name in *.gz) gzip -dc "$f" > "$w.in" || { failed "$row" "$name" "" unreadable "gzip failed"; return; }; body=$w.in ;; esac
    # by media type, or named in the query (qdcd records a Gmsh or VTK file as
    # the variant its header says)
    named=
    up=$(upload_of "${base##*.}")
    case ${up#* } in
    -) ct=application/octet-stream named=${up%% *} ;;
    *) ct=${up#* } ;;
    esac
    ext=${base##*.}
    base=${base%.*}
    q=$QUERY${named:+${QUERY:+&}format=$named}
    q=$q${q:+&}name=$(urlenc "$name")${LABEL:+&label=$(urlenc "$LABEL")}
    t0=$(date +%s)
    code=$(qcurl -o "$w.sub" -w '%{http_code}' -X POST --data-binary "@$body" \
        -H "Content-Type: $ct" -H "Idempotency-Key: batch-$RUN-$base.$ext" \
        "$SERVER/v1/jobs${q:+?$q}") || code=000
    rm -f "$w.in"
    if [ "$code" != 202 ]; then
        why=$(field "$w.sub" detail 2> /dev/null)
        log "$name: submit failed (HTTP $code) $why"
        failed "$row" "$name" "" "rejected:$code" "$why"
        return
    fi
    id=$(field "$w.sub" id)
    fmt=$FORMAT
    rext=$(ext_of "$FORMAT")
    # same: the job's own format, the upload written back
    if [ "$FORMAT" = same ]; then
        fmt=$(field "$w.sub" format mesh)
        rext=$ext
    fi
    log "$name: job $id"
    after=-1
    state=queued
    while :; do
        code=$(qcurl -m $((WAIT + 30)) -o "$w.poll" -w '%{http_code}' \
            "$SERVER/v1/jobs/$id/progress?after=$after&wait=$WAIT") || code=000
        if [ "$code" != 200 ]; then
            log "$name: progress failed (HTTP $code)"
            state=error
            break
        fi
        state=$(field "$w.poll" state)
        n=$(field "$w.poll" next_after)
        if [ -n "$n" ] && [ "$n" != "$after" ]; then
            after=$n
            # the last record of the reply: its members are the last of each name
            log "$(sed -n 's/.*"iteration":\([0-9]*\),"phase":"\([a-z]*\)".*"mean_ratio_mean":\([^,]*\),.*"mean_ratio_min":\([^,]*\),.*"n_inverted":\([0-9]*\),.*"elapsed":\([^,]*\),.*/\2 \1 \3 \4 \5 \6/p' "$w.poll" |
                awk -v n="$name" '{ printf "%s: %-6s %3d  q mean %.4f min %+.4f  inverted %d  %.1fs", n, $1, $2, $3, $4, $5, $6 }')"
        fi
        [ "$(field "$w.poll" "done")" = true ] && break
    done
    if [ "$state" != succeeded ]; then
        why=$(qcurl "$SERVER/v1/jobs/$id" | tr -d '\n' > "$w.job"; field "$w.job" detail error)
        log "$name: job $id $state $why"
        failed "$row" "$name" "$id" "$state" "$why"
        return
    fi
    res=$OUT/$base.$rext
    rep=$OUT/$base.report.json
    c1=$(qcurl -o "$res" -w '%{http_code}' "$SERVER/v1/jobs/$id/result?format=$fmt") || c1=000
    c2=$(qcurl -o "$rep" -w '%{http_code}' "$SERVER/v1/jobs/$id/report") || c2=000
    if [ "$c1" != 200 ] || [ "$c2" != 200 ]; then
        log "$name: download failed (HTTP $c1, $c2)"
        rm -f "$res" "$rep"
        failed "$row" "$name" "$id" download-failed "HTTP $c1 $c2"
        return
    fi
    csv "$row" "$name" "$id" succeeded "$(field "$rep" n_tets after)" \
        "$(field "$rep" iterations run)" \
        "$(field "$rep" mean_ratio_mean before)" "$(field "$rep" mean_ratio_mean after)" \
        "$(field "$rep" mean_ratio_min before)" "$(field "$rep" mean_ratio_min after)" \
        "$(field "$rep" n_inverted before)" "$(field "$rep" n_inverted after)" \
        "$(field "$rep" hausdorff_rel boundary_error)" "" "$(($(date +%s) - t0))" "$res" "$rep"
    log "$name: done -> $res"
}

# csv ROWFILE FIELDS...: one CSV line, fields quoted where needed.
csv() {
    r=$1
    shift
    line=
    sep=
    for v in "$@"; do
        case $v in
        *[\",]*) v="\"$(printf '%s' "$v" | sed 's/"/""/g')\"" ;;
        esac
        line=$line$sep$v
        sep=,
    done
    printf '%s\n' "$line" > "$r"
}

# failed ROWFILE NAME JOB STATE WHY: the row of a mesh without a result.
failed() {
    csv "$1" "$2" "$3" "$4" "" "" "" "" "" "" "" "" "" "$5" "" "" ""
}

# A FIFO of PAR tokens bounds the jobs in flight (POSIX sh has no wait -n).
mkfifo "$WORK/slots" || exit 2
exec 3<> "$WORK/slots"
i=0
while [ $i -lt "$PAR" ]; do
    echo >&3
    i=$((i + 1))
done

# is_mesh FILE: a file of one of the formats above
is_mesh() {
    [ -f "$1" ] || return 1
    b=${1%.gz}
    case $b in *.*) [ -n "$(upload_of "${b##*.}")" ] ;; *) return 1 ;; esac
}
# two meshes of one name (a.msh and a.vtu, a.mesh and a.mesh.gz) would write
# the same report (and result) in OUTDIR
dup=$(for f in "$DIR"/*; do
    is_mesh "$f" || continue
    b=$(basename "${f%.gz}")
    printf '%s\n' "${b%.*}"
done | sort | uniq -d | head -n 1)
if [ -n "$dup" ]; then
    echo "qdc-batch: two meshes in $DIR are named $dup: their results would overwrite each other in $OUT; rename one" >&2
    exit 2
fi

n=0
for f in "$DIR"/*; do
    is_mesh "$f" || continue
    n=$((n + 1))
    read -r _ <&3
    (
        trap 'echo >&3' EXIT
        one "$f" "$WORK/row.$(printf '%06d' $n)"
    ) &
done
wait
exec 3>&-
if [ $n -eq 0 ]; then
    echo "qdc-batch: no mesh in $DIR (*.$(awk '$4 == 1 && !s[$2]++ { printf "%s%s", t, $2; t = ", *." }' "$WORK/formats"), optionally .gz)" >&2
    exit 1
fi

SUMMARY=$OUT/summary.csv
{
    echo "file,job,state,tets,iterations,q_mean_before,q_mean_after,q_min_before,q_min_after,inverted_before,inverted_after,hausdorff_rel,error,seconds,result,report"
    cat "$WORK"/row.*
} > "$SUMMARY"
ok=$(grep -c '^[^,]*,[^,]*,succeeded,' "$SUMMARY")
echo "qdc-batch: $ok of $n succeeded; summary in $SUMMARY" >&2
[ "$ok" -eq "$n" ]
