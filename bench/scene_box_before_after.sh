#!/usr/bin/env bash
# Issue 13, item 2: the frame loop against bare rtcIntersect16 (`bench --baseline`) with and
# without a way of resolving misses without Embree: the scene-box test (core/engine/scene_box.h, rays
# that miss the scene's box; OFF_FLAG=--no-scene-box, the default) or the coverage mask
# (core/engine/coverage_mask.h, blocks that see no occupied cell; OFF_FLAG=--no-coverage-mask), on the
# scenes of bench/run_benchmarks.sh at their reference cameras. Three variants, run in turn
# for each scene, ROUNDS times:
#   before:  the BEFORE binary (a build without it);
#   off:     this build with OFF_FLAG (OFF_FLAG=none: no such run, two builds side by side);
#   on:      this build as it is.
# Prints the CPU model and the date, then a Markdown table: per scene and variant the median
# over rounds of the frame loop's Mrays/s, of bare Embree's, and of the ratio (each run's ratio
# is itself the median of its per-frame pairs; each round's in brackets), and the share of rays
# resolved without Embree.
#   git worktree add /tmp/before <commit> && (build apps/aperture there)
#   BEFORE=/tmp/before/build/apps/aperture bash bench/scene_box_before_after.sh
#   (AFTER=build/apps/aperture OFF_FLAG=--no-scene-box ROUNDS=2 FRAMES=10 THREADS=2
#    AOVS=depth,normal SCENES_LIST=...)
set -euo pipefail
cd "$(dirname "$0")/.."
: "${BEFORE:?BEFORE=path of the aperture binary to compare with}"
AFTER=${AFTER:-build/apps/aperture}
# shellcheck source=bench/reference_scenes.sh
source bench/reference_scenes.sh
read -r -a ORDER <<<"${SCENES_LIST:-bunny dragon crown bathroom procedural100k procedural1M procedural10M procedural40M}"
out=${OUT:-/tmp/scene_box_before_after}
rm -rf "$out"
mkdir -p "$out"
common=(--size 1920,1080 --aov "${AOVS:-depth,normal}" --baseline --frames "${FRAMES:-10}"
        --warmup 3 --builds 1 --quiet --threads "${THREADS:-2}")
for scene in "${ORDER[@]}"; do
  for round in $(seq 1 "${ROUNDS:-2}"); do
    # shellcheck disable=SC2086 # the scene flags are words
    "$BEFORE" bench ${SCENES[$scene]} "${common[@]}" --json "$out/$scene+before+$round.json" >/dev/null
    if [ "${OFF_FLAG:-}" != none ]; then
      # shellcheck disable=SC2086
      "$AFTER" bench ${SCENES[$scene]} "${common[@]}" "${OFF_FLAG:---no-scene-box}" \
        --json "$out/$scene+off+$round.json" >/dev/null
    fi
    # shellcheck disable=SC2086
    "$AFTER" bench ${SCENES[$scene]} "${common[@]}" --json "$out/$scene+on+$round.json" >/dev/null
  done
done
echo "CPU: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; $(date -u '+%Y-%m-%d %H:%M UTC')"
echo "AOVs ${AOVS:-depth,normal}, ${THREADS:-2} threads, ${ROUNDS:-2} rounds"
echo
python3 - "$out" "${ORDER[@]}" <<'PY'
import glob, json, statistics, sys
out, order = sys.argv[1], sys.argv[2:]
runs = {}
for f in glob.glob(f'{out}/*.json'):
    scene, variant, _ = f.rsplit('/', 1)[1][:-5].split('+')
    runs.setdefault((scene, variant), []).append(json.load(open(f)))
med = lambda rs, key: statistics.median(r.get(key, 0.0) for r in rs)
variants = [v for v in ('before', 'off', 'on') if any(k[1] == v for k in runs)]
print('| scene | ' + ' | '.join(f'{v}: Mrays/s | bare | ratio' for v in variants) +
      ' | rays resolved without Embree (on) |')
print('|---|' + '---:|' * (3 * len(variants) + 1))
for scene in order:
    cells = []
    for variant in variants:
        rs = runs[(scene, variant)]
        rounds = ', '.join(f"{r['render_over_baseline']:.3f}" for r in rs)
        cells += [f"{med(rs, 'mrays_per_s_median'):.1f}", f"{med(rs, 'baseline_mrays_per_s_median'):.1f}",
                  f"{med(rs, 'render_over_baseline'):.3f} ({rounds})"]
    share = med(runs[(scene, 'on')], 'rays_outside_box_fraction')
    print(f"| {scene} | {' | '.join(cells)} | {100 * share:.1f} % |")
PY
