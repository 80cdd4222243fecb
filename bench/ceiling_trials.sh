#!/usr/bin/env bash
# Issue 13's trials of the ceiling itself: does Embree's coherent stream API
# (rtcIntersectNM / rtcIntersect1M with RTC_INTERSECT_CONTEXT_FLAG_COHERENT, one stream per
# tile) or the tile size move bare-Embree throughput? Same rays (the minimal float pinhole of
# the reference camera), same scene build, 1920x1080, 2 threads by default.
#   bash bench/ceiling_trials.sh   (FRAMES=10 SCENES_LIST="bunny dragon crown bathroom")
# Prints two Markdown tables: baseline Mrays/s per API, and per tile size (packet16) with the
# frame loop's ratio to it.
set -euo pipefail
cd "$(dirname "$0")/.."
B=${BIN:-build/apps/aperture}
OUT=${OUT:-/tmp/ceiling_trials}
mkdir -p "$OUT"
rm -f "$OUT"/*.json
# shellcheck source=bench/reference_scenes.sh
source bench/reference_scenes.sh
read -r -a ORDER <<<"${SCENES_LIST:-bunny dragon crown bathroom}"
common=(--size 1920,1080 --aov depth,normal --baseline --frames "${FRAMES:-10}" --warmup 3
        --builds 1 --quiet --threads "${THREADS:-2}")
for scene in "${ORDER[@]}"; do
  for api in packet16 stream-nm stream-1m; do
    # shellcheck disable=SC2086
    $B bench ${SCENES[$scene]} "${common[@]}" --baseline-api "$api" \
      --json "$OUT/api+$scene+$api.json" >/dev/null
  done
  for tile in 8 16 64; do  # 32 (the default) is the packet16 run above
    # shellcheck disable=SC2086
    $B bench ${SCENES[$scene]} "${common[@]}" --tile "$tile" \
      --json "$OUT/tile+$scene+$tile.json" >/dev/null
  done
done
python3 - "$OUT" "${ORDER[@]}" <<'PY'
import json, sys
out, scenes = sys.argv[1], sys.argv[2:]
load = lambda f: json.load(open(f"{out}/{f}.json"))
print("| scene | packet16 Mrays/s | stream-nm | stream-1m | stream-nm / packet16 | stream-1m / packet16 |")
print("|---|---:|---:|---:|---:|---:|")
for s in scenes:
    r = {a: load(f"api+{s}+{a}")["baseline_mrays_per_s_median"] for a in ("packet16", "stream-nm", "stream-1m")}
    print(f"| {s} | {r['packet16']:.1f} | {r['stream-nm']:.1f} | {r['stream-1m']:.1f} | "
          f"{r['stream-nm'] / r['packet16']:.3f} | {r['stream-1m'] / r['packet16']:.3f} |")
print()
print("| scene | tile | baseline Mrays/s | frame loop Mrays/s | frame loop / baseline |")
print("|---|---:|---:|---:|---:|")
for s in scenes:
    for t in (8, 16, 32, 64):
        j = load(f"api+{s}+packet16" if t == 32 else f"tile+{s}+{t}")
        print(f"| {s} | {t} | {j['baseline_mrays_per_s_median']:.1f} | {j['mrays_per_s_median']:.1f} | "
              f"{j['render_over_baseline']:.3f} |")
PY
