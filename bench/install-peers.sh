#!/usr/bin/env bash
# Installs what the peer comparison (bench/peers.py) and the plots (bench/plot.py) need; run as
# root. Benchmarks only: the build and CI need none of this (see scripts/install-deps.sh).
#   - embree-tools (Debian): Embree's own `viewer`, the peer that traces one ray at a time
#   - python3-matplotlib, python3-numpy, python3-pil, python3-venv (Debian): plots, image checks
#   - mitsuba (PyPI) in a virtual environment outside the repository, since Debian's python3 is
#     externally managed: ${APERTURE_PEERS_VENV:-$HOME/.cache/aperture-peers/venv}. It sees the
#     Debian packages (--system-site-packages). MITSUBA_VERSION pins the version (default below).
#   - open3d-cpu (PyPI) in the same venv: Open3D's RaycastingScene, the peer traced on aperture's
#     own rays (bench/peers_open3d.py). OPEN3D_VERSION pins it (default below; pip picks the wheel
#     for the venv's Python, 3.11 on Debian 12). NumPy comes from Debian (python3-numpy, seen
#     through --system-site-packages), which satisfies open3d-cpu's requirement: pip adds no copy.
set -euo pipefail
venv="${APERTURE_PEERS_VENV:-$HOME/.cache/aperture-peers/venv}"
mitsuba_version="${MITSUBA_VERSION:-3.9.1}"
open3d_version="${OPEN3D_VERSION:-0.20.0}"

pkgs=(embree-tools python3-matplotlib python3-numpy python3-pil python3-venv)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "install-peers: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

if [[ ! -x "$venv/bin/python" ]]; then
  echo "install-peers: creating $venv"
  /usr/bin/python3 -m venv --system-site-packages "$venv"
fi
if ! "$venv/bin/python" -c "import mitsuba, sys; sys.exit(mitsuba.__version__ != '$mitsuba_version')" 2>/dev/null; then
  echo "install-peers: installing mitsuba==$mitsuba_version into $venv"
  "$venv/bin/python" -m pip install -q "mitsuba==$mitsuba_version"
fi
"$venv/bin/python" -c "import mitsuba as mi; assert 'llvm_ad_rgb' in mi.variants(); print('install-peers: mitsuba', mi.__version__, 'with llvm_ad_rgb')"
if ! "$venv/bin/python" -c "import open3d, sys; sys.exit(open3d.__version__ != '$open3d_version')" 2>/dev/null; then
  echo "install-peers: installing open3d-cpu==$open3d_version into $venv"
  "$venv/bin/python" -m pip install -q "open3d-cpu==$open3d_version" numpy
fi
"$venv/bin/python" -c "import open3d as o3d; o3d.t.geometry.RaycastingScene(); print('install-peers: open3d', o3d.__version__)"
command -v viewer >/dev/null && echo "install-peers: Embree viewer at $(command -v viewer)"
