"""knotflow-study: re-knottings, the three-column comparison, refusals, partial sweeps, overlap
statistics, run records, per-frame CSV and the --every-time schedule, on constructed inputs
whose answers are counted by hand."""

import json
import math
import shutil

import h5py
import numpy as np
import pytest
from analysis_fixture import write_knots

from knotflow_tools import io, study, study_compare, study_reference, study_rows
from knotflow_tools.cli import EXIT_USAGE, main_study

from conftest import write_case


def _straight(nframes, n=12):
    r = np.zeros((nframes, n, 3))
    r[:, :, 0] = 1.02 * np.arange(n)
    return r


# ------------------------------------------------------------------------------- re-knottings

def test_reknottings_of_a_constructed_kf_series():
    t = np.arange(12.0)
    kf = np.array([0.95, 0.5, 0.05, 0.5, 0.95, 0.92, 0.05, 0.08, 0.93, 0.5, 0.95, 0.05])
    events = study_rows.history(t, kf, knotted_at_start=True)
    # by hand: untied at 2, knotted at 4, untied at 6, knotted at 8, (0.95 at 10: still
    # knotted), untied at 11 -> two knot events after an untying
    assert events == [("unknot", 2.0), ("knot", 4.0), ("unknot", 6.0), ("knot", 8.0),
                      ("unknot", 11.0)]
    assert study_rows.reknottings(events) == 2
    # from an unknotted start the first knotting follows no untying
    events = study_rows.history(t[:4], np.array([0.05, 0.95, 0.05, 0.95]), knotted_at_start=False)
    assert events == [("knot", 1.0), ("unknot", 2.0), ("knot", 3.0)]
    assert study_rows.reknottings(events) == 1
    assert study_rows.reknottings([]) == 0


def _tref(a, o, events, status="finished", final="unknotted", mode="-"):
    return {"case": f"A{a:.2f}_or{o}", "A": a, "orientation": o, "status": status,
            "model": "multipole", "t_end": 1000.0, "t_reached": 1000.0 if status == "finished"
            else 400.0, "events": events, "final_state": final, "mode": mode,
            "unknot_then_knot": study_rows.reknottings(events) > 0, "kf0": 0.98, "final_kf": 0.0,
            "study_transition": study_reference.in_study(a, o)}


def test_reknot_totals_and_the_line_with_the_study():
    rows = [_tref(1.0, "a", [["unknot", 1], ["knot", 2], ["unknot", 3], ["knot", 4]]),
            _tref(1.0, "b", [["unknot", 1]]),
            _tref(1.0, "c", [["unknot", 1], ["knot", 2]], status="running")]
    tot = study_rows.reknot_totals(rows)
    assert tot == {"events": 3, "simulations": 2, "cases": 3, "finished": 2}
    lines, agree, total = study.trefoil_tables(rows)
    text = "\n".join(lines)
    assert "3 in 2 of 3 simulations (the study: 13 in 4 of 29)" in text
    assert "2 of 29 cases finished (3 present)" in text
    assert "| A1.00_orc | running, t = 400 of 1000 |" in text
    assert "U->K* / -" in text                          # the running case's cell is marked
    assert (agree, total) == (1, 3)
    # (1, a) and the running (1, c) re-knot where Table 2 has none; only (1, b) agrees
    assert "Agreement: 1 of 2 finished cases (1 of 3 with those not finished)." in text


# ---------------------------------------------------------------------- three-column tables

def test_three_column_trefoil_cells_and_counts():
    ours = [_tref(1.4, "b", [["unknot", 5]]),                                     # differs
            _tref(2.2, "c", [["unknot", 10], ["knot", 20], ["unknot", 30], ["knot", 40]]),
            _tref(3.0, "a", [["unknot", 5], ["knot", 9]], final="knotted", mode="II"),  # differs
            _tref(2.1, "c", [["unknot", 5]], status="running")]                   # differs
    rpy = [_tref(1.4, "b", [["unknot", 1], ["knot", 2]], mode="II"),
           _tref(2.2, "c", [["unknot", 3]]),                                      # differs
           _tref(3.0, "a", [["unknot", 4]], mode="II"),
           _tref(0.8, "d", [], final="knotted")]
    for r in rpy:
        del r["t_reached"], r["model"]                  # as in an older results.json
    lines, doc = study_compare.trefoil_comparison(ours, rpy)
    text = "\n".join(lines)
    row = {ln.split(" | ")[0]: ln for ln in lines if ln.startswith("| ")}
    assert row["| 1.4"] == "| 1.4 |   | U->K / **-** / U->K |   |   |"
    assert "U->K / U->K / **-**" in row["| 2.2"]        # (c, 2.2)
    assert row["| 3"].startswith("| 3 | - / **U->K** / - |")
    assert "U->K / **-*** / ?" in row["| 2.1"]           # running, no RPY case
    assert row["| 0.8"] == "| 0.8 |   |   |   | - / ? / - |"   # (d, 0.8): not run here
    # "Every case": a case not run by one model still fills its four cells, so that every row
    # has the header's eleven cells and the other model's columns stay under their heads
    cases = [ln for ln in lines if ln.startswith("| A") and "_or" in ln]
    assert len(cases) == 5
    assert {ln.count("|") for ln in cases} == {lines[lines.index("Every case:") + 2].count("|")}
    assert "| A0.80_ord | - | no | not run | | | | none | 0 | knotted | - |" in cases
    assert "| A2.10_orc | running, t = 400 of 1000 | yes | unknot 5 | 0 | unknotted | - | not run | | | |" \
        in cases
    assert (doc["ours"]["agree"], doc["ours"]["cases"]) == (1, 4)
    assert (doc["rpy"]["agree"], doc["rpy"]["cases"]) == (3, 4)
    assert (doc["ours"]["events"], doc["ours"]["simulations"]) == (3, 2)
    assert (doc["rpy"]["events"], doc["rpy"]["simulations"]) == (1, 1)
    assert doc["study"]["events"] == 13 and doc["study"]["simulations"] == 4
    assert "| unknot-then-knot events | 13 | 3 | 1 |" in text
    assert "| simulations with one or more | 4 of 29 | 2 of 4 | 1 of 4 |" in text
    assert "| cases finished | 29 | 3 of 29 | 4 of 4 |" in text
    # agreement: ours (2.2, c) of the finished three, the running (2.1, c) differs; RPY 3 of 4
    assert ("| cells agreeing with the study | - | 1 of 3 finished cases (1 of 4 with those not "
            "finished) | 3 of 4 cases |") in text
    assert "| final state knotted / unknotted / undecided | not stated | 1 / 3 / 0 | 1 / 3 / 0 |" \
        in text
    # stiff (A >= 2.2): ours (2.2, c) '-' and (3, a) II; RPY (2.2, c) '-' and (3, a) II
    # the study reports no mode for its trefoils (tumbling only for stiff candy-canes)
    assert ("| stiff trefoils (A >= 2.2) in mode II | not reported (tumbling is reported for stiff "
            "candy-canes) | 1 of 2 | 1 of 2 |") in text
    assert doc["columns"] == ["the study", "knotflow multipole", "knotflow RPY + EV"]


def _cane(a, cp, late, mode, matrices=(), status="finished"):
    return {"case": f"A{a:.2f}", "A": a, "status": status, "t_end": 2000.0,
            "t_reached": 2000.0 if status == "finished" else 408.0, "model": "multipole",
            "close_pairs_mean": cp, "close_pairs_late": late, "case_mode": mode, "max_kf": 0.2,
            "matrices": list(matrices)}


def test_three_column_candycane_ratios_modes_and_slipknots():
    cand = {"frame": 5, "time": 5.0, "whole_kf": 0.0, "max_K": 0.6, "knot_core": [3, 40],
            "slipknot": True, "confirmed_max_K": 0.4, "confirmed_slipknot": False}
    none = {"frame": 9, "time": 9.0, "whole_kf": 0.0, "max_K": 0.1, "knot_core": None,
            "slipknot": False}
    ours = [_cane(1.0, 8.0, 6.0, "I", status="running"), _cane(3.0, 2.0, 3.0, "II")]
    rpy = {"candycane": [_cane(1.0, 3.0, 1.0, "-"), _cane(1.4, 4.0, 4.0, "-", [cand, none]),
                         _cane(3.0, 2.0, 2.0, "-")],
           "ensemble": [_cane(1.0, 6.0, 5.0, "-"), _cane(1.0, 4.0, 3.0, "I"),
                        _cane(3.0, 2.0, 2.0, "II"), _cane(3.0, 4.0, 4.0, "-")]}
    lines, doc = study_compare.candycane_comparison(ours, [], rpy)
    text = "\n".join(lines)
    r = doc["close_pair_ratio"]
    assert r["all_t"]["ours"] == pytest.approx(4.0) and r["all_t"]["rpy"] == pytest.approx(1.5)
    assert r["late_t"]["ours"] == pytest.approx(2.0) and r["late_t"]["rpy"] == pytest.approx(0.5)
    # rotations: A = 1 mean 5, A = 3 mean 3
    assert r["rotations_all_t"]["rpy"] == pytest.approx(5 / 3)
    assert r["rotations_all_t"]["ours"] is None and r["all_t"]["study"] == "about 4"
    assert "| close pairs A = 1 / A = 3, all t | about 4 | 4.0 | 1.5 |" in text
    assert "| 1: case mode | I | I | - |" in text
    assert "| 3: case mode | II | II | - |" in text
    assert "| 1: status | - | running, t = 408 of 2000 | finished |" in text
    # an entry of an earlier results.json (recomputed, before the core check): not confirmed
    assert "| 1.4: slipknots | found | not run | 1 candidates, 1 recomputed, 0 still " \
           "slipknots, 0 confirmed (2 frames) |" in text
    assert "| 3: rotations: case mode I / II / neither | - | not run | 0 / 1 / 1 |" in text
    # the study's slipknots: found at A = 1.4, described visually at A = 3, nothing said at A = 1
    assert "| 3: slipknots | described visually |" in text
    assert "| 1: slipknots | not stated |" in text
    per = {e["A"]: e for e in doc["per_A"]}
    assert per[1.4]["rpy"][0]["slip_candidates"] == 1 and per[1.4]["ours"] == []
    assert per[1.0]["rpy_rotations_modes"] == {"I": 1, "II": 0, "-": 1, "?": 0}
    assert "| close pairs A = 1 / A = 3, all t, mean over rotations | about 4 | not run | 1.7 |" \
        in text
    # with rotations of this run: A = 1 means (9 + 7) / 2 = 8, A = 3 one case of 2 -> 4
    ensemble = [_cane(1.0, 9.0, 1.0, "I"), _cane(1.0, 7.0, 1.0, "-"), _cane(3.0, 2.0, 1.0, "II")]
    lines, doc = study_compare.candycane_comparison(ours, ensemble, rpy)
    assert doc["close_pair_ratio"]["rotations_all_t"]["ours"] == pytest.approx(4.0)
    assert "| 1: rotations: case mode I / II / neither | - | 1 / 0 / 1 | 1 / 0 / 1 |" in lines


# ------------------------------------------------------------------------------- refusals

@pytest.mark.parametrize("content, option, problem", [
    (None, "--rpy-trefoil", "no such file"),
    ("{not json", "--rpy-trefoil", "not JSON"),
    ("[1, 2]", "--rpy-trefoil", "no object at the top"),
    (json.dumps({"candycane": [], "ensemble": []}), "--rpy-trefoil", 'no "trefoil" part'),
    (json.dumps({"trefoil": {"cases": []}}), "--rpy-trefoil", 'the "trefoil" part holds no cases'),
    (json.dumps({"trefoil": {"cases": [{"case": "x", "A": 1, "orientation": "a", "mode": "-",
                                        "unknot_then_knot": False, "final_state": "knotted"}]}}),
     "--rpy-trefoil", '"trefoil" case 0: no events'),
    (json.dumps({"candycane": [_cane(1.0, 1, 1, "-")]}), "--rpy-candycane", 'no "ensemble" part'),
])
def test_refused_rpy_results(tmp_path, capsys, content, option, problem):
    path = tmp_path / "rpy.json"
    if content is not None:
        path.write_text(content)
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    out = tmp_path / "out"
    sweep_opt = "--trefoil" if option == "--rpy-trefoil" else "--candycane"
    status = main_study([sweep_opt, str(sweep), option, str(path), "--out", str(out)])
    err = capsys.readouterr().err
    assert status == EXIT_USAGE
    assert err.count("\n") == 1 and str(path) in err and problem in err
    assert not out.exists()                             # refused before anything is written


def test_rpy_option_needs_its_sweep(tmp_path, capsys):
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    with pytest.raises(SystemExit) as exc:
        main_study(["--candycane", str(sweep), "--rpy-trefoil", "x.json"])
    assert exc.value.code == EXIT_USAGE
    assert "--rpy-trefoil needs --trefoil" in capsys.readouterr().err


# ------------------------------------------------------ overlap statistics of a running case

def _diag_attrs(path, episodes):
    with h5py.File(path, "a") as f:
        for k, v in {"strand_passages": 0, "first_passage_time": -1.0,
                     "overlap_episodes": episodes, "overlap_mean_duration": 1.0,
                     "overlap_max_duration": 2.0, "max_overlapping_pairs": 1,
                     "min_distance": 0.99, "max_bond_strain": 0.01}.items():
            f.attrs["diagnostics." + k] = v


def test_overlap_statistics_of_a_running_case_come_from_its_checkpoint(tmp_path):
    running = write_case(tmp_path / "run.h5", _straight(3), status="running")
    _diag_attrs(running, 99)                             # one frame ahead of the checkpoint
    with h5py.File(running, "a") as f:
        g = f["checkpoint"].create_group("diagnostics")
        g["counters"] = np.array([1, 7, 4, 3, 3], dtype=np.int64)
        g["values"] = np.array([12.5, 10.0, 6.0, 0.81, 0.05])
    case = io.read_case(running)
    d = study_rows.overlap_stats(case)
    assert d["source"] == "checkpoint"
    assert d["overlap_episodes"] == 7 and d["strand_passages"] == 1
    assert d["overlap_mean_duration"] == pytest.approx(10.0 / 4)
    assert d["overlap_max_duration"] == 6.0 and d["max_overlapping_pairs"] == 3
    assert d["min_distance"] == pytest.approx(0.9) and d["first_passage_time"] == 12.5
    finished = write_case(tmp_path / "fin.h5", _straight(3))
    _diag_attrs(finished, 5)
    d = study_rows.overlap_stats(io.read_case(finished))
    assert d["source"] == "attributes" and d["overlap_episodes"] == 5
    assert study_rows.overlap_stats(io.read_case(write_case(tmp_path / "none.h5", _straight(3)))) is None
    rows = [{"case": "run", "status": "running", "t_reached": 2.0, "t_end": 10.0,
             "overlap": study_rows.overlap_stats(case)},
            {"case": "old", "status": "finished", "overlap": None}]
    text = "\n".join(study.overlap_table(rows))
    assert "| run | running, t = 2 of 10 | 7 | 2.50 | 6.00 | 3 | 0.90000 | 1 |" in text
    assert "| old | finished | not recorded |" in text


def test_overlap_heading_names_each_rule_by_its_scene_name(tmp_path):
    """The heading names the rules the cases ran with ('relax' is never called BWE); a model
    without an overlap rule (RPY) is named as such; the rule is read from the case's attributes."""
    def row(rule):
        return {"case": "x", "overlap_rule": rule}
    assert study.overlap_heading([row("relax")]) == "#### Overlap statistics (overlap = 'relax')"
    assert study.overlap_heading([row("bwe"), row("pair"), row(None)]) == \
        "#### Overlap statistics (overlap = 'bwe'; overlap = 'pair'; a model without an overlap rule)"
    path = write_case(tmp_path / "m.h5", _straight(3))
    with h5py.File(path, "a") as f:
        f.attrs["hydro.model"] = "multipole"
        f.attrs["hydro.overlap"] = "relax"
    assert study_rows.overlap_rule(io.read_case(path)) == "relax"
    with h5py.File(path, "a") as f:
        f.attrs["hydro.model"] = "rpy"
    assert study_rows.overlap_rule(io.read_case(path)) is None


# ---------------------------------------------------------------------------- run records

def _write_runs(path, commits, wall, load, drop=None, short=None, blas=None):
    """/runs of a case file; `blas` None writes none (a file of schema 4)."""
    n = len(commits)
    data = {"commit": np.array(commits, dtype=h5py.string_dtype()),
            "started": np.array(["2026-12-02T01:00:00Z"] * n, dtype=h5py.string_dtype()),
            "host": np.array(["node1"] * n, dtype=h5py.string_dtype()),
            "ranks": np.full(n, 2, dtype=np.int32), "threads": np.ones(n, dtype=np.int32),
            "t_start": np.arange(n) * 100.0, "t_end": np.arange(1, n + 1) * 100.0,
            "steps": np.full(n, 1000, dtype=np.int64), "wall_seconds": np.array(wall, float),
            "load_start": np.full(n, np.nan), "load_mean": np.array(load, float)}
    if blas is not None:
        data["blas"] = np.array(blas, dtype=h5py.string_dtype())
    with h5py.File(path, "a") as f:
        g = f.create_group("runs")
        for k, v in data.items():
            if k != drop:
                g[k] = v[:-1] if k == short else v


def test_run_records_are_read_and_summed(tmp_path):
    a = write_case(tmp_path / "a.h5", _straight(3))
    _write_runs(a, ["abc", "abc", "def"], [3600.0, 1800.0, 5400.0], [2.0, np.nan, 1.0],
                blas=["OpenBLAS 0.3.21 Prescott", "unknown", "OpenBLAS 0.3.21 SkylakeX"])
    b = write_case(tmp_path / "b.h5", _straight(3))
    _write_runs(b, ["def"], [7200.0], [3.0])
    case = io.read_case(a)
    assert len(case.runs) == 3 and case.runs[0]["commit"] == "abc"
    assert [r["blas"] for r in case.runs] == ["OpenBLAS 0.3.21 Prescott", "unknown",
                                              "OpenBLAS 0.3.21 SkylakeX"]
    assert io.read_case(b).runs[0]["blas"] is None   # schema 4: no /runs/blas
    assert case.runs[2]["host"] == "node1" and case.runs[1]["ranks"] == 2
    assert case.runs[1]["steps"] == 1000 and math.isnan(case.runs[1]["load_mean"])
    assert io.read_case(write_case(tmp_path / "c.h5", _straight(3))).runs == []
    sa = study_rows.runs_summary(case.runs)
    # by hand: 3600 + 1800 + 5400 = 10800 s; load (2 x 3600 + 1 x 5400) / 9000 = 1.4
    assert sa["commits"] == ["abc", "def"] and sa["wall_seconds"] == 10800.0
    assert sa["blas"] == ["OpenBLAS 0.3.21 Prescott", "OpenBLAS 0.3.21 SkylakeX"]
    assert sa["blas_unknown"] == 1
    assert sa["mean_load"] == pytest.approx(1.4) and sa["segments"] == 3
    assert (sa["t_start"], sa["t_end"]) == (0.0, 300.0) and sa["wall_unknown"] == 0
    # a segment without a wall time (NaN): left out of the sum and of the load weights
    d = study_rows.runs_summary([dict(case.runs[0], wall_seconds=math.nan), case.runs[2]])
    assert d["wall_seconds"] == 5400.0 and d["wall_unknown"] == 1 and d["mean_load"] == 1.0
    assert "| x | finished | abc, def | OpenBLAS 0.3.21 Prescott, OpenBLAS 0.3.21 SkylakeX | " \
        "1.50 h (+ 1 segment(s) not recorded) | 1.00 | 2 |" in \
        study.runs_table([{"case": "x", "status": "finished", "runs": d}])
    sb = study_rows.runs_summary(io.read_case(b).runs)
    rows = [{"case": "a", "status": "finished", "runs": sa},
            {"case": "b", "status": "finished", "runs": sb},
            {"case": "c", "status": "finished", "runs": None}]
    text = "\n".join(study.runs_table(rows))
    assert "| a | finished | abc, def | OpenBLAS 0.3.21 Prescott, OpenBLAS 0.3.21 SkylakeX " \
        "(+ 1 segment(s) not recorded) | 3.00 h | 1.40 | 3 |" in text
    assert "| b | finished | def | 1 segment(s) not recorded | 2.00 h | 3.00 | 1 |" in text
    assert "| c | finished | not recorded |" in text
    # all: 18000 s = 5 h; load (1.4 x 9000 + 3 x 7200) / 16200 = 2.111
    assert "| all (2 of 3 cases recorded) | | | | 5.00 h | 2.11 | 4 |" in text


@pytest.mark.parametrize("drop, short, problem", [
    ("host", None, "no dataset /runs/host"),
    (None, "wall_seconds", "different lengths"),
    (None, "blas", "different lengths"),
])
def test_bad_run_records_are_refused(tmp_path, drop, short, problem):
    path = write_case(tmp_path / "a.h5", _straight(3))
    _write_runs(path, ["abc", "abc"], [1.0, 2.0], [1.0, 1.0], drop=drop, short=short,
                blas=["OpenBLAS 0.3.21 Haswell"] * 2)
    with pytest.raises(ValueError, match=problem) as exc:
        io.read_case(path)
    assert str(path) in str(exc.value)


# ------------------------------------------------------------------ frames and CSV files

def test_every_time_frames_on_known_time_axes(tmp_path):
    assert study.time_frames(np.arange(96.0), 10.0) == list(range(0, 91, 10))
    # t_k = 0.7 k: the frames nearest to 0, 10, 20, 30 are 0 (0), 14 (9.8), 29 (20.3), 43 (30.1)
    assert study.time_frames(0.7 * np.arange(50), 10.0) == [0, 14, 29, 43]
    with pytest.raises(ValueError, match="every-time"):
        study.time_frames(np.arange(5.0), 0.0)
    path = write_case(tmp_path / "a.h5", _straight(26))
    with h5py.File(path, "a") as f:                     # one entangled frame: 17
        cp = np.zeros(26, dtype=np.int32)
        cp[17] = 5
        f["frames/observables/close_pairs"][...] = cp
    assert study.entangled_frames(path, every_time=10.0) == [0, 10, 17, 20, 25]
    assert study.entangled_frames(path) == [0, 17, 25]


def test_every_time_on_the_command_line(tmp_path, capsys):
    path = write_case(tmp_path / "a.h5", _straight(26))
    assert main_study(["--select-frames", str(path), "--every-time", "10"]) == 0
    assert capsys.readouterr().out.strip() == "0,10,20,25"
    with pytest.raises(SystemExit):
        main_study(["--select-frames", str(path), "--every-time", "-1"])
    with pytest.raises(SystemExit):
        main_study(["--trefoil", str(tmp_path), "--every-time", "10"])


def test_candycane_csv_has_every_frame_and_kf_where_computed(tmp_path):
    path = write_case(tmp_path / "A1.00.h5", _straight(6), time=np.arange(6) * 2.0)
    write_knots(path, [0, 2, 4, 5], [0.0, 4.0, 8.0, 10.0], [0.0, 0.25, 0.5, 0.0],
                np.zeros((4, 10)), ["0_1"] * 4, closures=10, seed=1)
    rows = study_rows.candycane_rows([path], closures=5)
    out = study.write_candycane_csv(rows, tmp_path / "candycane_shape.csv")
    lines = out.read_text().splitlines()
    assert lines[0] == "case,t,R_g,a,b,c,theta,phi,close_pairs,k_f"
    assert len(lines) == 7
    assert [ln.split(",")[-1] for ln in lines[1:]] == ["0", "", "0.25", "", "0.5", "0"]
    assert [ln.split(",")[1] for ln in lines[1:]] == ["0", "2", "4", "6", "8", "10"]
    rows = [{"case": "x", "time": [0.0, 1.0], "kf": [0.98, 0.5]}]
    out = study.write_trefoil_csv(rows, tmp_path / "trefoil_kf.csv")
    assert out.read_text() == "case,t,k_f\nx,0,0.98\nx,1,0.5\n"


def test_write_study_with_rpy_results_end_to_end(tmp_path, trefoil_case):
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    shutil.copy(trefoil_case, sweep / "A1.40_orb.h5")
    with h5py.File(sweep / "A1.40_orb.h5", "a") as f:
        f.attrs["forces.bending_a"] = 1.4
        f.attrs["chain.orientation"] = "b"
        f.attrs["status"] = "running"
        f.attrs["integrator.t_end"] = 1000.0
        f.attrs["case_name"] = "A1.40_orb"
    rpy = {"trefoil": {"cases": [_tref(1.4, "b", [["unknot", 1], ["knot", 2]])]}}
    (tmp_path / "rpy.json").write_text(json.dumps(rpy))
    out = tmp_path / "out"
    assert main_study(["--trefoil", str(sweep), "--rpy-trefoil", str(tmp_path / "rpy.json"),
                       "--out", str(out), "--closures", "20"]) == 0
    res = json.loads((out / "results.json").read_text())
    assert res["trefoil"]["reknottings"]["finished"] == 0
    (case,) = res["trefoil"]["cases"]
    assert case["status"] == "running" and case["t_reached"] == 70.0 and case["t_end"] == 1000.0
    cmp = res["comparison"]["trefoil"]
    assert cmp["rpy"]["agree"] == 1 and cmp["cells"][0]["ours_finished"] is False
    md = (out / "results.md").read_text()
    assert "0 of 29 cases finished (1 present)" in md and "| A1.40_orb | running, t = 70 of 1000 |" in md
    assert (out / "trefoil_kf.csv").read_text().startswith("case,t,k_f\nA1.40_orb,0,")
