#!/usr/bin/env bash
# Issue 12 item 5: the two layered-hit methods (core/engine/layers.h), interleaved, on the dragon and
# the bunny for K = 1, 2, 4, 8: "filter" (one traversal with a context filter keeping the K
# nearest hits) against "retrace" (K traversals, tnear moved past the previous hit). Mrays/s
# counts primary rays (pixels), so the two methods' figures compare directly; K = 1 shows the
# cost of the filter-capable scene alone. The winner becomes the default in
# defaultLayerMethod (core/engine/layers.cpp). Run on an idle machine:
#   bash bench/layers_methods.sh           (ROUNDS=3, FRAMES=5 by default; FRAMES=1 ROUNDS=1 to smoke-test)
set -euo pipefail
BIN=${BIN:-build/apps/aperture}
M=${M:-../shared/meshes/stanford}
out=${OUT:-/tmp/layers_methods}; mkdir -p "$out"; rm -f "$out"/*.json
declare -A VIEW=(
  [dragon]="--mesh $M/dragon_vrip.ply --eye 0,0.12,0.45 --at 0,0.12,0"
  [bunny]="--mesh $M/bun_zipper.ply --eye -0.02,0.11,0.25 --at -0.02,0.11,0"
)
for round in $(seq 1 "${ROUNDS:-3}"); do
  for mesh in dragon bunny; do
    for k in 1 2 4 8; do
      for method in filter retrace; do
        $BIN bench ${VIEW[$mesh]} --fov 30 --size 1280,720 --aov depth --layers "$k" \
          --layers-method "$method" --frames "${FRAMES:-5}" --warmup 1 --builds 1 --quiet \
          --json "$out/$mesh-$k-$method-$round.json" >/dev/null
      done
    done
  done
done
python3 - "$out" <<'PY'
import glob, json, statistics, sys
print("| mesh | K | filter Mrays/s | retrace Mrays/s | filter / retrace |")
print("|---|---|---|---|---|")
for mesh in ["dragon", "bunny"]:
    for k in [1, 2, 4, 8]:
        med = {}
        for method in ["filter", "retrace"]:
            files = sorted(glob.glob(f"{sys.argv[1]}/{mesh}-{k}-{method}-*.json"))
            med[method] = statistics.median(json.load(open(f))["mrays_per_s_median"] for f in files)
        print(f"| {mesh} | {k} | {med['filter']:.1f} | {med['retrace']:.1f} | "
              f"{med['filter'] / med['retrace']:.2f} |")
PY
