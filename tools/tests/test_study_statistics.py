"""Statistics of the study's questions over samples (study_statistics): exact binomial
intervals, proper scores of Table 2, and the candy-cane's modes per stiffness, on constructed
rows whose answers are known."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from knotflow_tools import study_statistics as st


def test_binomial_cdf_equals_the_direct_sum():
    for n, k, p in ((10, 3, 0.2), (29, 0, 0.05), (7, 6, 0.9), (50, 25, 0.5)):
        direct = sum(math.comb(n, i) * p ** i * (1 - p) ** (n - i) for i in range(k + 1))
        assert st.binomial_cdf(k, n, p) == pytest.approx(direct, rel=1e-12)


def test_clopper_pearson_exact_ends_symmetry_and_a_table_value():
    n, alpha = 10, 0.025
    lo, hi = st.clopper_pearson(0, n)
    assert lo == 0.0 and hi == pytest.approx(1 - alpha ** (1 / n), abs=1e-12)
    lo, hi = st.clopper_pearson(n, n)
    assert hi == 1.0 and lo == pytest.approx(alpha ** (1 / n), abs=1e-12)
    for k in range(n + 1):
        lo, hi = st.clopper_pearson(k, n)
        lo2, hi2 = st.clopper_pearson(n - k, n)
        assert lo == pytest.approx(1 - hi2, abs=1e-12) and hi == pytest.approx(1 - lo2, abs=1e-12)
    # the tabulated exact interval of 1 success in 10 trials: 0.0025 - 0.4450
    lo, hi = st.clopper_pearson(1, 10)
    assert round(lo, 4) == 0.0025 and round(hi, 4) == 0.4450
    with pytest.raises(ValueError):
        st.clopper_pearson(3, 2)


def _tref(a, o, reknot, t_unknot=50.0, status="finished"):
    return {"A": a, "orientation": o, "unknot_then_knot": reknot, "status": status,
            "t_unknot": t_unknot, "t_reknot": 300.0 if reknot else None}


def test_cell_probabilities_and_scores_of_table2_and_never():
    rows = ([_tref(1.4, "b", True)] * 3 + [_tref(1.4, "b", False)] * 7
            + [_tref(0.8, "a", False)] * 9 + [_tref(0.8, "a", False, t_unknot=None)]
            + [_tref(0.8, "a", True, status="running")])
    cells = st.cell_probabilities(rows)
    by = {(c["A"], c["orientation"]): c for c in cells}
    b = by[(1.4, "b")]
    assert (b["samples"], b["transitions"], b["study"], b["uncertain"]) == (10, 3, True, True)
    assert b["interval"] == pytest.approx(list(st.clopper_pearson(3, 10)))
    a = by[(0.8, "a")]
    assert (a["samples"], a["transitions"], a["never_untied"], a["uncertain"]) == (10, 0, 1, False)
    s = st.table2_scores(cells)
    # Table 2 says 1 for (1.4, b) and 0 for (0.8, a): squared errors 7 (of 20 samples)
    assert s["brier"]["table2"] == pytest.approx(7 / 20)
    assert s["brier"]["never"] == pytest.approx(3 / 20)
    floor = s["log"]["floor"]
    want = (3 * math.log(1 - floor) + 7 * math.log(floor) + 10 * math.log(1 - floor)) / 20
    assert s["log"]["table2"] == pytest.approx(want)
    text = "\n".join(st.probability_table(cells, s))
    assert "| 1.4 | b | 10 | 3 | **0.30 (0.07-0.65)** | U->K |" in text


def test_first_reknot_and_how_long_it_held():
    from knotflow_tools.study_rows import first_reknot
    # a short-lived knot: re-knotted at 680, untied again at 709
    assert first_reknot([("unknot", 154.0), ("knot", 680.0), ("unknot", 709.0)], 1000.0) == \
        (154.0, 680.0, 29.0, False)
    # a knot that holds to the last frame
    assert first_reknot([("unknot", 161.0), ("knot", 571.0)], 1000.0) == (161.0, 571.0, 429.0, True)
    # the first re-knotting counts, not a knot before the first untying or a later one
    events = [("knot", 10.0), ("unknot", 20.0), ("knot", 30.0), ("unknot", 40.0), ("knot", 50.0)]
    assert first_reknot(events, 100.0) == (20.0, 30.0, 10.0, False)
    assert first_reknot([("unknot", 152.0)], 1000.0) == (152.0, None, None, None)
    assert first_reknot([], 1000.0) == (None, None, None, None)


def test_cells_report_how_long_knots_held_and_the_final_state():
    def row(t_reknot, held, lasted, final):
        r = _tref(2.2, "c", held is not None)
        r.update({"t_reknot": t_reknot, "reknot_held": held, "reknot_lasted": lasted,
                  "final_state": final})
        return r
    rows = [row(571.0, 429.0, True, "knotted"), row(None, None, None, "unknotted"),
            row(483.0, 29.0, False, "unknotted")]
    cells = st.cell_probabilities(rows)
    (c,) = cells
    # in the order of the re-knot times, each with its own sample's time held
    assert c["t_reknot"] == [483.0, 571.0]
    assert c["held"] == [[29.0, False], [429.0, True]]
    assert (c["transitions"], c["ends_knotted"]) == (2, 1)
    text = "\n".join(st.probability_table(cells, st.table2_scores(cells)))
    assert "| 483, 571 | 29, 429+ | 1 | 0 |" in text
    # rows of an older results.json (no held time, no final state) give none
    (old,) = st.cell_probabilities([_tref(2.2, "c", True)])
    assert (old["held"], old["ends_knotted"]) == ([], 0)


def _cane(a, mode, fr1, fr2, t, obs, status="finished"):
    case = SimpleNamespace(time=np.asarray(t, float), observables={k: np.asarray(v, float)
                                                                     for k, v in obs.items()})
    return {"A": a, "case_mode": mode, "mode_I_late": fr1, "mode_II_late": fr2,
            "status": status, "_case": case}


def test_mode_statistics_and_close_pair_windows():
    t = np.arange(0.0, 101.0)
    omega = 0.05
    obs = {"a": np.full(t.size, 6.0), "b": np.full(t.size, 2.0), "c": np.full(t.size, 0.5),
           "theta": np.zeros(t.size), "phi": np.angle(np.exp(1j * omega * t)),
           "close_pairs": np.where(t < 50, 8.0, 4.0)}
    rows = [_cane(1.0, "I", 0.6, 0.1, t, obs), _cane(1.0, "-", 0.2, 0.3, t, obs),
            _cane(3.0, "II", 0.0, 0.9, t, {**obs, "close_pairs": np.full(t.size, 2.0)})]
    stats = {s["A"]: s for s in st.mode_statistics(rows)}
    one = stats[1.0]
    assert one["cases"] == 2 and one["case_mode_I"]["cases"] == 1
    assert one["case_mode_I"]["interval"] == pytest.approx(list(st.clopper_pearson(1, 2)))
    assert one["frames_mode_I"]["mean"] == pytest.approx(0.4)
    lo, hi = one["frames_mode_I"]["interval"]
    assert 0.2 <= lo <= 0.4 <= hi <= 0.6
    late = one["late_per_case"]
    assert late["a_over_b"]["median"] == pytest.approx(3.0)
    assert late["b_over_c"]["median"] == pytest.approx(4.0)
    assert late["abs_cos_theta"]["median"] == pytest.approx(1.0)
    assert late["phi_rate"]["median"] == pytest.approx(omega, rel=1e-9)
    assert late["close_pairs"]["median"] == pytest.approx(4.0)
    windows = st.close_pair_ratio_windows(rows, 50.0)
    assert [w["ratio"] for w in windows[:2]] == pytest.approx([4.0, 2.0])
    assert "| 0-50 | 8.00 | 2.00 | 4.00 |" in st.ratio_table(windows)
    assert "| 1 | 2 | 1 (0.50, 0.01-0.99) |" in "\n".join(st.mode_table(list(stats.values())))


def test_paired_starts_match_by_start_and_difference_per_a():
    """Three starts run with two models, one start only here and one only there: per A the
    pairs, the agreeing case modes and the mean differences of the late mode fractions, by
    hand: A = 1: (0.05 - 0.046 + 0 - 0)/2 = 0.002 (mode I), (0 - 0 + 0.2 - 0.126)/2 = 0.037
    (mode II), one of two case modes alike; A = 3: 0.5 - 0.461 = 0.039, none alike."""
    t = np.arange(0.0, 101.0)
    obs = {"a": np.full(t.size, 6.0), "b": np.full(t.size, 2.0), "c": np.full(t.size, 0.5),
           "theta": np.zeros(t.size), "phi": np.zeros(t.size), "close_pairs": np.full(t.size, 3.0)}

    def cane(a, seed, mode, fr1, fr2, status="finished"):
        return {**_cane(a, mode, fr1, fr2, t, obs, status), "seed": seed, "case": f"A{a}_s{seed}"}
    rows = [cane(1.0, 13, "-", 0.05, 0.0), cane(1.0, 14, "II", 0.0, 0.2),
            cane(3.0, 18, "II", 0.0, 0.5), cane(3.0, 99, "-", 0.0, 0.1),
            cane(3.0, 4, "II", 0.0, 0.4, status="running")]
    other = [cane(1.0, 13, "-", 0.046, 0.0), cane(1.0, 14, "-", 0.0, 0.126),
             cane(3.0, 18, "-", 0.0, 0.461), cane(3.0, 20, "-", 0.0, 0.0),
             cane(3.0, 4, "II", 0.0, 0.444)]
    paired = st.paired_starts(rows, other, key=lambda r: (r["A"], r["seed"]))
    assert [(p["A"], p["start"]) for p in paired["pairs"]] == [(1.0, 13), (1.0, 14), (3.0, 18)]
    by_a = {e["A"]: e for e in paired["per_A"]}
    assert (by_a[1.0]["pairs"], by_a[1.0]["same_case_mode"]) == (2, 1)
    assert by_a[1.0]["mode_I_late_difference"] == pytest.approx(0.002)
    assert by_a[1.0]["mode_II_late_difference"] == pytest.approx(0.037)
    assert (by_a[3.0]["pairs"], by_a[3.0]["same_case_mode"]) == (1, 0)
    assert by_a[3.0]["mode_II_late_difference"] == pytest.approx(0.039)
    # seed 99 here; seeds 20 and 4 there (4 is running here, so it pairs with nothing)
    assert (paired["unmatched"], paired["unmatched_other"]) == (1, 2)
    assert paired["pairs"][0]["this"]["a_over_b"] == pytest.approx(3.0)
    md = "\n".join(st.paired_table(paired, "multipole", "rpy"))
    assert "| 1 | 14 | II / - | 0.000 / 0.000 | 0.200 / 0.126 | 3.00 / 3.00 |" in md
    assert "| 1 | 2 | 1 of 2 | +0.002 | +0.037 |" in md


def test_knotflow_study_samples_and_rotations_end_to_end(tmp_path):
    """knotflow-study --samples: four perturbed samples of the cell (1.4, b), two of which re-knot
    (k_f written into /analysis/knots), give probability 2/4 with the exact interval; --rotations
    on candy-cane files gives one row per A and a results.json part."""
    import json

    import h5py
    from analysis_fixture import write_knots

    from knotflow_tools.cli import main_study

    from conftest import unknotting_trefoil_frames, write_case
    samples = tmp_path / "samples"
    samples.mkdir()
    t = np.arange(8) * 10.0
    for s, kf in enumerate(([0.98, 0.9, 0.05, 0.02, 0.95, 0.97, 0.96, 0.95],
                            [0.98, 0.9, 0.05, 0.02, 0.95, 0.97, 0.96, 0.95],
                            [0.98, 0.9, 0.05, 0.02, 0.03, 0.01, 0.02, 0.02],
                            [0.98, 0.9, 0.05, 0.02, 0.03, 0.01, 0.02, 0.02]), start=1):
        path = write_case(samples / f"A1.40_orb_s{s}.h5", unknotting_trefoil_frames(8), time=t,
                          attrs={"forces.bending_a": 1.4, "chain.orientation": "b",
                                 "case_name": f"A1.40_orb_s{s}"})
        write_knots(path, np.arange(8), t, kf, np.zeros((8, 10)), ["3_1"] * 8, closures=10, seed=s)
    cane = tmp_path / "cane"
    cane.mkdir()
    for a in (1.0, 3.0):
        path = write_case(cane / f"A{a:.2f}.h5", unknotting_trefoil_frames(8), time=t,
                          attrs={"forces.bending_a": a, "case_name": f"A{a:.2f}"})
        write_knots(path, np.arange(8), t, np.zeros(8), np.zeros((8, 10)), ["0_1"] * 8,
                    closures=10, seed=1)
    out = tmp_path / "out"
    assert main_study(["--samples", str(samples), "--rotations", str(cane), "--window", "40",
                       "--same-starts", str(cane), "--out", str(out)]) == 0
    res = json.loads((out / "results.json").read_text())
    (cell,) = res["samples"]["cells"]
    assert (cell["samples"], cell["transitions"], cell["study"]) == (4, 2, True)
    assert cell["interval"] == pytest.approx(list(st.clopper_pearson(2, 4)))
    assert [c["A"] for c in res["rotations"]["per_A"]] == [1.0, 3.0]
    assert len(res["rotations"]["close_pair_windows"]) == 2
    with pytest.raises(SystemExit):   # the starts compared with nothing: refused
        main_study(["--candycane", str(cane), "--same-starts", str(cane), "--out", str(out)])
    # the sweep against itself: each case its own partner (no scene text: matched by case)
    same = res["rotations"]["same_starts"]
    assert [(e["A"], e["pairs"], e["same_case_mode"]) for e in same["per_A"]] == [(1.0, 1, 1),
                                                                               (3.0, 1, 1)]
    assert (same["unmatched"], same["unmatched_other"]) == (0, 0)
    md = (out / "results.md").read_text()
    assert "## Table 2 as probabilities" in md and "| 1.4 | b | 4 | 2 | **0.50" in md
    with h5py.File(samples / "A1.40_orb_s1.h5") as f:
        assert f.attrs["case_name"] == "A1.40_orb_s1"
    with pytest.raises(SystemExit):
        main_study(["--rotations", str(cane), "--window", "0", "--out", str(out)])


def _path_scene(method, update="iterative", solver_tolerance=None, jacobian_steps=4):
    """A scene text as knotflow echoes it, with the variables of campaign.integration_path."""
    hydro = f"  update = '{update}'\n"
    if solver_tolerance is not None:
        hydro += f"  solver_tolerance = {solver_tolerance}\n"
    hydro += "  jacobian_order = 0\n"
    return ("&chain\n  shape = 'trefoil'\n  orientation = 'b'\n/\n&forces\n  bending_a = 1.4\n/\n"
            f"&hydro\n  model = 'multipole'\n{hydro}/\n"
            f"&integrator\n  method = '{method}'\n  tolerance = 0.10000000000000000E-3\n"
            f"  jacobian_steps = {jacobian_steps}\n/\n")


def test_integration_path_names_what_the_path_reads():
    from knotflow_tools.campaign import integration_path
    dopri = integration_path(_path_scene("dopri45", "adaptive", 0.1e-5))
    # dopri45 reads neither the Jacobian's variables nor, with 'adaptive', solver_tolerance
    assert dopri == "method = 'dopri45', tolerance = 0.0001, update = 'adaptive'"
    ros = integration_path(_path_scene("ros34pw2", solver_tolerance="0.10000000000000000E-3",
                                       jacobian_steps=1))
    assert ros == ("method = 'ros34pw2', tolerance = 0.0001, jacobian_steps = 1, "
                   "update = 'iterative', solver_tolerance = 0.0001, jacobian_order = 0")
    # a scene written before solver_tolerance existed says so; it is its own path, unless the
    # program's defaults (campaign.scene_defaults) complete it
    old = integration_path(_path_scene("dopri45"))
    assert "solver_tolerance not in the scene" in old
    new = integration_path(_path_scene("dopri45", solver_tolerance="0.1E-5"))
    assert old != new
    assert integration_path(_path_scene("dopri45"), {("hydro", "solver_tolerance"): "0.1E-5"}) == new
    assert integration_path(_path_scene("dopri45"), {("hydro", "solver_tolerance"): "0.1E-3"}) != new


def test_knotflow_study_samples_apart_by_integration_path(tmp_path):
    """Four samples of (1.4, b): two on dopri45 (one re-knots), two on ros34pw2 (both re-knot).
    Pooled 3 of 4; by path 1 of 2 and 2 of 2, each with its own exact interval and scores; one
    path alone gives no by_path part."""
    import json

    from analysis_fixture import write_knots

    from knotflow_tools.cli import main_study

    from conftest import unknotting_trefoil_frames, write_case
    reknot = [0.98, 0.9, 0.05, 0.02, 0.95, 0.97, 0.96, 0.95]
    stays = [0.98, 0.9, 0.05, 0.02, 0.03, 0.01, 0.02, 0.02]
    dopri = _path_scene("dopri45")
    ros = _path_scene("ros34pw2", solver_tolerance="0.10000000000000000E-3", jacobian_steps=1)
    t = np.arange(8) * 10.0
    samples = tmp_path / "samples"
    samples.mkdir()
    for s, (scene, kf) in enumerate(((dopri, reknot), (dopri, stays), (ros, reknot),
                                     (ros, reknot)), start=1):
        path = write_case(samples / f"A1.40_orb_s{s}.h5", unknotting_trefoil_frames(8), time=t,
                          attrs={"forces.bending_a": 1.4, "chain.orientation": "b",
                                 "case_name": f"A1.40_orb_s{s}", "scene": scene})
        write_knots(path, np.arange(8), t, kf, np.zeros((8, 10)), ["3_1"] * 8, closures=10, seed=s)
    out = tmp_path / "out"
    assert main_study(["--samples", str(samples), "--out", str(out)]) == 0
    res = json.loads((out / "results.json").read_text())["samples"]
    (pooled,) = res["cells"]
    assert (pooled["samples"], pooled["transitions"]) == (4, 3)
    by = {p["path"].split(",")[0]: p for p in res["by_path"]}
    assert sorted(by) == ["method = 'dopri45'", "method = 'ros34pw2'"]
    (d,) = by["method = 'dopri45'"]["cells"]
    (r,) = by["method = 'ros34pw2'"]["cells"]
    assert (d["samples"], d["transitions"], d["uncertain"]) == (2, 1, True)
    assert (r["samples"], r["transitions"], r["uncertain"]) == (2, 2, False)
    assert r["interval"] == pytest.approx(list(st.clopper_pearson(2, 2)))
    # Table 2 says a transition for (1.4, b): Brier 1/2 on the dopri45 samples, 0 on ros34pw2's
    assert by["method = 'dopri45'"]["scores"]["brier"]["table2"] == pytest.approx(0.5)
    assert by["method = 'ros34pw2'"]["scores"]["brier"]["table2"] == pytest.approx(0.0)
    md = (out / "results.md").read_text()
    assert "### By integration path" in md and "pools them" in md
    # the ros34pw2 samples alone: one path, no by_path part
    for s in (1, 2):
        (samples / f"A1.40_orb_s{s}.h5").unlink()
    assert main_study(["--samples", str(samples), "--out", str(out)]) == 0
    res = json.loads((out / "results.json").read_text())["samples"]
    assert "by_path" not in res and res["cells"][0]["samples"] == 2


def test_knotflow_study_samples_without_the_continued_ones(tmp_path):
    """Three samples of (1.4, b), one of them the continuation of a case from the ledger
    (`_from40`, its stepper restarted at t = 40): pooled 2 of 3; the uninterrupted table 1 of 2,
    with the continued sample and its time named; none continued, no such part."""
    import json

    from analysis_fixture import write_knots

    from knotflow_tools.cli import main_study

    from conftest import unknotting_trefoil_frames, write_case
    reknot = [0.98, 0.9, 0.05, 0.02, 0.95, 0.97, 0.96, 0.95]
    stays = [0.98, 0.9, 0.05, 0.02, 0.03, 0.01, 0.02, 0.02]
    t = np.arange(8) * 10.0
    samples = tmp_path / "samples"
    samples.mkdir()
    for name, kf in (("A1.40_orb_s1", reknot), ("A1.40_orb_s2", stays), ("A1.40_orb_s3_from40", reknot)):
        path = write_case(samples / f"{name}.h5", unknotting_trefoil_frames(8), time=t,
                          attrs={"forces.bending_a": 1.4, "chain.orientation": "b",
                                 "case_name": name, "scene": _path_scene("dopri45")})
        write_knots(path, np.arange(8), t, kf, np.zeros((8, 10)), ["3_1"] * 8, closures=10, seed=1)
    out = tmp_path / "out"
    assert main_study(["--samples", str(samples), "--out", str(out)]) == 0
    res = json.loads((out / "results.json").read_text())["samples"]
    (pooled,) = res["cells"]
    assert (pooled["samples"], pooled["transitions"]) == (3, 2)
    whole = res["uninterrupted"]
    assert whole["continued"] == [{"case": "A1.40_orb_s3_from40", "at": [40.0]}]
    (cell,) = whole["cells"]
    assert (cell["samples"], cell["transitions"], cell["uncertain"]) == (2, 1, True)
    assert whole["scores"]["brier"]["table2"] == pytest.approx(0.5)
    md = (out / "results.md").read_text()
    assert "### Without the samples continued from the case ledger" in md
    # each sample's events from its k_f series by the rule (below 0.1 untied, above 0.9
    # knotted, t = 10 k): the re-knotting ones untie at 20 and knot at 40, the other unties only
    per = {s["case"]: s for s in res["per_sample"]}
    assert sorted(per) == ["A1.40_orb_s1", "A1.40_orb_s2", "A1.40_orb_s3_from40"]
    for name in ("A1.40_orb_s1", "A1.40_orb_s3_from40"):
        assert per[name]["events"] == [["unknot", 20.0], ["knot", 40.0]]
        assert per[name]["max_kf_after_untie"] == pytest.approx(0.97)
        assert (per[name]["final_kf"], per[name]["final_state"]) == (pytest.approx(0.95), "knotted")
    assert per["A1.40_orb_s2"]["events"] == [["unknot", 20.0]]
    assert per["A1.40_orb_s2"]["max_kf_after_untie"] == pytest.approx(0.05)
    assert per["A1.40_orb_s2"]["final_state"] == "unknotted"
    assert per["A1.40_orb_s3_from40"]["continued_at"] == [40.0] and per["A1.40_orb_s1"]["continued_at"] == []
    assert "| A1.40_orb_s3_from40 | 1.4 | b | untied 20, knotted 40 | 0.97 | 0.95 | knotted | t = 40 |" in md
    (samples / "A1.40_orb_s3_from40.h5").unlink()
    assert main_study(["--samples", str(samples), "--out", str(out)]) == 0
    assert "uninterrupted" not in json.loads((out / "results.json").read_text())["samples"]


def test_knotflow_study_samples_scene_reference_completes_older_scenes(tmp_path):
    """Two samples on dopri45 'iterative', one scene without solver_tolerance (an older
    knotflow), one with it at 1e-6: two paths without --scene-reference, one with a reference
    whose default is 1e-6, two again with one whose default differs; the option is refused
    without --samples and with a file holding no scene variables."""
    import json

    from analysis_fixture import write_knots

    from knotflow_tools.cli import main_study

    from conftest import unknotting_trefoil_frames, write_case
    stays = [0.98, 0.9, 0.05, 0.02, 0.03, 0.01, 0.02, 0.02]
    t = np.arange(8) * 10.0
    samples = tmp_path / "samples"
    samples.mkdir()
    for s, scene in enumerate((_path_scene("dopri45"), _path_scene("dopri45", solver_tolerance="0.1E-5")),
                              start=1):
        path = write_case(samples / f"A1.40_orb_s{s}.h5", unknotting_trefoil_frames(8), time=t,
                          attrs={"forces.bending_a": 1.4, "chain.orientation": "b",
                                 "case_name": f"A1.40_orb_s{s}", "scene": scene})
        write_knots(path, np.arange(8), t, stays, np.zeros((8, 10)), ["3_1"] * 8, closures=10, seed=s)
    ref = tmp_path / "reference.md"
    out = tmp_path / "out"

    def paths(*extra):
        assert main_study(["--samples", str(samples), "--out", str(out), *extra]) == 0
        res = json.loads((out / "results.json").read_text())["samples"]
        return len(res.get("by_path", [None]))
    assert paths() == 2
    ref.write_text("## `&hydro`\n\n| variable | default |\n|---|---|\n"
                   "| `solver_tolerance` | `0.1E-5` | a number |\n")
    assert paths("--scene-reference", str(ref)) == 1
    ref.write_text(ref.read_text().replace("0.1E-5", "0.1E-3"))
    assert paths("--scene-reference", str(ref)) == 2
    with pytest.raises(SystemExit):
        main_study(["--rotations", str(samples), "--scene-reference", str(ref), "--out", str(out)])
    ref.write_text("no table here\n")
    with pytest.raises(SystemExit):
        main_study(["--samples", str(samples), "--scene-reference", str(ref), "--out", str(out)])
