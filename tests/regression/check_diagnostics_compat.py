"""Run diagnostics switched off, and files from before they existed.

1. `&output diagnostics = .false.`: the case file has no /frames/diagnostics, no diagnostics.*
   attributes and no /checkpoint/diagnostics; output.diagnostics = 0.
2. A file as written by a version without run diagnostics (its scene text has no diagnostics
   line), interrupted at t = 5, is resumed by the current program with the default scene
   (diagnostics on): it is continued without diagnostics, every frame once, and its trajectory
   is that of the uninterrupted run to integration tolerance.
Usage: check_diagnostics_compat.py KNOTFLOW WORKDIR
"""
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np
from kf_legacy import to_single_checkpoint

exe, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def scene(name, output_extra=""):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write("""&chain shape = 'trefoil', orientation = 'c' /
&forces excluded_volume = .true. /
&integrator t_end = 10.0 /
&output directory = '%s', case_name = 'c' %s /
""" % (os.path.join(work, name), output_extra))
    return path


def run(path):
    out = subprocess.run([exe, path], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, (out.stdout, out.stderr)
    return out.stdout


run(scene("off", ", diagnostics = .false."))
off_path = os.path.join(work, "off", "c.h5")
with h5py.File(off_path, "r") as h:
    assert "diagnostics" not in h["frames"]
    assert not [g for g in h["checkpoint"].values() if "diagnostics" in g]
    assert not [k for k in h.attrs if k.startswith("diagnostics.")]
    assert h.attrs["output.diagnostics"] == 0
    t_ref = h["frames/time"][:]
    r_ref = h["frames/positions"][:]
    text = h.attrs["scene"].decode()
assert "  diagnostics = .false.\n" in text, text

# The same file as an older version would have left it when killed after the frame t = 5.
os.makedirs(os.path.join(work, "old"))
old_path = os.path.join(work, "old", "c.h5")
shutil.copy(off_path, old_path)
with h5py.File(old_path, "a") as h:
    old_text = text.replace("  diagnostics = .false.\n", "").replace(
        os.path.join(work, "off"), os.path.join(work, "old"))
    h.attrs["scene"] = np.bytes_(old_text)
    h.attrs["output.directory"] = np.bytes_(os.path.join(work, "old"))
    del h.attrs["output.diagnostics"]
    h.attrs["status"] = np.bytes_("running")
    to_single_checkpoint(h, schema=None)   # an older version: one /checkpoint, no schema_version
    k = 5
    c = h["checkpoint"]
    c["time"][()] = h["frames/time"][k]
    c["positions"][...] = h["frames/positions"][k]
    c["dt"][()] = h["frames/integrator/dt"][k]
    c["steps"][()] = h["frames/integrator/steps"][k]
    c["rejected"][()] = h["frames/integrator/rejected"][k]
    c["nframes"][()] = k + 1
    del c["digest"]      # older versions wrote no checkpoint digest
out = run(scene("old"))
assert "resuming" in out, out
with h5py.File(old_path, "r") as h:
    assert h.attrs["status"] in (b"finished", "finished")
    assert "diagnostics" not in h["frames"] and "diagnostics" not in h["checkpoint"]
    # resumed, an older file gets the current layout: two checkpoint slots, /runs, schema_version 5
    assert sorted(h["checkpoint"].keys()) == ["slot0", "slot1"], list(h["checkpoint"].keys())
    assert h.attrs["schema_version"] == 5
    t = h["frames/time"][:]
    r = h["frames/positions"][:]
assert np.array_equal(t, t_ref), (t, t_ref)
dev = np.abs(r - r_ref).max()
assert dev < 1e-2, dev
print("diagnostics off: none written; a pre-diagnostics file resumed at t = 5 without them, "
      "max deviation %.2e" % dev)
