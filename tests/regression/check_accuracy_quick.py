"""knotflow-accuracy --quick: runs in seconds, writes every table, and the tables hold facts that
follow from the models, not from timing:
- the reference (multipole L = 2 + lubrication) has exactly zero error against itself;
- free draining (`none`) and multipole L = 1 without lubrication have no shear disturbance, so
  the relative RMS error of their disturbance part is exactly 1 (|0 - ref| / |ref|);
- every model evaluated and timed (status ok, time > 0);
- a 100x tighter integration tolerance brings the trajectory closer to the tight reference;
- the scaling and case-time tables have their rows (measured none/rpy, extrapolated L = 1).
Usage: check_accuracy_quick.py KNOTFLOW_ACCURACY COIL_FILE WORKDIR
"""
import csv
import os
import shutil
import subprocess
import sys
import time

exe, coil, work = sys.argv[1], sys.argv[2], sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
t0 = time.time()
run = subprocess.run(["env", "OPENBLAS_NUM_THREADS=1", exe, "--quick", "--out", work,
                      "--coil", coil], capture_output=True, text=True, timeout=300)
print(run.stdout)
assert run.returncode == 0, run.stdout + run.stderr
print("wall %.1f s" % (time.time() - t0))


def table(name):
    with open(os.path.join(work, name), newline="") as f:
        return list(csv.DictReader(f))


models = table("models.csv")
assert [(r["model"], r["order"], r["lubrication"]) for r in models] == [
    ("none", "0", "0"), ("rpy", "0", "0"), ("multipole", "1", "0"), ("multipole", "1", "1"),
    ("multipole", "2", "1")], models
for r in models:
    assert r["status"] == "ok", r
    assert float(r["t_eval"]) > 0 and int(r["n_evals"]) >= 1, r
ref = models[-1]
for key in ("rms_rel", "max_rel", "rms_force", "rms_shear"):
    assert float(ref[key]) == 0.0, (key, ref)
for r in (models[0], models[2]):
    assert abs(float(r["rms_shear"]) - 1.0) < 1e-12, r
for r in models[:-1]:
    assert float(r["rms_rel"]) > 0.0, r

tol = table("tolerance.csv")
dev = {float(r["tolerance"]): float(r["max_deviation"]) for r in tol}
assert dev[1e-7] == 0.0, dev          # the reference against itself
assert 0.0 < dev[1e-5] < dev[1e-3], dev

scaling = table("scaling.csv")
assert len(scaling) == 6 and all(r["status"] == "ok" and float(r["t_eval"]) > 0 for r in scaling)
assert len(table("scaling_fit.csv")) == 3

case = table("case_time.csv")
assert [(r["model"], r["kind"]) for r in case] == [
    ("none", "measured"), ("rpy", "measured"), ("rpy", "extrapolated"),
    ("multipole", "extrapolated")], case
for r in case:
    assert float(r["wall"]) > 0 and float(r["evals_per_time"]) > 0, r
print("OK")
