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
print("set-up refusals: %d refused as expected, %d skipped" % (ran, skipped))
