#!/bin/sh
# faults/options.sh - options the optimizer would reject are refused at
# submit time (400 problem+json naming the valid values), not accepted with
# a 202 and failed later: mu=0, eps_rel=0, mu=1e-400 (underflows to 0),
# max_iter=%205 (a leading space) and max_iter=5%00abc (a NUL byte) were all
# taken before; a valid set of the same options is accepted.
. "$(dirname "$0")/../lib.sh"
. "$ROOT/tests/server/daemon.inc"
start_qdcd "$TMP/d" --workers 1 || { fail "options: start qdcd" "$(tail -3 "$TMP/d.log")"; exit 1; }
CUBE=$ROOT/tests/data/sample/cube.mesh
for q in mu=0 eps_rel=0 mu=1e-400 "max_iter=%205" "max_iter=5%00abc" "max_iter=5.0" \
    "finish_frac=nan" "hausd=-1" "hausd=rel:" "metric=MIVL" "time_limit=inf" \
    "topology=twist"; do
    code=$(submit "$CUBE" model/x-medit "$q" "$TMP/o")
    ct=$(hdr "$TMP/o" Content-Type)
    detail=$(jf "$TMP/o" .detail 2> /dev/null)
    case $code:$ct:$detail in
    400:application/problem+json*:*option*)
        pass "options: $q -> 400: $detail" ;;
    *) fail "options: $q" "$code $ct $(head -c 200 "$TMP/o")" ;;
    esac
done
code=$(submit "$CUBE" model/x-medit "mu=0.5&eps_rel=1e-3&max_iter=3&hausd=rel:1e-3&finish=off&topology=none" "$TMP/ok")
id=$(jf "$TMP/ok" .id)
st=$(poll_all "$id")
req GET "/v1/jobs/$id/report" "$TMP/rep" > /dev/null
hb=$(jf "$TMP/rep" .run.hausd_bound)
[ "$code" = 202 ] && [ "$st" = succeeded ] && [ "$hb" != 0 ] && [ "$hb" != null ] &&
    pass "options: a valid set (mu=0.5, hausd=rel:1e-3, ...) -> 202, succeeded, report's hausd_bound $hb" ||
    fail "options: valid set" "$code $st hausd_bound $hb"
stop_qdcd || fail "options: stop" "exit $?"
exit 0
