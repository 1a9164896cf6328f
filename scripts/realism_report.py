#!/usr/bin/python3
"""Realism report: the same image statistics for a folder of our images and a folder of real ones,
side by side (issue 43). Nothing here is fitted to either side: each metric is computed the same
way on both folders and reported as the median and the 10-90 % range over the images, with
whether our median lies inside the real range.

  scripts/realism_report.py camera OURS REAL [--gt-ours TUM] [--gt-real TUM] [--out DIR]
  scripts/realism_report.py sonar OURS REAL [--gamma-ours G] [--gamma-real G] [--polar] [--out DIR]

OURS and REAL are folders of PNG/JPG images (sorted by name: a sequence), or single images.

Camera metrics (8-bit sRGB in, converted to CIELab with the D65 white):
  rms_contrast   standard deviation of the luminance Y in [0, 1] (Peli's RMS contrast)
  lab_L, lab_a, lab_b, chroma   mean CIELab L*, a*, b* and chroma C* = sqrt(a*^2 + b*^2)
  hue_deg        circular mean of the CIELab hue angle atan2(b*, a*) weighted by C* (deg, 0..360);
                 the HSV hue of the mean colour is also given (hsv_hue_deg, 0 red, 120 green, 240 blue)
  saturation     mean HSV saturation
  uciqe          Yang & Sowmya 2015: 0.4680 sigma_c + 0.2745 con_l + 0.2576 mu_s (sigma_c: std of
                 C*/100, con_l: mean of the top 1 % minus the bottom 1 % of L*/100, mu_s: mean of C*/L*)
  uiqm, uicm, uism, uiconm   Panetta et al. 2016: UIQM = 0.0282 UICM + 0.2953 UISM + 3.5753 UIConM;
                 UICM from the alpha-trimmed (10 %) mean and variance of RG = R - G and YB = (R + G)/2 - B;
                 UISM = sum of 0.299/0.587/0.114 x EME (8 x 8 blocks) of each channel's Sobel edge map;
                 UIConM = the PLIP log-AMEE of the intensity over 8 x 8 blocks
  delentropy     Larkin 2016: entropy (bits) of the joint histogram of the luminance gradients (fx, fy),
                 halved (as the underwater dataset papers use it)
  edge_density   fraction of pixels whose Sobel gradient of the sRGB-coded grey exceeds 0.1 a pixel
Every image is first scaled to --width pixels wide (default 320, the paper's observation; aspect
kept): sharpness and edge metrics depend on the scale.
Along the sequence: frame_std_<metric> (std over the frames of the per-frame means of L*, a*, b*,
hue) and frame_diff (mean absolute difference of consecutive frames, 0..255).
With ground truth (TUM: t x y z qx qy qz qw): speed_mps, rotation_dps (median angular rate),
and motion_diversity = exp(entropy) of the eigenvalues of the second moment of the unit-normalised
6-D twists between poses (1: one kind of motion only, 6: all six equally).

Sonar metrics (8-bit fan or polar images; inside the fan only: pixels of the filled region that the
non-zero pixels close, unless --polar says every pixel is data):
  p05, p25, p50, p95, p99   intensity percentiles (0..255); bright_ratio = p95 / p25
  zero_fraction, saturated_fraction   values 0 and 255 inside the fan
  speckle_contrast   std / mean of the linear intensity in homogeneous 32 x 32 blocks (the blocks
                 between the 40th and 95th percentile of block means whose four quadrant means agree
                 within 35 %); linear intensity = (value / 255)^(2 / gamma) for a display coding
                 value ~ amplitude^gamma (--gamma-*: 1 for amplitude-linear images, 0.5 for a gamma
                 coding); exponential speckle gives 1, K-distributed > 1
  fit_rayleigh, fit_k, k_shape_nu, best_fit   mean log-likelihood per sample of the block-normalised
                 intensity under fully developed speckle (Rayleigh amplitude = exponential intensity)
                 and under the K distribution (shape nu from the moments); best_fit: k when it is
                 better by > 0.01 a sample
  corr_x_px, corr_y_px   correlation length (lag where the autocorrelation of the block's
                 deviations falls to 1/e) across columns (beams in a polar image) and rows (range)
Between the two folders: the KL, JS divergences and the earth mover's distance of the in-fan
intensity histograms, and the JS divergence of the uniform LBP(8, 1) texture histograms.

Writes report.md and report.json to --out (default: out/realism) and prints the markdown.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

import numpy as np
from PIL import Image
from scipy import ndimage, special

IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff"}


# ---------------------------------------------------------------------------------------------
# Colour


def srgb_to_linear(rgb8: np.ndarray) -> np.ndarray:
    c = rgb8.astype(np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def rgb_to_lab(rgb8: np.ndarray) -> np.ndarray:
    """8-bit sRGB (H x W x 3) -> CIELab (D65), L* in [0, 100]."""
    lin = srgb_to_linear(rgb8)
    m = np.array([[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750],
                  [0.0193339, 0.1191920, 0.9503041]])
    xyz = lin @ m.T
    white = np.array([0.95047, 1.0, 1.08883])
    t = xyz / white
    eps, kappa = 216.0 / 24389.0, 24389.0 / 27.0
    f = np.where(t > eps, np.cbrt(t), (kappa * t + 16.0) / 116.0)
    lab = np.empty_like(f)
    lab[..., 0] = 116.0 * f[..., 1] - 16.0
    lab[..., 1] = 500.0 * (f[..., 0] - f[..., 1])
    lab[..., 2] = 200.0 * (f[..., 1] - f[..., 2])
    return lab


def luminance(rgb8: np.ndarray) -> np.ndarray:
    """Relative luminance Y in [0, 1] (linear sRGB, Rec. 709 weights)."""
    lin = srgb_to_linear(rgb8)
    return lin @ np.array([0.2126, 0.7152, 0.0722])


def hsv_saturation(rgb8: np.ndarray) -> np.ndarray:
    c = rgb8.astype(np.float64)
    mx, mn = c.max(axis=2), c.min(axis=2)
    return np.where(mx > 0, (mx - mn) / np.maximum(mx, 1e-12), 0.0)


def hsv_hue_deg(rgb: np.ndarray) -> float:
    """HSV hue (deg) of one RGB colour."""
    r, g, b = (float(v) for v in rgb)
    mx, mn = max(r, g, b), min(r, g, b)
    if mx - mn < 1e-12:
        return float("nan")
    d = mx - mn
    if mx == r:
        h = ((g - b) / d) % 6.0
    elif mx == g:
        h = (b - r) / d + 2.0
    else:
        h = (r - g) / d + 4.0
    return 60.0 * h


# ---------------------------------------------------------------------------------------------
# Camera metrics


def sobel_magnitude(x: np.ndarray) -> np.ndarray:
    return np.hypot(ndimage.sobel(x, axis=1, mode="nearest"), ndimage.sobel(x, axis=0, mode="nearest"))


def blocks(x: np.ndarray, size: int) -> np.ndarray:
    """Whole size x size blocks of a 2-D array as (n, size*size)."""
    h, w = (x.shape[0] // size) * size, (x.shape[1] // size) * size
    v = x[:h, :w].reshape(h // size, size, w // size, size).swapaxes(1, 2)
    return v.reshape(-1, size * size)


def alpha_trimmed(x: np.ndarray, alpha: float = 0.1) -> tuple[float, float]:
    s = np.sort(x.ravel())
    k = int(math.floor(alpha * s.size))
    t = s[k:s.size - k] if s.size - 2 * k > 0 else s
    mu = float(t.mean())
    return mu, float(np.mean((t - mu) ** 2))


def uicm(rgb8: np.ndarray) -> float:
    c = rgb8.astype(np.float64)
    rg = c[..., 0] - c[..., 1]
    yb = 0.5 * (c[..., 0] + c[..., 1]) - c[..., 2]
    mu_rg, var_rg = alpha_trimmed(rg)
    mu_yb, var_yb = alpha_trimmed(yb)
    return -0.0268 * math.hypot(mu_rg, mu_yb) + 0.1586 * math.sqrt(var_rg + var_yb)


def eme(x: np.ndarray, size: int = 8) -> float:
    b = blocks(x, size)
    mx, mn = b.max(axis=1), b.min(axis=1)
    ok = (mn > 0) & (mx > 0)
    if b.shape[0] == 0:
        return 0.0
    return float(2.0 / b.shape[0] * np.sum(np.log(mx[ok] / mn[ok])))


def uism(rgb8: np.ndarray) -> float:
    c = rgb8.astype(np.float64)
    total = 0.0
    for ch, lam in zip(range(3), (0.299, 0.587, 0.114)):
        edge = sobel_magnitude(c[..., ch]) / 8.0  # the Sobel kernels' gain: a unit step gives 4 (x2 for both sides)
        total += lam * eme(edge * c[..., ch] / 255.0)
    return total


def uiconm(rgb8: np.ndarray, size: int = 8) -> float:
    gray = rgb8.astype(np.float64).mean(axis=2)
    b = blocks(gray, size)
    mx, mn = b.max(axis=1), b.min(axis=1)
    top, bot = mx - mn, mx + mn
    ok = (top > 0) & (bot > 0)
    if b.shape[0] == 0:
        return 0.0
    r = top[ok] / bot[ok]
    return float(-1.0 / b.shape[0] * np.sum(r * np.log(r)))


def uciqe(lab: np.ndarray) -> float:
    L = lab[..., 0]
    chroma = np.hypot(lab[..., 1], lab[..., 2])
    sigma_c = float(np.std(chroma / 100.0))
    s = np.sort(L.ravel() / 100.0)
    k = max(1, int(round(0.01 * s.size)))
    con_l = float(s[-k:].mean() - s[:k].mean())
    mu_s = float(np.mean(np.where(L > 1e-6, chroma / np.maximum(L, 1e-6), 0.0)))
    return 0.4680 * sigma_c + 0.2745 * con_l + 0.2576 * mu_s


def delentropy(gray8: np.ndarray) -> float:
    g = gray8.astype(np.int32)
    fx = np.diff(g, axis=1)[:-1, :]
    fy = np.diff(g, axis=0)[:, :-1]
    idx = (fx + 255) * 511 + (fy + 255)
    counts = np.bincount(idx.ravel(), minlength=511 * 511)
    p = counts[counts > 0] / idx.size
    return float(-0.5 * np.sum(p * np.log2(p)))


def camera_metrics(rgb8: np.ndarray) -> dict:
    lab = rgb_to_lab(rgb8)
    Y = luminance(rgb8)
    chroma = np.hypot(lab[..., 1], lab[..., 2])
    w = chroma.sum()
    hue = math.degrees(math.atan2(float((lab[..., 2] * chroma).sum()), float((lab[..., 1] * chroma).sum()))) \
        if w > 0 else float("nan")
    gray8 = np.clip(np.rint(255.0 * (np.where(Y <= 0.0031308, 12.92 * Y, 1.055 * Y ** (1 / 2.4) - 0.055))), 0, 255)
    ui_cm, ui_sm, ui_conm = uicm(rgb8), uism(rgb8), uiconm(rgb8)
    return {
        "rms_contrast": float(Y.std()),
        "lab_L": float(lab[..., 0].mean()),
        "lab_a": float(lab[..., 1].mean()),
        "lab_b": float(lab[..., 2].mean()),
        "chroma": float(chroma.mean()),
        "hue_deg": hue % 360.0 if not math.isnan(hue) else hue,
        "hsv_hue_deg": hsv_hue_deg(rgb8.reshape(-1, 3).mean(axis=0)),
        "saturation": float(hsv_saturation(rgb8).mean()),
        "uciqe": uciqe(lab),
        "uicm": ui_cm,
        "uism": ui_sm,
        "uiconm": ui_conm,
        "uiqm": 0.0282 * ui_cm + 0.2953 * ui_sm + 3.5753 * ui_conm,
        "delentropy": delentropy(gray8),
        "edge_density": float(np.mean(sobel_magnitude(gray8 / 255.0) / 8.0 > 0.1)),
    }


def sequence_metrics(images: list[np.ndarray], per_frame: list[dict]) -> dict:
    out = {}
    for key in ("lab_L", "lab_a", "lab_b"):
        out["frame_std_" + key] = float(np.std([m[key] for m in per_frame]))
    hues = np.radians([m["hue_deg"] for m in per_frame if not math.isnan(m["hue_deg"])])
    if hues.size:
        r = math.hypot(np.cos(hues).mean(), np.sin(hues).mean())
        out["frame_std_hue_deg"] = math.degrees(math.sqrt(max(0.0, -2.0 * math.log(max(r, 1e-12)))))
    diffs = [np.abs(a.astype(np.float64) - b.astype(np.float64)).mean()
             for a, b in zip(images, images[1:]) if a.shape == b.shape]
    if diffs:
        out["frame_diff"] = float(np.mean(diffs))
    return out


# ---------------------------------------------------------------------------------------------
# Motion from ground truth


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    x, y, z, w = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def rotation_vector(R: np.ndarray) -> np.ndarray:
    c = max(-1.0, min(1.0, 0.5 * (np.trace(R) - 1.0)))
    angle = math.acos(c)
    v = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if angle < 1e-9:
        return 0.5 * v
    return angle / (2.0 * math.sin(angle)) * v if angle < math.pi - 1e-6 else angle * np.sqrt(
        np.maximum(np.diag(R) + 1.0, 0.0) / 2.0)


def read_tum(path: str) -> np.ndarray:
    rows = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            v = [float(x) for x in line.split()[:8]]
            if len(v) == 8:
                rows.append(v)
    return np.array(rows)


def motion_metrics(tum: np.ndarray) -> dict:
    """Body-frame twists between consecutive poses (TUM: t, position, quaternion x y z w)."""
    twists, speeds, rates = [], [], []
    for a, b in zip(tum, tum[1:]):
        dt = b[0] - a[0]
        if dt <= 0:
            continue
        Ra, Rb = quat_to_matrix(a[4:8]), quat_to_matrix(b[4:8])
        dp = Ra.T @ (b[1:4] - a[1:4])
        dphi = rotation_vector(Ra.T @ Rb)
        twists.append(np.concatenate([dp, dphi]) / dt)
        speeds.append(np.linalg.norm(dp) / dt)
        rates.append(math.degrees(np.linalg.norm(dphi)) / dt)
    if len(twists) < 3:
        return {}
    T = np.array(twists)
    norms = np.linalg.norm(T, axis=1)
    U = T[norms > 1e-9] / norms[norms > 1e-9, None]
    if U.shape[0] < 3:
        return {}
    # Second moment of the unit twists: its eigenvalues sum to 1; one kind of motion -> (1, 0, ...).
    ev = np.clip(np.linalg.eigvalsh(U.T @ U / U.shape[0]), 0.0, None)
    p = ev / ev.sum()
    p = p[p > 1e-12]
    return {"speed_mps": float(np.median(speeds)), "rotation_dps": float(np.median(rates)),
            "motion_diversity": float(math.exp(-np.sum(p * np.log(p))))}


# ---------------------------------------------------------------------------------------------
# Sonar metrics


def fan_mask(gray: np.ndarray, polar: bool) -> np.ndarray:
    if polar:
        return np.ones(gray.shape, bool)
    closed = ndimage.binary_closing(gray > 0, structure=np.ones((15, 15)), border_value=0)
    filled = ndimage.binary_fill_holes(closed)
    labels, n = ndimage.label(filled)
    if n == 0:
        return filled
    sizes = ndimage.sum(filled, labels, range(1, n + 1))
    return labels == (1 + int(np.argmax(sizes)))


def homogeneous_blocks(intensity: np.ndarray, mask: np.ndarray, size: int = 32) -> list[np.ndarray]:
    """Blocks inside the fan, bright enough to be seabed, whose quadrant means agree within 35 %
    (speckle alone moves a quadrant's mean by ~6 % uncorrelated, ~13 % with 2 x 2 px grain)."""
    h, w = intensity.shape
    cands = []
    for y in range(0, h - size + 1, size):
        for x in range(0, w - size + 1, size):
            if not mask[y:y + size, x:x + size].all():
                continue
            b = intensity[y:y + size, x:x + size]
            cands.append(b)
    if not cands:
        return []
    means = np.array([b.mean() for b in cands])
    lo, hi = np.percentile(means, 40), np.percentile(means, 95)
    out = []
    q = size // 2
    for b, m in zip(cands, means):
        if not (lo <= m <= hi) or m <= 0:
            continue
        quads = [b[:q, :q].mean(), b[:q, q:].mean(), b[q:, :q].mean(), b[q:, q:].mean()]
        if max(quads) - min(quads) <= 0.35 * m:
            out.append(b)
    return out


def correlation_length(blocks_: list[np.ndarray], axis: int, max_lag: int = 8) -> float:
    """Lag (px) where the mean normalised autocorrelation along `axis` first falls to 1/e."""
    if not blocks_:
        return float("nan")
    acf = np.zeros(max_lag + 1)
    used = 0
    for b in blocks_:
        d = b - b.mean()
        var = np.mean(d * d)
        if var <= 0:  # a flat (e.g. saturated) block has no autocorrelation to average
            continue
        used += 1
        for lag in range(max_lag + 1):
            if axis == 1:
                acf[lag] += np.mean(d[:, :d.shape[1] - lag] * d[:, lag:]) / var
            else:
                acf[lag] += np.mean(d[:d.shape[0] - lag, :] * d[lag:, :]) / var
    if used == 0:
        return float("nan")
    acf /= used
    target = math.exp(-1.0)
    for lag in range(1, max_lag + 1):
        if acf[lag] <= target:
            return (lag - 1) + (acf[lag - 1] - target) / max(acf[lag - 1] - acf[lag], 1e-12)
    return float(max_lag)


def k_log_pdf_intensity(i: np.ndarray, nu: float) -> np.ndarray:
    """log pdf of a unit-mean K-distributed intensity with shape nu."""
    z = 2.0 * np.sqrt(nu * i)
    kv = special.kve(nu - 1.0, z)
    return (math.log(2.0) + ((nu + 1.0) / 2.0) * math.log(nu) - special.gammaln(nu) +
            ((nu - 1.0) / 2.0) * np.log(i) + np.log(np.maximum(kv, 1e-300)) - z)


def distribution_fits(blocks_: list[np.ndarray]) -> dict:
    if not blocks_:
        return {}
    intensity = np.concatenate([(b / b.mean()).ravel() for b in blocks_ if b.mean() > 0])
    intensity = intensity[intensity > 0]
    if intensity.size < 100:
        return {}
    # A Rayleigh amplitude is an exponential intensity (fully developed speckle): one model, its
    # log-likelihood per sample on the unit-mean intensity; the K distribution (gamma-textured
    # speckle, shape nu from E[I^2] = 2 (1 + 1/nu); nu -> inf is the exponential) on the same.
    ll_exp = float(np.mean(-intensity))
    m2 = float(np.mean(intensity ** 2))
    nu = 1.0 / (m2 / 2.0 - 1.0) if m2 > 2.0 + 1e-6 else 1e3
    nu = float(min(max(nu, 0.05), 1e3))
    # Beyond nu = 50 the K is the exponential within ~2 % of its contrast (and its Bessel function
    # of large order overflows): the same model.
    ll_k = float(np.mean(k_log_pdf_intensity(intensity, nu))) if nu <= 50.0 else ll_exp
    if not math.isfinite(ll_k):
        ll_k = ll_exp
    fits = {"fit_rayleigh": ll_exp, "fit_k": ll_k, "k_shape_nu": nu}
    # K only when it explains the samples clearly better (it has one parameter more).
    fits["best_fit"] = "k" if ll_k > ll_exp + 0.01 else "rayleigh"
    return fits


def lbp_uniform(gray: np.ndarray) -> np.ndarray:
    """Rotation-invariant uniform LBP(8, 1) codes 0..9 (9: non-uniform) of the interior pixels."""
    g = gray.astype(np.int32)
    c = g[1:-1, 1:-1]
    offs = [(-1, -1), (-1, 0), (-1, 1), (0, 1), (1, 1), (1, 0), (1, -1), (0, -1)]
    bits = np.stack([(g[1 + dy:g.shape[0] - 1 + dy, 1 + dx:g.shape[1] - 1 + dx] >= c) for dy, dx in offs])
    transitions = np.sum(bits != np.roll(bits, 1, axis=0), axis=0)
    ones = bits.sum(axis=0)
    return np.where(transitions <= 2, ones, 9)


def sonar_metrics(gray8: np.ndarray, gamma: float, polar: bool) -> tuple[dict, np.ndarray, np.ndarray]:
    mask = fan_mask(gray8, polar)
    v = gray8[mask].astype(np.float64)
    p = np.percentile(v, [5, 25, 50, 95, 99]) if v.size else np.zeros(5)
    intensity = (gray8.astype(np.float64) / 255.0) ** (2.0 / gamma)
    blk = homogeneous_blocks(intensity, mask)
    contrast = [b.std() / b.mean() for b in blk if b.mean() > 0]
    m = {
        "p05": float(p[0]), "p25": float(p[1]), "p50": float(p[2]), "p95": float(p[3]), "p99": float(p[4]),
        "bright_ratio": float(p[3] / p[1]) if p[1] > 0 else float("inf"),
        "zero_fraction": float(np.mean(v == 0)) if v.size else 0.0,
        "saturated_fraction": float(np.mean(v == 255)) if v.size else 0.0,
        "homogeneous_blocks": float(len(blk)),
        "speckle_contrast": float(np.median(contrast)) if contrast else float("nan"),
        "corr_x_px": correlation_length(blk, axis=1),
        "corr_y_px": correlation_length(blk, axis=0),
    }
    m.update(distribution_fits(blk))
    hist = np.bincount(gray8[mask].ravel(), minlength=256).astype(np.float64)
    lbp = lbp_uniform(gray8)[mask[1:-1, 1:-1]]
    lbp_hist = np.bincount(lbp.ravel(), minlength=10).astype(np.float64)
    return m, hist, lbp_hist


# ---------------------------------------------------------------------------------------------
# Histogram distances


def normalised(h: np.ndarray, eps: float = 1e-9) -> np.ndarray:
    h = h.astype(np.float64) + eps
    return h / h.sum()


def kl(p: np.ndarray, q: np.ndarray) -> float:
    p, q = normalised(p), normalised(q)
    return float(np.sum(p * np.log(p / q)))


def js(p: np.ndarray, q: np.ndarray) -> float:
    p, q = normalised(p), normalised(q)
    m = 0.5 * (p + q)
    return float(0.5 * np.sum(p * np.log(p / m)) + 0.5 * np.sum(q * np.log(q / m)))


def emd_1d(p: np.ndarray, q: np.ndarray) -> float:
    """Earth mover's distance between two histograms over the same unit-spaced bins."""
    p, q = normalised(p, 0.0), normalised(q, 0.0)
    return float(np.sum(np.abs(np.cumsum(p) - np.cumsum(q))))


# ---------------------------------------------------------------------------------------------
# Folders and the report


def list_images(path: str) -> list[Path]:
    p = Path(path)
    if p.is_file():
        return [p]
    if not p.is_dir():
        raise SystemExit(f"realism_report: {path}: no such file or folder")
    files = sorted(f for f in p.iterdir() if f.suffix.lower() in IMAGE_SUFFIXES)
    if not files:
        raise SystemExit(f"realism_report: {path}: no images ({', '.join(sorted(IMAGE_SUFFIXES))})")
    return files


def load_rgb(path: Path, width: int) -> np.ndarray:
    img = Image.open(path).convert("RGB")
    if img.size[0] != width:
        img = img.resize((width, max(1, round(img.size[1] * width / img.size[0]))), Image.BICUBIC)
    return np.asarray(img)


def load_gray(path: Path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("L"))


def summary(values: list[float]) -> dict:
    v = np.array([x for x in values if x is not None and not math.isnan(x) and not math.isinf(x)])
    if v.size == 0:
        return {"median": float("nan"), "p10": float("nan"), "p90": float("nan"), "n": 0}
    return {"median": float(np.median(v)), "p10": float(np.percentile(v, 10)),
            "p90": float(np.percentile(v, 90)), "n": int(v.size)}


def circular_summary(values_deg: list[float]) -> dict:
    """Hue angles: the circular mean as the median, the 10-90 % range of the deviations from it."""
    v = np.radians([x for x in values_deg if not math.isnan(x)])
    if v.size == 0:
        return summary([])
    mean = math.atan2(np.sin(v).mean(), np.cos(v).mean())
    dev = (v - mean + math.pi) % (2 * math.pi) - math.pi
    lo, hi = np.percentile(dev, 10), np.percentile(dev, 90)
    return {"median": math.degrees(mean) % 360.0, "p10": math.degrees(mean + lo) % 360.0,
            "p90": math.degrees(mean + hi) % 360.0, "n": int(v.size)}


def within(ours: dict, real: dict, circular: bool) -> str:
    m, lo, hi = ours["median"], real["p10"], real["p90"]
    if any(math.isnan(x) for x in (m, lo, hi)):
        return "-"
    if circular:
        span = (hi - lo) % 360.0
        return "yes" if (m - lo) % 360.0 <= span else "no"
    return "yes" if lo <= m <= hi else "no"


def fmt(x: float) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    a = abs(x)
    return f"{x:.3g}" if a < 1000 else f"{x:.0f}"


def folder_camera(path: str, width: int, gt: str | None) -> tuple[dict, int]:
    files = list_images(path)
    images = [load_rgb(f, width) for f in files]
    per = [camera_metrics(im) for im in images]
    out = {}
    for key in per[0]:
        out[key] = circular_summary([m[key] for m in per]) if key.endswith("hue_deg") else summary(
            [m[key] for m in per])
    for key, value in sequence_metrics(images, per).items():
        out[key] = {"median": value, "p10": value, "p90": value, "n": 1}
    if gt:
        for key, value in motion_metrics(read_tum(gt)).items():
            out[key] = {"median": value, "p10": value, "p90": value, "n": 1}
    return out, len(files)


def folder_sonar(path: str, gamma: float, polar: bool) -> tuple[dict, np.ndarray, np.ndarray, int]:
    files = list_images(path)
    per, hist, lbp = [], np.zeros(256), np.zeros(10)
    for f in files:
        m, h, l = sonar_metrics(load_gray(f), gamma, polar)
        per.append(m)
        hist += h
        lbp += l
    out = {}
    for key in per[0]:
        if key == "best_fit":
            names = [m.get(key) for m in per if key in m]
            out[key] = max(set(names), key=names.count) if names else "-"
        else:
            out[key] = summary([m.get(key, float("nan")) for m in per])
    return out, hist, lbp, len(files)


def table(kind: str, ours: dict, real: dict, names: tuple[str, str], n: tuple[int, int]) -> list[str]:
    lines = [f"| {kind} metric | {names[0]} ({n[0]}) median [p10, p90] | {names[1]} ({n[1]}) median [p10, p90] "
             "| ours / real | ours in real range |", "|---|---|---|---|---|"]
    for key in ours:
        if key not in real:
            continue
        o, r = ours[key], real[key]
        if isinstance(o, str):
            lines.append(f"| {key} | {o} | {r} | - | {'yes' if o == r else 'no'} |")
            continue
        circular = key.endswith("hue_deg")
        ratio = "-" if circular or not r["median"] else fmt(o["median"] / r["median"])
        # A whole-sequence figure (one value a side) has no range to be in: the ratio says it.
        inside = within(o, r, circular) if r["n"] > 1 else "-"
        if r["n"] > 1:
            lines.append(f"| {key} | {fmt(o['median'])} [{fmt(o['p10'])}, {fmt(o['p90'])}] | {fmt(r['median'])} "
                         f"[{fmt(r['p10'])}, {fmt(r['p90'])}] | {ratio} | {inside} |")
        else:
            lines.append(f"| {key} | {fmt(o['median'])} | {fmt(r['median'])} | {ratio} | - |")
    return lines


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("kind", choices=["camera", "sonar"])
    ap.add_argument("ours")
    ap.add_argument("real")
    ap.add_argument("--name-ours", default="ours")
    ap.add_argument("--name-real", default="real")
    ap.add_argument("--gt-ours", help="TUM ground truth of our sequence (motion metrics)")
    ap.add_argument("--gt-real", help="TUM ground truth of the real sequence")
    ap.add_argument("--width", type=int, default=320, help="camera images are scaled to this width first")
    ap.add_argument("--gamma-ours", type=float, default=1.0, help="our sonar coding: value ~ amplitude^gamma")
    ap.add_argument("--gamma-real", type=float, default=1.0, help="the real sonar's coding exponent")
    ap.add_argument("--polar", action="store_true", help="sonar images are polar (every pixel is data)")
    ap.add_argument("--out", default="out/realism")
    a = ap.parse_args(argv)
    for g in (a.gamma_ours, a.gamma_real):
        if not (g > 0 and math.isfinite(g)):
            raise SystemExit(f"realism_report: --gamma-* must be finite and > 0 (got {g})")
    names = (a.name_ours, a.name_real)
    report = {"kind": a.kind, "ours": os.path.abspath(a.ours), "real": os.path.abspath(a.real)}
    if a.kind == "camera":
        if a.width < 16:
            raise SystemExit(f"realism_report: --width must be >= 16 (got {a.width})")
        ours, n_o = folder_camera(a.ours, a.width, a.gt_ours)
        real, n_r = folder_camera(a.real, a.width, a.gt_real)
        lines = table("camera", ours, real, names, (n_o, n_r))
    else:
        ours, h_o, l_o, n_o = folder_sonar(a.ours, a.gamma_ours, a.polar)
        real, h_r, l_r, n_r = folder_sonar(a.real, a.gamma_real, a.polar)
        dist = {"intensity_kl": kl(h_o, h_r), "intensity_js": js(h_o, h_r), "intensity_emd": emd_1d(h_o, h_r),
                "lbp_js": js(l_o, l_r)}
        report["distances"] = dist
        lines = table("sonar", ours, real, names, (n_o, n_r))
        lines += ["", "| histogram distance (ours vs real) | value |", "|---|---|"]
        lines += [f"| {k} | {v:.4g} |" for k, v in dist.items()]
    report.update({"ours_metrics": ours, "real_metrics": real})
    head = [f"# Realism report ({a.kind})", "", f"- {names[0]}: `{a.ours}` ({n_o} images)",
            f"- {names[1]}: `{a.real}` ({n_r} images)", ""]
    text = "\n".join(head + lines) + "\n"
    os.makedirs(a.out, exist_ok=True)
    Path(a.out, "report.md").write_text(text)
    Path(a.out, "report.json").write_text(json.dumps(report, indent=2, default=float) + "\n")
    print(text, end="")
    print(f"written: {a.out}/report.md, {a.out}/report.json")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
