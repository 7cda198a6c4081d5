#!/usr/bin/env bash
# README command 2: install what is missing, build, run the whole test suite,
# then a bounded fuzzing run under the sanitizers.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/deps.sh --tests
./scripts/check_format.sh  # the sources stay formatted with .clang-format
dir=$(./scripts/build.sh | tail -n 1)
ctest --test-dir "$dir" --output-on-failure -j "$(nproc)"
# The readers of user files fuzzed for 10 s each, and the bridge tests, under
# ASan and UBSan (docs/hard-cases.md, "Fuzzing and sanitizers").
./scripts/fuzz.sh 10
