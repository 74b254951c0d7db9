"""The Python tools use the library for knots and shape (knotflow_tools.analysis, .shape): their
results equal knotflow-analyze's on a case file and the numpy oracle's."""

import importlib.util
from pathlib import Path

import h5py
import numpy as np
import pytest

from knotflow_tools import analysis, io
from knotflow_tools import shape as tools_shape

from conftest import run

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
