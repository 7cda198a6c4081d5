#!/usr/bin/env python3
"""The impact force's peak over windows, and when the boulder stopped.

    python3 bench/resolved/peaks.py REFERENCE_DIR RUN_DIR... [--png FIG]

Each folder is a micro.structure run or a hybrid's (its result.h5 holds
/curves/impact: time_s, force_N, boulder_velocity_m_s, penetration_m). For
each it prints the force's largest value (`peak_force_N` of its summary),
the largest mean over windows of 1, 2 and 5 ms (a peak that one granular
spike does not set), the time from first contact to the deepest
penetration (when the boulder stopped), and when the force last fell
below 5 % of its peak and below the boulder's weight (m g, g = 9.81
m/s2: a boulder at rest in its crater still presses the face with a
part of its weight, so the contact's end at 1 % of the peak, the
summary's contact_duration_s, can fall inside that residual; nan where
the force never exceeds it); then each run's relative differences from
the first folder's. With --png, FIG shows each run's force and
penetration against the time from first contact ([LABEL=]DIR names a
curve LABEL).
"""
import json
import sys
from pathlib import Path

import numpy as np

try:
    import h5py
except ImportError:
    sys.exit("needs h5py (apt-get install python3-h5py)")

WINDOWS_S = (1e-3, 2e-3, 5e-3)
G_M_S2 = 9.81


def measures(folder):
    c = h5py.File(Path(folder) / "result.h5", "r")["curves/impact"]
    t, f, pen = c["time_s"][:], c["force_N"][:], c["penetration_m"][:]
    if len(t) < 2 or f.max() <= 0.0:
        sys.exit(f"{folder}: no impact force in result.h5")
    dt = (t[-1] - t[0]) / (len(t) - 1)
    out = [f.max()]
    for w in WINDOWS_S:
        n = max(1, int(round(w / dt)))
        out.append(np.convolve(f, np.ones(n) / n, "valid").max())
    first = np.argmax(f > 0.0)
    out.append(t[np.argmax(pen)] - t[first])
    for level in (0.05 * f.max(), weight(folder)):
        after = np.where(f[np.argmax(f):] >= level)[0]
        out.append(t[np.argmax(f) + after[-1]] - t[first] if after.size else float("nan"))
    return out


def weight(folder):
    """The boulder's weight (N), from the run's summary.json."""
    summary = Path(folder) / "summary.json"
    try:
        return json.loads(summary.read_text())["boulder_mass_kg"] * G_M_S2
    except (OSError, KeyError, ValueError) as e:
        sys.exit(f"{summary}: no boulder_mass_kg ({e})")


def curves(folder):
    c = h5py.File(Path(folder) / "result.h5", "r")["curves/impact"]
    t, f, pen = c["time_s"][:], c["force_N"][:], c["penetration_m"][:]
    first = np.argmax(f > 0.0)
    return 1e3 * (t - t[first]), 1e-3 * f, 1e3 * pen


def figure(runs, png):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        sys.exit("--png needs matplotlib (apt-get install python3-matplotlib)")
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7.5, 6.5))
    for k, (label, folder) in enumerate(runs):
        t, f, pen = curves(folder)
        style = dict(lw=2.2 if k == 0 else 1.2, color="black" if k == 0 else None)
        top.plot(t, f, label=label, **style)
        bottom.plot(t, pen, label=label, **style)
    top.set_ylabel("force on the boulder (kN)")
    bottom.set_ylabel("penetration (mm)")
    bottom.set_xlabel("time from first contact (ms)")
    top.set_xlim(left=-2)
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    top.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    print(f"figure: {png}")


def main():
    args, png = sys.argv[1:], None
    if "--png" in args:
        k = args.index("--png")
        if k + 1 >= len(args):
            sys.exit("--png needs a file name")
        png = args[k + 1]
        del args[k:k + 2]
    if not args:
        sys.exit(__doc__)
    runs = [(a.split("=", 1) if "=" in a else (a, a)) for a in args]
    sys.argv = [sys.argv[0]] + [folder for _, folder in runs]
    if png:
        figure(runs, png)
    names = ["peak kN", "1 ms kN", "2 ms kN", "5 ms kN", "to stop ms", "above 5 % ms", "above weight ms"]
    scale = [1e-3] * 4 + [1e3] * 3
    rows = [(f, measures(f)) for f in sys.argv[1:]]
    print("| run | " + " | ".join(names) + " |")
    print("|---" * (len(names) + 1) + "|")
    ref = rows[0][1]
    for k, (folder, m) in enumerate(rows):
        cells = []
        for v, r, s in zip(m, ref, scale):
            cells.append(f"{v * s:.1f}" + ("" if k == 0 else f" ({100 * (v / r - 1):+.1f} %)"))
        print(f"| {folder} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
