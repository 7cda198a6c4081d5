#!/usr/bin/env python3
"""Each cell of a hybrid against the same cell of its wall: where it stands
when the boulder comes, and how far it moves back in the impact.

    python3 bench/resolved/cells.py WALL_DIR HYBRID_DIR...

WALL_DIR is a micro.structure run (or a macro.resolved run's `resolved/`
folder), each HYBRID_DIR a hybrid run (`resolve` in a macro.impact case)
of the same wall, all finished: their result.h5 snapshots of the impact
(/bodies/position_m, every output interval) and summary.json. A cell's
place is its blocks' mean position: the blocks are the last bodies, cell
by cell in the order the cells were laid out (the wall's i fastest, then
j, then k; a hybrid's its `hybrid/resolved_cells`). It prints

  - for each hybrid, each resolved cell (i, j, k) at the impact's start:
    its place less the wall's same cell's (mm, x y z), the cells beside
    the struck column being the ones a plate under them holds up; and
    the furthest back it came in the impact (its place at the start plus
    its largest move back) less the wall's same cell's (mm, x): a cell
    that starts further back and moves back less may still come as far;
  - for the wall and each hybrid, each layer's grid of cells (rows from
    the top, j along the wall): how far the cell moved back along x in
    the impact, the largest over the snapshots (mm; `---` for a macro
    node); and from where it was laid out to where the impact found it,
    along x (mm, negative: forward, away from the back support), its
    place laid out from the first snapshot of the settling (landing/ when
    the cells were laced once landed, else settle/).

The snapshots are coarse (every output interval, 5 ms in the walls of
docs/resolved.md): the back face's largest move is the summary's
(`max_back_face_displacement_m`, every series sample).
"""
import json
import sys
from pathlib import Path

import numpy as np

try:
    import h5py
except ImportError:
    sys.exit("needs h5py (apt-get install python3-h5py)")


def laid_out(folder, n_blocks):
    """The blocks' places as laid out (the settling's first snapshot), or None."""
    for part in ("landing", "settle"):
        path = folder / part / "result.h5"
        if path.exists():
            with h5py.File(path, "r") as f:
                p = f["bodies/position_m"][0]
                return p[p.shape[0] - n_blocks :]
    return None


def cells(folder):
    """{(i, j, k): (place at the start (3,), largest move back along x, place laid out (3,) or None)},
    the grid's size."""
    s = json.loads((folder / "summary.json").read_text())
    n = np.asarray(s["cells"], dtype=int)
    # The cells laid out, in the order of their bodies: a hybrid's resolved
    # cells, or every cell of the wall (i fastest, then j, then k).
    if "hybrid" in s:
        laid = [tuple(c) for c in s["hybrid"]["resolved_cells"]]
    else:
        laid = [(i, j, k) for k in range(n[2]) for j in range(n[1]) for i in range(n[0])]
    per_cell = s["blocks"] // len(laid)
    with h5py.File(folder / "result.h5", "r") as f:
        p = f["bodies/position_m"]
        first_block = p.shape[1] - s["blocks"]  # (the blocks come after every sphere, cell by cell)
        blocks = [p[t][first_block:] for t in range(p.shape[0])]
    first = laid_out(folder, s["blocks"])
    out = {}
    for c, key in enumerate(laid):
        x = np.array([b[c * per_cell : (c + 1) * per_cell].mean(axis=0) for b in blocks])
        x_laid = None if first is None else first[c * per_cell : (c + 1) * per_cell].mean(axis=0)
        out[key] = (x[0], float((x[:, 0] - x[0, 0]).max()), x_laid)
    return out, n


def main(argv):
    if len(argv) < 2:
        sys.exit(__doc__)
    wall, n = cells(Path(argv[0]))
    runs = [(argv[0], wall)]
    for d in argv[1:]:
        hybrid, _ = cells(Path(d))
        runs.append((d, hybrid))
        print(f"{d}: each resolved cell at the impact's start, less the wall's (mm, x y z),"
              " and the furthest back it came, less the wall's (mm)")
        for key in sorted(hybrid, key=lambda c: (c[2], c[1], c[0])):
            if key in wall:
                d_mm = 1e3 * (hybrid[key][0] - wall[key][0])
                furthest = d_mm[0] + 1e3 * (hybrid[key][1] - wall[key][1])
                print(f"  {key}: {d_mm[0]:6.1f} {d_mm[1]:6.1f} {d_mm[2]:6.1f}   {furthest:6.1f}")
    def grid(run, value):
        for i in range(n[0]):
            print(f"  layer {i} (rows from the top)")
            for k in reversed(range(n[2])):
                row = [f"{value(run[(i, j, k)]):6.1f}" if (i, j, k) in run else "   ---" for j in range(n[1])]
                print("   " + " ".join(row))

    for d, run in runs:
        print(f"{d}: each cell's largest move back along x in the impact (mm)")
        grid(run, lambda c: 1e3 * c[1])
        if all(c[2] is not None for c in run.values()):
            print(f"{d}: each cell's move along x from where it was laid out to the impact's start (mm)")
            grid(run, lambda c: 1e3 * (c[0][0] - c[2][0]))


if __name__ == "__main__":
    main(sys.argv[1:])
