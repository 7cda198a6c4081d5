#!/usr/bin/env bash
# Compares Gabion binaries on the settling scene, alternating runs so that the
# machine's drift hits all of them alike; prints best and all body-steps/s.
#   bench/settle/compare.sh [-n N] [-t THREADS] [-r REPEAT] BINARY...
# One-thread runs are pinned to one core (taskset -c 1) when taskset exists.
# The scene comes from bench/settle/run.sh (bench/work/settle/settle_N.gabion.json);
# run.sh --steps 1 N makes it. docs/micro.md (Speed) shows its use.
set -euo pipefail
n=20000 threads=1 repeat=3
while getopts "n:t:r:h" opt; do
  case "$opt" in
    n) n=$OPTARG ;;
    t) threads=$OPTARG ;;
    r) repeat=$OPTARG ;;
    *) sed -n '2,7p' "$0"; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
[ $# -ge 1 ] || { sed -n '2,7p' "$0"; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
scene="$here/../work/settle/settle_$n.gabion.json"
[ -f "$scene" ] || { echo "compare.sh: no $scene; make it with: bench/settle/run.sh --steps 1 --engines gabion $n" >&2; exit 2; }
pin=()
if [ "$threads" = 1 ] && command -v taskset >/dev/null; then pin=(taskset -c 1); fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for _ in $(seq "$repeat"); do
  for b in "$@"; do
    "${pin[@]}" "$b" run "$scene" -o "$out/run" -q --threads "$threads" \
      --set run.duration_s=0.4 --set run.output_interval_s=0.4 >/dev/null
    python3 -c 'import json,sys; s=json.load(open(sys.argv[1])); print(sys.argv[2], round(s["body_steps_per_s"]/1e6, 2))' \
      "$out/run/summary.json" "$b"
  done
done | awk '{all[$1]=all[$1]" "$2; if ($2>best[$1]) best[$1]=$2} END {for (b in all) print b, "best", best[b], "all", all[b]}'
