"""knotflow-rheology: knotted/unknotted and mode I/II intervals, their statistics and the
sign-flip test, on small synthetic case files whose answers are known exactly."""

import json
import math

import analysis_fixture as fixture
import h5py
import numpy as np
import pytest

from knotflow_tools import cli, rheology
from knotflow_tools.rheology import KNOTTED, MODE_I, MODE_II, UNKNOTTED

from conftest import unknotting_trefoil_frames, write_case


def test_classes_and_intervals():
    kf = [0.9, 0.8, 0.2, 0.1, 0.5, 0.4]
    classes = rheology.knot_classes(kf)
    assert classes == [KNOTTED, KNOTTED, UNKNOTTED, UNKNOTTED, KNOTTED, UNKNOTTED]
    assert rheology.intervals(classes) == [(KNOTTED, 0, 2), (UNKNOTTED, 2, 4), (KNOTTED, 4, 5),
                                           (UNKNOTTED, 5, 6)]
    # hysteresis (0.1, 0.9): undecided until 0.95, in-band frames keep the state
    hyst = rheology.knot_classes([0.5, 0.95, 0.5, 0.05, 0.5, 0.95], hysteresis=(0.1, 0.9))
    assert hyst == [None, KNOTTED, KNOTTED, UNKNOTTED, UNKNOTTED, KNOTTED]
    assert rheology.intervals(hyst) == [(KNOTTED, 1, 3), (UNKNOTTED, 3, 5), (KNOTTED, 5, 6)]
    modes = rheology.mode_classes([1, 1, 0, 1, 2, 2, 0])
    assert modes == [MODE_I, MODE_I, None, MODE_I, MODE_II, MODE_II, None]
    # an excluded frame separates two runs of the same class
    assert rheology.intervals(modes) == [(MODE_I, 0, 2), (MODE_I, 3, 4), (MODE_II, 4, 6)]
    assert rheology.intervals([]) == []


def test_class_statistics():
    classes = [KNOTTED, KNOTTED, UNKNOTTED, UNKNOTTED, KNOTTED, UNKNOTTED]
    st = rheology.class_statistics([1.0, 3.0, 10.0, 20.0, 5.0, 7.0], classes,
                                   (KNOTTED, UNKNOTTED, MODE_I))
    k, u = st[KNOTTED], st[UNKNOTTED]
    assert (k["frames"], k["intervals"], u["frames"], u["intervals"]) == (3, 2, 3, 2)
    assert k["mean"] == pytest.approx(3.0) and k["std"] == pytest.approx(math.sqrt(8.0 / 3.0))
    assert k["interval_mean"] == pytest.approx(3.5) and k["interval_std"] == pytest.approx(1.5)
    assert u["mean"] == pytest.approx(37.0 / 3.0)
    assert u["interval_mean"] == pytest.approx(11.0) and u["interval_std"] == pytest.approx(4.0)
    assert st[MODE_I]["frames"] == 0 and math.isnan(st[MODE_I]["mean"])


def test_sign_flip_exact_and_sampled():
    # 3 differences of one sign: only all + and all - reach |mean| = 2, so p = 2/8
    assert rheology.sign_flip_test([1.0, 2.0, 3.0]) == 0.25
    assert rheology.sign_flip_test([1.0, -1.0]) == 1.0          # mean 0: every assignment
    assert rheology.sign_flip_test([1.0, 1.0, -1.0]) == 1.0     # |mean| 1/3 is the smallest
    assert math.isnan(rheology.sign_flip_test([]))
    # above exact_up_to: 30 equal differences, exact p = 2^-29, sampled (0 + 1)/(samples + 1)
    assert rheology.sign_flip_test(np.ones(30), samples=999) == 1.0 / 1000.0
    # sampled against exact on the same data: within 4 binomial standard deviations
    d = np.random.default_rng(5).normal(0.4, 1.0, size=12)
    exact = rheology.sign_flip_test(d)
    sampled = rheology.sign_flip_test(d, exact_up_to=0, samples=40000, seed=3)
    assert abs(sampled - exact) < 4.0 * math.sqrt(exact * (1.0 - exact) / 40000) + 1e-4
    assert 0.0 < exact < 1.0


def make_case(path, a, kf, modes, shift):
    """A case with known answers: viscosity = 2 + shift in knotted (k_f >= 0.5) and in mode I
    frames' counterpart as set below, psi1 = -frame index, psi2 = 1."""
    n = len(kf)
    path = write_case(path, unknotting_trefoil_frames(n), attrs={"forces.bending_a": a})
    kf = np.asarray(kf, dtype=float)
    knotted = kf >= 0.5
    with h5py.File(path, "a") as f:
        g = f["frames"].create_group("stresslet")
        g["hydrodynamic"] = np.zeros((n, 3, 3))
        g["elastic"] = np.zeros((n, 3, 3))
        g["viscosity"] = 2.0 + shift * knotted
        g["psi1"] = -np.arange(n, dtype=float)
        g["psi2"] = np.ones(n)
    fixture.write_knots(path, np.arange(n), np.arange(n, dtype=float), kf, np.zeros((n, 10)),
                   ["0_1"] * n, closures=10, seed=1)
    fixture.write_modes(path, modes, case_mode=0)
    return path


def test_compare_cases_known_answer(tmp_path):
    kf = [0.98, 0.9, 0.7, 0.3, 0.1, 0.6, 0.2, 0.05]
    modes = [1, 1, 0, 2, 2, 1, 0, 2]
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    for a, shift in ((1.0, 1.0), (2.0, 2.0), (3.0, 3.0)):
        make_case(sweep / f"A{a:.2f}.h5", a, kf, modes, shift)
    res = rheology.write_rheology([str(sweep)], [str(sweep)], str(tmp_path / "out"))
    knot = res["knot"]
    for r, shift in zip(knot["cases"], (1.0, 2.0, 3.0)):
        v = r["series"]["viscosity"]
        assert (v[KNOTTED]["frames"], v[KNOTTED]["intervals"]) == (4, 2)
        assert (v[UNKNOTTED]["frames"], v[UNKNOTTED]["intervals"]) == (4, 2)
        assert v["difference"] == pytest.approx(shift)
        # psi1 = -k: knotted frames 0, 1, 2, 5 and unknotted 3, 4, 6, 7
        assert r["series"]["psi1"]["difference"] == pytest.approx(-8.0 / 4 + 20.0 / 4)
        assert r["series"]["psi2"]["difference"] == 0.0
    v = knot["all"]["viscosity"]
    assert v["paired_cases"] == 3 and v["positive"] == 3
    assert v["difference_mean"] == pytest.approx(2.0)
    assert v["difference_std"] == pytest.approx(1.0)
    assert v["p_value"] == 0.25
    assert v[KNOTTED]["frames"] == 12 and v[KNOTTED]["intervals"] == 6
    assert v[KNOTTED]["mean"] == pytest.approx(4.0) and v[UNKNOTTED]["mean"] == 2.0
    assert knot["all"]["psi2"]["p_value"] == 1.0
    # by stiffness: one case per A, so Δ_A = the case's Δ
    assert v["paired_stiffnesses"] == 3 and v["stiffness_difference_mean"] == pytest.approx(2.0)
    assert v["stiffness_p_value"] == 0.25
    # modes: I at frames 0, 1, 5; II at 3, 4, 7 (2 intervals each)
    mode = res["mode"]["all"]["psi1"]
    assert mode[MODE_I]["frames"] == 9 and mode[MODE_I]["intervals"] == 6
    assert mode[MODE_II]["intervals"] == 6
    assert mode["difference_mean"] == pytest.approx(-2.0 + 14.0 / 3.0)
    md = (tmp_path / "out" / "rheology.md").read_text()
    assert "| A1.00 | 4 / 2 | 4 / 2 | 3 ± 0 | 2 ± 0 | 1 |" in md
    assert ("| viscosity | 3 / 6 / 12 | 4 ± 0.82 | 3 / 6 / 12 | 2 ± 0 | 3 | 2 ± 1 | 3 of 3 | "
            "0.25 |") in md
    assert (tmp_path / "out" / "rheology_vs_kf.png").stat().st_size > 1000
    assert (tmp_path / "out" / "rheology_vs_mode.png").stat().st_size > 1000
    assert "![viscosity against time](rheology_time.png)" in md
    with open(tmp_path / "out" / "rheology.json", encoding="utf-8") as fh:
        assert json.load(fh)["knot"]["all"]["viscosity"]["p_value"] == 0.25
    # t_from leaves out the first 3 frames: knotted frames 5 only (one interval)
    late = rheology.write_rheology([str(sweep)], [], str(tmp_path / "late"), t_from=3.0)
    v = late["knot"]["cases"][0]["series"]["viscosity"]
    assert (v[KNOTTED]["frames"], v[KNOTTED]["intervals"], v[UNKNOTTED]["intervals"]) == (1, 1, 2)


def test_stiffness_differences(tmp_path):
    """A chain that stays knotted against its sibling that is never knotted (same A): no case
    has both classes, the stiffness comparison has them."""
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    make_case(sweep / "A1_knotted.h5", 1.0, [0.9] * 4, [1] * 4, 3.0)
    make_case(sweep / "A1_open.h5", 1.0, [0.1] * 4, [1] * 4, 3.0)
    make_case(sweep / "A2_both.h5", 2.0, [0.9, 0.9, 0.9, 0.1], [1] * 4, -1.0)
    res = rheology.write_rheology([str(sweep)], [], str(tmp_path / "out"))
    v = res["knot"]["all"]["viscosity"]
    assert v["paired_cases"] == 1 and v["difference_mean"] == pytest.approx(-1.0)
    # A = 1: knotted frames 5, unknotted 2 (Δ = 3); A = 2: Δ = -1
    assert v["paired_stiffnesses"] == 2 and v["stiffness_positive"] == 1
    assert v["stiffness_difference_mean"] == pytest.approx(1.0)
    assert v["stiffness_difference_std"] == pytest.approx(math.sqrt(8.0))
    assert v["stiffness_p_value"] == 1.0     # |mean| of every sign assignment of (3, -1) >= 1
    md = (tmp_path / "out" / "rheology.md").read_text()
    assert "| viscosity | 2 | 1 ± 2.8 | 1 of 2 | 1 |" in md


def test_cli_and_errors(tmp_path, capsys):
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    make_case(sweep / "A1.00.h5", 1.0, [0.9, 0.9, 0.1, 0.1], [1, 1, 2, 2], 0.5)
    out = tmp_path / "out"
    assert cli.main_rheology(["--knots", str(sweep), "--out", str(out)]) == 0
    assert "knotted - unknotted: viscosity difference 0.5 over 1 case(s), p = 1" in \
        capsys.readouterr().out
    bare = tmp_path / "bare"
    bare.mkdir()
    write_case(bare / "plain.h5", unknotting_trefoil_frames(3))
    assert cli.main_rheology(["--knots", str(bare), "--out", str(out)]) == 2
    assert "plain.h5: no /frames/stresslet" in capsys.readouterr().err
    with h5py.File(sweep / "A1.00.h5", "a") as f:
        del f["analysis/knots"]
    assert cli.main_rheology(["--knots", str(sweep), "--out", str(out)]) == 2
    assert "A1.00.h5: no /analysis/knots (run knotflow-analyze" in capsys.readouterr().err
    for bad in (["--out", str(out)], ["--knots", str(tmp_path / "missing")],
                ["--knots", str(sweep), "--threshold", "0"],
                ["--knots", str(sweep), "--hysteresis", "0.9", "0.1"]):
        with pytest.raises(SystemExit) as exc:
            cli.main_rheology(bad)
        assert exc.value.code == 2


def test_a_case_ledger_gives_the_answer_of_its_case_files(tmp_path):
    """knotflow-rheology on one sweep of a case ledger (knotflow-campaign digest of the case
    files: k_f, modes and the stresslet's series per frame row) gives the comparison of the case
    files themselves, and names the models the cases ran with."""
    from knotflow_tools import campaign
    kf = [0.98, 0.9, 0.7, 0.3, 0.1, 0.6, 0.2, 0.05]
    modes = [1, 1, 0, 2, 2, 1, 0, 2]
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    ledger = tmp_path / "ledger"
    for a, shift in ((1.0, 1.0), (2.0, 2.0), (3.0, 3.0)):
        path = make_case(sweep / f"A{a:.2f}.h5", a, kf, modes, shift)
        with h5py.File(path, "a") as f:
            f.attrs["hydro.model"] = "multipole"
            f.attrs["hydro.overlap"] = "relax"
            f.attrs["scene"] = (f"&forces\n  bending_a = {a!r}\n/\n"
                                "&hydro\n  model = 'multipole'\n  overlap = 'relax'\n/\n")
        campaign.digest(str(path), str(ledger), "sw", 10)
    direct = rheology.write_rheology([str(sweep)], [str(sweep)], str(tmp_path / "direct"))
    via = rheology.write_rheology([str(ledger / "sw")], [str(ledger / "sw")], str(tmp_path / "via"))
    for by in ("knot", "mode"):
        for name in ("viscosity", "psi1", "psi2"):
            d, v = direct[by]["all"][name], via[by]["all"][name]
            assert v["difference_mean"] == pytest.approx(d["difference_mean"], rel=1e-6, abs=1e-9)
            assert v["paired_cases"] == d["paired_cases"] == 3
    md = (tmp_path / "via" / "rheology.md").read_text()
    assert "Models: multipole with overlap = 'relax' (3 cases)." in md


def scene_text(shape="trefoil", a=1.0, seed=1, rotation="random", method="dopri45"):
    """A scene text as the program echoes it (kf_scene_items), the variables sample_cell reads."""
    return (f"&chain\n  shape = '{shape}'\n  orientation = 'c'\n  seed = {seed}\n"
            f"  candycane_rotation = '{rotation}'\n  tilt_deg = 30.000000000000000\n"
            "  perturbation = 0.99999999999999995E-6\n/\n"
            f"&forces\n  bending_a = {a!r}\n/\n&hydro\n  model = 'multipole'\n  overlap = 'relax'\n/\n"
            f"&integrator\n  method = '{method}'\n/\n&output\n  case_name = 'x{seed}'\n/\n")


def test_sample_cell_leaves_out_only_a_perturbation_seed():
    from knotflow_tools.campaign import sample_cell
    one = sample_cell(scene_text(seed=1))
    assert one == sample_cell(scene_text(seed=2))                      # trefoil: a perturbation
    assert one == sample_cell(scene_text(seed=2, method="ros34pw2"))   # the stepper is no cell
    assert one != sample_cell(scene_text(a=1.4))
    # a candy-cane's random rotation is drawn from the seed: each seed its own start
    assert (sample_cell(scene_text("candycane", seed=1))
            != sample_cell(scene_text("candycane", seed=2)))
    # tilted about x, the seed draws only the perturbation
    assert (sample_cell(scene_text("candycane", seed=1, rotation="tilt_x"))
            == sample_cell(scene_text("candycane", seed=2, rotation="tilt_x")))


def test_sample_start_is_the_cell_without_the_model():
    from knotflow_tools.campaign import sample_cell, sample_start
    multipole = scene_text("candycane", seed=13)
    rpy = multipole.replace("model = 'multipole'\n  overlap = 'relax'", "model = 'rpy'")
    assert rpy != multipole
    assert sample_start(rpy) == sample_start(multipole)      # one start, two models
    assert sample_cell(rpy) != sample_cell(multipole)        # two cells
    assert sample_start(multipole) != sample_start(scene_text("candycane", seed=14))
    assert sample_start(multipole) != sample_start(scene_text("candycane", seed=13, a=3.0))
    # a trefoil's seed draws only the perturbation: one start
    assert sample_start(scene_text(seed=1)) == sample_start(scene_text(seed=2))


def test_cells_pool_their_samples(tmp_path):
    """Two samples of one cell (seeds 1, 2: viscosity shifts 3 and 1 in the knotted frames) and
    one of another (shift -1): three case differences 3, 1, -1, but two cell differences,
    (3 + 1)/2 = 2 (equal frame counts) and -1, whose sign-flip p over 2 cells is 1."""
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    kf = [0.9, 0.9, 0.9, 0.9, 0.1, 0.1, 0.1, 0.1]
    for name, a, seed, shift in (("A1_s1", 1.0, 1, 3.0), ("A1_s2", 1.0, 2, 1.0),
                                 ("A2_s1", 2.0, 1, -1.0)):
        path = make_case(sweep / f"{name}.h5", a, kf, [1] * 8, shift)
        with h5py.File(path, "a") as f:
            f.attrs["scene"] = scene_text(a=a, seed=seed)
    res = rheology.write_rheology([str(sweep)], [], str(tmp_path / "out"))
    v = res["knot"]["all"]["viscosity"]
    assert v["paired_cases"] == 3 and v["difference_mean"] == pytest.approx(1.0)
    assert v["cells"] == 2 and v["paired_cells"] == 2 and v["cell_positive"] == 1
    assert v["cell_difference_mean"] == pytest.approx(0.5)
    assert v["cell_difference_std"] == pytest.approx(math.sqrt(4.5))
    assert v["cell_p_value"] == 1.0
    assert [c["cell"] for c in res["knot"]["cases"]] == ["trefoil, A = 1, orientation c"] * 2 + [
        "trefoil, A = 2, orientation c"]
    md = (tmp_path / "out" / "rheology.md").read_text()
    assert "| trefoil, A = 1, orientation c | 2 | 2 |" in md
    assert "| viscosity | 2 / 2 | 0.5 ± 2.1 | 1 of 2 | 1 |" in md


def test_finished_only_leaves_out_a_running_case(tmp_path, capsys):
    """--finished: a case whose status is not 'finished' is left out and named; without it the
    case counts."""
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    kf = [0.9, 0.9, 0.1, 0.1]
    for name, shift, status in (("A1", 1.0, "finished"), ("A2", 3.0, "running")):
        path = make_case(sweep / f"{name}.h5", float(name[1]), kf, [1] * 4, shift)
        with h5py.File(path, "a") as f:
            f.attrs["status"] = status
            f.attrs["case_name"] = name
    out = tmp_path / "out"
    assert cli.main_rheology(["--knots", str(sweep), "--out", str(out)]) == 0
    assert "viscosity difference 2 over 2 case(s)" in capsys.readouterr().out
    assert cli.main_rheology(["--knots", str(sweep), "--out", str(out), "--finished"]) == 0
    assert "viscosity difference 1 over 1 case(s)" in capsys.readouterr().out
    assert "Left out, not finished: A2." in (out / "rheology.md").read_text()
