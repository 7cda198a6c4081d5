#!/usr/bin/env bash
# Settling benchmark and mixed-size scene: the same scenes in Gabion, LIGGGHTS,
# Yade and the ceiling kernel, one table per scene.
#   bench/settle/run.sh                      # settling scene, N = 5000 20000, 10000 steps
#   bench/settle/run.sh --scene mixed        # mixed-size scene (22,020 spheres), 5000 steps
#   bench/settle/run.sh --scene both         # both; the mixed table gives each engine's mixed / settling speed
#   bench/settle/run.sh --steps 500 5000     # quick check of the harness
#   bench/settle/run.sh --help               # every option
# Gabion: build/gabion (scripts/build.sh builds it) or --gabion PATH.
# Peers (Debian, not in scripts/deps.sh, large): apt-get install -y liggghts yade time
# The ceiling kernel: built from the repository's sibling ../shared/reference/ceiling
# (sol.cpp, gen.py) into bench/work/ceiling, or --ceiling-dir PATH.
# A peer that is not installed is skipped, and the table says so.
# Scenes and outputs go to bench/work/settle/ (git-ignored); docs/performance.md.
set -euo pipefail
exec python3 "$(dirname "$0")/bench.py" "$@"
