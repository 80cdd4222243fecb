#!/usr/bin/env bash
# Makes .venv, the Python environment of the Python module: nanobind and scikit-build-core to
# build it, NumPy and pytest to test it, pycolmap (COLMAP 4's own bindings) to check its
# camera models against, and trimesh to check its glTF scenes against. Quick start (a) installs
# the module into it; (b) builds it in the CMake tree with .venv's Python and runs its pytest
# suite. An up-to-date .venv is left as it is.
set -euo pipefail
cd "$(dirname "$0")/.."
if [[ ! -x .venv/bin/python ]]; then
  python3 -m venv .venv
fi
if ! .venv/bin/python -c 'import nanobind, scikit_build_core, numpy, pytest, pycolmap, trimesh' 2>/dev/null; then
  .venv/bin/python -m pip install -q --disable-pip-version-check nanobind scikit-build-core numpy pytest \
    'pycolmap>=4.2' trimesh
fi
# The LiDAR formats' own readers (tests/python/test_scan_formats.py): laspy, pypcd4 and
# ouster-sdk. ouster-sdk pins nanobind 2.9.2 among its requirements although its wheel carries
# its own compiled bindings, so the nanobind the module is built with is put back after it.
if ! .venv/bin/python -c 'import laspy, pypcd4, ouster.sdk' 2>/dev/null; then
  nanobind_version=$(.venv/bin/python -c 'import nanobind; print(nanobind.__version__)')
  .venv/bin/python -m pip install -q --disable-pip-version-check laspy pypcd4 ouster-sdk
  .venv/bin/python -m pip install -q --disable-pip-version-check "nanobind==${nanobind_version}"
fi
# The peers and clusters of issues 43 and 44: Open3D (open3d-cpu: its RaycastingScene is the
# reference the point queries and the Python render are compared with), Dask with its
# distributed scheduler and Ray (aperture.distributed's LocalCluster and ray.init tests).
# Ray publishes wheels for x86-64 Linux; where it cannot be installed its tests skip.
if ! .venv/bin/python -c 'import open3d, dask, distributed' 2>/dev/null; then
  .venv/bin/python -m pip install -q --disable-pip-version-check open3d-cpu 'dask[distributed]'
fi
# rtree and scipy: trimesh's proximity queries (closest_point, signed_distance) need them;
# bench/point_queries.py compares with them.
if ! .venv/bin/python -c 'import rtree, scipy' 2>/dev/null; then
  .venv/bin/python -m pip install -q --disable-pip-version-check rtree scipy
fi
if ! .venv/bin/python -c 'import ray' 2>/dev/null; then
  .venv/bin/python -m pip install -q --disable-pip-version-check 'ray[data]' ||
    echo "venv: ray could not be installed; the Ray tests will skip"
fi
