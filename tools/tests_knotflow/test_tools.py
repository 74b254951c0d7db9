"""The Python tools use the library for knots and shape (knotflow_tools.analysis, .shape): their
results equal knotflow-analyze's on a case file and the numpy oracle's."""

import importlib.util
import json
import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest

from knotflow_tools import analysis, io
from knotflow_tools import shape as tools_shape

from conftest import program, run

# the synthetic case files of the tools' tests (knotflow's HDF5 schema)
_spec = importlib.util.spec_from_file_location(
    "tools_tests_conftest", Path(__file__).resolve().parents[1] / "tests" / "conftest.py")
assert _spec is not None and _spec.loader is not None
tools_conftest = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(tools_conftest)


@pytest.mark.parametrize("seed", [7, 123456789])
def test_computed_kf_equals_knotflow_analyze(tmp_path, seed):
    frames = tools_conftest.unknotting_trefoil_frames(6)
    ours = tools_conftest.write_case(tmp_path / "ours_A1_a.h5", frames, time=np.linspace(0.0, 50.0, 6))
    theirs = tools_conftest.write_case(tmp_path / "theirs_A1_a.h5", frames, time=np.linspace(0.0, 50.0, 6))
    run("knotflow-analyze", str(theirs), "--closures", "100", "--seed", str(seed))
    with h5py.File(theirs, "r") as f:
        expected = f["analysis/knots/kf"][:]
        expected_spectrum = f["analysis/knots/spectrum"][:]
        assert np.array_equal(f["analysis/knots/frame_index"][:], np.arange(6))
    ana = analysis.analyze_case(io.read_case(str(ours)), closures=100, stride=1, seed=seed, use_stored=False)
    assert ana.kf_source == "computed"
    assert np.array_equal(ana.kf, expected)
    kf, spectrum, _ = analysis.knot_series(frames, np.arange(6), closures=100, seed=seed)
    assert np.array_equal(kf, expected) and np.array_equal(spectrum, expected_spectrum)
    assert expected[0] > 0.5 and expected[-1] == 0.0


def test_shape_series_is_the_library_and_agrees_with_the_oracle(trefoil, cluster):
    series = tools_shape.shape_series(np.stack([trefoil, trefoil[::-1] + 1.0]))
    for k, r in enumerate((trefoil, trefoil[::-1] + 1.0)):
        oracle = tools_shape.compute_shape(r)
        for name in ("rg", "a", "b", "c", "theta", "phi"):
            assert series[name][k] == pytest.approx(getattr(oracle, name), rel=1e-10, abs=1e-12), name
        assert series["close_pairs"][k] == oracle.close_pairs
    with pytest.raises(ValueError, match="at least 2 needed"):
        tools_shape.shape_series(np.zeros((1, 1, 3)))


def test_knotflow_kf_equals_knotflow_analyze(tmp_path, capsys):
    """knotflow-kf (the library's knots and knot matrix) prints knotflow-analyze's k_f, spectrum,
    closures, knot matrix, core and slipknot for the same seed, to the last bit."""
    from knotflow_tools import cli
    r = tools_conftest.unknotting_trefoil_frames(4)[0]
    path = tmp_path / "chain.xyz"
    path.write_text("".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in r.tolist()))
    args = ["--closures", "60", "--seed", "31", "--json", "--per-closure", "--matrix",
            "--matrix-closures", "3", "--min-length", str(len(r) - 12)]
    expected = json.loads(run("knotflow-analyze", str(path), *args))
    assert cli.main_kf([str(path), *args]) == 0
    got = json.loads(capsys.readouterr().out)
    for key in ("n_beads", "closures", "seed", "kf", "spectrum", "dominant", "per_closure", "matrix",
                "knot_core", "slipknot"):
        assert got[key] == expected[key], key
    assert got["kf"] > 0.5 and got["knot_core"] is not None


def test_default_seed_is_knotflow_analyze_s(tmp_path, capsys):
    """Without --seed, knotflow-kf and the tools' analysis draw knotflow-analyze's closures: the
    same closure types one by one, and the same k_f series of a case file."""
    from knotflow_tools import cli
    frames = tools_conftest.unknotting_trefoil_frames(4)
    path = tmp_path / "chain.xyz"
    path.write_text("".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in frames[0].tolist()))
    expected = json.loads(run("knotflow-analyze", str(path), "--closures", "40", "--json",
                              "--per-closure"))
    assert cli.main_kf([str(path), "--closures", "40", "--json", "--per-closure"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["seed"] == expected["seed"] and got["per_closure"] == expected["per_closure"]
    # a seed that differs from the default draws other closures (the check above can fail)
    other = json.loads(run("knotflow-analyze", str(path), "--closures", "40", "--json",
                           "--per-closure", "--seed", str(expected["seed"] + 1)))
    assert other["per_closure"] != expected["per_closure"]
    theirs = tools_conftest.write_case(tmp_path / "theirs_A1_a.h5", frames, time=np.linspace(0.0, 3.0, 4))
    run("knotflow-analyze", str(theirs), "--closures", "50")
    with h5py.File(theirs, "r") as f:
        kf = f["analysis/knots/kf"][:]
    ana = analysis.analyze_case(io.read_case(str(theirs)), closures=50, stride=1, use_stored=False)
    assert np.array_equal(ana.kf, kf)


def test_knotflow_analyze_refuses_a_frame_too_far_apart(tmp_path):
    """A case file whose frame 2 has beads so far apart that their squared distances overflow is
    refused by knotflow-analyze, naming the file and the frame, and nothing is written to it."""
    frames = tools_conftest.unknotting_trefoil_frames(4)
    frames[2, 5, 0] = 1.0e300
    path = tools_conftest.write_case(tmp_path / "far_A1_a.h5", frames, time=np.linspace(0.0, 3.0, 4),
                                     observables=False)
    before = path.read_bytes()
    done = subprocess.run([program("knotflow-analyze"), str(path), "--closures", "10"],
                          capture_output=True, text=True, check=False)
    assert done.returncode != 0
    assert (f"case file '{path}': frame 2 (t = 2.00000): the beads are too far apart: their squared "
            "distances overflow") in done.stderr
    assert path.read_bytes() == before


def test_tools_knot_matrix_equals_knotflow_analyze(tmp_path):
    """knotflow_tools.analysis computes a frame's knot matrix with the library: equal to
    knotflow-analyze --matrix-frames on the same case file and seed."""
    frames = tools_conftest.unknotting_trefoil_frames(3)
    theirs = tools_conftest.write_case(tmp_path / "theirs_A1_a.h5", frames, time=np.linspace(0.0, 2.0, 3))
    ours = tools_conftest.write_case(tmp_path / "ours_A1_a.h5", frames, time=np.linspace(0.0, 2.0, 3))
    n = frames.shape[1]
    run("knotflow-analyze", str(theirs), "--closures", "10", "--seed", "5", "--matrix-frames", "0",
        "--matrix-closures", "3", "--min-length", str(n - 10))
    expected = io.read_case(str(theirs)).knot_matrices[0]
    ana = analysis.analyze_case(io.read_case(str(ours)), closures=10, stride=1, seed=5, matrix_frames=[0],
                                matrix_closures=3, matrix_stride=1, min_length=n - 10, use_stored=False)
    assert np.array_equal(ana.knot_matrices[0], expected, equal_nan=True)
    assert np.isfinite(expected).sum() == 11 * 12 // 2 and np.nanmax(expected) > 0.5
