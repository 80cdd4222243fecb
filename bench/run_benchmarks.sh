#!/usr/bin/env bash
# Runs the throughput benchmarks of bench/RESULTS.md (issue 13's ceiling): every scene with its
# reference camera (../shared/meshes/README.md) and procedural scenes of 100k to 40M triangles
# at 1920x1080, the frame loop beside the bare rtcIntersect16 baseline (a minimal float pinhole
# in the same loop) frame by frame in turn, for two AOV sets. Writes
# bench/results/<scene>-<aovs>.json and prints a Markdown table.
# Usage: bench/run_benchmarks.sh [FRAMES] (default 10); SCENES_LIST="bunny dragon" picks scenes,
# AOVSETS="depth,normal" the AOV sets, BUILDS the timed builds (default 3).
set -euo pipefail
cd "$(dirname "$0")/.."
B=build/apps/aperture
FRAMES=${1:-10}
OUT=bench/results
mkdir -p "$OUT"
# shellcheck source=bench/reference_scenes.sh
source bench/reference_scenes.sh
read -r -a ORDER <<<"${SCENES_LIST:-bunny dragon crown bathroom procedural100k procedural1M procedural10M procedural40M}"
read -r -a AOVS <<<"${AOVSETS:-depth,normal color}"
for scene in "${ORDER[@]}"; do
  for aovs in "${AOVS[@]}"; do
    # shellcheck disable=SC2086
    $B bench --quiet ${SCENES[$scene]} --size 1920,1080 --aov "$aovs" --baseline \
      --frames "$FRAMES" --warmup 3 --builds "${BUILDS:-3}" \
      --json "$OUT/$scene-${aovs/,/-}.json" >/dev/null
  done
done
python3 - "$OUT" "${AOVS[*]}" "${ORDER[@]}" <<'PY'
import json, sys
out, aovsets, scenes = sys.argv[1], sys.argv[2].split(), sys.argv[3:]
print("| scene | triangles | AOVs | aperture Mrays/s (median) | cv | bare rtcIntersect16 Mrays/s | ratio | build s (median of 3) | Embree B/tri | load MB/s |")
print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|")
for s in scenes:
    for a in (a.replace(",", "-") for a in aovsets):
        j = json.load(open(f"{out}/{s}-{a}.json"))
        c = j["config"]
        print(f"| {s} | {c['triangles']:,} | {c['aovs']} | {j['mrays_per_s_median']:.1f} | "
              f"{100*j['mrays_per_s']['cv']:.1f}% | {j['baseline_mrays_per_s_median']:.1f} | "
              f"{j['render_over_baseline']:.3f} | {j['build_seconds_median']:.3f} | "
              f"{j['embree_bytes_per_triangle']:.1f} | {j['load_mb_per_s']:.0f} |")
PY
