"""Kill and resume, and a failing case.

1. A case killed with SIGKILL part-way resumes from its checkpoint when the command is run again:
   the finished file has every frame exactly once (times 0, 1, ..., t_end) and its trajectory
   equals that of an uninterrupted run to integration tolerance. The run diagnostics
   (/frames/diagnostics, the diagnostics.* attributes; the monitor state is in the checkpoint)
   continue across the kill: the frames before the kill are those of the uninterrupted run
   exactly, and the run totals agree with it (counts exactly or, for the overlap episodes, to
   the few episodes the different step times after the restart can add or remove).
   While the first run is alive, a second run into the same directory is refused with exit
   status 2 and leaves its case file alone; after the kill the lock is gone (the resume runs).
   The checkpoint holds the time stepper's whole state (/checkpoint/stepper): with a system
   without hidden state the resumed run is the uninterrupted one exactly. A kill that lands
   while the checkpoint is rewritten (frequent in this fast run) leaves it inconsistent: the
   file is moved aside and the case recomputed correctly; the scenario is then repeated (up to
   4 times) until a kill lands between checkpoints.
   The fibre's stresslet (&output stresslet, /frames/stresslet) is truncated and continued with
   the frames: one entry per frame, those before the kill equal to the uninterrupted run's.
2. A checkpoint written before the steppers saved their state (no /checkpoint/stepper, and no
   /checkpoint/digest, which came later: both removed here from a killed run) still resumes, from /checkpoint/{dt, steps, rejected}, and finishes
   with every frame, close to the uninterrupted run.
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
    assert "another knotflow run" in second.stderr and ".knotflow.lock" in second.stderr, second.stderr
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


# A kill while the checkpoint is being rewritten leaves one that does not match its digest: the
# file is then moved aside (never resumed wrongly, never deleted) and the case computed again
# (that result must be right too). Such a kill is rare in a long run but not in this fast one,
# so the scenario is repeated until a kill lands between two checkpoints.
for attempt in range(4):
    killed_name = "killed" if attempt == 0 else "killed%d" % attempt
    out, n_killed = kill_and_rerun(killed_name)
    if "resuming" in out:
        break
    assert "is damaged" in out and "computing the case again" in out, out
    assert os.path.exists(os.path.join(work, killed_name, "c.h5.damaged"))
    status, t, r = frames(killed_name)
    assert status in (b"finished", "finished") and np.array_equal(t, t_ref), (status, t)
    print("attempt %d: killed while its checkpoint was written; moved aside and recomputed" % attempt)
assert "resuming" in out, out
status, t, r = frames(killed_name)
assert status in (b"finished", "finished")
assert np.array_equal(t, t_ref), (t, t_ref)
dev = np.abs(r - r_ref).max()
assert dev < 1e-2, dev
print("killed at %d frames, resumed: %d frames, max deviation from the uninterrupted run %.2e"
      % (n_killed, len(t), dev))

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
d_res, tot_res, kept = diagnostics(killed_name)
for k in DIAG_SETS:
    assert len(d_res[k]) == len(t_ref), (k, len(d_res[k]))
# the killed run was the reference run up to its checkpoint (same code, same input): up to the
# first resumed frame every diagnostic is identical; cumulative counters never decrease
n_same = n_killed - 1
for k in DIAG_SETS:
    assert np.array_equal(d_res[k][:n_same], d_ref[k][:n_same]), (k, d_res[k][:n_same], d_ref[k][:n_same])
for k in ("strand_passages", "overlap_episodes"):
    assert np.all(np.diff(d_res[k]) >= 0), k
# at every frame, the per-frame values are those of its configuration (to the trajectory deviation)
assert np.abs(d_res["min_distance"] - d_ref["min_distance"]).max() < 2 * dev + 1e-12
assert np.abs(d_res["max_bond_strain"] - d_ref["max_bond_strain"]).max() < 2 * dev / 1.02 + 1e-12
# the totals: a resumed run that restarted its counters would miss the episodes before the kill
assert tot_res["strand_passages"] == tot_ref["strand_passages"], (tot_res, tot_ref)
if tot_ref["first_passage_time"] < 0:
    assert tot_res["first_passage_time"] == -1.0, (tot_res, tot_ref)
else:
    assert abs(tot_res["first_passage_time"] - tot_ref["first_passage_time"]) < 1.0, (tot_res, tot_ref)
# episodes of pairs hovering at r = 1 may start or end one step apart after the restart: allow a
# few, far fewer than those counted before the kill (which a reset of the counters would lose)
slack = 3
assert d_res["overlap_episodes"][n_same - 1] > 2 * slack, "the test needs overlap episodes before the kill"
assert abs(tot_res["overlap_episodes"] - tot_ref["overlap_episodes"]) <= slack, (tot_res, tot_ref)
assert abs(tot_res["max_overlapping_pairs"] - tot_ref["max_overlapping_pairs"]) <= 1, (tot_res, tot_ref)
assert abs(tot_res["min_distance"] - tot_ref["min_distance"]) < 1e-2, (tot_res, tot_ref)
assert abs(tot_res["max_bond_strain"] - tot_ref["max_bond_strain"]) < 1e-2, (tot_res, tot_ref)
assert abs(tot_res["overlap_max_duration"] - tot_ref["overlap_max_duration"]) < 0.1, (tot_res, tot_ref)
assert abs(tot_res["overlap_mean_duration"] - tot_ref["overlap_mean_duration"]) < 0.05, (tot_res, tot_ref)
STRESSLET_SETS = ("hydrodynamic", "elastic", "viscosity", "psi1", "psi2")


def stresslet(name):
    with h5py.File(os.path.join(work, name, "c.h5"), "r") as h:
        return {k: h["frames/stresslet/" + k][:] for k in STRESSLET_SETS}


s_ref, s_res = stresslet("reference"), stresslet(killed_name)
for k in STRESSLET_SETS:
    assert len(s_res[k]) == len(t_ref) and np.all(np.isfinite(s_res[k])), k
    assert np.array_equal(s_res[k][:n_same], s_ref[k][:n_same]), k
print("stresslet after the resume: %d frames; late-time mean viscosity %.3f (uninterrupted %.3f)"
      % (len(s_res["viscosity"]), s_res["viscosity"][100:].mean(), s_ref["viscosity"][100:].mean()))
print("diagnostics after the resume: " + ", ".join(
    "%s %s (uninterrupted %s)" % (k, tot_res[k], tot_ref[k]) for k in DIAG_ATTRS))

legacy = scene("legacy")
proc = subprocess.Popen([exe, legacy], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
for line in proc.stdout:
    if ": t = 15.000 /" in line:
        break
proc.send_signal(signal.SIGKILL)
proc.wait()
with h5py.File(os.path.join(work, "legacy", "c.h5"), "r+") as h:
    assert "checkpoint/stepper/reals" in h and "checkpoint/stepper/ints" in h
    assert h["checkpoint/stepper"].attrs["name"] in (b"dopri45", "dopri45")
    del h["checkpoint/stepper"]
    del h["checkpoint/digest"]        # an older file has neither the stepper state nor the digest
again = subprocess.run([exe, legacy], capture_output=True, text=True, timeout=600)
assert again.returncode == 0, again.stderr
assert "resuming" in again.stdout, again.stdout
status, t, r = frames("legacy")
assert status in (b"finished", "finished")
assert np.array_equal(t, t_ref), (t, t_ref)
dev_legacy = np.abs(r - r_ref).max()
assert dev_legacy < 1e-2, dev_legacy
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
