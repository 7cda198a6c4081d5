#!/usr/bin/env bash
# The hard cases (cases/hard/, docs/hard-cases.md) in full, with the README's
# build: each case's exit code, how it ended and why, and its wall time, as
# the Markdown table of docs/hard-cases.md.
#   bench/hard/run.sh [--out DIR]      (about 2 minutes on 2 cores, most of
#                                       it generating the default cell the
#                                       cell-striking cases share)
# ctest runs the same cases reduced (tests/app/test_hard_cases.cpp) and
# checks them against cases/hard/expected.json.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=${TMPDIR:-/tmp}/gabion-bench-hard
while [ $# -gt 0 ]; do
  case $1 in
    --out) out=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
gabion=${GABION:-$root/build/gabion}
[ -x "$gabion" ] || { echo "build first (scripts/build.sh)" >&2; exit 2; }
mkdir -p "$out"
# The cell the cell-striking cases generate (each would generate its own).
[ -f "$out/cell/cell.h5" ] || "$gabion" run "$root/cases/micro_cell.json" -q -o "$out/cell" >/dev/null

echo "| case | exit | ended | why / answer | wall (s) |"
echo "|---|---|---|---|---|"
for case in "$root"/cases/hard/*.json; do
  name=$(basename "$case" .json)
  [ "$name" = expected ] && continue
  extra=()
  case $name in micro_uci_*) extra=(--set "cell=\"$out/cell/cell.h5\"") ;; esac
  rm -rf "${out:?}/$name"
  start=$(date +%s%N)
  set +e
  text=$("$gabion" run "$case" -q -o "$out/$name" "${extra[@]}" 2>&1)
  code=$?
  set -e
  ms=$(( ($(date +%s%N) - start) / 1000000 ))
  ended=$({ grep -o '"step_status": "[a-z_]*"\|"outcome": "[a-z]*"' "$out/$name/summary.json" 2>/dev/null || true; } |
          tail -1 | sed 's/.*: "\(.*\)"/\1/')
  # (the last line of the answer, or the failure; a fine DEM run that ended
  # ok prints none: its energy balance error)
  why=$({ echo "$text" | grep -v '^  \|^results:\|what was written' || true; } | tail -1 | sed 's/|/\\|/g' | cut -c1-220)
  if [ -z "$why" ]; then
    why="energy balance error $({ grep -o '"balance_rel_error": [-0-9.e]*' "$out/$name/summary.json" || true; } |
                               head -1 | sed 's/.*: //')"
  fi
  printf '| %s | %s | %s | %s | %d.%01d |\n' "$name" "$code" "${ended:-?}" "$why" $((ms / 1000)) $((ms % 1000 / 100))
done
