"""Whole-case analysis: stored versus computed results, modes, spectra."""

import analysis_fixture as fixture
import h5py
import numpy as np
import pytest

from knotflow_tools import io
from knotflow_tools.analysis import analyze_case
from knotflow_tools.knots import KNOT_TYPES

from conftest import unknotting_trefoil_frames, write_case


def tumbling_rod_frames(n=30, period=50.0, nframes=101, tmax=200.0):
    """A straight rod rotating in the xz-plane (flow-gradient plane) with the given period."""
    t = np.linspace(0.0, tmax, nframes)
    s = 1.02 * (np.arange(n) - (n - 1) / 2)
    frames = []
    for tt in t:
        ang = 2 * np.pi * tt / period
        d = np.array([np.sin(ang), 0.0, np.cos(ang)])
        frames.append(s[:, None] * d[None, :])
    return t, np.array(frames)


def test_spectra_of_tumbling_rod(tmp_path):
    t, frames = tumbling_rod_frames()
    case = io.read_case(write_case(tmp_path / "rod.h5", frames, time=t))
    ana = analyze_case(case, closures=5, stride=25)
    # the end-to-end vector turns once per period; phi (unwrapped) grows linearly
    assert ana.spectra["dominant_period_end_to_end"] == pytest.approx(50.0, rel=0.02)
    assert np.allclose(ana.observables["theta"], np.pi / 2, atol=1e-9)
    assert np.all(ana.kf == 0.0) and ana.events == []
    # modes come only from /analysis/shape (knotflow-analyze; its rule is tested in test_modes.pf)
    assert ana.modes.size == 0 and ana.case_mode is None


def test_stored_analysis_is_used(tmp_path):
    frames = unknotting_trefoil_frames(5)
    path = str(write_case(tmp_path / "c.h5", frames))
    kf = np.array([1.0, 0.95, 0.5, 0.05, 0.0])
    spec = np.zeros((5, len(KNOT_TYPES)))
    spec[:, 0] = 1 - kf
    spec[:, 1] = kf
    fixture.write_knots(path, np.arange(5), np.arange(5.0), kf, spec, ["3_1"] * 3 + ["0_1"] * 2,
                   1000, 3)
    ana = analyze_case(io.read_case(path))
    assert ana.kf_source == "stored" and np.array_equal(ana.kf, kf)
    assert [(e.kind, e.index) for e in ana.events] == [("unknot", 3)]
    assert ana.final_state == "unknotted"
    ana2 = analyze_case(io.read_case(path), closures=20, use_stored=False)
    assert ana2.kf_source == "computed" and ana2.kf[-1] == 0.0


def test_fortran_style_fixed_length_strings(tmp_path):
    frames = unknotting_trefoil_frames(3)
    path = str(write_case(tmp_path / "c.h5", frames))
    with h5py.File(path, "a") as f:
        f.attrs["chain.orientation"] = np.array([b"b   "], dtype="S4")
        f.attrs["status"] = np.bytes_(b"finished  ")
    case = io.read_case(path)
    assert case.orientation == "b" and case.status == "finished"
