"""A campaign that outlives its machine: the case ledger (knotflow_tools.campaign).

A sweep of two trefoils (RPY + excluded volume, t_end = 40) is run twice:
1. uninterrupted, analysed (knotflow-analyze, every frame) and digested into a reference ledger;
2. as a campaign: `knotflow --write-scenes` writes each case's scene; case A1.40 is run from its
   own scene (which writes the very file the sweep would: the sweep's dry run accepts it),
   killed after t = 15 (while it runs, A again and the sweep are refused by the locks, and B
   runs beside it from its own scene), its copy analysed and digested; then the machine is
   "lost" (results deleted). `plan` must say 'continue' for A (from the ledger's newest frame)
   and 'run' for B; each planned scene is run, analysed and digested.
Checked: the ledger rows of A are the frames 0, 1, ..., 40 exactly once; before the kill they
equal the reference rows (same file, same frames, same k_f); after it the continuation is the
same physics restarted (step size, overlap monitor): the chain at t = 40 within 0.05 d of the
uninterrupted one and R_g within 1 %. A has two segments, B one; both finished; `plan` then says
'finished'. The case mode of a one-segment case's rows (knotflow-analyze ROWS.csv) is the
file's, and the study's rows (knotflow-study) of its ledger entry equal those of its file; the
two-segment case's row has both runs at the case's time and the overlap episodes summed. `--write-scenes` without a directory, or into one that cannot be made, exits with
status 2. Refused, leaving the ledger as it was: a file analysed with other closures, the old
segment again after its continuation (a rewind), a gap.
Usage: check_campaign.py KNOTFLOW KNOTFLOW_ANALYZE WORKDIR   (Python with knotflow_tools)
"""
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
from knotflow_tools import campaign, study_rows

exe, analyze, work = (os.path.abspath(a) for a in sys.argv[1:4])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
os.chdir(work)
CLOSURES = 30
SWEEP = "sw"


def write(path, text):
    with open(path, "w") as fh:
        fh.write(text)


write("sw.nml", """&chain shape = 'trefoil', orientation = 'c' /
&forces excluded_volume = .true. /
&integrator t_end = 40.0 /
&output directory = 'results/sw', frame_interval = 1.0, progress_interval = 0.0,
  stresslet = .true., diagnostics = .true. /
&sweep bending_a = 1.4, 2.2 /
""")


def run(*args, **kw):
    return subprocess.run(list(args), check=True, capture_output=True, text=True, timeout=600, **kw)


def analyse_copy(src, copies):
    """Copy `src` (under results/) into `copies`, mirroring, and analyse the copy."""
    dst = os.path.join(copies, os.path.relpath(src, "results"))
    os.makedirs(os.path.dirname(dst), exist_ok=True)
    shutil.copy(src, dst)
    run(analyze, dst, "--closures", str(CLOSURES), "--stride", "1")
    return dst


def digest(src, ledger, closures=CLOSURES):
    dst = analyse_copy(src, "copies")
    return campaign.digest(dst, ledger, SWEEP, closures, 10.0,
                           os.path.join("results", os.path.relpath(dst, "copies")))


def close(x, y):
    """Equal, numbers to what 7 significant digits of the ledger leave (recursively)."""
    if isinstance(x, dict):
        return isinstance(y, dict) and x.keys() == y.keys() and all(close(x[k], y[k]) for k in x)
    if isinstance(x, (list, tuple)):
        return isinstance(y, (list, tuple)) and len(x) == len(y) and all(map(close, x, y))
    if isinstance(x, float) and isinstance(y, (int, float)):
        return bool(np.isclose(x, y, rtol=1e-6, atol=1e-6, equal_nan=True))
    return x == y


def snapshot(ledger):
    return {f: open(os.path.join(ledger, SWEEP, f), "rb").read()
            for f in sorted(os.listdir(os.path.join(ledger, SWEEP)))}


def refused(fn, text):
    try:
        fn()
    except ValueError as exc:
        assert text in str(exc), f"refusal without '{text}': {exc}"
        return
    raise AssertionError(f"not refused (expected '{text}')")


def check_status(entries, t_left):
    """`knotflow-campaign status` of the ledger against the run records of its entries: the
    sweep's rate is the wall time of its runs over the time they covered (one BLAS kernel
    here), the time left that rate times t_left; the markdown row (--markdown) says the same."""
    runs = [r for e in entries for seg in e["segments"] for r in seg["runs"]]
    assert len({r["blas"] for r in runs}) == 1, runs
    rate = sum(r["wall_seconds"] for r in runs) / sum(r["t_end"] - r["t_start"] for r in runs)
    st = campaign.status("ledger", "status_scenes")
    (w,) = st["sweeps"]
    running = [(e["case"], e["t_reached"]) for e in entries if e["status"] == "running"]
    assert w["cases"] == 2 and w["running"] == running, w
    assert w["finished"] == sum(e["status"] == "finished" for e in entries), w
    assert w["not_started"] == 2 - len(entries), w
    assert np.isclose(w["rate"], rate, rtol=1e-12) and np.isclose(w["left"], rate * t_left), (w, rate)
    assert st["campaign"]["left"] == w["left"] and st["campaign"]["counted"], st["campaign"]
    md = run(sys.executable, "-c", "import sys; from knotflow_tools.cli import main_campaign; "
             "sys.exit(main_campaign(sys.argv[1:]))", "status", "--ledger", "ledger", "--scenes",
             "status_scenes", "--markdown").stdout.split("\n")
    row = [ln for ln in md if ln.startswith(f"| `{SWEEP}` |")]
    cells = [c.strip() for c in row[0].strip("|").split("|")]
    assert cells[1:3] == ["2", str(w["finished"])] and cells[4] == str(2 - len(entries)), cells
    assert cells[5].startswith(f"{rate:.2f} (") and cells[6] == f"{rate * t_left / 3600:.1f}", cells
    assert cells[3] == (", ".join(f"{c} (t = {t:g})" for c, t in running) or "-"), cells


# 1. The reference: the sweep uninterrupted.
run(exe, "sw.nml")
for c in ("A1.40", "A2.20"):
    digest(f"results/sw/{c}.h5", "ledger_ref")
# The case mode of the ledger's rows (knotflow-analyze ROWS.csv) is that of the whole file
# (/analysis/shape) for a case of one segment.
for c in ("A1.40", "A2.20"):
    with h5py.File(f"copies/sw/{c}.h5", "r") as h:
        stored = int(h["analysis/shape"].attrs["case_mode"])
    out = run(analyze, f"ledger_ref/sw/{c}.csv", "--json").stdout
    assert json.loads(out)["case_mode"] == stored, (c, out, stored)
    campaign.set_case_mode("ledger_ref", SWEEP, c, out)
    # The study's rows of the ledger entry are those of the case file (the slower exact path),
    # but for where the overlap totals come from.
    for rows_of in (study_rows.trefoil_rows, study_rows.candycane_rows):
        a = rows_of([f"copies/sw/{c}.h5"], CLOSURES)[0]
        b = rows_of([f"ledger_ref/sw/{c}.json"], CLOSURES)[0]
        assert a["overlap"].pop("source") == "attributes" and b["overlap"].pop("source") == "ledger"
        for k in a:
            if not k.startswith("_"):
                assert close(a[k], b[k]), (c, k, a[k], b[k])
ref = campaign.read_rows("ledger_ref", SWEEP, "A1.40")
ref_last = np.asarray(campaign.load("ledger_ref", SWEEP, "A1.40")["last_frame"])
shutil.move("results", "results_ref")

# 2. The campaign: scenes, A killed part-way.
for bad, text in ((["--write-scenes"], "--write-scenes needs a directory"),
                  (["--write-scenes", "sw.nml/x"], "--write-scenes 'sw.nml/x'")):
    r = subprocess.run([exe, "sw.nml"] + bad, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and text in r.stderr, (bad, r.returncode, r.stderr)
run(exe, "sw.nml", "--write-scenes", "scenes")
assert sorted(os.listdir("scenes")) == ["A1.40.nml", "A2.20.nml"], os.listdir("scenes")
proc = subprocess.Popen([exe, "scenes/A1.40.nml"], stdout=subprocess.PIPE,
                        stderr=subprocess.DEVNULL, text=True)
# Locks while A runs (stopped meanwhile, holding them) in the sweep's directory: A again and the
# sweep are refused, B runs beside it (a single case takes the directory lock shared and its own
# case lock).
while proc.poll() is None and not os.path.exists("results/sw/A1.40.h5"):
    time.sleep(0.01)
proc.send_signal(signal.SIGSTOP)
for args, text in ((["scenes/A1.40.nml"], "computing case A1.40 here"),
                   (["sw.nml"], "another knotflow run is writing into this directory")):
    r = subprocess.run([exe] + args, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and text in r.stderr, (args, r.returncode, r.stderr)
beside = subprocess.Popen([exe, "scenes/A2.20.nml"], stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, text=True)
proc.send_signal(signal.SIGCONT)
for line in proc.stdout:          # one progress line per frame (progress_interval = 0)
    if ": t = 15.000 /" in line:
        break
proc.send_signal(signal.SIGKILL)
proc.wait()
with h5py.File("results/sw/A1.40.h5", "r") as h:
    t_kill = float(h["frames/time"][-1])
assert 15.0 <= t_kill < 40.0, f"killed at t = {t_kill}"
assert beside.wait(timeout=600) == 0, beside.stderr.read()
os.remove("results/sw/A2.20.h5")
# The single-case scene wrote the sweep's own file: the sweep accepts it (dry run: no refusal).
run(exe, "sw.nml", "--dry-run")
e = digest("results/sw/A1.40.h5", "ledger")
T = e["t_reached"]
assert e["status"] == "running" and T >= 14.0, e
# the stepper's state at the newest frame (dopri45: dt, statistics, err_prev, the FSAL stage)
kept_state = e
assert e["stepper_state"]["t"] == T and e["stepper_state"]["method"] == "dopri45", e["stepper_state"]
assert len(e["stepper_state"]["reals"]) == 3 + 2 + 2 * 3 * e["n_beads"], len(e["stepper_state"]["reals"])
# Status: A running at T, B not started (the campaign's scenes, <dir>/<sweep>/<case>.nml).
shutil.copytree("scenes", f"status_scenes/{SWEEP}")
check_status([e], (40.0 - T) + 40.0)
kept = snapshot("ledger")
refused(lambda: digest("results/sw/A1.40.h5", "ledger", closures=CLOSURES + 1),
        "closures per frame")
assert snapshot("ledger") == kept
shutil.rmtree("results")          # the machine is lost; the ledger is what was committed
shutil.rmtree("copies")

out = run(sys.executable, "-c", "import sys; from knotflow_tools.cli import main_campaign; "
          "sys.exit(main_campaign(sys.argv[1:]))", "plan", "--scenes", "scenes", "--results",
          "results", "--ledger", "ledger", "--sweep", SWEEP).stdout.split("\n")
plan = [ln.split() for ln in out if ln.strip()]
assert [p[:2] for p in plan] == [["A1.40", "continue"], ["A2.20", "run"]], plan
assert plan[0][2].endswith(f"continued/A1.40_from{T:g}.nml"), plan
# The continuation starts from the stepper's state at T (the killed file's newest checkpoint,
# kept by the digest): the state file beside the scene, named by &chain stepper_state.
state = os.path.abspath(f"results/sw/continued/A1.40_from{T:g}.state.h5")
cscene = open(plan[0][2]).read()
assert f"stepper_state = '{state}'" in cscene, cscene
with h5py.File(state, "r") as h:
    assert h["time"][()] == T and h["stepper"].attrs["name"] == "dopri45", dict(h.attrs)
    assert np.array_equal(h["positions"][()], np.asarray(kept_state["last_frame"])), "state positions"
# Refused at set-up, nothing written (exit 2, the variable, the file and why): a state of another
# stepper, of other positions (one bead moved by 1e-9 d), a state in a sweep of several cases,
# a file that is not HDF5, a FIFO (refused by its type, not opened).
xyz = next(ln.split("'")[1] for ln in cscene.splitlines() if "coordinate_file" in ln)
moved = np.asarray(kept_state["last_frame"])
moved[0, 0] += 1e-9
write("moved.xyz", "".join(f"{x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in moved))
os.makedirs("bad", exist_ok=True)
open("bad/not_a_state.h5", "wb").write(b"not HDF5")
os.mkfifo("bad/fifo.h5")
def elsewhere(text, directory):
    """The scene text with its &output directory replaced."""
    return re.sub(r"directory = '[^']*'", f"directory = '{directory}'", text, count=1)


for name, change, text in (
        ("rk4", ("method = 'dopri45'", "method = 'rk4'"), "it holds the state of stepper 'dopri45'"),
        ("moved", (xyz, os.path.abspath("moved.xyz")), "its positions differ from the chain"),
        ("sweep", ("", ""), "in a sweep of 2 cases"),
        ("nostate", (state, os.path.abspath("bad/not_a_state.h5")), "not_a_state.h5"),
        ("fifo", (state, os.path.abspath("bad/fifo.h5")), "only a regular file is read")):
    bad_text = elsewhere(cscene.replace(*change), os.path.abspath("bad/" + name))
    if name == "sweep":
        bad_text += "&sweep bending_a = 1.4, 2.2 /\n"
    write(f"bad/{name}.nml", bad_text)
    r = subprocess.run([exe, f"bad/{name}.nml"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "stepper_state" in r.stderr and text in r.stderr, (name, r.returncode, r.stderr)
    assert not os.path.exists(f"bad/{name}"), f"{name}: something was written"
# A control: the same continuation without the state (the stepper afresh at dt_initial), elsewhere.
write("control.nml", elsewhere(cscene.replace(f"stepper_state = '{state}'", "stepper_state = ''"),
                               os.path.abspath("control")))
run(exe, "control.nml")
for name, _action, scene in plan:
    run(exe, scene)
cont = f"results/sw/continued/A1.40_from{T:g}.h5"
with h5py.File(cont, "r") as h:
    assert abs(h["frames/time"][-1] - (40.0 - T)) < 1e-9, h["frames/time"][-1]
e = digest(cont, "ledger")
digest("results/sw/A2.20.h5", "ledger")

rows = campaign.read_rows("ledger", SWEEP, "A1.40")
t = rows[:, 0]
assert np.array_equal(t, np.arange(41.0)), t
before = t < T - 1e-9
col = {c: k for k, c in enumerate(campaign.FRAME_COLUMNS)}
for c in ("rg", "a", "theta", "close_pairs", "min_distance", "viscosity"):
    assert np.array_equal(rows[before, col[c]], ref[before, col[c]]), c
assert np.array_equal(rows[before, col["kf"]], ref[before, col["kf"]])
assert np.all(np.isfinite(rows[:, col["kf"]]))
last = np.asarray(campaign.load("ledger", SWEEP, "A1.40")["last_frame"])
dev = np.max(np.linalg.norm(last - ref_last, axis=1))
with h5py.File(f"control/A1.40_from{T:g}.h5", "r") as h:
    dev_control = np.max(np.linalg.norm(h["frames/positions"][-1] - ref_last, axis=1))
# With the stepper's state the continuation is the uninterrupted run to rounding (its clock
# starts at 0, not at T: the clipped steps' sizes differ in the last bits); the control, its
# stepper afresh, is another trajectory within the tolerance.
assert dev < 1e-9, f"continued chain at t = 40 is {dev:.3g} d from the uninterrupted one"
# ... with its steps and derivative evaluations (the counts go on from the state's; the FSAL
# stage is reused, its time moved to the new clock, so no evaluation is added)
counts = []
for path in ("results_ref/sw/A1.40.h5", cont):
    with h5py.File(path, "r") as h:
        g = max((h["checkpoint"][k] for k in ("slot0", "slot1")), key=lambda g: int(g["nframes"][()]))
        counts.append(tuple(int(x) for x in g["stepper/ints"][()][1:4]))
assert counts[0] == counts[1], f"steps, rejected, evaluations: uninterrupted {counts[0]}, continued {counts[1]}"
assert dev_control > 100 * max(dev, 1e-15), (dev, dev_control)
assert e["status"] == "finished" and len(e["segments"]) == 2, e
assert e["segments"][1]["t_offset"] == T and e["segments"][1]["case_name"] == f"A1.40_from{T:g}"
assert e["segments"][1]["from_state"] and not e["segments"][0]["from_state"], e["segments"]
assert "stepper_state" not in e, "a finished entry keeps no stepper state"
assert campaign.ledger_case("ledger/sw/A1.40.json").attrs["continued_at"] == [], "continued exactly"
# The study's row of the case in two segments: its runs at the case's time, totals summed.
campaign.set_case_mode("ledger", SWEEP, "A1.40", run(analyze, "ledger/sw/A1.40.csv", "--json").stdout)
row = study_rows.trefoil_rows(["ledger/sw/A1.40.json"], CLOSURES)[0]
assert row["status"] == "finished" and row["t_reached"] == 40.0, row
assert row["runs"]["segments"] == 2 and row["runs"]["t_start"] == 0.0 and row["runs"]["t_end"] == 40.0
episodes = sum(s["diagnostic_totals"]["overlap_episodes"] for s in e["segments"])
assert row["overlap"]["overlap_episodes"] == episodes, (row["overlap"], episodes)
b = campaign.load("ledger", SWEEP, "A2.20")
assert b["status"] == "finished" and len(b["segments"]) == 1
check_status([e, b], 0.0)
assert np.array_equal(campaign.read_rows("ledger", SWEEP, "A2.20"),
                      campaign.read_rows("ledger_ref", SWEEP, "A2.20"))
pt, pos = campaign.read_positions("ledger", SWEEP, "A1.40")
assert np.array_equal(pt, [0.0, 10.0, 20.0, 30.0, 40.0]), pt
assert np.max(np.abs(pos[-1] - last)) <= 5e-5 + 1e-12
assert [p[1] for p in campaign.plan("scenes", "results", "ledger", SWEEP)] == ["finished"] * 2

# Refusals: the old segment after its continuation (rewind), a gap; nothing changes.
kept = snapshot("ledger")
shutil.copytree("results_ref", "results_old")
old = "copies_old/sw/A1.40.h5"
os.makedirs("copies_old/sw")
shutil.copy("results_old/sw/A1.40.h5", old)
run(analyze, old, "--closures", str(CLOSURES), "--stride", "1")
refused(lambda: campaign.digest(old, "ledger", SWEEP, CLOSURES, 10.0, "results_old/sw/A1.40.h5"),
        "a segment must go on where it ends")
gap = "copies_old/sw/A1.40_from45.h5"     # the ledger ends at t = 40
shutil.copy(old, gap)
with h5py.File(gap, "r+") as h:
    h.attrs["case_name"] = "A1.40_from45"
refused(lambda: campaign.digest(gap, "ledger", SWEEP, CLOSURES, 10.0, gap),
        "a segment must go on where it ends")
assert snapshot("ledger") == kept
print(f"campaign ledger: A killed at t = {T:g}, continued to 40 from the stepper's state, {dev:.2e} d "
      f"from the uninterrupted chain (without the state: {dev_control:.2e} d)")
