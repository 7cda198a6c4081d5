#!/usr/bin/env bash
# Rows of a sweep run every way Gabion runs them, on this machine, with the
# README's build (docs/cluster.md, "Scaling on one machine"):
#   local threads (1 and 2), MPI ranks (1 and 2; on one rank gabion does not
#   start MPI: the cost of mpirun alone), a Slurm job array
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
small=$count large=$((4 * count))
args() { echo "$root/cases/macro_sweep.json" --set "sweep.velocity_m_s.count=$1"; }
rows_of() { "$gabion" rows $(args "$1") | wc -l; }
rows=$(rows_of "$small") rows_large=$(rows_of "$large")
now() { date +%s.%N; }
since() { python3 -c "print($(now) - $1)"; }
results=$out/results.txt
: >"$results"
record() { echo "$1|$2|$3|$4" >>"$results"; }  # how|workers|rows|wall seconds

same() {  # the table of run $1 is the 1-thread run's of the same size
  cmp -s "$out/threads1-$2/sweep.csv" "$out/$1/sweep.csv" || { echo "$1: table differs from the 1-thread run" >&2; exit 1; }
}

# Each way at two sizes: wall = start-up + rows x (time per row) / workers.
for n in "$small" "$large"; do
  nrows=$(rows_of "$n")
  for t in 1 2; do
    t0=$(now)
    "$gabion" run $(args "$n") -q --threads "$t" -o "$out/threads$t-$n" >/dev/null
    record "local threads" "$t" "$nrows" "$(since "$t0")"
    same "threads$t-$n" "$n"
  done
  if command -v mpirun >/dev/null; then
    for np in 1 2; do
      t0=$(now)
      mpirun --allow-run-as-root --oversubscribe -np "$np" "$gabion" run $(args "$n") -q -o "$out/mpi$np-$n" >/dev/null
      record "MPI ranks (mpirun -np $np)" "$np" "$nrows" "$(since "$t0")"
      same "mpi$np-$n" "$n"
    done
  fi
done
case_args=($(args "$small"))

# One row per process: what a slice costs beyond its rows (start-up, the
# case read and checked, the plan built, the row's folder written).
t0=$(now)
for i in $(seq 0 19); do "$gabion" run "${case_args[@]}" -q --rows "$i" -o "$out/single" >/dev/null; done
single=$(python3 -c "print(($(now) - $t0) / 20)")

if [ "$slurm" = 1 ] && [ "$(id -u)" -eq 0 ]; then
  "$root/scripts/slurm_local.sh" install >/dev/null 2>&1
  eval "$("$root/scripts/slurm_local.sh" start "$out/cluster" 2>/dev/null)"
  trap '"$root/scripts/slurm_local.sh" stop "$out/cluster" 2>/dev/null' EXIT
  # (tasks of half the rows one at a time, then two at a time; then ten tasks)
  for spec in "$((rows / 2)) 1" "$((rows / 2)) 2" "$((rows / 10)) 2"; do
    read -r per par <<<"$spec"
    t0=$(now)
    job=$("$gabion" submit slurm "${case_args[@]}" -o "$out/slurm$per-$par" --rows-per-task "$per" \
      --max-parallel "$par" | sed -n 's/^submitted: job \([0-9]*\).*/\1/p')
    while squeue -h -j "$job" 2>/dev/null | grep -q .; do sleep 0.1; done
    "$gabion" collect "$out/slurm$per-$par" -q >/dev/null
    record "Slurm array, $((rows / per)) tasks of $per rows, $par at once" "$par" "$rows" "$(since "$t0")"
    same "slurm$per-$par" "$small"
  done
fi

# The rows' own compute time: the mean of the 1-thread run's rows.
row_s=$(python3 -c "
import json,sys
lines=[json.loads(l) for l in open('$out/threads1-$large/rows.jsonl')][1:]
print(sum(l['wall_time_s'] for l in lines)/len(lines))")
python3 -c "print('sweep: $rows and $rows_large rows (cases/macro_sweep.json, sweep.velocity_m_s.count=$small and $large); one row computes in %.2f ms' % ($row_s * 1000))"
echo
python3 - "$results" "$row_s" "$single" <<'PY'
import sys, collections
results, row, single = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
runs = collections.OrderedDict()
for line in open(results):
    how, workers, rows, wall = line.strip().split("|")
    runs.setdefault((how, int(workers)), []).append((int(rows), float(wall)))
print("| how | workers | rows | wall time (s) | rows/s | start-up (s) | time per row x workers (ms) | overhead per row (ms) |")
print("|---|---|---|---|---|---|---|---|")
for (how, w), pts in runs.items():
    if len(pts) == 2:  # wall = a + b rows: a the start-up, b w the time a worker gives a row
        (n1, t1), (n2, t2) = pts
        b = (t2 - t1) / (n2 - n1)
        a = t1 - b * n1
        for n, t in pts:
            print("| %s | %d | %d | %.2f | %.0f | %.2f | %.2f | %.2f |" % (how, w, n, t, n / t, a, b * w * 1e3, (b * w - row) * 1e3))
    else:
        for n, t in pts:
            print("| %s | %d | %d | %.2f | %.0f | | | %.2f |" % (how, w, n, t, n / t, (t * w / n - row) * 1e3))
print("| one row per process (gabion run --rows i) | 1 | 1 | %.3f | %.1f | | | %.1f |" % (single, 1 / single, (single - row) * 1e3))
PY
