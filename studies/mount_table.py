"""Tables of the mount-yaw study from ``studies.mount_turn``'s JSON files: real +- sd / twin per variant, with
issue 11's bounds (``x``: outside); the foot-flat |w| profile; the heading check.

``python3 -m studies.mount_table FILE.json [FILE.json ...]``
"""

from __future__ import annotations

import json
import sys

import numpy as np

QUANTITIES = {"window_s": ("window (s)", 1.0, "{:.3f}"), "in_window_velocity_mps": ("in-window velocity (mm/s)", 1e3, "{:.1f}"),
              "underestimate_pct": ("underestimate (pp)", 1.0, "{:.2f}")}


def main(paths):
    results = {}
    for p in paths:
        results.update(json.load(open(p)))
    for q, (title, scale, fmt) in QUANTITIES.items():
        print(f"\n**{title}**: real +- sd / " + " / ".join(next(iter(results.values()))["twins"]) + " (x: outside)\n")
        ths = next(iter(results.values()))["real"]["thresholds"]
        print("| recording | " + " | ".join(f"{t:.0e}" for t in ths) + " |")
        print("|---" * (len(ths) + 1) + "|")
        for name, r in results.items():
            cells = []
            for j in range(len(ths)):
                real = r["real"][q]
                parts = []
                for v in r["twins"].values():
                    row = v["comparison"][q][j]
                    parts.append(fmt.format(row["twin"] * scale) + ("" if row["within"] else "x"))
                cells.append(fmt.format(real["value"][j] * scale) + " +- " + fmt.format(real["sd"][j] * scale)
                             + " / " + " / ".join(parts))
            print(f"| {name} | " + " | ".join(cells) + " |")
    print("\n**slope** (pp, 5e4 - 1e4): real +- sd / twins\n")
    for name, r in results.items():
        s = r["real"]["underestimate_pct"]
        parts = [f"{v['comparison']['slope']['twin']:.2f}" + ("" if v["comparison"]["slope"]["within"] else "x")
                 for v in r["twins"].values()]
        print(f"| {name} | {s['slope']:.2f} +- {s['slope_sd']:.2f} | " + " / ".join(parts) + " |")
    print("\n**foot-flat |w| at 0.4/0.6/0.8** (deg/s)\n")
    for name, r in results.items():
        ph = np.array(r["real_profile"]["phase"])
        at = [int(np.argmin(abs(ph - u))) for u in (0.4, 0.6, 0.8)]
        def prof(p):
            return "/".join(f"{p['median']['rate_dps'][k]:.1f}" for k in at)
        print(f"| {name} | real {prof(r['real_profile'])} | " + " | ".join(
            f"{k} {prof(v['profile'])}" for k, v in r["twins"].items()) + " |")
    print("\n**core foot-flat rate per axis (deg/s, median over strides)**\n")
    for name, r in results.items():
        print(f"| {name} | real {r['real_rates']['core_median_dps']} | " + " | ".join(
            f"{k} {v['rates']['core_median_dps']} (mount {v['mount_rate_core_dps']}, max angle {v['max_mount_angle_deg']:.1f} deg, at contacts {v['mount_angle_at_contacts_deg']:.3f})"
            for k, v in r["twins"].items()) + " |")
    print("\n**heading / start-to-end** at 1e4 and 5e4: yaw error (filter - true sensor yaw) first/last/mean+-sd deg at foot-flat middles; start-to-end underestimate %\n")
    for name, r in results.items():
        for k, v in r["twins"].items():
            print(f"| {name} | {k} | " + " | ".join(
                f"{th}: {h['yaw_error_first_deg']:.2f} / {h['yaw_error_last_deg']:.2f} / {h['yaw_error_mean_deg']:.2f}+-{h['yaw_error_sd_deg']:.2f}; {h['start_to_end_underestimate_pct']:.2f} %"
                for th, h in v["heading"].items()) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
