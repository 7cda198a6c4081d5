#!/usr/bin/env python3
"""How long a link sub-step may be: speed against error over run.link_dt_safety.

    python3 bench/netting/substeps.py CELL_H5 [--out DIR] [--safety 0.2,0.3,0.5,0.7,1]
                                      [--gabion build/gabion] [--threads N] [--png FIG]

The nodes of a netting advance in sub-steps of each engine step, each a
fraction `run.link_dt_safety` of their critical step (docs/micro.md, Link
sub-steps; it defaults to run.dt_safety, 0.2). This runs the cell's
confined compression (cases/micro_cc.json: quasi-static, its netting's
mass scaled 8 times) and its unconfined impact at 15 m/s
(cases/micro_uci.json: dynamic, no scaling) at each fraction, one after
the other, into DIR/<test>_<fraction>/, and prints for each run:

  - the link sub-steps per step, the step loop's wall time and its speed-up
    on the first fraction's (the runs' own `step_loop_wall_time_s`);
  - the energy ledger's balance error at the end;
  - against the first fraction's run: the peak force, and the force
    curve's root-mean-square difference over its peak (against time,
    interpolated onto the first run's samples); the compression's
    lateral reaction coefficient, the impact's largest penetration.

The first fraction is also run on another thread count (1 for --threads
2 or more): its sums round otherwise, and a granular run's trajectory
parts from round-off alone, so its difference is the floor under which
a fraction's error does not show.

With --png, FIG draws each test's curve error and speed-up against the
fraction. Run it alone on the machine: the speed-ups are wall times.
"""
import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

try:
    import h5py
except ImportError:
    sys.exit("needs h5py (apt-get install python3-h5py)")

ROOT = Path(__file__).resolve().parents[2]
TESTS = {
    # name: (case file, extra --set arguments, curve x, curve y)
    "cc": ("cases/micro_cc.json", [], "curves/axial/time_s", "curves/axial/force_N"),
    "uci_15": ("cases/micro_uci.json", ["--set", "velocities_m_s=[15]"], "curves/impact/time_s",
               "curves/impact/force_N"),
}


def run(gabion, test, cell, fraction, out, threads, suffix=""):
    case, extra, _, _ = TESTS[test]
    folder = out / f"{test}_{fraction:g}{suffix}"
    if not (folder / "summary.json").exists():
        cmd = [gabion, "run", "-q", str(ROOT / case), "--set", f"cell={cell}", *extra,
               "--set", f"run.link_dt_safety={fraction}", "--threads", str(threads), "-o", str(folder)]
        done = subprocess.run(cmd, capture_output=True, text=True)
        if done.returncode != 0:
            sys.exit(f"{' '.join(cmd)}\nfailed ({done.returncode}):\n{done.stdout}{done.stderr}")
    return folder


def measures(test, folder):
    """The run's summary and its force curve, from one run or a replicate set's single run."""
    summary = json.loads((folder / "summary.json").read_text())
    h5 = folder / "result.h5"
    if not h5.exists():  # (micro.uci writes one folder per velocity)
        subs = sorted(p for p in folder.iterdir() if (p / "result.h5").exists())
        if len(subs) != 1:
            sys.exit(f"{folder}: expected one run's result.h5")
        h5, summary = subs[0] / "result.h5", json.loads((subs[0] / "summary.json").read_text())
    _, _, xs, ys = TESTS[test]
    with h5py.File(h5, "r") as f:
        x, y = f[xs][:], f[ys][:]
    return summary, x, y


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("cell")
    ap.add_argument("--out", default=str(ROOT / "results" / "substeps"))
    ap.add_argument("--safety", default="0.2,0.3,0.5,0.7,1")
    ap.add_argument("--gabion", default=str(ROOT / "build" / "gabion"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--png")
    a = ap.parse_args()
    fractions = [float(s) for s in a.safety.split(",")]
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    cell = str(Path(a.cell).resolve())
    rows, floor = {}, {}
    for test in TESTS:
        for s in fractions:
            rows[(test, s)] = measures(test, run(a.gabion, test, cell, s, out, a.threads))
        # The noise floor: the first fraction on another thread count, whose
        # sums round otherwise (a granular run's trajectory parts from
        # round-off alone).
        other = 1 if a.threads > 1 else 2
        floor[test] = measures(test, run(a.gabion, test, cell, fractions[0], out, other, f"_threads_{other}"))
    print("| test | link_dt_safety | sub-steps | step loop s | speed-up | balance | peak kN | peak error | "
          "curve rms / peak | other |")
    print("|---" * 10 + "|")
    errors = {t: [] for t in TESTS}
    for test in TESTS:
        ref_summary, rx, ry = rows[(test, fractions[0])]
        t0 = ref_summary["step_loop_wall_time_s"]
        for s in [None] + fractions:
            summary, x, y = floor[test] if s is None else rows[(test, s)]
            # (onto the first run's samples, within the range both cover)
            inside = (rx >= x.min()) & (rx <= x.max())
            order = np.argsort(x, kind="stable")
            rms = np.sqrt(np.mean((np.interp(rx[inside], x[order], y[order]) - ry[inside]) ** 2)) / ry.max()
            if test == "cc":
                other = f"lateral coefficient {summary['lateral_reaction_coefficient']:.4f}"
            else:
                other = f"penetration {1e3 * summary['max_penetration_m']:.1f} mm"
            speed = t0 / summary["step_loop_wall_time_s"]
            if s is None:  # (its speed is another thread count's: not comparable)
                print(f"| {test} | {fractions[0]:g}, {summary['threads']} thread(s): the noise floor | "
                      f"{summary['link_substeps']} | | | {summary['energy']['balance_rel_error']:.1e} | "
                      f"{1e-3 * summary['peak_force_N']:.2f} | "
                      f"{100 * (summary['peak_force_N'] / ref_summary['peak_force_N'] - 1):+.2f} % | "
                      f"{100 * rms:.2f} % | {other} |")
                errors[test + " floor"] = rms
                continue
            errors[test].append((s, rms, speed))
            print(f"| {test} | {s:g} | {summary['link_substeps']} | {summary['step_loop_wall_time_s']:.1f} | "
                  f"{speed:.2f} | {summary['energy']['balance_rel_error']:.1e} | {1e-3 * summary['peak_force_N']:.2f} | "
                  f"{100 * (summary['peak_force_N'] / ref_summary['peak_force_N'] - 1):+.2f} % | {100 * rms:.2f} % | "
                  f"{other} |")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
        for test in TESTS:
            e = errors[test]
            s = [v[0] for v in e]
            line, = left.plot(s[1:], [100 * v[1] for v in e[1:]], "o-", label=test)
            left.axhline(100 * errors[test + " floor"], ls="--", color=line.get_color(),
                         label=f"{test}: {fractions[0]:g} on another thread count")
            right.plot(s, [v[2] for v in e], "o-", label=test)
        left.set_xlabel("run.link_dt_safety")
        left.set_ylabel(f"force curve rms difference from {fractions[0]:g} (% of peak)")
        right.set_xlabel("run.link_dt_safety")
        right.set_ylabel(f"step loop speed-up on {fractions[0]:g}")
        left.set_ylim(bottom=0.0)
        for ax in (left, right):
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7, loc="lower left" if ax is left else "upper left")
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)
        print(f"figure: {a.png}")


if __name__ == "__main__":
    main()
