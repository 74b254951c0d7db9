"""Scenes refused at set-up: exit status 2, one line on stderr naming the file, group, variable
and value with what is allowed, and nothing written (not even the output directory).

Each entry of CASES is (name, scene text, expected fragments); '{out}' in the scene is the
output directory, which must not exist afterwards. Entries whose refusal depends on the
machine (the memory estimate) are skipped where the machine is big enough to run them.
Usage: check_setup_refusals.py KNOTFLOW WORKDIR
"""
import os
import shutil
import subprocess
import sys

exe, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def mem_total():
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemTotal:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


GiB = 1024 ** 3
CASES = [
    # (name, scene, fragments, memory the refusal needs to be certain: the machine must have less)
    ("memory_rpy", "&chain shape = 'straight', n_beads = 100000 /\n&output directory = '{out}' /\n",
     ["&chain: n_beads = 100000 needs about 316.8 GiB of memory per case",
      "&hydro model = 'rpy' 260.8 GiB; run diagnostics 55.9 GiB", "of this machine (allowed: "], 316 * GiB),
    ("memory_multipole", "&chain shape = 'straight', n_beads = 20000 /\n&hydro model = 'multipole' /\n"
     "&output directory = '{out}', diagnostics = .false. /\n",
     ["&chain: n_beads = 20000 needs about 134.1 GiB", "&hydro model = 'multipole' 134.1 GiB)"], 134 * GiB),
    ("frames", "&integrator t_end = 1.0e7 /\n&output directory = '{out}', frame_interval = 1.0 /\n",
     ["&output: frame_interval = 1.0 with &integrator: t_end = 10000000.0 would write 10000001 frames",
      "allowed: at most 1000000 frames"], None),
    ("frames_small_interval", "&integrator t_end = 1000.0 /\n&output directory = '{out}', frame_interval = 1.0e-4 /\n",
     ["&output: frame_interval = 0.0001 with &integrator: t_end = 1000.0 would write 10000001 frames"], None),
    ("sweep_rounding", "&output directory = '{out}' /\n&sweep bending_a = 2.201, 2.204 /\n",
     ["&sweep: cases 1 (bending_a = 2.201) and 2 (bending_a = 2.204)", "'A2.20.h5'"], None),
    ("sweep_seed_twice", "&chain shape = 'candycane' /\n&output directory = '{out}' /\n&sweep seed = 1, 2, 1 /\n",
     ["&sweep: cases 1 (seed = 1) and 3 (seed = 1)", "'s1.h5'"], None),
]

# Coordinate files are read and checked at set-up.
for name, points, frag in [
        ("coords_one_bead", "1 2 3\n", "holds fewer than 2 beads"),
        ("coords_columns", "1 2 3\n4 5\n", "line 2: expected three numbers 'x y z', got '4 5'"),
        ("coords_nan", "1 2 3\n2 2 nan\n", "line 2: expected three numbers"),
        ("coords_coincident", "1 2 3\n2 2 3\n1 2 3\n", "beads 1 and 3 coincide (allowed: distinct points)")]:
    xyz = os.path.join(work, name + ".xyz")
    with open(xyz, "w") as f:
        f.write(points)
    CASES.append((name, "&chain shape = 'file', coordinate_file = '%s' /\n&output directory = '{out}' /\n" % xyz,
                  ["&chain: coordinate_file", frag], None))
# The models are built at set-up: what they reject is refused before any case runs.
CASES.append(("eps_lub_zero", "&hydro model = 'multipole', eps_lub = 0.0 /\n&output directory = '{out}' /\n",
              ["&hydro: eps_lub = 0.0", "(0, 0.5)"], None))
CASES.append(("orientation_long", "&chain orientation = 'bc' /\n&output directory = '{out}' /\n",
              ["&chain: orientation = 'bc' is 2 characters long (allowed: at most 1)"], None))
CASES.append(("twice", "&integrator t_end = 10.0, t_end = 20.0 /\n&output directory = '{out}' /\n",
              ["&integrator: t_end is given twice"], None))
CASES.append(("outside", "&output directory = '{out}' /\nt_end = 5\n",
              ["text outside a group: \"t_end = 5\""], None))

total = mem_total()
ran = skipped = 0
for name, text, fragments, needs in CASES:
    if needs is not None and (total is None or total >= needs):
        skipped += 1
        print("skipped %s: this machine has enough memory to run it" % name)
        continue
    out = os.path.join(work, name + "_out")
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write(text.format(out=out))
    r = subprocess.run([exe, path], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, (name, r.returncode, r.stdout, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, (name, r.stderr)
    assert lines[0].startswith("knotflow: error: " + path + ": "), (name, lines[0])
    for frag in fragments:
        assert frag in lines[0], (name, frag, lines[0])
    assert not os.path.exists(out), name + ": a refused scene created its output directory"
    ran += 1
# Not a scene at all: a directory, a binary file, an empty file (the output directory would be
# ./results: run in a scratch directory and check that nothing appears there).
scratch = os.path.join(work, "scratch")
os.makedirs(scratch)
binary = os.path.join(work, "binary.nml")
with open(binary, "wb") as f:
    f.write(bytes(range(256)) * 8)
empty = os.path.join(work, "empty.nml")
open(empty, "w").close()
for path, frag in [(work, "is a directory"), (binary, "not a text file"),
                   (empty, "no namelist group found")]:
    r = subprocess.run([exe, path], capture_output=True, text=True, timeout=120, cwd=scratch)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and frag in lines[0], (path, r.returncode, r.stderr)
    assert lines[0].startswith("knotflow: error: " + path + ": "), lines[0]
    assert os.listdir(scratch) == [], os.listdir(scratch)
    ran += 1
print("set-up refusals: %d refused as expected, %d skipped" % (ran, skipped))
