#!/usr/bin/env bash
# Quick start (b): install missing Debian packages and .venv, build (with the Python module,
# built once in the CMake tree), and run the whole test suite through CTest: GoogleTest, the
# format check and the pytest suite (tests/python). Tests that need ../shared/meshes skip
# with a message when it is absent. Then checks that `pip install .` itself works, into .venv.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/venv.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DAPERTURE_WERROR=ON \
  -DAPERTURE_PYTHON=ON -DPython_EXECUTABLE="$PWD/.venv/bin/python" \
  -DCMAKE_CXX_COMPILER_LAUNCHER=ccache
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)" "$@"

# `pip install .` (scikit-build-core, the extension target only) into .venv, then a render
# through the installed module. Its compile commands are the CMake build's (its compiler by the
# same name, -Werror too), so ccache serves its objects from that build: on 2 cores it took
# 95 s from a clean clone without ccache. APERTURE_PIP_CHECK=0 skips it.
if [[ "${APERTURE_PIP_CHECK:-1}" != 0 ]]; then
  t0=$SECONDS
  compiler=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' build/CMakeCache.txt)
  CMAKE_BUILD_PARALLEL_LEVEL="$(nproc)" .venv/bin/python -m pip install -q \
    --disable-pip-version-check --no-build-isolation \
    --config-settings=cmake.define.CMAKE_CXX_COMPILER="$compiler" \
    --config-settings=cmake.define.CMAKE_CXX_COMPILER_LAUNCHER=ccache \
    --config-settings=cmake.define.APERTURE_WERROR=ON .
  (cd /tmp && "$OLDPWD/.venv/bin/python" -c '
import aperture, numpy as np
out = aperture.Scene("procedural:sphere").render(
    aperture.Camera(eye=(0, 0, 5), at=(0, 0, 0), size=(32, 32)), aovs="depth")
assert abs(out["depth"][16, 16] - 4.0) < 0.01, out["depth"][16, 16]
import os, tempfile  # a 16-bit PNG: the OpenImageIO plugin installed beside the module loads
plugin = os.path.join(os.path.dirname(aperture._aperture.__file__), "libaperture_oiio.so")
assert os.path.isfile(plugin), plugin + " is not installed"
with tempfile.TemporaryDirectory() as d:
    aperture.write(os.path.join(d, "depth.png"), out["depth"], depth_scale=1000)
    assert open(os.path.join(d, "depth.png"), "rb").read(4) == b"\x89PNG"
print("pip install . check: aperture", aperture.__version__, "from", aperture.__file__)')
  echo "pip install . check: $((SECONDS - t0)) s"
  ccache --show-stats | grep -E 'Hits|Misses' || true
fi
