"""The case ledger (knotflow_tools.campaign): names, the continuation scene, frame rows and the
refusals of digest. The whole cycle with the real programs (a case killed, its machine lost,
continued from the ledger) is tests/regression/check_campaign.py."""

import json
import os

import h5py
import numpy as np
import pytest

from knotflow_tools import campaign
from knotflow_tools.io import read_case

from conftest import unknotting_trefoil_frames, write_case

SCENE = """&chain
  shape = 'candycane'
  n_beads = 152
  coordinate_file = ''
  seed = 1
/
&forces
  bending_a = 1.0000000000000000
/
&integrator
  method = 'dopri45'
  t_end = 2000.0000000000000
  dt_initial = 0.10000000000000000E-2
/
&output
  directory = 'results/cc'
  case_name = 'A1.00'
  frame_interval = 1.0000000000000000
/
"""


def entry(t_reached=1234.5, t_end=2000.0):
    return {"sweep": "cc", "case": "A1.00", "scene": SCENE, "t_reached": t_reached,
            "t_end": t_end}


def test_names_round_trip():
    assert campaign.continuation_name("A1.00", 1200.0) == "A1.00_from1200"
    assert campaign.split_name(campaign.continuation_name("A1.00_s2", 12.5)) == ("A1.00_s2", 12.5)
    assert campaign.split_name("A0.80_ora") == ("A0.80_ora", 0.0)


def test_continuation_scene_changes_only_what_it_must():
    text = campaign.continuation_scene(entry(), "/x/A1.00_from1234.5.xyz", "results/cc/continued")
    body = [ln for ln in text.splitlines() if not ln.startswith("!")]
    changed = {a: b for a, b in zip(SCENE.splitlines(), body) if a != b}
    assert len(body) == len(SCENE.splitlines())
    assert changed == {
        "  shape = 'candycane'": "  shape = 'file'",
        "  coordinate_file = ''": "  coordinate_file = '/x/A1.00_from1234.5.xyz'",
        "  t_end = 2000.0000000000000": "  t_end = 765.5",
        "  directory = 'results/cc'": "  directory = 'results/cc/continued'",
        "  case_name = 'A1.00'": "  case_name = 'A1.00_from1234.5'",
    }
    # The core of the scene (what a continuation must not change) is the same.
    assert campaign.scene_differences(SCENE, text, {}) == []


def test_continuation_does_not_perturb_again():
    # A sample perturbed at its start (&chain perturbation > 0): the ledger's frame holds the
    # displaced trajectory; displacing the beads again at the continuation's start would make
    # the continued case another sample. Only the perturbation's value changes, to 0.
    perturbed = SCENE.replace("  seed = 1\n", "  seed = 1\n  perturbation = 0.99999999999999995E-6\n")
    e = entry()
    e["scene"] = perturbed
    text = campaign.continuation_scene(e, "/x/A1.00_from1234.5.xyz", "results/cc/continued")
    body = [ln for ln in text.splitlines() if not ln.startswith("!")]
    changed = {a: b for a, b in zip(perturbed.splitlines(), body) if a != b}
    assert len(body) == len(perturbed.splitlines())
    assert changed["  perturbation = 0.99999999999999995E-6"] == "  perturbation = 0.0"
    assert len(changed) == 6
    assert campaign._scene_value(text, "chain", "perturbation") == 0.0


def test_continuation_from_the_stepper_state(tmp_path):
    """With a state file the scene names it in &chain stepper_state: replaced where the scene has
    the variable, added to &chain where it was written before the variable existed; nothing else
    changes but what a plain continuation changes. The state file holds what knotflow reads
    (kf_stepper_state_file): /time on the segment's clock, the frame's positions, the arrays."""
    e = entry()
    e["last_frame"] = [[0.5, 1.0, 2.0], [1.5, 1.0, 2.0]]
    e["stepper_state"] = {"t": 1234.5, "t_local": 34.5, "method": "dopri45",
                          "reals": [0.01, 0.001, 0.1, 0.3, 34.5], "ints": [1, 10, 0, 61, 0, 0, 0]}
    assert campaign.usable_state(e)
    plain = campaign.continuation_scene(e, "/x/c.xyz", "d")
    for scene in (SCENE, SCENE.replace("  seed = 1\n", "  seed = 1\n  stepper_state = ''\n")):
        e["scene"] = scene
        text = campaign.continuation_scene(e, "/x/c.xyz", "d", "/x/c.state.h5")
        assert campaign._scene_value(text, "chain", "stepper_state") == "/x/c.state.h5"
        assert campaign.from_state(text) and not campaign.from_state(scene)
        without = [ln for ln in text.splitlines() if "stepper_state" not in ln]
        assert without == [ln for ln in campaign.continuation_scene(e, "/x/c.xyz", "d").splitlines()
                           if "stepper_state" not in ln]
    assert "stepper_state" not in plain
    path = str(tmp_path / "c.state.h5")
    campaign.write_state_file(path, e)
    with h5py.File(path, "r") as h:
        assert h["time"][()] == 34.5 and h["stepper"].attrs["name"] == "dopri45"
        assert np.array_equal(h["positions"][()], e["last_frame"])
        assert h["stepper/reals"].dtype == np.float64 and h["stepper/ints"].dtype == np.int64
        assert list(h["stepper/ints"][()]) == e["stepper_state"]["ints"]
    # Not usable: another frame than the newest, or a state of another stepper than the scene's.
    assert not campaign.usable_state({**e, "t_reached": 1240.0})
    assert not campaign.usable_state({**e, "stepper_state": {**e["stepper_state"], "method": "rk4"}})
    assert not campaign.usable_state(entry())


def test_continued_at_leaves_out_exact_continuations():
    """A continuation from the stepper state is the case's own resume: not a continued sample."""
    from knotflow_tools.io import Case
    with_state = SCENE.replace("  seed = 1\n", "  seed = 1\n  stepper_state = '/x/s.h5'\n")
    for scene, expected in ((SCENE, [1234.5]), (with_state, [])):
        case = Case(path="x.h5", attrs={"case_name": "A1.00_from1234.5", "scene": scene},
                    time=np.zeros(1), positions=np.zeros((1, 2, 3)))
        assert campaign.continued_at(case) == expected


def test_continuation_refused_when_nothing_is_left():
    with pytest.raises(ValueError, match="nothing left to run"):
        campaign.continuation_scene(entry(t_reached=2000.0), "a.xyz", "d")


def test_positions_every():
    t = np.arange(26.0) + 0.0
    assert campaign._every(t, 10.0) == [0, 10, 20, 25]
    assert campaign._every(np.arange(1200.0, 1221.0), 10.0) == [0, 10, 20]


def test_frame_rows_and_refusals(tmp_path):
    path = str(write_case(tmp_path / "A1.00.h5", unknotting_trefoil_frames(6), status="running"))
    with pytest.raises(ValueError, match="run knotflow-analyze first"):
        campaign.digest(path, str(tmp_path / "ledger"), "cc", 10)
    with h5py.File(path, "r+") as f:
        g = f.create_group("analysis/knots")
        g.attrs["closures"] = np.int64(10)
        g["frame_index"] = np.array([0, 2, 4], dtype=np.int64)
        g["time"] = np.array([0.0, 2.0, 4.0])
        g["kf"] = np.array([0.9, 0.5, 0.1])
    case = read_case(path)
    rows = campaign.frame_rows(case, 100.0)
    col = {c: k for k, c in enumerate(campaign.FRAME_COLUMNS)}
    assert np.array_equal(rows[:, col["t"]], 100.0 + np.arange(6.0))
    assert np.array_equal(rows[[0, 2, 4], col["kf"]], [0.9, 0.5, 0.1])
    assert np.all(np.isnan(rows[[1, 3, 5], col["kf"]]))
    assert np.array_equal(rows[:, col["rg"]], case.observables["rg"])
    with pytest.raises(ValueError, match="from 10 closures per frame, the ledger takes 20"):
        campaign.digest(path, str(tmp_path / "ledger"), "cc", 20)
    with pytest.raises(ValueError, match="k_f of 3 of 6 frames"):
        campaign.digest(path, str(tmp_path / "ledger"), "cc", 10)
    assert not (tmp_path / "ledger").exists()


def test_combined_totals_of_segments():
    seg = [{"t_offset": 0.0, "diagnostic_totals": {
               "strand_passages": 0, "first_passage_time": -1.0, "overlap_episodes": 3,
               "overlap_mean_duration": 0.2, "overlap_max_duration": 0.5,
               "max_overlapping_pairs": 4, "min_distance": 0.99, "max_bond_strain": 0.01}},
           {"t_offset": 700.0, "diagnostic_totals": {
               "strand_passages": 2, "first_passage_time": 12.5, "overlap_episodes": 1,
               "overlap_mean_duration": 1.0, "overlap_max_duration": 1.0,
               "max_overlapping_pairs": 2, "min_distance": 0.95, "max_bond_strain": 0.02}}]
    t = campaign.combined_totals(seg)
    assert t["strand_passages"] == 2 and t["first_passage_time"] == 712.5
    assert t["overlap_episodes"] == 4 and t["overlap_mean_duration"] == pytest.approx(0.4)
    assert t["overlap_max_duration"] == 1.0 and t["max_overlapping_pairs"] == 4
    assert t["min_distance"] == 0.95 and t["max_bond_strain"] == 0.02
    assert campaign.combined_totals([{"t_offset": 0.0, "diagnostic_totals": {}}]) is None


def test_kept_positions_in_chunks(tmp_path):
    (tmp_path / "cc").mkdir()
    (tmp_path / "cc" / "A1.00.json").write_text('{"ledger_version": 1, "n_beads": 3}')
    times = [10.0 * k for k in range(46)] + [455.0]
    frames = [np.arange(9.0).reshape(3, 3) + t for t in times]
    campaign._write_positions(str(tmp_path), "cc", "A1.00", times, frames)
    files = sorted(p.name for p in (tmp_path / "cc").iterdir() if p.name.endswith(".gz"))
    assert files == ["A1.00.positions.t00000.gz", "A1.00.positions.t00200.gz",
                     "A1.00.positions.t00400.gz"]
    t, r = campaign.read_positions(str(tmp_path), "cc", "A1.00")
    assert np.array_equal(t, times) and np.allclose(r, frames, atol=5e-5)
    # The next digest: a finished chunk keeps its bytes (and its file); the last one grows.
    stamp = {f: (tmp_path / "cc" / f).stat().st_mtime_ns for f in files}
    first = (tmp_path / "cc" / files[0]).read_bytes()
    times2 = times[:-1] + [460.0, 470.0]
    campaign._write_positions(str(tmp_path), "cc", "A1.00", times2, [np.zeros((3, 3))] * len(times2))
    assert (tmp_path / "cc" / files[0]).read_bytes() != first      # other content: rewritten
    campaign._write_positions(str(tmp_path), "cc", "A1.00", times2, [np.zeros((3, 3))] * len(times2))
    again = {f: (tmp_path / "cc" / f).stat().st_mtime_ns for f in files}
    campaign._write_positions(str(tmp_path), "cc", "A1.00", times2, [np.zeros((3, 3))] * len(times2))
    assert {f: (tmp_path / "cc" / f).stat().st_mtime_ns for f in files} == again
    assert stamp.keys() == again.keys()
    campaign._write_positions(str(tmp_path), "cc", "A1.00", times2[:5], [np.zeros((3, 3))] * 5)
    assert sorted(p.name for p in (tmp_path / "cc").iterdir() if p.name.endswith(".gz")) == files[:1]


def test_rows_to_t_end_are_a_finished_case(tmp_path):
    """A run killed while it was being marked finished holds every frame: the ledger counts
    it finished (plan has nothing left to run), one frame fewer is still running."""
    for nframes, status in ((6, "finished"), (5, "running")):
        path = str(write_case(tmp_path / "A1.00.h5", unknotting_trefoil_frames(nframes),
                              status="running", attrs={"integrator.t_end": 5.0}))
        with h5py.File(path, "r+") as f:
            g = f.create_group("analysis/knots")
            g.attrs["closures"] = np.int64(10)
            g["frame_index"] = np.arange(nframes, dtype=np.int64)
            g["time"] = np.arange(float(nframes))
            g["kf"] = np.zeros(nframes)
        ledger = str(tmp_path / f"ledger{nframes}")
        e = campaign.digest(path, ledger, "cc", 10)
        assert e["status"] == status and e["t_end"] == 5.0, e


def _ledger_entry(case, status, t_reached, t_end, walls_loads):
    runs = [{"commit": "abcdef012345", "wall_seconds": w, "load_mean": x} for w, x in walls_loads]
    return {"ledger_version": campaign.LEDGER_VERSION, "sweep": "tr", "case": case,
            "status": status, "t_reached": t_reached, "t_end": t_end,
            "segments": [{"runs": runs}]}


def test_status_counts_cases_and_time_left(tmp_path):
    """Rate = wall of all runs / time reached; time left = rate x (t_end − t_reached) of the
    running cases + rate x t_end of those not started (t_end from their scenes)."""
    import json
    ledger, scenes = tmp_path / "ledger", tmp_path / "scenes"
    (ledger / "tr").mkdir(parents=True)
    (scenes / "tr").mkdir(parents=True)
    (scenes / "cc").mkdir(parents=True)
    entries = [_ledger_entry("A1", "finished", 1000.0, 1000.0, [(3000.0, 2.0), (1000.0, 4.0)]),
               _ledger_entry("A2", "running", 500.0, 1000.0, [(2000.0, 2.0)])]
    for e in entries:
        (ledger / "tr" / (e["case"] + ".json")).write_text(json.dumps(e))
    for name, t_end in (("A1", 1000.0), ("A2", 1000.0), ("A3", 800.0)):
        (scenes / "tr" / (name + ".nml")).write_text(
            SCENE.replace("2000.0000000000000", repr(t_end)).replace("candycane", "trefoil"))
    (scenes / "cc" / "B1.nml").write_text(SCENE)
    lines = campaign.status_lines(str(ledger), str(scenes))
    assert lines[0] == ("tr/A1: finished, t = 1000 of 1000, 1 segment(s), wall 1.11 h, load 2.5, "
                        "commits abcdef0")
    assert lines[1].startswith("tr/A2: running, t = 500 of 1000,")
    # cc: one case, nothing measured; tr: 6000 s for 1500 time units = 4 s per time unit, left
    # 500 + 800 time units = 5200 s (without the scenes: 500, 2000 s); load
    # (3000*2 + 1000*4 + 2000*2) / 6000.
    assert lines[2] == "cc: 0 of 1 finished, 0 running, 1 not started; no rate measured yet"
    assert lines[3] == ("tr: 1 of 3 finished, 1 running, 1 not started; 4.00 s of wall per time "
                        "unit (load 2.3): about 1.4 h of one worker left")
    assert lines[4] == ("campaign: 1 of 4 cases finished; about 1.4 h of one worker left at the "
                        "measured rates (sweeps without a measured rate not counted)")
    assert campaign.status_lines(str(ledger)) == lines[:2] + [
        "tr: 1 of 2 finished, 1 running; 4.00 s of wall per time unit (load 2.3): about 0.6 h of "
        "one worker left"]


def test_status_rate_from_the_newest_kernels(tmp_path):
    """Runs that recorded their BLAS kernels: the rate comes from the runs on the kernels of
    the newest of them (by `started`); older runs (other kernels, or none recorded) are left
    out of it but still count for the time reached."""
    import json
    ledger = tmp_path / "ledger"
    (ledger / "tr").mkdir(parents=True)

    def run(started, blas, t0, t1, wall, load):
        return {"commit": "abcdef012345", "started": started, "blas": blas, "t_start": t0,
                "t_end": t1, "wall_seconds": wall, "load_mean": load}
    a1 = _ledger_entry("A1", "running", 600.0, 1000.0, [])
    a1["segments"] = [{"runs": [run("2026-12-02T11:00:00Z", None, 0.0, 300.0, 6000.0, 3.0),
                                run("2026-12-02T16:00:00Z", "OpenBLAS 0.3.21 Prescott", 300.0,
                                    400.0, 1000.0, 2.0),
                                run("2026-12-02T17:00:00Z", "OpenBLAS 0.3.21 SkylakeX", 400.0,
                                    500.0, 300.0, 2.0)]},
                      {"runs": [run("2026-12-02T18:00:00Z", "OpenBLAS 0.3.21 SkylakeX", 0.0,
                                    100.0, 200.0, 4.0)]}]
    (ledger / "tr" / "A1.json").write_text(json.dumps(a1))
    lines = campaign.status_lines(str(ledger))
    # SkylakeX runs: 300 + 200 s for 100 + 100 time units = 2.5 s per time unit, load
    # (300*2 + 200*4) / 500 = 2.8; left 400 time units = 1000 s = 0.28 h
    assert lines[-1] == ("tr: 0 of 1 finished, 1 running; 2.50 s of wall per time unit (load "
                         "2.8, runs with OpenBLAS 0.3.21 SkylakeX): about 0.3 h of one worker left")


def test_windows_table_of_two_runs(tmp_path, capsys):
    """`knotflow-campaign windows`: a run and one started at t = 20 of it (--offset), window by
    window; without /analysis no k_f (nan) and no modes (-); an --offset per case."""
    from knotflow_tools import cli
    from knotflow_tools.shape import shape_series
    frames = unknotting_trefoil_frames(6)
    (tmp_path / "full").mkdir()
    (tmp_path / "late").mkdir()
    full = str(write_case(tmp_path / "full" / "A1.h5", frames, time=10.0 * np.arange(6)))
    late = str(write_case(tmp_path / "late" / "A1.h5", frames[2:], time=10.0 * np.arange(4)))
    assert cli.main_campaign(["windows", full, late, "--width", "20", "--offset", "0", "20"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("| window | case | frames | R_g |")
    rows = [[x.strip() for x in line.split("|")[1:-1]] for line in lines[2:]]
    # full: windows 0-20 (t 0, 10), 20-40 (20, 30), 40-60 (40, 50); late: 20-40, 40-60
    assert [r[:3] for r in rows] == [["0-20", "full/A1", "2"], ["20-40", "full/A1", "2"],
                                     ["20-40", "late/A1", "2"], ["40-60", "full/A1", "2"],
                                     ["40-60", "late/A1", "2"]]
    rg = shape_series(frames)["rg"]
    assert float(rows[1][3]) == pytest.approx(rg[2:4].mean(), abs=0.05)
    assert rows[1][3:11] == rows[2][3:11]
    bc = shape_series(frames)["b"] / shape_series(frames)["c"]
    assert float(rows[1][8]) == pytest.approx(bc[2:4].min(), abs=0.05)
    assert rows[0][11:] == ["nan", "nan", "-", "-"]
    assert cli.main_campaign(["windows", full, late, "--width", "20", "--offset", "5"]) == 2
    assert "--offset: 1 value(s) for 2 case(s)" in capsys.readouterr().err
    assert cli.main_campaign(["windows", full, "--width", "0"]) == 2
    assert "window width 0.0" in capsys.readouterr().err


def test_shape_map_figure(tmp_path, capsys):
    """`knotflow-campaign shapes`: a PNG of the frames of two runs in the plane of b/c and a/b;
    a case without a frame in the time range and a wrong number of offsets are refused."""
    from knotflow_tools import cli
    frames = unknotting_trefoil_frames(6)
    (tmp_path / "full").mkdir()
    full = str(write_case(tmp_path / "full" / "A1.h5", frames, time=10.0 * np.arange(6)))
    out = tmp_path / "map.png"
    assert cli.main_campaign(["shapes", full, full, "--offset", "0", "20", "--from", "20",
                              "--out", str(out)]) == 0
    assert capsys.readouterr().out.strip() == str(out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert cli.main_campaign(["shapes", full, "--from", "60", "--out", str(out)]) == 2
    assert "no frame in the time range" in capsys.readouterr().err
    assert cli.main_campaign(["shapes", full, full, "--offset", "5", "--out", str(out)]) == 2
    assert "--offset: 1 value(s) for 2 case(s)" in capsys.readouterr().err


def test_ledger_case_names_its_overlap_rule(tmp_path):
    """A ledger entry carries the overlap rule of its scene (`&hydro overlap`), so the study's
    tables name the rule a case ran with: a multipole case with overlap = 'relax' is 'relax',
    a model without an overlap rule has none."""
    from knotflow_tools import study_rows
    multipole = SCENE + "&hydro\n  model = 'multipole'\n  overlap = 'relax'\n/\n"
    rpy = SCENE + "&hydro\n  model = 'rpy'\n  overlap = 'pair'\n/\n"
    for scene, rule in ((multipole, "relax"), (rpy, None)):
        path = str(write_case(tmp_path / "A1.00.h5", unknotting_trefoil_frames(3),
                              attrs={"integrator.t_end": 2.0, "scene": scene}))
        with h5py.File(path, "r+") as f:
            g = f.create_group("analysis/knots")
            g.attrs["closures"] = np.int64(10)
            g["frame_index"] = np.arange(3, dtype=np.int64)
            g["time"] = np.arange(3.0)
            g["kf"] = np.zeros(3)
        ledger = tmp_path / f"ledger_{rule}"
        campaign.digest(path, str(ledger), "cc", 10)
        case = campaign.ledger_case(str(ledger / "cc" / "A1.00.json"))
        assert study_rows.overlap_rule(case) == rule


def test_ledger_keeps_the_elastic_viscosity_and_reads_version_1(tmp_path):
    """Version 2 rows carry viscosity_elastic (the ledger case then has both parts of the
    viscosity); a version 1 ledger (no such column) is read with it NaN and no parts."""
    frames = unknotting_trefoil_frames(5)
    n = frames.shape[1]
    path = str(write_case(tmp_path / "A1.00.h5", frames,
                          attrs={"flow.flow_type": "shear", "flow.shear_rate": 1.0}))
    k = np.arange(5, dtype=float)
    hyd, el = np.zeros((5, 3, 3)), np.zeros((5, 3, 3))
    hyd[:, 0, 2] = hyd[:, 2, 0] = 2.0
    el[:, 0, 2] = el[:, 2, 0] = 0.5 * k
    with h5py.File(path, "r+") as f:
        g = f["frames"].create_group("stresslet")
        g["hydrodynamic"], g["elastic"] = hyd, el
        g["viscosity"] = 6.0 * (2.0 + 0.5 * k) / n
        g["psi1"] = g["psi2"] = np.zeros(5)
        a = f.create_group("analysis/knots")
        a.attrs["closures"] = np.int64(10)
        a["frame_index"] = np.arange(5, dtype=np.int64)
        a["time"] = np.arange(5.0)
        a["kf"] = np.zeros(5)
    ledger = str(tmp_path / "ledger")
    campaign.digest(path, ledger, "cc", 10)
    case = campaign.ledger_case(os.path.join(ledger, "cc", "A1.00.json"))
    assert np.allclose(case.stresslet["viscosity_elastic"], 3.0 * k / n, rtol=1e-6)
    assert np.allclose(case.stresslet["viscosity_hydrodynamic"], 12.0 / n, rtol=1e-6)
    csv = tmp_path / "ledger" / "cc" / "A1.00.csv"
    lines = csv.read_text(encoding="utf-8").splitlines()
    old = [",".join(campaign.FRAME_COLUMNS_V1)] + [r.rsplit(",", 1)[0] for r in lines[1:]]
    csv.write_text("\n".join(old) + "\n", encoding="utf-8")
    jpath = tmp_path / "ledger" / "cc" / "A1.00.json"
    entry = json.loads(jpath.read_text(encoding="utf-8"))
    entry["ledger_version"] = 1
    jpath.write_text(json.dumps(entry), encoding="utf-8")
    rows = campaign.read_rows(ledger, "cc", "A1.00")
    assert rows.shape == (5, len(campaign.FRAME_COLUMNS))
    assert np.all(np.isnan(rows[:, -1]))
    case = campaign.ledger_case(str(jpath))
    assert "viscosity_elastic" not in case.stresslet
    assert np.allclose(case.stresslet["viscosity"], 6.0 * (2.0 + 0.5 * k) / n, rtol=1e-6)


HYDRO = "&hydro\n  model = 'multipole'\n  overlap = 'relax'\n/\n"


def test_scene_differences_and_the_programs_defaults():
    """A scene variable written in one scene only (added by a later version of the program,
    which writes its default) is the same as its default, taken from the program's own
    `--scene-reference` (docs/scenes.md is that output, checked by the docs tests); a different
    value, or a variable the reference does not know, is another scene, named."""
    reference = (__import__("pathlib").Path(__file__).resolve().parents[2] / "docs" / "scenes.md")
    defaults = campaign.scene_defaults(reference.read_text(encoding="utf-8"))
    assert ("hydro", "solver_tolerance") in defaults and ("integrator", "method") in defaults
    old = SCENE + HYDRO
    new = SCENE.replace("1.0000000000000000", "1.0") + HYDRO.replace(
        "  overlap = 'relax'\n", "  overlap = 'relax'\n  solver_tolerance = 0.99999999999999995E-6\n")
    assert campaign.scene_differences(old, new, defaults) == []
    assert campaign.scene_differences(old, new, {}) == [
        "&hydro solver_tolerance: (not written), 0.99999999999999995E-6"]
    looser = new.replace("0.99999999999999995E-6", "0.1E-3")
    assert campaign.scene_differences(old, looser, defaults) == [
        "&hydro solver_tolerance: (not written), 0.1E-3"]
    other = new.replace("'relax'", "'pair'")
    assert campaign.scene_differences(old, other, defaults) == ["&hydro overlap: 'relax', 'pair'"]
    unknown = new.replace("  model = 'multipole'\n", "  model = 'multipole'\n  no_such_variable = 1\n")
    assert campaign.scene_differences(old, unknown, defaults) == [
        "&hydro no_such_variable: (not written), 1"]


def test_continuation_with_a_new_default_is_digested(tmp_path):
    """A continuation run by a later program writes a new scene variable with its default: the
    ledger takes it with the program's defaults and refuses it, naming the variable, without."""
    ledger = str(tmp_path / "ledger")
    old = SCENE + HYDRO
    new = old.replace("  overlap = 'relax'\n", "  overlap = 'relax'\n  solver_tolerance = 0.1E-5\n")
    frames = unknotting_trefoil_frames(6)
    for name, scene, t0 in (("A1.00", old, 0.0), ("A1.00_from5", new, 5.0)):
        part = frames if t0 == 0.0 else frames[:3]
        path = str(write_case(tmp_path / f"{name}.h5", part, status="running",
                              attrs={"integrator.t_end": 10.0 - t0, "scene": scene,
                                     "case_name": name}))
        with h5py.File(path, "r+") as f:
            g = f.create_group("analysis/knots")
            g.attrs["closures"] = np.int64(10)
            g["frame_index"] = np.arange(len(part), dtype=np.int64)
            g["time"] = np.arange(float(len(part)))
            g["kf"] = np.zeros(len(part))
        if t0 == 0.0:
            campaign.digest(path, ledger, "cc", 10)
    with pytest.raises(ValueError, match="another scene.*&hydro solver_tolerance: \\(not written\\), 0.1E-5"):
        campaign.digest(path, ledger, "cc", 10)
    defaults = {("hydro", "solver_tolerance"): "0.1E-5"}
    e = campaign.digest(path, ledger, "cc", 10, defaults=defaults)
    assert len(e["segments"]) == 2 and e["t_reached"] == 7.0, e
    # the case is marked continued at the continuation's time (its stepper restarted there);
    # so is the continuation's own case file, by its name
    case = campaign.ledger_case(os.path.join(ledger, "cc", "A1.00.json"))
    assert campaign.continued_at(case) == [5.0]
    assert campaign.continued_at(read_case(path)) == [5.0]
    assert campaign.continued_at(read_case(str(tmp_path / "A1.00.h5"))) == []


def test_status_rate_from_alike_sweeps(tmp_path, capsys):
    """A sweep with time left and no run of its own takes the pooled rate of the sweeps with a
    rate whose scenes are alike (the same chain shape and beads, hydrodynamics, integration,
    flow and forces but for the bending stiffness); a variable written in one scene only counts
    as the same only when it has the program's default (--scene-reference)."""
    import json

    from knotflow_tools import cli
    base = SCENE.replace("candycane", "trefoil").replace("n_beads = 152", "n_beads = 99").replace(
        "2000.0000000000000", "1000.0000000000000").replace(
        "&integrator", "&hydro\n  model = 'multipole'\n  update = 'iterative'\n/\n&integrator")
    ledger, scenes = tmp_path / "ledger", tmp_path / "scenes"
    (ledger / "ma").mkdir(parents=True)
    e = _ledger_entry("A0.80_s1", "finished", 1000.0, 1000.0, [(3000.0, 2.0), (1000.0, 4.0)])
    e["sweep"], e["scene"] = "ma", base.replace("bending_a = 1.0", "bending_a = 0.8")
    (ledger / "ma" / "A0.80_s1.json").write_text(json.dumps(e))
    later = base.replace("  update = 'iterative'", "  update = 'iterative'\n  solver_tolerance = 0.1E-5")
    cases = {"mb": later.replace("seed = 1", "seed = 3").replace("bending_a = 1.0", "bending_a = 2.2"),
             "mc": later.replace("n_beads = 99", "n_beads = 152"),
             "md": later.replace("'iterative'", "'adaptive'")}
    for sweep, text in cases.items():
        (scenes / sweep).mkdir(parents=True)
        for k in (1, 2):
            (scenes / sweep / f"A{k}.nml").write_text(text)
    ma = ("ma: 1 of 1 finished, 0 running, 0 not started; 4.00 s of wall per time unit (load "
          "2.5): about 0.0 h of one worker left")
    # without the default of solver_tolerance the older scene may have run with another value
    lines = campaign.status_lines(str(ledger), str(scenes))
    assert lines[1:] == [ma] + [f"{s}: 0 of 2 finished, 0 running, 2 not started; no rate "
                                "measured yet" for s in ("mb", "mc", "md")] + [
        "campaign: 1 of 7 cases finished; about 0.0 h of one worker left at the measured rates "
        "(sweeps without a measured rate not counted)"]
    # with it (written as knotflow writes it, 1e-6 in another format): mb, 2000 time units at
    # 4 s; mc (other beads) and md (other update) stay without a rate
    lines = campaign.status_lines(str(ledger), str(scenes), {("hydro", "solver_tolerance"): "1.0e-6"})
    assert lines[2] == ("mb: 0 of 2 finished, 0 running, 2 not started; no rate measured yet, at "
                        "that of ma (alike scenes): 4.00 s of wall per time unit (load 2.5): about "
                        "2.2 h of one worker left")
    assert lines[3].endswith("no rate measured yet") and lines[4].endswith("no rate measured yet")
    assert lines[5].startswith("campaign: 1 of 7 cases finished; about 2.2 h of one worker left")
    st = campaign.status(str(ledger), str(scenes), {("hydro", "solver_tolerance"): "1.0e-6"})
    assert [w["rate_from"] for w in st["sweeps"]] == [[], ["ma"], [], []]
    # another default: the older scene ran with another solver tolerance, not alike
    lines = campaign.status_lines(str(ledger), str(scenes), {("hydro", "solver_tolerance"): "1.0e-4"})
    assert lines[2].endswith("no rate measured yet")
    # the command line: --scene-reference FILE (knotflow --scene-reference's Markdown)
    ref = tmp_path / "scene-reference.md"
    ref.write_text("## `&hydro`\n\n| variable | default |\n|---|---|\n| `solver_tolerance` | `1.0e-6` |\n")
    assert cli.main_campaign(["status", "--ledger", str(ledger), "--scenes", str(scenes),
                              "--scene-reference", str(ref), "--markdown"]) == 0
    out = capsys.readouterr().out
    assert "| `mb` | 2 | 0 | - | 2 | 4.00 (2.5), that of `ma` | 2.2 |" in out
    with pytest.raises(SystemExit) as stop:
        cli.main_campaign(["status", "--ledger", str(ledger), "--scene-reference",
                           str(tmp_path / "none.md")])
    assert stop.value.code == 2 and "--scene-reference" in capsys.readouterr().err
