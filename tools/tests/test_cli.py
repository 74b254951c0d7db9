"""Console commands on coordinate files and synthetic case files."""

import json
import os

import h5py
import numpy as np

import knotflow
from knotflow_tools import cli, io, knots

from conftest import unknotting_trefoil_frames, write_case
from helpers import open_from_closed, open_trefoil, torus_knot


def test_kf_json_on_xyz(tmp_path, capsys):
    p = tmp_path / "chain.xyz"
    io.write_xyz(p, open_trefoil())
    assert cli.main_kf([str(p), "--closures", "30", "--seed", "4", "--json",
                        "--per-closure"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["n_beads"] == 99 and out["closures"] == 30 and out["seed"] == 4
    assert out["dominant"] == "3_1"
    assert set(out["spectrum"]) == set(knots.KNOT_TYPES)
    assert abs(sum(out["spectrum"].values()) - 1.0) < 1e-12
    assert len(out["per_closure"]) == 30
    assert out["kf"] == 1.0 - out["per_closure"].count("0_1") / 30
    assert "matrix" not in out and out["knot_core"] is None and out["slipknot"] is False
    # the library's knot code (knotflow-analyze's) with the same seed, closure for closure
    assert out["per_closure"] == list(knotflow.knots(open_trefoil(), 30, seed=4).per_closure)
    # and the numpy oracle (another random stream) agrees: the trefoil's k_f is high in both
    assert knots.analyze_chain(open_trefoil(), 30, seed=4).kf > 0.5 and out["kf"] > 0.5


def test_kf_closure_points_and_matrix(tmp_path, capsys):
    r = open_from_closed(torus_knot(2, 3, 24, R=2.0, r=0.8), 1)
    p = tmp_path / "chain.xyz"
    io.write_xyz(p, r)
    gap = 0.5 * (r[0] + r[-1])
    com = r.mean(axis=0)
    pts = tmp_path / "points.txt"
    io.write_xyz(pts, [com + 40 * (gap - com), com + 50 * (gap - com)])
    assert cli.main_kf([str(p), "--closure-points", str(pts), "--json", "--per-closure",
                        "--matrix", "--min-length", "20", "--closures", "5"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["closures"] == 2 and out["per_closure"] == ["3_1", "3_1"] and out["kf"] == 1.0
    mat = out["matrix"]
    assert len(mat) == len(r) and mat[0][1] is None and mat[1][0] is None
    assert mat[0][len(r) - 1] is not None
    assert out["knot_core"] is not None and out["slipknot"] is False


def test_kf_text_output_and_h5_frame(tmp_path, capsys):
    path = write_case(tmp_path / "c.h5", unknotting_trefoil_frames(4))
    assert cli.main_kf([str(path), "--frame", "0", "--closures", "20"]) == 0
    text = capsys.readouterr().out
    assert "dominant 3_1" in text and "kf " in text
    assert cli.main_kf([str(path), "--closures", "20"]) == 0      # last frame: straight
    assert "kf 0.000000" in capsys.readouterr().out
    assert cli.main_kf([str(tmp_path / "missing.xyz")]) == 2


def test_plot_command_writes_files(tmp_path, trefoil_case):
    out = tmp_path / "plots"
    assert cli.main_plot([trefoil_case, "--out", str(out), "--closures", "20",
                          "--matrix-frames", "0", "--matrix-closures", "4",
                          "--matrix-stride", "12", "--movie"]) == 0
    names = sorted(os.listdir(out))
    assert "case_A1_a_kf.png" in names and "case_A1_a_shape.png" in names
    assert "case_A1_a_snapshots.png" in names and "case_A1_a_knot_matrix_0.png" in names
    assert any(n.startswith("case_A1_a_movie") for n in names)
    for n in names:
        if n.endswith(".png"):
            assert (out / n).stat().st_size > 5000
    # the Python tools never write /analysis (knotflow-analyze is its one writer)
    with h5py.File(trefoil_case, "r") as f:
        assert "analysis" not in f


def test_report_on_sweep(tmp_path):
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    frames = unknotting_trefoil_frames(6)
    knotted = np.stack([open_from_closed(torus_knot(2, 3, 60, R=6, r=2.5), 1)] * 6)
    write_case(sweep / "A1_a.h5", frames, attrs={"forces.bending_a": 1.0,
                                                 "chain.orientation": "a"})
    write_case(sweep / "A2_b.h5", knotted, attrs={"forces.bending_a": 2.0,
                                                  "chain.orientation": "b"},
               status="failed: step size underflow")
    (sweep / "summary.txt").write_text("case A1_a finished\ncase A2_b failed\n")
    assert cli.main_report([str(sweep), "--closures", "20"]) == 0
    md = (sweep / "report" / "report.md").read_text()
    html = (sweep / "report" / "report.html").read_text()
    assert "| A1_a | 1 | a | finished |" in md
    assert "failed: step size underflow" in md
    assert "## Grid A x orientation" in md and "| 2 | - | no / knotted" in md
    assert "yes / unknotted" in md
    assert "case A1_a finished" in md and "<table>" in html
    figs = os.listdir(sweep / "report" / "figures")
    assert "A1_a_kf.png" in figs and "A2_b_shape.png" in figs
    # a movie of each case (mp4 with ffmpeg, else gif), linked from the report
    movies = sorted(f for f in figs if f.startswith("A1_a_movie"))
    assert movies and movies[0] in html
    # ParaView-ready XDMF beside each case file, linked from the report
    assert (sweep / "A1_a.xdmf2").is_file() and (sweep / "A2_b.xdmf2").is_file()
    assert "[A1_a.xdmf2](../A1_a.xdmf2)" in md and "href='../A2_b.xdmf2'" in html


def test_every_tool_answers_version(capsys):
    """Every console script of pyproject.toml answers --version with '<program> <version>' and
    exit status 0."""
    import importlib
    import re

    import pytest

    import knotflow_tools
    with open(os.path.join(os.path.dirname(__file__), "..", "pyproject.toml"), encoding="utf-8") as fh:
        text = fh.read()
    scripts = re.findall(r'^(knotflow-[a-z-]+) = "([a-z_.]+):([a-z_]+)"', text, re.M)
    assert len(scripts) >= 8, scripts
    for prog, module, func in scripts:
        main = getattr(importlib.import_module(module), func)
        with pytest.raises(SystemExit) as stop:
            main(["--version"])
        assert stop.value.code in (0, None), prog
        assert capsys.readouterr().out.strip() == f"{prog} {knotflow_tools.__version__}", prog
