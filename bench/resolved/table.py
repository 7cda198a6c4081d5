#!/usr/bin/env python3
"""The tables of bench/resolved/run.sh and, with --in-place OUT, of
bench/resolved/in_place.sh. run.sh's: for each scenario, the resolved wall,
its macro twin and its hybrids on the compared keys, with the relative errors
against the resolved wall and the wall times (Python standard library); and,
with bench_curves (argument 2), a chart per scenario of each model's error
against its wall time, OUT/figures/<scenario>_error_vs_time.png. With --wide
OUT, the table and chart of bench/resolved/wide.sh; with --hybrids OUT, the
hybrid variants of bench/resolved/hybrids.sh."""
import json
import math
import os
import re
import subprocess
import sys

KEYS = [("peak_force_N", "peak force kN", 1e-3), ("max_penetration_m", "penetration mm", 1e3),
        ("contact_duration_s", "contact ms", 1e3), ("max_back_face_displacement_m", "back face mm", 1e3)]


def cell(value, scale):
    return "-" if value is None else f"{value * scale:.3g}"


def err(e):
    return "-" if e is None else f"{100 * e:+.0f} %"


def relative(run, ref):
    """Relative errors of `run` against `ref` on KEYS (None where either lacks the key)."""
    return [None if ref.get(k) in (None, 0) or run.get(k) is None else (run[k] - ref[k]) / abs(ref[k])
            for k, _, _ in KEYS]


# The twins of bench/resolved/in_place.sh: folder prefix under OUT/in_place, and label.
IN_PLACE = [("twin_", "impact law fitted in the wall at 10 m/s"),
            ("twin_rate_", "rate law fitted in the wall at 6 and 10 m/s"),
            ("twin_hist_", "rate law fitted on the walls' histories at 6 and 10 m/s"),
            ("twin_visc_", "rate law fitted on the histories, axial laws viscous"),
            ("twin_hist_flux_", "rate law fitted on the histories, axial laws with the cell's momentum flux"),
            ("twin_flux_", "rate law fitted on the histories with the cell's momentum flux"),
            ("twin_cell_", "rate law fitted on the histories with the axial law of the cell's compressions")]


def settings(depth, info):
    """A hybrid's settings other than its reach, in words, from its summary's
    `hybrid` object (`info`) and its depth."""
    return ((" through the depth" if depth == "whole" else "") +
            (" and below" if info.get("below") == "cells" else "") +
            (", weight above" if info.get("above") == "weight" else "") +
            (", plates beside following" if info.get("beside") == "follow" else "") +
            (", plates following in plane" if info.get("in_plane") == "follow" else "") +
            (", plates free along x and y" if info.get("in_plane") == "free" else "") +
            {"xy": ", macro nodes along x and y", "xyz": ", macro nodes along x, y and z"}.get(
                info.get("macro_motion"), "") +
            (", plates across x giving" if info.get("across") == "gives" else "") +
            (", joint" if info.get("joint") == "law" else ""))


def summary(path):
    s = json.load(open(path))
    return s.get("results", s)


def chart(curves, out, name, label, points):
    """points: (model, wall_s, {key: relative error}) per model."""
    os.makedirs(os.path.join(out, "figures"), exist_ok=True)
    series = []
    for key, title, _ in KEYS:
        xy = [(math.log10(w), 100 * abs(e[key])) for _, w, e in points
              if w and e.get(key) is not None]
        if xy:
            series.append(title.rsplit(" ", 1)[0] + "=" + ",".join(f"{x:.4f}:{y:.3f}" for x, y in sorted(xy)))
    png = os.path.join(out, "figures", f"{name}_error_vs_time.png")
    subprocess.run([curves, "points", png, f"Error against wall time: {label}",
                    "wall time, log10 of seconds (from the left: macro twin, hybrids within 0, 0.25, 0.5 m, resolved)",
                    "|error| against the resolved wall (%)"] + series, check=True)


def main(out, curves=None):
    rows = []
    for name in sorted(os.listdir(out)):
        path = os.path.join(out, name, "summary.json")
        if not os.path.isfile(path) or name.startswith("floor_"):
            continue
        s = json.load(open(path))
        r = s.get("results", s)
        case = s.get("case", {})
        speed = case.get("boulder", {}).get("velocity_m_s")
        aim = case.get("boulder", {}).get("aim_point_m", "centre")
        label = f"{name} ({speed} m/s, aim {aim})"
        if s.get("status") != "ok":  # (the scenario failed: its message is in NAME.log)
            rows.append((label, "resolved", [None] * 4, [None] * 4, "failed", None, None, None))
            continue
        rows.append((label, "resolved", [r.get(k) for k, _, _ in KEYS], [None] * 4, r.get("outcome"),
                     r.get("wall_time_s_resolved"), 1.0, r.get("resolved", {}).get("energy_balance_rel_error")))
        t = r.get("macro_twin", {})
        rows.append((label, "macro twin", [t.get(k) for k, _, _ in KEYS],
                     [r.get("relative_error", {}).get(k) for k, _, _ in KEYS], t.get("outcome"), t.get("wall_time_s"),
                     r.get("speed_up"), None))
        floor = os.path.join(out, "floor_" + name.split("_", 1)[1], "summary.json")
        if name.startswith("centre_") and os.path.isfile(floor):
            f = summary(floor)
            rows.append((label, "resolved again, step 5 % shorter", [f.get(k) for k, _, _ in KEYS], relative(f, r),
                         f.get("outcome"), f.get("wall_time_s"), None, f.get("energy", {}).get("balance_rel_error")))
        for prefix, what in IN_PLACE:
            twin = os.path.join(out, "in_place", prefix + name, "summary.json")
            if os.path.isfile(twin):
                f = summary(twin)
                rows.append((label, f"macro twin, {what} (in_place.sh)", [f.get(k) for k, _, _ in KEYS],
                             relative(f, r), f.get("outcome"), f.get("wall_time_s"), None, f.get("balance_rel_error")))
        points = [("resolved", r.get("wall_time_s_resolved"), {k: 0.0 for k, _, _ in KEYS}),
                  ("macro twin", t.get("wall_time_s"), r.get("relative_error", {}))]
        for h in r.get("hybrids", []):
            if h.get("status") == "ok":
                points.append((f"hybrid {h['within_m']}", h.get("wall_time_s"), h.get("relative_error", {})))
        if curves:
            chart(curves, out, name, label, points)
        for h in r.get("hybrids", []):
            what = f"hybrid within {h['within_m']} m"
            if h.get("status") != "ok":
                rows.append((label, what, [None] * 4, [None] * 4, "failed", None, None, None))
                continue
            what += f" ({h['resolved_cells']} of 12 cells)"
            rows.append((label, what, [h.get(k) for k, _, _ in KEYS],
                         [h.get("relative_error", {}).get(k) for k, _, _ in KEYS], h.get("outcome"),
                         h.get("wall_time_s"), h.get("speed_up"), h.get("balance_rel_error")))
    head = ["scenario", "model"] + [f"{title}" for _, title, _ in KEYS] + ["outcome", "wall s", "x faster", "balance"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for label, model, values, errors, outcome, wall, speed_up, balance in rows:
        cells = []
        for (key, _, scale), v, e in zip(KEYS, values, errors):
            cells.append(cell(v, scale) + ("" if e is None else f" ({err(e)})"))
        wall_s = "-" if wall is None else (f"{wall:.3g}" if wall >= 0.01 else f"{wall:.2g}")
        fast = "-" if speed_up is None else f"{speed_up:.3g}"
        bal = "-" if balance is None else f"{balance:.1e}"
        print("| " + " | ".join([label, model] + cells + [str(outcome), wall_s, fast, bal]) + " |")


def hybrid_more(out):
    """The table of the hybrid's variants run by hand (docs/resolved.md,
    What the hybrids buy): OUT/below/<scenario> (resolve.below "cells") and
    OUT/hybrid_more/<run> (the centred 10 m/s scenario's 4-cell hybrid
    changed), each against its scenario's resolved wall, next to the
    scenario's 4-cell hybrid as macro.resolved ran it."""
    head = ["scenario", "hybrid"] + [title for _, title, _ in KEYS] + ["outcome"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    runs = []
    for name in sorted(os.listdir(os.path.join(out, "below"))) if os.path.isdir(os.path.join(out, "below")) else []:
        runs.append((name, os.path.join(out, "below", name)))
    more = os.path.join(out, "hybrid_more")
    for name in sorted(os.listdir(more)) if os.path.isdir(more) else []:
        runs.append(("centre_10_m_s", os.path.join(more, name)))
    shown = set()
    for scenario, folder in runs:
        f = os.path.join(folder, "summary.json")
        ref_file = os.path.join(out, scenario, "summary.json")
        if not os.path.isfile(f) or not os.path.isfile(ref_file):
            continue
        r = summary(ref_file)
        if scenario not in shown:  # (the scenario's own hybrid, within 0.25 m, first)
            shown.add(scenario)
            for k, h in enumerate(r.get("hybrids", [])):
                if h.get("within_m") == 0.25 and h.get("status") == "ok":
                    print("| " + " | ".join([scenario, f"within 0.25 m ({h['resolved_cells']} cells, hybrid_{k})"] + [
                        cell(h.get(key), scale) + f" ({err(h.get('relative_error', {}).get(key))})"
                        for key, _, scale in KEYS] + [str(h.get("outcome"))]) + " |")
        h = summary(f)
        info = h.get("hybrid", {})
        what = f"within {info.get('within_m')} m" + settings(info.get("depth"), info)
        what += f" ({len(info.get('resolved_cells', []))} cells, {os.path.relpath(folder, out)})"
        errors = relative(h, r)
        print("| " + " | ".join([scenario, what] + [cell(h.get(key), scale) + f" ({err(e)})"
                                                    for (key, _, scale), e in zip(KEYS, errors)] +
                                [str(h.get("outcome"))]) + " |")


def in_place_charts(out, curves, by_speed):
    """Peak force and penetration against the impact speed, one line per
    model, the centre scenarios: OUT/in_place/figures/in_place_vs_speed_<key>.png."""
    figures = os.path.join(out, "in_place", "figures")
    os.makedirs(figures, exist_ok=True)
    for key, title, scale in (KEYS[0], KEYS[1], KEYS[3]):
        series = []
        for label in dict.fromkeys(label for rows in by_speed.values() for label, _ in rows):
            xy = sorted((v, s[key] * scale) for v, rows in by_speed.items() for lab, s in rows
                        if lab == label and s.get(key) is not None)
            if xy:  # (short legend entries: the chart is for the lines, the table for the words)
                short = (label.replace("macro twin, ", "").replace("rate law fitted on the walls' histories", "histories' law")
                         .replace("rate law fitted on the histories", "histories' law").replace(" at 6 and 10 m/s", ""))
                series.append(short + "=" + ",".join(f"{x:g}:{y:.4g}" for x, y in xy))
        png = os.path.join(figures, f"in_place_vs_speed_{key}.png")
        subprocess.run([curves, "points", png, f"{title.rsplit(' ', 1)[0].capitalize()} against impact speed, "
                        "aimed at the centre", "impact speed (m/s)", title] + series, check=True)


def in_place(out, curves=None):
    """The table of bench/resolved/in_place.sh: per scenario, the resolved
    wall, its twin with the UCI impact law and its twins with the impact
    laws fitted in the wall, on peak force, penetration and back face; with
    bench_curves (`curves`), the charts of in_place_charts."""
    d = os.path.join(out, "in_place")
    by_speed = {}
    for fit in ("fit", "fit_rate", "fit_hist", "fit_flux", "fit_cell"):
        law = os.path.join(d, fit, "law.json")
        if os.path.isfile(law):
            print(f"impact law of {fit}:", json.dumps(json.load(open(law))["materials"]["front"]["impact"]))
    keys = [KEYS[0], KEYS[1], KEYS[3]]
    print("| scenario | model | " + " | ".join(title for _, title, _ in keys) + " | outcome |")
    print("|---" * (len(keys) + 3) + "|")
    for name in sorted(os.listdir(out)):
        path = os.path.join(out, name, "summary.json")
        if not (name.startswith("centre_") or name.startswith("side_")) or not os.path.isfile(path):
            continue
        doc = json.load(open(path))
        if doc.get("status") != "ok":  # (the scenario failed: no wall to compare with)
            continue
        r = doc.get("results", doc)
        rows = [("resolved", r, None), ("macro twin, UCI impact law", r["macro_twin"], r)]
        for prefix, what in IN_PLACE:
            twin = os.path.join(d, prefix + name)
            if os.path.isfile(os.path.join(twin, "summary.json")):
                rows.append(("macro twin, " + what, summary(os.path.join(twin, "summary.json")), r))
            elif os.path.isfile(twin + ".log"):
                log = open(twin + ".log").read().strip().splitlines()
                rows.append(("macro twin, " + what, {"outcome": "failed: " + (log[-1] if log else "")}, r))
        speed = doc.get("case", {}).get("boulder", {}).get("velocity_m_s")
        if name.startswith("centre_") and speed is not None:
            by_speed[speed] = [(label, s) for label, s, _ in rows if "failed" not in str(s.get("outcome"))]
        for label, s, ref in rows:
            cells = []
            for k, _, scale in keys:
                e = None if ref is None else relative(s, ref)[[q for q, _, _ in KEYS].index(k)]
                cells.append(cell(s.get(k), scale) + ("" if e is None else f" ({err(e)})"))
            print(f"| {name} | {label} | " + " | ".join(cells) + f" | {s.get('outcome')} |")
    if curves and by_speed:
        in_place_charts(out, curves, by_speed)


def wide(out, curves=None):
    """The table of bench/resolved/wide.sh: per wall, the resolved wall, its
    macro twin and every hybrid, errors against that wall and how many times
    faster than it; with bench_curves (`curves`), each hybrid's largest error
    over the compared keys against that speed-up,
    OUT/figures/wide_error_vs_speed_up.png."""
    head = ["wall", "model"] + [title for _, title, _ in KEYS] + ["outcome", "wall s", "x faster"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    series = []
    walls = sorted(int(m.group(1)) for m in (re.fullmatch(r"wall_(\d+)", d) for d in os.listdir(out)) if m)
    for n in walls:
        path = os.path.join(out, f"wall_{n}", "summary.json")
        if not os.path.isfile(path):
            continue
        r = summary(path)
        ref_wall = r.get("wall_time_s_resolved")
        rows = [(f"resolved ({r.get('resolved', {}).get('bodies', 0):,} bodies)", r, None, ref_wall)]
        rows.append(("macro twin", r.get("macro_twin", {}), r, r.get("macro_twin", {}).get("wall_time_s")))
        hybrids = []
        for k, h in enumerate(r.get("hybrids", [])):
            folder = os.path.join(out, f"wall_{n}", f"hybrid_{k}")
            hybrids.append((h.get("within_m"), h.get("depth", "reach"), folder))
        more = os.path.join(out, f"wall_{n}_more")
        if os.path.isdir(more):
            for name in sorted(os.listdir(more)):
                folder = os.path.join(more, name)
                if os.path.isdir(folder):
                    hybrids.append((None, None, folder))
        for within, depth, folder in hybrids:
            f = os.path.join(folder, "summary.json")
            if not os.path.isfile(f):
                continue
            h = summary(f)
            info = h.get("hybrid", {})
            within = info.get("within_m", within)
            depth = info.get("depth", depth)
            resolved = len(info.get("resolved_cells", []))
            what = (f"hybrid within {within:g} m" + settings(depth, info) +
                    (f", settled {h['settle']['duration_s']:.2g} s" if h.get("settle", {}).get("until_at_rest") is False
                     else "") + f" ({resolved} cells)")
            rows.append((what, h, r, h.get("wall_time_s")))
        points = []
        for model, s, ref, wall in rows:
            errors = [None] * len(KEYS) if ref is None else relative(s, ref)
            cells = [cell(s.get(k), scale) + ("" if e is None else f" ({100 * e:+.1f} %)")
                     for (k, _, scale), e in zip(KEYS, errors)]
            fast = ref_wall / wall if ref_wall and wall else None
            wall_s = "-" if wall is None else (f"{wall:.3g}" if wall >= 0.01 else f"{wall:.2g}")
            print("| " + " | ".join([f"{n} cells", model] + cells +
                                    [str(s.get("outcome")), wall_s, "-" if fast is None else f"{fast:.3g}"]) + " |")
            if model.startswith("hybrid") and fast and None not in errors:
                points.append((math.log10(fast), 100 * max(abs(e) for e in errors)))
        if points:
            series.append(f"{n}-cell wall's hybrids=" + ",".join(f"{x:.4f}:{y:.3f}" for x, y in sorted(points)))
    if curves and series:
        os.makedirs(os.path.join(out, "figures"), exist_ok=True)
        series.append("target: within 5 % at a tenth of the time or less=1:0,1:5,2:5")
        subprocess.run([curves, "points", os.path.join(out, "figures", "wide_error_vs_speed_up.png"),
                        "The hybrid on wide walls: largest error against speed-up, 10 m/s on the centre",
                        "times faster than the resolved wall, log10", "largest |error| of the four keys (%)"] + series,
                       check=True)


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--hybrids":
        hybrid_more(sys.argv[2] if len(sys.argv) > 2 else "results/speed_error")
    elif len(sys.argv) > 1 and sys.argv[1] == "--wide":
        wide(sys.argv[2] if len(sys.argv) > 2 else "results/wide", sys.argv[3] if len(sys.argv) > 3 else None)
    elif len(sys.argv) > 1 and sys.argv[1] == "--in-place":
        in_place(sys.argv[2] if len(sys.argv) > 2 else "results/speed_error", sys.argv[3] if len(sys.argv) > 3 else None)
    else:
        main(sys.argv[1] if len(sys.argv) > 1 else "results/speed_error", sys.argv[2] if len(sys.argv) > 2 else None)
