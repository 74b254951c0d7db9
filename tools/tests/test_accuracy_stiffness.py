"""knotflow-accuracy-report --stiffness: the section on the step-size limit of docs/accuracy.md
from synthetic knotflow-bench-reuse stiffness outputs (key = value lines and per-trial rows),
between its own markers (appended the first time, replaced afterwards, the reuse block and the
rest of the report untouched), its figure, and a clear error without outputs."""

import pytest

from knotflow_tools import accuracy, cli

KEYS = """part = stiffness
config = trefoil
t_end = 50.0000
loadavg_start = 1.00 1.00 1.00 1/2 3
update = adaptive
stability_boundary = 3.307
steps = 3
rejected = 1
evaluations_per_time = 120.00
h_mean = 7.500E-02
lambda_min = 22.000
lambda_max = 41.000
lambda_mean = 35.000
lambda_h_mean_accepted = 2.900
lambda_h_max_accepted = 3.200
lambda_h_mean_rejected = 3.600
accepted_above_0.9_boundary = 2
error_over_tol_mean_accepted = 0.400
"""
ROWS = """# t h lambda lambda_h error_over_tol accepted lanczos_iterations
  0.000000E+00   1.0000E-03   -22.0000   0.0220   4.8066E-01 1  25
  1.000000E-03   9.0000E-02   -40.0000   3.6000   1.5000E+00 0   5
  1.000000E-03   8.0000E-02   -40.0000   3.2000   2.0000E-01 1   5
  8.100000E-02   7.5000E-02   -41.0000   3.0750   5.0000E-01 1   5
"""


def write_outputs(directory):
    (directory / "stiffness_trefoil.txt").write_text(KEYS)
    (directory / "stiffness_trefoil.dat").write_text(ROWS)


def test_read_trials(tmp_path):
    write_outputs(tmp_path)
    rows = accuracy.read_trials(str(tmp_path / "stiffness_trefoil.dat"))
    assert len(rows) == 4
    assert rows[1]["accepted"] == 0 and rows[1]["lambda_h"] == pytest.approx(0.09*40.0)


def test_section_appended_then_replaced(tmp_path):
    write_outputs(tmp_path)
    md = tmp_path / "accuracy.md"
    md.write_text("# Report\n\nbody\n\n%s\nreuse text\n%s\n" % (accuracy.REUSE_BEGIN,
                                                              accuracy.REUSE_END))
    figs = tmp_path / "figures"
    section = accuracy.update_stiffness(str(md), str(tmp_path), str(figs))
    assert ("| trefoil | 50.0000 | adaptive | 3 | 1 | 120.00 | 7.500E-02 | 22.000 / 35.000 / "
            "41.000 | 2.900 | 3.200 | 2 | 3.600 | 0.400 | 1.00 1.00 1.00 1/2 3 |") in section
    assert "![stiffness](figures/accuracy_stiffness.png)" in section
    assert "\\|λ_max\\| min / mean / max" in section   # pipes escaped in the table
    assert (figs / accuracy.STIFFNESS_FIGURE).stat().st_size > 0
    text = md.read_text()
    assert "reuse text" in text and text.startswith("# Report\n\nbody\n")
    assert text.count(accuracy.STIFFNESS_BEGIN) == 1
    (tmp_path / "stiffness_trefoil.txt").write_text(KEYS.replace("120.00", "99.00"))
    accuracy.update_stiffness(str(md), str(tmp_path), str(figs))
    text = md.read_text()
    assert "| 99.00 |" in text and "| 120.00 |" not in text
    assert text.count(accuracy.STIFFNESS_BEGIN) == 1 and "reuse text" in text


def test_cli_without_outputs(tmp_path, capsys):
    md = tmp_path / "accuracy.md"
    status = cli.main_accuracy_report(["--stiffness", str(tmp_path), "--markdown", str(md)])
    assert status != 0
    assert "no knotflow-bench-reuse stiffness outputs" in capsys.readouterr().err


def test_window_medians():
    rows = [{"t": 0.1*i, "h": 0.08, "lambda_h": 0.9*3.3, "error_over_tol": 1e-5*3.2**5,
             "accepted": 1} for i in range(20)]
    rows.append({"t": 0.5, "h": 1.0, "lambda_h": 9.0, "error_over_tol": 9.0, "accepted": 0})
    m = accuracy.window_medians(rows, 3.3, 0.2, 1.0)
    assert m["steps"] == 9    # t = 0.2 .. 1.0, the rejected trial left out
    assert m["lambda_h_over_boundary"] == pytest.approx(0.9)
    # error ~ h^5: the accuracy-limited step is h (1/err)^(1/5) = 0.08 * 10 / 3.2
    assert m["h_accuracy"] == pytest.approx(0.25)
    assert accuracy.window_medians(rows, 3.3, 5.0, 6.0) == {}


def test_tolerance_rows():
    # h ~ tol^(1/5) between 1e-5 and 1e-4 (accuracy), constant from 1e-4 to 1e-3 (stability)
    def trials(h):
        return [{"t": 0.5*i, "h": h, "lambda_h": 40*h, "error_over_tol": 0.17, "accepted": 1}
                for i in range(41)]
    runs = {"stiffness_a": {"config": "trefoil", "tolerance": "1.000E-05", "t_end": "10"},
            "stiffness_b": {"config": "trefoil", "t_end": "20"},   # no tolerance line: 1e-4
            "stiffness_c": {"config": "trefoil", "tolerance": "1.000E-03", "t_end": "10"},
            "stiffness_d": {"config": "coil", "tolerance": "1.000E-04", "t_end": "10"}}
    tables = {"a": trials(0.05), "b": trials(0.05*10**0.2), "c": trials(0.05*10**0.2),
              "d": trials(0.1)}
    rows = accuracy.tolerance_rows(runs, tables, 3.3)
    assert [r[1] for r in rows] == ["1e-05", "1e-04", "1e-03"]   # coil: one tolerance only
    assert rows[0][2] == "1–10" and rows[0][3] == "19"
    assert [r[-1] for r in rows] == ["–", "0.20", "0.00"]
