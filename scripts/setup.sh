#!/usr/bin/env bash
# Quick start (a): install missing Debian packages, configure, build (Release), and render the
# default procedural scene to out/default.exr with a PNG preview beside it.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
./build/apps/aperture render --out out/default.exr --preview out/default.png
