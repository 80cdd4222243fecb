#!/usr/bin/env bash
# Fails (exit 1) naming every C++ file that clang-format (the checked-in .clang-format) would
# change. Run by CTest as the test `Format`, so scripts/test.sh and CI enforce it.
set -euo pipefail
cd "$(dirname "$0")/.."
command -v clang-format >/dev/null ||
  { echo "check-format: clang-format is not installed (apt-get install clang-format)"; exit 1; }
bad=()
while IFS= read -r -d '' f; do
  clang-format --dry-run -Werror "$f" >/dev/null 2>&1 || bad+=("$f")
done < <(find core cameras apps bench tests python \( -name '*.cpp' -o -name '*.h' \) -print0 2>/dev/null)
if ((${#bad[@]})); then
  echo "check-format: not clang-formatted (run clang-format -i on them): ${bad[*]}"
  exit 1
fi
echo "check-format: all C++ files are clang-formatted"
