#!/usr/bin/env python3
"""The table of bench/resolved/run.sh: for each scenario, the resolved wall,
its macro twin and its hybrids on the compared keys, with the relative errors
against the resolved wall and the wall times (Python standard library)."""
import json
import os
import sys

KEYS = [("peak_force_N", "peak force kN", 1e-3), ("max_penetration_m", "penetration mm", 1e3),
        ("contact_duration_s", "contact ms", 1e3), ("max_back_face_displacement_m", "back face mm", 1e3)]


def cell(value, scale):
    return "-" if value is None else f"{value * scale:.3g}"


def err(e):
    return "-" if e is None else f"{100 * e:+.0f} %"


def main(out):
    rows = []
    for name in sorted(os.listdir(out)):
        path = os.path.join(out, name, "summary.json")
        if not os.path.isfile(path):
            continue
        s = json.load(open(path))
        r = s.get("results", s)
        case = s.get("case", {})
        speed = case.get("boulder", {}).get("velocity_m_s")
        aim = case.get("boulder", {}).get("aim_point_m", "centre")
        label = f"{name} ({speed} m/s, aim {aim})"
        rows.append((label, "resolved", [r.get(k) for k, _, _ in KEYS], [None] * 4, r.get("outcome"),
                     r.get("wall_time_s_resolved"), 1.0, r.get("resolved", {}).get("energy_balance_rel_error")))
        t = r.get("macro_twin", {})
        rows.append((label, "macro twin", [t.get(k) for k, _, _ in KEYS],
                     [r.get("relative_error", {}).get(k) for k, _, _ in KEYS], t.get("outcome"), t.get("wall_time_s"),
                     r.get("speed_up"), None))
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


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "results/speed_error")
