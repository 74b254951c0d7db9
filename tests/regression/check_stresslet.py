"""The fibre's stresslet in case files (&output stresslet), every hydrodynamic model:
1. the datasets /frames/stresslet/{hydrodynamic, elastic} (F, 3, 3) and {viscosity, psi1,
   psi2} (F,) exist, one entry per frame, chunked with the Fletcher-32 filter, the tensors
   symmetric and traceless, and the observables those of the tensors (6 S_xz / N, ...);
2. a straight chain at rest with free-draining beads (`none`: no forces at t = 0) gives
   Einstein's 5/2 and no normal-stress differences at frame 0;
3. recording the stresslet changes nothing else: the adaptive multipole run (the study's path)
   has bitwise the same trajectory and hydro counters with and without it.
Usage: check_stresslet.py KNOTFLOW WORKDIR
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
SETS = ("hydrodynamic", "elastic", "viscosity", "psi1", "psi2")


def run(name, hydro, stresslet, t_end=2.0):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write("""&chain shape = 'straight', n_beads = 8, straight_direction = 1.0, 0.0, 1.0 /
&hydro %s /
&integrator t_end = %g /
&output directory = '%s', case_name = 'c', frame_interval = 0.5, stresslet = %s /
""" % (hydro, t_end, os.path.join(work, name), ".true." if stresslet else ".false."))
    subprocess.run([exe, path], check=True, capture_output=True, timeout=600)
    return os.path.join(work, name, "c.h5")


for model in ("model = 'none'", "model = 'rpy'",
              "model = 'multipole', order = 2, lubrication = .true., update = 'adaptive'"):
    path = run(model.split("'")[1], model, True)
    with h5py.File(path, "r") as h:
        nframes = h["frames/time"].shape[0]
        n = int(h.attrs["n_beads"])
        g = h["frames/stresslet"]
        for k in SETS:
            ds = g[k]
            assert ds.shape == ((nframes, 3, 3) if k in SETS[:2] else (nframes,)), (k, ds.shape)
            assert ds.chunks is not None and ds.fletcher32, k
        s = g["hydrodynamic"][:] + g["elastic"][:]
        for part in ("hydrodynamic", "elastic"):
            t = g[part][:]
            assert np.allclose(t, np.swapaxes(t, 1, 2), atol=1e-12 * np.abs(t).max()), part
            assert np.allclose(np.trace(t, axis1=1, axis2=2), 0.0, atol=1e-12 * np.abs(t).max()), part
        assert np.allclose(g["viscosity"][:], 6.0 * s[:, 0, 2] / n, rtol=1e-14)
        assert np.allclose(g["psi1"][:], 6.0 * (s[:, 0, 0] - s[:, 2, 2]) / n, rtol=1e-14)
        assert np.allclose(g["psi2"][:], 6.0 * (s[:, 2, 2] - s[:, 1, 1]) / n, rtol=1e-14)
        print("%s: viscosity at frames 0 and %d: %.6f, %.6f" % (model, nframes - 1, g["viscosity"][0],
                                                               g["viscosity"][-1]))
        if "none" in model:
            assert abs(g["viscosity"][0] - 2.5) < 1e-12, g["viscosity"][0]
            assert abs(g["psi1"][0]) < 1e-12 and abs(g["psi2"][0]) < 1e-12

hydro = "model = 'multipole', order = 2, lubrication = .true., update = 'adaptive'"
with_s = run("adaptive_with", hydro, True, 3.0)
without = run("adaptive_without", hydro, False, 3.0)
with h5py.File(with_s, "r") as a, h5py.File(without, "r") as b:
    assert "stresslet" in a["frames"] and "stresslet" not in b["frames"]
    assert np.array_equal(a["frames/positions"][:], b["frames/positions"][:])
    for k in ("hydro.evaluations", "hydro.refreshes", "hydro.reused", "hydro.cg_iterations"):
        assert a.attrs[k] == b.attrs[k], k
    print("adaptive multipole: the same trajectory with and without the stresslet (%d refreshes)"
          % a.attrs["hydro.refreshes"])
