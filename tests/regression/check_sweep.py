"""Regression run of the real program: a tiny sweep on 2 ranks, then the same command again.

Checks: every case ran exactly once (one file each, status 'finished', summary lists each
once), frames are strictly increasing in time with frame 0 at t = 0 and the last at t_end,
the bond lengths stay within 2% of l0, /runs records one segment on 2 ranks, and the rerun
skips every case without touching files.
Usage: check_sweep.py MPIEXEC "FLAGS" KNOTFLOW WORKDIR
"""
import json
import os
import shlex
import shutil
import subprocess
import sys

import h5py
import numpy as np

mpiexec, flags, exe, work = sys.argv[1], shlex.split(sys.argv[2]), sys.argv[3], sys.argv[4]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
scene = os.path.join(work, "sweep.nml")
with open(scene, "w") as f:
    f.write("""&chain shape = 'straight', n_beads = 8 /
&forces spring_k = 500.0, bending_a = 1.0 /
&hydro model = 'rpy' /
&integrator t_end = 3.0 /
&output directory = '%s', frame_interval = 0.5, progress_interval = 0.0 /
&sweep bending_a = 0.5, 1.0, 2.0, seed = 1, 2 /
""" % os.path.join(work, "out"))
cmd = [mpiexec, "-n", "2"] + flags + [exe, scene]
run = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
print(run.stdout)
assert run.returncode == 0, run.stderr
out = os.path.join(work, "out")
summary = json.load(open(os.path.join(out, "summary.json")))
names = [c["case"] for c in summary["cases"]]
assert len(names) == 6 and len(set(names)) == 6, names
assert all(c["status"] == "finished" for c in summary["cases"]), summary
assert {c["rank"] for c in summary["cases"]} == {0, 1}, "both ranks must compute"
user_threads = os.environ.get("OPENBLAS_NUM_THREADS", "").strip()
threads = int(user_threads) if user_threads.isdigit() and int(user_threads) >= 1 else 1
mtimes = {}
for name in names:
    path = os.path.join(out, name + ".h5")
    with h5py.File(path, "r") as h:
        assert h.attrs["status"] in (b"finished", "finished")
        t = h["frames/time"][:]
        assert t[0] == 0.0 and abs(t[-1] - 3.0) < 1e-12 and np.all(np.diff(t) > 0), t
        r = h["frames/positions"][:]
        bonds = np.linalg.norm(np.diff(r, axis=1), axis=2)
        assert np.all(np.abs(bonds - 1.02) < 0.02 * 1.02), bonds.max()
        # one run segment, recorded with the sweep's 2 ranks and 1 BLAS thread per rank
        # (several ranks on a node keep one each, unless OPENBLAS_NUM_THREADS says otherwise;
        # 0 where the BLAS is not OpenBLAS)
        assert list(h["runs/ranks"][()]) == [2], h["runs/ranks"][()]
        assert list(h["runs/threads"][()]) in ([threads], [0]), h["runs/threads"][()]
    mtimes[path] = os.path.getmtime(path)
for name in names:
    assert run.stdout.count("case %s: started" % name) == 1, name
again = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
assert again.returncode == 0, again.stderr
assert again.stdout.count("skipped") >= 6, again.stdout
for path, m in mtimes.items():
    assert os.path.getmtime(path) == m, path + " was rewritten"
print("sweep regression: 6 cases, each once, rerun skipped all")
