#!/usr/bin/env bash
# Issue 13, item 2: the frame loop against bare rtcIntersect16 (`bench --baseline`) with and
# without the scene-box test (core/scene_box.h: rays that miss the scene's box are resolved as
# misses without Embree), on the scenes of bench/run_benchmarks.sh at their reference cameras.
# Three variants, run in turn for each scene, ROUNDS times:
#   before:  the BEFORE binary (a build without the test);
#   off:     this build with --no-scene-box;
#   on:      this build as it is.
# Prints a Markdown table: per scene and variant the median over rounds of the frame loop's
# Mrays/s, of bare Embree's, and of the ratio (each run's ratio is itself the median of its
# per-frame pairs), and the share of rays the test resolved.
#   git worktree add /tmp/before <commit> && (build apps/aperture there)
#   BEFORE=/tmp/before/build/apps/aperture bash bench/scene_box_before_after.sh
#   (AFTER=build/apps/aperture ROUNDS=2 FRAMES=10 THREADS=2 AOVS=depth,normal SCENES_LIST=...)
set -euo pipefail
cd "$(dirname "$0")/.."
: "${BEFORE:?BEFORE=path of the aperture binary to compare with}"
AFTER=${AFTER:-build/apps/aperture}
M=../shared/meshes
declare -A SCENES=(
  [bunny]="--mesh $M/stanford/bun_zipper.ply --eye -0.02,0.11,0.35 --at -0.017,0.11,0 --up 0,1,0 --fov 30"
  [dragon]="--mesh $M/stanford/dragon_vrip.ply --eye 0,0.12,0.45 --at 0,0.12,0 --up 0,1,0 --fov 30"
  [crown]="--mesh $M/scenes/crown_flat.ply --eye 0,5.5,24 --at 0,11,-10 --up 0,1,0 --fov 47 --fov-axis x"
  [bathroom]="--mesh $M/scenes/contemporary-bathroom_flat.ply --eye 0.00724,0.91240,-0.22758 --dir -0.751879,0.015471,-0.659119 --up 0.0116337,0.99988,0.0101985 --fov 55"
  [procedural100k]="--mesh procedural:spheres?tris=100000"
  [procedural1M]="--mesh procedural:spheres?tris=1000000"
  [procedural10M]="--mesh procedural:spheres?tris=10000000"
  [procedural40M]="--mesh procedural:spheres?tris=40000000"
)
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
    # shellcheck disable=SC2086
    "$AFTER" bench ${SCENES[$scene]} "${common[@]}" --no-scene-box \
      --json "$out/$scene+off+$round.json" >/dev/null
    # shellcheck disable=SC2086
    "$AFTER" bench ${SCENES[$scene]} "${common[@]}" --json "$out/$scene+on+$round.json" >/dev/null
  done
done
python3 - "$out" "${ORDER[@]}" <<'PY'
import glob, json, statistics, sys
out, order = sys.argv[1], sys.argv[2:]
runs = {}
for f in glob.glob(f'{out}/*.json'):
    scene, variant, _ = f.rsplit('/', 1)[1][:-5].split('+')
    runs.setdefault((scene, variant), []).append(json.load(open(f)))
med = lambda rs, key: statistics.median(r.get(key, 0.0) for r in rs)
print('| scene | before: Mrays/s | bare | ratio | off: Mrays/s | bare | ratio | on: Mrays/s | bare | ratio | rays resolved by the box |')
print('|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|')
for scene in order:
    cells = []
    for variant in ('before', 'off', 'on'):
        rs = runs[(scene, variant)]
        cells += [f"{med(rs, 'mrays_per_s_median'):.1f}", f"{med(rs, 'baseline_mrays_per_s_median'):.1f}",
                  f"{med(rs, 'render_over_baseline'):.3f}"]
    share = med(runs[(scene, 'on')], 'rays_outside_box_fraction')
    print(f"| {scene} | {' | '.join(cells)} | {100 * share:.1f} % |")
PY
