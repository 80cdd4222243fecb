#!/usr/bin/env bash
# Installs the Debian 12 packages aperture needs to build and test (run as root).
# Only missing packages are installed; an up-to-date machine does nothing.
set -euo pipefail
pkgs=(
  build-essential cmake ninja-build pkg-config
  libembree-dev libtbb-dev libopenexr-dev libopenimageio-dev libglm-dev
  googletest libgtest-dev libbenchmark-dev
  nlohmann-json3-dev libcli11-dev
  libyaml-cpp-dev  # OpenCV FileStorage YAML camera files
  libtinygltf-dev libdraco-dev libmeshoptimizer-dev  # glTF 2.0 scenes and their compression
  clang-format  # the Format test enforces .clang-format
  ccache  # scripts/test.sh: its `pip install .` check reuses the objects of the CMake build
  openimageio-tools  # Debian's OpenImageIO CMake config references its binaries
  python3-dev python3-venv  # the Python module: headers, and venv with pip for .venv
)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
