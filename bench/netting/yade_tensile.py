# -*- coding: utf-8 -*-
"""Yade side of the wire-netting sheet tensile benchmark.

Runs the sheet tensile test described by a netting file (JSON, format
"gabion.netting/1", see README.md) with Yade's wire model: WireMat,
Ip2_WireMat_WireMat_WirePhys and Law2_ScGeom_WirePhys_WirePM (type 0,
Bertrand et al. 2008 double-twist parameters lambda_k / lambda_eps).

How to call (Debian package "yade", 2023.02a; the binary is `yade`, a link to
`yade-double`):

    yade -j1 -n -x yade_tensile.py NETTING.json [csv=out.csv] [steps=N] \
         [csv_every=1000] [sample_every=100] [collider=1] [result=out.json]

or with environment variables (upper case names, same meaning):

    NETTING=NETTING.json CSV=out.csv STEPS=N yade -j1 -n -x yade_tensile.py

  -j1 / -j2      OpenMP threads (Yade's default is 1)
  -n             no GUI;  -x  exit when the script ends
  NETTING        netting description file (required)
  CSV            CSV output path (default: none written); columns
                 step,time_s,displacement_m,force_N every csv_every steps
  STEPS          number of steps (default: test.steps from the file)
  CSV_EVERY      K, CSV row period in steps (default 1000)
  SAMPLE_EVERY   period in steps of the force / rupture sampling that gives
                 peak force and first rupture (default 100; must divide K;
                 1 gives the exact peak and rupture step at some cost)
  COLLIDER       1 (default): keep Yade's InsertionSortCollider in the loop,
                 as in Yade's examples; 0: drop the collider after the links
                 are created (only the listed links are ever processed)
  RESULT         also write the JSON result line to this file

Output: one JSON line on stdout starting with {"engine": "yade", ...} with
nodes, links, steps, dt_s, wall_s (time of the O.run loop only),
peak_force_N, displacement_at_peak_m, broken_links, first_rupture_step.
Diagnostics go to stderr.

What is modelled:
  * every node is a Yade sphere of the listed radius; state.mass is the
    listed mass and the inertia 2/5 m r^2 (density plays no role);
  * exactly the listed links exist: each is created with createInteraction()
    at iteration 0 (so WirePhys.isLinked is true); afterwards
    Ip2.linkThresholdIteration is set to 0, aabbEnlargeFactor and
    interactionDetectionFactor to -1, so any interaction the collider might
    create later is never linked and Law2 erases it in the same step.
    WirePM has no compressive response, so node-node contact is OFF (in both
    engines for this benchmark);
  * link law per kind: "single" = mesh wire (wire.mesh_diameter_m),
    "selvedge" = wire of wire.selvedge_diameter_m, "double_twist" = two
    twisted mesh wires.  Yade decides the law from the body materials and ids
    (double twist iff both bodies share a WireMat with isDoubleTwist=True and
    |id1-id2| == 1; links between different materials take the thinner
    wire).  The script therefore uses three materials (twist nodes: mesh
    diameter, isDoubleTwist=True; other mesh nodes: mesh diameter,
    isDoubleTwist=False; selvedge nodes: selvedge diameter) and numbers the
    bodies itself so that exactly the double-twist partners get consecutive
    ids.  Before running, every link's WirePhys (kn, isDoubleTwist and the
    whole force-displacement table) is checked against the file and against
    Yade's formula; the script stops on any mismatch;
  * gravity 0, NewtonIntegrator damping = test.local_damping, O.dt = test.dt_s;
  * clamped nodes: blockedDOFs 'xyzXYZ', zero velocity; pulled nodes:
    blockedDOFs 'xyzXYZ', velocity = test.pull_velocity_m_s (constant);
  * force = sum over pulled nodes of -(O.forces.f(id) . u), u the unit pull
    direction (tension positive); displacement = |v| t.  The force sampled
    during step i belongs to the configuration at t = i dt (the CSV "step"
    is i, the number of completed steps before that force evaluation);
  * broken links = listed links minus the real interactions left (WirePM
    erases a link when it breaks); first_rupture_step is the first sampled
    step at which that count is non-zero (resolution SAMPLE_EVERY).
"""
import json
import math
import os
import sys
import time


def elog(*a):
    print(*a, file=sys.stderr)
    sys.stderr.flush()


def fail(msg, code=2):
    elog("yade_tensile: ERROR: " + msg)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


# ---------------------------------------------------------------- arguments
cfg = {}
for k in ("NETTING", "CSV", "STEPS", "CSV_EVERY", "SAMPLE_EVERY", "COLLIDER", "RESULT"):
    if os.environ.get(k):
        cfg[k] = os.environ[k]
for arg in sys.argv[1:]:
    if "=" in arg:
        k, v = arg.split("=", 1)
        cfg[k.strip().upper()] = v
    else:
        cfg["NETTING"] = arg
if "NETTING" not in cfg:
    fail("no netting file given (NETTING=path or first script argument)")

with open(cfg["NETTING"]) as f:
    net = json.load(f)
if net.get("format") != "gabion.netting/1":
    fail("unexpected format %r" % net.get("format"))

pos = net["nodes"]["position_m"]
rad = net["nodes"]["radius_m"]
mass = net["nodes"]["mass_kg"]
N = len(pos)
la = net["links"]["a"]
lb = net["links"]["b"]
lkind = net["links"]["kind"]
lrest = net["links"]["rest_length_m"]
lk_file = net["links"]["elastic_stiffness_N_m"]
L = len(la)
wire = net["wire"]
test = net["test"]

steps = int(cfg.get("STEPS", test["steps"]))
csv_every = int(cfg.get("CSV_EVERY", 1000))
sample_every = int(cfg.get("SAMPLE_EVERY", 100))
if csv_every % sample_every != 0:
    sample_every = math.gcd(csv_every, sample_every)
use_collider = cfg.get("COLLIDER", "1") not in ("0", "false", "no", "off")
dt = float(test["dt_s"])
damping = float(test["local_damping"])
vpull = [float(c) for c in test["pull_velocity_m_s"]]
vnorm = math.sqrt(sum(c * c for c in vpull))
if vnorm <= 0:
    fail("pull velocity is zero")
upull = [c / vnorm for c in vpull]

strain = [float(e) for e in wire["strain"]]
stress = [float(s) for s in wire["stress_Pa"]]
young = stress[0] / strain[0]
poisson = float(wire.get("poisson", 0.3))  # Yade's helix rule needs it; Gabion's twist does not
lambda_k = float(wire["lambda_k"])
lambda_eps = float(wire["lambda_eps"])
d_mesh = float(wire["mesh_diameter_m"])
d_selv = float(wire["selvedge_diameter_m"])

for i in range(L):
    if lkind[i] not in ("single", "selvedge", "double_twist"):
        fail("link %d: unknown kind %r" % (i, lkind[i]))
    if la[i] == lb[i]:
        fail("link %d joins node %d to itself" % (i, la[i]))

# ------------------------------------------- node classes and body numbering
pairset = {}
for i in range(L):
    key = (min(la[i], lb[i]), max(la[i], lb[i]))
    if key in pairset:
        fail("links %d and %d join the same nodes %s" % (pairset[key], i, key))
    pairset[key] = i

selv_nodes = set()
dt_adj = {}
for i in range(L):
    if lkind[i] == "selvedge":
        selv_nodes.update((la[i], lb[i]))
    elif lkind[i] == "double_twist":
        dt_adj.setdefault(la[i], []).append(lb[i])
        dt_adj.setdefault(lb[i], []).append(la[i])
both = selv_nodes & set(dt_adj)
if both:
    fail("%d nodes carry both a selvedge and a double-twist link (e.g. node %d); "
         "Yade's WireMat cannot express that" % (len(both), min(both)))
for i in range(L):
    if lkind[i] == "single" and la[i] in selv_nodes and lb[i] in selv_nodes and d_selv > d_mesh:
        fail("single link %d joins two selvedge nodes; Yade would give it the selvedge wire" % i)

# double-twist components must be simple paths -> blocks of consecutive ids
seen = set()
blocks = []
for n0 in sorted(dt_adj):
    if n0 in seen:
        continue
    comp, stack = [], [n0]
    seen.add(n0)
    while stack:
        n = stack.pop()
        comp.append(n)
        for m in dt_adj[n]:
            if m not in seen:
                seen.add(m)
                stack.append(m)
    if any(len(dt_adj[n]) > 2 for n in comp):
        fail("double-twist links around node %d do not form a chain" % n0)
    ends = [n for n in comp if len(dt_adj[n]) == 1]
    if not ends:
        fail("double-twist links around node %d form a loop" % n0)
    path, prev, cur = [ends[0]], None, ends[0]
    while True:
        nxt = [m for m in dt_adj[cur] if m != prev]
        if not nxt:
            break
        prev, cur = cur, nxt[0]
        path.append(cur)
    blocks.append(path)

other = [n for n in range(N) if n not in dt_adj]   # selvedge / plain mesh nodes
order = []          # body id -> node index (-1 = spacer body)
pending = list(blocks)
while pending:
    last = order[-1] if order and order[-1] >= 0 and order[-1] in dt_adj else None
    chosen = None
    for j in range(min(len(pending), 64)):
        for cand in (pending[j], pending[j][::-1]):
            if last is None or (min(last, cand[0]), max(last, cand[0])) not in pairset:
                chosen = (j, cand)
                break
        if chosen:
            break
    if chosen is None:
        order.append(other.pop() if other else -1)
        continue
    pending.pop(chosen[0])
    order.extend(chosen[1])
order.extend(other)
bid = [None] * N
for b, n in enumerate(order):
    if n >= 0:
        bid[n] = b
n_spacers = order.count(-1)

# ------------------------------------------------------------- materials
ss = [(e, s) for e, s in zip(strain, stress)]


def wiremat(d, dtwist):
    return O.materials.append(WireMat(young=young, poisson=poisson, frictionAngle=0.5,
                                      density=7850.0, isDoubleTwist=dtwist, diameter=d,
                                      strainStressValues=ss, lambdaEps=lambda_eps,
                                      lambdak=lambda_k, type=0))


mat_dt = wiremat(d_mesh, True)      # nodes of double twists
mat_mesh = wiremat(d_mesh, False)   # other mesh nodes
mat_selv = wiremat(d_selv, False)   # selvedge nodes

# --------------------------------------------------------------- bodies
far = 1e3
for b, n in enumerate(order):
    if n < 0:
        body = sphere((far + b, far, far), 0.01, material=mat_mesh)
        body.state.blockedDOFs = "xyzXYZ"
    else:
        m = mat_dt if n in dt_adj else (mat_selv if n in selv_nodes else mat_mesh)
        body = sphere(tuple(pos[n]), rad[n], material=m)
        body.state.mass = mass[n]
        I = 0.4 * mass[n] * rad[n] ** 2
        body.state.inertia = (I, I, I)
    got = O.bodies.append(body)
    if got != b:
        fail("body id %d != expected %d" % (got, b))

clamped = [bid[n] for n in test["clamped"]]
pulled = [bid[n] for n in test["pulled"]]
for b in clamped:
    st = O.bodies[b].state
    st.blockedDOFs = "xyzXYZ"
    st.vel = (0, 0, 0)
    st.angVel = (0, 0, 0)
for b in pulled:
    st = O.bodies[b].state
    st.blockedDOFs = "xyzXYZ"
    st.vel = tuple(vpull)
    st.angVel = (0, 0, 0)

# --------------------------------------------------------------- engines
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(aabbEnlargeFactor=-1, label="aabb")], label="collider"),
    InteractionLoop(
        [Ig2_Sphere_Sphere_ScGeom(interactionDetectionFactor=-1, label="ig2")],
        [Ip2_WireMat_WireMat_WirePhys(linkThresholdIteration=1, label="ip2")],
        [Law2_ScGeom_WirePhys_WirePM(linkThresholdIteration=1, label="law2")],
    ),
    NewtonIntegrator(damping=damping, gravity=(0, 0, 0), label="newton"),
    PyRunner(iterPeriod=sample_every, initRun=True, command="sample()", label="sampler"),
]
O.dt = dt

# links: created explicitly at iteration 0 (-> isLinked), nothing else
if O.iter != 0:
    fail("scene not at iteration 0")
for i in range(L):
    createInteraction(bid[la[i]], bid[lb[i]])
ip2.linkThresholdIteration = 0     # nothing created later is ever linked
aabb.aabbEnlargeFactor = -1.
ig2.interactionDetectionFactor = -1.
if not use_collider:
    O.engines = [e for e in O.engines if not isinstance(e, Collider)]

# ----------------------------------------------------------- verification
linkpairs = set((min(bid[la[i]], bid[lb[i]]), max(bid[la[i]], bid[lb[i]])) for i in range(L))


def count_real_links(when):
    # The real interactions, each of which must be a listed link.
    n = 0
    for I in O.interactions:
        if I.isReal:
            n += 1
            if (min(I.id1, I.id2), max(I.id1, I.id2)) not in linkpairs:
                fail("%sinteraction %d-%d is not a listed link" % (when, I.id1, I.id2))
    return n


nreal = count_real_links("")
if nreal != L or len(O.interactions) != L:
    fail("%d interactions (%d real) but %d links in the file" % (len(O.interactions), nreal, L))


def yade_curve(kind, l0):
    """Force-displacement table and elastic stiffness as Ip2_WireMat_WireMat_WirePhys
    (type 0) computes them; displacements and forces are negative in tension."""
    d = d_selv if kind == "selvedge" else d_mesh
    A = (d * 0.5) ** 2 * math.pi
    DF = [[-e * l0, -s * A] for e, s in zip(strain, stress)]
    k = DF[0][1] / DF[0][0]
    if kind == "double_twist":
        alpha = math.atan(l0 / (3. * math.pi * d))
        kh = k * (l0 * d / A) / (48. * math.cos(alpha) *
                                 (41. / 9. * (1. + poisson) + 17. / 4. * math.tan(alpha) ** 2))
        k = 2. * (lambda_k * kh + (1 - lambda_k) * k)
        F = k * DF[0][0]
        mapping = F / DF[0][1]
        DF[0][1] = F
        for p in DF[1:]:
            p[0] *= lambda_eps
            p[1] *= mapping
    return k, [[0., 0.]] + DF


def rel(a, b):
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


worst = {"kn_vs_file": 0., "kn_vs_formula": 0., "table": 0., "rest_length": 0.}
shown = set()
for i in range(L):
    b1, b2 = bid[la[i]], bid[lb[i]]
    I = O.interactions[b1, b2]
    ph = I.phys
    if not ph.isLinked:
        fail("link %d (bodies %d-%d) is not linked" % (i, b1, b2))
    if ph.isDoubleTwist != (lkind[i] == "double_twist"):
        fail("link %d (%s): WirePhys.isDoubleTwist=%s" % (i, lkind[i], ph.isDoubleTwist))
    l0 = O.bodies[b1].shape.radius + O.bodies[b2].shape.radius - ph.initD
    worst["rest_length"] = max(worst["rest_length"], rel(l0, lrest[i]))
    kf, DF = yade_curve(lkind[i], l0)
    # Yade's double twist follows its own published rule (helix stiffness,
    # forces scaled with it); Gabion's is two wires, stiffness x lambda_k
    # (docs/netting.md). Only the single and selvedge wires must agree.
    if lkind[i] != "double_twist":
        worst["kn_vs_file"] = max(worst["kn_vs_file"], rel(ph.kn, lk_file[i]))
    worst["kn_vs_formula"] = max(worst["kn_vs_formula"], rel(ph.kn, kf))
    got = [[float(p[0]), float(p[1])] for p in ph.displForceValues]
    if len(got) != len(DF):
        fail("link %d: %d table points, expected %d" % (i, len(got), len(DF)))
    for p, q in zip(got, DF):
        for x, y in zip(p, q):
            if x != y:
                worst["table"] = max(worst["table"], rel(x, y))
    if lkind[i] not in shown:
        shown.add(lkind[i])
        elog("link %d %-12s nodes %d-%d bodies %d-%d L0=%.6g m  Yade kn=%.9g  file k=%.9g  rel=%.2e  "
            "rupture at %.6g m / %.6g N" % (i, lkind[i], la[i], lb[i], b1, b2, l0, ph.kn, lk_file[i],
                                            rel(ph.kn, lk_file[i]), -got[-1][0], -got[-1][1]))
elog("checked %d links: max rel diff kn vs file %.2e, kn vs formula %.2e, table %.2e, L0 vs rest %.2e"
    % (L, worst["kn_vs_file"], worst["kn_vs_formula"], worst["table"], worst["rest_length"]))
if worst["kn_vs_file"] > 1e-6:
    fail("Yade's elastic stiffness differs from the file's elastic_stiffness_N_m")
if worst["kn_vs_formula"] > 1e-9 or worst["table"] > 1e-9:
    fail("Yade's WirePhys differs from the expected WirePM curve")
if worst["rest_length"] > 1e-6:
    fail("rest lengths differ from the initial node distances (Yade links are stress free at creation)")

# ----------------------------------------------------------------- run
state = {"peak": -float("inf"), "peak_disp": 0., "peak_step": 0, "first_rupture": None,
         "broken": 0, "extra_max": 0}
rows = []


def sample():
    it = O.iter
    t = O.time
    F = 0.
    for b in pulled:
        f = O.forces.f(b)
        F -= f[0] * upull[0] + f[1] * upull[1] + f[2] * upull[2]
    disp = vnorm * t
    if F > state["peak"]:
        state["peak"], state["peak_disp"], state["peak_step"] = F, disp, it
    broken = L - O.interactions.countReal()
    if broken > 0 and state["first_rupture"] is None:
        state["first_rupture"] = it
    state["broken"] = broken
    if it % csv_every == 0:
        rows.append((it, t, disp, F))


elog("yade_tensile: %d nodes (%d spacer bodies), %d links, %d steps, dt=%g s, threads=%d, collider=%s"
    % (N, n_spacers, L, steps, dt, O.numThreads, use_collider))
t0 = time.perf_counter()
O.run(steps, True)
wall = time.perf_counter() - t0

# final bookkeeping (outside the timed loop)
nreal = count_real_links("after the run: ")
broken = L - nreal
broken_by_kind = {}
broken_ids = []
for i in range(L):
    I = O.interactions[bid[la[i]], bid[lb[i]]] if O.interactions.has(bid[la[i]], bid[lb[i]]) else None
    if I is None or not I.isReal:
        broken_ids.append(i)
        broken_by_kind[lkind[i]] = broken_by_kind.get(lkind[i], 0) + 1
if broken_ids:
    elog("broken links (file indices): %s" % broken_ids)
nb_state = sum(O.bodies[b].state.numBrokenLinks for b in range(len(order)))
if nb_state != 2 * broken:
    elog("warning: WireState.numBrokenLinks sum %d != 2 x broken links %d" % (nb_state, broken))

if "CSV" in cfg:
    with open(cfg["CSV"], "w") as f:
        f.write("step,time_s,displacement_m,force_N\n")
        for r in rows:
            f.write("%d,%.9g,%.9g,%.9g\n" % r)

result = {
    "engine": "yade",
    "nodes": N,
    "links": L,
    "steps": steps,
    "dt_s": dt,
    "wall_s": wall,
    "peak_force_N": state["peak"],
    "displacement_at_peak_m": state["peak_disp"],
    "broken_links": broken,
    "first_rupture_step": state["first_rupture"],
    "broken_by_kind": broken_by_kind,
    "threads": O.numThreads,
    "collider": use_collider,
    "sample_every": sample_every,
    "yade_version": yade.config.version,
}
line = json.dumps(result)
if "RESULT" in cfg:
    with open(cfg["RESULT"], "w") as f:
        f.write(line + "\n")
sys.stderr.flush()
print(line)
sys.stdout.flush()
