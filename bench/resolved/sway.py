#!/usr/bin/env python3
"""How a resolved wall settles: how fast its bodies still move, and how far
each row of cells moved over the settling.

    python3 bench/resolved/sway.py [LABEL=]RESOLVED_DIR... [--png FIGURE]

RESOLVED_DIR is a micro.structure run (or a macro.resolved run's
`resolved/` folder), finished or still settling: its case (case.json, or
run.json's) names the cell file and the wall's cells; its settling is
settle/result.h5, after landing/result.h5 where the cells were laced once
landed (`lacing`, docs/resolved.md). It prints

  - the bodies' mass-weighted rms speed, sqrt(2 KE / M), at the settling's
    series samples (every tenth of its length, and the last), from
    /series/kinetic_translational_J and the cells' mass (the cell file's
    rock, its summary's mass_kg, and its netting nodes);
  - for each row of cells (k = 0 the bottom one), each cell's move over
    the settling (the mean position of its blocks, first snapshot against
    last): the row's mean along x (out of the front face is negative), y
    (along the wall) and z, and the least and largest over its cells.

With --png, the rms speeds of every run given are drawn against time into
FIGURE (log scale; matplotlib), each named LABEL where given.
"""
import json
import sys
from pathlib import Path

import numpy as np

try:
    import h5py
except ImportError:
    sys.exit("needs h5py (apt-get install python3-h5py)")


def case_of(folder):
    """The case a resolved run ran: case.json, or a plain run's run.json (its cell beside the case file)."""
    if (folder / "case.json").exists():  # (a macro.resolved run's resolved/)
        return json.loads((folder / "case.json").read_text())
    run = json.loads((folder / "run.json").read_text())  # (a micro.structure run of its own)
    case = run["case"]
    case["cell"] = str(Path(run["case_file"]).parent / case["cell"])
    return case


def main():
    args = sys.argv[1:]
    png = None
    if "--png" in args:
        k = args.index("--png")
        if k + 1 >= len(args):
            sys.exit(__doc__)
        png = args[k + 1]
        del args[k:k + 2]
    if not args:
        sys.exit(__doc__)
    curves = [(a.split("=", 1)[0] if "=" in a else a, *sway(Path(a.split("=", 1)[-1]))[1:]) for a in args]
    if png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 4))
        for label, t, rms in curves:
            ax.semilogy(t, rms, label=label)
        ax.set_xlabel("time from the laid-out wall (s)")
        ax.set_ylabel("rms speed of the bodies (m/s)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(png, dpi=120)
        print(f"\nwrote {png}")


def sway(folder):
    """Prints one run's settling; returns (folder, time, rms speed)."""
    case = case_of(folder)
    cell = h5py.File(case["cell"], "r")
    spheres, blocks = len(cell["spheres/center_m"]), len(cell["blocks/position_m"])
    free = ~cell["spheres/fixed"][:].astype(bool)
    cell_mass = json.loads(cell.attrs["summary"])["mass_kg"] + cell["spheres/mass_kg"][:][free].sum()
    nx, ny, nz = (int(v) for v in case["structure"]["cells"])
    cells = nx * ny * nz
    mass = cells * cell_mass

    parts = [p for p in (folder / "landing" / "result.h5", folder / "settle" / "result.h5") if p.exists()]
    if not parts:
        sys.exit(f"{folder}: no settle/result.h5 (still in its first snapshot interval, or not a micro.structure run)")
    t_all, ke_all, first, last, offset = [], [], None, None, 0.0
    for p in parts:
        f = h5py.File(p, "r")
        t = f["series/time_s"][:]
        t_all.append(offset + t)
        ke_all.append(f["series/kinetic_translational_J"][:])
        pos = f["bodies/position_m"]
        if pos.shape[1] != cells * (spheres + blocks):
            sys.exit(f"{p}: {pos.shape[1]} bodies, not {cells} cells of {spheres} spheres and {blocks} blocks")
        if first is None:
            first = pos[0]
        last, last_t = pos[-1], offset + f["bodies/time_s"][-1]
        offset += t[-1]
    t, ke = np.concatenate(t_all), np.concatenate(ke_all)
    rms = np.sqrt(2.0 * np.maximum(ke, 0.0) / mass)
    print(f"{folder}: {cells} cells of {cell_mass:.1f} kg; settling {' + '.join(str(p.parent.name) for p in parts)}, "
          f"{t[-1]:.3f} s")
    print("rms speed (m/s):")
    for k in sorted(set(np.linspace(0, len(t) - 1, 11).astype(int))):
        print(f"  t = {t[k]:6.3f} s  {rms[k]:.4f}")

    def centre(p, slot):
        b = cells * spheres + slot * blocks
        return p[b:b + blocks].mean(axis=0)

    print(f"\neach cell's move over the settling, 0 -> {last_t:.3f} s (mm): row mean (least .. largest)")
    print("row        x                      y                      z")
    for k in range(nz):
        moves = np.array([centre(last, s) - centre(first, s)
                          for s in (i + nx * (j + ny * k) for j in range(ny) for i in range(nx))]) * 1e3
        cols = "".join(f"  {moves[:, a].mean():6.1f} ({moves[:, a].min():6.1f} .. {moves[:, a].max():6.1f})"
                       for a in range(3))
        print(f"{k:3d} {cols}")
    return folder, t, rms


if __name__ == "__main__":
    main()
