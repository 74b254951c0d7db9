"""The multipole model with update = 'iterative' in the real program, killed and resumed.

A random self-avoiding chain (N = 20, L = 2 with lubrication, shear) run with 'stage' (the exact
path) and with 'iterative': the iterative run ends within 1e-5 d of the stage run at every frame
(its velocities equal stage's to the relative solver tolerance 1e-6). An iterative run killed
with SIGKILL part-way resumes from its checkpoint; its reference factorisation is not in the
checkpoint but rebuilt at the first evaluation after the resume, so the resumed run is not bit for
bit the uninterrupted one (as 'adaptive'), only within the solver tolerance: every frame exactly
once and every position within 1e-5 d of the uninterrupted run. The work counters hydro.* are
cumulative over the resume.
Usage: check_iterative_resume.py KNOTFLOW WORKDIR
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
T_END, KILL_AT = 12.0, 6.0


def scene(name, update):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write("""&chain shape = 'random', n_beads = 20 /
&hydro model = 'multipole', order = 2, lubrication = .true., update = '%s' /
&integrator t_end = %g /
&output directory = '%s', case_name = 'c', frame_interval = 1.0, progress_interval = 0.0 /
""" % (update, T_END, os.path.join(work, name)))
    return path


def frames(name):
    with h5py.File(os.path.join(work, name, "c.h5"), "r") as h:
        attrs = {k: h.attrs[k] for k in ("status", "hydro.evaluations", "hydro.refreshes", "hydro.reused")}
        return attrs, h["frames/time"][:], h["frames/positions"][:]


env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
for name, update in (("stage", "stage"), ("iterative", "iterative")):
    subprocess.run([exe, scene(name, update)], check=True, capture_output=True, timeout=600, env=env)
a_stage, t_stage, r_stage = frames("stage")
a_it, t_it, r_it = frames("iterative")
assert np.array_equal(t_it, t_stage), (t_it, t_stage)
dev_stage = np.linalg.norm(r_it - r_stage, axis=2).max()
moved = np.linalg.norm(r_stage[-1] - r_stage[0], axis=1).max()
assert dev_stage < 1e-5 and moved > 0.1, (dev_stage, moved)
assert a_it["hydro.reused"] > a_it["hydro.refreshes"] > 0, a_it

killed = scene("killed", "iterative")
proc = subprocess.Popen([exe, killed], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                        env=env)
assert proc.stdout is not None
for line in proc.stdout:          # one progress line per frame (progress_interval = 0)
    if ": t = %.3f /" % KILL_AT in line:
        break
proc.send_signal(signal.SIGKILL)
proc.wait()
with h5py.File(os.path.join(work, "killed", "c.h5"), "r") as h:
    n_killed = h["frames/time"].shape[0]
    assert h.attrs["status"] in (b"running", "running")
assert n_killed < len(t_it), "the run finished before it could be killed"
again = subprocess.run([exe, killed], capture_output=True, text=True, timeout=600, env=env)
assert again.returncode == 0, again.stderr
assert "resuming" in again.stdout, again.stdout
a_res, t_res, r_res = frames("killed")
assert a_res["status"] in (b"finished", "finished")
assert np.array_equal(t_res, t_it), (t_res, t_it)
dev_resume = np.linalg.norm(r_res - r_it, axis=2).max()
assert dev_resume < 1e-5, dev_resume
assert a_res["hydro.refreshes"] > 0 and a_res["hydro.evaluations"] >= a_it["hydro.evaluations"] // 2, a_res
print("iterative vs stage: largest bead deviation %.2e d over %d frames (beads moved up to %.2f d); "
      "killed at %d frames and resumed: %.2e d from the uninterrupted run; counters %s"
      % (dev_stage, len(t_it), moved, n_killed, dev_resume, a_res))
