"""/runs: one entry per run segment (the first start and every resume of a case).

1. A case killed with SIGKILL part-way (run with OPENBLAS_NUM_THREADS=1) and run again to the end
   (OPENBLAS_NUM_THREADS=2) has two entries: t_start of the second = t_end of the first = the
   time of the checkpoint it resumed from (the newest whole checkpoint of the killed file, and
   the time the resume reports); t_end of the last = the scene's t_end; the steps of the segments
   add up to the run's total (/frames/integrator/steps of the last frame) and the first
   segment's to the steps of the checkpoint; wall_seconds > 0; commit = the root attribute
   git_hash; host = this machine's name; started ISO 8601 UTC, within the test's run time, in
   order; ranks = 1; threads = 1 then 2 (0 where the BLAS is not OpenBLAS and cannot be asked);
   blas = 'OpenBLAS <version> <core>' with the core OpenBLAS itself reports (OPENBLAS_VERBOSE=2)
   for each segment, run with OPENBLAS_CORETYPE Prescott then Nehalem (kernels any x86-64 CPU
   runs), the same as the start-up line 'knotflow: BLAS ...' ('unknown' for another BLAS);
   load_start and load_mean finite on Linux (getloadavg); schema_version 5.
2. Rerun when finished: skipped, /runs unchanged (no new entry).
3. A file of the previous schema (3: no /runs, no run figures in its checkpoint), killed
   part-way, resumes: it gets /runs with one entry starting at its checkpoint time and ending at
   t_end, its steps the steps after the checkpoint, and schema_version 5. The same file finished
   (schema 3, no /runs) is skipped and left without /runs.
4. A file of schema 4 (/runs without blas), killed part-way, resumes: its first entry's blas
   reads 'unknown', the new entry's the kernels, and the Python reader gives None for a file
   without /runs/blas.
Usage: check_run_records.py KNOTFLOW WORKDIR HAVE_OPENBLAS(0/1)
"""
import datetime
import os
import re
import shutil
import signal
import socket
import subprocess
import sys

import h5py
import numpy as np
from kf_legacy import drop_run_records, newest_slot
from knotflow_tools.io import read_case

exe, work, have_openblas = sys.argv[1], sys.argv[2], sys.argv[3] == "1"
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
T_END = 40.0
RUN_SETS = ("commit", "started", "host", "blas", "ranks", "threads", "t_start", "t_end", "steps",
            "wall_seconds", "load_start", "load_mean")
SCHEMA = 5
CORES = ("Prescott", "Nehalem")   # OPENBLAS_CORETYPE of the two segments


def scene(name):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write("""&chain shape = 'trefoil', orientation = 'c' /
&forces excluded_volume = .true. /
&integrator t_end = %r /
&output directory = '%s', case_name = 'c', frame_interval = 1.0, progress_interval = 0.0 /
""" % (T_END, os.path.join(work, name)))
    return path


def env(threads, core=CORES[0]):
    e = dict(os.environ)
    e["OPENBLAS_NUM_THREADS"] = str(threads)
    e["OPENBLAS_CORETYPE"] = core
    e["OPENBLAS_VERBOSE"] = "2"
    return e


def blas_seen(stdout, stderr):
    """What the run's start-up line says of its BLAS, checked against OpenBLAS's own report of
    its core (OPENBLAS_VERBOSE=2 prints 'Core: <name>'; nothing from a library built for one
    CPU or from another BLAS)."""
    m = re.search(r"^knotflow: BLAS (.+?)(, \d+ thread\(s\) per rank.*)?$", stdout, re.M)
    assert m, stdout
    said = m.group(1)
    core = re.search(r"^Core: (\S+)", stderr, re.M)
    if not have_openblas:
        assert said == "unknown", said
    elif core:
        assert re.fullmatch(r"OpenBLAS \d+\.\d+\.\d+ " + re.escape(core.group(1)), said), \
            (said, core.group(1))
    else:
        assert said.startswith("OpenBLAS "), said
    return said


def run(path, threads, core=CORES[0]):
    done = subprocess.run([exe, path], capture_output=True, text=True, timeout=600,
                          env=env(threads, core))
    assert done.returncode == 0, (done.stdout, done.stderr)
    return done.stdout, blas_seen(done.stdout, done.stderr)


def killed_run(path, threads, at="15.000", core=CORES[0]):
    """Start the scene, kill it with SIGKILL after the progress line of t = `at`; the BLAS its
    start-up line named."""
    proc = subprocess.Popen([exe, path], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env(threads, core))
    lines = []
    for line in proc.stdout:
        lines.append(line)
        if ": t = %s /" % at in line:
            break
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    return blas_seen("".join(lines), proc.stderr.read())


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def runs(h):
    assert "runs" in h, "no /runs"
    r = {k: h["runs"][k][()] for k in RUN_SETS}
    n = len(r["t_start"])
    assert all(len(v) == n for v in r.values()), {k: len(v) for k, v in r.items()}
    return r


def checkpoint(h):
    """Time and steps of the newest checkpoint of a killed file."""
    g = newest_slot(h)
    return float(g["time"][()]), int(g["steps"][()])


before = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0)

# 1. killed, then resumed to the end
case = os.path.join(work, "two", "c.h5")
blas1 = killed_run(scene("two"), 1)
with h5py.File(case, "r") as h:
    assert text(h.attrs["status"]) == "running"
    t_ck, steps_ck = checkpoint(h)
    first = runs(h)
    assert len(first["t_start"]) == 1, first
    # the killed file's entry holds the figures of its newest checkpoint
    assert first["t_end"][0] == t_ck and first["steps"][0] == steps_ck, (first, t_ck, steps_ck)
assert 15.0 <= t_ck < T_END, t_ck
out, blas2 = run(scene("two"), 2, core=CORES[1])
m = re.search(r"resuming at t = (\S+) from its checkpoint", out)
assert m and abs(float(m.group(1)) - t_ck) < 1e-3 * max(1.0, t_ck), (out, t_ck)
after = datetime.datetime.now(datetime.timezone.utc)
with h5py.File(case, "r") as h:
    assert text(h.attrs["status"]) == "finished"
    assert h.attrs["schema_version"] == SCHEMA
    r = runs(h)
    total_steps = int(h["frames/integrator/steps"][-1])
    git_hash = text(h.attrs["git_hash"])
assert len(r["t_start"]) == 2, r
assert r["t_start"][0] == 0.0 and r["t_start"][1] == r["t_end"][0] == t_ck, r
assert r["t_end"][1] == T_END, r
assert r["steps"][0] == steps_ck and r["steps"].sum() == total_steps and r["steps"][1] > 0, \
    (r["steps"], steps_ck, total_steps)
assert np.all(r["wall_seconds"] > 0), r["wall_seconds"]
assert [text(c) for c in r["commit"]] == [git_hash] * 2, (r["commit"], git_hash)
assert [text(c) for c in r["host"]] == [socket.gethostname()] * 2, r["host"]
started = [datetime.datetime.strptime(text(s), "%Y-%m-%dT%H:%M:%SZ").replace(tzinfo=datetime.timezone.utc)
           for s in r["started"]]
assert before <= started[0] <= started[1] <= after, (started, before, after)
assert list(r["ranks"]) == [1, 1], r["ranks"]
assert list(r["threads"]) == ([1, 2] if have_openblas else [0, 0]), r["threads"]
assert [text(b) for b in r["blas"]] == [blas1, blas2], (r["blas"], blas1, blas2)
for k in ("load_start", "load_mean"):
    if sys.platform.startswith("linux"):
        assert np.all(np.isfinite(r[k])) and np.all(r[k] >= 0), (k, r[k])
    else:
        assert np.all(np.isfinite(r[k])) or np.all(np.isnan(r[k])), (k, r[k])
print("killed at t = %g (%d steps) and resumed: /runs t %s, steps %s (total %d), wall %s s, "
      "threads %s, BLAS %s, load at start %s, mean %s"
      % (t_ck, steps_ck, list(zip(r["t_start"].tolist(), r["t_end"].tolist())), r["steps"].tolist(),
         total_steps, np.round(r["wall_seconds"], 2).tolist(), r["threads"].tolist(),
         [text(b) for b in r["blas"]],
         np.round(r["load_start"], 2).tolist(), np.round(r["load_mean"], 2).tolist()))

# 2. a finished case rerun is skipped and gets no entry
out, _ = run(scene("two"), 1)
assert "1 skipped (already finished)" in out, out
with h5py.File(case, "r") as h:
    again = runs(h)
for k in RUN_SETS:
    assert np.array_equal(again[k], r[k]), (k, again[k], r[k])
print("rerun of the finished case: skipped, /runs unchanged (2 entries)")

# ... and the Python tools read the same records (knotflow-study's runs table)
tool_runs = read_case(case).runs
assert len(tool_runs) == 2, tool_runs
for k in RUN_SETS:
    got = [e[k] for e in tool_runs]
    want = [text(v) for v in r[k]] if r[k].dtype.kind in "SOU" else r[k].tolist()
    assert got == want, (k, got, want)
print("knotflow_tools.io.read_case reads the same 2 run records")

# 3. a file of schema 3 (before /runs), interrupted: resumed, it gets /runs from then on
old = os.path.join(work, "old", "c.h5")
killed_run(scene("old"), 1, at="12.000")
with h5py.File(old, "r+") as h:
    drop_run_records(h)
    t_old, steps_old = checkpoint(h)
assert 12.0 <= t_old < T_END, t_old
run(scene("old"), 1)
with h5py.File(old, "r") as h:
    assert text(h.attrs["status"]) == "finished"
    assert h.attrs["schema_version"] == SCHEMA
    r = runs(h)
    total_steps = int(h["frames/integrator/steps"][-1])
assert len(r["t_start"]) == 1, r
assert r["t_start"][0] == t_old and r["t_end"][0] == T_END, r
assert r["steps"][0] == total_steps - steps_old, (r["steps"], total_steps, steps_old)
print("schema 3 file interrupted at t = %g: resumed, /runs has one entry from t = %g to %g, %d steps"
      % (t_old, r["t_start"][0], r["t_end"][0], r["steps"][0]))

# ... and a finished file of schema 3 is skipped and left as it is
with h5py.File(old, "r+") as h:
    drop_run_records(h)
out, _ = run(scene("old"), 1)
assert "1 skipped (already finished)" in out, out
with h5py.File(old, "r") as h:
    assert "runs" not in h and h.attrs["schema_version"] == 3
print("finished schema 3 file: skipped, no /runs added")

# 4. a file of schema 4 (/runs without blas), interrupted: resumed, its old entry reads 'unknown'
four = os.path.join(work, "four", "c.h5")
killed_run(scene("four"), 1)
with h5py.File(four, "r+") as h:
    del h["runs/blas"]
    h.attrs["schema_version"] = np.int32(4)
assert read_case(four).runs[0]["blas"] is None
_, blas_new = run(scene("four"), 1, core=CORES[1])
with h5py.File(four, "r") as h:
    assert h.attrs["schema_version"] == SCHEMA
    r = runs(h)
assert [text(b) for b in r["blas"]] == ["unknown", blas_new], r["blas"]
print("schema 4 file resumed: /runs/blas %s" % [text(b) for b in r["blas"]])
