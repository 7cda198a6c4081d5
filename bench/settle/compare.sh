#!/usr/bin/env bash
# Compares Gabion binaries on the settling scene, alternating runs so that the
# machine's drift hits all of them alike; prints best and all body-steps/s,
# and each binary over the first paired by round (median and range).
#   bench/settle/compare.sh [-n N|mixed] [-t THREADS] [-r REPEAT] BINARY...
# One-thread runs are pinned to one core (taskset -c 1) when taskset exists.
# The scene comes from bench/settle/run.sh (bench/work/settle/settle_N.gabion.json,
# 0.4 s; -n mixed: mixed.gabion.json, 5000 steps); run.sh --steps 1 N (or
# run.sh --scene mixed --steps 1 --engines gabion) makes it. docs/micro.md (Speed) shows its use.
set -euo pipefail
n=20000 threads=1 repeat=3
while getopts "n:t:r:h" opt; do
  case "$opt" in
    n) n=$OPTARG ;;
    t) threads=$OPTARG ;;
    r) repeat=$OPTARG ;;
    *) sed -n '2,9p' "$0"; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
[ $# -ge 1 ] || { sed -n '2,9p' "$0"; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
if [ "$n" = mixed ]; then
  scene="$here/../work/settle/mixed.gabion.json"
  make="bench/settle/run.sh --scene mixed --steps 1 --engines gabion"
else
  scene="$here/../work/settle/settle_$n.gabion.json"
  make="bench/settle/run.sh --steps 1 --engines gabion $n"
fi
[ -f "$scene" ] || { echo "compare.sh: no $scene; make it with: $make" >&2; exit 2; }
duration=0.4
if [ "$n" = mixed ]; then
  duration=$(python3 -c 'import json,sys; print(repr(5000 * json.load(open(sys.argv[1]))["dt_s"]))' "${scene%.gabion.json}.meta.json")
fi
pin=()
if [ "$threads" = 1 ] && command -v taskset >/dev/null; then pin=(taskset -c 1); fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for _ in $(seq "$repeat"); do
  for b in "$@"; do
    "${pin[@]}" "$b" run "$scene" -o "$out/run" -q --threads "$threads" \
      --set run.duration_s="$duration" --set run.output_interval_s="$duration" >/dev/null
    python3 -c 'import json,sys; s=json.load(open(sys.argv[1])); print(sys.argv[2], round(s["body_steps_per_s"]/1e6, 2))' \
      "$out/run/summary.json" "$b"
  done
done | python3 -c '
# Best and every run of each binary (M body-steps/s), then each binary over
# the first paired by round: the runs of one round lie seconds apart, so a
# drift of the machine speed over minutes hits both (median and range).
import statistics, sys
runs = {}
for line in sys.stdin:
    b, v = line.split()
    runs.setdefault(b, []).append(float(v))
for b, v in runs.items():
    print(b, "best", max(v), "all", " ".join(str(x) for x in v))
first = next(iter(runs), None)
for b, v in runs.items():
    if b != first and len(v) > 1:
        x = sorted(p / q for p, q in zip(v, runs[first]))
        print(f"{b} over {first}, paired by round: median {statistics.median(x):.3f} "
              f"({x[0]:.3f}-{x[-1]:.3f} over {len(x)} rounds)")
'
