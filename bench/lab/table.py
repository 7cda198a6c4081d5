#!/usr/bin/env python3
"""Tables of bench/lab/run.sh: the validation runs' headline values, and the
speed runs' curve error (bench_curves error) against wall time."""
import json
import os
import subprocess
import sys


def summary(path):
    with open(os.path.join(path, "summary.json")) as f:
        return json.load(f)


def fmt(v, digits=3):
    if isinstance(v, bool) or v is None:
        return str(v)
    if isinstance(v, (int, float)):
        return f"{v:.{digits}g}"
    return str(v)


def validation(out):
    print("| run | peak force (kN) | at (mm) | final force (kN) | power-law exponent | lateral coefficient | drops | kinetic/work | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for run in ["cc", "cc_flim", "uc_f0.3", "uc_f0.5", "uc_f0.8"]:
        s = summary(os.path.join(out, run))
        print(f"| {run} | {fmt(s['peak_force_N'] / 1e3)} | {fmt(1e3 * s['displacement_at_peak_m'])} | "
              f"{fmt(s['final_force_N'] / 1e3)} | {fmt(s['power_law_exponent'])} | "
              f"{fmt(s.get('lateral_reaction_coefficient', '-'))} | {s.get('drop_count', '-')} | "
              f"{fmt(s['kinetic_to_work_ratio'])} | {fmt(s['step_loop_wall_time_s'])} |")
    print()
    print("| run | velocity (m/s) | energy (kJ) | peak force (kN) | peak base force (kN) | penetration (mm) | contact (ms) | rebound (m/s) | broken wires | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    rows = [("uci", f"v{v}") for v in (8, 10, 12, 15)] + [("uci_f0.3", ""), ("uci_f0.8", "")] + \
           [("uci_stiff", f"v{v}") for v in (8, 15, 20, 30)]
    for run, sub in rows:
        path = os.path.join(out, run, sub)
        s = summary(path)
        if s.get("status") != "ok":
            print(f"| {run} {sub} | {s.get('velocity_m_s', '')} | failed: {s.get('message', '')[:80]} |")
            continue
        print(f"| {run} {sub} | {fmt(s['velocity_m_s'])} | {fmt(s['impact_energy_J'] / 1e3)} | {fmt(s['peak_force_N'] / 1e3)} | "
              f"{fmt(s['peak_base_force_N'] / 1e3)} | {fmt(1e3 * s['max_penetration_m'])} | {fmt(1e3 * s['contact_duration_s'])} | "
              f"{fmt(s['rebound_velocity_m_s'])} | {s['broken_links']} | {fmt(s['step_loop_wall_time_s'])} |")
    s = summary(os.path.join(out, "shear"))
    print()
    print(f"shear: friction coefficient {fmt(s['friction_coefficient'])} (peak {fmt(s['peak_friction_coefficient'])}), "
          f"tangential stiffness {fmt(s['tangential_stiffness_N_m'])} N/m, normal {fmt(s['mean_normal_force_N'])} N, "
          f"sliding {s['sliding']}, kinetic/work {fmt(s['kinetic_to_work_ratio'])}, wall {fmt(s['step_loop_wall_time_s'])} s")


def speed(out):
    """Each run against the slow reference: the RMS difference over the
    whole curve, and over its first part (CC: up to 60 mm, before the first
    force chains give way; UCI: the first 18 ms, through the peak), each
    over the largest force of the reference in that range."""
    curves = os.environ.get("CURVES", os.path.join(os.path.dirname(__file__), "../../build/bench/bench_curves"))
    rows = []
    for test, ref, runs, xds, yds, first in [
            ("cc", "cc_ref", ["cc_v0.05_s8", "cc_v0.1_s8", "cc_v0.1_s8_twin", "cc_v0.2_s8", "cc_v0.1_s1", "cc_v0.1_s32"],
             "/curves/axial/displacement_m", "/curves/axial/force_N", 0.06),
            ("uci", "uci_ref", ["uci_dt0.1", "uci_dt0.2", "uci_dt0.2_twin", "uci_dt0.4", "uci_dt0.2_s8"],
             "/curves/impact/time_s", "/curves/impact/force_N", 0.018)]:
        r = summary(os.path.join(out, "speed", ref))
        for run in [ref] + runs:
            s = summary(os.path.join(out, "speed", run))
            files = [os.path.join(out, "speed", ref, "result.h5"), os.path.join(out, "speed", run, "result.h5")]
            whole = json.loads(subprocess.check_output([curves, "error"] + files + [xds, yds]))
            part = json.loads(subprocess.check_output([curves, "error"] + files + [xds, yds, "0", str(first)]))
            rows.append({"test": test, "run": run, "dt_s": s["dt_s"], "steps": s["steps"],
                         "wall_s": s["step_loop_wall_time_s"],
                         "speedup": r["step_loop_wall_time_s"] / s["step_loop_wall_time_s"],
                         "rms_first": part["rms_rel"], "rms_whole": whole["rms_rel"], "max_whole": whole["max_rel"],
                         "peak_force_N": s["peak_force_N"], "balance": s["energy"]["balance_rel_error"],
                         "kinetic_to_work_ratio": s.get("kinetic_to_work_ratio"),
                         "penetration_m": s.get("max_penetration_m"), "status": s.get("status")})
    with open(os.path.join(out, "speed.jsonl"), "w") as f:
        for row in rows:
            f.write(json.dumps(row) + "\n")
    print("| test | run | dt (us) | steps | wall (s) | speed-up | RMS error, first part | RMS error, whole | largest error | peak force (kN) | energy balance | kinetic/work |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['test']} | {r['run']} | {fmt(1e6 * r['dt_s'])} | {r['steps']} | {fmt(r['wall_s'])} | {fmt(r['speedup'])} | "
              f"{fmt(r['rms_first'])} | {fmt(r['rms_whole'])} | {fmt(r['max_whole'])} | {fmt(r['peak_force_N'] / 1e3)} | "
              f"{fmt(r['balance'])} | {fmt(r['kinetic_to_work_ratio'])} |")


if __name__ == "__main__":
    {"validation": validation, "speed": speed}[sys.argv[1]](sys.argv[2])
