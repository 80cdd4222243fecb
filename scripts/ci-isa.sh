#!/usr/bin/env bash
# CI: the GoogleTest suite again at the vector widths of CPUs other than the one CI runs on,
# forced through the two environment variables that pick the kernels:
#   - Embree at AVX2 (APERTURE_EMBREE_CONFIG=isa=avx2: what Embree picks on any CPU without
#     AVX-512) with aperture's x86-64-v3 kernels (APERTURE_KERNEL_ISA, core/util/vector_kernel.h);
#   - Embree at SSE4.2 with aperture's baseline kernels.
# The golden hashes (tests/cameras/models/test_golden.cpp) must hold under both, as under the
# default run of scripts/test.sh. Reuses build/ of scripts/test.sh (run it first): only the
# tests run again, not the format check (no vector code) nor pytest (the same C++ through
# the Python module). A combination this CPU cannot run is skipped with a message.
#   scripts/ci-isa.sh [avx2|sse4.2]...   (default: both)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${CI_JOBS:-$(nproc)}
parts=("$@")
((${#parts[@]})) || parts=(avx2 sse4.2)

[[ -x build/tests/aperture_tests ]] || {
  echo "ci-isa: build/tests/aperture_tests is missing: run scripts/test.sh first" >&2
  exit 1
}

status=0
for part in "${parts[@]}"; do
  case $part in
    avx2) kernels=x86-64-v3 flag=avx2 ;;
    sse4.2) kernels=baseline flag=sse4_2 ;;
    *)
      echo "ci-isa: unknown combination '$part' (known: avx2, sse4.2)" >&2
      exit 2
      ;;
  esac
  if ! grep -qw "$flag" /proc/cpuinfo; then
    echo "ci-isa: skipping Embree isa=$part: this CPU has no $flag"
    continue
  fi
  start=$SECONDS
  if ! APERTURE_EMBREE_CONFIG=isa=$part APERTURE_KERNEL_ISA=$kernels \
    ctest --test-dir build --output-on-failure -j"$jobs" -E '^(Format|pytest)$'; then
    status=1
  fi
  echo "ci-isa: Embree isa=$part with aperture's $kernels kernels: $((SECONDS - start)) s"
done
exit $status
