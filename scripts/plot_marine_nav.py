#!/usr/bin/env python3
"""Plots the marine navigation demo (unav_marine_nav_demo's CSV): the USBL fixes against the
ground truth seen from above, the DVL beams' bottom points along the track, and the tether's
shape at a few instants seen from the side.

Usage: scripts/plot_marine_nav.py [--data out/marine_nav] [--out docs/gallery]
(run `unav_marine_nav_demo --out out/marine_nav` first; workspace sourced)."""
import argparse
import csv
import math
import os
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows(path):
    with open(path) as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default="out/marine_nav")
    ap.add_argument("--out", default="docs/gallery")
    a = ap.parse_args()
    truth = rows(os.path.join(a.data, "truth.csv"))
    usbl = rows(os.path.join(a.data, "usbl.csv"))
    tether = rows(os.path.join(a.data, "tether.csv"))
    dvl = rows(os.path.join(a.data, "dvl.csv"))
    os.makedirs(a.out, exist_ok=True)

    # USBL track, top view (east right, north up).
    fixes = [u for u in usbl if u["valid"] > 0.5]
    err = [math.dist((u["x"], u["y"]), (u["truth_x"], u["truth_y"])) for u in fixes]
    rms = math.sqrt(sum(e * e for e in err) / len(err)) if err else float("nan")
    fig, ax = plt.subplots(figsize=(7.5, 3.4), dpi=100)
    ax.plot([t["y"] for t in truth], [t["x"] for t in truth], "-", color="0.3", lw=1.2, label="ground truth")
    ax.plot([u["y"] for u in fixes], [u["x"] for u in fixes], ".", color="tab:red", ms=5,
            label=f"USBL fixes ({len(fixes)}, RMS {rms:.2f} m horizontal)")
    ax.plot([0.0], [0.0], "^", color="tab:blue", ms=9, label="transceiver and tether anchor")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_aspect("equal")
    ax.set_ylim(-3.0, 5.0)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=7, ncol=3)
    ax.set_title("USBL fixes of the vehicle (1 Hz, 0.1 m / 1 deg noise), 0.2 m/s current east", fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "usbl_track.png"))

    # DVL footprints, top view: each beam's bottom point (from its measured slant range) over the
    # first 40 s, 1 reading in 5, with the vehicle's track; lost beams are left out.
    fig, ax = plt.subplots(figsize=(7.5, 3.4), dpi=100)
    first = [t for t in truth if t["t"] <= 40.0]
    ax.plot([t["y"] for t in first], [t["x"] for t in first], "-", color="0.3", lw=1.2, label="vehicle track")
    colours = ["tab:blue", "tab:orange", "tab:green", "tab:red"]
    stamps = sorted({r["t"] for r in dvl if r["t"] <= 40.0})[::5]
    keep = set(stamps)
    for b in range(4):
        pts = [r for r in dvl if r["beam"] == b and r["t"] in keep and r["valid"] > 0.5]
        ax.plot([r["y"] for r in pts], [r["x"] for r in pts], ".", color=colours[b], ms=3, label=f"beam {b + 1}")
    locked = sum(1 for r in dvl if r["valid"] > 0.5) / max(1, len(dvl))
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.margins(y=0.3)  # room for the legend above the footprints
    ax.legend(loc="upper left", fontsize=7, ncol=5)
    ax.set_title(f"DVL (4 beams, 22.5 deg Janus): bottom points along the first 40 s ({100 * locked:.0f} % of beams "
                 "locked over the flight)", fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "dvl_footprints.png"))

    # Tether shapes, side view: horizontal distance from the anchor against depth.
    shapes = defaultdict(list)
    for r in tether:
        shapes[r["t"]].append(r)
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=100)
    for t, nodes in sorted(shapes.items()):
        nodes.sort(key=lambda r: r["node"])
        ax.plot([math.hypot(n["x"], n["y"]) for n in nodes], [n["z"] for n in nodes], "-o", ms=2, lw=1,
                label=f"t = {t:.0f} s")
    ax.axhline(10.0, color="tan", lw=2, label="seabed (~10 m)")
    ax.invert_yaxis()
    ax.set_xlabel("horizontal distance from the anchor [m]")
    ax.set_ylabel("depth [m]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    ax.set_title("The 25 m tether: slack, lying on the seabed, then taut (20 lumped segments)", fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "tether_shapes.png"))
    print(f"plot_marine_nav: {os.path.join(a.out, 'usbl_track.png')}, {os.path.join(a.out, 'dvl_footprints.png')}, "
          f"{os.path.join(a.out, 'tether_shapes.png')}")


if __name__ == "__main__":
    main()
