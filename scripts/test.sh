#!/usr/bin/env bash
# README command 2: install what is missing, build, run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/deps.sh --tests
./scripts/check_format.sh  # the sources stay formatted with .clang-format
dir=$(./scripts/build.sh | tail -n 1)
ctest --test-dir "$dir" --output-on-failure -j "$(nproc)"
