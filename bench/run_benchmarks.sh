#!/usr/bin/env bash
# Runs the throughput benchmarks of bench/RESULTS.md: every scene with its reference camera
# (../shared/meshes/README.md) at 1920x1080, the frame loop beside the bare rtcIntersect16
# baseline in the same run, for two AOV sets. Writes bench/results/<scene>-<aovs>.json and
# prints a Markdown table. Usage: bench/run_benchmarks.sh [FRAMES] (default 10).
set -euo pipefail
cd "$(dirname "$0")/.."
B=build/apps/aperture
M=../shared/meshes
FRAMES=${1:-10}
OUT=bench/results
mkdir -p "$OUT"
declare -A SCENES=(
  [bunny]="--mesh $M/stanford/bun_zipper.ply --eye -0.02,0.11,0.35 --at -0.017,0.11,0 --up 0,1,0 --fov 30"
  [dragon]="--mesh $M/stanford/dragon_vrip.ply --eye 0,0.12,0.45 --at 0,0.12,0 --up 0,1,0 --fov 30"
  [crown]="--mesh $M/scenes/crown_flat.ply --eye 0,5.5,24 --at 0,11,-10 --up 0,1,0 --fov 47 --fov-axis x"
  [bathroom]="--mesh $M/scenes/contemporary-bathroom_flat.ply --eye 0.00724,0.91240,-0.22758 --dir -0.751879,0.015471,-0.659119 --up 0.0116337,0.99988,0.0101985 --fov 55"
  [procedural20M]="--mesh procedural:spheres?tris=20000000"
)
ORDER=(bunny dragon crown bathroom procedural20M)
for scene in "${ORDER[@]}"; do
  for aovs in depth,normal color; do
    # shellcheck disable=SC2086
    $B bench --quiet ${SCENES[$scene]} --size 1920,1080 --aov "$aovs" --baseline \
      --frames "$FRAMES" --warmup 3 --builds 3 --json "$OUT/$scene-${aovs/,/-}.json" >/dev/null
  done
done
python3 - "$OUT" "${ORDER[@]}" <<'PY'
import json, sys
out, scenes = sys.argv[1], sys.argv[2:]
print("| scene | triangles | AOVs | aperture Mrays/s (median) | cv | bare rtcIntersect16 Mrays/s | ratio | build s (median of 3) | Embree B/tri | load MB/s |")
print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|")
for s in scenes:
    for a in ("depth-normal", "color"):
        j = json.load(open(f"{out}/{s}-{a}.json"))
        c = j["config"]
        print(f"| {s} | {c['triangles']:,} | {c['aovs']} | {j['mrays_per_s_median']:.1f} | "
              f"{100*j['mrays_per_s']['cv']:.1f}% | {j['baseline_mrays_per_s_median']:.1f} | "
              f"{j['render_over_baseline']:.3f} | {j['build_seconds_median']:.3f} | "
              f"{j['embree_bytes_per_triangle']:.1f} | {j['load_mb_per_s']:.0f} |")
PY
