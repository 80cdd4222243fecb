#!/usr/bin/env bash
# Issue 13: `bench/null_overhead.sh` for two builds side by side in one run: rounds alternate
# between the BEFORE and the AFTER binary (three rounds by default), and the table gives the
# median of the rounds' medians of each and their ratio.
#   git worktree add /tmp/before <commit> && cmake -S /tmp/before -B /tmp/before/build ... &&
#   ninja -C /tmp/before/build apps/aperture
#   BEFORE=/tmp/before/build/apps/aperture bash bench/null_before_after.sh
#   (AFTER=build/apps/aperture ROUNDS=3 FRAMES=20 THREADS=2 by default)
set -euo pipefail
: "${BEFORE:?BEFORE=path of the aperture binary to compare with}"
AFTER=${AFTER:-build/apps/aperture}
out=${OUT:-/tmp/null_before_after}
rm -rf "$out"
mkdir -p "$out"
for round in $(seq 1 "${ROUNDS:-3}"); do
  for side in before after; do
    bin=$BEFORE
    [ "$side" = after ] && bin=$AFTER
    BIN=$bin OUT="$out/$side-$round" ROUNDS=1 FRAMES=${FRAMES:-20} bash bench/null_overhead.sh \
      >"$out/$side-$round.md"
  done
done
SIZE=${SIZE:-1920,1080}
source bench/null_cameras.sh  # NULL_CAMERA_ORDER, the table's row order
python3 - "$out" <<'PY'
import glob, json, os, statistics, sys
rows = {}
for f in glob.glob(f'{sys.argv[1]}/*-*/*.json'):
    side = f.split('/')[-2].split('-')[0]
    name, aovs, _ = f.rsplit('/', 1)[1][:-5].split('+')
    rows.setdefault((name, aovs), {}).setdefault(side, []).append(
        json.load(open(f))['null_ns_per_ray_median'])
order = os.environ['NULL_CAMERA_ORDER'].split()
print('| camera | AOVs | before ns/ray | after ns/ray | after / before |')
print('|---|---|---:|---:|---:|')
for (name, aovs), d in sorted(rows.items(), key=lambda r: (order.index(r[0][0]), r[0][1])):
    b, a = statistics.median(d['before']), statistics.median(d['after'])
    print(f'| {name} | {aovs} | {b:.2f} | {a:.2f} | {a / b:.2f} |')
PY
