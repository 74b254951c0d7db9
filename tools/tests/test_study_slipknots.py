"""knotflow-study: the slipknot confirmation (exact binomial bounds), its files, its figure, and
sweeps without case files."""

import contextlib
import json
import math
from fractions import Fraction

import numpy as np
import pytest

from knotflow_tools import cli, io, study_compare, study_slipknots

from conftest import write_case
from helpers import open_trefoil, tailed_trefoil

ALPHA = study_slipknots.CONFIRM_ALPHA


def _exact_tail(x, n, p):
    """P(X >= x), X ~ Binomial(n, p) with p a Fraction: exact rational arithmetic."""
    return sum(math.comb(n, k) * p**k * (1 - p)**(n - k) for k in range(x, n + 1))


def _threshold_core(n, alpha):
    """Smallest x with P_{1/2}(X >= x) < alpha, exactly (the one-sided binomial test of
    p <= 1/2, which is what 'Clopper-Pearson lower bound > 1/2' means)."""
    a = Fraction(alpha).limit_denominator(10**12)
    x = n
    while x > 0 and _exact_tail(x - 1, n, Fraction(1, 2)) < a:
        x -= 1
    return x


def test_bounds_have_their_closed_forms_at_the_ends():
    # all n knotted: P_p(X >= n) = p^n = alpha -> p = alpha^(1/n); none: 1 - alpha^(1/n)
    for n in (1, 10, 200, 1000):
        assert study_slipknots.lower_bound(n, n) == pytest.approx(ALPHA ** (1 / n), abs=1e-9)
        assert study_slipknots.upper_bound(0, n) == pytest.approx(1 - ALPHA ** (1 / n), abs=1e-9)
        assert study_slipknots.lower_bound(0, n) == 0.0 and study_slipknots.upper_bound(n, n) == 1.0


def test_binomial_tail_equals_the_exact_sum():
    for x, n, p in ((550, 1000, Fraction(1, 2)), (72, 1000, Fraction(1, 10)),
                    (3, 10, Fraction(3, 10)), (1000, 1000, Fraction(1, 2))):
        assert study_slipknots.binomial_tail(x, n, float(p)) == pytest.approx(float(_exact_tail(x, n, p)),
                                                                    rel=1e-9)


def test_core_rule_at_its_boundary_with_1000_closures():
    x = _threshold_core(1000, ALPHA)
    assert x == 550                           # the number docs/analysis.md states
    assert study_slipknots.confirm_counts(1000)[0] == x
    assert study_slipknots.kf_estimate(x / 1000, 1000)["lower"] > study_slipknots.SLIP_K
    assert study_slipknots.kf_estimate((x - 1) / 1000, 1000)["lower"] <= study_slipknots.SLIP_K
    # 0.51 (the biased maximum seen at 100 closures per subchain) is far from enough
    assert study_slipknots.kf_estimate(0.51, 1000)["lower"] < 0.48


def test_whole_chain_rule_at_its_boundary_with_1000_closures():
    # the largest x with P_{1/10}(X <= x) < alpha, exactly
    a = Fraction(ALPHA).limit_denominator(10**12)
    x = 0
    while 1 - _exact_tail(x + 2, 1000, Fraction(1, 10)) < a:
        x += 1
    assert x == 71
    assert study_slipknots.confirm_counts(1000)[1] == x
    assert study_slipknots.kf_estimate(x / 1000, 1000)["upper"] < study_slipknots.SLIP_WHOLE
    assert study_slipknots.kf_estimate((x + 1) / 1000, 1000)["upper"] >= study_slipknots.SLIP_WHOLE


def test_ten_closures_all_knotted_just_pass():
    # 0.001^(1/10) = 0.5012 > 0.5, 0.001^(1/9) = 0.464; 9 of 10: P(X >= 9 | 1/2) = 11/1024
    assert study_slipknots.kf_estimate(1.0, 10)["lower"] > 0.5
    assert study_slipknots.kf_estimate(1.0, 9)["lower"] < 0.5
    assert study_slipknots.kf_estimate(0.9, 10)["lower"] < 0.5
    # and no whole chain is ever 'unknotted' at this level with 10 closures: 0.9^10 = 0.35
    assert study_slipknots.confirm_counts(10) == (10, -1)


def test_estimate_standard_error_and_refusal():
    e = study_slipknots.kf_estimate(0.6, 1000)
    assert e["knotted"] == 600 and e["se"] == pytest.approx(math.sqrt(0.24 / 1000))
    with pytest.raises(ValueError, match="closures"):
        study_slipknots.kf_estimate(0.5, 0)
    with pytest.raises(ValueError, match="k_f 1.5"):
        study_slipknots.kf_estimate(1.5, 100)


# ----------------------------------------------------------------- the confirm directory

N = 30


def _matrix(peak, at=(3, 25)):
    m = np.full((N, N), np.nan)
    m[np.triu_indices(N, 9)] = 0.0
    m[at] = peak
    return m


def _doc(kf, closures, matrix=None):
    d = {"kf": kf, "closures": closures, "knot_core": None}
    if matrix is not None:
        d["matrix"] = [[None if np.isnan(v) else v for v in row] for row in matrix]
        core = np.argwhere(np.nan_to_num(matrix, nan=-1) >= 0.5)
        d["knot_core"] = core[0].tolist() if len(core) else None
    return d


def _put(tmp_path, part, doc, frame=4):
    with open(study_slipknots.confirm_path(str(tmp_path), "A1.40", frame, part), "w") as fh:
        json.dump(doc, fh)


class _Case:
    name = "A1.40"

    def __init__(self, mats):
        self.knot_matrices = mats
        self.time = np.arange(6) * 10.0


@pytest.mark.parametrize("core_kf, whole_kf, verdict", [
    (0.62, 0.0, study_slipknots.CONFIRMED),
    (0.51, 0.0, "not confirmed: core k_f lower bound"),
    (0.62, 0.08, "not confirmed: whole-chain k_f upper bound"),
])
def test_confirmation_files_give_the_verdict(tmp_path, core_kf, whole_kf, verdict):
    _put(tmp_path, "matrix", _doc(0.0, 1000, _matrix(0.51)))
    _put(tmp_path, "core", _doc(core_kf, 1000))
    _put(tmp_path, "whole", _doc(whole_kf, 1000))
    (m,) = study_slipknots.slipknot_scan(_Case({4: _matrix(0.7)}), np.array([0.0, 50.0]), np.zeros(2),
                               str(tmp_path))
    assert m["slipknot"] and m["recomputed_slipknot"] and m["recomputed_max_K"] == 0.51
    assert m["core_beads"] == [3, 25] and m["core_closures"] == 1000
    assert m["core_kf"] == pytest.approx(core_kf)
    assert m["core_se"] == pytest.approx(math.sqrt(core_kf * (1 - core_kf) / 1000))
    assert m["check_whole_kf"] == pytest.approx(whole_kf)
    assert m["verdict"].startswith(verdict)
    assert m["confirmed_slipknot"] == (verdict == study_slipknots.CONFIRMED)


def test_confirmation_stages_before_the_core_check(tmp_path):
    case = _Case({4: _matrix(0.7), 5: _matrix(0.8), 3: _matrix(0.2)})
    _put(tmp_path, "matrix", _doc(0.0, 1000, _matrix(0.51)), frame=4)   # core files missing
    _put(tmp_path, "matrix", _doc(0.0, 1000, _matrix(0.35)), frame=5)   # rejected
    scan = {m["frame"]: m for m in study_slipknots.slipknot_scan(case, np.array([0.0, 50.0]), np.zeros(2),
                                                       str(tmp_path))}
    assert study_slipknots.slip_verdict(scan[4]) == study_slipknots.UNCHECKED
    assert study_slipknots.slip_verdict(scan[5]) == study_slipknots.REJECTED
    assert study_slipknots.slip_verdict(scan[3]) == study_slipknots.NO_CANDIDATE
    # the figure shows the frame that went furthest: 4 (still a slipknot with more closures)
    rows = [{"case": "A1.40", "A": 1.4, "matrices": list(scan.values())}]
    assert [m["frame"] for _, m in study_slipknots.slipknot_figure_frames(rows)] == [4]
    n = study_compare._cc_numbers({**rows[0], "case_mode": "-", "close_pairs_mean": 0.0,
                           "close_pairs_late": 0.0, "max_kf": 0.0})
    assert (n["slip_candidates"], n["slip_recomputed"], n["slip_passed"],
            n["slip_confirmed"]) == (2, 2, 1, 0)


def test_an_earlier_results_json_is_read_by_its_recomputation():
    old = {"frame": 4, "time": 40.0, "whole_kf": 0.0, "max_K": 0.6, "knot_core": [3, 25],
           "slipknot": True, "confirmed_max_K": 0.51, "confirmed_slipknot": True}
    assert study_slipknots.slip_verdict(old) == study_slipknots.UNCHECKED      # not 'confirmed'


# --------------------------------------------------------------------- real geometry

def _slipknot_chain():
    """The classical slipknot: the open trefoil (k_f about 0.95) followed by its own path
    retraced at an offset of 0.05 -- the whole chain is unknotted, beads 0..98 are knotted."""
    t = open_trefoil(23)
    return np.vstack([t, t[::-1] + np.array([0.0, 0.0, 0.05])]), len(t)


def _check_with_knotflow_kf(tmp_path, r, core_end, closures=200):
    """The pipeline of scripts/reproduce.sh with knotflow-kf (the JSON of knotflow-analyze) in
    place of knotflow-analyze, and the recomputed matrix constructed with the core 0..core_end."""
    case_path = tmp_path / "A1.40.h5"
    write_case(case_path, np.stack([r, r]), time=np.array([0.0, 10.0]))
    conf = tmp_path / "confirm"
    conf.mkdir()
    mat = np.full((len(r), len(r)), np.nan)
    mat[np.triu_indices(len(r), 9)] = 0.0
    mat[0, core_end] = 0.9
    doc = _doc(0.0, 1000, mat)
    assert doc["knot_core"] == [0, core_end]
    with open(study_slipknots.confirm_path(str(conf), "A1.40", 1), "w") as fh:
        json.dump(doc, fh)
    frame = study_slipknots.confirm_path(str(conf), "A1.40", 1, "frame")
    core = study_slipknots.confirm_path(str(conf), "A1.40", 1, "core_xyz")
    assert cli.main_study(["--write-frame", str(case_path), "1", frame]) == 0
    assert cli.main_study(["--write-frame", str(case_path), "1", core, "--core-of",
                           study_slipknots.confirm_path(str(conf), "A1.40", 1)]) == 0
    assert np.allclose(io.read_xyz(core), r[:core_end + 1], atol=1e-9)
    for part, xyz in (("core", core), ("whole", frame)):
        with open(study_slipknots.confirm_path(str(conf), "A1.40", 1, part), "w") as fh, \
                contextlib.redirect_stdout(fh):
            assert cli.main_kf([xyz, "--closures", str(closures), "--seed", "7", "--json"]) == 0
    return study_slipknots.confirmation(str(conf), "A1.40", 1)


class _Frames:
    def __init__(self, r):
        self.positions = np.stack([r, r])
        self.knot_matrices = {1: np.zeros((len(r), len(r)))}


def test_constructed_slipknot_is_confirmed_and_drawn(tmp_path):
    r, nt = _slipknot_chain()
    c = _check_with_knotflow_kf(tmp_path, r, nt - 1)
    assert c["core_kf"] > 0.85 and c["check_whole_kf"] < 0.03
    assert c["verdict"] == study_slipknots.CONFIRMED
    entry = {"frame": 1, "time": 10.0, "whole_kf": 0.0, "max_K": 0.9, "knot_core": [0, nt - 1],
             "slipknot": True, **c}
    rows = [{"case": "A1.40", "A": 1.4, "matrices": [entry], "_case": _Frames(r)}]
    path = study_slipknots.plot_slipknots(rows, str(tmp_path / "s.png"), str(tmp_path / "confirm"))
    assert path and (tmp_path / "s.png").stat().st_size > 10000
    assert study_slipknots.slipknot_caption(rows).startswith("the 1 confirmed slipknot frame")
    # the figure's matrix is the recomputed one (the screen's here is all zeros)
    mat, core, source = study_slipknots._shown_matrix(rows[0], entry, str(tmp_path / "confirm"))
    assert source == "recomputed" and core == [0, nt - 1] and mat[0, nt - 1] == 0.9


def test_trefoil_with_tails_is_a_knot_not_a_slipknot(tmp_path):
    r = tailed_trefoil()
    c = _check_with_knotflow_kf(tmp_path, r, len(r) - 11)
    # the knotted subchain has k_f about 1, and so has the whole chain: a knot
    assert c["core_kf"] > 0.95 and c["check_whole_kf"] > 0.95
    assert c["verdict"].startswith("not confirmed: whole-chain")


def test_write_frame_refuses_a_matrix_without_core(tmp_path):
    case_path = tmp_path / "A1.40.h5"
    r = open_trefoil()
    write_case(case_path, np.stack([r]), time=np.array([0.0]))
    bad = tmp_path / "m.json"
    bad.write_text(json.dumps(_doc(0.0, 1000, _matrix(0.2))))
    assert cli.main_study(["--write-frame", str(case_path), "0", str(tmp_path / "c.xyz"),
                           "--core-of", str(bad)]) == cli.EXIT_USAGE
    assert not (tmp_path / "c.xyz").exists()


# ------------------------------------------------------------------- the study's output

def test_sweep_without_case_files_is_named_and_the_others_written(tmp_path):
    empty = tmp_path / "trefoil_table2"
    empty.mkdir()
    cane = tmp_path / "candycane"
    cane.mkdir()
    r, _ = _slipknot_chain()
    write_case(cane / "A1.40.h5", np.stack([r, r]), time=np.array([0.0, 10.0]),
               attrs={"forces.bending_a": 1.4})
    out = tmp_path / "out"
    assert cli.main_study(["--trefoil", str(empty), "--candycane", str(cane), "--out", str(out),
                           "--closures", "5"]) == 0
    text = (out / "results.md").read_text()
    assert f"no case files in {empty}" in text and "## Candy-cane" in text
    res = json.loads((out / "results.json").read_text())
    assert res["missing"] == [f"no case files in {empty}"] and "trefoil" not in res
