"""knotflow-accuracy-report --reuse: the reuse section of docs/accuracy.md from synthetic
knotflow-bench-reuse outputs (key = value lines), placed between its markers (appended the
first time, replaced afterwards, the rest of the report untouched), and a clear error."""

from knotflow_tools import accuracy, cli

VELOCITY = """part = velocity
config = trefoil
t_end = 10.0000
loadavg_start = 1.00 1.00 1.00 1/2 3
checks = 883
every = 1
velocity_rms_max = 8.284E-04
velocity_rms_mean = 8.193E-05
velocity_maxnorm_max = 1.122E-03
adaptive.evaluations = 883
adaptive.refreshes = 381
adaptive.reused = 502
adaptive.cg_iterations = 1004
adaptive.max_error_ratio = 5.359E+00
"""
SPEED = """part = speed
config = trefoil
t_end = 50.0000
loadavg_start = 2.00 2.00 2.00 1/2 3
adaptive.wall_s = 100.00
adaptive.steps = 629
adaptive.evaluations = 3775
adaptive.refreshes = 1567
stage.wall_s = 250.00
stage.steps = 628
loadavg_end = 2.50 2.00 2.00 1/2 3
"""


def write_outputs(directory):
    (directory / "velocity_trefoil.txt").write_text(VELOCITY)
    (directory / "speed_trefoil.txt").write_text(SPEED)


def test_read_keys(tmp_path):
    write_outputs(tmp_path)
    keys = accuracy.read_keys(str(tmp_path / "speed_trefoil.txt"))
    assert keys["stage.wall_s"] == "250.00"
    assert keys["loadavg_start"] == "2.00 2.00 2.00 1/2 3"


def test_section_appended_then_replaced(tmp_path):
    write_outputs(tmp_path)
    md = tmp_path / "accuracy.md"
    md.write_text("# Report\n\nbody text\n")
    section = accuracy.update_reuse(str(md), str(tmp_path))
    assert "| trefoil | 10.0000 | 883 | 8.284E-04 | 8.193E-05 | 1.122E-03 | 381 of 883 | 2.00 |" in section
    assert "**2.50× less wall time**" in section
    text = md.read_text()
    assert text.startswith("# Report\n\nbody text\n")
    assert text.count(accuracy.REUSE_BEGIN) == 1 and text.count(accuracy.REUSE_END) == 1
    (tmp_path / "speed_trefoil.txt").write_text(SPEED.replace("100.00", "125.00"))
    accuracy.update_reuse(str(md), str(tmp_path))
    text = md.read_text()
    assert text.count(accuracy.REUSE_BEGIN) == 1
    assert "**2.00× less wall time**" in text and "2.50×" not in text
    assert text.startswith("# Report\n\nbody text\n")


def test_no_outputs_is_an_error(tmp_path, capsys):
    md = tmp_path / "accuracy.md"
    md.write_text("# Report\n")
    assert cli.main_accuracy_report(["--reuse", str(tmp_path / "missing"), "--markdown", str(md)]) == 2
    assert "no knotflow-bench-reuse outputs" in capsys.readouterr().err
    assert md.read_text() == "# Report\n"


def test_overlap_rule_stated(tmp_path):
    """Outputs without an overlap line predate the option: they ran the rule 'pair'."""
    def section():
        return accuracy.update_reuse(str(tmp_path / "a.md"), str(tmp_path))
    write_outputs(tmp_path)
    assert "overlap rule 'pair'," in section()
    for name, text in (("velocity_trefoil.txt", VELOCITY), ("speed_trefoil.txt", SPEED)):
        (tmp_path / name).write_text(text.replace("t_end =", "overlap = relax\nt_end ="))
    assert "overlap rule 'relax'," in section()
    (tmp_path / "speed_trefoil.txt").write_text(SPEED)
    assert "overlap rule 'pair' / 'relax' (by part)," in section()
