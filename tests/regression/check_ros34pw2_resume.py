"""The Rosenbrock-W stepper (&integrator method = 'ros34pw2') in the real program, killed and resumed.

A trefoil with RPY hydrodynamics and excluded volume, t_end = 30, one frame per time unit, once
with jacobian_steps = 1 and 3 (which RPY ignores: its mobility is never kept). Each is run uninterrupted, and again killed with SIGKILL after t = 10 and
rerun: the rerun resumes from the checkpoint and its frames equal the uninterrupted run's bit for
bit (positions and the integrator counts per frame); the checkpoint names the stepper 'ros34pw2'
and holds its state (err_prev; the count of Jacobians, one per accepted step).
Usage: check_ros34pw2_resume.py KNOTFLOW WORKDIR
"""
import os
import shutil
import signal
import subprocess
import sys

import h5py
import numpy as np

exe, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def scene(name, keep):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write("""&chain shape = 'trefoil', orientation = 'c' /
&forces excluded_volume = .true. /
&integrator method = 'ros34pw2', t_end = 30.0, jacobian_steps = %d /
&output directory = '%s', case_name = 'c', frame_interval = 1.0, progress_interval = 0.0 /
""" % (keep, os.path.join(work, name)))
    return path


def frames(name):
    with h5py.File(os.path.join(work, name, "c.h5"), "r") as h:
        counts = {k: h["frames/integrator/" + k][:] for k in h["frames/integrator"].keys()}
        return h.attrs["status"], h["frames/time"][:], h["frames/positions"][:], counts


for keep in (1, 3):
    ref = "reference_keep%d" % keep
    run = subprocess.run([exe, scene(ref, keep)], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    status, t_ref, r_ref, c_ref = frames(ref)
    assert status in (b"finished", "finished"), status

    killed = "killed_keep%d" % keep
    path = scene(killed, keep)
    proc = subprocess.Popen([exe, path], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    for line in proc.stdout:          # one progress line per frame (progress_interval = 0)
        if ": t = 10.000 /" in line:
            break
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    with h5py.File(os.path.join(work, killed, "c.h5"), "r") as h:
        n_killed = h["frames/time"].shape[0]
        assert h.attrs["status"] in (b"running", "running")
        slots = [s for s in h["checkpoint"].keys() if "stepper" in h["checkpoint"][s]]
        assert slots, list(h["checkpoint"].keys())
        for s in slots:
            st = h["checkpoint"][s]["stepper"]
            assert st.attrs["name"] in (b"ros34pw2", "ros34pw2"), st.attrs["name"]
            ints = st["ints"][:]
            assert len(ints) == 4 + 1 and ints[4] == ints[1], ints   # a Jacobian per step
            assert len(st["reals"][:]) == 3 + 1
    assert n_killed < len(t_ref), "the run finished before it could be killed"
    again = subprocess.run([exe, path], capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    assert "resuming" in again.stdout, again.stdout
    status, t, r, c = frames(killed)
    assert status in (b"finished", "finished")
    assert np.array_equal(t, t_ref), (t, t_ref)
    assert np.array_equal(r, r_ref), np.abs(r - r_ref).max()
    for k in c_ref:
        assert np.array_equal(c[k], c_ref[k]), (k, c[k], c_ref[k])
    print("jacobian_steps = %d: killed at %d frames, resumed: %d frames equal to the uninterrupted "
          "run bit for bit, %d steps" % (keep, n_killed, len(t), int(c_ref["steps"][-1])))
