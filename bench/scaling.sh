#!/usr/bin/env bash
# Issue 13 item 3: scaling to 1e8 triangles. `aperture bench --scaling` measures
# procedural:spheres at each size in a fresh child process (load s, build s, peak RSS in
# bytes/triangle, Embree bytes/triangle, Mrays/s of the frame loop and of the bare
# rtcIntersect16 baseline, the --max-memory estimate beside the measured peak), first with the
# default BVH, then with --compact. Writes the JSON, the Markdown table beside it (.md) and the
# plot (bench/plot.py --scaling). Needs ~12 GB free at 1e8 (the estimate says how much before
# each size runs; the 4e7 and 1e8 sizes take minutes). Run it on an idle machine.
#   bash bench/scaling.sh   (SIZES=1e5,1e6,1e7,4e7,1e8 THREADS=0 (all cores) FRAMES=10
#                            WARMUP=3 OUT=bench/results/scaling.json PYTHON=python3: one with matplotlib,
#                            e.g. the peers venv of bench/install-peers.sh)
set -euo pipefail
BIN=${BIN:-build/apps/aperture}
OUT=${OUT:-bench/results/scaling.json}
cmd=("$BIN" bench --scaling --scaling-sizes "${SIZES:-1e5,1e6,1e7,4e7,1e8}" --compact
     --threads "${THREADS:-0}" --frames "${FRAMES:-10}" --warmup "${WARMUP:-3}" --json "$OUT")
mkdir -p "$(dirname "$OUT")"
echo "command: ${cmd[*]}"
echo "date: $(date -u +%Y-%m-%dT%H:%MZ); CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-)"
"${cmd[@]}"
"${PYTHON:-python3}" bench/plot.py --scaling "$OUT" -o "${PLOT:-bench/plots/scaling.png}"
