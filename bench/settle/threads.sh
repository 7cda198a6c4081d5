#!/usr/bin/env bash
# What two threads gain on a machine whose two CPUs may differ: per round,
# Gabion and the ceiling kernel each run the settling scene on one thread
# pinned to CPU 0, on one thread pinned to CPU 1, and on two threads; prints
# each run (M body-steps/s), then per engine, over the rounds (median and
# range): two threads over CPU 0 alone, over CPU 1 alone, and the parallel
# efficiency, two threads over the sum of the two CPUs alone (1 when the two
# threads together do what each CPU does alone; the target "1.6x more on two
# threads" is 0.8 on two alike CPUs).
#   bench/settle/threads.sh [-n N] [-r ROUNDS] [GABION_BINARY]
# Before each round, bench_core_round_trip (beside the binary, bench/) says
# where the CPUs lie and how fast each reads memory (on stderr). The scene
# and the kernel's builds come from bench/settle/run.sh (run.sh --steps 1
# --engines ceiling,gabion N makes them). docs/performance.md
# (settling benchmark, What two threads gain) shows its use.
set -euo pipefail
n=5000 rounds=5
while getopts "n:r:h" opt; do
  case "$opt" in
    n) n=$OPTARG ;;
    r) rounds=$OPTARG ;;
    *) sed -n '2,15p' "$0"; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
here=$(cd "$(dirname "$0")" && pwd)
gabion=${1:-$here/../../build/gabion}
scene="$here/../work/settle/settle_$n.gabion.json"
spheres="$here/../work/settle/settle_$n.spheres"
sol="$here/../work/ceiling/sol" sol_omp="$here/../work/ceiling/sol_omp"
make="bench/settle/run.sh --steps 1 --engines ceiling,gabion $n"
for f in "$scene" "$spheres" "$sol" "$sol_omp"; do
  [ -e "$f" ] || { echo "threads.sh: no $f; make it with: $make" >&2; exit 2; }
done
[ -x "$gabion" ] || { echo "threads.sh: no Gabion binary $gabion" >&2; exit 2; }
command -v taskset >/dev/null || { echo "threads.sh: needs taskset (util-linux)" >&2; exit 2; }
[ "$(nproc)" -ge 2 ] || { echo "threads.sh: needs two CPUs" >&2; exit 2; }
side=$(python3 -c 'import json,sys; print(repr(json.load(open(sys.argv[1]))["side_m"]))' "${scene%.gabion.json}.meta.json")
steps=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["steps"])' "${scene%.gabion.json}.meta.json")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
gabion_run() {  # threads, pin... -> M body-steps/s
  local t=$1
  shift
  "$@" "$gabion" run "$scene" -o "$out/run" -q --threads "$t" >/dev/null
  python3 -c 'import json,sys; print(round(json.load(open(sys.argv[1]))["body_steps_per_s"] / 1e6, 2))' \
    "$out/run/summary.json"
}
ceiling_run() {  # threads, pin...
  local t=$1 exe=$sol
  shift
  [ "$t" = 1 ] || exe=$sol_omp
  OMP_NUM_THREADS=$t "$@" "$exe" "$spheres" "$side" --steps "$steps" | sed -n 's/.*body-steps\/s \([0-9.]*\) M.*/\1/p'
}
probe="$(dirname "$gabion")/bench/bench_core_round_trip"
for r in $(seq "$rounds"); do
  # (where the CPUs lie and how fast each reads memory, before each round: stderr)
  [ -x "$probe" ] && "$probe" --trips 50000 --batches 3 | sed "s/^/round $r: /" >&2
  for e in gabion ceiling; do
    run=${e}_run
    c0=$($run 1 taskset -c 0) c1=$($run 1 taskset -c 1) both=$($run 2)
    echo "$r $e $c0 $c1 $both"
  done
done | python3 -c '
import statistics, sys
rows = {}
print("round engine cpu0 cpu1 two-threads (M body-steps/s)")
for line in sys.stdin:
    print(line.rstrip())
    r, e, c0, c1, both = line.split()
    rows.setdefault(e, []).append((float(c0), float(c1), float(both)))
def span(x):
    x = sorted(x)
    return f"{statistics.median(x):.2f} ({x[0]:.2f}-{x[-1]:.2f})"
for e, v in rows.items():
    print(f"{e}: two threads over CPU 0 alone {span([b / a for a, _, b in v])}, over CPU 1 alone "
          f"{span([b / c for _, c, b in v])}; CPU 1 alone over CPU 0 alone {span([c / a for a, c, _ in v])}; "
          f"efficiency (two threads over CPU 0 + CPU 1 alone) {span([b / (a + c) for a, c, b in v])} "
          f"over {len(v)} rounds")
'
