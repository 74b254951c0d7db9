"""Rerun with a changed scene, older case files, and sweeps whose cases would share a file.

1. A finished case rerun with the same scene is skipped (file untouched); rerun with another
   A or a longer t_end it is refused at set-up: exit status 2, one line naming the case file,
   the group, variable and both values and what to do, and no case file changed. The same for
   an interrupted case (status 'running'). A change in output.progress_interval alone is not a
   change of the scene (skipped).
2. New case files carry schema_version = 5. An older file (no schema_version, no hydro.update,
   no output.diagnostics attribute) counts the missing variables as their defaults, except
   hydro.update, which counts as 'stage' (the only behaviour before it existed, whatever the
   default is now): skipped when the requested scene has those values, refused naming the
   variable when it has not. A file of a newer schema (99) is never reused.
3. Sweeps whose cases would share a file (A = 2.201 and 2.204, a seed listed twice, a zip
   repeating a pair) are refused at set-up with exit status 2, naming both cases, and
   nothing is written (no output directory).
4. Case files record effective values: chain.n_beads is the bead count of the shape (trefoil
   100 - 1, candy-cane 90 + 62, a coordinate file its bead lines, straight 99 when not given),
   equal to the root n_beads and to the stored positions, and hydro.eps_lub not given is the
   integration tolerance. A file from before (chain.n_beads = 99 for a candy-cane, hydro.eps_lub
   = -1) is still skipped when finished and resumed when interrupted; another tolerance is
   still refused.
Usage: check_scene_match.py KNOTFLOW WORKDIR
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
out = os.path.join(work, "out")


def scene(name, a="1.0", t_end="2.0", extra_output="", extra="", hydro=", update = 'stage'"):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write("""&chain shape = 'straight', n_beads = 6 /
&forces bending_a = %s /
&hydro model = 'rpy' %s /
&integrator t_end = %s /
&output directory = '%s', case_name = 'c', frame_interval = 0.5 %s /
%s""" % (a, hydro, t_end, out, extra_output, extra))
    return path


def run(path, cwd=None):
    return subprocess.run([exe, path], capture_output=True, text=True, timeout=300, cwd=cwd)


def refused(path, *fragments):
    before = {f: os.path.getmtime(os.path.join(out, f)) for f in os.listdir(out) if f.endswith(".h5")}
    r = run(path)
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    for frag in fragments:
        assert frag in lines[0], (frag, lines[0])
    assert "case 1: started" not in r.stdout, r.stdout
    after = {f: os.path.getmtime(os.path.join(out, f)) for f in os.listdir(out) if f.endswith(".h5")}
    assert before == after, "a case file was written by a refused run"
    return lines[0]


def skipped(path):
    c = os.path.join(out, "c.h5")
    m = os.path.getmtime(c)
    r = run(path)
    assert r.returncode == 0, (r.stdout, r.stderr)
    assert "1 skipped" in r.stdout, r.stdout
    assert os.path.getmtime(c) == m, "a skipped case file was rewritten"


def set_attrs(**attrs):
    with h5py.File(os.path.join(out, "c.h5"), "a") as h:
        for k, v in attrs.items():
            k = k.replace("__", ".")
            if v is None:
                if k in h.attrs:
                    del h.attrs[k]
            elif isinstance(v, str):
                h.attrs[k] = np.bytes_(v)
            else:
                h.attrs[k] = v


base = scene("base")
r = run(base)
assert r.returncode == 0, (r.stdout, r.stderr)
case = os.path.join(out, "c.h5")
with h5py.File(case, "r") as h:
    assert h.attrs["schema_version"] == 5, dict(h.attrs)
    assert h.attrs["status"] in (b"finished", "finished")
checks = 1

# 1. same scene: skipped; other A or t_end: refused, finished and interrupted alike
skipped(base)
skipped(scene("progress", extra_output=", progress_interval = 0.0"))
line = refused(scene("other_a", a="2.5"), case + " (finished)",
               "&forces: bending_a = 1.0 in the file, 2.5 requested",
               "remove or move away that file", "another &output directory")
print("changed A:", line)
refused(scene("longer", t_end="4.0"), case, "&integrator: t_end = 2.0 in the file, 4.0 requested")
refused(scene("both", a="1.0000001", t_end="4.0"), "bending_a = 1.0 in the file, 1.0000001 requested",
        "; &integrator: t_end = 2.0 in the file, 4.0 requested")
set_attrs(status="running")
refused(scene("other_a_running", a="2.5"), case + " (interrupted)", "bending_a = 1.0 in the file, 2.5 requested")
set_attrs(status="finished")
checks += 6

# 2. an older file: missing variables are their defaults, except hydro.update, which was
#    'stage' before it existed (whatever its default is now)
with h5py.File(case, "a") as h:     # an older file also has the older checkpoint layout
    to_single_checkpoint(h, schema=None)
set_attrs(hydro__update=None, output__diagnostics=None)
skipped(base)
refused(scene("adaptive_update", hydro=", update = 'adaptive'"),
        "&hydro: update = 'stage' in the file, 'adaptive' requested")
refused(scene("adaptive", extra_output=", diagnostics = .false."),
        "&output: diagnostics = .true. in the file, .false. requested")
set_attrs(schema_version=np.int32(99))
refused(base, case, "schema_version = 99 in the file")
set_attrs(schema_version=np.int32(2), hydro__update="stage", output__diagnostics=np.int64(1))
skipped(base)
checks += 5

# 3. sweeps whose cases would share a file: refused, nothing written
for name, sweep, fragments in [
        ("rounding", "&sweep bending_a = 2.201, 2.204 /\n",
         ["cases 1 (bending_a = 2.201) and 2 (bending_a = 2.204)", "'c_A2.20.h5'"]),
        ("seed_twice", "&sweep bending_a = 1.0, 2.0, seed = 3, 4, 3 /\n",
         ["cases 1 (bending_a = 1.0, seed = 3) and 3 (bending_a = 1.0, seed = 3)", "'c_A1.00_s3.h5'"]),
        ("zip_repeat", "&sweep combine = 'zip', bending_a = 1.0, 2.0, 1.0, seed = 5, 6, 5 /\n",
         ["cases 1 (", "and 3 (", "'c_A1.00_s5.h5'"])]:
    path = os.path.join(work, name + ".nml")
    fresh = os.path.join(work, "fresh_" + name)
    with open(path, "w") as f:
        f.write(open(base).read().replace(out, fresh) + sweep)
    r = run(path)
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    line = r.stderr.strip()
    assert "\n" not in line and path + ": &sweep: " in line and "every case needs its own name" in line, line
    for frag in fragments:
        assert frag in line, (frag, line)
    assert not os.path.exists(fresh), "a refused sweep created its output directory"
    checks += 1

# 4. effective values in the case file, and files from before they were recorded
out4 = os.path.join(work, "effective")
coords = os.path.join(work, "seven.xyz")
with open(coords, "w") as f:
    f.write("# seven beads\n\n" + "".join("%.2f 0 0\n" % (1.02 * k) for k in range(7)))
n_file = sum(1 for ln in open(coords) if ln.strip() and not ln.lstrip().startswith("#"))


def scene4(name, chain, tolerance="1e-3"):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write("&chain %s /\n&hydro model = 'rpy' /\n&integrator t_end = 0.5, tolerance = %s /\n"
                "&output directory = '%s', case_name = '%s', frame_interval = 0.25 /\n"
                % (chain, tolerance, out4, name))
    return path


for name, chain, n_expected in [("cc", "shape = 'candycane'", 90 + 62),
                                ("tref", "shape = 'trefoil'", 100 - 1),
                                ("coords", "shape = 'file', coordinate_file = '%s'" % coords, n_file),
                                ("line", "shape = 'straight'", 99)]:
    r = run(scene4(name, chain))
    assert r.returncode == 0, (name, r.stdout, r.stderr)
    with h5py.File(os.path.join(out4, name + ".h5"), "r") as h:
        assert int(h.attrs["chain.n_beads"]) == n_expected == int(h.attrs["n_beads"]), (name, dict(h.attrs))
        assert h["frames/positions"].shape[1:] == (n_expected, 3), h["frames/positions"].shape
        assert h.attrs["hydro.eps_lub"] == 1e-3 == h.attrs["integrator.tolerance"], dict(h.attrs)
        text = h.attrs["scene"]
        text = text.decode() if isinstance(text, bytes) else text
        assert "n_beads = %d\n" % n_expected in text and "eps_lub = -" not in text, text
    checks += 1

cc = os.path.join(out4, "cc.h5")
with h5py.File(cc, "a") as h:       # as knotflow wrote it before the scene was resolved
    h.attrs["chain.n_beads"] = np.int64(99)
    h.attrs["hydro.eps_lub"] = -1.0
r = run(scene4("cc", "shape = 'candycane'"))
assert r.returncode == 0 and "1 skipped" in r.stdout, (r.stdout, r.stderr)
with h5py.File(cc, "a") as h:
    h.attrs["status"] = np.bytes_("running")
r = run(scene4("cc", "shape = 'candycane'"))
assert r.returncode == 0 and "1 finished" in r.stdout, (r.stdout, r.stderr)
with h5py.File(cc, "r") as h:
    assert h.attrs["status"] in (b"finished", "finished")
    assert list(h["frames/time"][:]) == [0.0, 0.25, 0.5], h["frames/time"][:]
r = run(scene4("cc", "shape = 'candycane'", tolerance="1e-4"))
assert r.returncode == 2, (r.stdout, r.stderr)
assert "&integrator: tolerance = 0.001 in the file, 0.0001 requested" in r.stderr, r.stderr
assert "&hydro: eps_lub = 0.001 in the file, 0.0001 requested" in r.stderr, r.stderr
checks += 3
print("scene match: %d checks passed (skip on equal scene, refusal on changed A / t_end, "
      "old schema defaults, newer schema, 3 clashing sweeps, effective values recorded for 4 shapes, "
      "a file with eps_lub = -1 and n_beads = 99 skipped and resumed)" % checks)
