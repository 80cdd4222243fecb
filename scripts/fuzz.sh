#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan, -DAPERTURE_FUZZ=ON) in build-fuzz/ and
# runs each for SECONDS (default 300), then replays the committed seed corpus
# (tests/fuzz/corpus/<target>/), the regressions (tests/fuzz/regressions/<target>/) and, for
# the mesh and job targets, the malformed corpora (tests/data/bad/, tests/data/bad_jobs/) as a
# regression suite. Targets: ply, obj, gltf (mesh and scene loaders), job (batch job parser),
# cameras (camera files: COLMAP, transforms.json, OpenCV JSON and YAML).
#   scripts/fuzz.sh [SECONDS] [TARGET...]      e.g. scripts/fuzz.sh 600 ply
# New inputs go to build-fuzz/corpus/<target>/, crashes to build-fuzz/crashes/<target>/; a
# crash makes the script fail (turn it into a file under tests/fuzz/regressions/<target>/).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-300}
shift || true
targets=("$@")
if ((${#targets[@]} == 0)); then
  for d in tests/fuzz/corpus/*/; do targets+=("$(basename "$d")"); done
fi

if ! command -v clang++ >/dev/null || ! ls /usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a >/dev/null 2>&1; then
  echo "fuzz: installing clang and libFuzzer (Debian: clang libclang-rt-14-dev)"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends clang libclang-rt-14-dev
fi

build=${FUZZ_BUILD_DIR:-build-fuzz}
# -O1 -g, as the sanitizers' documentation advises (compiling the fuzz targets took 220 s of CPU
# at -O1 against 244 s at -O2 on 2 cores).
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g -DNDEBUG" \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DAPERTURE_FUZZ=ON \
  -DAPERTURE_BUILD_TESTS=OFF -DAPERTURE_BUILD_BENCH=OFF -DAPERTURE_NATIVE=OFF >/dev/null
cmake --build "$build" -j"${FUZZ_JOBS:-2}" --target "${targets[@]/#/fuzz_}"

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# Small inputs, a 1 s hang limit (the malformed-file budget is 2 s on much larger files) and
# at most 256 MB in one allocation: a loader that allocates from an unchecked count fails here.
flags=(-max_len=16384 -timeout=1 -rss_limit_mb=1024 -malloc_limit_mb=256 -print_final_stats=1)
# Fuzzes target $1 for $seconds s, then replays every committed input once; prints what it
# found and returns 1 on any finding.
fuzz_target() {
  local t=$1 status=0
  local bin="$build/tests/fuzz/fuzz_$t" work="$build/corpus/$t" crashes="$build/crashes/$t"
  mkdir -p "$work" "$crashes"
  local dict=()
  [[ -f tests/fuzz/$t.dict ]] && dict=(-dict="tests/fuzz/$t.dict")
  if ((seconds > 0)); then
    echo "fuzz: $t for $seconds s"
    if ! "$bin" "${flags[@]}" "${dict[@]}" -max_total_time="$seconds" \
        -artifact_prefix="$crashes/" "$work" "tests/fuzz/corpus/$t" 2>"$build/fuzz-$t.log"; then
      echo "fuzz: $t FOUND A CRASH (see $build/fuzz-$t.log and $crashes/)"
      tail -40 "$build/fuzz-$t.log"
      status=1
    fi
    grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$build/fuzz-$t.log" | sed "s/^/fuzz: $t /" || true
  fi
  # Regression suite: every committed input once.
  local inputs=(tests/fuzz/corpus/"$t"/*) f
  for f in tests/fuzz/regressions/"$t"/*; do [[ -f $f ]] && inputs+=("$f"); done
  case $t in
    ply) for f in tests/data/bad/*.ply; do inputs+=("$f"); done ;;
    obj) for f in tests/data/bad/*.obj; do inputs+=("$f"); done ;;
    job) for f in tests/data/bad_jobs/*.json; do inputs+=("$f"); done ;;
  esac
  if "$bin" "${flags[@]}" "${inputs[@]}" >"$build/regress-$t.log" 2>&1; then
    echo "fuzz: $t regression suite: ${#inputs[@]} inputs clean"
  else
    echo "fuzz: $t regression suite FAILED"
    tail -40 "$build/regress-$t.log"
    status=1
  fi
  return $status
}

# One target per core at a time (each libFuzzer run is single-threaded); each target's report
# is printed whole, in the order given, once all have run.
parallel=${FUZZ_PARALLEL:-$(nproc)}
for t in "${targets[@]}"; do
  while (($(jobs -rp | wc -l) >= parallel)); do wait -n || true; done
  rm -f "$build/status-$t"
  (status=0; fuzz_target "$t" || status=$?; echo $status >"$build/status-$t") \
    >"$build/report-$t.txt" 2>&1 &
done
wait
status=0
for t in "${targets[@]}"; do
  cat "$build/report-$t.txt"
  [[ $(cat "$build/status-$t" 2>/dev/null) == 0 ]] || status=1
done
exit $status
