"""Kill and resume, and a failing case.

1. A case killed with SIGKILL part-way resumes from its checkpoint when the command is run again:
   the finished file has every frame exactly once (times 0, 1, ..., t_end) and is the
   uninterrupted run exactly (positions bit for bit): the checkpoint holds the time stepper's
   whole state (/checkpoint/slot*/stepper) and RPY has no hidden state. The run diagnostics
   (/frames/diagnostics, the diagnostics.* attributes; the monitor state is in the checkpoint)
   continue across the kill and equal the uninterrupted run's exactly.
   While the first run is alive, a second run into the same directory is refused with exit
   status 2 and leaves its case file alone; after the kill the lock is gone (the resume runs).
   A kill while a checkpoint is written leaves the previous one whole in the other slot, so
   the first rerun always resumes (check_kill_points.py kills at every write of a run).
   The fibre's stresslet (&output stresslet, /frames/stresslet) is truncated and continued with
   the frames: one entry per frame, all equal to the uninterrupted run's.
2. A file of an older version (schema 2: one /checkpoint; no stepper state and no digest,
   which came later: both removed here from a killed run) still resumes, from
   /checkpoint/{dt, steps, rejected}, finishes with every frame, close to the uninterrupted
   run, and has the current layout afterwards.
3. A case that cannot finish (max_steps too small) is reported with its reason: exit status 3,
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
from kf_legacy import to_single_checkpoint

exe, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def scene(name, extra=""):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write("""&chain shape = 'trefoil', orientation = 'c' /
&forces excluded_volume = .true. /
&integrator t_end = 300.0 %s /
&output directory = '%s', case_name = 'c', frame_interval = 1.0, progress_interval = 0.0, stresslet = .true. /
""" % (extra, os.path.join(work, name)))
    return path


def frames(name):
    with h5py.File(os.path.join(work, name, "c.h5"), "r") as h:
        return h.attrs["status"], h["frames/time"][:], h["frames/positions"][:]


ref = scene("reference")
subprocess.run([exe, ref], check=True, capture_output=True, timeout=600)
status, t_ref, r_ref = frames("reference")

def kill_and_rerun(name):
    """Start the scene `name`, check the directory lock, kill it with SIGKILL after t = 15 and
    run it again; returns the output of the second run and the frames the killed one wrote."""
    killed = scene(name)
    proc = subprocess.Popen([exe, killed], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    path = os.path.join(work, name, "c.h5")
    for line in proc.stdout:          # one progress line per frame (progress_interval = 0)
        if ": t = 15.000 /" in line:
            break
    # A second run into the same directory while the first is alive is refused (exit 2) and must
    # not touch the case file the first one is writing (it would otherwise see a locked HDF5 file,
    # take it for a corrupt one and delete it).
    second = subprocess.run([exe, killed], capture_output=True, text=True, timeout=120)
    assert second.returncode == 2, (second.returncode, second.stdout, second.stderr)
    # (a single case: its case lock, kf_fs lock_case)
    assert "computing case c here" in second.stderr and ".knotflow.c.lock" in second.stderr, second.stderr
    assert os.path.exists(path)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    with h5py.File(path, "r") as h:
        n = h["frames/time"].shape[0]
        assert h.attrs["status"] in (b"running", "running")
    assert n < len(t_ref), "the run finished before it could be killed"
    again = subprocess.run([exe, killed], capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    return again.stdout, n


out, n_killed = kill_and_rerun("killed")
assert "resuming" in out and "is damaged" not in out, out
status, t, r = frames("killed")
assert status in (b"finished", "finished")
assert np.array_equal(t, t_ref), (t, t_ref)
assert np.array_equal(r, r_ref), np.abs(r - r_ref).max()
print("killed at %d frames, resumed: %d frames, equal to the uninterrupted run bit for bit"
      % (n_killed, len(t)))

DIAG_SETS = ("strand_passages", "overlapping_pairs", "overlap_episodes", "min_distance",
             "max_bond_strain")
DIAG_ATTRS = ("strand_passages", "first_passage_time", "overlap_episodes",
              "overlap_mean_duration", "overlap_max_duration", "max_overlapping_pairs",
              "min_distance", "max_bond_strain")


def diagnostics(name):
    with h5py.File(os.path.join(work, name, "c.h5"), "r") as h:
        sets = {k: h["frames/diagnostics/" + k][:] for k in DIAG_SETS}
        totals = {k: h.attrs["diagnostics." + k].item() for k in DIAG_ATTRS}
        kept = int(h["frames/time"].shape[0])
    return sets, totals, kept


d_ref, tot_ref, _ = diagnostics("reference")
d_res, tot_res, kept = diagnostics("killed")
for k in DIAG_SETS:
    assert np.array_equal(d_res[k], d_ref[k]), (k, d_res[k], d_ref[k])
assert d_res["overlap_episodes"][n_killed - 1] > 0, "the test needs overlap episodes before the kill"
assert tot_res == tot_ref, (tot_res, tot_ref)
STRESSLET_SETS = ("hydrodynamic", "elastic", "viscosity", "psi1", "psi2")


def stresslet(name):
    with h5py.File(os.path.join(work, name, "c.h5"), "r") as h:
        return {k: h["frames/stresslet/" + k][:] for k in STRESSLET_SETS}


s_ref, s_res = stresslet("reference"), stresslet("killed")
for k in STRESSLET_SETS:
    assert len(s_res[k]) == len(t_ref) and np.all(np.isfinite(s_res[k])), k
    assert np.array_equal(s_res[k], s_ref[k]), k
print("stresslet after the resume: %d frames; late-time mean viscosity %.3f (uninterrupted %.3f)"
      % (len(s_res["viscosity"]), s_res["viscosity"][100:].mean(), s_ref["viscosity"][100:].mean()))
print("diagnostics after the resume: " + ", ".join(
    "%s %s" % (k, tot_res[k]) for k in DIAG_ATTRS) + " (the uninterrupted run's)")

legacy = scene("legacy")
proc = subprocess.Popen([exe, legacy], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
for line in proc.stdout:
    if ": t = 15.000 /" in line:
        break
proc.send_signal(signal.SIGKILL)
proc.wait()
with h5py.File(os.path.join(work, "legacy", "c.h5"), "r+") as h:
    to_single_checkpoint(h, schema=2)
    assert "checkpoint/stepper/reals" in h and "checkpoint/stepper/ints" in h
    assert h["checkpoint/stepper"].attrs["name"] in (b"dopri45", "dopri45")
    del h["checkpoint/stepper"]
    del h["checkpoint/digest"]        # an older file has neither the stepper state nor the digest
    t_legacy = float(h["checkpoint/time"][()])
again = subprocess.run([exe, legacy], capture_output=True, text=True, timeout=600)
assert again.returncode == 0, again.stderr
assert "resuming" in again.stdout, again.stdout
status, t, r = frames("legacy")
assert status in (b"finished", "finished")
assert np.array_equal(t, t_ref), (t, t_ref)
dev_legacy = np.abs(r - r_ref).max()
assert dev_legacy < 1e-2, dev_legacy
with h5py.File(os.path.join(work, "legacy", "c.h5"), "r") as h:
    assert sorted(h["checkpoint"].keys()) == ["slot0", "slot1"], list(h["checkpoint"].keys())
    assert h.attrs["schema_version"] == 5
    # the run records begin with the resume (/runs, schema 4 on)
    assert list(h["runs/t_start"][()]) == [t_legacy] and list(h["runs/t_end"][()]) == [300.0]
print("resumed without the stepper state: max deviation from the uninterrupted run %.2e" % dev_legacy)

bad = scene("failing", extra=", max_steps = 50")
run = subprocess.run([exe, bad], capture_output=True, text=True, timeout=600)
assert run.returncode == 3, (run.returncode, run.stdout, run.stderr)
status, t, r = frames("failing")
status = status.decode() if isinstance(status, bytes) else status
assert status.startswith("failed: ") and "max_steps" in status, status
summary = open(os.path.join(work, "failing", "summary.txt")).read()
assert "FAILED" in summary, summary
print("failing case reported:", status)
