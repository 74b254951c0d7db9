"""Reading synthetic case files and text coordinate files; writing /analysis."""

import analysis_fixture as fixture
import h5py
import numpy as np
import pytest

from knotflow_tools import io
from knotflow_tools.knots import KNOT_TYPES
from knotflow_tools.transitions import Event

from conftest import write_case
from helpers import open_trefoil


def test_read_case_schema(tmp_path):
    pos = np.stack([open_trefoil() + k for k in range(3)])
    path = write_case(tmp_path / "c.h5", pos, time=[0.0, 0.5, 1.0],
                      attrs={"forces.bending_a": 2.5, "chain.orientation": "d"})
    case = io.read_case(path)
    assert case.positions.shape == (3, 99, 3)
    assert np.array_equal(case.positions, pos)
    assert case.bending_a == 2.5 and case.orientation == "d"
    assert case.status == "finished" and case.name == "c"
    assert case.attrs["n_beads"] == 99
    assert np.allclose(case.attrs["chain.rotation"], np.eye(3))
    assert set(case.observables) == set(io.OBSERVABLES)
    assert case.knots is None and case.events is None


def test_read_case_truncates_to_checkpoint(tmp_path):
    pos = np.stack([open_trefoil() + k for k in range(4)])
    path = write_case(tmp_path / "c.h5", pos)
    with h5py.File(path, "a") as f:
        f["checkpoint/nframes"][()] = 3
    assert io.read_case(path).nframes == 3


def test_read_case_truncates_to_newest_slot(tmp_path):
    """Schema 3: two checkpoint slots written alternately; the frames counted by the newer one
    are complete, a frame beyond it was being written when the run stopped."""
    pos = np.stack([open_trefoil() + k for k in range(5)])
    path = write_case(tmp_path / "c.h5", pos)
    with h5py.File(path, "a") as f:
        del f["checkpoint"]
        f["checkpoint/slot0/nframes"] = np.int64(4)
        f["checkpoint/slot1/nframes"] = np.int64(3)
        f.attrs["schema_version"] = np.int32(3)
    assert io.read_case(path).nframes == 4
    with h5py.File(path, "a") as f:
        f["checkpoint/slot1/nframes"][()] = 5
    assert io.read_case(path).nframes == 5


def test_write_and_read_analysis(tmp_path):
    pos = np.stack([open_trefoil()] * 3)
    path = str(write_case(tmp_path / "c.h5", pos))
    spec = np.zeros((3, len(KNOT_TYPES)))
    spec[:, 1] = [1.0, 0.5, 0.0]
    spec[:, 0] = 1 - spec[:, 1]
    fixture.write_knots(path, [0, 1, 2], [0.0, 1.0, 2.0], spec[:, 1], spec, ["3_1", "0_1", "0_1"],
                   100, 7)
    fixture.write_events(path, [Event("unknot", 2, 2.0)], 0.1, 0.9)
    fixture.write_knot_matrix(path, 2, np.full((99, 99), np.nan), 20, 10, 2.0)
    fixture.write_modes(path, [0, 1, 1], 1)
    case = io.read_case(path)
    assert list(case.knots["kf"]) == [1.0, 0.5, 0.0]
    assert case.knots["dominant"] == ["3_1", "0_1", "0_1"]
    assert case.knots["types"] == list(KNOT_TYPES)
    assert case.knots["attrs"]["closures"] == 100 and case.knots["attrs"]["seed"] == 7
    assert case.events["kind"] == ["unknot"] and list(case.events["frame_index"]) == [2]
    assert case.events["attrs"]["low"] == 0.1
    assert list(case.knot_matrices) == [2]
    assert list(case.modes) == [0, 1, 1] and case.case_mode == 1


def test_xyz_roundtrip_and_comments(tmp_path):
    r = open_trefoil()
    p = tmp_path / "chain.xyz"
    io.write_xyz(p, r, comment="open trefoil\nN = 99")
    text = p.read_text()
    assert text.startswith("# open trefoil\n# N = 99\n")
    p.write_text(text + "\n\n# trailing comment\n")
    assert np.array_equal(io.read_xyz(p), r)
    bad = tmp_path / "bad.xyz"
    bad.write_text("1 2\n")
    with pytest.raises(ValueError):
        io.read_xyz(bad)
