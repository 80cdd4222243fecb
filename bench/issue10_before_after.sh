#!/usr/bin/env bash
# Side by side, interleaved: the binary before issue 10 (53a691b) and after, dragon reference view.
set -euo pipefail
BEFORE=${BEFORE:?path of the aperture binary built at 53a691b}
AFTER=${AFTER:-build/apps/aperture}
D=${D:-../shared/meshes/stanford/dragon_vrip.ply}
VIEW="--eye 0,0.12,0.45 --at 0,0.12,0 --up 0,1,0 --fov 30 --size 1920,1080"
out=${OUT:-/tmp/b10}; mkdir -p $out
for round in 1 2 3; do
  for cfg in "dn1:--aov depth,normal --spp 1 --baseline" "dn4:--aov depth,normal --spp 4" "cd4:--aov color,depth --spp 4"; do
    name=${cfg%%:*}; flags=${cfg#*:}
    for which in before after; do
      bin=$BEFORE; [ $which = after ] && bin=$AFTER
      $bin bench --mesh $D $VIEW $flags --frames 10 --warmup 2 --builds 1 --quiet --json $out/$name-$which-$round.json >/dev/null 2>&1 || echo "fail $name $which"
    done
  done
done
