#!/usr/bin/env bash
# README command 1: install what is missing, build, run the default case.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/deps.sh
dir=$(./scripts/build.sh | tail -n 1)
"$dir/gabion" run "${1:-cases/pipeline.json}" -o "${2:-results/pipeline}"
