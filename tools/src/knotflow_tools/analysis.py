"""Whole-case analysis: k_f(t), events, shape observables, modes and spectra.

The modes are those knotflow-analyze stored in /analysis/shape (the one mode rule, kf_modes,
docs/analysis.md); without them a case has no modes here.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

import knotflow

from . import knots, shape, transitions
from .io import Case

AUTO_MAX_FRAMES = 100   #: stride <= 0: analyse at most about this many frames


@dataclass
class CaseAnalysis:
    """Results of analysing one case (computed or taken from /analysis)."""

    frame_index: np.ndarray
    time: np.ndarray
    kf: np.ndarray
    dominant: list
    events: list
    low: float
    high: float
    observables: dict
    modes: np.ndarray            #: per frame (empty without /analysis/shape)
    case_mode: int | None        #: None without /analysis/shape
    spectra: dict
    knot_matrices: dict = field(default_factory=dict)
    kf_source: str = "computed"

    @property
    def final_kf(self) -> float:
        return float(self.kf[-1]) if len(self.kf) else float("nan")

    @property
    def final_state(self):
        return transitions.final_state(self.kf, self.low, self.high)

    @property
    def has_transitions(self) -> bool:
        return len(self.events) > 0


def kf_at(kf, t):
    """(k_f, its time) of the latest analysed frame at or before time t, or None."""
    if kf is None or not len(kf[0]):
        return None
    k = int(np.searchsorted(kf[0], t, side="right")) - 1
    return (float(kf[1][k]), float(kf[0][k])) if k >= 0 else None


def kf_label(kf, t, sub="<sub>f</sub>") -> str:
    """'k_f = 0.830', with '(at t = ...)' when it comes from an earlier analysed frame."""
    found = kf_at(kf, t)
    if found is None:
        return f"k{sub}: not analysed"
    value, tk = found
    at = "" if abs(tk - t) <= 1e-9 * max(1.0, abs(t)) else f" (at t = {tk:.4g})"
    return f"k{sub} = {value:.3f}{at}"


def knot_series(positions, frames, closures=200, seed=None):
    """k_f, spectrum rows and dominant types for the given frame indices: the library's knot
    analysis (knotflow.knots), frame k with the closure stream k as knotflow-analyze draws it,
    so that the results equal knotflow-analyze's for the same closures and seed (None: the
    library's default seed, knotflow-analyze's)."""
    kf, spec, dom = [], [], []
    for fi in frames:
        res = knotflow.knots(positions[fi], closures=closures, seed=seed, stream=int(fi))
        kf.append(res.kf)
        spec.append([res.spectrum[t] for t in knots.KNOT_TYPES])
        dom.append(res.dominant)
    return np.array(kf), np.array(spec).reshape(len(frames), len(knots.KNOT_TYPES)), dom


def observables_of(case: Case) -> dict:
    """Observables from /frames/observables, computed from positions where missing."""
    needed = ("rg", "a", "b", "c", "theta", "phi", "close_pairs")
    if all(k in case.observables and len(case.observables[k]) == case.nframes for k in needed):
        return {k: np.asarray(case.observables[k]) for k in needed}
    return shape.shape_series(case.positions)


def analyze_case(case: Case, closures: int = 200, stride: int = 0, seed: int | None = None,
                 matrix_frames=(), matrix_closures: int = 50, matrix_stride: int = 4,
                 min_length: int = 10, use_stored: bool = True) -> CaseAnalysis:
    """Analyse a case; stored /analysis results are used when present (unless use_stored).

    The modes always come from /analysis/shape (knotflow-analyze), also without use_stored.
    """
    low, high = transitions.LOW, transitions.HIGH
    if use_stored and case.knots is not None:
        frames = case.knots["frame_index"]
        kf = case.knots["kf"]
        tk = case.knots["time"]
        dom = case.knots["dominant"] or [""] * len(kf)
        source = "stored"
    else:
        if stride <= 0:
            stride = max(1, -(-case.nframes // AUTO_MAX_FRAMES))
        frames = np.arange(0, case.nframes, stride, dtype=np.int64)
        if case.nframes and frames[-1] != case.nframes - 1:
            frames = np.append(frames, case.nframes - 1)
        kf, _, dom = knot_series(case.positions, frames, closures, seed)
        tk = case.time[frames]
        source = "computed"
    if use_stored and case.events is not None:
        ea = case.events["attrs"]
        low = float(ea.get("low", low))
        high = float(ea.get("high", high))
        times = case.events["time"] if case.events["time"] is not None else []
        idx = case.events["frame_index"] if case.events["frame_index"] is not None else []
        events = [transitions.Event(k, int(i), float(t))
                  for k, i, t in zip(case.events["kind"], idx, times)]
    else:
        events = transitions.detect_events(kf, tk, low, high)
        # index into the frame list -> frame index
        events = [transitions.Event(e.kind, int(frames[e.index]), e.time) for e in events]
    obs = observables_of(case)
    if case.modes is not None and len(case.modes) == case.nframes:
        modes, cmode = np.asarray(case.modes), case.case_mode
    else:
        modes, cmode = np.zeros(0, dtype=np.int32), None
    spec = shape.spectra(case.time, case.positions, obs)
    mats = dict(case.knot_matrices) if use_stored else {}
    for fi in matrix_frames:
        fi = int(fi) % case.nframes
        if fi not in mats:
            mats[fi] = knotflow.knot_matrix(case.positions[fi], closures=matrix_closures,
                                            seed=seed, min_length=min_length,
                                            stride=matrix_stride).matrix
    return CaseAnalysis(frame_index=np.asarray(frames), time=np.asarray(tk), kf=np.asarray(kf),
                        dominant=list(dom), events=events, low=low, high=high,
                        observables=obs, modes=modes, case_mode=cmode, spectra=spec,
                        knot_matrices=mats, kf_source=source)
