"""A trefoil scene with hydro model = 'multipole', L = 2, lubrication on, runs in the real program
and behaves sensibly: it finishes, bonds stay near l0, and the short-time motion agrees with RPY
to a few per cent (the two models differ only in near-field corrections; L = 1 would equal RPY).
Usage: check_multipole_scene.py KNOTFLOW WORKDIR
"""
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

exe, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
runs = {}
for model in ("multipole', order = 2, lubrication = .true., eps_lub = 1e-4", "rpy'"):
    name = model.split("'")[0]
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write("&chain shape = 'trefoil', orientation = 'c' /\n&hydro model = '%s /\n"
                "&integrator t_end = 0.5 /\n&output directory = '%s', case_name = '%s', "
                "frame_interval = 0.25 /\n" % (model, work, name))
    run = subprocess.run(["env", "OPENBLAS_NUM_THREADS=1", exe, path], capture_output=True,
                         text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    with h5py.File(os.path.join(work, name + ".h5"), "r") as h:
        assert h.attrs["hydro.model"] in (name, name.encode())
        runs[name] = h["frames/positions"][:]
mp, rpy = runs["multipole"], runs["rpy"]
assert np.all(np.isfinite(mp))
bonds = np.linalg.norm(np.diff(mp[-1], axis=0), axis=1)
assert np.all(np.abs(bonds - 1.02) < 0.05), (bonds.min(), bonds.max())
disp_mp = np.linalg.norm(mp[-1] - mp[0], axis=1)
disp_rpy = np.linalg.norm(rpy[-1] - rpy[0], axis=1)
rel = np.abs(disp_mp.mean() - disp_rpy.mean()) / disp_rpy.mean()
dev = np.linalg.norm(mp[-1] - rpy[-1], axis=1).max() / disp_rpy.max()
print("mean displacement multipole %.4f, rpy %.4f (rel. diff %.3f); max deviation / max "
      "displacement %.3f" % (disp_mp.mean(), disp_rpy.mean(), rel, dev))
assert rel < 0.05 and 0 < dev < 0.1
