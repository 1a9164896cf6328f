#!/usr/bin/env python3
"""Learning curves of the pipe follower over several training seeds, as one PNG.

    .venv/bin/python scripts/plot_learning_curves.py out/train/seed0 out/train/seed1 out/train/seed2 \\
        --out docs/gallery/pipe_following_learning.png

Left: mean episode return of the training rollouts (monitor.csv, smoothed over 50 episodes) vs
environment steps, per seed. Right: held-out evaluation (eval.csv: deterministic policy on
split=eval scenes) return and episode length vs steps. Step 0 holds two evaluations: before and
after the behaviour-cloning warm start."""
from __future__ import annotations

import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def read_monitor(path: str):
    steps, rets, lens = [], [], []
    total = 0
    with open(path) as f:
        lines = [l for l in f if not l.startswith("#")]
    for row in csv.DictReader(lines):
        total += int(row["l"])
        steps.append(total)
        rets.append(float(row["r"]))
        lens.append(int(row["l"]))
    return np.array(steps), np.array(rets), np.array(lens)


def read_eval(path: str):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return (np.array([int(r["steps"]) for r in rows]), np.array([float(r["mean_return"]) for r in rows]),
            np.array([float(r["mean_length"]) for r in rows]))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--out", default="docs/gallery/pipe_following_learning.png")
    ap.add_argument("--offset", type=int, default=0,
                    help="steps before PPO (critic warm-up) are counted; monitor steps start at 0")
    args = ap.parse_args()
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    for run in args.runs:
        name = os.path.basename(os.path.normpath(run))
        steps, rets, _ = read_monitor(os.path.join(run, "monitor.csv"))
        if len(rets):
            k = min(50, len(rets))
            smooth = np.convolve(rets, np.ones(k) / k, mode="valid")
            a.plot(steps[k - 1:], smooth, label=name)
        es, er, el = read_eval(os.path.join(run, "eval.csv"))
        b.plot(es, er, marker="o", label=f"{name} return")
    a.set_xlabel("environment steps (0-4096: critic warm-up, actor frozen; then PPO)")
    a.set_ylabel("episode return (rollouts, mean of 50)")
    a.set_title("training rollouts")
    a.grid(alpha=0.3)
    a.legend()
    b.set_xlabel("environment steps")
    b.set_ylabel("held-out return (deterministic)")
    b.set_title("evaluation on held-out scenes (split=eval)")
    b.grid(alpha=0.3)
    b.legend(fontsize=8)
    fig.tight_layout()
    os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)
    fig.savefig(args.out, dpi=90)
    print(args.out)


if __name__ == "__main__":
    main()
