#!/usr/bin/env bash
# The sheet tensile benchmark in one run: Gabion's micro.netting_tensile case
# (cases/micro_netting_tensile.json) at a fixed time step for a fixed number
# of steps, then Yade on the netting file that run wrote (same nodes, links,
# masses, clamps, pull, damping and step), one thread each, and the ratio of
# their step-loop times. Needs the README's build (build/gabion) and Debian's
# yade (apt-get install -y yade).
#   bench/netting/run.sh [--steps N] [--dt S] [--repeat R] [--out DIR]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
steps=874000 dt=2.2e-6 repeat=1 out=${TMPDIR:-/tmp}/gabion-bench-netting
while [ $# -gt 0 ]; do
  case $1 in
    --steps) steps=$2; shift 2 ;;
    --dt) dt=$2; shift 2 ;;
    --repeat) repeat=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
gabion=${GABION:-$root/build/gabion}
[ -x "$gabion" ] || { echo "no $gabion: build first (scripts/build.sh)" >&2; exit 2; }
command -v yade >/dev/null || { echo "yade is not installed (apt-get install -y yade)" >&2; exit 2; }
mkdir -p "$out"
speed=$(python3 -c "import json;print(json.load(open('$root/cases/micro_netting_tensile.json'))['test']['pull_speed_m_s'])")
disp=$(python3 -c "print(repr($steps * $dt * $speed))")
# dt_safety 0.3: the step (2.2 us, 0.26 of the wires' critical step) is then
# also the wires' step, one link sub-step per step, as Yade integrates them.
for r in $(seq 1 "$repeat"); do
  "$gabion" run "$root/cases/micro_netting_tensile.json" -q -o "$out/gabion" \
    --set run.dt_s="$dt" --set run.dt_safety=0.3 --set test.max_displacement_m="$disp" --set run.series_interval_s="$(python3 -c "print(100 * $dt)")" \
    --set run.output_interval_s="$(python3 -c "print($steps * $dt / 4)")" >/dev/null
  python3 - "$out/gabion/summary.json" <<'PY' >>"$out/results.jsonl"
import json, sys
s = json.load(open(sys.argv[1]))
print(json.dumps({"engine": "gabion", "nodes": s["nodes"], "links": s["links"], "steps": s["steps"], "dt_s": s["dt_s"],
                  "wall_s": s["step_loop_wall_time_s"], "peak_force_N": s["peak_force_N"],
                  "broken_links": s["broken_links"]}))
PY
  for collider in 1 0; do
    (cd "$out" && yade -j1 -n -x "$here/yade_tensile.py" "$out/gabion/netting.json" collider=$collider \
      result="$out/yade.json" >/dev/null 2>"$out/yade.log")
    python3 -c "import json;d=json.load(open('$out/yade.json'));d['collider']=$collider;print(json.dumps(d))" >>"$out/results.jsonl"
  done
done
python3 - "$out/results.jsonl" <<'PY'
import json, sys, statistics
rows = [json.loads(l) for l in open(sys.argv[1])]
def best(pred):
    return min(r["wall_s"] for r in rows if pred(r))
g = best(lambda r: r["engine"] == "gabion")
y1 = best(lambda r: r["engine"] == "yade" and r.get("collider") == 1)
y0 = best(lambda r: r["engine"] == "yade" and r.get("collider") == 0)
r0 = next(r for r in rows if r["engine"] == "gabion")
print(f"sheet: {r0['nodes']} nodes, {r0['links']} links, {r0['steps']} steps of {r0['dt_s']:.3g} s, 1 thread")
print(f"gabion              {g:8.2f} s  {1e6 * g / r0['steps']:6.2f} us/step")
print(f"yade (collider on)  {y1:8.2f} s  {1e6 * y1 / r0['steps']:6.2f} us/step   gabion {y1 / g:5.1f}x faster")
print(f"yade (collider off) {y0:8.2f} s  {1e6 * y0 / r0['steps']:6.2f} us/step   gabion {y0 / g:5.1f}x faster")
PY
