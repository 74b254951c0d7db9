"""knotflow-accuracy-report on small synthetic tables: markdown tables with the given numbers,
PNG figures, the README block replaced (and nothing else), and clear errors."""

import os

import pytest

from knotflow_tools import accuracy, cli

META = ("key,value\nquick,0\nref_order,3\nbending_a_models,1.40\ncoil_file,c.xyz\n"
        "loadavg_start,0.50 0.40 0.30 1/2 3\n")
MODELS = """config,n,model,order,lubrication,rms_rel,max_rel,rms_force,rms_shear,t_eval,n_evals,status
trefoil,99,none,0,0,9.90000E-01,9.20000E-01,6.80000E-01,1.00000E+00,6.50000E-06,100,ok
trefoil,99,rpy,0,0,8.70000E-01,7.60000E-01,1.30000E+00,8.80000E-01,6.00000E-05,100,ok
trefoil,99,multipole,2,1,6.40000E-03,5.20000E-03,1.40000E-02,6.40000E-03,7.40000E-02,7,ok
trefoil,99,multipole,3,1,0.00000E+00,0.00000E+00,0.00000E+00,0.00000E+00,3.30000E-01,3,ok
loose,152,rpy,0,0,5.00000E-01,4.00000E-01,5.00000E-01,5.00000E-01,1.35000E-04,100,ok
loose,152,multipole,2,1,-1.00000E+00,-1.00000E+00,-1.00000E+00,-1.00000E+00,-1.00000E+00,0,failed: x
"""
TOL = """model,order,lubrication,t_end,tolerance,wall,steps,rejected,evaluations,max_deviation,ref_tolerance
rpy,0,0,2.00000E+01,1.00000E-09,5.00000E+00,1000,0,6000,0.00000E+00,1.00000E-09
rpy,0,0,2.00000E+01,1.00000E-03,5.00000E-01,100,2,612,1.00000E-04,1.00000E-09
rpy,0,0,2.00000E+01,1.00000E-05,7.00000E-01,150,0,900,1.00000E-06,1.00000E-09
"""
SCALING = """model,order,lubrication,n,t_eval,n_evals,status
rpy,0,0,25,1.00000E-05,10,ok
rpy,0,0,50,4.00000E-05,10,ok
multipole,3,1,25,1.00000E-02,3,ok
multipole,3,1,50,8.00000E-02,3,skipped
"""
FIT = "model,order,lubrication,exponent,n_min,n_max,points\nrpy,0,0,2.000,25,50,2\n"
CASE = """model,order,lubrication,kind,t_end,wall,evaluations,evals_per_time,t_eval,rate_source
none,0,0,measured,1.00000E+03,5.00000E+00,1000,1.00000E+03,5.00000E-06,full run
rpy,0,0,measured,1.00000E+03,2.64000E+01,433093,4.33093E+02,6.10000E-05,full run
rpy,0,0,extrapolated,1.00000E+03,2.50000E+01,420000,4.20000E+02,5.95000E-05,rate over t = 0.10..0.60
multipole,2,1,extrapolated,1.00000E+03,3.24000E+04,420000,4.20000E+02,7.40000E-02,rate over t = 0.10..0.60
"""


@pytest.fixture
def results(tmp_path):
    d = tmp_path / "res"
    d.mkdir()
    for name, text in [("meta.csv", META), ("models.csv", MODELS), ("tolerance.csv", TOL),
                       ("scaling.csv", SCALING), ("scaling_fit.csv", FIT),
                       ("case_time.csv", CASE)]:
        (d / name).write_text(text)
    return d


def test_helpers():
    assert accuracy.label({"model": "multipole", "order": "4", "lubrication": "1"}) == "L4+lub"
    assert accuracy.label({"model": "multipole", "order": "2", "lubrication": "0"}) == "L2"
    assert accuracy.label({"model": "rpy", "order": "0", "lubrication": "0"}) == "rpy"
    assert accuracy.fmt_time(6.0e-5) == "60 µs"
    assert accuracy.fmt_time(0.074) == "74 ms"
    assert accuracy.fmt_time(26.4) == "26.4 s"
    assert accuracy.fmt_time(32400.0) == "9 h"
    assert accuracy.fmt_time(-1.0) == "–"
    assert accuracy.fmt_err(0.0) == "0" and accuracy.fmt_err(-1.0) == "failed"


def test_report_and_readme(results, tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text("# x\nbefore\n%s\nold table\n%s\nafter\n" % (accuracy.BEGIN, accuracy.END))
    md = tmp_path / "docs" / "accuracy.md"
    figs = tmp_path / "docs" / "figures"
    rc = cli.main_accuracy_report([str(results), "--markdown", str(md), "--figures", str(figs),
                        "--readme", str(readme)])
    assert rc == 0
    text = md.read_text()
    # summary rows: errors per configuration, time per evaluation, case wall time
    assert "| rpy | 8.70e-01 | 5.00e-01 | 60 µs | 26.4 s (measured) |" in text
    assert "| L2+lub | 6.40e-03 | failed | 74 ms | 9 h (extrapolated) |" in text
    assert "| L3+lub | 0 | – | 330 ms | – |" in text
    # tolerance, scaling and case-time tables
    assert "| rpy | 20 | 1e-03 | 500 ms | 100 | 2 | 612 | 1.00e-04 |" in text
    assert "| rpy | 10 µs | 40 µs | 2.00 (N = 25–50) |" in text
    assert "| L3+lub | 10 ms | skipped | – |" in text
    assert "rate over t = 0.10..0.60" in text and "Quick run" not in text
    for name in ("accuracy_error_cost.png", "accuracy_tolerance.png", "accuracy_scaling.png"):
        data = (figs / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n"
        assert "figures/%s" % name in text
    new = readme.read_text()
    assert new.startswith("# x\nbefore\n%s\n" % accuracy.BEGIN)
    assert new.endswith("%s\nafter\n" % accuracy.END)
    assert "old table" not in new
    assert "| rpy | 8.70e-01 | 5.00e-01 | 60 µs | 26.4 s (measured) |" in new
    assert "load average 0.50 0.40 0.30 1/2 3" in new


def test_errors(results, tmp_path, capsys):
    readme = tmp_path / "README.md"
    readme.write_text("no markers here\n")
    rc = cli.main_accuracy_report([str(results), "--markdown", str(tmp_path / "a.md"), "--figures",
                        str(tmp_path / "f"), "--readme", str(readme)])
    assert rc == 2
    assert "markers" in capsys.readouterr().err
    assert readme.read_text() == "no markers here\n"
    rc = cli.main_accuracy_report([str(tmp_path / "missing"), "--markdown", str(tmp_path / "b.md")])
    assert rc == 2
    assert "no meta.csv" in capsys.readouterr().err
    assert not os.path.exists(tmp_path / "b.md")


def test_regenerating_keeps_what_follows_the_generated_part(results, tmp_path):
    """The reuse and stiffness blocks and the sections written by hand after the generated part
    survive a regeneration, in a report with the end marker and in one written before it."""
    md = tmp_path / "accuracy.md"
    args = [str(results), "--markdown", str(md), "--figures", str(tmp_path / "f")]
    hand = ("%s\nreuse table\n%s\n\n## Written by hand\n\nmeasured with `x --y`: 1.23e-4\n"
            % (accuracy.REUSE_BEGIN, accuracy.REUSE_END))
    # a report of the layout before the marker: the generated part, then the blocks and sections
    md.write_text("# old generated part\n\n| stale | table |\n\n" + hand)
    assert cli.main_accuracy_report(args) == 0
    text = md.read_text()
    assert "stale" not in text and text.count("\n%s\n" % accuracy.GENERATED_END) == 1
    assert text.endswith(accuracy.GENERATED_END + "\n\n" + hand)
    assert "| rpy | 8.70e-01 | 5.00e-01 | 60 µs | 26.4 s (measured) |" in text
    # regenerated again (the marker present now): the same file, nothing lost or repeated
    assert cli.main_accuracy_report(args) == 0
    assert md.read_text() == text
    # a section added after the marker is kept too; the generated part is rewritten
    md.write_text(text.replace("| rpy | 8.70e-01", "| rpy | edited") + "\n## Later\n\nmore\n")
    assert cli.main_accuracy_report(args) == 0
    again = md.read_text()
    assert again == text + "\n## Later\n\nmore\n"
    # the stiffness block, written after it, lands after the hand sections and is kept
    accuracy.write_block(str(md), "stiffness table", accuracy.STIFFNESS_BEGIN,
                         accuracy.STIFFNESS_END)
    assert cli.main_accuracy_report(args) == 0
    final = md.read_text()
    assert final.index("## Later") < final.index("stiffness table")
    assert final.count(accuracy.STIFFNESS_BEGIN) == 1 and "1.23e-4" in final
