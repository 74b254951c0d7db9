"""Shape observables on configurations with exact values; modes; spectra."""

import numpy as np
import pytest

from knotflow_tools import shape as S


def rod(n, direction, spacing=1.02):
    d = np.asarray(direction, dtype=float)
    d /= np.linalg.norm(d)
    return np.arange(n)[:, None] * spacing * d[None, :]


def test_straight_chain_exact_values():
    n, l0 = 11, 1.02
    s = S.compute_shape(rod(n, [1, 0, 0], l0))
    # R_g^2 of N equally spaced points: l0^2 (N^2 - 1) / 12
    assert s.rg == pytest.approx(l0 * np.sqrt((n * n - 1) / 12.0), rel=1e-12)
    assert s.a == pytest.approx(np.sqrt(3.0) * s.rg, rel=1e-12)
    assert s.b == pytest.approx(0.0, abs=1e-7) and s.c == pytest.approx(0.0, abs=1e-7)
    assert s.close_pairs == 0


@pytest.mark.parametrize("direction,theta,phi", [
    ([0, 1, 0], 0.0, None), ([0, -1, 0], np.pi, None), ([0, 0, 1], np.pi / 2, 0.0),
    ([1, 0, 0], np.pi / 2, np.pi / 2), ([-1, 0, 0], np.pi / 2, -np.pi / 2),
    ([0, 0, -1], np.pi / 2, np.pi), ([1, 0, 1], np.pi / 2, np.pi / 4),
    ([0, 1, 1], np.pi / 4, 0.0)])
def test_axis_aligned_rod_angles(direction, theta, phi):
    s = S.compute_shape(rod(8, direction))
    assert s.theta == pytest.approx(theta, abs=1e-9)
    if phi is not None:
        # phi = pi and -pi are the same direction
        assert np.cos(s.phi) == pytest.approx(np.cos(phi), abs=1e-9)
        assert np.sin(s.phi) == pytest.approx(np.sin(phi), abs=1e-9)


def test_planar_rectangle_semi_axes_and_close_pairs():
    # 4 corners of a 2 x 1 rectangle in the xz-plane: lambda = (1, 1/4, 0)
    r = np.array([[-1.0, 0, -0.5], [1.0, 0, -0.5], [1.0, 0, 0.5], [-1.0, 0, 0.5]])
    s = S.compute_shape(r)
    assert s.a == pytest.approx(np.sqrt(3.0), rel=1e-12)
    assert s.b == pytest.approx(np.sqrt(0.75), rel=1e-12)
    assert s.c == pytest.approx(0.0, abs=1e-7)
    assert s.rg == pytest.approx(np.sqrt(1.25), rel=1e-12)
    # pair (0, 3) at distance 1 < 1.05 and |i - j| = 3: one close pair; (0, 2) too far
    assert s.close_pairs == 1
    assert S.count_close_pairs(r, cutoff=2.5) == 3


def test_gyration_tensor_is_pair_formula():
    rng = np.random.default_rng(2)
    r = rng.normal(size=(9, 3))
    diff = r[:, None, :] - r[None, :, :]
    t = np.einsum("ijn,ijm->nm", diff, diff) / (2 * len(r) ** 2)
    assert np.allclose(S.gyration_tensor(r), t, atol=1e-14)


def test_dominant_period_of_sines():
    t = np.linspace(0.0, 200.0, 2001)
    f, p, per = S.dominant_period(t, 3 + np.sin(2 * np.pi * t / 25.0))
    assert per == pytest.approx(25.0, rel=0.01)
    # 2-D signal (end-to-end vector rotating with period 40)
    v = np.stack([np.cos(2 * np.pi * t / 40), np.sin(2 * np.pi * t / 40), 0 * t], axis=1)
    assert S.dominant_period(t, v)[2] == pytest.approx(40.0, rel=0.01)
    assert S.dominant_period(t[:3], t[:3])[2] == float("inf")


def _window_series(t):
    t = np.asarray(t, dtype=float)
    return {"rg": t, "a": 2.0 * t + 2.0, "b": t + 1.0, "c": np.full(len(t), 0.5),
            "theta": np.where(np.arange(len(t)) % 2 == 0, 0.0, np.pi / 3),
            "close_pairs": np.arange(len(t)) % 3}


def test_window_means_exact_values():
    # t = 0..10 in windows of 5: [0, 5) has 5 frames, the last holds t = 5..10 (6 frames)
    t = np.arange(11.0)
    kf = np.full(11, np.nan)
    kf[[1, 2, 4]] = (0.2, 0.4, 0.9)
    modes = np.array([1, 2, 1, 0, 0, 1, 1, 1, 2, 0, 1])
    w = S.window_means(t, _window_series(t), 5.0, kf, modes)
    assert [(x["t0"], x["t1"], x["frames"]) for x in w] == [(0.0, 5.0, 5), (5.0, 10.0, 6)]
    assert w[0]["rg"] == pytest.approx(2.0) and w[1]["rg"] == pytest.approx(7.5)
    assert w[0]["a_over_b"] == pytest.approx(2.0) and w[1]["c"] == pytest.approx(0.5)
    # b / c = 2 (t + 1): smallest at the first frame of each window
    assert w[0]["b_over_c_min"] == pytest.approx(2.0) and w[1]["b_over_c_min"] == pytest.approx(12.0)
    # |cos theta| alternates 1 and 1/2: frames 0..4 -> (3 + 1) / 5, frames 5..10 -> (3 + 1.5) / 6
    assert w[0]["abs_cos_theta"] == pytest.approx(4.0 / 5.0)
    assert w[1]["abs_cos_theta"] == pytest.approx(4.5 / 6.0)
    assert w[0]["close_pairs"] == pytest.approx((0 + 1 + 2 + 0 + 1) / 5.0)
    assert w[0]["kf_mean"] == pytest.approx(0.5) and w[0]["kf_max"] == pytest.approx(0.9)
    assert np.isnan(w[1]["kf_mean"]) and np.isnan(w[1]["kf_max"])
    assert (w[0]["mode_1"], w[0]["mode_2"], w[1]["mode_1"], w[1]["mode_2"]) == (2, 1, 4, 1)
    assert np.isnan(S.window_means(t, _window_series(t), 5.0)[0]["mode_1"])


def test_frame_ratios_exact_values():
    # a/b = 2 everywhere, b/c = 2 (t + 1); offset 100, range [103, 105] holds t = 3, 4, 5
    t = np.arange(11.0)
    ab, bc = S.frame_ratios(t, _window_series(t), offset=100.0, t_from=103.0, t_to=105.0)
    assert np.allclose(ab, 2.0) and np.allclose(bc, [8.0, 10.0, 12.0])
    assert len(S.frame_ratios(t, _window_series(t))[0]) == 11
    series = _window_series(t)
    series["c"] = np.zeros(11)
    assert np.all(np.isinf(S.frame_ratios(t, series)[1]))
    with pytest.raises(ValueError):
        S.frame_ratios(np.array([0.0, np.nan]), _window_series([0.0, 1.0]))


def test_window_means_offset_and_range():
    # a run started at t = 800 of another: its times 0..30 are 800..830
    t = np.arange(31.0)
    w = S.window_means(t, _window_series(t), 10.0, offset=800.0, t_from=805.0, t_to=825.0)
    assert [(x["t0"], x["frames"]) for x in w] == [(805.0, 10), (815.0, 11)]
    assert w[0]["rg"] == pytest.approx(9.5) and w[1]["rg"] == pytest.approx(20.0)
    # the default start is the first time rounded down; windows without frames are left out
    t = np.array([3.0, 4.0, 31.0])
    w = S.window_means(t, _window_series(t), 10.0)
    assert [(x["t0"], x["frames"]) for x in w] == [(0.0, 2), (30.0, 1)]
    assert [x["frames"] for x in S.window_means([7.0], _window_series([7.0]), 10.0)] == [1]


@pytest.mark.parametrize("width", [0.0, -1.0, np.nan, np.inf])
def test_window_means_refuses_bad_width(width):
    with pytest.raises(ValueError, match="window width"):
        S.window_means(np.arange(3.0), _window_series(np.arange(3.0)), width)


def test_window_means_refuses_non_finite_times():
    t = np.array([0.0, np.nan, 2.0])
    with pytest.raises(ValueError, match="non-finite"):
        S.window_means(t, _window_series(t), 1.0)
