#!/usr/bin/env bash
# The lab tests' validation and speed-against-error runs (docs/validation.md,
# docs/speed-vs-error.md), on the default cell, with the README's build.
#   bench/lab/run.sh [validation|speed|budget|all] [--out DIR] [--threads N]
# validation: CC with and without the F_lim cap, UC at three frictions, UCI at
#   8-15 m/s (and friction 0.3 / 0.8 at 12 m/s), UCI at 8-30 m/s with contacts
#   ten times stiffer, the interface shear; figures in OUT/figures.
# speed: CC at several lid speeds and netting mass scalings, and UCI at
#   several time steps, each against a slow reference run (curve error and
#   wall time, OUT/speed.jsonl).
# budget: the four default cases (CC, UC, UCI at four velocities, shear) on
#   the default cell, two processes at a time on the machine's two cores,
#   and the wall time of the whole (the lab tests' speed target).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
what=all out=${TMPDIR:-/tmp}/gabion-bench-lab threads=2
while [ $# -gt 0 ]; do
  case $1 in
    validation|speed|budget|all) what=$1; shift ;;
    --out) out=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
gabion=${GABION:-$root/build/gabion}
curves=${CURVES:-$root/build/bench/bench_curves}
[ -x "$gabion" ] && [ -x "$curves" ] || { echo "build first (scripts/build.sh)" >&2; exit 2; }
mkdir -p "$out/figures"
cases=$root/cases

# The default cell, once.
[ -f "$out/cell/cell.h5" ] || "$gabion" run "$cases/micro_cell.json" -q -o "$out/cell" >/dev/null
cell="--set cell=$out/cell/cell.h5"
run() { local dir=$1; shift; [ -f "$out/$dir/summary.json" ] || "$gabion" run "$@" -q -o "$out/$dir" >/dev/null || true; }
# Two runs at a time, one thread each (background jobs).
pair() { "$@" & }

if [ "$what" = budget ]; then
  rm -rf "$out/budget"
  start=$(date +%s.%N)
  ( "$gabion" run "$cases/micro_shear.json" $cell -q -o "$out/budget/shear" >/dev/null ) &
  "$gabion" run "$cases/micro_cc.json" $cell -q -o "$out/budget/cc" >/dev/null
  "$gabion" run "$cases/micro_uci.json" $cell -q -o "$out/budget/uci" >/dev/null
  "$gabion" run "$cases/micro_uc.json" $cell -q -o "$out/budget/uc" >/dev/null
  wait
  end=$(date +%s.%N)
  python3 -c "print('budget: CC, UC, UCI at 4 velocities and shear in %.1f s on 2 processes' % ($end - $start))"
  for t in cc uc uci shear; do python3 -c "import json; s=json.load(open('$out/budget/$t/summary.json')); print('  $t:', s['status'], round(s['wall_time_s'], 1), 's')"; done
  exit 0
fi

if [ "$what" != speed ]; then
  pair run cc "$cases/micro_cc.json" $cell --set loading.unload_at_strain=[]
  # The rock crushing at its own contacts (F_lim), not under the wires; its
  # plastic overlaps may pass half a member's radius.
  pair run cc_flim "$cases/micro_cc.json" $cell --set loading.unload_at_strain=[] --set 'materials={"rock": {"normal_force_limit_N": 300}}' \
    --set 'contact_pairs=[{"materials": ["rock", "netting"], "normal_force_limit_N": "none"}]' --set 'run={"max_overlap_ratio": 1.0}'
  wait
  for f in 0.3 0.5 0.8; do pair run uc_f$f "$cases/micro_uc.json" $cell --set loading.strain=0.2 --set "materials={\"rock\": {\"friction\": $f}}"; done
  wait
  run uci "$cases/micro_uci.json" $cell --threads "$threads"
  for f in 0.3 0.8; do pair run uci_f$f "$cases/micro_uci.json" $cell --set velocities_m_s=[12] --set "materials={\"rock\": {\"friction\": $f}}"; done
  wait
  run uci_stiff "$cases/micro_uci.json" $cell --threads "$threads" --set velocities_m_s=[8,15,20,30] \
    --set 'materials={"rock": {"normal_stiffness_N_m": 1e7, "shear_stiffness_N_m": 2.5e6}, "netting": {"normal_stiffness_N_m": 1e7, "shear_stiffness_N_m": 2.5e6}}' \
    --set 'plates={"normal_stiffness_N_m": 1e7, "shear_stiffness_N_m": 2.5e6}'
  run shear "$cases/micro_shear.json" $cell
  fig=$out/figures
  "$curves" plot "$fig/cc_flim.png" "CC: constant contact stiffness against the F_lim cap" "lid displacement (mm)" "axial force (kN)" \
    "k_n constant=$out/cc/result.h5:/curves/axial/displacement_m:/curves/axial/force_N:1000:0.001" \
    "F_lim 300 N=$out/cc_flim/result.h5:/curves/axial/displacement_m:/curves/axial/force_N:1000:0.001"
  "$curves" plot "$fig/uc_friction.png" "UC: the rock's friction" "lid displacement (mm)" "axial force (kN)" \
    "f 0.3=$out/uc_f0.3/result.h5:/curves/uc/displacement_m:/curves/uc/force_N:1000:0.001" \
    "f 0.5=$out/uc_f0.5/result.h5:/curves/uc/displacement_m:/curves/uc/force_N:1000:0.001" \
    "f 0.8=$out/uc_f0.8/result.h5:/curves/uc/displacement_m:/curves/uc/force_N:1000:0.001"
  "$curves" plot "$fig/uci_velocity.png" "UCI: force on the boulder at 8-15 m/s" "time (ms)" "force (kN)" \
    $(for v in 8 10 12 15; do echo "${v}m/s=$out/uci/v$v/result.h5:/curves/impact/time_s:/curves/impact/force_N:1000:0.001"; done)
  "$curves" plot "$fig/uci_friction.png" "UCI at 12 m/s: the rock's friction" "time (ms)" "force (kN)" \
    "f 0.3=$out/uci_f0.3/result.h5:/curves/impact/time_s:/curves/impact/force_N:1000:0.001" \
    "f 0.5=$out/uci/v12/result.h5:/curves/impact/time_s:/curves/impact/force_N:1000:0.001" \
    "f 0.8=$out/uci_f0.8/result.h5:/curves/impact/time_s:/curves/impact/force_N:1000:0.001"
  "$curves" plot "$fig/uci_stiff.png" "UCI at 8-30 m/s, contacts ten times stiffer" "time (ms)" "force (kN)" \
    $(for v in 8 15 20 30; do echo "${v}m/s=$out/uci_stiff/v$v/result.h5:/curves/impact/time_s:/curves/impact/force_N:1000:0.001"; done)
  "$curves" plot "$fig/uci_penetration.png" "UCI: force against penetration" "penetration (mm)" "force (kN)" \
    $(for v in 8 15; do echo "${v}m/s=$out/uci/v$v/result.h5:/curves/impact/penetration_m:/curves/impact/force_N:1000:0.001"; done) \
    $(for v in 20 30; do echo "${v}m/s_stiff=$out/uci_stiff/v$v/result.h5:/curves/impact/penetration_m:/curves/impact/force_N:1000:0.001"; done)
  cp "$out/cc/cc_lateral.png" "$fig/cc_lateral.png"
  cp "$out/shear/shear_curve.png" "$fig/shear_curve.png"
  python3 "$here/table.py" validation "$out"
fi

if [ "$what" != validation ]; then
  # CC: a slow reference (lid at 0.025 m/s, nodes unscaled), then lid speed and mass scaling.
  base="$cases/micro_cc.json $cell --set loading.unload_at_strain=[]"
  pair run speed/cc_ref $base --set loading.velocity_m_s=0.025 --set netting_mass_scale=1
  pair run speed/cc_v0.05_s8 $base --set loading.velocity_m_s=0.05
  wait
  for v in 0.1 0.2; do pair run speed/cc_v${v}_s8 $base --set loading.velocity_m_s=$v; done
  wait
  for s in 1 32; do pair run speed/cc_v0.1_s$s $base --set netting_mass_scale=$s; done
  wait
  # Twins: the default settings at a step 5 % shorter, an equally valid run
  # whose difference is the floor of any comparison (the moment force chains
  # give way is not the same in any two trajectories).
  pair run speed/cc_v0.1_s8_twin $base --set 'run={"dt_safety": 0.19}'
  pair run speed/uci_dt0.2_twin "$cases/micro_uci.json" $cell --set velocities_m_s=[12] --set run.dt_safety=0.19
  wait
  # UCI at 12 m/s: a reference at dt_safety 0.05, then the step, and mass scaling.
  ubase="$cases/micro_uci.json $cell --set velocities_m_s=[12]"
  pair run speed/uci_ref $ubase --set run.dt_safety=0.05
  pair run speed/uci_dt0.1 $ubase --set run.dt_safety=0.1
  wait
  pair run speed/uci_dt0.2 $ubase
  pair run speed/uci_dt0.4 $ubase --set run.dt_safety=0.4
  wait
  run speed/uci_dt0.2_s8 $ubase --set netting_mass_scale=8
  python3 "$here/table.py" speed "$out"
  "$curves" plot "$out/figures/speed_cc.png" "CC: lid speed and mass scaling" "lid displacement (mm)" "axial force (kN)" \
    $(for r in ref v0.05_s8 v0.1_s8 v0.2_s8 v0.1_s1 v0.1_s32; do echo "$r=$out/speed/cc_$r/result.h5:/curves/axial/displacement_m:/curves/axial/force_N:1000:0.001"; done)
  "$curves" plot "$out/figures/speed_uci.png" "UCI at 12 m/s: time step and mass scaling" "time (ms)" "force (kN)" \
    $(for r in ref dt0.1 dt0.2 dt0.4 dt0.2_s8; do echo "$r=$out/speed/uci_$r/result.h5:/curves/impact/time_s:/curves/impact/force_N:1000:0.001"; done)
fi
echo "figures: $out/figures"
