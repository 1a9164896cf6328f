"""Analytic cases of scripts/realism_report.py's metrics, and the script on two small folders."""
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
import realism_report as rr  # noqa: E402


def test_lab_of_reference_colours():
    # sRGB white is the D65 white: L* 100, a* = b* = 0; sRGB red is (53.24, 80.09, 67.20) (CIE tables).
    lab = rr.rgb_to_lab(np.array([[[255, 255, 255], [0, 0, 0], [255, 0, 0]]], np.uint8))
    assert lab[0, 0] == pytest.approx([100.0, 0.0, 0.0], abs=0.01)
    assert lab[0, 1] == pytest.approx([0.0, 0.0, 0.0], abs=1e-9)
    assert lab[0, 2] == pytest.approx([53.24, 80.09, 67.20], abs=0.05)


def test_rms_contrast_and_colour_of_flat_images():
    half = np.zeros((40, 40, 3), np.uint8)
    half[:, 20:] = 255
    m = rr.camera_metrics(half)
    assert m["rms_contrast"] == pytest.approx(0.5, abs=1e-12)  # Y in {0, 1}, half each
    assert m["uicm"] == pytest.approx(0.0, abs=1e-12)  # grey: RG = YB = 0
    blue = np.zeros((32, 32, 3), np.uint8)
    blue[...] = (20, 90, 160)  # a sea blue
    mb = rr.camera_metrics(blue)
    assert mb["rms_contrast"] == pytest.approx(0.0, abs=1e-12)
    assert mb["uiconm"] == 0.0 and mb["uism"] == 0.0  # no contrast in any block
    assert mb["hsv_hue_deg"] == pytest.approx(210.0, abs=1e-9)  # (b - r) / (max - min) + 2 -> 3.5 x 60
    assert mb["lab_b"] < -30.0 and 180.0 < mb["hue_deg"] < 300.0
    assert mb["saturation"] == pytest.approx(140.0 / 160.0)


def test_delentropy_counts_gradient_pairs():
    assert rr.delentropy(np.full((20, 20), 77, np.uint8)) == 0.0
    # fx alternates +10 / -10 (equally often), fy is 0: one bit of gradient entropy, halved.
    row = np.tile([0, 10], 21)[:41].astype(np.uint8)  # 40 differences: 20 of each
    assert rr.delentropy(np.tile(row, (20, 1))) == pytest.approx(0.5, abs=1e-12)


def test_exponential_speckle_contrast_one_and_rayleigh_fit():
    rng = np.random.default_rng(1)
    intensity = rng.exponential(1.0, (256, 256))
    # Amplitude-linear 8-bit coding (gamma 1): the value is the amplitude sqrt(I), scaled.
    v = np.clip(np.rint(255.0 * np.sqrt(intensity / 12.0)), 1, 255).astype(np.uint8)
    m, hist, _ = rr.sonar_metrics(v, gamma=1.0, polar=True)
    # Exponential intensity: std / mean = 1; 8-bit rounding and the few clipped samples above
    # 12 x the mean (6e-6) move it by well under 5 %.
    assert m["speckle_contrast"] == pytest.approx(1.0, abs=0.05)
    assert m["best_fit"] == "rayleigh"
    assert m["k_shape_nu"] > 10.0
    assert m["corr_x_px"] < 1.0 and m["corr_y_px"] < 1.0  # independent pixels
    assert hist.sum() == v.size


def test_k_distributed_speckle_is_found_with_its_shape():
    rng = np.random.default_rng(2)
    nu = 1.0
    texture = rng.gamma(nu, 1.0 / nu, (256, 256))  # unit-mean gamma texture x exponential speckle
    intensity = texture * rng.exponential(1.0, (256, 256))
    fits = rr.distribution_fits([intensity[y:y + 32, x:x + 32] for y in range(0, 256, 32) for x in range(0, 256, 32)])
    assert fits["best_fit"] == "k"
    # Moments of 65536 samples: E[I^2] = 2 (1 + 1/nu) has a heavy tail; nu within 35 %.
    assert fits["k_shape_nu"] == pytest.approx(nu, rel=0.35)
    # K intensity contrast: sqrt(1 + 2/nu) = 1.73 for nu = 1.
    assert np.std(intensity) / np.mean(intensity) == pytest.approx(math.sqrt(1 + 2 / nu), rel=0.1)


def test_correlation_length_of_a_box_filtered_field():
    # A 3-tap box along x: autocorrelation 1, 2/3, 1/3, 0 -> 1/e at lag 1 + (2/3 - 1/e) / (1/3) = 1.90.
    rng = np.random.default_rng(3)
    w = rng.normal(size=(512, 520))
    f = (w[:, :-2] + w[:, 1:-1] + w[:, 2:])[:, :512] + 100.0
    blks = [f[y:y + 32, x:x + 32] for y in range(0, 512, 32) for x in range(0, 512, 32)]
    assert rr.correlation_length(blks, axis=1) == pytest.approx(1.0 + (2 / 3 - math.exp(-1)) * 3, abs=0.15)
    assert rr.correlation_length(blks, axis=0) < 1.0  # rows independent


def test_fan_mask_fills_the_sector_and_holes():
    h, w = 200, 300
    y, x = np.mgrid[0:h, 0:w]
    r = np.hypot(x - 150, 199 - y)
    ang = np.degrees(np.arctan2(x - 150, 199 - y))
    sector = (r < 190) & (np.abs(ang) < 60)
    img = np.where(sector, 100, 0).astype(np.uint8)
    img[100:104, 140:160] = 0  # a dark patch inside the fan: in the fan, counted as zeros
    mask = rr.fan_mask(img, polar=False)
    assert mask[100:104, 140:160].all()
    assert np.mean(mask == sector) > 0.99
    m, _, _ = rr.sonar_metrics(img, gamma=1.0, polar=False)
    assert m["zero_fraction"] == pytest.approx(80 / sector.sum(), rel=0.05)


def test_histogram_distances():
    p = np.zeros(256)
    p[0] = 1
    q = np.zeros(256)
    q[10] = 1
    assert rr.emd_1d(p, q) == pytest.approx(10.0)
    assert rr.kl(p, p) == pytest.approx(0.0, abs=1e-9) and rr.js(p, p) == pytest.approx(0.0, abs=1e-9)
    assert rr.js(p, q) == pytest.approx(math.log(2), rel=1e-3)  # disjoint: JS = ln 2


def test_motion_diversity_of_straight_and_tumbling_flights():
    t = np.arange(50) * 0.1
    straight = np.column_stack([t, 0.5 * t, 0 * t, 0 * t, 0 * t, 0 * t, 0 * t, 1 + 0 * t])
    m = rr.motion_metrics(straight)
    assert m["motion_diversity"] == pytest.approx(1.0, abs=1e-9)
    assert m["speed_mps"] == pytest.approx(0.5) and m["rotation_dps"] == pytest.approx(0.0, abs=1e-9)
    rng = np.random.default_rng(4)
    rows, p, q = [], np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0])
    for k in range(400):  # random twists in all six directions
        rows.append([0.1 * k, *p, *q])
        p = p + rng.normal(scale=0.05, size=3)
        dq = np.concatenate([0.5 * rng.normal(scale=0.05, size=3), [1.0]])
        x1, y1, z1, w1 = q
        x2, y2, z2, w2 = dq / np.linalg.norm(dq)
        q = np.array([w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2, w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                      w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2, w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2])
    assert rr.motion_metrics(np.array(rows))["motion_diversity"] > 5.0


def test_script_on_two_folders(tmp_path):
    rng = np.random.default_rng(5)
    for name, tint in (("ours", (40, 160, 140)), ("real", (30, 110, 170))):
        d = tmp_path / name
        d.mkdir()
        for k in range(3):
            img = np.clip(np.array(tint) + rng.normal(scale=20, size=(60, 80, 3)), 0, 255).astype(np.uint8)
            Image.fromarray(img).save(d / f"{k:03d}.png")
    out = tmp_path / "report"
    r = subprocess.run([sys.executable, str(ROOT / "scripts/realism_report.py"), "camera", str(tmp_path / "ours"),
                        str(tmp_path / "real"), "--out", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    text = (out / "report.md").read_text()
    for key in ("| uiqm |", "| uciqe |", "| delentropy |", "| hue_deg |", "| frame_diff |"):
        assert key in text
    assert (out / "report.json").exists()
    bad = subprocess.run([sys.executable, str(ROOT / "scripts/realism_report.py"), "sonar", str(tmp_path / "ours"),
                          str(tmp_path / "real"), "--gamma-real", "nan", "--out", str(out)],
                         capture_output=True, text=True)
    assert bad.returncode != 0 and "--gamma-* must be finite and > 0 (got nan)" in bad.stderr
    missing = subprocess.run([sys.executable, str(ROOT / "scripts/realism_report.py"), "camera",
                              str(tmp_path / "nope"), str(tmp_path / "real")], capture_output=True, text=True)
    assert missing.returncode != 0 and "nope: no such file or folder" in missing.stderr
