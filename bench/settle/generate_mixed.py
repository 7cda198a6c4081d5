#!/usr/bin/env python3
"""Generate the mixed-size benchmark scene (docs/performance.md, "Mixed-size scene").

20,000 spheres of radius 4 mm, 2,000 of 18 mm and 20 of 70 mm in a closed
cubic box (six walls) under gravity, a seeded random cloud at solid fraction
0.33 of the box volume with random initial velocities up to 0.5 m/s. Written
so that Gabion and LIGGGHTS start from exactly the same state:

  OUTDIR/mixed.gabion.json   Gabion case (gabion.case/1, kind micro.scene)
  OUTDIR/mixed.data          LIGGGHTS read_data file (atom_style granular,
                             atom type 1, 2, 3 = radius 4, 18, 70 mm; with a
                             Velocities section)
  OUTDIR/mixed.meta.json     the scene parameters (L, dt, masses, ...)

Cloud: random sequential addition, largest spheres first, with a minimum gap
of 1 mm between spheres and to the six walls; the box is a cube of side
L = (V_spheres / 0.33)^(1/3). Velocities: each sphere gets a direction
uniform on the unit sphere and a speed uniform in [0, 0.5] m/s, drawn after
all positions from the same generator; no initial spin.

Contact law and damping are those of the settling scene (generate.py):
k_n = 1e5 N/m, k_t = 2.5e4 N/m, friction 0.5, Gabion viscous damping ratio
0.2155 (restitution 0.5); density 2500 kg/m3. dt = 0.15 sqrt(m_4mm / k_n).
Gabion's overlap stop is raised to 1 x the smaller radius (see write_gabion).

Standard library only. Same seed -> byte-identical files.
"""
import argparse
import json
import math
import os
import random
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
import generate as settle  # noqa: E402  (the settling scene's material constants)

# (radius m, count), largest first: the order of placement.
CLASSES = [(0.070, 20), (0.018, 2000), (0.004, 20000)]
GAP_M = 0.001
SOLID_FRACTION = 0.33
MAX_SPEED_M_S = 0.5
DT_FACTOR = 0.15
CELL_M = 0.010  # hash-grid cell of the addition (any size is correct; this one is fast)


def sphere_volume(r):
    return 4.0 / 3.0 * math.pi * r ** 3


def box_side_m():
    vol = sum(n * sphere_volume(r) for r, n in CLASSES)
    return (vol / SOLID_FRACTION) ** (1.0 / 3.0)


def time_step_s():
    m_small = settle.DENSITY_KG_M3 * sphere_volume(min(r for r, _ in CLASSES))
    return DT_FACTOR * math.sqrt(m_small / settle.KN_N_M)


def cells_of(c, reach):
    """Grid cells overlapped by the box of half-side reach around c."""
    lo = [int(math.floor((c[k] - reach) / CELL_M)) for k in range(3)]
    hi = [int(math.floor((c[k] + reach) / CELL_M)) for k in range(3)]
    return [(i, j, k) for i in range(lo[0], hi[0] + 1) for j in range(lo[1], hi[1] + 1)
            for k in range(lo[2], hi[2] + 1)]


def cloud(side, rng):
    """Random sequential addition, largest first; returns [(x, y, z, r)].

    A placed sphere is entered in every cell that its ball grown by gap/2
    overlaps (by bounding box); a candidate looks in the cells of its own
    grown ball: two grown balls that intersect share a cell."""
    grid = {}
    out = []
    for r, n in CLASSES:
        lo, hi = r + GAP_M, side - r - GAP_M
        placed = 0
        attempts = 0
        max_attempts = 1000 * n + 100000
        while placed < n:
            attempts += 1
            if attempts > max_attempts:
                sys.exit(f"generate_mixed.py: random sequential addition stuck after {attempts} tries "
                         f"({placed} of {n} spheres of radius {r} m placed)")
            c = (rng.uniform(lo, hi), rng.uniform(lo, hi), rng.uniform(lo, hi))
            reach = r + 0.5 * GAP_M
            cells = cells_of(c, reach)
            ok = True
            seen = set()
            for key in cells:
                for q in grid.get(key, ()):
                    if q in seen:
                        continue
                    seen.add(q)
                    p = out[q]
                    dmin = r + p[3] + GAP_M
                    if (p[0] - c[0]) ** 2 + (p[1] - c[1]) ** 2 + (p[2] - c[2]) ** 2 < dmin * dmin:
                        ok = False
                        break
                if not ok:
                    break
            if ok:
                q = len(out)
                out.append((c[0], c[1], c[2], r))
                for key in cells:
                    grid.setdefault(key, []).append(q)
                placed += 1
    return out


def velocities(n, rng):
    out = []
    for _ in range(n):
        while True:
            d = (rng.gauss(0.0, 1.0), rng.gauss(0.0, 1.0), rng.gauss(0.0, 1.0))
            norm = math.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2)
            if norm > 1e-12:
                break
        s = rng.uniform(0.0, MAX_SPEED_M_S) / norm
        out.append((d[0] * s, d[1] * s, d[2] * s))
    return out


def fmt(v):
    return float(f"{v:.9g}")


def write_gabion(path, pts, vel, side, steps, dt):
    duration = steps * dt
    walls = [
        {"point_m": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0], "material": "grain"},
        {"point_m": [0.0, 0.0, side], "normal": [0.0, 0.0, -1.0], "material": "grain"},
        {"point_m": [0.0, 0.0, 0.0], "normal": [1.0, 0.0, 0.0], "material": "grain"},
        {"point_m": [side, 0.0, 0.0], "normal": [-1.0, 0.0, 0.0], "material": "grain"},
        {"point_m": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0], "material": "grain"},
        {"point_m": [0.0, side, 0.0], "normal": [0.0, -1.0, 0.0], "material": "grain"},
    ]
    head = {
        "format": "gabion.case/1",
        "kind": "micro.scene",
        "description": f"Mixed-size benchmark: {len(pts)} spheres of radius 4, 18 and 70 mm in a closed "
                       f"{side:.4f} m cube (bench/settle --scene mixed, docs/performance.md)",
        "gravity_m_s2": [0.0, 0.0, -settle.GRAVITY_M_S2],
        "materials": {
            "grain": {
                "density_kg_m3": settle.DENSITY_KG_M3,
                "normal_stiffness_N_m": settle.KN_N_M,
                "shear_stiffness_N_m": settle.KS_N_M,
                "friction": settle.FRICTION,
                "viscous_damping_ratio": fmt(settle.ZETA),
            }
        },
    }
    # max_overlap_ratio 1 (the largest Gabion accepts, default 0.5): k_n is the
    # same for every size, so a 70 mm sphere (3.6 kg) landing at 0.5 m/s on a
    # 4 mm sphere lying on the floor presses it in by more than half its radius
    # (LIGGGHTS, which has no such stop, shows 0.5 of the radius at step ~1170
    # and more after; Gabion's default limit stops the run there).
    tail = {"walls": walls,
            "run": {"duration_s": duration, "dt_s": dt, "output_interval_s": duration, "max_overlap_ratio": 1.0}}
    with open(path, "w") as f:
        # One sphere per line keeps the file readable and diffable.
        f.write("{\n")
        for k, v in head.items():
            f.write(f"  {json.dumps(k)}: {json.dumps(v)},\n")
        f.write('  "spheres": [\n')
        for j, ((x, y, z, r), (vx, vy, vz)) in enumerate(zip(pts, vel)):
            s = {"center_m": [fmt(x), fmt(y), fmt(z)], "radius_m": r, "material": "grain",
                 "velocity_m_s": [fmt(vx), fmt(vy), fmt(vz)]}
            f.write("    " + json.dumps(s) + ("," if j + 1 < len(pts) else "") + "\n")
        f.write("  ],\n")
        keys = list(tail)
        for i, k in enumerate(keys):
            f.write(f"  {json.dumps(k)}: {json.dumps(tail[k])}" + ("," if i + 1 < len(keys) else "") + "\n")
        f.write("}\n")


def write_liggghts_data(path, pts, vel, side):
    types = {r: t + 1 for t, (r, _) in enumerate(sorted(CLASSES))}
    with open(path, "w") as f:
        f.write(f"LIGGGHTS data file: mixed-size benchmark, {len(pts)} spheres (bench/settle/generate_mixed.py)\n\n")
        f.write(f"{len(pts)} atoms\n{len(CLASSES)} atom types\n\n")
        # Box a little larger than the walls so that no atom leaves the fixed
        # box before a wall/gran plane pushes it back.
        for ax in ("x", "y", "z"):
            f.write(f"{-0.01:.6f} {side + 0.01:.6f} {ax}lo {ax}hi\n")
        f.write("\nAtoms\n\n")
        # atom_style granular: atom-ID atom-type diameter density x y z
        for i, (x, y, z, r) in enumerate(pts, start=1):
            f.write(f"{i} {types[r]} {2 * r:.9g} {settle.DENSITY_KG_M3:.9g} {x:.9g} {y:.9g} {z:.9g}\n")
        # atom_style granular: atom-ID vx vy vz omegax omegay omegaz
        f.write("\nVelocities\n\n")
        for i, (vx, vy, vz) in enumerate(vel, start=1):
            f.write(f"{i} {vx:.9g} {vy:.9g} {vz:.9g} 0 0 0\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=5000, help="time steps (default 5000)")
    ap.add_argument("--seed", type=int, default=20261122, help="random seed (default 20261122)")
    ap.add_argument("--outdir", default="bench/work", help="where to write (default bench/work)")
    a = ap.parse_args()
    if a.steps < 1:
        sys.exit("generate_mixed.py: --steps must be >= 1")
    os.makedirs(a.outdir, exist_ok=True)
    side = box_side_m()
    dt = time_step_s()
    rng = random.Random(a.seed)
    pts = cloud(side, rng)
    vel = velocities(len(pts), rng)
    base = os.path.join(a.outdir, "mixed")
    write_gabion(base + ".gabion.json", pts, vel, side, a.steps, dt)
    write_liggghts_data(base + ".data", pts, vel, side)
    masses = [settle.DENSITY_KG_M3 * sphere_volume(p[3]) for p in pts]
    mtot = sum(masses)
    meta = {"n": len(pts), "classes": [{"radius_m": r, "count": n} for r, n in CLASSES], "seed": a.seed,
            "steps": a.steps, "dt_s": dt, "side_m": side, "solid_fraction": SOLID_FRACTION, "gap_m": GAP_M,
            "max_speed_m_s": MAX_SPEED_M_S, "density_kg_m3": settle.DENSITY_KG_M3, "kn_N_m": settle.KN_N_M,
            "ks_N_m": settle.KS_N_M, "friction": settle.FRICTION,
            "gabion_viscous_damping_ratio": settle.ZETA, "total_mass_kg": mtot,
            "initial_mean_z_m": sum(p[2] for p in pts) / len(pts),
            "initial_com_z_m": sum(m * p[2] for m, p in zip(masses, pts)) / mtot,
            "initial_kinetic_translational_J": sum(0.5 * m * (v[0] ** 2 + v[1] ** 2 + v[2] ** 2)
                                                   for m, v in zip(masses, vel))}
    with open(base + ".meta.json", "w") as f:
        json.dump(meta, f, indent=1)
        f.write("\n")
    print(f"generated {base}.* : N={len(pts)} L={side:.4f} m dt={dt:.6g} s steps={a.steps} seed={a.seed}")


if __name__ == "__main__":
    main()
