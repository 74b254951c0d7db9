"""Transition detection with hysteresis on synthetic k_f series."""

import numpy as np
import pytest

from knotflow_tools.transitions import Event, detect_events, final_state, states, unknot_then_knot


def kinds(events):
    return [(e.kind, e.index) for e in events]


def test_single_unknotting():
    kf = [1.0, 0.98, 0.95, 0.6, 0.3, 0.05, 0.0]
    assert kinds(detect_events(kf)) == [("unknot", 5)]
    assert final_state(kf) == "unknotted"


def test_hysteresis_ignores_excursions_inside_band():
    kf = [0.95, 0.5, 0.2, 0.85, 0.11, 0.89, 0.95]
    assert detect_events(kf) == []
    assert states(kf) == ["knotted"] * 7


def test_unknot_then_knot_again_with_times():
    kf = [0.99, 0.5, 0.02, 0.05, 0.4, 0.93, 0.97, 0.08]
    t = np.linspace(0.0, 7.0, 8) * 10
    ev = detect_events(kf, t)
    assert kinds(ev) == [("unknot", 2), ("knot", 5), ("unknot", 7)]
    assert [e.time for e in ev] == [20.0, 50.0, 70.0]
    assert unknot_then_knot(ev)
    assert not unknot_then_knot([Event("knot", 1, 1.0), Event("unknot", 2, 2.0)])


def test_initial_state_from_first_frame_outside_band():
    kf = [0.5, 0.6, 0.05, 0.3, 0.95]
    st = states(kf)
    assert st[:2] == [None, None] and st[2] == "unknotted"
    assert kinds(detect_events(kf)) == [("knot", 4)]
    assert final_state([0.5, 0.5]) is None


def test_thresholds_are_strict_and_configurable():
    # exactly 0.9 / 0.1 are inside the band
    assert detect_events([1.0, 0.1, 0.9, 0.1]) == []
    assert kinds(detect_events([1.0, 0.3], low=0.4, high=0.8)) == [("unknot", 1)]
    with pytest.raises(ValueError):
        detect_events([0.5], low=0.9, high=0.1)


def test_noisy_series_events_match_construction():
    rng = np.random.default_rng(0)
    truth = np.r_[np.ones(50), np.zeros(50), np.ones(50)]
    kf = np.clip(truth + rng.normal(0, 0.04, truth.size), 0, 1)
    ev = detect_events(kf)
    assert [e.kind for e in ev] == ["unknot", "knot"]
    assert abs(ev[0].index - 50) <= 1 and abs(ev[1].index - 100) <= 1
