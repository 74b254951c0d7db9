"""knotflow.run_scene / read_case / scene_cases: a scene run in this process equals the same
scene run by the program knotflow to the last bit (every frame), read_case equals h5py's reading
of the file, and bad scenes, paths and files raise KnotflowError with the library's message."""

import os
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import h5py
import numpy as np
import pytest

import knotflow
from knotflow import KnotflowError

from conftest import program

SCENE = """&chain shape = 'trefoil', orientation = 'c' /
&forces excluded_volume = .true. /
&integrator t_end = 3.0 /
&output directory = '{directory}', case_name = 'c', frame_interval = 0.5, progress_interval = 0.0 /
{extra}"""

OBSERVABLES = ("rg", "a", "b", "c", "theta", "phi", "close_pairs")


def write_scene(path: Path, directory: Path | str, extra: str = "") -> Path:
    path.write_text(SCENE.format(directory=directory, extra=extra))
    return path


def run_program(scene: Path) -> None:
    # one BLAS thread, as in this process's library for these small sizes
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    done = subprocess.run([program("knotflow"), str(scene)], capture_output=True, text=True, env=env,
                          check=False)
    assert done.returncode == 0, done.stdout + done.stderr


def h5_frames(path: Path) -> dict:
    with h5py.File(path, "r") as f:
        status = f.attrs["status"]
        out = {"time": f["frames/time"][:], "positions": f["frames/positions"][:],
               "status": status.decode() if isinstance(status, bytes) else status}
        for name in OBSERVABLES:
            out[name] = f["frames/observables"][name][:]
    return out


def assert_case_is_file(case: knotflow.Case, path: Path) -> None:
    """read_case equals h5py's reading of the same file, array for array."""
    want = h5_frames(path)
    assert case.path == path
    assert case.status == want["status"] == "finished"
    assert np.array_equal(case.time, want["time"])
    assert case.positions.shape == want["positions"].shape == (case.nframes, case.n_beads, 3)
    assert np.array_equal(case.positions, want["positions"])
    for name in OBSERVABLES:
        assert np.array_equal(case.observables[name], want[name]), name
        assert case.observables[name].dtype == want[name].dtype, name


def test_run_scene_equals_the_program(tmp_path):
    prog = write_scene(tmp_path / "prog.nml", tmp_path / "prog")
    run_program(prog)
    py_scene = write_scene(tmp_path / "py.nml", tmp_path / "elsewhere")
    assert knotflow.scene_cases(py_scene, output_dir=tmp_path / "py") == (tmp_path / "py" / "c.h5",)
    assert not (tmp_path / "py").exists()          # scene_cases writes nothing
    res = knotflow.run_scene(py_scene, output_dir=tmp_path / "py")
    assert res.case_files == (tmp_path / "py" / "c.h5",) and res.statuses == ("finished",)
    assert not (tmp_path / "elsewhere").exists()   # output_dir replaced the scene's directory
    theirs, ours = h5_frames(tmp_path / "prog" / "c.h5"), h5_frames(res.case_files[0])
    # t_end / frame_interval + 1 frames of the 99-bead trefoil, every one equal to the last bit
    assert ours["positions"].shape == (7, 99, 3)
    assert np.array_equal(ours["time"], theirs["time"])
    assert np.array_equal(ours["positions"], theirs["positions"])
    for name in OBSERVABLES:
        assert np.array_equal(ours[name], theirs[name]), name
    assert not np.array_equal(ours["positions"][0], ours["positions"][-1])   # it moved
    assert_case_is_file(res.read(), res.case_files[0])
    assert_case_is_file(knotflow.read_case(str(tmp_path / "prog" / "c.h5")), tmp_path / "prog" / "c.h5")
    # the library's shape of a frame is the frame's recorded observables
    s = knotflow.shape(ours["positions"][3])
    assert (s.rg, s.close_pairs) == (ours["rg"][3], ours["close_pairs"][3])
    # run again: the finished case is skipped, the file unchanged
    again = knotflow.run_scene(py_scene, output_dir=tmp_path / "py")
    assert again.statuses == ("skipped",)
    assert np.array_equal(h5_frames(res.case_files[0])["positions"], ours["positions"])


def test_a_sweep_runs_every_case(tmp_path):
    scene = write_scene(tmp_path / "s.nml", tmp_path / "out", "&sweep bending_a = 1.0, 3.0 /\n")
    res = knotflow.run_scene(scene)
    assert [p.name for p in res.case_files] == ["c_A1.00.h5", "c_A3.00.h5"]
    assert res.statuses == ("finished", "finished") and len(res.messages) == 2
    one, three = (knotflow.read_case(p) for p in res.case_files)
    with h5py.File(res.case_files[1], "r") as f:
        assert f.attrs["forces.bending_a"] == 3.0
    assert np.array_equal(one.positions[0], three.positions[0])       # the same start
    assert not np.array_equal(one.positions[-1], three.positions[-1])  # another stiffness
    assert_case_is_file(three, res.case_files[1])


def test_a_bad_scene_is_refused_before_anything_is_written(tmp_path):
    out = tmp_path / "out"
    scene = write_scene(tmp_path / "bad.nml", out, "&hydro model = 'multipole', order = 11 /\n")
    # the program's message, word for word
    done = subprocess.run([program("knotflow"), str(scene)], capture_output=True, text=True, check=False)
    assert done.returncode == 2 and not out.exists()
    expected = done.stderr.strip().removeprefix("knotflow: error: ")
    assert "bad.nml: &hydro: order = 11 is not allowed" in expected
    with pytest.raises(KnotflowError) as err:
        knotflow.run_scene(scene)
    assert str(err.value) == expected and err.value.status == 1
    assert not out.exists()
    with pytest.raises(KnotflowError) as err:
        knotflow.scene_cases(scene)
    assert str(err.value) == expected
    with pytest.raises(KnotflowError, match=r"missing\.nml: file not found"):
        knotflow.run_scene(tmp_path / "missing.nml")
    assert not out.exists()


def test_a_case_file_of_another_scene_is_refused(tmp_path):
    out = tmp_path / "out"
    knotflow.run_scene(write_scene(tmp_path / "a.nml", out))
    other = tmp_path / "b.nml"
    other.write_text((tmp_path / "a.nml").read_text().replace("t_end = 3.0", "t_end = 2.0"))
    with pytest.raises(KnotflowError, match=r"b\.nml: .*c\.h5 \(finished\) was computed with another scene: "
                       r"&integrator: t_end = 3\.0 in the file, 2\.0 requested"):
        knotflow.run_scene(other)
    # the lock of the first run was released: the same scene runs (skips) again in this process
    assert knotflow.run_scene(tmp_path / "a.nml").statuses == ("skipped",)


@pytest.mark.parametrize(("path", "message"), [
    ("", "an empty path"), ("a\0b", "NUL"), (3, "expected a path")])
def test_bad_paths(path, message):
    for call in (knotflow.run_scene, knotflow.read_case, knotflow.scene_cases):
        with pytest.raises(KnotflowError, match=message):
            call(path)


def test_read_case_refuses_what_is_no_case_file(tmp_path):
    with pytest.raises(KnotflowError, match=r"case file '.*nothere\.h5': not found"):
        knotflow.read_case(tmp_path / "nothere.h5")
    text = tmp_path / "text.h5"
    text.write_text("not HDF5\n")
    with pytest.raises(KnotflowError, match=r"text\.h5.*corrupt"):
        knotflow.read_case(text)
    plain = tmp_path / "plain.h5"
    with h5py.File(plain, "w") as f:
        f.attrs["status"] = np.bytes_("finished")
    with pytest.raises(KnotflowError, match=r"plain\.h5': no /frames group \(not a knotflow case file\)"):
        knotflow.read_case(plain)
    with h5py.File(plain, "a") as f:
        f["frames/time"] = np.arange(3.0)
        f["frames/positions"] = np.zeros((3, 4, 3))
    with pytest.raises(KnotflowError, match=r"/frames/observables/rg missing"):
        knotflow.read_case(plain)
    with pytest.raises(KnotflowError, match="not a regular file|corrupt"):
        knotflow.read_case(tmp_path)


def test_read_case_in_threads(tmp_path):
    res = knotflow.run_scene(write_scene(tmp_path / "t.nml", tmp_path / "out"))
    first = knotflow.read_case(res.case_files[0])
    with ThreadPoolExecutor(max_workers=4) as pool:
        cases = list(pool.map(lambda _: knotflow.read_case(res.case_files[0]), range(8)))
    for c in cases:
        assert np.array_equal(c.positions, first.positions) and np.array_equal(c.time, first.time)


def test_ctrl_c_stops_after_a_frame_and_the_run_resumes(tmp_path):
    """SIGINT to a Python process inside run_scene (Ctrl-C) stops the running case after a whole
    frame with its checkpoint, starts no further case and raises KeyboardInterrupt; run_scene
    again resumes both cases, and the files equal the program's uninterrupted run frame for frame."""
    import signal
    import sys
    import time
    sweep = "&sweep bending_a = 2.2, 3.0 /\n"
    scene = write_scene(tmp_path / "long.nml", tmp_path / "py", sweep)
    scene.write_text(scene.read_text().replace("t_end = 3.0", "t_end = 200.0"))
    # the interpreter's Ctrl-C (a process started in the background may inherit SIGINT ignored)
    code = ("import signal, sys, knotflow; signal.signal(signal.SIGINT, signal.default_int_handler); "
            "knotflow.run_scene(sys.argv[1])")
    child = subprocess.Popen([sys.executable, "-c", code, str(scene)], cwd=tmp_path,
                             env=dict(os.environ, OPENBLAS_NUM_THREADS="1"),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    first = tmp_path / "py" / "c_A2.20.h5"
    for _ in range(600):   # the first case file appears when its run starts (at most 60 s)
        if first.exists() or child.poll() is not None:
            break
        time.sleep(0.1)
    time.sleep(0.5)
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=120)
    assert child.returncode != 0 and "KeyboardInterrupt" in err, out + err
    stopped = h5_frames(first)
    assert stopped["status"] == "running" and 2 <= len(stopped["time"]) < 401
    assert np.all(np.isfinite(stopped["positions"]))
    assert not (tmp_path / "py" / "c_A3.00.h5").exists()
    run = knotflow.run_scene(scene)
    assert run.statuses == ("finished", "finished")
    program_scene = write_scene(tmp_path / "prog.nml", tmp_path / "prog", sweep)
    program_scene.write_text(scene.read_text().replace(str(tmp_path / "py"), str(tmp_path / "prog")))
    run_program(program_scene)
    for name in ("c_A2.20", "c_A3.00"):
        ours, theirs = h5_frames(tmp_path / "py" / f"{name}.h5"), h5_frames(tmp_path / "prog" / f"{name}.h5")
        assert ours["status"] == theirs["status"] == "finished"
        for key in ("time", "positions", *OBSERVABLES):
            assert np.array_equal(ours[key], theirs[key]), (name, key)
