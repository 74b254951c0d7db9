"""Kill -9 at any moment, also inside a checkpoint write: no kill loses the run or changes it.

A short case (trefoil N = 99, rpy, excluded volume, run diagnostics, t_end = 4, a frame every
0.2: 21 frames, so /frames/positions gets a second chunk) is run once without interruption.
Then it is started again and again, each time killed, and run once more without interruption
(the rerun of a user after a crash); that rerun must exit 0 with the case finished and the file
equal to the uninterrupted run: every /frames dataset (times, positions, observables,
integrator counts and step sizes, run diagnostics) bit for bit and the diagnostics.* and hydro.*
attributes exactly; its /runs segments join up (each starts at the t_end of the one before),
end at t_end and their steps add up to the run's. After a kill that came after frame k had been reported (its checkpoint
flushed), the rerun must resume from frame k or later: a kill costs at most the frame being
written. A kill before the first checkpoint is whole may instead make the rerun move the file
aside (named `.damaged`) and compute the case from the start; the result is checked the same.
The uninterrupted run has one BLAS thread (OPENBLAS_NUM_THREADS=1), the killed runs and reruns
two: knotflow picks the thread count from the machine's load at start-up, so a resume may well
get another count, and an RPY case must not depend on it (its dynamics call no BLAS; the shape
observables use kf_symmetric_eigen, not the threaded dsyev).

Kill points:
- at the N-th write: strace delivers SIGKILL when the process enters its N-th pwrite64 call
  (HDF5 writes through pwrite64: frames, both checkpoint slots, attributes, the final status),
  so the kill lands between two writes of a checkpoint as often as anywhere else. The pwrite
  calls of the uninterrupted run are counted first, with the progress line after each frame
  (to know which frames were complete at a kill point). STRIDE = 1 kills at every write (the
  'slow' test); a larger STRIDE at every STRIDE-th write, plus the first 8 writes (creating
  the file) and every write of frame 16 (the one that allocates the second chunk of
  /frames/positions).
  DENSE (default 1) thins the first 8 writes and the writes of frame 16 to every DENSE-th one
  (the short test of the default suite; the full sets in the 'slow' tests).
  Skipped, with a message, when strace is not installed or cannot trace (no ptrace).
- at RANDOM random moments of the run (SIGKILL from this script after a random number of
  frames and a random delay of up to 0.06 s, about one frame).

Usage: check_kill_points.py KNOTFLOW WORKDIR [STRIDE] [RANDOM] [DENSE]
"""
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import time

import h5py
import numpy as np

exe, work = sys.argv[1], sys.argv[2]
stride = int(sys.argv[3]) if len(sys.argv) > 3 else 9
n_random = int(sys.argv[4]) if len(sys.argv) > 4 else 8
dense_stride = int(sys.argv[5]) if len(sys.argv) > 5 else 1
dense_frames = (16,)     # frame indices whose every write is a kill point
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

scene = os.path.join(work, "scene.nml")
out = os.path.join(work, "out")
case = os.path.join(out, "c.h5")
with open(scene, "w") as f:
    f.write("""&chain shape = 'trefoil', orientation = 'c' /
&forces excluded_volume = .true. /
&integrator t_end = 4.0 /
&output directory = '%s', case_name = 'c', frame_interval = 0.2, progress_interval = 0.0 /
""" % out)


def contents(path):
    """Every /frames dataset and the run totals of a case file."""
    data = {}
    with h5py.File(path, "r") as h:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                data[name] = obj[()]
        h["frames"].visititems(visit)
        for k, v in h.attrs.items():
            if k.startswith("diagnostics.") or k.startswith("hydro."):
                data["@" + k] = v
        status = h.attrs["status"]
    return status.decode() if isinstance(status, bytes) else status, data


def threads(n):
    """The environment of a run with n BLAS threads."""
    return dict(os.environ, OPENBLAS_NUM_THREADS=str(n))


def run(n=2):
    return subprocess.run([exe, scene], capture_output=True, text=True, timeout=600, env=threads(n))


# the uninterrupted run, its pwrite calls and the progress line after each frame
strace = shutil.which("strace")
traced = None
if strace:
    log = os.path.join(work, "trace.txt")
    traced = subprocess.run([strace, "-o", log, "-s", "200", "-e", "trace=pwrite64,write", exe, scene],
                            capture_output=True, text=True, timeout=600, env=threads(1))
    if traced.returncode != 0:
        print("strace cannot trace here (%s): the kill points at writes are skipped"
              % traced.stderr.strip().splitlines()[-1:])
        strace = None
        shutil.rmtree(out)
if not strace:
    ref = run(1)
    assert ref.returncode == 0, ref.stderr
status, reference = contents(case)
assert status == "finished", status
assert len(reference["time"]) == 21, reference["time"]
shutil.move(out, os.path.join(work, "reference"))
print("uninterrupted run: %d frames" % len(reference["time"]))

progress = re.compile(r": t = ([0-9.]+) / ")


def check_runs(label):
    """/runs after the rerun: the segments join up (each starts where the one before ended, at
    the checkpoint it resumed from, whatever moment the kill hit), the last ends at t_end and
    their steps add up to the run's."""
    with h5py.File(case, "r") as h:
        r = {k: h["runs/" + k][()] for k in ("t_start", "t_end", "steps", "wall_seconds")}
        total = int(h["frames/integrator/steps"][-1])
    assert r["t_start"][0] == 0.0 and r["t_end"][-1] == 4.0, (label, r)
    assert np.array_equal(r["t_start"][1:], r["t_end"][:-1]), (label, r)
    assert r["steps"].sum() == total and np.all(r["wall_seconds"] > 0), (label, r, total)


def check_rerun(label, frames_done):
    """Rerun after a kill: finished, equal to the uninterrupted run, resumed from a frame not
    before `frames_done` (frames reported complete before the kill; None: unknown)."""
    again = run()
    assert again.returncode == 0, (label, again.stdout, again.stderr)
    st, data = contents(case)
    assert st == "finished", (label, st)
    assert data.keys() == reference.keys(), (label, sorted(set(data) ^ set(reference)))
    for k, v in reference.items():
        assert np.array_equal(data[k], v), (label, k, data[k], v)
    check_runs(label)
    m = re.search(r"resuming at t = \S+ from its checkpoint \((\d+) frames\)", again.stdout)
    if m:
        kind = "resumed"
        if frames_done is not None:
            assert int(m.group(1)) >= frames_done, (label, frames_done, again.stdout)
    elif "1 skipped (already finished)" in again.stdout:
        kind = "finished before the kill"
    elif "is damaged" in again.stdout:
        kind = "moved aside"
        assert frames_done is None or frames_done < 2, (label, frames_done, again.stdout)
        assert os.path.exists(case + ".damaged"), label
    else:
        kind = "computed anew"
        assert frames_done is None, (label, again.stdout)
    return kind


counts = {}
if strace:
    calls = []          # for each pwrite64 call: the number of frames reported before it
    reported = 0
    for line in open(log):
        if line.startswith("pwrite64("):
            calls.append(reported)
        elif line.startswith("write(1,") and progress.search(line):
            reported += 1
    total = len(calls)
    # frame k (0-based) is written after the progress line of frame k - 1 (none for frame 0)
    first_write = {}
    for n, done in enumerate(calls, start=1):
        first_write.setdefault(done, n)
    dense = set()
    for k in dense_frames:    # frame k >= 1 is written after the progress line of frame k - 1
        if k - 1 in first_write and k in first_write:
            dense.update(range(first_write[k - 1], first_write[k], dense_stride))
    # the first writes create the file: a kill there leaves a file without scene attributes
    points = sorted(set(range(1, total + 1, stride)) | dense | set(range(1, 9, dense_stride)))
    print("%d pwrite64 calls in the uninterrupted run, %d progress lines; %d kill points"
          % (total, reported, len(points)))
    for n in points:
        shutil.rmtree(out, ignore_errors=True)
        killed = subprocess.run([strace, "-o", os.devnull, "-e", "trace=pwrite64", "-e",
                                 "inject=pwrite64:signal=KILL:when=%d" % n, exe, scene],
                                capture_output=True, text=True, timeout=600, env=threads(2))
        assert killed.returncode in (-9, 137), (n, killed.returncode, killed.stderr[-500:])
        # frames complete before the kill: reported ones (progress line after the checkpoint)
        done = calls[n - 1] + (1 if calls[n - 1] > 0 else 0)
        kind = check_rerun("kill at pwrite %d" % n, done if calls[n - 1] > 0 else None)
        counts[kind] = counts.get(kind, 0) + 1
    print("kills at writes: " + ", ".join("%d %s" % (v, k) for k, v in sorted(counts.items()))
          + "; every rerun equal to the uninterrupted run bit for bit")

# kills at random moments: after a random number of frames (progress lines) and a random
# fraction of the next frame's time
rng = random.Random(20261201)
random_counts = {}
for i in range(n_random):
    shutil.rmtree(out, ignore_errors=True)
    proc = subprocess.Popen([exe, scene], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                            env=threads(2))
    wanted = rng.randrange(0, len(reference["time"]) - 1)
    seen = 0
    lines = []
    while seen < wanted:
        line = proc.stdout.readline()
        if not line:
            break
        lines.append(line)
        if progress.search(line):
            seen += 1
    time.sleep(rng.uniform(0.0, 0.06))
    proc.send_signal(signal.SIGKILL)
    lines.append(proc.communicate()[0])
    stdout = "".join(lines)
    frames_done = len(progress.findall(stdout)) + (1 if progress.search(stdout) else 0)
    if proc.returncode == 0:
        kind = "finished before the kill"
        st, data = contents(case)
        assert st == "finished" and all(np.array_equal(data[k], v) for k, v in reference.items())
    else:
        kind = check_rerun("random kill %d" % i, frames_done if frames_done >= 2 else None)
    random_counts[kind] = random_counts.get(kind, 0) + 1
print("kills at random moments: " + ", ".join("%d %s" % (v, k) for k, v in sorted(random_counts.items())))
