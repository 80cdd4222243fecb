#!/usr/bin/env bash
# Issue 13: the instructions the frame loop and its camera execute per ray, counted by
# valgrind's callgrind (`--toggle-collect='*renderTile*'`) over one `bench --null` frame at one
# thread, for each camera of bench/null_cameras.sh. Unlike ns/ray the count is the same on
# every run, whatever else the machine does, so it compares two builds where timings drift.
# Valgrind has no AVX-512: the per-ISA kernels run their AVX2 (x86-64-v3) clones, which a CPU
# with AVX-512 never runs in a timed bench. Takes about 10 s per camera and AOV set.
#   bash bench/instruction_counts.sh   (BIN=build/apps/aperture SIZE=1920,1080
#                                       AOVS='depth,normal color' by default)
#   BEFORE=<aperture binary> bash bench/instruction_counts.sh   adds that build's counts
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-build/apps/aperture}
MESH=${MESH:-procedural:spheres?tris=100000}
SIZE=${SIZE:-1920,1080}
source bench/null_cameras.sh
command -v valgrind >/dev/null || { echo "instruction_counts: valgrind is not installed"; exit 2; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
read -r -a aovsets <<<"${AOVS:-depth,normal color}"
sides=(after)
[[ -n ${BEFORE:-} ]] && sides=(before after)
for cfg in "${NULL_CAMERAS[@]}"; do
  name=${cfg%%:*}
  flags=${cfg#*:}
  for aovs in "${aovsets[@]}"; do
    for side in "${sides[@]}"; do
      bin=$BIN
      [[ $side == before ]] && bin=$BEFORE
      # shellcheck disable=SC2086 # the flags are words
      valgrind --tool=callgrind --callgrind-out-file="$out/cg" --toggle-collect='*renderTile*' \
        "$bin" bench --null --mesh "$MESH" $POSE $flags --aov "$aovs" --threads 1 --frames 1 \
        --warmup 0 --builds 1 --quiet --json "$out/$name+$aovs+$side.json" \
        >/dev/null 2>"$out/log"
      grep -o 'refs: *[0-9,]*' "$out/log" | tr -dc '0-9' >"$out/$name+$aovs+$side.ir"
    done
  done
done
echo "instruction_counts: $(date -u '+%Y-%m-%d %H:%M UTC'); $(valgrind --version); $SIZE; one thread"
python3 - "$out" <<'PY'
import glob, json, os, sys
out = sys.argv[1]
rows = {}
for f in glob.glob(f'{out}/*.ir'):
    name, aovs, side = os.path.basename(f)[:-3].split('+')
    rays = json.load(open(f[:-3] + '.json'))['null_rays_per_frame']
    rows.setdefault((name, aovs), {})[side] = (int(open(f).read()), rays)
order = os.environ['NULL_CAMERA_ORDER'].split()
before = any('before' in d for d in rows.values())
print('| camera | AOVs | ' + ('before instructions | before / ray | ' if before else '') +
      'instructions | per ray' + (' | after / before |' if before else ' |'))
print('|---|---|' + ('---:|---:|' if before else '') + '---:|---:|' + ('---:|' if before else ''))
for (name, aovs), d in sorted(rows.items(), key=lambda r: (order.index(r[0][0]), r[0][1])):
    ir, rays = d['after']
    cells = [name, aovs]
    if before:
        b, brays = d['before']
        cells += [f'{b:,}', f'{b / brays:.1f}']
    cells += [f'{ir:,}', f'{ir / rays:.1f}']
    if before:
        cells.append(f'{ir / b:.2f}')
    print('| ' + ' | '.join(cells) + ' |')
PY
