#!/usr/bin/env python3
"""Generate the settling benchmark scene (docs/performance.md, "micro" section).

One seeded random cloud of N monodisperse spheres, written three ways so that
Gabion, LIGGGHTS and Yade start from exactly the same positions:

  OUTDIR/settle_N.gabion.json   Gabion case (gabion.case/1, kind micro.scene)
  OUTDIR/settle_N.data          LIGGGHTS read_data file (atom_style granular)
  OUTDIR/settle_N.spheres       plain text "x y z" per line, read by yade_settle.py
  OUTDIR/settle_N.meta.json     the scene parameters (L, H, top of cloud, seed, ...)

Scene (shared/reference/bench-settle.md): radius 0.010 m, density 2500 kg/m3,
random sequential addition with a minimum gap of 1 mm between spheres and to
the side walls, centres between z = 0.05 + R and z = 0.05 + H - R (every
sphere lies inside the slab 0.05 <= z <= 0.05 + H), H chosen for a solid
fraction of 0.20 over the L x L floor. L = 0.6 m for N = 5,000 and 1.2 m for
N = 20,000; other N get L = 0.6 * sqrt(N / 5000) m (same H).

Standard library only. Same seed and N -> byte-identical files.
"""
import argparse
import json
import math
import os
import random
import sys

RADIUS_M = 0.010
DENSITY_KG_M3 = 2500.0
GAP_M = 0.001
Z0_M = 0.05
SOLID_FRACTION = 0.20
KN_N_M = 1.0e5
KS_N_M = 2.5e4
FRICTION = 0.5
DT_S = 4.0e-5
GRAVITY_M_S2 = 9.81
# Restitution about 0.5, as LIGGGHTS gamma_n = 1883 1/s gives for a
# sphere-sphere contact: zeta = -ln e / sqrt(pi^2 + ln^2 e).
RESTITUTION = 0.5
ZETA = -math.log(RESTITUTION) / math.sqrt(math.pi ** 2 + math.log(RESTITUTION) ** 2)


def floor_side_m(n):
    if n == 5000:
        return 0.6
    if n == 20000:
        return 1.2
    return 0.6 * math.sqrt(n / 5000.0)


def cloud(n, side, height, seed):
    """Random sequential addition; returns a list of (x, y, z) centres."""
    rng = random.Random(seed)
    lo_xy, hi_xy = RADIUS_M + GAP_M, side - RADIUS_M - GAP_M
    lo_z, hi_z = Z0_M + RADIUS_M, Z0_M + height - RADIUS_M
    min_d = 2.0 * RADIUS_M + GAP_M
    min_d2 = min_d * min_d
    cell = min_d
    grid = {}
    out = []
    attempts = 0
    max_attempts = 200 * n + 100000
    while len(out) < n:
        attempts += 1
        if attempts > max_attempts:
            sys.exit(f"generate.py: random sequential addition stuck after {attempts} tries "
                     f"({len(out)} of {n} placed)")
        x = rng.uniform(lo_xy, hi_xy)
        y = rng.uniform(lo_xy, hi_xy)
        z = rng.uniform(lo_z, hi_z)
        ci, cj, ck = int(x / cell), int(y / cell), int(z / cell)
        ok = True
        for di in (-1, 0, 1):
            for dj in (-1, 0, 1):
                for dk in (-1, 0, 1):
                    for (px, py, pz) in grid.get((ci + di, cj + dj, ck + dk), ()):
                        if (px - x) ** 2 + (py - y) ** 2 + (pz - z) ** 2 < min_d2:
                            ok = False
                            break
                    if not ok:
                        break
                if not ok:
                    break
            if not ok:
                break
        if ok:
            p = (x, y, z)
            grid.setdefault((ci, cj, ck), []).append(p)
            out.append(p)
    return out


def fmt(v):
    return float(f"{v:.9g}")


def write_gabion(path, pts, side, steps):
    duration = steps * DT_S
    case = {
        "format": "gabion.case/1",
        "kind": "micro.scene",
        "description": f"Settling benchmark: {len(pts)} spheres R=0.01 m falling into an open "
                       f"{side:g} m x {side:g} m box (bench/settle, docs/performance.md)",
        "gravity_m_s2": [0.0, 0.0, -GRAVITY_M_S2],
        "materials": {
            "grain": {
                "density_kg_m3": DENSITY_KG_M3,
                "normal_stiffness_N_m": KN_N_M,
                "shear_stiffness_N_m": KS_N_M,
                "friction": FRICTION,
                "viscous_damping_ratio": fmt(ZETA),
            }
        },
        "spheres": [{"center_m": [fmt(x), fmt(y), fmt(z)], "radius_m": RADIUS_M, "material": "grain"}
                    for (x, y, z) in pts],
        "walls": [
            {"point_m": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0], "material": "grain"},
            {"point_m": [0.0, 0.0, 0.0], "normal": [1.0, 0.0, 0.0], "material": "grain"},
            {"point_m": [side, 0.0, 0.0], "normal": [-1.0, 0.0, 0.0], "material": "grain"},
            {"point_m": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0], "material": "grain"},
            {"point_m": [0.0, side, 0.0], "normal": [0.0, -1.0, 0.0], "material": "grain"},
        ],
        "run": {"duration_s": fmt(duration), "dt_s": DT_S, "output_interval_s": fmt(duration)},
    }
    with open(path, "w") as f:
        # One sphere per line keeps the file readable and diffable.
        f.write("{\n")
        keys = list(case.keys())
        for i, k in enumerate(keys):
            sep = "," if i + 1 < len(keys) else ""
            if k == "spheres":
                f.write('  "spheres": [\n')
                for j, s in enumerate(case["spheres"]):
                    f.write("    " + json.dumps(s) + ("," if j + 1 < len(pts) else "") + "\n")
                f.write("  ]" + sep + "\n")
            else:
                f.write(f"  {json.dumps(k)}: {json.dumps(case[k])}{sep}\n")
        f.write("}\n")


def write_liggghts_data(path, pts, side, top):
    with open(path, "w") as f:
        f.write(f"LIGGGHTS data file: settling benchmark, {len(pts)} spheres (bench/settle/generate.py)\n\n")
        f.write(f"{len(pts)} atoms\n1 atom types\n\n")
        # Box a little larger than the walls so that no atom leaves the fixed box
        # before a wall/gran plane pushes it back.
        f.write(f"{-0.01:.6f} {side + 0.01:.6f} xlo xhi\n")
        f.write(f"{-0.01:.6f} {side + 0.01:.6f} ylo yhi\n")
        f.write(f"{-0.01:.6f} {top:.6f} zlo zhi\n\nAtoms\n\n")
        # atom_style granular: atom-ID atom-type diameter density x y z
        for i, (x, y, z) in enumerate(pts, start=1):
            f.write(f"{i} 1 {2 * RADIUS_M:.9g} {DENSITY_KG_M3:.9g} {x:.9g} {y:.9g} {z:.9g}\n")


def write_plain(path, pts):
    with open(path, "w") as f:
        for (x, y, z) in pts:
            f.write(f"{x:.9g} {y:.9g} {z:.9g}\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("n", type=int, help="number of spheres")
    ap.add_argument("--steps", type=int, default=10000, help="time steps of dt = 4e-5 s (default 10000)")
    ap.add_argument("--seed", type=int, default=20261122, help="random seed (default 20261122)")
    ap.add_argument("--outdir", default="bench/work", help="where to write (default bench/work)")
    a = ap.parse_args()
    if a.n < 1 or a.steps < 1:
        sys.exit("generate.py: n and --steps must be >= 1")
    os.makedirs(a.outdir, exist_ok=True)
    side = floor_side_m(a.n)
    vol = 4.0 / 3.0 * math.pi * RADIUS_M ** 3
    height = a.n * vol / (SOLID_FRACTION * side * side)
    pts = cloud(a.n, side, height, a.seed)
    # Room above the cloud for the LIGGGHTS box (spheres only fall).
    top = Z0_M + height + 0.1
    base = os.path.join(a.outdir, f"settle_{a.n}")
    write_gabion(base + ".gabion.json", pts, side, a.steps)
    write_liggghts_data(base + ".data", pts, side, top)
    write_plain(base + ".spheres", pts)
    meta = {"n": a.n, "seed": a.seed, "steps": a.steps, "dt_s": DT_S, "side_m": side,
            "cloud_height_m": height, "z0_m": Z0_M, "box_top_m": top, "radius_m": RADIUS_M,
            "density_kg_m3": DENSITY_KG_M3, "kn_N_m": KN_N_M, "ks_N_m": KS_N_M, "friction": FRICTION,
            "gabion_viscous_damping_ratio": ZETA,
            "initial_mean_z_m": sum(p[2] for p in pts) / len(pts)}
    with open(base + ".meta.json", "w") as f:
        json.dump(meta, f, indent=1)
        f.write("\n")
    print(f"generated {base}.* : N={a.n} L={side:g} m H={height:.4f} m steps={a.steps} seed={a.seed}")


if __name__ == "__main__":
    main()
