#!/usr/bin/env python3
"""Settling benchmark: Gabion against LIGGGHTS, Yade and the ceiling kernel.

Called by bench/settle/run.sh (see there and docs/performance.md). Two scenes:

  settle  N monodisperse spheres settling into an open box (generate.py,
          shared/reference/bench-settle.md), for each N given;
  mixed   22,020 spheres of radius 4, 18 and 70 mm in a closed box
          (generate_mixed.py), Gabion and LIGGGHTS only.

For each scene it generates the input (seeded), runs every engine that is
installed in turn (round-robin with --repeat) and prints one table per scene:

  engine, threads, N, steps, loop wall time, body-steps/s, body-steps/s per
  core, ratios (to LIGGGHTS, Yade and the ceiling kernel at the same N; in the
  mixed scene to the best LIGGGHTS setting and to the engine's own settling
  speed), peak memory (max RSS) and memory per body, the load average before
  the run, the share of its cores the process got, body-steps per CPU-second
  of the loop (from a second, 1-step run that measures the start-up), and the
  mean height, translational kinetic energy and contact count at the end
  (physics sanity). Around every run with threads it measures where the two
  CPUs lie (bench_core_round_trip: the cache-line round trip and how fast
  they compute together), and splits the paired two-thread gains by it.

The loop time of each engine covers the time steps only:
  Gabion   summary.json results.step_loop_wall_time_s (timed inside the run)
  LIGGGHTS the "Loop time of ..." line printed after `run` (LIGGGHTS' own timer)
  Yade     time.perf_counter() around O.run(steps, True) in yade_settle.py
  ceiling  the "loop_time" line of ../shared/reference/ceiling/sol.cpp (a
           steady clock around its step loop), built here into bench/work/ceiling
Peak memory: "Maximum resident set size" of /usr/bin/time -v (GNU time), or,
if that is not installed, the ru_maxrss that os.wait4 returns for the child
(the same kernel counter GNU time reads).

Standard library only. Exit code 0 when every engine that was found ran.
"""
import argparse
import datetime
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
GNU_TIME = "/usr/bin/time"
TIMED_OUT = " (stopped by --timeout)"

INSTALL_HINT = {
    "liggghts": "apt-get install -y liggghts   (Debian package; binary /usr/bin/liggghts)",
    "yade": "apt-get install -y yade   (Debian package; binary /usr/bin/yade)",
    "gabion": "scripts/build.sh   (builds build/gabion), or pass --gabion PATH",
}


def log(msg):
    print(msg, flush=True)


def loadavg():
    try:
        with open("/proc/loadavg") as f:
            return [float(v) for v in f.read().split()[:3]]
    except OSError:
        return [float("nan")] * 3


def cpu_model():
    """"AMD EPYC (family 25, model 17)": the name alone does not tell Zen 4 from Zen 5."""
    fields = {}
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if not line.strip():
                    break
                k, _, v = line.partition(":")
                fields[k.strip()] = v.strip()
    except OSError:
        pass
    name = fields.get("model name", "unknown")
    if "cpu family" in fields and "model" in fields:
        name += f" (family {fields['cpu family']}, model {fields['model']})"
    return name


# Where the two CPUs of a two-thread run lie (on a virtual machine this can
# change within minutes), from two measures of bench_core_round_trip: near
# (a cache-line round trip under TRIP_NEAR_NS: cores that share a cache) or
# apart, and, near, whether the two compute together each at its speed
# alone or markedly slower (the two hardware threads of one core share its
# arithmetic units; another job on the host's cores slows them too). On the
# Zen 5 machine measured the trips were 70-120 ns near and 400-560 ns apart.
TRIP_NEAR_NS = 250
TOGETHER_FULL = 0.8
PLACES = {"near": "near, at full speed together", "near_slow": "near, slower together", "apart": "apart"}


def core_pair(gabion, quick=False):
    """CPUs 0 and 1 as bench_core_round_trip (built beside gabion, build/bench/) measures them:
    {"trip_ns": the cache-line round trip (what every fork and join of a two-thread step pays, several
    times a step), "together": their speed computing at once over one alone, "memory": CPU 1's speed
    reading memory alone over CPU 0's (the host's other work can slow one CPU's memory side: a
    one-thread run then depends on which CPU it lands on)}, each None where not
    measured (not built, one CPU). quick: fewer trips (a quarter of a second in all), around each run
    with threads."""
    out = {"trip_ns": None, "together": None, "memory": None}
    exe = os.path.join(os.path.dirname(os.path.abspath(gabion)), "bench", "bench_core_round_trip")
    if (os.cpu_count() or 1) < 2 or not os.access(exe, os.X_OK):
        return out
    try:
        args = ["--trips", "50000", "--batches", "3"] if quick else []
        text = subprocess.run([exe] + args, capture_output=True, text=True, timeout=60).stdout
    except (OSError, subprocess.SubprocessError):
        return out
    m = re.search(r"round trip .*?: (\d+) ns", text)
    out["trip_ns"] = int(m.group(1)) if m else None
    m = re.search(r"computing together: ([0-9.]+)", text)
    out["together"] = float(m.group(1)) if m else None
    m = re.search(r"reading memory: CPU \d+ at ([0-9.]+)", text)
    out["memory"] = float(m.group(1)) if m else None
    return out


def placement(pair):
    """A key of PLACES for a core_pair() measurement; None where not measured."""
    if not pair or pair.get("trip_ns") is None:
        return None
    if pair["trip_ns"] >= TRIP_NEAR_NS:
        return "apart"
    return "near_slow" if pair.get("together") is not None and pair["together"] < TOGETHER_FULL else "near"


def run_measured(cmd, cwd, env, stdout_path, stderr_path, timeout_s):
    """Runs cmd; returns (rc, max_rss_kB or None, elapsed_s, how, cpu_s).

    cpu_s is the user + system CPU time of the whole process (start-up and
    output included), from os.wait4 (with GNU time in between, its rusage
    includes the engine it waited for)."""
    time_file = stderr_path + ".time"
    use_gnu_time = os.access(GNU_TIME, os.X_OK)
    full = [GNU_TIME, "-v", "-o", time_file] + cmd if use_gnu_time else cmd
    t0 = time.perf_counter()
    with open(stdout_path, "w") as out, open(stderr_path, "w") as err:
        proc = subprocess.Popen(full, cwd=cwd, env=env, stdout=out, stderr=err, stdin=subprocess.DEVNULL,
                                start_new_session=True)
        deadline = None if timeout_s <= 0 else t0 + timeout_s
        rc = None
        rusage = None
        while rc is None:
            pid, status, ru = os.wait4(proc.pid, os.WNOHANG)
            if pid == proc.pid:
                rc = os.waitstatus_to_exitcode(status)
                rusage = ru
                proc.returncode = rc
                break
            if deadline is not None and time.perf_counter() > deadline:
                # The engine runs under /usr/bin/time in its own session: stop them all.
                os.killpg(proc.pid, 9)
                _, _, rusage = os.wait4(proc.pid, 0)
                rc = 124
                break
            time.sleep(0.05)
    elapsed = time.perf_counter() - t0
    rss = None
    how = ""
    if use_gnu_time and os.path.exists(time_file):
        with open(time_file) as f:
            m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", f.read())
        if m:
            rss = int(m.group(1))
            how = "/usr/bin/time -v"
    if rss is None and rusage is not None and not use_gnu_time:
        rss = int(rusage.ru_maxrss)  # kB on Linux
        how = "os.wait4 ru_maxrss"
    cpu = rusage.ru_utime + rusage.ru_stime if rusage is not None else None
    return rc, rss, elapsed, how, cpu


def tail(path, n=15):
    try:
        with open(path, errors="replace") as f:
            lines = f.read().splitlines()
        return "\n".join("      " + s for s in lines[-n:])
    except OSError:
        return ""

INSTALL_HINT["ceiling"] = ("the kernel's sources in the repository's sibling shared/reference/ceiling (sol.cpp, "
                           "gen.py) and g++ with OpenMP; or pass --ceiling-dir PATH")

GRAVITY_M_S2 = 9.81
SETTLE_DT_S = 4.0e-5
SETTLE_SPHERE_MASS_KG = 2500.0 * 4.0 / 3.0 * math.pi * 0.010 ** 3
# The ceiling kernel's compile lines, as in shared/reference/ceiling/README.md.
CEILING_FLAGS = ["-O3", "-march=native", "-fno-math-errno", "-fno-trapping-math"]
CEILING_BUILDS = {"sol": CEILING_FLAGS + ["-fopenmp-simd"], "sol_omp": CEILING_FLAGS + ["-fopenmp"]}
# A LIGGGHTS neighbour setting whose list-based sphere-sphere contact count is
# below this share of the count found geometrically in its final state misses
# contacts (LIGGGHTS 3.8's `neighbor ... multi` finds none).
CONTACTS_FOUND_SHARE = 0.99


# ---------------------------------------------------------------- engines


def gabion_available(binary):
    if not binary or not os.access(binary, os.X_OK):
        return False, f"no executable at {binary}"
    try:
        out = subprocess.run([binary, "kinds"], capture_output=True, text=True, timeout=60).stdout
    except (OSError, subprocess.TimeoutExpired) as e:
        return False, f"{binary} kinds failed: {e}"
    if not any(line.split("\t")[0].strip() == "micro.scene" for line in out.splitlines()):
        kinds = ", ".join(line.split("\t")[0] for line in out.splitlines() if line.strip()) or "none"
        return False, f"{binary} has no case kind micro.scene yet (its kinds: {kinds})"
    return True, ""


def run_engine(cmd, rundir, env, timeout_s):
    """Runs one engine in rundir (stdout.txt, stderr.txt there) with
    run_measured; returns the result record every row starts from."""
    rc, rss, elapsed, how, cpu = run_measured(cmd, rundir, env, os.path.join(rundir, "stdout.txt"),
                                              os.path.join(rundir, "stderr.txt"), timeout_s)
    return {"cmd": cmd, "rc": rc, "rss_kB": rss, "rss_how": how, "elapsed_s": elapsed, "cpu_s": cpu}


def engine_stdout(rundir):
    with open(os.path.join(rundir, "stdout.txt"), errors="replace") as f:
        return f.read()


def run_gabion(binary, scene, threads, rundir, timeout_s):
    outdir = os.path.join(rundir, "out")
    duration = repr(scene["steps"] * scene["dt_s"])
    cmd = [binary, "run", scene["gabion_case"], "-o", outdir, "--threads", str(threads), "-q",
           "--set", f"run.duration_s={duration}", "--set", f"run.output_interval_s={duration}"]
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    res = run_engine(cmd, rundir, env, timeout_s)
    rc = res["rc"]
    summary_path = os.path.join(outdir, "summary.json")
    if rc != 0 or not os.path.exists(summary_path):
        res["error"] = f"exit code {rc}{TIMED_OUT if rc == 124 else ''}\n" + tail(os.path.join(rundir, "stderr.txt"))
        return res
    with open(summary_path) as f:
        s = json.load(f)
    r = s.get("results", s)
    loop = r.get("step_loop_wall_time_s", s.get("step_loop_wall_time_s"))
    steps = s.get("steps", r.get("steps"))
    if loop is None or steps is None:
        res["error"] = "summary.json has no step_loop_wall_time_s or steps"
        return res
    res["loop_s"] = float(loop)
    res["steps"] = int(steps)
    res["status"] = s.get("status")
    res["profile"] = s.get("profile") or r.get("profile")
    contacts = r.get("contacts", s.get("contacts"))
    res["contacts"] = int(contacts) if contacts is not None else None
    mz, ket = gabion_sanity(s, scene)
    res["mean_z_m"] = mz
    res["ke_t_J"] = ket
    return res


def gabion_sanity(summary, scene):
    """Centre-of-mass height and translational kinetic energy at the end of a Gabion run.

    Both come from the energy terms of summary.json: kinetic_translational_J,
    and gravity_potential_J = -sum m g.x (zero at the origin), which under
    g = 9.81 m/s2 along -z is M g z_cm (M the total mass); for N equal spheres
    z_cm is their mean height."""
    energy = summary.get("energy") or summary.get("results", {}).get("energy") or {}
    ket = energy.get("kinetic_translational_J")
    ket = float(ket) if ket is not None else None
    mz = None
    pe = energy.get("gravity_potential_J")
    if pe is not None:
        mz = float(pe) / (scene["total_mass_kg"] * GRAVITY_M_S2)
    return mz, ket


def parse_neigh(spec):
    """LIGGGHTS neighbour setting "STYLE:SKIN[:BINSIZE]" -> (style, skin m, binsize m; 0 = default)."""
    parts = spec.split(":")
    if len(parts) not in (2, 3) or parts[0] not in ("bin", "multi"):
        raise ValueError(f"LIGGGHTS neighbour setting '{spec}': expected bin|multi:SKIN[:BINSIZE] (metres)")
    skin = float(parts[1])
    binsize = float(parts[2]) if len(parts) == 3 else 0.0
    if skin <= 0 or binsize < 0:
        raise ValueError(f"LIGGGHTS neighbour setting '{spec}': skin must be > 0, binsize >= 0")
    return parts[0], skin, binsize


def neigh_words(spec):
    style, skin, binsize = parse_neigh(spec)
    s = f"{style}, skin {skin * 1e3:g} mm"
    return s + (f", binsize {binsize * 1e3:g} mm" if binsize > 0 else "")


def run_liggghts(binary, scene, rundir, timeout_s, neigh=None):
    if scene["name"] == "settle":
        cmd = [binary, "-in", os.path.join(HERE, "in.settle"), "-log", "none", "-echo", "none",
               "-var", "datafile", scene["liggghts_data"], "-var", "side", repr(scene["side_m"]),
               "-var", "steps", str(scene["steps"])]
    else:
        style, skin, binsize = parse_neigh(neigh)
        cmd = [binary, "-in", os.path.join(HERE, "in.mixed"), "-log", "none", "-echo", "none",
               "-var", "datafile", scene["liggghts_data"], "-var", "side", repr(scene["side_m"]),
               "-var", "steps", str(scene["steps"]), "-var", "dt", repr(scene["dt_s"]),
               "-var", "skin", repr(skin), "-var", "neighstyle", style, "-var", "binsize", repr(binsize),
               "-var", "dumpfile", os.path.join(rundir, "final.dump")]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    res = run_engine(cmd, rundir, env, timeout_s)
    rc = res["rc"]
    text = engine_stdout(rundir)
    m = re.search(r"Loop time of ([\d.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", text)
    r = re.search(r"BENCH_RESULT mean_z_m (\S+) kinetic_translational_J (\S+) kinetic_rotational_J (\S+)", text)
    c = re.search(r"BENCH_CONTACTS pair (\S+) wall (\S+)", text)
    if rc != 0 or not m or not r:
        res["error"] = (f"exit code {rc}{TIMED_OUT if rc == 124 else ''}, loop line {'found' if m else 'missing'}\n"
                        + tail(os.path.join(rundir, "stdout.txt")) + "\n" + tail(os.path.join(rundir, "stderr.txt")))
        return res
    if int(m.group(4)) != scene["n"]:
        res["error"] = f"LIGGGHTS ended with {m.group(4)} atoms, expected {scene['n']}"
        return res
    res["loop_s"] = float(m.group(1))
    res["steps"] = int(m.group(3))
    res["mean_z_m"] = float(r.group(1))
    res["ke_t_J"] = float(r.group(2))
    if c:
        res["contacts_pair"] = int(round(float(c.group(1))))
        res["contacts_wall"] = int(round(float(c.group(2))))
        res["contacts"] = res["contacts_pair"] + res["contacts_wall"]
    dump = os.path.join(rundir, "final.dump")
    if scene["name"] == "mixed" and os.path.exists(dump):
        pairs, walls = count_contacts_dump(dump, scene["side_m"])
        res["contacts_geom_pair"] = pairs
        res["contacts_geom"] = pairs + walls
        res["finds_contacts"] = ("contacts_pair" in res
                                 and res["contacts_pair"] >= CONTACTS_FOUND_SHARE * pairs)
    return res


def count_contacts_dump(path, side):
    """Sphere-sphere and sphere-wall contacts (d < r_i + r_j; coordinate < r from
    one of the six walls of the cube [0, side]^3) in a LIGGGHTS dump whose
    ATOMS lines are "id type radius x y z", found geometrically with a hash
    grid: independent of the engine's neighbour list."""
    pts = []
    with open(path) as f:
        lines = f.read().splitlines()
    start = next(i for i, s in enumerate(lines) if s.startswith("ITEM: ATOMS"))
    cols = lines[start].split()[2:]
    ir, ix, iy, iz = cols.index("radius"), cols.index("x"), cols.index("y"), cols.index("z")
    for s in lines[start + 1:]:
        v = s.split()
        if len(v) == len(cols):
            pts.append((float(v[ix]), float(v[iy]), float(v[iz]), float(v[ir])))
    cell = 0.02
    grid = {}
    for q, (x, y, z, r) in enumerate(pts):
        for key in _cells((x, y, z), r, cell):
            grid.setdefault(key, []).append(q)
    pairs = 0
    walls = 0
    for q, (x, y, z, r) in enumerate(pts):
        seen = set()
        for key in _cells((x, y, z), r, cell):
            for p in grid[key]:
                if p <= q or p in seen:
                    continue
                seen.add(p)
                px, py, pz, pr = pts[p]
                d = r + pr
                if (px - x) ** 2 + (py - y) ** 2 + (pz - z) ** 2 < d * d:
                    pairs += 1
        for c in (x, y, z):
            walls += (c < r) + (c > side - r)
    return pairs, walls


def _cells(c, reach, cell):
    lo = [int(math.floor((c[k] - reach) / cell)) for k in range(3)]
    hi = [int(math.floor((c[k] + reach) / cell)) for k in range(3)]
    return [(i, j, k) for i in range(lo[0], hi[0] + 1) for j in range(lo[1], hi[1] + 1)
            for k in range(lo[2], hi[2] + 1)]


def run_yade(binary, scene, rundir, timeout_s):
    result_json = os.path.join(rundir, "result.json")
    cmd = [binary, "-j1", "-n", "-x", os.path.join(HERE, "yade_settle.py")]
    env = dict(os.environ, OMP_NUM_THREADS="1", BENCH_SPHERES=scene["spheres"], BENCH_SIDE=repr(scene["side_m"]),
               BENCH_STEPS=str(scene["steps"]), BENCH_RESULT=result_json)
    res = run_engine(cmd, rundir, env, timeout_s)
    rc = res["rc"]
    if rc != 0 or not os.path.exists(result_json):
        res["error"] = (f"exit code {rc}{TIMED_OUT if rc == 124 else ''}\n" + tail(os.path.join(rundir, "stdout.txt"))
                        + "\n" + tail(os.path.join(rundir, "stderr.txt")))
        return res
    with open(result_json) as f:
        y = json.load(f)
    res["loop_s"] = float(y["step_loop_wall_time_s"])
    res["steps"] = int(y["steps"])
    res["mean_z_m"] = y["mean_z_m"]
    res["ke_t_J"] = y["kinetic_translational_J"]
    res["yade_contact_kn"] = y["contact_kn_N_m"]
    if y.get("real_contacts") is not None:
        res["contacts"] = int(y["real_contacts"])
    return res


def build_ceiling(src_dir, bindir):
    """Builds the ceiling kernel (sol.cpp) twice with its README's compile lines.

    Returns ({"sol": path, "sol_omp": path, "cmds": [...], "compiler": ...}, None)
    or (None, why). A build is reused while sol.cpp and the command are unchanged."""
    src = os.path.join(src_dir, "sol.cpp")
    gen = os.path.join(src_dir, "gen.py")
    for p in (src, gen):
        if not os.path.exists(p):
            return None, f"no {p}"
    cxx = shutil.which("g++")
    if not cxx:
        return None, "no g++ on PATH"
    os.makedirs(bindir, exist_ok=True)
    out = {"cmds": [], "source": os.path.abspath(src)}
    try:
        out["compiler"] = subprocess.run([cxx, "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        out["compiler"] = "g++"
    for name, flags in CEILING_BUILDS.items():
        exe = os.path.join(bindir, name)
        cmd = ["g++"] + flags + ["-o", exe, src]
        stamp = exe + ".cmd"
        out["cmds"].append(" ".join(["g++"] + flags + ["-o", name, "sol.cpp"]))
        fresh = (os.path.exists(exe) and os.path.exists(stamp) and os.path.getmtime(exe) >= os.path.getmtime(src))
        if fresh:
            with open(stamp) as f:
                fresh = f.read() == " ".join(cmd)
        if not fresh:
            log(f"building the ceiling kernel: {' '.join(cmd)}")
            p = subprocess.run(cmd, capture_output=True, text=True)
            if p.returncode != 0:
                return None, f"{' '.join(cmd)} failed:\n{p.stderr[-2000:]}"
            with open(stamp, "w") as f:
                f.write(" ".join(cmd))
        out[name] = exe
    out["gen"] = gen
    return out, None


def ceiling_gen_cloud(ceiling, n, side, bindir):
    """The kernel's own cloud (its gen.py, run in bindir): spheres_N.txt."""
    path = os.path.join(bindir, f"spheres_{n}.txt")
    stamp = path + ".side"
    if not (os.path.exists(path) and os.path.exists(stamp) and os.path.getmtime(path) >= os.path.getmtime(ceiling["gen"])
            and open(stamp).read() == repr(side)):
        subprocess.run([sys.executable, ceiling["gen"], str(n), repr(side)], cwd=bindir, check=True,
                       stdout=subprocess.DEVNULL)
        with open(stamp, "w") as f:
            f.write(repr(side))
    with open(path) as f:
        zs = [float(s.split()[2]) for s in f if s.strip()]
    return path, (sum(zs) / len(zs) if zs else float("nan")), len(zs)


def run_ceiling(ceiling, scene, threads, rundir, timeout_s, cloud):
    exe = ceiling["sol"] if threads == 1 else ceiling["sol_omp"]
    spheres = scene["spheres"] if cloud == "ours" else scene["ceiling_gen_spheres"]
    cmd = [exe, spheres, repr(scene["side_m"]), "--steps", str(scene["steps"])]
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    res = run_engine(cmd, rundir, env, timeout_s)
    rc = res["rc"]
    text = engine_stdout(rundir)
    h = re.search(r"N=(\d+) L=\S+ threads=(\d+)", text)
    m = re.search(r"loop_time ([\d.eE+-]+) s", text)
    r = re.search(r"final: KE (\S+) J\s+KErot (\S+) J\s+PE (\S+) J.*contacts pp (\d+) \(direct search (\d+)\)\s+pw (\d+)",
                  text)
    if rc != 0 or not m or not r or not h:
        res["error"] = (f"exit code {rc}{TIMED_OUT if rc == 124 else ''}, loop line {'found' if m else 'missing'}\n"
                        + tail(os.path.join(rundir, "stdout.txt")) + "\n" + tail(os.path.join(rundir, "stderr.txt")))
        return res
    if int(h.group(1)) != scene["n"] or int(h.group(2)) != threads:
        res["error"] = f"the kernel ran N={h.group(1)} on {h.group(2)} threads, expected N={scene['n']} on {threads}"
        return res
    res["loop_s"] = float(m.group(1))
    res["steps"] = scene["steps"]
    res["ke_t_J"] = float(r.group(1))
    res["mean_z_m"] = float(r.group(3)) / (scene["total_mass_kg"] * GRAVITY_M_S2)
    res["contacts"] = int(r.group(4)) + int(r.group(6))
    res["contacts_geom_pair"] = int(r.group(5))
    return res


# ---------------------------------------------------------------- tables


def fmt(v, spec, none="-"):
    return none if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, spec)


def bsps_of(r):
    return r["n"] * r["steps"] / r["loop_s"]


def label_of(r):
    if r.get("label"):
        return r["label"]
    return r["engine"]


def cpu_columns(r):
    share = r["cpu_s"] / (r["elapsed_s"] * r["threads"]) if r.get("cpu_s") is not None else None
    cpu_rate = (r["n"] * (r["steps"] - 1) / r["loop_cpu_s"]) if r.get("loop_cpu_s", 0) > 0 else None
    return share, cpu_rate


def stage_line(rows, prefix):
    stages = []
    for r in rows:
        prof = r.get("profile")
        if r["engine"] != "gabion" or not prof:
            continue
        wall = prof.get("stage_wall_time_s", {})
        busy = prof.get("thread_busy_time_s") or prof.get("partition_busy_time_s", {})
        parts = []
        for name in ("neighbours", "contacts", "walls", "integrate"):
            if name not in wall:
                continue
            item = f"{name} {wall[name]:.2f}"
            if r["threads"] > 1 and busy.get(name):
                item += " (" + ", ".join(f"{b:.2f}" for b in busy[name]) + ")"
            parts.append(item)
        total = sum(wall.get(k, 0.0) for k in ("neighbours", "contacts", "walls", "integrate", "energy"))
        if total > 0 and "neighbours" in wall:
            parts.append(f"neighbours {100.0 * wall['neighbours'] / total:.0f} % of the stages")
        stages.append(f"{prefix}N={r['n']} {r['threads']}t: " + ", ".join(parts))
    if not stages:
        return None
    return ("Gabion stages, s (summary.json `profile` of the runs above; with threads, each thread's "
            "busy time in brackets): " + "; ".join(stages) + ".")


def settle_row(rows, engine, n, threads):
    """The row of an engine's run at N and thread count (the kernel's on the benchmark's own cloud); None
    where it did not run."""
    return next((r for r in rows if r["engine"] == engine and r["n"] == n and r["threads"] == threads
                 and r.get("variant") in (None, "ours")), None)


def balance_words(r):
    """A two-thread Gabion run's contact stage: the share of it its threads were busy on average (below
    100 %: waiting for the other thread). From results of an engine with one fixed partition per thread
    (`partition_busy_time_s`): the partitions' busiest over mean; they held equal estimated work, so a
    value well above 1 pointed at a CPU that ran slower (docs/performance.md, settling Results)."""
    prof = (r or {}).get("profile") or {}
    busy = (prof.get("thread_busy_time_s") or {}).get("contacts") or []
    wall = (prof.get("stage_wall_time_s") or {}).get("contacts") or 0.0
    if len(busy) >= 2 and wall > 0:
        return f"; contact stage threads busy {100.0 * sum(busy) / len(busy) / wall:.0f} %"
    busy = (prof.get("partition_busy_time_s") or {}).get("contacts") or []
    if len(busy) < 2 or sum(busy) <= 0:
        return ""
    return f"; contact partitions busiest / mean {max(busy) / (sum(busy) / len(busy)):.2f}"


def render_settle(info, rows):
    # Ratios against the one-thread peers and against the ceiling kernel on
    # the same cloud with the same threads, at the same N.
    ref = {(r["engine"], r["n"]): bsps_of(r) for r in rows
           if r["threads"] == 1 and r["engine"] in ("liggghts", "yade")}
    ceil = {(r["n"], r["threads"]): bsps_of(r) for r in rows
            if r["engine"] == "ceiling" and r.get("variant", "ours") == "ours"}
    head = ("| engine | threads | N | steps | loop s | M body-steps/s | per core | x LIGGGHTS | x ceiling | x Yade | "
            "max RSS MB | kB/body | load | CPU share | M body-steps/CPU-s | mean z m | KE J | contacts |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in rows:
        bsps = bsps_of(r)
        lig = ref.get(("liggghts", r["n"]))
        yad = ref.get(("yade", r["n"]))
        cei = ceil.get((r["n"], r["threads"]))
        rss = r["rss_kB"]
        share, cpu_rate = cpu_columns(r)
        lines.append(
            f"| {label_of(r)} | {r['threads']} | {r['n']} | {r['steps']} | {r['loop_s']:.3f} | {bsps / 1e6:.2f} | "
            f"{bsps / r['threads'] / 1e6:.2f} | {fmt(bsps / lig if lig else None, '.2f')} | "
            f"{fmt(bsps / cei if cei else None, '.2f')} | "
            f"{fmt(bsps / yad if yad else None, '.2f')} | {fmt(rss / 1024 if rss else None, '.1f')} | "
            f"{fmt(rss / r['n'] if rss else None, '.2f')} | {r['load1']:.2f} | {fmt(share, '.2f')} | "
            f"{fmt(cpu_rate / 1e6 if cpu_rate else None, '.2f')} | "
            f"{fmt(r.get('mean_z_m'), '.4f')} | "
            f"{fmt(r.get('ke_t_J'), '.3g')} | {fmt(r.get('contacts'), 'd')} |")
    # Memory per extra body between the smallest and the largest N (removes
    # the fixed cost of the executable, libraries and, for Yade, Python).
    marg = []
    ns = sorted(set(r["n"] for r in rows))
    if len(ns) >= 2:
        for key in sorted(set((label_of(r), r["threads"]) for r in rows)):
            by_n = {r["n"]: r["rss_kB"] for r in rows if (label_of(r), r["threads"]) == key and r["rss_kB"]}
            if ns[0] in by_n and ns[-1] in by_n:
                per = (by_n[ns[-1]] - by_n[ns[0]]) * 1024.0 / (ns[-1] - ns[0])
                marg.append(f"{key[0]} ({key[1]} thread{'s' if key[1] > 1 else ''}): {per:.0f} bytes/body")

    out = []
    out.append(f"Settling benchmark, {info['date']}; {info.get('machine', 'machine ?')}; "
               f"steps = {info['steps']}, dt = 4e-5 s, seed = {info['seed']}, best of {info.get('repeat', 1)}")
    out.append("")
    out.extend(lines)
    out.append("")
    how = rows[0]["rss_how"] if rows and rows[0]["rss_how"] else "n/a"
    z0 = ", ".join(f"N={n}: {z:.4f} m" for n, z in info.get("initial_mean_z_m", {}).items())
    out.append(
        "loop s: wall time of the time-step loop only (Gabion summary.json step_loop_wall_time_s; LIGGGHTS "
        "'Loop time'; Yade time around O.run; ceiling kernel its loop_time line). per core = body-steps/s / "
        "threads. x LIGGGHTS, x Yade: body-steps/s over the one-thread peer at the same N. x ceiling: over the "
        "ceiling kernel on the same cloud, same N and same threads. max RSS: peak resident memory of the whole "
        f"process ({how}); kB/body = max RSS / N. load: 1-minute load average just before the run. "
        "CPU share: CPU time of the whole process / (its wall time x threads), below 1 when it waited for a "
        "core (other jobs running). M body-steps/CPU-s: N x (steps - 1) / (CPU time of the run - CPU time of "
        "the same run with 1 step), i.e. per CPU-second of the loop: less sensitive to other jobs than the "
        "wall time; with 2 threads it counts both threads' CPU, waiting included. mean z, KE: mean sphere "
        f"centre height and translational kinetic energy after the last step (initial mean z: {z0}). "
        "contacts: touching sphere-sphere + sphere-wall pairs after the last step (Gabion summary.json "
        "`contacts`; LIGGGHTS compute contact/atom / 2 + spheres closer than their radius to a wall; ceiling "
        "its `contacts pp` + `pw`; Yade real interactions).")
    cinfo = info.get("ceiling")
    if cinfo and any(r["engine"] == "ceiling" for r in rows):
        gen = cinfo.get("gen_clouds", {})
        gz = ", ".join(f"N={n}: {g['initial_mean_z_m']:.4f} m" for n, g in gen.items())
        out.append(
            f"ceiling: the single-purpose kernel {cinfo['source']} (not a general engine: one radius, one "
            f"material), built here with `{cinfo['cmds'][0]}` (1 thread) and `{cinfo['cmds'][1]}` (threads > 1, "
            f"OMP_NUM_THREADS) ({cinfo.get('compiler', 'g++')}); same contact law and dissipation as Gabion's "
            "(restitution 0.5 through the reduced mass, a wall of infinite mass), 0.2 R skin. Row `ceiling` "
            "reads the same cloud as the other engines (settle_N.spheres); its own gen.py is the same random "
            "sequential addition with another seed (generate.py --seed 12345 reproduces gen.py's file to "
            "5e-10 m: a different cloud of the same statistics)"
            + (f"; row `ceiling (gen.py cloud)` runs it on that cloud (initial mean z {gz})." if gen else "."))
    if marg:
        out.append(f"Memory per extra body (max RSS difference between N={ns[0]} and N={ns[-1]}): "
                   + "; ".join(marg) + ".")
    st = stage_line(rows, "")
    if st:
        out.append(st)
    # Scaling with threads and the issue's targets for Gabion.
    scal = []
    for lab in sorted(set(label_of(r) for r in rows if r["engine"] in ("gabion", "ceiling"))):
        for n in ns:
            by_t = {r["threads"]: bsps_of(r) for r in rows if label_of(r) == lab and r["n"] == n}
            for t in sorted(by_t):
                if t > 1 and 1 in by_t:
                    scal.append(f"{lab} N={n}: {by_t[t] / by_t[1]:.2f}x on {t} threads")
    if scal:
        out.append("Threads over one thread: " + "; ".join(scal) + ".")
    targ = []
    for n in ns:
        g1_row, g2_row = settle_row(rows, "gabion", n, 1), settle_row(rows, "gabion", n, 2)
        if g1_row is None:
            continue
        g1, g2 = bsps_of(g1_row), bsps_of(g2_row) if g2_row else None
        c1 = ceil.get((n, 1))
        lig = ref.get(("liggghts", n))
        items = []
        if c1:
            items.append(f"ceiling / Gabion {c1 / g1:.2f} (target <= 1.3: {'met' if c1 / g1 <= 1.3 else 'not met'})")
        if lig:
            items.append(f"x LIGGGHTS {g1 / lig:.2f} (target >= 3: {'met' if g1 / lig >= 3 else 'not met'})")
        if g2:
            items.append(f"2 threads / 1 {g2 / g1:.2f} (target >= 1.6: {'met' if g2 / g1 >= 1.6 else 'not met'}"
                         + balance_words(g2_row) + ")")
        if items:
            targ.append(f"N={n}: " + ", ".join(items))
    if targ:
        out.append("Targets, Gabion on one thread: " + "; ".join(targ) + ".")
    targ = []
    for n in ns:
        g1, g2 = settle_row(rows, "gabion", n, 1), settle_row(rows, "gabion", n, 2)
        c1, lig = settle_row(rows, "ceiling", n, 1), settle_row(rows, "liggghts", n, 1)
        items = []
        v = paired(g1, c1)
        if v:
            items.append(paired_words("ceiling / Gabion", v, "<= 1.3", lambda x: x <= 1.3))
        v = paired(lig, g1)
        if v:
            items.append(paired_words("x LIGGGHTS", v, ">= 3", lambda x: x >= 3))
        v = paired(g1, g2)
        if v:
            items.append(paired_words("2 threads / 1", v, ">= 1.6", lambda x: x >= 1.6,
                                      place_words(paired_by_place(g1, g2, g2))))
        c2 = settle_row(rows, "ceiling", n, 2)
        v = paired(c1, c2)
        if v:
            items.append(f"the kernel's 2 threads / 1 {v[0]:.2f} ({v[1]:.2f}-{v[2]:.2f}"
                         + place_words(paired_by_place(c1, c2, c2)) + ")")
        if items:
            targ.append(f"N={n}: " + ", ".join(items))
    if targ:
        out.append("Targets paired by round (the median over the rounds of each round's ratio; the runs of one "
                   "round lie seconds apart, so that a drift of the machine's speed over minutes hits both "
                   "sides alike): " + "; ".join(targ) + ".")
    return out


def paired(num, den):
    """(median, lowest, highest, rounds) of loop(num) / loop(den) over the rounds where both ran, i.e. of
    den's speed over num's; None with fewer than 2 such rounds. The two runs of one round lie seconds
    apart, so a drift of the machine's speed over minutes, which the best of each engine's runs does not
    cancel, hits both alike. num, den: result rows, whose round_loop_s hold each round's loop time."""
    a, b = (num or {}).get("round_loop_s") or [], (den or {}).get("round_loop_s") or []
    x = sorted(p / q for p, q in zip(a, b) if p and q)
    if len(x) < 2:
        return None
    return statistics.median(x), x[0], x[-1], len(x)


def paired_by_place(num, den, threaded):
    """paired(num, den) split by where the CPUs of each round's run of `threaded` (the row with
    threads) lay, measured just before and just after it: {place: (median, lowest, highest, rounds)}
    for the places of PLACES with rounds; a round whose CPUs moved during the run is left out."""
    a, b = (num or {}).get("round_loop_s") or [], (den or {}).get("round_loop_s") or []
    pairs = (threaded or {}).get("round_cpus") or []
    split = {}
    for p, q, around in zip(a, b, pairs):
        places = {placement(m) for m in (around or [])}
        if p and q and len(places) == 1 and None not in places:
            split.setdefault(places.pop(), []).append(p / q)
    return {k: (statistics.median(x), min(x), max(x), len(x)) for k, x in split.items()}


def place_words(split):
    """'; by where the two-thread run's CPUs lay: apart 1.30 (1.23-1.33, 5 rounds), ...', or ''."""
    parts = [f"{PLACES[k]} {split[k][0]:.2f} ({split[k][1]:.2f}-{split[k][2]:.2f}, {split[k][3]} round"
             f"{'s' if split[k][3] > 1 else ''})" for k in PLACES if k in split]
    return ("; by where the two-thread run's CPUs lay: " + ", ".join(parts)) if parts else ""


def paired_words(name, value, target, met, extra=""):
    med, lo, hi, k = value
    return (f"{name} {med:.2f} ({lo:.2f}-{hi:.2f} over {k} rounds; target {target}: "
            f"{'met' if met(med) else 'not met'}{extra})")


def liggghts_zeta(m_a, m_b=None, gamma_n=1883.0, kn=1.0e5):
    """LIGGGHTS hooke/stiffness damping as a fraction of critical: gamma_n m* / (2 sqrt(k_n m*))."""
    ms = m_a if m_b is None else m_a * m_b / (m_a + m_b)
    return gamma_n * math.sqrt(ms / kn) / 2.0


def render_mixed(info, rows):
    mi = info["mixed"]
    valid = [r for r in rows if r["engine"] == "liggghts" and r.get("finds_contacts")]
    best = min(valid, key=lambda r: r["loop_s"]) if valid else None
    settle_rows = [r for r in info["rows"] if r.get("scene", "settle") == "settle"
                   and r.get("variant") in (None, "ours")]
    n_mono = max((r["n"] for r in settle_rows), default=None)
    mono = {(r["engine"], r["threads"]): bsps_of(r) for r in settle_rows if r["n"] == n_mono}
    head = ("| engine | neighbour setting | threads | N | steps | loop s | M body-steps/s | per core | x LIGGGHTS | "
            "x mono | max RSS MB | load | CPU share | M body-steps/CPU-s | COM z m | KE J | contacts | "
            "contacts (geometric) |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in rows:
        bsps = bsps_of(r)
        if r["engine"] == "liggghts":
            setting = neigh_words(r["variant"]) + (" (best)" if r is best else "")
            if r.get("finds_contacts") is False:
                setting += " (misses contacts)"
        else:
            setting = "default Verlet skin (0.2 x mean grid radius)"
        lig = bsps_of(best) if best else None
        mo = mono.get((r["engine"], r["threads"]))
        share, cpu_rate = cpu_columns(r)
        rss = r["rss_kB"]
        geom = r.get("contacts_geom")
        lines.append(
            f"| {r['engine']} | {setting} | {r['threads']} | {r['n']} | {r['steps']} | {r['loop_s']:.3f} | "
            f"{bsps / 1e6:.2f} | {bsps / r['threads'] / 1e6:.2f} | {fmt(bsps / lig if lig else None, '.2f')} | "
            f"{fmt(bsps / mo if mo else None, '.2f')} | {fmt(rss / 1024 if rss else None, '.1f')} | "
            f"{r['load1']:.2f} | {fmt(share, '.2f')} | {fmt(cpu_rate / 1e6 if cpu_rate else None, '.2f')} | "
            f"{fmt(r.get('mean_z_m'), '.4f')} | {fmt(r.get('ke_t_J'), '.3g')} | {fmt(r.get('contacts'), 'd')} | "
            f"{fmt(geom, 'd')} |")
    rho = mi["density_kg_m3"]
    mass = {c["radius_m"]: rho * 4.0 / 3.0 * math.pi * c["radius_m"] ** 3 for c in mi["classes"]}
    rs = sorted(mass)
    zetas = ", ".join([f"{rs[0] * 1e3:g}-{rs[0] * 1e3:g} mm {liggghts_zeta(mass[rs[0]], mass[rs[0]]):.3f}",
                       f"{rs[1] * 1e3:g}-{rs[1] * 1e3:g} mm {liggghts_zeta(mass[rs[1]], mass[rs[1]]):.3f}",
                       f"{rs[2] * 1e3:g}-{rs[2] * 1e3:g} mm {liggghts_zeta(mass[rs[2]], mass[rs[2]]):.2f}",
                       f"{rs[0] * 1e3:g} mm-wall {liggghts_zeta(mass[rs[0]]):.3f}",
                       f"{rs[2] * 1e3:g} mm-wall {liggghts_zeta(mass[rs[2]]):.2f}"])
    classes = ", ".join(f"{c['count']:,} of radius {c['radius_m'] * 1e3:g} mm" for c in mi["classes"])
    out = []
    out.append(f"Mixed-size scene, {info['date']}; {info.get('machine', 'machine ?')}; steps = {mi['steps']}, "
               f"dt = {mi['dt_s']:.5g} s, seed = {mi['seed']}, best of {info.get('repeat', 1)}")
    out.append("")
    out.extend(lines)
    out.append("")
    out.append(
        f"Scene (generate_mixed.py): {classes} ({mi['n']:,} spheres, density {rho:g} kg/m3) in a closed cube "
        f"of side L = {mi['side_m']:.4f} m (six walls; solid fraction {mi['solid_fraction']:g} of its volume), "
        f"random sequential addition, largest first, gap {mi['gap_m'] * 1e3:g} mm; initial speeds uniform in "
        f"[0, {mi['max_speed_m_s']:g}] m/s in uniform directions (initial translational KE "
        f"{mi['initial_kinetic_translational_J']:.3g} J, centre-of-mass height {mi['initial_com_z_m']:.4f} m); "
        f"gravity; k_n = 1e5 N/m, k_t = 2.5e4 N/m, friction 0.5; dt = 0.15 sqrt(m_4mm / k_n) = "
        f"{mi['dt_s']:.5g} s, {mi['steps']} steps ({mi['steps'] * mi['dt_s']:.4g} s).")
    out.append(
        "Damping, as in the settling scene: Gabion viscous_damping_ratio 0.2155 of the critical damping of "
        "each contact's reduced mass (restitution 0.5 for every pair); LIGGGHTS hooke/stiffness gamma_n = "
        "1883 1/s times the reduced mass, i.e. a fraction of critical that grows with the mass: "
        f"{zetas} (restitution 0.5 only for two 10 mm spheres). The end states therefore differ a little.")
    out.append(
        "neighbour setting (LIGGGHTS): `neighbor SKIN bin|multi` with `neigh_modify delay 0 binsize B` (no "
        "binsize: LIGGGHTS' default, half the largest cutoff). contacts: touching sphere-sphere + sphere-wall "
        "pairs after the last step (Gabion summary.json `contacts`; LIGGGHTS compute contact/atom / 2, which "
        "walks its neighbour list, + spheres closer than their radius to a wall). contacts (geometric): the "
        "same count done by bench.py from LIGGGHTS' final positions (write_dump), without its neighbour list; "
        f"a setting whose list count of sphere-sphere contacts is below {CONTACTS_FOUND_SHARE:.0%} of it "
        "misses contacts. x LIGGGHTS: over the fastest LIGGGHTS setting that finds the contacts (best). "
        + (f"x mono: body-steps/s over the same engine's, same threads, in the settling scene at N = {n_mono} "
           "of this invocation. " if n_mono else "x mono: needs --scene both (settling and mixed in one run). ")
        + "COM z: height of the centre of mass (Gabion: gravity potential / (M g)); KE: translational kinetic "
        "energy. Other columns as in the settling table.")
    st = stage_line(rows, "mixed ")
    if st:
        out.append(st)
    targ = []
    for r in rows:
        if r["engine"] != "gabion":
            continue
        items = []
        if best:
            x = bsps_of(r) / bsps_of(best)
            items.append(f"x LIGGGHTS {x:.2f} (target >= 3: {'met' if x >= 3 else 'not met'})")
        mo = mono.get(("gabion", r["threads"]))
        if mo:
            x = mo / bsps_of(r)
            items.append(f"settling / mixed body-steps/s {x:.2f} (target <= 1.5: {'met' if x <= 1.5 else 'not met'})")
        if items:
            targ.append(f"{r['threads']} thread{'s' if r['threads'] > 1 else ''}: " + ", ".join(items))
    if targ:
        out.append("Targets, Gabion: " + "; ".join(targ) + ".")
    targ = []
    for r in rows:
        v = paired(best, r) if r["engine"] == "gabion" else None
        if v:
            targ.append(f"{r['threads']} thread{'s' if r['threads'] > 1 else ''}: "
                        + paired_words("x LIGGGHTS", v, ">= 3", lambda x: x >= 3))
    if targ:
        out.append("Targets paired by round (against the best LIGGGHTS setting's run of the same round; the "
                   "median over the rounds): " + "; ".join(targ) + ".")
    return out


def render(info):
    """The tables and their notes (markdown) from the collected results."""
    rows = info["rows"]
    settle = [r for r in rows if r.get("scene", "settle") == "settle"]
    mixed = [r for r in rows if r.get("scene") == "mixed"]
    out = []
    if settle or not mixed:
        out.extend(render_settle(info, settle))
    if mixed and info.get("mixed"):
        if out:
            out.append("")
        out.extend(render_mixed(info, mixed))
    for item in info.get("skipped", []):
        e, why = (item["engine"], item["why"]) if isinstance(item, dict) else item
        out.append(f"Skipped {e}: {why}." + (f" Install: {INSTALL_HINT[e]}" if e in INSTALL_HINT else ""))
    starved = [f"{label_of(r)} {r.get('scene', 'settle')} N={r['n']} {r['threads']}t "
               f"({r['cpu_s'] / (r['elapsed_s'] * r['threads']):.2f})"
               for r in rows if r.get("cpu_s") is not None and r["elapsed_s"] > 2.0
               and r["cpu_s"] / (r["elapsed_s"] * r["threads"]) < 0.85]
    if starved:
        out.append("WARNING: these runs had less than 85 % of their cores (CPU share): " + ", ".join(starved) +
                   ". Other jobs shared the machine: their wall times are inflated and the ratios unreliable "
                   "(the M body-steps/CPU-s column is less affected). Re-run on a quiet machine.")
    return "\n".join(out)


# ---------------------------------------------------------------- run


# LIGGGHTS neighbour settings of the mixed scene. A sweep of 5,000 steps
# (skin 0.8 to 24 mm, binsize default / 50 / 35 / 24 mm, CPU seconds of one
# run each) put the fastest at a skin of 4-8 mm with a binsize of 35 mm
# (7.2-7.4 s), the default binsize 3-6 % slower, 24 mm bins 30-40 % slower,
# skins of 12 mm and more slower again (pair time grows), 0.8 mm (Gabion's
# 0.2 x mean radius) about 3x slower in 500-step runs (a rebuild every ~40 steps, each
# binning with bins of half the 70 mm spheres' cutoff). The defaults run the
# contenders, the skin Gabion uses, and multi.
DEFAULT_LIGGGHTS_NEIGH = "bin:0.0008,bin:0.008,bin:0.004:0.035,bin:0.008:0.035,multi:0.008"


def settle_scene(n, steps, seed, workdir):
    subprocess.run([sys.executable, os.path.join(HERE, "generate.py"), str(n), "--steps", str(steps),
                    "--seed", str(seed), "--outdir", workdir], check=True, stdout=subprocess.DEVNULL)
    base = os.path.join(workdir, f"settle_{n}")
    with open(base + ".meta.json") as f:
        meta = json.load(f)
    log(f"scene settle N={n}: L={meta['side_m']:g} m, cloud height {meta['cloud_height_m']:.4f} m, "
        f"initial mean z {meta['initial_mean_z_m']:.4f} m")
    return {"name": "settle", "n": n, "steps": steps, "dt_s": SETTLE_DT_S, "side_m": meta["side_m"],
            "gabion_case": base + ".gabion.json", "liggghts_data": base + ".data", "spheres": base + ".spheres",
            "initial_mean_z_m": meta["initial_mean_z_m"], "total_mass_kg": n * SETTLE_SPHERE_MASS_KG}


def mixed_scene(steps, seed, workdir):
    subprocess.run([sys.executable, os.path.join(HERE, "generate_mixed.py"), "--steps", str(steps),
                    "--seed", str(seed), "--outdir", workdir], check=True, stdout=subprocess.DEVNULL)
    base = os.path.join(workdir, "mixed")
    with open(base + ".meta.json") as f:
        meta = json.load(f)
    log(f"scene mixed N={meta['n']}: cube L={meta['side_m']:.4f} m, dt={meta['dt_s']:.5g} s, "
        f"initial centre-of-mass height {meta['initial_com_z_m']:.4f} m")
    return {"name": "mixed", "n": meta["n"], "steps": steps, "dt_s": meta["dt_s"], "side_m": meta["side_m"],
            "gabion_case": base + ".gabion.json", "liggghts_data": base + ".data",
            "initial_mean_z_m": meta["initial_com_z_m"], "total_mass_kg": meta["total_mass_kg"], "meta": meta}


def run_job(available, scene, job, rundir, timeout_s):
    e, t, v = job
    if e == "gabion":
        return run_gabion(available[e], scene, t, rundir, timeout_s)
    if e == "liggghts":
        return run_liggghts(available[e], scene, rundir, timeout_s, v)
    if e == "ceiling":
        return run_ceiling(available[e], scene, t, rundir, timeout_s, v)
    return run_yade(available[e], scene, rundir, timeout_s)


def job_label(job):
    e, t, v = job
    if e == "ceiling" and v == "gen":
        return "ceiling (gen.py cloud)"
    return e


def job_dir(scene, job, repeat_index):
    e, t, v = job
    name = e
    if v and not (e == "ceiling" and v == "ours"):
        name += "-" + re.sub(r"[^A-Za-z0-9.]+", "-", v)
    prefix = "mixed_" if scene["name"] == "mixed" else ""
    return f"{prefix}{name}_N{scene['n']}_t{t}" + (f"_r{repeat_index}" if repeat_index else "")


def main():
    ap = argparse.ArgumentParser(
        description="Settling benchmark and mixed-size scene: Gabion, LIGGGHTS, Yade and the ceiling kernel "
                    "(docs/performance.md).")
    ap.add_argument("n", nargs="*", type=int, default=[5000, 20000],
                    help="numbers of spheres of the settling scene (default 5000 20000)")
    ap.add_argument("--scene", choices=("settle", "mixed", "both"), default="settle",
                    help="settle: the settling scene for each N; mixed: the mixed-size scene (22,020 spheres of "
                         "4, 18 and 70 mm); both: both, so that the mixed table gives each engine's ratio to its "
                         "settling speed (default settle)")
    ap.add_argument("--steps", type=int, default=None,
                    help="time steps of every scene (default: settle 10000 of 4e-5 s, mixed 5000)")
    ap.add_argument("--seed", type=int, default=20261122, help="scene seed (default 20261122)")
    ap.add_argument("--engines", default="liggghts,yade,ceiling,gabion",
                    help="comma list of engines to run, in this order (default liggghts,yade,ceiling,gabion; "
                         "the mixed scene runs gabion and liggghts only)")
    ap.add_argument("--gabion", default=os.environ.get("GABION_BINARY", os.path.join(REPO, "build", "gabion")),
                    help="gabion binary (default $GABION_BINARY or build/gabion)")
    ap.add_argument("--gabion-threads", default="1,2",
                    help="comma list of thread counts of Gabion and the ceiling kernel (default 1,2)")
    ap.add_argument("--liggghts", default=shutil.which("liggghts") or "",
                    help="LIGGGHTS binary (default: liggghts on PATH)")
    ap.add_argument("--liggghts-neigh", default=DEFAULT_LIGGGHTS_NEIGH,
                    help="mixed scene: comma list of LIGGGHTS neighbour settings STYLE:SKIN[:BINSIZE] (metres; "
                         "STYLE bin or multi; no BINSIZE: LIGGGHTS' default), each run as a row; the fastest "
                         f"that finds the contacts gives the ratio (default {DEFAULT_LIGGGHTS_NEIGH})")
    ap.add_argument("--yade", default=shutil.which("yade") or "", help="Yade binary (default: yade on PATH)")
    ap.add_argument("--ceiling-dir", default=os.path.join(REPO, "..", "shared", "reference", "ceiling"),
                    help="the ceiling kernel's sources, sol.cpp and gen.py (default: the repository's sibling "
                         "shared/reference/ceiling); built into bench/work/ceiling")
    ap.add_argument("--ceiling-clouds", default="ours,gen",
                    help="clouds the ceiling kernel runs on: ours (the settling scene's, as the other engines) "
                         "and/or gen (the kernel's own gen.py cloud, another seed) (default ours,gen)")
    ap.add_argument("--repeat", type=int, default=1,
                    help="runs of each engine; the fastest loop is reported (default 1)")
    ap.add_argument("--no-baseline", action="store_true",
                    help="skip the 1-step run of each engine that gives the CPU time of the loop alone")
    ap.add_argument("--timeout", type=float, default=0, help="seconds per engine run, 0 = none (default 0)")
    ap.add_argument("--workdir", default=os.path.join(REPO, "bench", "work", "settle"),
                    help="scenes and engine outputs (default bench/work/settle, git-ignored)")
    ap.add_argument("--report", metavar="RESULTS_JSON",
                    help="only print the table again from a results.json this script wrote")
    a = ap.parse_args()
    a.workdir = os.path.abspath(a.workdir)
    if a.report:
        with open(a.report) as f:
            print(render(json.load(f)))
        return 0
    if (a.steps is not None and a.steps < 1) or a.repeat < 1 or any(n < 1 for n in a.n):
        ap.error("N, --steps and --repeat must be >= 1")
    engines = [e.strip() for e in a.engines.split(",") if e.strip()]
    for e in engines:
        if e not in ("gabion", "liggghts", "yade", "ceiling"):
            ap.error(f"unknown engine '{e}' (gabion, liggghts, yade, ceiling)")
    gthreads = [int(t) for t in a.gabion_threads.split(",") if t.strip()]
    neighs = [s.strip() for s in a.liggghts_neigh.split(",") if s.strip()]
    try:
        for s in neighs:
            parse_neigh(s)
    except ValueError as err:
        ap.error(str(err))
    clouds = [c.strip() for c in a.ceiling_clouds.split(",") if c.strip()]
    if any(c not in ("ours", "gen") for c in clouds) or not clouds:
        ap.error("--ceiling-clouds: a comma list of ours, gen")
    do_settle = a.scene in ("settle", "both")
    do_mixed = a.scene in ("mixed", "both")
    settle_steps = a.steps if a.steps is not None else 10000
    mixed_steps = a.steps if a.steps is not None else 5000

    os.makedirs(a.workdir, exist_ok=True)
    stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    log(f"settling benchmark, {stamp}")
    machine = f"{cpu_model()}, {os.cpu_count()} logical CPUs"
    pair = core_pair(a.gabion)
    if pair["trip_ns"] is not None:
        machine += f", cache-line round trip between CPUs 0 and 1 {pair['trip_ns']} ns"
        if pair["together"] is not None:
            machine += f", computing together at {pair['together']:.2f} of one alone"
        if pair["memory"] is not None:
            machine += f", CPU 1 reading memory at {pair['memory']:.2f} of CPU 0's speed"
        machine += " (bench_core_round_trip)"
    log(f"machine: {machine}; load average {loadavg()}")
    log(f"scene {a.scene}: settle N = {a.n if do_settle else '-'}, steps = {settle_steps if do_settle else '-'}; "
        f"mixed steps = {mixed_steps if do_mixed else '-'}; seed = {a.seed}, repeat = {a.repeat}")

    skipped = []
    available = {}
    ceiling_info = None
    for e in engines:
        if e == "gabion":
            ok, why = gabion_available(os.path.abspath(a.gabion) if a.gabion else "")
            if ok:
                available[e] = os.path.abspath(a.gabion)
            else:
                skipped.append((e, why))
        elif e == "ceiling":
            if not do_settle:
                continue
            ceiling_info, why = build_ceiling(os.path.abspath(a.ceiling_dir),
                                              os.path.join(REPO, "bench", "work", "ceiling"))
            if ceiling_info:
                available[e] = ceiling_info
            else:
                skipped.append((e, why))
        else:
            b = a.liggghts if e == "liggghts" else a.yade
            if b and os.access(b, os.X_OK):
                available[e] = b
            else:
                skipped.append((e, f"no executable at {b}" if b else "not installed"))
    for e, why in skipped:
        log(f"SKIP {e}: {why}. Install: {INSTALL_HINT[e]}")
    if do_mixed and any(e in engines and e in available for e in ("yade", "ceiling")):
        log("note: the mixed scene runs Gabion and LIGGGHTS only (Yade's script and the ceiling kernel are "
            "for the settling scene)")
    if not os.access(GNU_TIME, os.X_OK):
        log("note: /usr/bin/time not found (Debian package `time`); peak memory from os.wait4 ru_maxrss instead")

    def jobs_for(scene_name):
        out = []
        for e in engines:
            if e not in available:
                continue
            if e == "gabion":
                out += [(e, t, None) for t in gthreads]
            elif e == "liggghts":
                out += [(e, 1, None)] if scene_name == "settle" else [(e, 1, v) for v in neighs]
            elif scene_name != "settle":
                continue
            elif e == "yade":
                out.append((e, 1, None))
            else:
                out += [(e, t, c) for c in clouds for t in gthreads]
        return out

    plan = ([("settle", n) for n in a.n] if do_settle else []) + ([("mixed", None)] if do_mixed else [])
    total = sum(len(jobs_for(name)) for name, _ in plan) * a.repeat

    rows = []
    failures = 0
    k = 0
    scenes = {}
    for name, n in plan:
        t0 = time.perf_counter()
        if name == "settle":
            scene = settle_scene(n, settle_steps, a.seed, a.workdir)
            if "ceiling" in available and "gen" in clouds:
                path, z0, count = ceiling_gen_cloud(available["ceiling"], n, scene["side_m"],
                                                    os.path.join(REPO, "bench", "work", "ceiling"))
                scene["ceiling_gen_spheres"] = path
                ceiling_info.setdefault("gen_clouds", {})[str(n)] = {"path": path, "initial_mean_z_m": z0,
                                                                     "n": count}
                log(f"    the ceiling kernel's own cloud (gen.py): {count} spheres, initial mean z {z0:.4f} m")
        else:
            scene = mixed_scene(mixed_steps, a.seed, a.workdir)
        log(f"    (scene written in {time.perf_counter() - t0:.1f} s)")
        scenes[(name, scene["n"])] = scene
        # Round-robin: with --repeat R the engines run in turn R times, so that
        # a drift of the machine's speed hits all of them alike; the best run
        # of each is kept.
        jobs = jobs_for(name)
        bests = {j: None for j in jobs}
        rounds = {j: [] for j in jobs}  # each round's loop s (None: failed), for ratios paired by round
        cpus = {j: [] for j in jobs}  # runs with threads: each round's core_pair() before and after
        for r in range(a.repeat):
            for job in jobs:
                e, t, v = job
                k += 1
                rundir = os.path.join(a.workdir, job_dir(scene, job, r + 1 if a.repeat > 1 else 0))
                shutil.rmtree(rundir, ignore_errors=True)
                os.makedirs(rundir)
                la = loadavg()
                what = job_label(job) + (f" [{neigh_words(v)}]" if e == "liggghts" and v else "")
                log(f"[{k}/{total}] {name} {what} N={scene['n']} threads={t} steps={scene['steps']} "
                    f"(load {la[0]:.2f}) ...")
                # (where the two CPUs lie can change within minutes: measured around the run itself)
                before = core_pair(a.gabion, quick=True) if t > 1 else None
                res = run_job(available, scene, job, rundir, a.timeout)
                if t > 1:
                    cpus[job].append([before, core_pair(a.gabion, quick=True)])
                res["load1"] = la[0]
                if "error" not in res and res["steps"] != scene["steps"]:
                    res["error"] = f"ran {res['steps']} steps, expected {scene['steps']}"
                rounds[job].append(None if "error" in res else res["loop_s"])
                if "error" in res:
                    failures += 1
                    log(f"    FAILED ({res['elapsed_s']:.1f} s): {res['error']}\n    outputs in {rundir}")
                    continue
                bsps = scene["n"] * res["steps"] / res["loop_s"]
                extra = ""
                if res.get("contacts") is not None:
                    extra = f", contacts {res['contacts']}"
                    if res.get("contacts_geom") is not None:
                        extra += f" (geometric {res['contacts_geom']})"
                if t > 1 and cpus[job][-1][0]["trip_ns"] is not None:
                    b_, a_ = cpus[job][-1]
                    extra += (f", CPUs before / after: round trip {b_['trip_ns']} / {a_['trip_ns']} ns, "
                              f"together {fmt(b_['together'], '.2f')} / {fmt(a_['together'], '.2f')}, "
                              f"CPU 1 reading memory at {fmt(b_['memory'], '.2f')} / {fmt(a_['memory'], '.2f')} "
                              f"of CPU 0's speed ({placement(b_)} / {placement(a_)})")
                log(f"    loop {res['loop_s']:.2f} s ({bsps / 1e6:.2f} M body-steps/s), whole run "
                    f"{res['elapsed_s']:.1f} s, max RSS {fmt(res['rss_kB'], '.0f')} kB{extra}")
                if bests[job] is None or res["loop_s"] < bests[job]["loop_s"]:
                    bests[job] = res
        for job in jobs:
            e, t, v = job
            best = bests[job]
            if best is not None and not a.no_baseline and scene["steps"] > 1:
                # The same run with 1 step: its CPU time is the start-up and
                # output; the difference is the CPU time of steps - 1 steps,
                # which other jobs on the machine disturb much less than the
                # wall time.
                rundir = os.path.join(a.workdir, job_dir(scene, job, 0) + "_1step")
                shutil.rmtree(rundir, ignore_errors=True)
                os.makedirs(rundir)
                b = run_job(available, dict(scene, steps=1), job, rundir, a.timeout)
                if "error" in b or b.get("cpu_s") is None or best.get("cpu_s") is None:
                    log(f"    1-step baseline of {job_label(job)} failed: {b.get('error', 'no CPU time')}")
                else:
                    best["loop_cpu_s"] = best["cpu_s"] - b["cpu_s"]
                    log(f"    1-step baseline of {job_label(job)} t={t}: CPU {b['cpu_s']:.2f} s; "
                        f"loop CPU {best['loop_cpu_s']:.2f} s")
            if best is not None:
                best["round_loop_s"] = rounds[job]
                if t > 1:
                    best["round_cpus"] = cpus[job]
                best.update({"engine": e, "n": scene["n"], "threads": t, "scene": name, "variant": v,
                             "label": job_label(job)})
                rows.append(best)

    info = {"date": stamp, "machine": machine, "steps": settle_steps,
            "seed": a.seed, "repeat": a.repeat, "rows": rows, "skipped": skipped, "scene": a.scene,
            "initial_mean_z_m": {str(s["n"]): s["initial_mean_z_m"] for s in scenes.values()
                                 if s["name"] == "settle"},
            "command": "bench/settle/run.sh " + " ".join(sys.argv[1:])}
    if ceiling_info:
        info["ceiling"] = {k: v for k, v in ceiling_info.items() if k not in ("sol", "sol_omp", "gen")}
    mixed = [s for s in scenes.values() if s["name"] == "mixed"]
    if mixed:
        info["mixed"] = mixed[0]["meta"]
        info["mixed"]["steps"] = mixed[0]["steps"]
    text = render(info)
    log("")
    log(text)
    report = os.path.join(a.workdir, "results.md")
    with open(report, "w") as f:
        f.write(text + "\n")
    with open(os.path.join(a.workdir, "results.json"), "w") as f:
        json.dump(info, f, indent=1)
    log(f"\n(table also in {report} and results.json; engine outputs under {a.workdir})")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
