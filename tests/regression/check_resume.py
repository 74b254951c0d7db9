"""Kill and resume, and a failing case.

1. A case killed with SIGKILL part-way resumes from its checkpoint when the command is run again:
   the finished file has every frame exactly once (times 0, 1, ..., t_end) and its trajectory
   equals that of an uninterrupted run to integration tolerance.
2. A case that cannot finish (max_steps too small) is reported with its reason: exit status 3,
   status 'failed: ...' in the case file and 'FAILED' in the summary.
Usage: check_resume.py KNOTFLOW WORKDIR
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


def scene(name, extra=""):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write("""&chain shape = 'trefoil', orientation = 'c' /
&forces excluded_volume = .true. /
&integrator t_end = 300.0 %s /
&output directory = '%s', case_name = 'c', frame_interval = 1.0, progress_interval = 0.0 /
""" % (extra, os.path.join(work, name)))
    return path


def frames(name):
    with h5py.File(os.path.join(work, name, "c.h5"), "r") as h:
        return h.attrs["status"], h["frames/time"][:], h["frames/positions"][:]


ref = scene("reference")
subprocess.run([exe, ref], check=True, capture_output=True, timeout=600)
status, t_ref, r_ref = frames("reference")

killed = scene("killed")
proc = subprocess.Popen([exe, killed], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
path = os.path.join(work, "killed", "c.h5")
for line in proc.stdout:          # one progress line per frame (progress_interval = 0)
    if ": t = 15.000 /" in line:
        break
proc.send_signal(signal.SIGKILL)
proc.wait()
with h5py.File(path, "r") as h:
    n_killed = h["frames/time"].shape[0]
    assert h.attrs["status"] in (b"running", "running")
assert n_killed < len(t_ref), "the run finished before it could be killed"
again = subprocess.run([exe, killed], capture_output=True, text=True, timeout=600)
assert again.returncode == 0, again.stderr
assert "resuming" in again.stdout, again.stdout
status, t, r = frames("killed")
assert status in (b"finished", "finished")
assert np.array_equal(t, t_ref), (t, t_ref)
dev = np.abs(r - r_ref).max()
assert dev < 1e-2, dev
print("killed at %d frames, resumed: %d frames, max deviation from the uninterrupted run %.2e"
      % (n_killed, len(t), dev))

bad = scene("failing", extra=", max_steps = 50")
run = subprocess.run([exe, bad], capture_output=True, text=True, timeout=600)
assert run.returncode == 3, (run.returncode, run.stdout, run.stderr)
status, t, r = frames("failing")
status = status.decode() if isinstance(status, bytes) else status
assert status.startswith("failed: ") and "max_steps" in status, status
summary = open(os.path.join(work, "failing", "summary.txt")).read()
assert "FAILED" in summary, summary
print("failing case reported:", status)
