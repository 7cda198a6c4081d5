#!/usr/bin/env python3
"""How a stacked cell comes down onto the cell under it, in parts.

    python3 bench/resolved/stack.py RESOLVED_DIR
    python3 bench/resolved/stack.py CELL.h5       (the cell's lid alone)

RESOLVED_DIR is a micro.structure run (or a macro.resolved run's
`resolved/` folder): its case (case.json, or run.json's) names the cell
file and the wall's cells, its settle/result.h5 holds the bodies laid out
(first snapshot; landing/result.h5's first where the cells were laced once
landed) and settled (last). For each pair of cells one above the other, the sink of the upper
cell's blocks onto the lower cell's blocks (their mean heights' drops,
upper less lower) is cut into three parts that add up to it:

  clearance  how much the gap between the upper cell's base net and the
             lower cell's lid closed (the mean height of the upper cell's
             base nodes less that of the lower cell's lid nodes, laid out
             against settled);
  lid        how far the lower cell's lid came down more than its blocks
             (the lid pressed into the rock under it);
  rock       how far the upper cell's blocks came down more than its base
             nodes (the rock settling onto its own base net).

It prints the cell's lid as laid out (the layout stacks the cells at the
cell's whole extent, its highest node), then each row's mean over its
columns, and the spread over the columns.
"""
import json
import sys
from pathlib import Path

import numpy as np

from sway import case_of  # (the case a resolved run ran, as sway.py reads it)

try:
    import h5py
except ImportError:
    sys.exit("needs h5py (apt-get install python3-h5py)")


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    folder = Path(sys.argv[1])
    if folder.suffix == ".h5":  # (a cell file alone: its lid)
        case = {"cell": str(folder)}
    else:
        case = case_of(folder)
    cell = h5py.File(case["cell"], "r")
    x = cell["spheres/center_m"][:]
    r = cell["spheres/radius_m"][:]
    node = np.zeros(len(x), bool)
    node[cell["links/a"][:]] = True
    node[cell["links/b"][:]] = True
    spheres, blocks = len(x), len(cell["blocks/position_m"])
    edge = json.loads(cell.attrs["summary"])["edge_m"]
    inside = (x[:, 0] > 0.02 * edge) & (x[:, 0] < 0.98 * edge) & (x[:, 1] > 0.02 * edge) & (x[:, 1] < 0.98 * edge)
    lid = node & inside & (x[:, 2] > 0.7 * edge)
    base = node & inside & (x[:, 2] < 0.1 * edge)
    if not lid.any() or not base.any():
        sys.exit(f"{case['cell']}: no lid or base nodes found")
    contact = 2 * np.mean(r[lid])  # (a base node on a lid node, centre to centre)
    top = x[:, 2] + r
    print(f"cell {case['cell']}: {lid.sum()} lid nodes, {base.sum()} base nodes")
    print(f"  lid nodes' height above the base nodes: mean {1e3 * (x[lid, 2].mean() - x[base, 2].mean()):.0f} mm, "
          f"highest {1e3 * (x[lid, 2].max() - x[base, 2].mean()):.0f} mm, lowest "
          f"{1e3 * (x[lid, 2].min() - x[base, 2].mean()):.0f} mm, spread (std) {1e3 * x[lid, 2].std():.0f} mm")
    print(f"  the cell's extent (the layout's pitch) {1e3 * (top.max() - (x[:, 2] - r).min()):.0f} mm high; "
          f"a base node rests on a lid node at {1e3 * contact:.1f} mm, centre to centre")

    if folder.suffix == ".h5":
        return
    nx, ny, nz = (int(v) for v in case["structure"]["cells"])
    if nz < 2:
        sys.exit(f"{folder}: the wall is one cell high; nothing stands on a cell")
    f = h5py.File(folder / "settle" / "result.h5", "r")
    pos = f["bodies/position_m"]
    t = f["bodies/time_s"][:]
    first, last = pos[0], pos[-1]
    if (folder / "landing" / "result.h5").exists():  # (laced once landed: laid out at the landing's start)
        landing = h5py.File(folder / "landing" / "result.h5", "r")
        first = landing["bodies/position_m"][0]
        t = t + landing["series/time_s"][-1]
    cells = nx * ny * nz
    if pos.shape[1] != cells * (spheres + blocks):
        sys.exit(f"{folder}: {pos.shape[1]} bodies, not {cells} cells of {spheres} spheres and {blocks} blocks")
    print(f"settled {t[-1]:.3f} s ({folder / 'settle' / 'result.h5'}, first and last snapshot)")

    def spheres_of(p, slot, mask):
        return p[slot * spheres:(slot + 1) * spheres][mask][:, 2].mean()

    def blocks_of(p, slot):
        b = cells * spheres + slot * blocks
        return p[b:b + blocks, 2].mean()

    print("\nrows   sink  = clearance + lid + rock (mm, mean over the columns; min-max of the sink)"
          "   clearance laid out -> settled")
    for k in range(nz - 1):
        rows = []
        for j in range(ny):
            for i in range(nx):
                lo, up = i + nx * (j + ny * k), i + nx * (j + ny * (k + 1))
                lid_drop = spheres_of(first, lo, lid) - spheres_of(last, lo, lid)
                base_drop = spheres_of(first, up, base) - spheres_of(last, up, base)
                lower_drop = blocks_of(first, lo) - blocks_of(last, lo)
                upper_drop = blocks_of(first, up) - blocks_of(last, up)
                gap0 = spheres_of(first, up, base) - spheres_of(first, lo, lid) - contact
                gap1 = spheres_of(last, up, base) - spheres_of(last, lo, lid) - contact
                rows.append((upper_drop - lower_drop, base_drop - lid_drop, lid_drop - lower_drop,
                             upper_drop - base_drop, gap0, gap1))
        a = 1e3 * np.array(rows)
        m = a.mean(axis=0)
        print(f"{k}->{k + 1}  {m[0]:6.1f} = {m[1]:6.1f}    + {m[2]:5.1f} + {m[3]:5.1f}"
              f"   ({a[:, 0].min():.1f}-{a[:, 0].max():.1f})"
              f"          {m[4]:5.1f} -> {m[5]:5.1f}")


if __name__ == "__main__":
    main()
