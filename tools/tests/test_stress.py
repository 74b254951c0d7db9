"""knotflow-stress-summary: the row of a case with run diagnostics takes the recorded totals;
without them the geometric columns come from the frames (checked against hand-made
configurations) and the step counters are n/a; wall times, status and the Markdown file."""

import h5py
import numpy as np

from knotflow_tools import cli, stress

from conftest import write_case


def two_strands(gap):
    """Two parallel 6-bead strands (bonds 1.02) joined at one end, `gap` apart: bead i faces
    bead 11 - i; (5, 6) is the joining bond, of length `gap`. The closest non-bonded distance
    is `gap` (the 5 other facing pairs); diagonal pairs are sqrt(1.02^2 + gap^2) apart."""
    x = 1.02 * np.arange(6)
    a = np.c_[x, np.zeros(6), np.zeros(6)]
    b = np.c_[x[::-1], np.full(6, gap), np.zeros(6)]
    return np.vstack([a, b])


def test_frames_fallback(tmp_path):
    frames = np.stack([two_strands(1.5), two_strands(0.8)])
    path = write_case(tmp_path / "hp.h5", frames, time=[0.0, 1.0], observables=False,
                      attrs={"case_name": "hp", "integrator.t_end": 1.0, "chain.bond_length": 1.02})
    row = stress.summarise_case(path, {"hp": 12.5})
    assert row["source"] == "frames"
    # the 5 non-bonded facing pairs + the joining bond (length 0.8) are closer than 1;
    # diagonal pairs are at sqrt(1.02^2 + 0.64) = 1.30
    assert row["max_overlapping_pairs"] == 6
    # non-bonded minimum: the facing pairs at 0.8 (the joining bond is bonded and excluded)
    assert abs(row["min_distance"] - 0.8) < 1e-12
    # the joining bond is the only strained one: 1.5 (frame 0) and 0.8 (frame 1) against
    # l0 = 1.02; the larger strain is frame 0's
    assert abs(row["max_bond_strain"] - (1.5 - 1.02) / 1.02) < 1e-12
    assert row["strand_passages"] is None and row["overlap_episodes"] is None
    assert row["steps"] == 10 and row["rejected"] == 0     # conftest: 10 steps per frame
    assert row["wall_s"] == 12.5 and row["status"] == "finished"
    assert row["t"] == "1 / 1"
    table = stress.format_table([row])
    assert "| 6 f |" in table and "| n/a |" in table


def test_recorded_totals_win(tmp_path):
    frames = np.stack([two_strands(1.5), two_strands(1.5)])
    path = write_case(tmp_path / "d.h5", frames, observables=False, status="failed: Cholesky",
                      attrs={"case_name": "d", "integrator.t_end": 5.0})
    totals = {"strand_passages": np.int64(2), "first_passage_time": 0.75,
              "overlap_episodes": np.int64(9), "overlap_mean_duration": 0.125,
              "overlap_max_duration": 0.5, "max_overlapping_pairs": np.int32(3),
              "min_distance": 0.61, "max_bond_strain": 0.02}
    with h5py.File(path, "a") as f:
        for k, v in totals.items():
            f.attrs["diagnostics." + k] = v
    row = stress.summarise_case(path)
    assert row["source"] == "steps"
    # the recorded values, not the frames' (which have no overlaps and min distance 1.5)
    assert row["max_overlapping_pairs"] == 3 and row["min_distance"] == 0.61
    assert row["strand_passages"] == 2 and row["first_passage_time"] == 0.75
    assert row["status"] == "failed: Cholesky" and row["wall_s"] is None
    assert row["t"] == "1 / 5"
    table = stress.format_table([row])
    assert "| 2 | 0.75 | 9 | 0.125 | 0.5 | 3 | 0.61 | 0.02 | failed: Cholesky |" in table
    # no passage recorded: first passage time -1 is shown as "none"
    row["first_passage_time"] = -1.0
    assert "| none |" in stress.format_table([row])


def test_main_writes_markdown(tmp_path, capsys):
    frames = np.stack([two_strands(1.5)] * 3)
    write_case(tmp_path / "b.h5", frames, observables=False, attrs={"case_name": "b"})
    write_case(tmp_path / "a.h5", frames, observables=False, attrs={"case_name": "a"})
    wall = tmp_path / "wall.txt"
    wall.write_text("# case seconds\na 1.5\nb 20\n")
    out = tmp_path / "summary.md"
    assert cli.main_stress_summary([str(tmp_path), "--wall-times", str(wall), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    text = out.read_text()
    assert text.startswith("# knotflow stress runs")
    assert printed in text
    rows = [line for line in printed.splitlines() if line.startswith("| a") or line.startswith("| b")]
    assert [r.split("|")[1].strip() for r in rows] == ["a", "b"]       # sorted by file name
    assert rows[0].split("|")[2].strip() == "1.5" and rows[1].split("|")[2].strip() == "20"
    assert cli.main_stress_summary([str(tmp_path / "empty_dir_missing")]) == 2
