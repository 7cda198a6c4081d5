#!/usr/bin/env bash
# The joint between two cells (docs/fitting.md, The joint between two cells;
# docs/resolved.md, Where the struck cell's move is lost), on the pipeline's
# cell and law:
#   OUT/cc_x_1, OUT/cc_x_2      the cell in confined compression along x, alone
#                               and in a row of two (micro.cc, loading.axis "x",
#                               loading.cells_in_series 1 and 2);
#   OUT/uc_x_1, OUT/uc_x_2      the same unconfined (micro.uc), for comparison;
#   OUT/fit                     the joint law fitted from the CC pair (a fit
#                               case's "joint"), added to the pipeline's law:
#                               OUT/fit/law.json;
#   OUT/fit_uc                  the same from the UC pair;
#   OUT/law_plastic_joint.json  that law with plastic densification;
#   OUT/hybrid_joint_0.25, OUT/hybrid_plastic_joint_0.25,
#   OUT/hybrid_plastic_joint_across_0.25
#                               bench/resolved/run.sh's 4-cell hybrid at 10 m/s
#                               on the centre with resolve.joint "law", with
#                               plastic densification too, and with the plates
#                               across x giving too;
#   OUT/hybrid_joint_tiles_3_0.25, OUT/hybrid_joint_tiles_5_0.25,
#   OUT/hybrid_plastic_joint_tiles_3_0.25
#                               the same with the x faces' plates in 3 x 3 and
#                               5 x 5 tiles (resolve.joint_tiles), and with
#                               plastic densification in 3 x 3;
#   OUT/hybrid_xy_0.25, OUT/hybrid_xyz_0.25, OUT/hybrid_xyz_joint_tiles_3_0.25
#                               the same with the macro nodes moving along x
#                               and y, and along x, y and z
#                               (resolve.macro_motion "xy", "xyz"), the
#                               latter also with the joint in 3 x 3 tiles;
#   OUT/<scenario>/hybrid_joint_0.25, OUT/<scenario>/hybrid_plastic_joint_0.25
#                               the same on centre_6_m_s, centre_8_m_s and
#                               side_10_m_s.
#   OUT/wall_54/...             where the 54-cell wall struck while settling
#                               is there (results/wide_moving/wall_54, the
#                               first command of docs/resolved.md's table of
#                               wide walls struck while settling): its 5-cell
#                               hybrid with the joint, in 1, 3 x 3 and 5 x 5
#                               tiles, with plastic densification, and with the
#                               plates across x giving; its 10-cell hybrid
#                               (within 0.5 m) without and with the joint;
#                               and those with the macro nodes moving along
#                               x and y, or x, y and z (resolve.macro_motion),
#                               the hybrid through the depth too (its x-only
#                               row where docs/resolved.md's wall_54_more
#                               runs are there);
#   OUT/figures/wall_54_error_vs_speed_up.png
#                               each of those hybrids' largest error against
#                               its speed-up (build/bench/bench_curves).
#   bench/resolved/joint.sh [--out DIR] [--threads N]
# About 25 minutes on 2 cores, 20 more with the 54-cell wall. Needs the
# pipeline's results (README, command 1) and bench/resolved/run.sh's
# centre_10_m_s (its hybrid_1/case.json).
# A run whose summary.json exists is not run again (delete it to rerun);
# one stopped by SIGTERM or Ctrl-C (its summary "interrupted") is resumed.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=$root/results/joint threads=2
while [ $# -gt 0 ]; do
  case $1 in
    --out) out=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
. "$here/common.sh"
hybrid=$root/results/speed_error/centre_10_m_s/hybrid_1/case.json
[ -f "$hybrid" ] || { echo "no $hybrid: run bench/resolved/run.sh first" >&2; exit 2; }
for n in 1 2; do
  run_once "cc_x_$n" "$root/results/pipeline/2_cc/case.json" --set loading.axis=x \
    --set loading.cells_in_series=$n --set loading.strain=0.15 --set 'loading.unload_at_strain=[]'
  run_once "uc_x_$n" "$root/results/pipeline/2_uc/case.json" --set loading.axis=x \
    --set loading.cells_in_series=$n --set loading.strain=0.2
done
# The fit cases: the joint from each pair, the pipeline's other laws kept.
python3 - "$out" "$root/results/pipeline/law.json" <<'PY'
import json, sys
out, law = sys.argv[1], sys.argv[2]
for name, pair, group in (("fit", "cc", "axial"), ("fit_uc", "uc", "uc")):
    curve = lambda n: {"file": f"{pair}_x_{n}/result.h5", "x_dataset": f"/curves/{group}/displacement_m",
                       "y_dataset": f"/curves/{group}/force_N"}
    json.dump({"format": "gabion.case/1", "kind": "fit",
               "description": f"the joint between two cells from {pair.upper()} along x of one cell and a row of two",
               "material": {"name": "front"}, "base_law": {"file": law, "material": "front"},
               "joint": {"cell": curve(1), "row": curve(2), "cells_in_series": 2}},
              open(f"{out}/{name}.json", "w"), indent=1)
PY
run_once fit "$out/fit.json"
run_once fit_uc "$out/fit_uc.json"
python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
law = json.load(open(f"{out}/fit/law.json"))
law["materials"]["front"]["axial"]["densification"] = "plastic"
json.dump(law, open(f"{out}/law_plastic_joint.json", "w"), indent=1)
PY
run_once hybrid_joint_0.25 "$hybrid" --law "$out/fit/law.json" --set resolve.joint=law
run_once hybrid_plastic_joint_0.25 "$hybrid" --law "$out/law_plastic_joint.json" --set resolve.joint=law
run_once hybrid_plastic_joint_across_0.25 "$hybrid" --law "$out/law_plastic_joint.json" --set resolve.joint=law \
  --set resolve.across=gives
# The plates behind cut into tiles, each with its share of the joint law.
for n in 3 5; do
  run_once "hybrid_joint_tiles_${n}_0.25" "$hybrid" --law "$out/fit/law.json" --set resolve.joint=law \
    --set resolve.joint_tiles=$n
done
run_once hybrid_plastic_joint_tiles_3_0.25 "$hybrid" --law "$out/law_plastic_joint.json" --set resolve.joint=law \
  --set resolve.joint_tiles=3
# The macro nodes moving along x and y: the plates beside follow their cells pushed aside.
run_once hybrid_xy_0.25 "$hybrid" --law "$root/results/pipeline/law.json" --set resolve.macro_motion=xy
run_once hybrid_xyz_0.25 "$hybrid" --law "$root/results/pipeline/law.json" --set resolve.macro_motion=xyz
run_once hybrid_xyz_joint_tiles_3_0.25 "$hybrid" --law "$out/fit/law.json" --set resolve.joint=law \
  --set resolve.joint_tiles=3 --set resolve.macro_motion=xyz
# The other scenarios of bench/resolved/run.sh: the joint, and with plastic densification.
for s in centre_6_m_s centre_8_m_s side_10_m_s; do
  h=$root/results/speed_error/$s/hybrid_1/case.json
  [ -f "$h" ] || { echo "no $h: run bench/resolved/run.sh first" >&2; continue; }
  run_once "$s/hybrid_joint_0.25" "$h" --law "$out/fit/law.json" --set resolve.joint=law
  run_once "$s/hybrid_plastic_joint_0.25" "$h" --law "$out/law_plastic_joint.json" --set resolve.joint=law
done
# The 54-cell wall struck while settling, where it is there.
wide=$root/results/wide_moving/wall_54
if [ -f "$wide/hybrid_0/case.json" ]; then
  wide_run() {
    local name=$1 law=$2; shift 2
    run_once "wall_54/$name" "$wide/hybrid_0/case.json" --law "$law" --set resolve.settle.until_at_rest=false "$@"
  }
  for n in 1 3 5; do
    wide_run "joint_tiles_${n}_0.25" "$out/fit/law.json" --set resolve.joint=law --set resolve.joint_tiles=$n
  done
  wide_run plastic_joint_tiles_3_0.25 "$out/law_plastic_joint.json" --set resolve.joint=law --set resolve.joint_tiles=3
  wide_run plastic_joint_tiles_3_across_0.25 "$out/law_plastic_joint.json" --set resolve.joint=law \
    --set resolve.joint_tiles=3 --set resolve.across=gives
  wide_run reach_0.5 "$root/results/pipeline/law.json" --set resolve.within_m=0.5
  wide_run reach_0.5_joint_tiles_3 "$out/fit/law.json" --set resolve.within_m=0.5 --set resolve.joint=law \
    --set resolve.joint_tiles=3
  wide_run xy_0.25 "$root/results/pipeline/law.json" --set resolve.macro_motion=xy
  wide_run xyz_0.25 "$root/results/pipeline/law.json" --set resolve.macro_motion=xyz
  wide_run xyz_joint_tiles_3_0.25 "$out/fit/law.json" --set resolve.joint=law --set resolve.joint_tiles=3 \
    --set resolve.macro_motion=xyz
  wide_run plastic_xyz_joint_tiles_3_0.25 "$out/law_plastic_joint.json" --set resolve.joint=law \
    --set resolve.joint_tiles=3 --set resolve.macro_motion=xyz
  wide_run reach_0.5_xyz "$root/results/pipeline/law.json" --set resolve.within_m=0.5 --set resolve.macro_motion=xyz
  wide_run reach_0.5_xyz_joint_tiles_3 "$out/fit/law.json" --set resolve.within_m=0.5 --set resolve.joint=law \
    --set resolve.joint_tiles=3 --set resolve.macro_motion=xyz
  wide_run whole_0.25_xyz "$root/results/pipeline/law.json" --set resolve.depth=whole --set resolve.macro_motion=xyz
  wide_run whole_0.25_xyz_across "$root/results/pipeline/law.json" --set resolve.depth=whole \
    --set resolve.macro_motion=xyz --set resolve.across=gives
fi
for f in fit fit_uc; do grep "^fit: joint" "$out/$f.log" || true; done
python3 - "$root" "$out" <<'PY'
import json, math, os, subprocess, sys
root, out = sys.argv[1], sys.argv[2]
keys = ["peak_force_N", "max_penetration_m", "contact_duration_s", "max_back_face_displacement_m"]


def load(d):
    try:
        return json.load(open(f"{d}/summary.json"))
    except OSError:
        return None


def rows(scenario, runs, first="", wall_dir=None):
    """A table row per run found: its errors against the scenario's resolved
    wall, its wall time and how many times faster than the wall it ran.
    Returns (label, times faster, largest |error| in %) of each."""
    wall = load(wall_dir or f"{root}/results/speed_error/{scenario}/resolved")
    points = []
    for label, d in runs:
        s = load(d)
        if wall is None or s is None:
            continue
        errors = [100 * (s[k] / wall[k] - 1) for k in keys]
        err = " | ".join(f"{e:+.1f} %" for e in errors)
        fast = wall["wall_time_s"] / s["wall_time_s"]
        print(f"| {first}{label} | {err} | {s['outcome']} | {s['wall_time_s']:.0f} | {fast:.1f} |")
        points.append((label, fast, max(abs(e) for e in errors)))
    return points


head = "peak force | penetration | contact | back face | outcome | wall time s | x faster |"
print(f"| 4-cell hybrid, 10 m/s on the centre | {head}")
print("|---|---|---|---|---|---|---|---|")
rows("centre_10_m_s", (("as before", f"{root}/results/speed_error/centre_10_m_s/hybrid_1"),
                       ("plastic densification", f"{out}/plastic_densification_0.25"),
                       ("joint", f"{out}/hybrid_joint_0.25"),
                       ("plastic densification, joint", f"{out}/hybrid_plastic_joint_0.25"),
                       ("plastic densification, joint, plates across x giving",
                        f"{out}/hybrid_plastic_joint_across_0.25"),
                       ("joint, plates behind in 3 x 3 tiles", f"{out}/hybrid_joint_tiles_3_0.25"),
                       ("joint, plates behind in 5 x 5 tiles", f"{out}/hybrid_joint_tiles_5_0.25"),
                       ("plastic densification, joint in 3 x 3 tiles", f"{out}/hybrid_plastic_joint_tiles_3_0.25"),
                       ("macro nodes along x and y", f"{out}/hybrid_xy_0.25"),
                       ("macro nodes along x, y and z", f"{out}/hybrid_xyz_0.25"),
                       ("macro nodes along x, y and z, joint in 3 x 3 tiles", f"{out}/hybrid_xyz_joint_tiles_3_0.25")))
others = [s for s in ("centre_6_m_s", "centre_8_m_s", "side_10_m_s")
          if load(f"{root}/results/speed_error/{s}/resolved") is not None]
if others:
    print()
    print(f"| scenario | 4-cell hybrid | {head}")
    print("|---|---|---|---|---|---|---|---|---|")
for scenario in others:
    rows(scenario, (("as before", f"{root}/results/speed_error/{scenario}/hybrid_1"),
                    ("joint", f"{out}/{scenario}/hybrid_joint_0.25"),
                    ("plastic densification, joint", f"{out}/{scenario}/hybrid_plastic_joint_0.25")),
         first=f"{scenario} | ")
wide = f"{root}/results/wide_moving/wall_54"
if load(f"{wide}/resolved") is not None:
    print()
    print(f"| 54-cell wall struck while settling, hybrid | {head}")
    print("|---|---|---|---|---|---|---|---|")
    points = rows(None, (("5 cells", f"{wide}/hybrid_0"),
                ("5 cells, joint", f"{out}/wall_54/joint_tiles_1_0.25"),
                ("5 cells, joint in 3 x 3 tiles", f"{out}/wall_54/joint_tiles_3_0.25"),
                ("5 cells, joint in 5 x 5 tiles", f"{out}/wall_54/joint_tiles_5_0.25"),
                ("5 cells, plastic densification, joint in 3 x 3 tiles", f"{out}/wall_54/plastic_joint_tiles_3_0.25"),
                ("5 cells, plastic densification, joint in 3 x 3 tiles, plates across x giving",
                 f"{out}/wall_54/plastic_joint_tiles_3_across_0.25"),
                ("10 cells (within 0.5 m)", f"{out}/wall_54/reach_0.5"),
                ("10 cells, joint in 3 x 3 tiles", f"{out}/wall_54/reach_0.5_joint_tiles_3"),
                ("5 cells, macro nodes along x and y", f"{out}/wall_54/xy_0.25"),
                ("5 cells, macro nodes along x, y and z", f"{out}/wall_54/xyz_0.25"),
                ("5 cells, macro nodes along x, y and z, joint in 3 x 3 tiles", f"{out}/wall_54/xyz_joint_tiles_3_0.25"),
                ("5 cells, macro nodes along x, y and z, plastic densification, joint in 3 x 3 tiles",
                 f"{out}/wall_54/plastic_xyz_joint_tiles_3_0.25"),
                ("10 cells, macro nodes along x, y and z", f"{out}/wall_54/reach_0.5_xyz"),
                ("10 cells, macro nodes along x, y and z, joint in 3 x 3 tiles",
                 f"{out}/wall_54/reach_0.5_xyz_joint_tiles_3"),
                ("10 cells through the depth", f"{root}/results/wide_moving/wall_54_more/whole_0.25"),
                ("10 cells through the depth, macro nodes along x, y and z", f"{out}/wall_54/whole_0.25_xyz"),
                ("10 cells through the depth, macro nodes along x, y and z, plates across x giving",
                 f"{out}/wall_54/whole_0.25_xyz_across")),
         wall_dir=f"{wide}/resolved")
    # The chart: each hybrid's largest error against its speed-up, those
    # with x-only macro nodes apart from those moving across x.
    curves = f"{root}/build/bench/bench_curves"
    if points and os.path.exists(curves):
        series = []
        for name, across in (("x-only macro nodes", False), ("macro nodes moving across x", True)):
            pts = sorted((math.log10(f), e) for label, f, e in points if ("macro nodes" in label) == across)
            if pts:
                series.append(f"{name}=" + ",".join(f"{x:.4f}:{y:.3f}" for x, y in pts))
        series.append("line:target: within 5 % at a tenth of the time or less=1:0,1:5,2:5")
        os.makedirs(f"{out}/figures", exist_ok=True)
        subprocess.run([curves, "scatter", f"{out}/figures/wall_54_error_vs_speed_up.png",
                        "54-cell wall struck while settling: each hybrid's largest error against its speed-up",
                        "times faster than the resolved wall, log10", "largest |error| of the four keys (%)"] + series,
                       check=True)
PY
