"""Shape observables and spectra (PHYSICS.md section 6).

The observables of a configuration are the library's (knotflow.shape, the code knotflow records
every frame with); `compute_shape` is an independent numpy implementation kept as the oracle of
the tests (tools/tests/test_shape.py, tools/tests_knotflow/test_functions.py).

The modes I and II are classified by the Fortran tool only (kf_modes, the rule in
docs/analysis.md) and read from /analysis/shape; this module computes no mode.
"""

from __future__ import annotations

import math

import numpy as np

import knotflow

CLOSE_PAIR_DISTANCE = 1.05


# The record of the observables is the library's (one definition, knotflow.Shape).
Shape = knotflow.Shape


def gyration_tensor(r: np.ndarray) -> np.ndarray:
    """T_nm = (1/2N^2) sum_ij (r_i - r_j)_n (r_i - r_j)_m = centred second moment."""
    d = np.asarray(r, dtype=float) - np.mean(r, axis=0)
    return d.T @ d / len(d)


def count_close_pairs(r: np.ndarray, cutoff: float = CLOSE_PAIR_DISTANCE) -> int:
    """Pairs i < j with j - i > 1 and |r_i - r_j| < cutoff."""
    r = np.asarray(r, dtype=float)
    n = len(r)
    if n < 3:
        return 0
    diff = r[:, None, :] - r[None, :, :]
    d2 = (diff * diff).sum(axis=2)
    ii, jj = np.triu_indices(n, k=2)
    return int(np.count_nonzero(d2[ii, jj] < cutoff * cutoff))


def compute_shape(r: np.ndarray) -> Shape:
    """R_g, semi-axes, orientation (theta, phi) of the principal axis and close pairs (numpy;
    the tests' oracle of the library's knotflow.shape).

    The principal axis e1 is signed so that the end-to-end vector projects non-negatively;
    theta = acos(e1_y) in [0, pi], phi = atan2(e1_x, e1_z).
    """
    r = np.asarray(r, dtype=float)
    lam, vec = np.linalg.eigh(gyration_tensor(r))
    lam = np.clip(lam, 0.0, None)
    e1 = vec[:, 2]
    if np.dot(e1, r[-1] - r[0]) < 0.0:
        e1 = -e1
    return Shape(rg=float(np.sqrt(lam.sum())), a=float(np.sqrt(3 * lam[2])),
                 b=float(np.sqrt(3 * lam[1])), c=float(np.sqrt(3 * lam[0])),
                 theta=float(np.arccos(np.clip(e1[1], -1.0, 1.0))),
                 phi=float(np.arctan2(e1[0], e1[2])), close_pairs=count_close_pairs(r))


def shape_series(positions: np.ndarray) -> dict:
    """Observables for every frame of positions (nframes, N, 3) as arrays: the library's
    (knotflow.shape), as knotflow records them; a frame it refuses (fewer than 2 beads, a
    non-finite coordinate) raises knotflow.KnotflowError, a ValueError."""
    shapes = [knotflow.shape(p) for p in positions]
    out = {k: np.array([getattr(s, k) for s in shapes]) for k in
           ("rg", "a", "b", "c", "theta", "phi")}
    out["close_pairs"] = np.array([s.close_pairs for s in shapes], dtype=np.int32)
    return out


def dominant_period(time: np.ndarray, signal: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """(frequency, power, dominant period) of a signal sampled at (nearly) uniform times.

    The mean is removed; the signal is resampled onto a uniform grid if needed.  The period is
    1 / f of the largest non-zero-frequency peak (inf if the series is too short or constant).
    """
    t = np.asarray(time, dtype=float)
    y = np.asarray(signal, dtype=float)
    if y.ndim == 1:
        y = y[:, None]
    n = len(t)
    if n < 4:
        return np.zeros(0), np.zeros(0), float("inf")
    tu = np.linspace(t[0], t[-1], n)
    if not np.allclose(np.diff(t), np.diff(tu), rtol=1e-6, atol=1e-12):
        y = np.stack([np.interp(tu, t, y[:, k]) for k in range(y.shape[1])], axis=1)
    dt = tu[1] - tu[0]
    y = y - y.mean(axis=0)
    power = (np.abs(np.fft.rfft(y, axis=0)) ** 2).sum(axis=1)
    freq = np.fft.rfftfreq(n, d=dt)
    if len(power) < 2 or power[1:].max() <= 0.0:
        return freq, power, float("inf")
    k = 1 + int(np.argmax(power[1:]))
    return freq, power, float(1.0 / freq[k])


def spectra(time: np.ndarray, positions: np.ndarray, obs: dict) -> dict:
    """Power spectra of R_g(t), unwrapped phi(t) and the end-to-end vector; dominant periods."""
    f, p_rg, per_rg = dominant_period(time, obs["rg"])
    _, p_phi, per_phi = dominant_period(time, np.unwrap(obs["phi"]))
    ree = positions[:, -1, :] - positions[:, 0, :]
    _, p_ee, per_ee = dominant_period(time, ree)
    return {"frequency": f, "power_rg": p_rg, "power_phi": p_phi, "power_end_to_end": p_ee,
            "dominant_period_rg": per_rg, "dominant_period_phi": per_phi,
            "dominant_period_end_to_end": per_ee}


#: The columns of `window_means`, in table order.
WINDOW_COLUMNS = ("frames", "rg", "a", "b", "c", "a_over_b", "b_over_c_min", "abs_cos_theta",
                  "close_pairs", "kf_mean", "kf_max", "mode_1", "mode_2")


def frame_ratios(time, obs: dict, offset: float = 0.0, t_from: float | None = None,
                 t_to: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(a/b, b/c) of the frames whose time offset + time lies in [t_from, t_to] (default: all):
    where a frame lies between the study's mode I (a >> b >~ c) and mode II (a >> b >> c).
    b/c is inf where c = 0. Raises ValueError on non-finite times."""
    t = offset + np.asarray(time, dtype=float)
    if not np.all(np.isfinite(t)):
        raise ValueError("non-finite frame times")
    m = np.ones(len(t), dtype=bool)
    if t_from is not None:
        m &= t >= t_from
    if t_to is not None:
        m &= t <= t_to
    a, b, c = (np.asarray(obs[k], dtype=float)[m] for k in ("a", "b", "c"))
    with np.errstate(divide="ignore"):
        return a / b, b / c


def window_means(time, obs: dict, width: float, kf=None, modes=None, offset: float = 0.0,
                 t_from: float | None = None, t_to: float | None = None) -> list:
    """Means of the shape observables over consecutive windows of the case time offset + time.

    Windows are [t0, t0 + width) with t0 = t_from + k width (t_from default: the first time
    rounded down to a multiple of width) below t_to (default: the last time); the last one
    also holds the frames at its end up to t_to (so 0..2000 in windows of 100 is 20 windows,
    t = 2000 in the last). A window without frames is left out. Per window (WINDOW_COLUMNS):
    the number of frames, the means of R_g, a, b, c, a/b and |cos theta| and of the close
    pairs, the smallest b/c of a frame (how round the roundest frame's cross-section is: mode
    I asks b >~ c; inf where c = 0), the mean and maximum of k_f over the frames that have one
    (NaN if none: kf None or all NaN), and the frames of mode I and mode II (NaN when modes is
    None). Raises ValueError on a width that is not positive and finite or on non-finite times.
    """
    if not (math.isfinite(width) and width > 0.0):
        raise ValueError(f"window width {width}: must be positive and finite")
    t = offset + np.asarray(time, dtype=float)
    if len(t) == 0:
        return []
    if not np.all(np.isfinite(t)):
        raise ValueError("non-finite frame times")
    start = math.floor(t[0] / width) * width if t_from is None else float(t_from)
    stop = t[-1] if t_to is None else float(t_to)
    kfa = None if kf is None else np.asarray(kf, dtype=float)
    md = None if modes is None else np.asarray(modes)
    o = {key: np.asarray(obs[key], dtype=float) for key in ("rg", "a", "b", "c", "close_pairs")}
    a_over_b = o["a"] / o["b"]
    with np.errstate(divide="ignore"):
        b_over_c = o["b"] / o["c"]
    abs_cos = np.abs(np.cos(np.asarray(obs["theta"], dtype=float)))
    out = []
    k = 0
    while start + k * width < stop or k == 0:
        t0 = start + k * width
        k += 1
        last = t0 + width >= stop
        m = (t >= t0) & ((t < t0 + width) | last) & (t <= stop)
        if not m.any():
            continue
        row = {"t0": t0, "t1": t0 + width, "frames": int(m.sum())}
        for key, values in o.items():
            row[key] = float(np.mean(values[m]))
        row["a_over_b"] = float(np.mean(a_over_b[m]))
        row["b_over_c_min"] = float(np.min(b_over_c[m]))
        row["abs_cos_theta"] = float(np.mean(abs_cos[m]))
        kw = np.array([]) if kfa is None else kfa[m][np.isfinite(kfa[m])]
        row["kf_mean"] = float(kw.mean()) if kw.size else math.nan
        row["kf_max"] = float(kw.max()) if kw.size else math.nan
        for mode in (1, 2):
            row[f"mode_{mode}"] = (math.nan if md is None
                                   else int(np.count_nonzero(md[m] == mode)))
        out.append(row)
    return out
