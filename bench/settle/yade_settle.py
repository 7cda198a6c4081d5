# Yade script: settling benchmark (bench/settle, docs/performance.md).
# Run in batch mode, one thread:
#   BENCH_SPHERES=bench/work/settle_5000.spheres BENCH_SIDE=0.6 BENCH_STEPS=10000 \
#   BENCH_RESULT=out.json yade -j1 -n -x bench/settle/yade_settle.py
# Contact: Law2_ScGeom_FrictPhys_CundallStrack (linear normal spring,
# incremental tangential spring, Coulomb friction 0.5). Ip2_FrictMat_FrictMat_FrictPhys
# gives kn = 2 Ea Ra Eb Rb / (Ea Ra + Eb Rb) = E R for two equal spheres, and
# ks = poisson * kn, so E = kn / R = 1e7 Pa and poisson = ks / kn = 0.25 give
# kn = 1e5 N/m and ks = 2.5e4 N/m exactly; the script checks this on every
# real contact at the end (sphere-sphere and sphere-wall) and fails otherwise.
# Collider: InsertionSortCollider with verletDist 0.1 R (the same 2 mm skin as
# the other engines; Yade's default 0.5 R doubled the run time here).
# Dissipation: Cundall local damping 0.2 (NewtonIntegrator.damping), no
# viscous damping. The figure of merit is the wall time of O.run(steps, True)
# only: building the scene before and the checks after are not timed.
import json
import math
import os
import sys
import time

from yade import O, utils
from yade.wrapper import (FrictMat, ForceResetter, InsertionSortCollider, Bo1_Sphere_Aabb, Bo1_Wall_Aabb,
                          InteractionLoop, Ig2_Sphere_Sphere_ScGeom, Ig2_Wall_Sphere_ScGeom,
                          Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom_FrictPhys_CundallStrack,
                          NewtonIntegrator)

RADIUS_M = 0.010
KN, KS = 1.0e5, 2.5e4

spheres_file = os.environ["BENCH_SPHERES"]
side = float(os.environ["BENCH_SIDE"])
steps = int(os.environ.get("BENCH_STEPS", "10000"))
result_file = os.environ.get("BENCH_RESULT", "")

mat = O.materials.append(FrictMat(young=KN / RADIUS_M, poisson=KS / KN, frictionAngle=math.atan(0.5),
                                  density=2500.0, label="grain"))
with open(spheres_file) as f:
    centres = [tuple(float(v) for v in line.split()) for line in f if line.strip()]
O.bodies.append([utils.sphere(c, RADIUS_M, material=mat) for c in centres])
# utils.wall(position, axis, sense): sense 1 = contact on the positive side.
O.bodies.append([
    utils.wall(0.0, axis=2, sense=1, material=mat),
    utils.wall(0.0, axis=0, sense=1, material=mat),
    utils.wall(side, axis=0, sense=-1, material=mat),
    utils.wall(0.0, axis=1, sense=1, material=mat),
    utils.wall(side, axis=1, sense=-1, material=mat),
])

O.engines = [
    ForceResetter(),
    # Bounds enlarged by 1 mm (0.1 R): pairs are found up to a 2 mm gap, the
    # same skin as Gabion (verlet_skin_ratio 0.2) and LIGGGHTS (neighbor 0.002).
    # Yade's default (verletDist = -0.5: 0.5 R) made this scene 2x slower.
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()], verletDist=0.1 * RADIUS_M),
    InteractionLoop(
        [Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
        [Ip2_FrictMat_FrictMat_FrictPhys()],
        [Law2_ScGeom_FrictPhys_CundallStrack()],
    ),
    NewtonIntegrator(damping=0.2, gravity=(0.0, 0.0, -9.81)),
]
O.dt = 4.0e-5

t0 = time.perf_counter()
O.run(steps, True)
loop_s = time.perf_counter() - t0

n = len(centres)
zsum = 0.0
ke_t = 0.0
ke_r = 0.0
for b in O.bodies:
    if not isinstance(b.shape, type(O.bodies[0].shape)):
        continue
    zsum += b.state.pos[2]
    ke_t += 0.5 * b.state.mass * b.state.vel.squaredNorm()
    w = b.state.angVel
    ke_r += 0.5 * b.state.inertia[0] * w.squaredNorm()  # sphere: isotropic inertia

kn_seen = set()
ks_seen = set()
real = 0
for i in O.interactions:
    if not i.isReal:
        continue
    real += 1
    kn_seen.add(round(i.phys.kn, 6))
    ks_seen.add(round(i.phys.ks, 6))
ok = all(abs(k - KN) <= 1e-6 * KN for k in kn_seen) and all(abs(k - KS) <= 1e-6 * KS for k in ks_seen)

res = {
    "engine": "yade",
    "n": n,
    "steps": int(O.iter),
    "step_loop_wall_time_s": loop_s,
    "mean_z_m": zsum / n,
    "kinetic_translational_J": ke_t,
    "kinetic_rotational_J": ke_r,
    "real_contacts": real,
    "contact_kn_N_m": sorted(kn_seen),
    "contact_ks_N_m": sorted(ks_seen),
    "stiffness_ok": ok,
}
print("BENCH_RESULT " + json.dumps(res))
if result_file:
    with open(result_file, "w") as f:
        json.dump(res, f, indent=1)
sys.stdout.flush()
if not ok:
    sys.stderr.write("yade_settle.py: contact stiffness differs from kn=1e5, ks=2.5e4: kn %s ks %s\n"
                     % (sorted(kn_seen), sorted(ks_seen)))
    os._exit(4)
