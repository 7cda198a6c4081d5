# Sourced by bench/resolved/run.sh and wide.sh once they have set $root,
# $out and $threads: the binaries ($gabion, $curves), the pipeline's results
# they need, and run_once.
gabion=${GABION:-$root/build/gabion}
curves=${CURVES:-$root/build/bench/bench_curves}
[ -x "$gabion" ] && [ -x "$curves" ] || { echo "build first (scripts/build.sh)" >&2; exit 2; }
[ -f "$root/results/pipeline/law.json" ] || { echo "run the pipeline first (README, command 1)" >&2; exit 2; }
mkdir -p "$out"
# run_once NAME CASE ARGS...: one gabion run of CASE into OUT/NAME (its
# output in OUT/NAME.log), unless OUT/NAME/summary.json is there; a run
# that was stopped (its summary "interrupted") is resumed from its
# checkpoints (gabion run --resume); a failure is reported and the script
# goes on.
run_once() {
  local name=$1 case=$2; shift 2
  if [ -f "$out/$name/summary.json" ]; then
    grep -q '"status": "interrupted"' "$out/$name/summary.json" || return 0
    echo "== $name (resumed)" >&2
    "$gabion" run --resume "$out/$name" --threads "$threads" -q >>"$out/$name.log" 2>&1 ||
      echo "   $name failed: $(tail -n 1 "$out/$name.log")" >&2
    return 0
  fi
  echo "== $name" >&2
  mkdir -p "$(dirname "$out/$name")"
  "$gabion" run "$case" --threads "$threads" -q -o "$out/$name" "$@" >"$out/$name.log" 2>&1 ||
    echo "   $name failed: $(tail -n 1 "$out/$name.log")" >&2
}
