#!/usr/bin/env bash
# CI: each fuzz target for 20 s (FUZZ_SECONDS; it was 60, 40 and 30 s before CI neared its 30 minutes), then the
# committed corpus, regressions and malformed corpora replayed once. Fails on any crash, leak,
# UB report, hang (> 1 s) or allocation over 256 MB.
set -euo pipefail
cd "$(dirname "$0")/.."
exec bash scripts/fuzz.sh "${FUZZ_SECONDS:-20}"
