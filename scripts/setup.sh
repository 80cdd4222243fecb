#!/usr/bin/env bash
# Quick start (a): install missing Debian packages, configure, build (Release), render the
# default procedural scene to out/default.exr with a PNG preview beside it, and install the
# Python module into .venv (.venv/bin/python -c "import aperture").
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
./build/apps/aperture render --out out/default.exr --preview out/default.png
bash scripts/venv.sh
CMAKE_BUILD_PARALLEL_LEVEL="$(nproc)" .venv/bin/python -m pip install -q --disable-pip-version-check .
.venv/bin/python -c 'import aperture; print("aperture", aperture.__version__, "installed in .venv")'
