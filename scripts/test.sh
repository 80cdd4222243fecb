#!/usr/bin/env bash
# Quick start (b): install missing Debian packages and .venv, build (with the Python module,
# built once in the CMake tree), and run the whole test suite through CTest: GoogleTest, the
# format check and the pytest suite (tests/python). Tests that need ../shared/meshes skip
# with a message when it is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/venv.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DAPERTURE_WERROR=ON \
  -DAPERTURE_PYTHON=ON -DPython_EXECUTABLE="$PWD/.venv/bin/python"
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)" "$@"
