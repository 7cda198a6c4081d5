#!/usr/bin/env bash
# Configures and builds Gabion (RelWithDebInfo) into build/ (CI: build-ci/,
# warnings as errors, portable code).
set -euo pipefail
cd "$(dirname "$0")/.."
preset=release
[ "${CI:-}" = "true" ] && preset=ci
dir=build
[ "$preset" = ci ] && dir=build-ci
cmake --preset "$preset" -B "$dir" >&2
cmake --build "$dir" -j "$(nproc)" >&2
echo "$dir"
