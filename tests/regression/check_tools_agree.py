"""The Fortran tool (knotflow-analyze) and the Python tool (knotflow-kf) agree.

1. Same closure points -> the same knot type for every closure, on shared configurations: the
   open trefoil (N = 99, orientation a) as written by knotflow at t = 0 and after a short run in
   shear, and random walks.
2. Each with its own random points (1000 closures) -> k_f agree within statistical error
   (|difference| <= 4 sigma of the difference of two binomial estimates).
Usage: check_tools_agree.py KNOTFLOW KNOTFLOW_ANALYZE PYTHON WORKDIR
"""
import json
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

knotflow, analyze, python, work = sys.argv[1:5]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
scene = os.path.join(work, "trefoil.nml")
with open(scene, "w") as f:
    f.write("&chain shape = 'trefoil', orientation = 'a' /\n&forces bending_a = 1.0 /\n"
            "&integrator t_end = 20.0 /\n&output directory = '%s', case_name = 'tref', "
            "frame_interval = 20.0 /\n" % work)
subprocess.run([knotflow, scene], check=True, capture_output=True, timeout=300)
with h5py.File(os.path.join(work, "tref.h5"), "r") as h:
    frames = h["frames/positions"][:]
rng = np.random.default_rng(12345)
chains = {"trefoil_t0": frames[0], "trefoil_t20": frames[-1]}
for k in range(3):
    steps = rng.normal(size=(60, 3))
    steps /= np.linalg.norm(steps, axis=1)[:, None]
    chains["walk%d" % k] = np.cumsum(steps, axis=0)


def write_xyz(path, pts):
    np.savetxt(path, pts, fmt="%.17g")


def fortran(xyz, *args):
    out = subprocess.run([analyze, xyz, "--json"] + list(args), check=True,
                         capture_output=True, text=True, timeout=600).stdout
    return json.loads(out)


def python_tool(xyz, *args):
    out = subprocess.run([python, "-m", "knotflow_tools.cli", xyz, "--json"] + list(args),
                         check=True, capture_output=True, text=True, timeout=600).stdout
    return json.loads(out)


total = 0
for name, pts in chains.items():
    xyz = os.path.join(work, name + ".xyz")
    write_xyz(xyz, pts)
    centre = pts.mean(axis=0)
    rg = np.sqrt(((pts - centre) ** 2).sum(axis=1).mean())
    u = rng.normal(size=(200, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    cp = os.path.join(work, name + "_closures.xyz")
    write_xyz(cp, centre + 10.0 * rg * u)
    a = fortran(xyz, "--closure-points", cp, "--per-closure")
    b = python_tool(xyz, "--closure-points", cp, "--per-closure")
    assert len(a["per_closure"]) == 200 and a["per_closure"] == b["per_closure"], name
    total += 200
    print("%-12s same type on all 200 closures; k_f = %.3f" % (name, a["kf"]))

xyz = os.path.join(work, "trefoil_t0.xyz")
a = fortran(xyz, "--closures", "1000", "--seed", "7")
b = python_tool(xyz, "--closures", "1000", "--seed", "7")
sigma = np.sqrt(a["kf"] * (1 - a["kf"]) / 1000 + b["kf"] * (1 - b["kf"]) / 1000)
print("own random points: k_f Fortran %.3f, Python %.3f, sigma %.3f" % (a["kf"], b["kf"], sigma))
assert abs(a["kf"] - b["kf"]) <= 4 * sigma + 1e-12
print("tools agree: %d closures identical" % total)
