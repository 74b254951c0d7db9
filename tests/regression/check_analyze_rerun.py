"""knotflow-analyze on 2 ranks: re-runs that cannot hang, the directory lock, usage errors.

1. Two tiny cases are run and analysed (k_f of every frame, knot matrices of two frames); then
   knotflow-analyze is run again RERUNS times on the analysed files with 2 ranks, each under a
   timeout. Every re-run must end with status 0 within the timeout and leave an /analysis group
   equal to the first one (it reuses what is stored: nothing new to compute). Before the ranks
   shared their decisions, a re-run hung in about 1 run in 8 (one rank read the stored knot
   matrix while rank 0 rewrote /analysis, decided to compute it, and waited in an all-reduce
   while rank 0 waited in a barrier).
2. While another process holds the directory lock of knotflow (<dir>/.knotflow.lock, as a
   running sweep does), knotflow-analyze refuses with exit status 2, names the lock file, and
   leaves the case files untouched (same bytes).
3. Usage errors (unknown option, bad value, no file) exit with status 2, like knotflow's.
Usage: check_analyze_rerun.py MPIEXEC "MPIEXEC_FLAGS" KNOTFLOW KNOTFLOW_ANALYZE WORKDIR [RERUNS]
"""
import fcntl
import hashlib
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

mpiexec, flags, knotflow, analyze, work = sys.argv[1:6]
reruns = int(sys.argv[6]) if len(sys.argv) > 6 else 30
mpi = [mpiexec] + flags.split() + ["-n", "2"]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
out = os.path.join(work, "cases")
sweep = os.path.join(work, "sweep.nml")
with open(sweep, "w") as f:
    f.write("""&chain shape = 'trefoil' /
&forces excluded_volume = .true. /
&integrator t_end = 4.0 /
&output directory = '%s', frame_interval = 1.0, progress_interval = 0.0 /
&sweep orientation = 'b', 'c' /
""" % out)
subprocess.run(mpi + [knotflow, sweep], check=True, capture_output=True, timeout=600)
files = sorted(os.path.join(out, f) for f in os.listdir(out) if f.endswith(".h5"))
assert len(files) == 2, files
args = files + ["--closures", "20", "--matrix-frames", "0,last", "--matrix-closures", "2"]


def analysis(path):
    """Every dataset of /analysis (name -> array)."""
    items = {}
    with h5py.File(path, "r") as h:
        h["analysis"].visititems(lambda name, obj: items.__setitem__(name, obj[()])
                                 if isinstance(obj, h5py.Dataset) else None)
    return items


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


first = subprocess.run(mpi + [analyze] + args, capture_output=True, text=True, timeout=300)
assert first.returncode == 0, (first.stdout, first.stderr)
ref = {p: analysis(p) for p in files}
for p in files:
    assert "knots/kf" in ref[p] and "knot_matrix/frame_0" in ref[p], sorted(ref[p])

# 1. re-runs on analysed files: each ends (status 0) within its timeout, with the same analysis
for k in range(reruns):
    try:
        run = subprocess.run(mpi + [analyze] + args, capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired:
        raise AssertionError("re-run %d of knotflow-analyze on 2 ranks hung (no end in 60 s)" % (k + 1))
    assert run.returncode == 0, (k + 1, run.returncode, run.stdout, run.stderr)
    assert run.stdout.count("(0 new)") == 2, run.stdout
    for p in files:
        now = analysis(p)
        assert now.keys() == ref[p].keys(), (p, sorted(now), sorted(ref[p]))
        for name in now:
            np.testing.assert_array_equal(now[name], ref[p][name], err_msg=p + ":" + name)
print("%d re-runs on 2 ranks ended with the same /analysis" % reruns)

# 2. the directory lock of a running sweep (flock on <dir>/.knotflow.lock) refuses the analysis
before = {p: digest(p) for p in files}
with open(os.path.join(out, ".knotflow.lock"), "a") as lock:
    fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    run = subprocess.run(mpi + [analyze] + args + ["--force"], capture_output=True, text=True, timeout=120)
assert run.returncode == 2, (run.returncode, run.stdout, run.stderr)
assert ".knotflow.lock" in run.stderr and "writing into this directory" in run.stderr, run.stderr
assert before == {p: digest(p) for p in files}, "a refused analysis changed a case file"
# the lock released (the sweep ended): the analysis runs
run = subprocess.run(mpi + [analyze] + args, capture_output=True, text=True, timeout=120)
assert run.returncode == 0, (run.stdout, run.stderr)
print("refused while the directory lock is held (exit 2, files unchanged); runs after")

# 3. usage errors: exit status 2 and one error line
for bad in (["--closures", "0", files[0]], ["--no-such-option", files[0]], [],
            [files[0], "--matrix"]):
    run = subprocess.run([analyze] + bad, capture_output=True, text=True, timeout=60)
    assert run.returncode == 2, (bad, run.returncode, run.stderr)
    assert "knotflow-analyze: error:" in run.stderr, (bad, run.stderr)
print("usage errors exit with status 2")
