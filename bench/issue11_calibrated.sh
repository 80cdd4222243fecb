#!/usr/bin/env bash
# Issue 11: a distorted calibrated camera against a pinhole, side by side and interleaved, on the
# dragon's reference view at 1920x1080 (vertical fov 30°: fy = 540 / tan 15°). Three cameras:
# the lecture perspective camera, the same camera as a calibrated PINHOLE, and an OPENCV lens
# (k1 −0.1, k2 0.01, p1 1e-4, p2 −1e-4) with the same K. Prints medians and ratios.
#   bash bench/issue11_calibrated.sh            (ROUNDS=5 by default)
set -euo pipefail
BIN=${BIN:-build/apps/aperture}
D=${D:-../shared/meshes/stanford/dragon_vrip.ply}
F=2015.3084396258 # 540 / tan(15°)
POSE="--eye 0,0.12,0.45 --at 0,0.12,0 --up 0,1,0 --size 1920,1080"
K="--intrinsics $F,$F,960,540"
out=${OUT:-/tmp/b11}; mkdir -p "$out"; rm -f "$out"/*.json
for round in $(seq 1 "${ROUNDS:-5}"); do
  for cfg in "perspective:--fov 30" "pinhole:$K" \
             "opencv:$K --lens-model OPENCV --distortion -0.1,0.01,1e-4,-1e-4"; do
    name=${cfg%%:*}; flags=${cfg#*:}
    $BIN bench --mesh "$D" $POSE $flags --aov depth,normal --frames 10 --warmup 2 --builds 1 \
      --quiet --json "$out/$name-$round.json" >/dev/null
  done
done
python3 - "$out" <<'PY'
import json, glob, statistics, sys
med = {}
for name in ['perspective', 'pinhole', 'opencv']:
    vals = [json.load(open(f))['mrays_per_s_median'] for f in sorted(glob.glob(f'{sys.argv[1]}/{name}-*.json'))]
    med[name] = statistics.median(vals)
    print(f"| {name} | {med[name]:.1f} | {med[name] / med['perspective']:.3f} | {[round(v, 1) for v in vals]}")
print(f"opencv / pinhole = {med['opencv'] / med['pinhole']:.3f}")
PY
