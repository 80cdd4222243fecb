#!/usr/bin/env bash
# Issue 13, item 4: mesh loading speed of two builds side by side in one run. Each round loads
# every file once with each binary (alternating, a fresh process each time, file in page
# cache after the first round), and the table gives the median MB/s of the rounds (file bytes
# over the loader's wall time, as `aperture bench` prints it) and the ratio.
# The host's share of each CPU (bench/host_steal.py, 2 s) is printed before and after the
# rounds: a load of a few milliseconds that meets one of its gaps is slower by all of it.
#   BEFORE=/tmp/before/build/apps/aperture bash bench/load_before_after.sh
#   (AFTER=build/apps/aperture ROUNDS=5 by default; SHARED=../shared)
set -euo pipefail
: "${BEFORE:?BEFORE=path of the aperture binary to compare with}"
AFTER=${AFTER:-build/apps/aperture}
meshes=${SHARED:-../shared}/meshes
files=("$meshes/scenes/crown_flat.ply" "$meshes/scenes/contemporary-bathroom_flat.ply"
  "$meshes/stanford/dragon_vrip.ply" "$meshes/obj/stanford-bunny.obj")
out=${OUT:-/tmp/load_before_after}
rm -rf "$out"
mkdir -p "$out"
for f in "${files[@]}"; do cat "$f" >/dev/null; done  # page cache
steal=$(dirname "$0")/host_steal.py
echo "host before the rounds:"
python3 "$steal" 2
for round in $(seq 0 "${ROUNDS:-5}"); do  # round 0 is a warm-up, not counted
  for f in "${files[@]}"; do
    for side in before after; do
      bin=$BEFORE
      [ "$side" = after ] && bin=$AFTER
      "$bin" bench --mesh "$f" --frames 1 --warmup 0 --builds 1 --size 64,64 \
        --json "$out/$side-$round-$(basename "$f").json" >/dev/null 2>&1
    done
  done
done
echo "host after the rounds:"
python3 "$steal" 2
python3 - "$out" <<'PY'
import glob, json, statistics, sys
rows = {}
for f in glob.glob(f'{sys.argv[1]}/*.json'):
    side, rnd, name = f.rsplit('/', 1)[1][:-5].split('-', 2)
    if rnd == '0':
        continue
    rows.setdefault(name, {}).setdefault(side, []).append(json.load(open(f))['load_mb_per_s'])
print('| file | before MB/s (median) | after MB/s (median) | after / before | after, every round |')
print('|---|---:|---:|---:|---|')
for name, d in sorted(rows.items()):
    b, a = statistics.median(d['before']), statistics.median(d['after'])
    print(f'| {name} | {b:.0f} | {a:.0f} | {a / b:.2f} | {", ".join(f"{x:.0f}" for x in d["after"])} |')
PY
