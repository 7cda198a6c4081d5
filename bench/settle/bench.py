#!/usr/bin/env python3
"""Settling benchmark: Gabion against LIGGGHTS and Yade on the same scene.

Called by bench/settle/run.sh (see there and docs/performance.md). For each N
it generates the scene (generate.py, seeded), runs every engine that is
installed, one after the other, and prints one table:

  engine, threads, N, steps, loop wall time, body-steps/s, body-steps/s per
  core, ratio to LIGGGHTS and to Yade (same N), peak memory (max RSS) and
  memory per body, the load average before the run, the share of its cores
  the process got, body-steps per CPU-second of the loop (from a second,
  1-step run that measures the start-up), and the mean sphere height and
  translational kinetic energy at the end (physics sanity).

The loop time of each engine covers the time steps only:
  Gabion   summary.json results.step_loop_wall_time_s (timed inside the run)
  LIGGGHTS the "Loop time of ..." line printed after `run` (LIGGGHTS' own timer)
  Yade     time.perf_counter() around O.run(steps, True) in yade_settle.py
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
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown"


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


def run_gabion(binary, scene, threads, rundir, timeout_s):
    outdir = os.path.join(rundir, "out")
    duration = repr(scene["steps"] * 4.0e-5)
    cmd = [binary, "run", scene["gabion_case"], "-o", outdir, "--threads", str(threads), "-q",
           "--set", f"run.duration_s={duration}", "--set", f"run.output_interval_s={duration}"]
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    rc, rss, elapsed, how, cpu = run_measured(cmd, rundir, env, os.path.join(rundir, "stdout.txt"),
                                         os.path.join(rundir, "stderr.txt"), timeout_s)
    res = {"cmd": cmd, "rc": rc, "rss_kB": rss, "rss_how": how, "elapsed_s": elapsed, "cpu_s": cpu}
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
    res["profile"] = s.get("profile")
    mz, ket = gabion_sanity(s, scene)
    res["mean_z_m"] = mz
    res["ke_t_J"] = ket
    return res


def gabion_sanity(summary, scene):
    """Mean height and translational kinetic energy at the end of a Gabion run.

    Both come from the energy terms of summary.json: kinetic_translational_J,
    and gravity_potential_J = -sum m g.x (zero at the origin), which for N equal
    spheres under g = 9.81 m/s2 along -z is N m g mean(z)."""
    energy = summary.get("energy") or summary.get("results", {}).get("energy") or {}
    ket = energy.get("kinetic_translational_J")
    ket = float(ket) if ket is not None else None
    mz = None
    pe = energy.get("gravity_potential_J")
    if pe is not None:
        mass = 2500.0 * 4.0 / 3.0 * math.pi * 0.010 ** 3
        mz = float(pe) / (scene["n"] * mass * 9.81)
    return mz, ket


def run_liggghts(binary, scene, rundir, timeout_s):
    cmd = [binary, "-in", os.path.join(HERE, "in.settle"), "-log", "none", "-echo", "none",
           "-var", "datafile", scene["liggghts_data"], "-var", "side", repr(scene["side_m"]),
           "-var", "steps", str(scene["steps"])]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    stdout_path = os.path.join(rundir, "stdout.txt")
    rc, rss, elapsed, how, cpu = run_measured(cmd, rundir, env, stdout_path, os.path.join(rundir, "stderr.txt"),
                                         timeout_s)
    res = {"cmd": cmd, "rc": rc, "rss_kB": rss, "rss_how": how, "elapsed_s": elapsed, "cpu_s": cpu}
    with open(stdout_path, errors="replace") as f:
        text = f.read()
    m = re.search(r"Loop time of ([\d.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", text)
    r = re.search(r"BENCH_RESULT mean_z_m (\S+) kinetic_translational_J (\S+) kinetic_rotational_J (\S+)", text)
    if rc != 0 or not m or not r:
        res["error"] = (f"exit code {rc}{TIMED_OUT if rc == 124 else ''}, loop line {'found' if m else 'missing'}\n"
                        + tail(stdout_path) + "\n" + tail(os.path.join(rundir, "stderr.txt")))
        return res
    if int(m.group(4)) != scene["n"]:
        res["error"] = f"LIGGGHTS ended with {m.group(4)} atoms, expected {scene['n']}"
        return res
    res["loop_s"] = float(m.group(1))
    res["steps"] = int(m.group(3))
    res["mean_z_m"] = float(r.group(1))
    res["ke_t_J"] = float(r.group(2))
    return res


def run_yade(binary, scene, rundir, timeout_s):
    result_json = os.path.join(rundir, "result.json")
    cmd = [binary, "-j1", "-n", "-x", os.path.join(HERE, "yade_settle.py")]
    env = dict(os.environ, OMP_NUM_THREADS="1", BENCH_SPHERES=scene["spheres"], BENCH_SIDE=repr(scene["side_m"]),
               BENCH_STEPS=str(scene["steps"]), BENCH_RESULT=result_json)
    rc, rss, elapsed, how, cpu = run_measured(cmd, rundir, env, os.path.join(rundir, "stdout.txt"),
                                         os.path.join(rundir, "stderr.txt"), timeout_s)
    res = {"cmd": cmd, "rc": rc, "rss_kB": rss, "rss_how": how, "elapsed_s": elapsed, "cpu_s": cpu}
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
    return res


# ---------------------------------------------------------------- table


def fmt(v, spec, none="-"):
    return none if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, spec)


def render(info):
    """The table and its notes (markdown) from the collected results."""
    # Ratios against the one-thread peers at the same N.
    ref = {(r["engine"], r["n"]): r["n"] * r["steps"] / r["loop_s"] for r in info["rows"] if r["threads"] == 1}
    head = ("| engine | threads | N | steps | loop s | M body-steps/s | per core | x LIGGGHTS | x Yade | "
            "max RSS MB | kB/body | load | CPU share | M body-steps/CPU-s | mean z m | KE J |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in info["rows"]:
        bsps = r["n"] * r["steps"] / r["loop_s"]
        lig = ref.get(("liggghts", r["n"]))
        yad = ref.get(("yade", r["n"]))
        rss = r["rss_kB"]
        share = r["cpu_s"] / (r["elapsed_s"] * r["threads"]) if r.get("cpu_s") is not None else None
        cpu_rate = (r["n"] * (r["steps"] - 1) / r["loop_cpu_s"]) if r.get("loop_cpu_s", 0) > 0 else None
        lines.append(
            f"| {r['engine']} | {r['threads']} | {r['n']} | {r['steps']} | {r['loop_s']:.3f} | {bsps / 1e6:.2f} | "
            f"{bsps / r['threads'] / 1e6:.2f} | {fmt(bsps / lig if lig else None, '.2f')} | "
            f"{fmt(bsps / yad if yad else None, '.2f')} | {fmt(rss / 1024 if rss else None, '.1f')} | "
            f"{fmt(rss / r['n'] if rss else None, '.2f')} | {r['load1']:.2f} | {fmt(share, '.2f')} | "
            f"{fmt(cpu_rate / 1e6 if cpu_rate else None, '.2f')} | "
            f"{fmt(r.get('mean_z_m'), '.4f')} | "
            f"{fmt(r.get('ke_t_J'), '.3g')} |")
    # Memory per extra body between the smallest and the largest N (removes
    # the fixed cost of the executable, libraries and, for Yade, Python).
    marg = []
    ns = sorted(set(r["n"] for r in info["rows"]))
    if len(ns) >= 2:
        for key in sorted(set((r["engine"], r["threads"]) for r in info["rows"])):
            by_n = {r["n"]: r["rss_kB"] for r in info["rows"] if (r["engine"], r["threads"]) == key and r["rss_kB"]}
            if ns[0] in by_n and ns[-1] in by_n:
                per = (by_n[ns[-1]] - by_n[ns[0]]) * 1024.0 / (ns[-1] - ns[0])
                marg.append(f"{key[0]} ({key[1]} thread{'s' if key[1] > 1 else ''}): {per:.0f} bytes/body")

    out = []
    out.append(f"Settling benchmark, {info['date']}; {info.get('machine', 'machine ?')}; "
               f"steps = {info['steps']}, dt = 4e-5 s, seed = {info['seed']}, best of {info.get('repeat', 1)}")
    out.append("")
    out.extend(lines)
    out.append("")
    how = info["rows"][0]["rss_how"] if info["rows"] and info["rows"][0]["rss_how"] else "n/a"
    z0 = ", ".join(f"N={n}: {z:.4f} m" for n, z in info.get("initial_mean_z_m", {}).items())
    out.append(
        "loop s: wall time of the time-step loop only (Gabion summary.json step_loop_wall_time_s; LIGGGHTS "
        "'Loop time'; Yade time around O.run). per core = body-steps/s / threads. x LIGGGHTS, x Yade: "
        "body-steps/s over the one-thread peer at the same N. max RSS: peak resident memory of the whole "
        f"process ({how}); kB/body = max RSS / N. load: 1-minute load average just before the run. "
        "CPU share: CPU time of the whole process / (its wall time x threads), below 1 when it waited for a "
        "core (other jobs running). M body-steps/CPU-s: N x (steps - 1) / (CPU time of the run - CPU time of "
        "the same run with 1 step), i.e. per CPU-second of the loop: less sensitive to other jobs than the "
        "wall time; with 2 threads it counts both threads' CPU, waiting included. mean z, KE: mean sphere "
        f"centre height and translational kinetic energy after the last step (initial mean z: {z0}).")
    if marg:
        out.append(f"Memory per extra body (max RSS difference between N={ns[0]} and N={ns[-1]}): "
                   + "; ".join(marg) + ".")
    stages = []
    for r in info["rows"]:
        prof = r.get("profile")
        if r["engine"] != "gabion" or not prof:
            continue
        wall = prof.get("stage_wall_time_s", {})
        busy = prof.get("partition_busy_time_s", {})
        parts = []
        for name in ("neighbours", "contacts", "walls", "integrate"):
            if name not in wall:
                continue
            item = f"{name} {wall[name]:.2f}"
            if r["threads"] > 1 and busy.get(name):
                item += " (" + ", ".join(f"{b:.2f}" for b in busy[name]) + ")"
            parts.append(item)
        stages.append(f"N={r['n']} {r['threads']}t: " + ", ".join(parts))
    if stages:
        out.append("Gabion stages, s (summary.json `profile` of the runs above; with threads, each partition's "
                   "busy time in brackets): " + "; ".join(stages) + ".")
    for item in info.get("skipped", []):
        e, why = (item["engine"], item["why"]) if isinstance(item, dict) else item
        out.append(f"Skipped {e}: {why}. Install: {INSTALL_HINT[e]}")
    starved = [f"{r['engine']} N={r['n']} {r['threads']}t ({r['cpu_s'] / (r['elapsed_s'] * r['threads']):.2f})"
               for r in info["rows"] if r.get("cpu_s") is not None and r["elapsed_s"] > 2.0
               and r["cpu_s"] / (r["elapsed_s"] * r["threads"]) < 0.85]
    if starved:
        out.append("WARNING: these runs had less than 85 % of their cores (CPU share): " + ", ".join(starved) +
                   ". Other jobs shared the machine: their wall times are inflated and the ratios unreliable "
                   "(the M body-steps/CPU-s column is less affected). Re-run on a quiet machine.")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(
        description="Settling benchmark: Gabion, LIGGGHTS and Yade on the same scene (docs/performance.md).")
    ap.add_argument("n", nargs="*", type=int, default=[5000, 20000], help="numbers of spheres (default 5000 20000)")
    ap.add_argument("--steps", type=int, default=10000, help="time steps, dt = 4e-5 s (default 10000)")
    ap.add_argument("--seed", type=int, default=20261122, help="scene seed (default 20261122)")
    ap.add_argument("--engines", default="liggghts,yade,gabion",
                    help="comma list of engines to run, in this order (default liggghts,yade,gabion)")
    ap.add_argument("--gabion", default=os.environ.get("GABION_BINARY", os.path.join(REPO, "build", "gabion")),
                    help="gabion binary (default $GABION_BINARY or build/gabion)")
    ap.add_argument("--gabion-threads", default="1,2", help="comma list of Gabion thread counts (default 1,2)")
    ap.add_argument("--liggghts", default=shutil.which("liggghts") or "",
                    help="LIGGGHTS binary (default: liggghts on PATH)")
    ap.add_argument("--yade", default=shutil.which("yade") or "", help="Yade binary (default: yade on PATH)")
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
    if a.steps < 1 or a.repeat < 1 or any(n < 1 for n in a.n):
        ap.error("N, --steps and --repeat must be >= 1")
    engines = [e.strip() for e in a.engines.split(",") if e.strip()]
    for e in engines:
        if e not in ("gabion", "liggghts", "yade"):
            ap.error(f"unknown engine '{e}' (gabion, liggghts, yade)")
    gthreads = [int(t) for t in a.gabion_threads.split(",") if t.strip()]

    os.makedirs(a.workdir, exist_ok=True)
    stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    log(f"settling benchmark, {stamp}")
    log(f"machine: {cpu_model()}, {os.cpu_count()} logical CPUs; load average {loadavg()}")
    log(f"N = {a.n}, steps = {a.steps}, dt = 4e-5 s, seed = {a.seed}, repeat = {a.repeat}")

    skipped = []
    available = {}
    for e in engines:
        if e == "gabion":
            ok, why = gabion_available(os.path.abspath(a.gabion) if a.gabion else "")
            if ok:
                available[e] = os.path.abspath(a.gabion)
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
    if not os.access(GNU_TIME, os.X_OK):
        log("note: /usr/bin/time not found (Debian package `time`); peak memory from os.wait4 ru_maxrss instead")

    jobs = []
    for n in a.n:
        for e in engines:
            if e not in available:
                continue
            for t in (gthreads if e == "gabion" else [1]):
                jobs.append((n, e, t))
    total = len(jobs) * a.repeat

    rows = []
    failures = 0
    k = 0
    scenes = {}
    for n in a.n:
        t0 = time.perf_counter()
        subprocess.run([sys.executable, os.path.join(HERE, "generate.py"), str(n), "--steps", str(a.steps),
                        "--seed", str(a.seed), "--outdir", a.workdir], check=True, stdout=subprocess.DEVNULL)
        base = os.path.join(a.workdir, f"settle_{n}")
        with open(base + ".meta.json") as f:
            meta = json.load(f)
        scenes[n] = {"n": n, "steps": a.steps, "side_m": meta["side_m"], "gabion_case": base + ".gabion.json",
                     "liggghts_data": base + ".data", "spheres": base + ".spheres",
                     "initial_mean_z_m": meta["initial_mean_z_m"]}
        log(f"scene N={n}: L={meta['side_m']:g} m, cloud height {meta['cloud_height_m']:.4f} m, "
            f"initial mean z {meta['initial_mean_z_m']:.4f} m (generated in {time.perf_counter() - t0:.1f} s)")
        # Round-robin: with --repeat R the engines run in turn R times, so that
        # a drift of the machine's speed hits all of them alike; the best run
        # of each is kept.
        jobs_n = [j for j in jobs if j[0] == n]
        bests = {j: None for j in jobs_n}
        for r in range(a.repeat):
            for (jn, e, t) in jobs_n:
                k += 1
                rundir = os.path.join(a.workdir, f"{e}_N{n}_t{t}" + (f"_r{r + 1}" if a.repeat > 1 else ""))
                shutil.rmtree(rundir, ignore_errors=True)
                os.makedirs(rundir)
                la = loadavg()
                log(f"[{k}/{total}] {e} N={n} threads={t} steps={a.steps} (load {la[0]:.2f}) ...")
                if e == "gabion":
                    res = run_gabion(available[e], scenes[n], t, rundir, a.timeout)
                elif e == "liggghts":
                    res = run_liggghts(available[e], scenes[n], rundir, a.timeout)
                else:
                    res = run_yade(available[e], scenes[n], rundir, a.timeout)
                res["load1"] = la[0]
                if "error" in res:
                    failures += 1
                    log(f"    FAILED ({res['elapsed_s']:.1f} s): {res['error']}\n    outputs in {rundir}")
                    continue
                bsps = n * res["steps"] / res["loop_s"]
                log(f"    loop {res['loop_s']:.2f} s ({bsps / 1e6:.2f} M body-steps/s), whole run "
                    f"{res['elapsed_s']:.1f} s, max RSS {fmt(res['rss_kB'], '.0f')} kB")
                if bests[(jn, e, t)] is None or res["loop_s"] < bests[(jn, e, t)]["loop_s"]:
                    bests[(jn, e, t)] = res
        for (jn, e, t) in jobs_n:
            best = bests[(jn, e, t)]
            if best is not None and not a.no_baseline and a.steps > 1:
                # The same run with 1 step: its CPU time is the start-up and
                # output; the difference is the CPU time of steps - 1 steps,
                # which other jobs on the machine disturb much less than the
                # wall time.
                rundir = os.path.join(a.workdir, f"{e}_N{n}_t{t}_1step")
                shutil.rmtree(rundir, ignore_errors=True)
                os.makedirs(rundir)
                one = dict(scenes[n], steps=1)
                if e == "gabion":
                    b = run_gabion(available[e], one, t, rundir, a.timeout)
                elif e == "liggghts":
                    b = run_liggghts(available[e], one, rundir, a.timeout)
                else:
                    b = run_yade(available[e], one, rundir, a.timeout)
                if "error" in b or b.get("cpu_s") is None or best.get("cpu_s") is None:
                    log(f"    1-step baseline failed: {b.get('error', 'no CPU time')}")
                else:
                    best["loop_cpu_s"] = best["cpu_s"] - b["cpu_s"]
                    log(f"    1-step baseline: CPU {b['cpu_s']:.2f} s; loop CPU {best['loop_cpu_s']:.2f} s")
            if best is not None:
                best.update({"engine": e, "n": n, "threads": t})
                rows.append(best)

    info = {"date": stamp, "machine": f"{cpu_model()}, {os.cpu_count()} logical CPUs", "steps": a.steps,
            "seed": a.seed, "repeat": a.repeat, "rows": rows, "skipped": skipped,
            "initial_mean_z_m": {str(n): scenes[n]["initial_mean_z_m"] for n in scenes}}
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
