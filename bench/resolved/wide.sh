#!/usr/bin/env bash
# The hybrid on walls wider than the default one (docs/resolved.md,
# Targets): the hybrid's time goes with its resolved cells, the resolved
# wall's with all of them. Struck at 10 m/s on the centre of the face:
#   wall_54   2 x 9 x 3 cells: resolved, macro twin, and hybrids within
#             0.25 and 0.5 m of the aim, within 0.25 and 0.36 m through
#             the depth (resolve.depth "whole"), and within 0.25 m with
#             the cells below (resolve.below "cells"), on the face and
#             through the depth, and within 0.25 m with the weight of the
#             cells above (resolve.above "weight") or the plates beside
#             coming down with their cells (resolve.beside "follow"),
#             and settled for the wall's 1 s, as it is and with below
#             "cells" and beside "follow";
#   wall_150  2 x 15 x 5 cells: resolved, macro twin, and the hybrid within
#             0.5 m through the depth (the 3 x 3 front cells around the aim
#             and those behind them, 18 cells), as it is and with the macro
#             nodes moving along x, y and z and the plates across x giving,
#             and the latter within 0.25 m (10 cells);
#   wall_210  2 x 15 x 7 cells: resolved, macro twin, and hybrids within
#             0.25 and 0.36 m through the depth;
#   wall_90   2 x 15 x 3 cells: resolved, macro twin, and the hybrid within
#             0.25 m through the depth, as it is and with the macro nodes
#             moving along x, y and z and the plates across x giving, and
#             the latter within 0.5 m (18 cells);
# with --pipeline DIR, every wall is made of DIR's cell (DIR/1_cell/cell.h5)
# and its twin takes DIR's laws (DIR/law.json), and wall_54 also runs the
# 10-cell hybrid through the depth with the macro nodes along x, y and z, as
# it is and with the plates across x giving (resolve.macro_motion "xyz",
# resolve.across "gives"), in place of the variants above;
# with --laced, every wall's cells are laced once landed (micro.structure
# "lacing" at 0.15 s, docs/resolved.md, Laced) and settled until their
# bodies' rms speed is under 0.02 m/s, and so are the resolved cells of its
# hybrids (they take the wall's micro keys), and each wall's xyz/gives
# hybrids run once more with their resolved cells laced to their plates
# too (resolve.lacing.to_plates, into *_more/plates_xyz_gives_*);
# with --pull N (implies --laced), every lacing wire is pulled tight with N
# newtons while the settling goes on (lacing.pull_N; docs/resolved.md,
# Laced, Pulled tight), in the walls and their hybrids alike;
# with --base-friction MU, the walls' base and back support have friction
# MU (micro.structure "plates", docs/resolved.md, On a base with
# friction), and so have their hybrids' (resolve.plates, the same keys);
# then one table, and a chart of each hybrid's largest error against how
# many times faster than its resolved wall it ran (OUT/figures/wide_error_vs_speed_up.png).
#   bench/resolved/wide.sh [--out DIR] [--threads N] [--walls "54 90 150 210"] [--pipeline DIR] [--laced]
#                         [--pull N] [--base-friction MU]
# About two hours for wall_54 on 2 cores, most of it the resolved wall
# settling (1 s); with --pipeline of the denser cell (docs/resolved.md, A
# denser cell) about 50 minutes, the wall at rest after 0.28 s. wall_90's
# resolved wall has 1.7 times the bodies (`gabion check` of its case: up to
# 6.4 h on one thread with the longest settling); wall_210 needs a denser
# cell to stand at rest (docs/resolved.md, What is left).
# Needs the pipeline's cell and laws (README, command 1: results/pipeline).
# A run whose summary.json exists is not run again (delete it to rerun);
# one stopped by SIGTERM or Ctrl-C (its summary "interrupted") is resumed.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=$root/results/wide threads=2 walls="54 210" pipeline= laced=false pull= base_friction=
while [ $# -gt 0 ]; do
  case $1 in
    --laced) laced=true; shift ;;
    --pull) laced=true pull=$2; shift 2 ;;
    --base-friction) base_friction=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --walls) walls=$2; shift 2 ;;
    --pipeline) pipeline=$(cd "$2" && pwd); shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
. "$here/common.sh"
# (the cell and the laws of another pipeline's results, with --pipeline)
cell=()
if [ -n "$pipeline" ]; then
  [ -f "$pipeline/law.json" ] && [ -f "$pipeline/1_cell/cell.h5" ] ||
    { echo "$pipeline: no law.json or 1_cell/cell.h5 (a pipeline's results)" >&2; exit 2; }
  cell=(--set "law_file=$pipeline/law.json" --set "cell=$pipeline/1_cell/cell.h5")
fi
# (laced walls, with --laced: the hybrids' cases written by macro.resolved carry the same keys)
if $laced; then
  cell+=(--set 'resolved.lacing={"at_s": 0.15}' --set resolved.settle.at_rest_rms_speed_m_s=0.02)
  if [ -n "$pull" ]; then cell+=(--set "resolved.lacing.pull_N=$pull"); fi
fi
if [ -n "$base_friction" ]; then cell+=(--set "resolved.plates={\"friction\": $base_friction}"); fi
for w in $walls; do
  case $w in
    54)
      if [ -n "$pipeline" ]; then
        run_once wall_54 "$root/cases/macro_resolved.json" "${cell[@]}" --set 'structure.cells=[2,9,3]' \
          --set 'hybrid.within_m=[0.25]' --set hybrid.depth=whole
        h=$out/wall_54/hybrid_0/case.json
        if [ -f "$h" ]; then
          run_once wall_54_more/reach_0.25 "$h" --set resolve.depth=reach
          run_once wall_54_more/whole_xyz_0.25 "$h" --set resolve.macro_motion=xyz
          run_once wall_54_more/whole_xyz_gives_0.25 "$h" --set resolve.macro_motion=xyz --set resolve.across=gives
          $laced && run_once wall_54_more/plates_xyz_gives_0.25 "$h" --set resolve.macro_motion=xyz \
            --set resolve.across=gives --set resolve.lacing.to_plates=true
        fi
        continue
      fi
      run_once wall_54 "$root/cases/macro_resolved.json" "${cell[@]}" --set 'structure.cells=[2,9,3]' --set 'hybrid.within_m=[0.25]'
      h=$out/wall_54/hybrid_0/case.json
      if [ -f "$h" ]; then
        run_once wall_54_more/reach_0.5 "$h" --set resolve.within_m=0.5
        run_once wall_54_more/whole_0.25 "$h" --set resolve.depth=whole
        run_once wall_54_more/whole_0.36 "$h" --set resolve.depth=whole --set resolve.within_m=0.36
        run_once wall_54_more/below_0.25 "$h" --set resolve.below=cells
        run_once wall_54_more/whole_below_0.25 "$h" --set resolve.below=cells --set resolve.depth=whole
        run_once wall_54_more/weight_0.25 "$h" --set resolve.above=weight
        run_once wall_54_more/follow_0.25 "$h" --set resolve.beside=follow
        # (settled for the wall's 1 s, not until at rest)
        run_once wall_54_more/settle_1s_0.25 "$h" --set resolve.settle.until_at_rest=false --set resolve.settle.duration_s=1
        run_once wall_54_more/below_follow_1s_0.25 "$h" --set resolve.below=cells --set resolve.beside=follow \
          --set resolve.settle.until_at_rest=false --set resolve.settle.duration_s=1
      fi
      ;;
    90)
      run_once wall_90 "$root/cases/macro_resolved.json" "${cell[@]}" --set 'structure.cells=[2,15,3]' \
        --set 'hybrid.within_m=[0.25]' --set hybrid.depth=whole
      h=$out/wall_90/hybrid_0/case.json
      if [ -f "$h" ]; then
        run_once wall_90_more/whole_xyz_gives_0.25 "$h" --set resolve.macro_motion=xyz --set resolve.across=gives
        run_once wall_90_more/whole_xyz_gives_0.5 "$h" --set resolve.within_m=0.5 --set resolve.macro_motion=xyz \
          --set resolve.across=gives
        if $laced; then
          run_once wall_90_more/plates_xyz_gives_0.25 "$h" --set resolve.macro_motion=xyz --set resolve.across=gives \
            --set resolve.lacing.to_plates=true
          run_once wall_90_more/plates_xyz_gives_0.5 "$h" --set resolve.within_m=0.5 --set resolve.macro_motion=xyz \
            --set resolve.across=gives --set resolve.lacing.to_plates=true
        fi
      fi
      ;;
    150)
      run_once wall_150 "$root/cases/macro_resolved.json" "${cell[@]}" --set 'structure.cells=[2,15,5]' \
        --set 'hybrid.within_m=[0.5]' --set hybrid.depth=whole
      h=$out/wall_150/hybrid_0/case.json
      [ -f "$h" ] && run_once wall_150_more/whole_xyz_gives_0.5 "$h" --set resolve.macro_motion=xyz \
        --set resolve.across=gives
      [ -f "$h" ] && run_once wall_150_more/whole_xyz_gives_0.25 "$h" --set resolve.within_m=0.25 \
        --set resolve.macro_motion=xyz --set resolve.across=gives
      [ -f "$h" ] && $laced && run_once wall_150_more/plates_xyz_gives_0.5 "$h" --set resolve.macro_motion=xyz \
        --set resolve.across=gives --set resolve.lacing.to_plates=true
      ;;
    210)
      run_once wall_210 "$root/cases/macro_resolved.json" "${cell[@]}" --set 'structure.cells=[2,15,7]' \
        --set 'hybrid.within_m=[0.25,0.36]' --set hybrid.depth=whole
      ;;
    *) echo "unknown wall $w (54, 90, 150 or 210)" >&2; exit 2 ;;
  esac
done
python3 "$here/table.py" --wide "$out" "$curves"
