#!/usr/bin/env bash
# Issue 13, item 2: the frame loop against bare rtcIntersect16 (`bench --baseline`) for two
# builds side by side in one run, on the reference scenes: per scene, rounds alternate between
# the BEFORE and the AFTER binary. Prints a Markdown table: per scene and build the median over
# rounds of the frame loop's Mrays/s, of bare Embree's, and of their ratio (each run's ratio is
# itself the median of its per-frame pairs), with the CPU model and the date above it.
#   git worktree add /tmp/before <commit> && (build apps/aperture there)
#   BEFORE=/tmp/before/build/apps/aperture bash bench/ceiling_before_after.sh
#   (AFTER=build/apps/aperture ROUNDS=2 FRAMES=10 THREADS=2 AOVS=depth,normal
#    SCENES_LIST="bunny dragon crown bathroom procedural100k procedural1M procedural10M")
set -euo pipefail
cd "$(dirname "$0")/.."
: "${BEFORE:?BEFORE=path of the aperture binary to compare with}"
AFTER=${AFTER:-build/apps/aperture}
# shellcheck source=bench/reference_scenes.sh
source bench/reference_scenes.sh
read -r -a ORDER <<<"${SCENES_LIST:-bunny dragon crown bathroom procedural100k procedural1M procedural10M}"
out=${OUT:-/tmp/ceiling_before_after}
rm -rf "$out"
mkdir -p "$out"
common=(--size 1920,1080 --aov "${AOVS:-depth,normal}" --baseline --frames "${FRAMES:-10}"
        --warmup 3 --builds 1 --quiet --threads "${THREADS:-2}")
for scene in "${ORDER[@]}"; do
  for round in $(seq 1 "${ROUNDS:-2}"); do
    for side in before after; do
      bin=$BEFORE
      [ "$side" = after ] && bin=$AFTER
      # shellcheck disable=SC2086
      "$bin" bench ${SCENES[$scene]} "${common[@]}" --json "$out/$scene+$side+$round.json" \
        >/dev/null
    done
  done
done
echo "CPU: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; $(date -u '+%Y-%m-%d %H:%M UTC')"
echo "AOVs ${AOVS:-depth,normal}, ${THREADS:-2} threads, ${ROUNDS:-2} alternating rounds"
echo
python3 - "$out" "${ORDER[@]}" <<'PY'
import glob, json, statistics, sys
out, order = sys.argv[1], sys.argv[2:]
runs = {}
for f in glob.glob(f'{out}/*.json'):
    scene, side, _ = f.rsplit('/', 1)[1][:-5].split('+')
    j = json.load(open(f))
    runs.setdefault((scene, side), []).append(j)
def median(scene, side, key):
    return statistics.median(r[key] for r in runs[(scene, side)])
print('| scene | before: render / bare Mrays/s | ratio | after: render / bare Mrays/s | ratio |')
print('|---|---:|---:|---:|---:|')
for s in order:
    cells = []
    for side in ('before', 'after'):
        rounds = ', '.join(f"{r['render_over_baseline']:.3f}" for r in runs[(s, side)])
        cells.append(f"{median(s, side, 'mrays_per_s_median'):.1f} / "
                     f"{median(s, side, 'baseline_mrays_per_s_median'):.1f}")
        cells.append(f"**{median(s, side, 'render_over_baseline'):.3f}** ({rounds})")
    print(f'| {s} | ' + ' | '.join(cells) + ' |')
PY
