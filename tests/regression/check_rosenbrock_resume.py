"""The Rosenbrock-W steppers (&integrator method = 'ros34pw2', 'ros34pw3') in the real program,
killed and resumed.

A trefoil with RPY hydrodynamics and excluded volume, t_end = 30, one frame per time unit:
ros34pw2 with jacobian_steps = 1 and 3 (which RPY ignores: its mobility is never kept), ros34pw3
with 1. Each is run uninterrupted, and again killed with SIGKILL after t = 10 and rerun: the
rerun resumes from the checkpoint and its frames equal the uninterrupted run's bit for bit
(positions and the integrator counts per frame); the checkpoint names the stepper and holds its
state (err_prev; the count of Jacobians, one per accepted step). The two methods differ (frames
not equal). A killed case of one method is refused by the other (the scene differs in &integrator
method; exit status 2, the file left as it was).
Usage: check_rosenbrock_resume.py KNOTFLOW WORKDIR
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


def scene(name, method, keep, directory=None):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write("""&chain shape = 'trefoil', orientation = 'c' /
&forces excluded_volume = .true. /
&integrator method = '%s', t_end = 30.0, jacobian_steps = %d /
&output directory = '%s', case_name = 'c', frame_interval = 1.0, progress_interval = 0.0 /
""" % (method, keep, os.path.join(work, directory or name)))
    return path


def frames(name):
    with h5py.File(os.path.join(work, name, "c.h5"), "r") as h:
        counts = {k: h["frames/integrator/" + k][:] for k in h["frames/integrator"].keys()}
        return h.attrs["status"], h["frames/time"][:], h["frames/positions"][:], counts


final = {}
for method, keep in (("ros34pw2", 1), ("ros34pw2", 3), ("ros34pw3", 1)):
    ref = "reference_%s_keep%d" % (method, keep)
    run = subprocess.run([exe, scene(ref, method, keep)], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    status, t_ref, r_ref, c_ref = frames(ref)
    assert status in (b"finished", "finished"), status

    final[method] = r_ref[-1]
    killed = "killed_%s_keep%d" % (method, keep)
    path = scene(killed, method, keep)
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
            assert st.attrs["name"] in (method.encode(), method), st.attrs["name"]
            ints = st["ints"][:]
            assert len(ints) == 4 + 1 and ints[4] == ints[1], ints   # a Jacobian per step
            assert len(st["reals"][:]) == 3 + 1
    assert n_killed < len(t_ref), "the run finished before it could be killed"
    if keep == 1:   # the other method refuses this checkpoint, and writes nothing
        other = "ros34pw3" if method == "ros34pw2" else "ros34pw2"
        h5 = os.path.join(work, killed, "c.h5")
        before = open(h5, "rb").read()
        wrong = subprocess.run([exe, scene("wrong_" + killed, other, keep, directory=killed)],
                               capture_output=True, text=True, timeout=600)
        assert wrong.returncode == 2, (wrong.returncode, wrong.stdout, wrong.stderr)
        expected = "method = '%s' in the file, '%s' requested" % (method, other)
        assert expected in wrong.stderr, wrong.stderr
        assert open(h5, "rb").read() == before, "the refused run changed the case file"
        print("%s checkpoint refused by %s: %s" % (method, other, wrong.stderr.strip()))
    again = subprocess.run([exe, path], capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    assert "resuming" in again.stdout, again.stdout
    status, t, r, c = frames(killed)
    assert status in (b"finished", "finished")
    assert np.array_equal(t, t_ref), (t, t_ref)
    assert np.array_equal(r, r_ref), np.abs(r - r_ref).max()
    for k in c_ref:
        assert np.array_equal(c[k], c_ref[k]), (k, c[k], c_ref[k])
    print("%s, jacobian_steps = %d: killed at %d frames, resumed: %d frames equal to the uninterrupted "
          "run bit for bit, %d steps" % (method, keep, n_killed, len(t), int(c_ref["steps"][-1])))
deviation = np.linalg.norm(final["ros34pw2"] - final["ros34pw3"], axis=-1).max()
assert deviation > 0.0, "ros34pw3 ran the ros34pw2 tableau"
print("ros34pw2 and ros34pw3 at t = 30: largest bead deviation %.2e d" % deviation)
