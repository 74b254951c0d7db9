"""Run diagnostics in case files: read when present (per-frame datasets and run totals),
absent from older files without any error, and shown in the report's table."""

import h5py
import numpy as np

from knotflow_tools import io, report

from conftest import unknotting_trefoil_frames, write_case


def add_diagnostics(path, positions, passages, episodes, totals):
    """Add /frames/diagnostics as knotflow writes it; the per-frame geometric values are
    computed here from the positions (pairs closer than 1, smallest |i-j| > 1 distance,
    largest |l - 1.02|/1.02)."""
    d = np.linalg.norm(positions[:, :, None, :] - positions[:, None, :, :], axis=-1)
    n = positions.shape[1]
    i, j = np.triu_indices(n, 1)
    far = (j - i) > 1
    bonds = np.linalg.norm(np.diff(positions, axis=1), axis=-1)
    with h5py.File(path, "a") as f:
        g = f["frames"].create_group("diagnostics")
        g["strand_passages"] = np.asarray(passages, dtype=np.int64)
        g["overlapping_pairs"] = (d[:, i, j] < 1.0).sum(axis=1).astype(np.int32)
        g["overlap_episodes"] = np.asarray(episodes, dtype=np.int64)
        g["min_distance"] = d[:, i[far], j[far]].min(axis=1)
        g["max_bond_strain"] = np.abs(bonds - 1.02).max(axis=1) / 1.02
        for k, v in totals.items():
            f.attrs["diagnostics." + k] = v


TOTALS = {"strand_passages": np.int64(3), "first_passage_time": 2.5,
          "overlap_episodes": np.int64(17), "overlap_mean_duration": 0.25,
          "overlap_max_duration": 1.5, "max_overlapping_pairs": np.int32(4),
          "min_distance": 0.8, "max_bond_strain": 0.03}


def test_read_with_and_without_diagnostics(tmp_path):
    frames = unknotting_trefoil_frames(5)
    plain = write_case(tmp_path / "plain.h5", frames)
    case = io.read_case(plain)
    assert case.diagnostics is None and case.diagnostic_totals is None
    diag = write_case(tmp_path / "diag.h5", frames)
    add_diagnostics(diag, frames, [0, 0, 1, 3, 3], [0, 2, 5, 9, 17], TOTALS)
    with h5py.File(diag, "a") as f:            # a killed run: one frame beyond the checkpoint
        f["checkpoint/nframes"][()] = 4
    case = io.read_case(diag)
    assert set(case.diagnostics) == set(io.DIAGNOSTICS)
    assert all(len(v) == 4 for v in case.diagnostics.values())
    assert list(case.diagnostics["strand_passages"]) == [0, 0, 1, 3]
    assert list(case.diagnostics["overlap_episodes"]) == [0, 2, 5, 9]
    assert case.diagnostics["overlapping_pairs"].dtype == np.int32
    # the first frame is the tailed trefoil, opened by removing one bead of a closed polygon of
    # bonds 1.02: the gap spans two bonds, a chord of about 2 x 1.02, so the strain is about 1
    assert abs(case.diagnostics["max_bond_strain"][0] - 1.0) < 0.01
    assert case.diagnostic_totals == {k: (v.item() if hasattr(v, "item") else v)
                                      for k, v in TOTALS.items()}


def test_report_shows_diagnostics(tmp_path):
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    frames = unknotting_trefoil_frames(4)
    write_case(sweep / "old.h5", frames)
    new = write_case(sweep / "new.h5", frames)
    add_diagnostics(new, frames, [0, 1, 2, 3], [0, 5, 10, 17], TOTALS)
    out = report.build_report(str(sweep), closures=10)
    rows = {r["name"]: r for r in out["rows"]}
    assert rows["new"]["strand_passages"] == 3 and rows["new"]["overlap_episodes"] == 17
    assert rows["old"]["strand_passages"] is None
    with open(out["md"], encoding="utf-8") as fh:
        md = fh.read()
    with open(out["html"], encoding="utf-8") as fh:
        html = fh.read()
    assert "| strand passages | overlap episodes |" in md
    line_new = next(line for line in md.splitlines() if line.startswith("| new |"))
    line_old = next(line for line in md.splitlines() if line.startswith("| old |"))
    assert line_new.endswith("| 3 | 17 |") and line_old.endswith("| - | - |")
    assert "<th>strand passages</th>" in html
