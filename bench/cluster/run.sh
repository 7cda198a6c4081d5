#!/usr/bin/env bash
# Rows of a sweep run every way Gabion runs them, on this machine, with the
# README's build (docs/cluster.md, "Scaling on one machine"):
#   local threads (1 and 2), MPI ranks (1 and 2 workers), a Slurm job array
#   on a one-node cluster on localhost (scripts/slurm_local.sh; needs root),
#   and single-row slices (the start-up cost of one `gabion run --rows`).
# Each run's table is checked against the 1-thread run's (sweep.csv, byte for
# byte). Prints a markdown table: wall time, rows per second, and the
# overhead per row over the rows' own compute time.
#   bench/cluster/run.sh [--rows-per-speed N] [--out DIR] [--no-slurm]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
count=100 out=${TMPDIR:-/tmp}/gabion-bench-cluster slurm=1
while [ $# -gt 0 ]; do
  case $1 in
    --rows-per-speed) count=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --no-slurm) slurm=0; shift ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
gabion=${GABION:-$root/build/gabion}
[ -x "$gabion" ] || { echo "build first (scripts/build.sh)" >&2; exit 2; }
rm -rf "$out" && mkdir -p "$out"
case_args=("$root/cases/macro_sweep.json" --set "sweep.velocity_m_s.count=$count")
rows=$("$gabion" rows "${case_args[@]}" | wc -l)
now() { date +%s.%N; }
since() { python3 -c "print($(now) - $1)"; }
results=$out/results.txt
: >"$results"
record() { echo "$1|$2|$3" >>"$results"; }  # how|workers|wall seconds

same() {  # the table of run $1 is the 1-thread run's
  cmp -s "$out/threads1/sweep.csv" "$out/$1/sweep.csv" || { echo "$1: table differs from the 1-thread run" >&2; exit 1; }
}

for t in 1 2; do
  t0=$(now)
  "$gabion" run "${case_args[@]}" -q --threads "$t" -o "$out/threads$t" >/dev/null
  record "local threads" "$t" "$(since "$t0")"
  same "threads$t"
done

if command -v mpirun >/dev/null; then
  for np in 2 3; do
    t0=$(now)
    mpirun --allow-run-as-root --oversubscribe -np "$np" "$gabion" run "${case_args[@]}" -q -o "$out/mpi$np" >/dev/null
    record "MPI ranks (mpirun -np $np)" "$((np - 1))" "$(since "$t0")"
    same "mpi$np"
  done
fi

# One row per process: what a slice costs beyond its rows (start-up, the
# case read and checked, the plan built, the row's folder written).
t0=$(now)
for i in $(seq 0 19); do "$gabion" run "${case_args[@]}" -q --rows "$i" -o "$out/single" >/dev/null; done
single=$(python3 -c "print(($(now) - $t0) / 20)")

if [ "$slurm" = 1 ] && [ "$(id -u)" -eq 0 ]; then
  "$root/scripts/slurm_local.sh" install >/dev/null 2>&1
  eval "$("$root/scripts/slurm_local.sh" start "$out/cluster" 2>/dev/null)"
  trap '"$root/scripts/slurm_local.sh" stop "$out/cluster" 2>/dev/null' EXIT
  for per in $((rows / 2)) $((rows / 10)); do
    t0=$(now)
    job=$("$gabion" submit slurm "${case_args[@]}" -o "$out/slurm$per" --rows-per-task "$per" |
      sed -n 's/^submitted: job \([0-9]*\).*/\1/p')
    while squeue -h -j "$job" 2>/dev/null | grep -q .; do sleep 0.1; done
    "$gabion" collect "$out/slurm$per" -q >/dev/null
    record "Slurm array, $((rows / per)) tasks of $per rows" 2 "$(since "$t0")"
    same "slurm$per"
  done
fi

# The rows' own compute time: the mean of the 1-thread run's rows.
row_s=$(python3 -c "
import json,sys
lines=[json.loads(l) for l in open('$out/threads1/rows.jsonl')][1:]
print(sum(l['wall_time_s'] for l in lines)/len(lines))")
python3 -c "print('sweep: $rows rows (cases/macro_sweep.json, sweep.velocity_m_s.count=$count); one row computes in %.2f ms' % ($row_s * 1000))"
echo
echo "| how | workers | wall time (s) | rows/s | overhead per row (ms) |"
echo "|---|---|---|---|---|"
while IFS='|' read -r how workers wall; do
  python3 -c "
rows,wall,w,row=$rows,$wall,$workers,$row_s
print('| $how | %d | %.2f | %.0f | %.2f |' % (w, wall, rows/wall, (wall*w/rows-row)*1000))"
done <"$results"
python3 -c "print('| one row per process (gabion run --rows i) | 1 | %.3f | %.1f | %.1f |' % ($single, 1/$single, ($single-$row_s)*1000))"
