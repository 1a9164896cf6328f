#!/usr/bin/env python3
"""Does the renderer's realism make visual localisation harder? A paired A/B over many scenes.

One run of the vslam benchmark is not enough to say: its monocular SLAM figures swing several-fold
with sub-percent pixel changes (issue 13's closing notes). This script renders the same flight
over N scenes (seeds: rock field, seabed relief, pipe and sensor noise differ) once per renderer
variant -- `on` (shadows, caustics and materials, the defaults), `off` (all three off), or one
feature off at a time (`no_shadows`, `no_caustics`, `no_materials`) -- with `unav datagen`
(640x480 down camera, TUM layout), runs `unav localize` (orb_slam, klt_mono) on each sequence
and reports, per light condition, method and variant: the median and range of the Sim(3)-aligned
APE and of the tracked fraction, and per seed the ratio of each variant's APE to `on`'s on the
same scene (paired: the scene's difficulty cancels). Deterministic: the same seeds give the same
images and numbers.

Usage: scripts/vslam_realism_ab.py [--out out/realism_ab] [--seeds 1,2,3,4,5] [--frames 150]
       [--conditions day,night] [--variants on,off] [--methods orb_slam,klt_mono]
Writes <out>/runs.csv (one row per sequence and method) and <out>/summary.md.
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vslam_water_sweep import CONDITIONS, SPEC, localize  # noqa: E402  (same flight, same parser)

VARIANTS = {
    "on": (True, True, True),
    "off": (False, False, False),
    "no_shadows": (False, True, True),
    "no_caustics": (True, False, True),
    "no_materials": (True, True, False),
}
RENDER = "render: {{shadows: {}, caustics: {}, materials: {}}}\n"


def render_and_localize(out, ws, cond, seed, variant, frames, preset, methods):
    name = f"{cond}_s{seed}_{variant}"
    spec = os.path.join(out, name + ".yaml")
    flags = ["true" if f else "false" for f in VARIANTS[variant]]
    with open(spec, "w") as f:
        f.write(SPEC.format(seed=seed, ws=ws, frames=frames, preset=preset, **CONDITIONS[cond]))
        f.write(RENDER.format(*flags))
    data = os.path.join(out, name)
    subprocess.run(["unav", "datagen", spec, "-n", "1", "--out", data], check=True, stdout=subprocess.DEVNULL)
    seq = os.path.join(data, "sample_000000")
    rows = []
    for method in methods:
        r = localize(seq, method)
        r.update({"condition": cond, "seed": seed, "variant": variant, "method": method})
        rows.append(r)
        print(f"{cond:5s} seed {seed:3d} {variant:12s} {method:8s} tracked {100 * r['tracked']:5.1f} %  "
              f"APE {r['ape_m']:.4f} m  RPE {r['rpe_m']:.4f} m", flush=True)
    return rows


def fmt_range(values, scale=1.0, digits=4):
    v = [x * scale for x in values if x == x]  # NaN: the method gave no trajectory
    if not v:
        return "n/a"
    lost = len(values) - len(v)
    s = f"{statistics.median(v):.{digits}f} ({min(v):.{digits}f}-{max(v):.{digits}f})"
    return s + (f", {lost} lost" if lost else "")


def summary(rows, conditions, variants, methods, seeds):
    out = ["| light | method | variant | APE [m] median (range) | tracked [%] median (range) | "
           "APE / APE(on), per seed | median ratio, scenes with a lower APE |", "|---|---|---|---|---|---|---|"]
    for cond in conditions:
        for method in methods:
            for variant in variants:
                sel = {r["seed"]: r for r in rows
                       if r["condition"] == cond and r["method"] == method and r["variant"] == variant}
                base = {r["seed"]: r for r in rows
                        if r["condition"] == cond and r["method"] == method and r["variant"] == "on"}
                apes = [sel[s]["ape_m"] for s in seeds]
                tracked = [sel[s]["tracked"] for s in seeds]
                ratios, per_seed = [], ""
                if variant != "on" and base:
                    for s in seeds:
                        a, b = sel[s]["ape_m"], base[s]["ape_m"]
                        ok = a == a and b == b and b > 0
                        ratios.append(a / b if ok else float("nan"))
                    per_seed = " ".join("-" if x != x else f"{x:.2f}" for x in ratios)
                finite = [x for x in ratios if x == x]
                # How many scenes this variant did better on (a sign test's count).
                med = ""
                if finite:
                    med = f"{statistics.median(finite):.2f}, lower on {sum(x < 1 for x in finite)} of {len(finite)}"
                out.append(f"| {cond} | {method} | {variant} | {fmt_range(apes)} | "
                           f"{fmt_range(tracked, 100.0, 0)} | {per_seed} | {med} |")
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="out/realism_ab")
    ap.add_argument("--seeds", default="1,2,3,4,5")
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--preset", default="IB", help="Jerlov water type of every scene")
    ap.add_argument("--conditions", default="day,night")
    ap.add_argument("--variants", default="on,off")
    ap.add_argument("--methods", default="orb_slam,klt_mono")
    a = ap.parse_args()
    seeds = [int(s) for s in a.seeds.split(",")]
    conditions, variants, methods = a.conditions.split(","), a.variants.split(","), a.methods.split(",")
    for c in conditions:
        if c not in CONDITIONS:
            ap.error(f"--conditions: unknown '{c}' (known: {', '.join(CONDITIONS)})")
    for v in variants:
        if v not in VARIANTS:
            ap.error(f"--variants: unknown '{v}' (known: {', '.join(VARIANTS)})")
    if "on" not in variants:
        variants.insert(0, "on")  # the reference of the paired ratios
    ws = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for cond in conditions:
        for seed in seeds:
            for variant in variants:
                rows += render_and_localize(a.out, ws, cond, seed, variant, a.frames, a.preset, methods)
    with open(os.path.join(a.out, "runs.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["condition", "seed", "variant", "method", "tracked", "ape_m", "rpe_m"])
        w.writeheader()
        w.writerows(rows)
    text = (f"# Realism A/B: {len(seeds)} scenes (seeds {a.seeds}), {a.frames} frames, Jerlov {a.preset}\n\n"
            "Variants: on = shadows, caustics and materials (the defaults); off = none of them.\n\n"
            + summary(rows, conditions, variants, methods, seeds))
    with open(os.path.join(a.out, "summary.md"), "w") as f:
        f.write(text)
    print(text)
    print(f"results: {a.out}/summary.md, runs.csv")


if __name__ == "__main__":
    main()
