"""The fibre's rheological series (``/frames/stresslet``, written with ``&output stresslet``):
running and late-time averages of the intrinsic-viscosity-form shear viscosity and the normal
stress difference coefficients psi1, psi2 (normalisation in the README: far-apart free beads
give a viscosity of 5/2)."""

from __future__ import annotations

import numpy as np

SERIES = ("viscosity", "psi1", "psi2")


def running_mean(values) -> np.ndarray:
    """Cumulative mean of a per-frame series: element k is the mean of frames 0..k."""
    v = np.asarray(values, dtype=float)
    return np.cumsum(v) / np.arange(1, len(v) + 1)


def late_time_mean(time, values, t_from):
    """(mean, standard deviation, number of frames) of the frames at t >= t_from; (nan, nan,
    0) when there are none."""
    t = np.asarray(time, dtype=float)
    v = np.asarray(values, dtype=float)[t >= t_from]
    if len(v) == 0:
        return float("nan"), float("nan"), 0
    return float(v.mean()), float(v.std()), int(len(v))


def rheology_summary(case, t_from) -> dict | None:
    """Late-time statistics {name: (mean, std, frames)} of the case's viscosity, psi1, psi2
    from t_from on; None for a file without the stresslet."""
    if not case.stresslet:
        return None
    return {k: late_time_mean(case.time, case.stresslet[k], t_from)
            for k in SERIES if k in case.stresslet}
