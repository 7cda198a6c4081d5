#!/usr/bin/env bash
# Closing the twin's gap on the impact law (docs/resolved.md): the impact
# law identified on the struck cell in place, in the resolved wall (force on
# the boulder against its indentation of the struck cell, the boulder's
# penetration less that cell's own move), instead of on the free-standing
# UCI cell; then the macro twins of the wall run again with it, at every
# speed bench/resolved/run.sh ran.
#   bench/resolved/in_place.sh [--out DIR]
# Needs bench/resolved/run.sh's runs in DIR: it fits on the resolved wall of
# floor_10_m_s and compares with the other runs of the same wall (the 10 m/s
# one is centre_10_m_s: two equally valid runs, so the law is not judged on
# the curve it was fitted to). Candidates: elastic-perfectly plastic,
# bilinear and softening, chosen by BIC; the search is NLopt's ISRES (the
# softening law's five parameters have local optima that DIRECT-L's default
# 400 evaluations stop in). Then the impact law with the rate term
# (softening_rate: the overstress c r^2 of the indentation rate r, read from
# the curves' time axis), fitted on the walls at 6 and 10 m/s together
# (centre_6_m_s, floor_10_m_s) and judged at 13 m/s, a speed it has not seen,
# as well as on the other runs. Then the rate law identified on the walls'
# histories at 6 and 10 m/s (fit.macro: force and penetration against time,
# the twin run inside the objective), the axial laws' densification made
# plastic (DENSIFICATION=elastic keeps the pipeline's); and once more with
# the axial laws viscous (VISCOSITY). Where bench/resolved/cc_rate.sh has
# run, the axial laws also get the momentum flux it identified on the cell
# alone: the histories' law with it (hist_flux), and that law's impact law
# fitted anew on the histories with it (fit_flux); and, where cc_rate.sh
# has fitted the axial law on a cycle past the densification onset, the
# impact law fitted anew with that whole axial law (fit_cell: the cell's
# compressions alone give the axial law). Prints a table; draws
# DIR/in_place/figures/.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=$root/results/speed_error
while [ $# -gt 0 ]; do
  case $1 in
    --out) out=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
out=$(cd "$out" && pwd)
gabion=${GABION:-$root/build/gabion}
curves=${CURVES:-$root/build/bench/bench_curves}
fit_from=$out/floor_10_m_s/result.h5
law=$(python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['law_file'])" "$out/centre_10_m_s/macro_twin/case.json")
[ -f "$fit_from" ] && [ -f "$law" ] || { echo "run bench/resolved/run.sh first" >&2; exit 2; }
dir=$out/in_place
mkdir -p "$dir/figures"
# Runs DIR/NAME.json into DIR/NAME and prints its answer line.
run_case() {  # NAME
  "$gabion" run "$dir/$1.json" -q -o "$dir/$1" >"$dir/$1.log" 2>&1 || { tail -n 3 "$dir/$1.log" >&2; exit 1; }
  tail -n 1 "$dir/$1.log"
}
# A curve entry of a resolved wall's indentation curve; with "time", its time axis too.
curve() {  # FILE VELOCITY [time]
  printf '{"file": "%s", "path": "cyclic", "velocity_m_s": %s, "x_dataset": "/curves/impact/indentation_m", "y_dataset": "/curves/impact/force_N"%s}' \
    "$1" "$2" "$([ "${3:-}" = time ] && echo ', "t_dataset": "/curves/impact/time_s"')"
}
# The pipeline's laws with the impact law of material "front" fitted anew
# (no lock-up within the indentation the wall shows: half the edge), run;
# its chart copied to figures/FIGURE.
impact_fit() {  # NAME GLOBAL_EVALUATIONS MODELS CURVES BOUNDS FIGURE
  cat >"$dir/$1.json" <<JSON
{"format": "gabion.case/1", "kind": "fit", "seed": 1,
 "material": {"name": "front"},
 "base_law": {"file": "$law", "material": "front"},
 "lockup": {"strain": 0.5},
 "optimizer": {"global": "GN_ISRES", "global_max_evaluations": $2},
 "impact": {"models": $3, "curves": $4, "bounds": $5}}
JSON
  run_case "$1"
  cp "$dir/$1/fit_impact.png" "$dir/figures/$6"
}
impact_fit fit 4000 '["elastic_perfectly_plastic", "bilinear", "softening"]' "[$(curve "$fit_from" 10)]" \
  '{"stiffness_N_m": [1e5, 1e9], "yield_force_N": [1e3, 1e6], "hardening_stiffness_N_m": [0, 1e7]}' in_place_fit.png
# The rate term: the walls at 6 and 10 m/s, each curve with its time axis.
slow=$out/centre_6_m_s/resolved/result.h5
if [ -f "$slow" ]; then
  impact_fit fit_rate 10000 '["softening", "softening_rate"]' "[$(curve "$fit_from" 10 time), $(curve "$slow" 6 time)]" \
    '{"stiffness_N_m": [1e5, 1e9], "yield_force_N": [1e3, 1e6]}' in_place_rate_fit.png
fi
# The same law identified on the walls' histories instead (fit.macro): the
# twin itself runs inside the objective, at 6 and 10 m/s, against the
# force on the boulder and its penetration from first contact; the seven
# parameters of the rate law, from the rate fit's law (its lock-up), with
# the axial laws' densification plastic (DENSIFICATION, "plastic" or
# "elastic": a compacted cell keeps its compaction, docs/formats.md).
if [ -f "$slow" ] && [ -f "$dir/fit_rate/law.json" ]; then
  # The same fit once more with the axial laws viscous (VISCOSITY N s/m,
  # default 1e4: a dashpot in parallel while the cell is in contact,
  # docs/formats.md), against the back face's overshoot: fit_visc.
  python3 - "$out" "$dir" "${DENSIFICATION:-plastic}" "${VISCOSITY:-1e4}" <<'PY'
import json, os, sys
out, d, densification, eta = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
law = json.load(open(f"{d}/fit_rate/law.json"))
for m in law["materials"].values():
    m["axial"]["densification"] = densification
# The twin with these laws, with each axial law's `axial` keys changed: NAME_law.json, NAME_twin.json.
def twin_with(name, axial):
    for m in law["materials"].values():
        m["axial"].update(axial)
    json.dump(law, open(f"{d}/{name}_law.json", "w"), indent=1)
    twin = json.load(open(f"{out}/centre_10_m_s/macro_twin/case.json"))
    twin["law_file"] = f"{d}/{name}_law.json"
    json.dump(twin, open(f"{d}/{name}_twin.json", "w"), indent=1)
twin_with("hist", {})
twin_with("visc", {"viscosity_N_s_m": eta})
# The cell's momentum flux from bench/resolved/cc_rate.sh (the viscosity off again).
cc = f"{out}/cc_rate/fit/law.json"
if os.path.isfile(cc):
    a = next(iter(json.load(open(cc))["materials"].values()))["axial"]
    flux = {k: a[k] for k in ("momentum_flux_kg_m", "momentum_flux_growth_m") if k in a}
    json.dump(flux, open(f"{d}/flux.json", "w"))
    twin_with("flux", dict(flux, viscosity_N_s_m=0.0))
# The axial law fitted on the CC cycle past the onset and the fast CCs (cc_rate.sh), whole.
cell = f"{out}/cc_rate/fit_cycle/law.json"
if os.path.isfile(cell):
    axial = next(iter(json.load(open(cell))["materials"].values()))["axial"]
    for m in law["materials"].values():
        m["axial"] = {}
    twin_with("cell", axial)
imp = "laws.materials.front.impact."
def p(name, key, lo, hi, scale="auto"):
    return {"name": name, "set": imp + key, "bounds": [lo, hi], "scale": scale}
def history(h5, quantity, dataset):
    return {"quantity": quantity, "file": h5, "x_dataset": "/curves/impact/time_s", "y_dataset": "/curves/impact/" + dataset}
scenarios = []
for v, h5 in ((6, f"{out}/centre_6_m_s/resolved/result.h5"), (10, f"{out}/floor_10_m_s/result.h5")):
    scenarios.append({"name": f"{v} m/s", "set": {"boulder.velocity_m_s": v},
                      "curves": [history(h5, "boulder_force_N", "force_N"), history(h5, "penetration_m", "penetration_m")]})
fit = {"format": "gabion.case/1", "kind": "fit.macro", "seed": 1, "macro_case": "hist_twin.json",
           "parameters": [p("stiffness", "stiffness_N_m", 3e5, 1e7), p("static yield force", "yield_force_N", 3e3, 6e4),
                          p("rate coefficient", "rate_coefficient_N_s2_m2", 100, 2e4),
                          p("rate growth", "rate_growth_m", 0.005, 0.15),
                          p("softening onset", "softening_onset_m", 0, 0.1, "linear"),
                          p("softening stiffness", "softening_stiffness_N_m", 1e5, 1e9),
                          p("residual force", "residual_force_N", 500, 2e4)],
           "scenarios": scenarios,
           "optimizer": {"global": "GN_ISRES", "global_max_evaluations": 4000, "local": "LN_SBPLX",
                         "local_max_evaluations": 1000}}
json.dump(fit, open(f"{d}/fit_hist.json", "w"), indent=1)
json.dump(dict(fit, macro_case="visc_twin.json"), open(f"{d}/fit_visc.json", "w"), indent=1)
if os.path.isfile(cc):
    json.dump(dict(fit, macro_case="flux_twin.json"), open(f"{d}/fit_flux.json", "w"), indent=1)
if os.path.isfile(cell):
    json.dump(dict(fit, macro_case="cell_twin.json"), open(f"{d}/fit_cell.json", "w"), indent=1)
PY
  run_case fit_hist
  for png in "$dir"/fit_hist/fit_macro_*.png; do cp "$png" "$dir/figures/in_place_hist_$(basename "$png" .png | sed 's/^fit_macro_//').png"; done
  run_case fit_visc
  if [ -f "$dir/flux.json" ]; then
    # The histories' law with the cell's momentum flux, not refitted; then refitted with it.
    python3 -c "import json, sys; l = json.load(open(sys.argv[1])); f = json.load(open(sys.argv[2]))
for m in l['materials'].values(): m['axial'].update(f)
json.dump(l, open(sys.argv[3], 'w'), indent=1)" "$dir/fit_hist/law.json" "$dir/flux.json" "$dir/hist_flux_law.json"
    run_case fit_flux
  fi
  [ -f "$dir/fit_cell.json" ] && run_case fit_cell
fi
for s in "$out"/centre_*_m_s "$out"/side_*_m_s; do
  [ -f "$s/summary.json" ] || continue
  name=$(basename "$s")
  for fit in fit fit_rate fit_hist fit_visc hist_flux fit_flux fit_cell; do
    law_file=$dir/$fit/law.json
    [ "$fit" = hist_flux ] && law_file=$dir/hist_flux_law.json
    [ -f "$law_file" ] || continue
    tag=_${fit#fit_}
    [ "$fit" = fit ] && tag=
    "$gabion" run "$s/macro_twin/case.json" --law "$law_file" -q -o "$dir/twin${tag}_$name" >"$dir/twin${tag}_$name.log" 2>&1 ||
      echo "   $name: the twin with the law of $fit failed: $(tail -n 1 "$dir/twin${tag}_$name.log")" >&2
  done
done
python3 "$here/table.py" --in-place "$out" "$([ -x "$curves" ] && echo "$curves")"
# Force on the boulder at 10 m/s: the resolved wall and both twins.
if [ -x "$curves" ] && [ -f "$dir/twin_centre_10_m_s/result.h5" ]; then
  "$curves" plot "$dir/figures/in_place_force_time.png" "Force on the boulder, 10 m/s on the centre" "time (s)" "force (N)" \
    "resolved wall=$out/centre_10_m_s/resolved/result.h5:/curves/impact/time_s:/curves/impact/force_N" \
    "macro twin, UCI impact law=$out/centre_10_m_s/macro_twin/result.h5:/series/time_s:/series/boulder_force_N" \
    "macro twin, impact law fitted in the wall=$dir/twin_centre_10_m_s/result.h5:/series/time_s:/series/boulder_force_N"
fi
# Force on the boulder at 13 m/s (the speed the rate law was not fitted at).
if [ -x "$curves" ] && [ -f "$dir/twin_rate_centre_13_m_s/result.h5" ]; then
  "$curves" plot "$dir/figures/in_place_rate_force_time.png" "Force on the boulder, 13 m/s on the centre" "time (s)" "force (N)" \
    "resolved wall=$out/centre_13_m_s/resolved/result.h5:/curves/impact/time_s:/curves/impact/force_N" \
    "macro twin, impact law fitted at 10 m/s=$dir/twin_centre_13_m_s/result.h5:/series/time_s:/series/boulder_force_N" \
    "macro twin, rate law fitted at 6 and 10 m/s=$dir/twin_rate_centre_13_m_s/result.h5:/series/time_s:/series/boulder_force_N"
fi
