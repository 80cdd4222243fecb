#!/usr/bin/env bash
# CI: the whole GoogleTest suite under AddressSanitizer + UndefinedBehaviorSanitizer (no
# recovery: the first report fails the run), and the frame-loop and batch tests under
# ThreadSanitizer. Debian's TBB is uninstrumented: core/util/parallel.h annotates the fork and join
# of our one parallel loop, and tests/tsan.supp names the TBB-internal frames that remain
# (checked at -O0 and -O1: a deliberate race in a loop body is still reported).
# Build trees: build-asan/ and build-tsan/ (with -g: TSan reports name source lines), gcc,
# both -O0. Measured on 2 cores (AMD EPYC, 2026-11-26): the ASan build takes 162 s at -O0,
# 327 s at -O1 and 657 s at -O3 (the -O3 figure with every target in unity batches); its
# tests, one shard per core, 149 s at -O0 and 111 s at -O1. The TSan build takes 121 s at -O0
# and 196 s at -O1 -g, its tests as long. The suites run in gtest shards, not as one CTest
# process per test: under ASan, 666 process start-ups and leak checks had cost more than half
# of the suite's 246 s. The command lines the tests start load OpenImageIO only as the plugin,
# when they need it (core/CMakeLists.txt): linked in, it added 0.7 s to every ASan process, and
# the four ASan shards took 1105 s in all instead of 676 (Intel Xeon, 2026-11-27).
#   scripts/ci-sanitizers.sh [asan|tsan]...   (default: both)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${CI_JOBS:-2}
parts=("$@")
((${#parts[@]})) || parts=(asan tsan)

# Builds the command line and the test binary in build-<part>/ with APERTURE_SANITIZE=$2 and
# the compiler flags $3.
build() {
  cmake -S . -B "build-$1" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE="$3" \
    -DAPERTURE_WERROR=ON -DAPERTURE_SANITIZE="$2" -DAPERTURE_BUILD_BENCH=OFF >/dev/null
  cmake --build "build-$1" -j"$jobs" --target aperture aperture_tests
}

# Runs build-<part>/tests/aperture_tests as 2·jobs gtest shards at once, in the directory
# CTest would use; extra arguments go to every shard. Prints each shard's summary, and the end
# of the log of a shard that failed.
run_shards() {
  local part=$1 shards=$((2 * jobs)) pids=() status=0 k
  shift
  for ((k = 0; k < shards; ++k)); do
    (cd "build-$part/tests" && GTEST_TOTAL_SHARDS=$shards GTEST_SHARD_INDEX=$k \
      ./aperture_tests "$@" >"../shard-$k.log" 2>&1) &
    pids+=($!)
  done
  for k in "${!pids[@]}"; do
    if ! wait "${pids[$k]}"; then
      echo "ci-sanitizers: $part shard $k FAILED (build-$part/shard-$k.log):"
      grep -E '^\[  FAILED  \]|ERROR: |runtime error|WARNING: ThreadSanitizer|^SUMMARY: ' \
        "build-$part/shard-$k.log" || true
      tail -60 "build-$part/shard-$k.log"
      status=1
    fi
    { grep -E '^\[==========\] .* ran' "build-$part/shard-$k.log" || true; } |
      sed "s/^/ci-sanitizers: $part shard $k: /"
  done
  return $status
}

for part in "${parts[@]}"; do
  start=$SECONDS
  case $part in
    asan)
      build asan address "-O0 -DNDEBUG"
      # Leak checking stays on; Embree/TBB/OpenEXR/OIIO are uninstrumented but their heap
      # allocations still go through ASan's malloc.
      # Every test but two, which load and build the procedural city in world space far from
      # the origin and each held its shard longest: NumericsTranslation.CameraRelativeIs...
      # (nine builds) took 302 s under ASan on an Intel Xeon (2026-11-26), holding its shard at
      # 420 s while the others took 247-330 s; CullingCity.FarFromTheOrigin... took 78 s of its
      # shard's 389 s (the others 225-295 s) in a rehearsal that took 1745 s of the 30 minutes
      # (2026-11-27). The loader, placement, culling and frame loop they run are under ASan in
      # the other tests (CullingCity.* among them), and both run in the normal suite.
      ASAN_OPTIONS=detect_leaks=1:exitcode=86 \
      UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1:exitcode=87 \
        run_shards asan --gtest_filter='-NumericsTranslation.CameraRelativeIsInvariantWorldSpaceErrorIsMeasured:CullingCity.FarFromTheOriginInWorldSpaceTheOriginRoundingIsCovered'
      ;;
    tsan)
      build tsan thread "-O0 -g -DNDEBUG"
      # The frame loop (tiles over TBB workers) and batch (render thread + writer threads).
      # tests/tsan.supp covers reports inside the uninstrumented TBB, Embree and OpenImageIO only.
      TSAN_OPTIONS="halt_on_error=1:exitcode=88:second_deadlock_stack=1:suppressions=$PWD/tests/tsan.supp" \
        run_shards tsan --gtest_filter='Render*:PerspectiveShift.*:Batch*:Cli.PacketWidthsAndThreads*'
      ;;
    *) echo "ci-sanitizers: unknown part '$part' (asan or tsan)"; exit 2 ;;
  esac
  echo "ci-sanitizers: $part took $((SECONDS - start)) s"
done
