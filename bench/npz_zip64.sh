#!/usr/bin/env bash
# Issue 40, item 7: the .npz writer and reader through libzip (core/npz.cpp at LIBZIP) against
# the hand-written zip code they replaced (core/npz.cpp at BASE), on archives past 4 GiB.
# bench/npz_zip64.cpp is compiled twice with the Release flags (-O3 -DNDEBUG) and the project's
# warnings, each with the core sources it needs from that commit.
# Each round writes and then reads (page cache) BYTES of float32 with each build, alternating
# which goes first, for two layouts: one member of BYTES (zip64 sizes) and members of 1 MiB
# (zip64 offsets past 4 GiB). The write includes the fsync of the atomic write. Then, once:
# `unzip -t`, np.load and Python's zipfile read the libzip archive, each build reads the
# other's, and the bytes that differ between the two archives are counted. The table: medians
# of the rounds, wall seconds and CPU seconds (user + system) of the call.
#   bash bench/npz_zip64.sh   (ROUNDS=5 BYTES=4500000000 BASE=9bf1f53 LIBZIP=c155488
#                              DIR=/tmp/npz_zip64)
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
rounds=${ROUNDS:-5}
bytes=${BYTES:-4500000000}
base=${BASE:-9bf1f53}      # the last commit with the hand-written zip code
libzip=${LIBZIP:-c155488}  # the commit whose writer and reader are libzip's
dir=${DIR:-/tmp/npz_zip64}
python=${PYTHON:-$src/.venv/bin/python}
rm -rf "$dir"
flags=(-std=c++17 -O3 -DNDEBUG -Wall -Wextra -Wpedantic -Wshadow -Werror)
# The sources bench/npz_zip64.cpp needs, wherever a commit keeps them (core/ or core/io/ ...).
sources() { (cd "$1" && find core -name npz.cpp -o -name npy.cpp -o -name atomic_file.cpp \
  -o -name mapped_file.cpp | sed "s|^|$1/|"); }
for variant in handwritten libzip; do
  rev=$base
  [[ $variant == libzip ]] && rev=$libzip
  mkdir -p "$dir/$variant"
  git -C "$src" archive "$rev" core | tar -x -C "$dir/$variant"
  # Both commits predate the part folders: core/io/npz.h, which the program includes, is theirs.
  if [[ ! -e "$dir/$variant/core/io/npz.h" ]]; then
    mkdir -p "$dir/$variant/core/io"
    printf '#pragma once\n#include "core/npz.h"\n' >"$dir/$variant/core/io/npz.h"
  fi
  # shellcheck disable=SC2046
  g++ "${flags[@]}" -I"$dir/$variant" "$src/bench/npz_zip64.cpp" $(sources "$dir/$variant") \
    -lz $(pkg-config --cflags --libs libzip) -o "$dir/npz_$variant"
done

echo "$(date -u +%FT%TZ) $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) CPUs, $bytes bytes," \
  "$rounds rounds, base $base, libzip $libzip"
log="$dir/times.txt"
: >"$log"
for layout in one many; do
  for ((r = 1; r <= rounds; r++)); do
    order=(handwritten libzip)
    ((r % 2 == 0)) && order=(libzip handwritten)
    for impl in "${order[@]}"; do
      f="$dir/$impl.npz"
      for op in write read; do
        echo "$impl $("$dir/npz_$impl" $op "$f" $layout "$bytes")" | tee -a "$log"
      done
      if ((r == 1)); then
        cp --reflink=never "$f" "$dir/kept_$impl.npz" 2>/dev/null || cp "$f" "$dir/kept_$impl.npz"
      fi
      rm -f "$f"
    done
  done
  echo "checks of the $layout archives:"
  unzip -tq "$dir/kept_libzip.npz"
  "$python" - "$dir/kept_libzip.npz" "$bytes" <<'EOF'
import sys, zipfile, numpy as np
path, total = sys.argv[1], int(sys.argv[2])
with zipfile.ZipFile(path) as z:
    infos = z.infolist()
    assert sum(i.file_size for i in infos) > total and all(i.compress_type == 0 for i in infos)
d = np.load(path)
n = 0
for name in d.files:
    a = d[name]
    assert a.dtype == np.float32, name
    for at in range(0, a.size, 1 << 24):
        part = a[at:at + (1 << 24)]
        i = np.arange(n + at, n + at + part.size, dtype=np.uint64) % (1 << 24)
        assert np.array_equal(part, i.astype(np.float32) * np.float32(0.5)), (name, at)
    n += a.size
assert n * 4 == total, n
print(f"np.load and zipfile: {len(infos)} members, {n * 4} data bytes, every value as written")
EOF
  "$dir/npz_handwritten" read "$dir/kept_libzip.npz" $layout "$bytes" >/dev/null &&
    echo "the hand-written reader reads libzip's archive"
  "$dir/npz_libzip" read "$dir/kept_handwritten.npz" $layout "$bytes" >/dev/null &&
    echo "libzip's reader reads the hand-written archive"
  ls -l "$dir"/kept_*.npz
  echo "bytes that differ between the two archives: $(cmp -l "$dir/kept_handwritten.npz" \
    "$dir/kept_libzip.npz" | wc -l || true)"
  rm -f "$dir"/kept_*.npz
done

python3 - "$log" <<'EOF'
import statistics, sys, collections
t = collections.defaultdict(list)
for line in open(sys.argv[1]):
    impl, op, layout, _, wall, cpu = line.split()
    t[(layout, op, impl)].append((float(wall), float(cpu)))
print("| layout | operation | hand-written wall s | libzip wall s | ratio |"
      " hand-written CPU s | libzip CPU s | ratio |")
print("|---|---|---|---|---|---|---|---|")
for layout in ("one", "many"):
    for op in ("write", "read"):
        cells = []
        for k in (0, 1):
            h, z = (statistics.median(x[k] for x in t[(layout, op, i)])
                    for i in ("handwritten", "libzip"))
            cells += [f"{h:.2f}", f"{z:.2f}", f"{z / h:.3f}"]
        print(f"| {layout} | {op} | " + " | ".join(cells) + " |")
EOF
