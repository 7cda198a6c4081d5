#!/usr/bin/env python3
"""Write a sample netting description (format "gabion.netting/1") for the
wire-netting sheet tensile benchmark.

Usage:
    python3 make_sample_netting.py [out.json] [--rows N] [--width W]

Default: 13 rows (r = 0..12), width 0.48 m, written to sample_netting.json
next to this script.

Geometry: hexagonal double-twisted mesh in the x-y plane, twists along y.
Row r lies at y_r = r*(a+b) with a = 0.04 m (twist length) and b = 0.03 m
(rise of the single wires).  Even rows have twists at x = 0, 0.08, ..., W,
odd rows at x = 0.04, ..., W-0.04.  Each twist is a bottom node (x, y_r) and
a top node (x, y_r + a) joined by one "double_twist" link.  The top node of
each twist in row r is joined by "single" links to the bottom nodes of the
row r+1 twists at x-0.04 and x+0.04 where these exist.  On the side edges
(x = 0 and x = W) the twists of even rows are "selvedge" links instead of
double twists, and successive edge nodes along y (top node of row r to bottom
node of row r+2 on that edge) are joined by "selvedge" links.
Clamped nodes: bottom nodes of row 0.  Pulled nodes: top nodes of the last row.

Elastic link stiffness (what Yade's Ip2_WireMat_WireMat_WirePhys computes,
type 0 / Bertrand et al. 2008):
    single wire:   k = E A / L0,   A = pi d^2 / 4, E = stress[0] / strain[0]
    selvedge:      same with the selvedge diameter
    double twist:  alpha = atan(L0 / (3 pi d))
                   k_h = k (L0 d / A) / (48 cos(alpha) (41/9 (1+nu) + 17/4 tan^2(alpha)))
                   k_D = 2 (lambda_k k_h + (1 - lambda_k) k)
with k the single-wire stiffness of the same length and diameter d.
"""
import argparse
import json
import math
import os

WIRE = {
    "strain": [0.0019231, 0.0192, 0.05, 0.15, 0.25, 0.30, 0.35],
    "stress_Pa": [250e6, 321.95e6, 382.92e6, 512.19e6, 558.54e6, 565.85e6, 565.85e6],
    "poisson": 0.3,
    "lambda_k": 0.66,
    "lambda_eps": 0.4,
    "mesh_diameter_m": 0.0027,
    "selvedge_diameter_m": 0.0034,
}


def single_stiffness(E, d, L0):
    A = math.pi * d * d / 4.0
    return E * A / L0


def double_twist_stiffness(E, d, L0, nu, lambda_k):
    A = math.pi * d * d / 4.0
    k = E * A / L0
    alpha = math.atan(L0 / (3.0 * math.pi * d))
    kh = k * (L0 * d / A) / (48.0 * math.cos(alpha) *
                             (41.0 / 9.0 * (1.0 + nu) + 17.0 / 4.0 * math.tan(alpha) ** 2))
    return 2.0 * (lambda_k * kh + (1.0 - lambda_k) * k)


def build(rows=13, width=0.48, a=0.04, b=0.03, half_pitch=0.04,
          radius=0.0108, mass=0.0039, pull_v=0.05, dt=2.2e-6, steps=874000,
          local_damping=0.5):
    E = WIRE["stress_Pa"][0] / WIRE["strain"][0]
    nu = WIRE["poisson"]
    lk = WIRE["lambda_k"]
    dm = WIRE["mesh_diameter_m"]
    ds = WIRE["selvedge_diameter_m"]
    ncol = int(round(width / half_pitch))  # number of half pitches across
    eps = 1e-9

    pos = []
    twists = {}  # (row, col) -> (bottom node, top node); x = col*half_pitch
    for r in range(rows):
        y = r * (a + b)
        for c in range(r % 2, ncol + 1, 2):
            x = c * half_pitch
            bot = len(pos)
            pos.append([x, y, 0.0])
            top = len(pos)
            pos.append([x, y + a, 0.0])
            twists[(r, c)] = (bot, top)

    la, lb, kind = [], [], []

    def add(i, j, k):
        la.append(i)
        lb.append(j)
        kind.append(k)

    # twists
    for (r, c), (bot, top) in sorted(twists.items()):
        on_edge = (c == 0 or c == ncol)
        add(bot, top, "selvedge" if (on_edge and r % 2 == 0) else "double_twist")
    # single wires between rows
    for (r, c), (bot, top) in sorted(twists.items()):
        for cc in (c - 1, c + 1):
            if (r + 1, cc) in twists:
                add(top, twists[(r + 1, cc)][0], "single")
    # selvedge wires along the side edges
    for c in (0, ncol):
        for r in range(rows):
            if (r, c) in twists and (r + 2, c) in twists:
                add(twists[(r, c)][1], twists[(r + 2, c)][0], "selvedge")

    rest, kel = [], []
    for i, j, k in zip(la, lb, kind):
        L0 = math.dist(pos[i], pos[j])
        rest.append(L0)
        if k == "single":
            kel.append(single_stiffness(E, dm, L0))
        elif k == "selvedge":
            kel.append(single_stiffness(E, ds, L0))
        else:
            kel.append(double_twist_stiffness(E, dm, L0, nu, lk))

    clamped = [twists[(0, c)][0] for c in range(0, ncol + 1) if (0, c) in twists]
    pulled = [twists[(rows - 1, c)][1] for c in range(0, ncol + 1) if (rows - 1, c) in twists]
    n = len(pos)
    return {
        "format": "gabion.netting/1",
        "nodes": {"position_m": pos, "radius_m": [radius] * n, "mass_kg": [mass] * n},
        "links": {"a": la, "b": lb, "kind": kind, "rest_length_m": rest,
                  "elastic_stiffness_N_m": kel},
        "wire": dict(WIRE),
        "test": {"clamped": clamped, "pulled": pulled,
                 "pull_velocity_m_s": [0.0, pull_v, 0.0], "dt_s": dt,
                 "steps": steps, "local_damping": local_damping},
    }


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("out", nargs="?", default=os.path.join(here, "sample_netting.json"))
    p.add_argument("--rows", type=int, default=13)
    p.add_argument("--width", type=float, default=0.48)
    p.add_argument("--steps", type=int, default=874000)
    args = p.parse_args()
    net = build(rows=args.rows, width=args.width, steps=args.steps)
    with open(args.out, "w") as f:
        json.dump(net, f, indent=1)
    kinds = net["links"]["kind"]
    print("wrote %s: %d nodes, %d links (%d double_twist, %d single, %d selvedge), "
          "%d clamped, %d pulled" % (
              args.out, len(net["nodes"]["position_m"]), len(kinds),
              kinds.count("double_twist"), kinds.count("single"), kinds.count("selvedge"),
              len(net["test"]["clamped"]), len(net["test"]["pulled"])))


if __name__ == "__main__":
    main()
