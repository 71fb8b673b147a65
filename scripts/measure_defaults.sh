#!/bin/sh
# scripts/measure_defaults.sh - the study behind qdc's defaults (docs/defaults.md):
# every variant of one option at a time against the defaults, on a subset of the
# dev corpus, quality from the same run's report. Prints a Markdown table.
# Usage: scripts/measure_defaults.sh [MESH...]   (default: 10 dev meshes)
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
QDC=$ROOT/build/rel/qdc
DEV=$ROOT/tests/data/dev
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
MESHES=${*:-"cube_h0.1_lowq cube_h0.1_tangled sphere_h0.1_good sphere_h0.1_noisy torus_h0.1_lowq torus_h0.1_tangled bracket_h0.1_noisy bracket_h0.1_good bunny_low_10k bunny_tangled-low_10k"}
VARIANTS="default|
metric mimr|--metric mimr
metric micn|--metric micn
harmonic on|--harmonic on
harmonic on + mu scaled|--harmonic on --mu-scaled on
weights paper|--weights paper
finish off|--finish off
finish frac 0.05|--finish-frac 0.05
finish sweeps 2|--finish-sweeps 2
finish sweeps 4|--finish-sweeps 4
angle polish off|--angle-polish off
boundary fixed|--boundary fixed
boundary slide|--boundary slide
literal (paper as written)|--mode literal --finish off"
echo "| variant | mean ratio (avg) | min mean ratio (avg) | worst min | min dihedral (avg) | inverted left | Hausdorff/diag (max) | seconds (sum) |"
echo "|---|---|---|---|---|---|---|---|"
echo "$VARIANTS" | while IFS='|' read -r name opts; do
    for m in $MESHES; do
        [ -f "$TMP/$m.mesh" ] || gzip -dc "$DEV/$m.mesh.gz" > "$TMP/$m.mesh"
        # shellcheck disable=SC2086
        OMP_NUM_THREADS=1 "$QDC" optimize "$TMP/$m.mesh" "$TMP/out.mesh" --quiet $opts \
            --report "$TMP/$m.json" >/dev/null 2>&1 || echo "{}" > "$TMP/$m.json"
    done
    /usr/bin/python3 - "$name" $MESHES "$TMP" <<'PY'
import json, sys
name, meshes, tmp = sys.argv[1], sys.argv[2:-1], sys.argv[-1]
rows = []
for m in meshes:
    try:
        rows.append(json.load(open(f"{tmp}/{m}.json")))
    except Exception:
        pass
ok = [r for r in rows if "after" in r]
if len(ok) < len(meshes):
    print(f"| {name} | failed on {len(meshes) - len(ok)} meshes | | | | | | |")
    sys.exit()
avg = lambda f: sum(f(r) for r in ok) / len(ok)
print(f"| {name} | {avg(lambda r: r['after']['mean_ratio_mean']):.4f} | "
      f"{avg(lambda r: r['after']['mean_ratio_min']):.4f} | "
      f"{min(r['after']['mean_ratio_min'] for r in ok):.4f} | "
      f"{avg(lambda r: r['after']['dihedral_min']):.2f} | "
      f"{sum(r['after']['n_inverted'] for r in ok)} | "
      f"{max(r['boundary_error']['hausdorff_rel'] for r in ok):.2e} | "
      f"{sum(r['run']['seconds']['total'] for r in ok):.1f} |")
PY
done
