#!/usr/bin/env bash
# Settling benchmark: the same scene in Gabion, LIGGGHTS and Yade, one table.
#   bench/settle/run.sh                      # N = 5000 20000, 10000 steps
#   bench/settle/run.sh --steps 1000 5000    # quick check of the harness
#   bench/settle/run.sh --help               # every option
# Gabion: build/gabion (scripts/build.sh builds it) or --gabion PATH.
# Peers (Debian, not in scripts/deps.sh, large): apt-get install -y liggghts yade time
# A peer that is not installed is skipped, and the table says so.
# Scenes and outputs go to bench/work/settle/ (git-ignored); docs/performance.md.
set -euo pipefail
exec python3 "$(dirname "$0")/bench.py" "$@"
