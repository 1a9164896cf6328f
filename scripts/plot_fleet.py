#!/usr/bin/env python3
"""Plots a fleet run (pipe_inspection_pair.launch.yaml): every vehicle's ground truth seen from
above (east right, north up) with markers every 5 s, and the distance between the first two
vehicles over time.

Usage: scripts/plot_fleet.py [--run out/pipe_inspection_pair] [--out docs/gallery/fleet_pair.png]
       [--target 5.0]
(each vehicle's evaluator writes <run>/<ns>/ground_truth.tum: `timestamp x y z qx qy qz qw`, NED)."""
import argparse
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def tum(path):
    with open(path) as f:
        return [[float(v) for v in line.split()] for line in f if line.strip() and not line.startswith("#")]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--run", default="out/pipe_inspection_pair")
    ap.add_argument("--out", default="docs/gallery/fleet_pair.png")
    ap.add_argument("--target", type=float, default=5.0, help="station-keeping distance drawn [m]")
    a = ap.parse_args()
    names = sorted(d for d in os.listdir(a.run) if os.path.isfile(os.path.join(a.run, d, "ground_truth.tum")))
    if not names:
        raise SystemExit(f"{a.run}: no <ns>/ground_truth.tum")
    tracks = {n: tum(os.path.join(a.run, n, "ground_truth.tum")) for n in names}
    fig, (top, dist) = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [1.5, 1]})
    for n, t in tracks.items():
        top.plot([r[2] for r in t], [r[1] for r in t], label=n)
        marks = [r for r in t if abs(r[0] / 5.0 - round(r[0] / 5.0)) < 1e-6]
        top.scatter([r[2] for r in marks], [r[1] for r in marks], s=12)
    top.set_xlabel("east [m]")
    top.set_ylabel("north [m]")
    top.set_aspect("equal", adjustable="datalim")
    top.grid(alpha=0.3)
    top.legend(loc="lower left")
    top.set_title("ground truth from above (dots every 5 s)")
    if len(names) >= 2:
        a0, b0 = tracks[names[0]], tracks[names[1]]
        n = min(len(a0), len(b0))
        dist.plot([a0[i][0] for i in range(n)], [math.dist(a0[i][1:4], b0[i][1:4]) for i in range(n)],
                  label=f"{names[1]} to {names[0]}")
        dist.axhline(a.target, color="gray", ls="--", label=f"target {a.target:g} m")
        dist.set_xlabel("time [s]")
        dist.set_ylabel("distance [m]")
        dist.grid(alpha=0.3)
        dist.legend()
        dist.set_title("station keeping from USBL fixes")
    fig.tight_layout()
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
    fig.savefig(a.out, dpi=90)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
