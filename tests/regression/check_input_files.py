"""Fault test of the input readers (issue 37, causes F, G, H and the special files): each input
refused with one error line naming the file and the problem, or read exactly as its plain form.

F  malformed numbers in coordinate files ('0 0 1,5', '1.0 2.0 /', '7/8 0 3'): refused by
   knotflow-mobility, knotflow-analyze, knotflow (shape = 'file') and knotflow-kf, naming the
   file, the line and the item (they were read as z = 1, the previous bead's z, 7).
G  lines longer than 1024 characters: a bead after 1015 or 4000 blanks is read as written
   (it was cut: (1, 2, 1) for '1.0 2.0 12345', a bead lost): the mobility matrix equals that
   of the same file without the blanks, bead count included.
H  a small case file declaring frames (10^8, 59, 3): refused by knotflow-analyze and
   knotflow-kf before allocating (no crash, no traceback); knotflow-report reports the good
   case beside it and lists the bad one.
S  a FIFO or a device: coordinate_file = '/dev/zero', a FIFO as coordinate file, as scene and
   as the case file `case.h5` of a scene's output: refused by type, under a timeout (a FIFO
   hung knotflow, /dev/zero ate memory).

Usage: check_input_files.py KNOTFLOW KNOTFLOW_ANALYZE KNOTFLOW_MOBILITY PYTHON TOOLS_SRC WORKDIR
       [SECTIONS (default FGHSR: run only these parts)]
"""
import math
import os
import shutil
import subprocess
import sys
import time

import h5py
import numpy as np

knotflow, analyze, mobility, python, tools_src, work = sys.argv[1:7]
SECTIONS = sys.argv[7] if len(sys.argv) > 7 else "FGHSR"
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
env = dict(os.environ, PYTHONPATH=tools_src)
TIMEOUT = 60


def path(name):
    return os.path.join(work, name)


def write(name, text):
    with open(path(name), "w", encoding="utf-8") as fh:
        fh.write(text)
    return path(name)


def run(cmd, **kw):
    try:
        return subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT, env=env, **kw)
    except subprocess.TimeoutExpired:
        raise AssertionError(f"{cmd}: still running after {TIMEOUT} s (hung on its input)") from None


def refused(tool, cmd, fragments):
    """cmd exits non-zero with one error line holding every fragment, no traceback."""
    r = run(cmd)
    lines = r.stderr.strip().splitlines()
    assert r.returncode != 0, (tool, cmd, r.stdout, r.stderr)
    assert len(lines) == 1 and ": error: " in lines[0], (tool, cmd, r.stderr)
    for frag in fragments:
        assert frag in lines[0], (tool, frag, lines[0])
    assert "Traceback" not in r.stderr and "Backtrace" not in r.stderr, (tool, r.stderr)
    return lines[0]


def kf(*args):
    return [python, "-m", "knotflow_tools.cli", *args]


def scene(name, chain, directory):
    return write(name, f"&chain {chain} /\n&integrator t_end = 0.1 /\n"
                       f"&output directory = '{directory}', frame_interval = 0.1 /\n")


# ---- F: malformed numbers, each line 2 of a two-bead file
if "F" in SECTIONS:
    BASE = "0.0 0.0 0.0\n"
    for name, line, item in (("comma.xyz", "0 0 1,5", "'1,5'"), ("slash.xyz", "1.0 2.0 /", "'/'"),
                             ("fraction.xyz", "7/8 0 3", "'7/8'"), ("dexp.xyz", "0 0 1d0", "'1d0'"),
                             ("underscore.xyz", "0 0 1_0", "'1_0'")):
        p = write(name, BASE + line + "\n")
        refused("knotflow-mobility", [mobility, p, "--model", "rpy"], [p, "line 2", item])
        refused("knotflow-analyze", [analyze, p, "--closures", "10"], [p, "line 2", item])
        refused("knotflow-kf", kf(p, "--closures", "10"), [p + ":2:", item])
        sc = scene(name + ".nml", f"shape = 'file', coordinate_file = '{p}'", path("out_" + name))
        refused("knotflow", [knotflow, sc], [p, "line 2", item])
        assert not os.path.exists(path("out_" + name)), name
    print("F: 5 malformed numbers refused by knotflow-mobility, knotflow-analyze, knotflow-kf and "
          "knotflow, naming file, line and item")


# ---- G: long lines read whole
if "G" in SECTIONS:
    def mobility_of(p):
        r = run([mobility, p, "--model", "rpy"])
        assert r.returncode == 0, (p, r.stderr)
        return np.array([[float(x) for x in row.split()] for row in r.stdout.strip().splitlines()])


    chain = [(2.5 * i, 0.3 * math.sin(i), 0.0) for i in range(10)]
    rows = ["%r %r %r" % b for b in chain]
    plain = write("plain.xyz", "\n".join(rows) + "\n")
    blanks = write("blanks.xyz", "\n".join(rows[:9]) + "\n" + " " * 4000 + rows[9] + "\n")
    cut = write("cut.xyz", "0 0 0\n" + " " * 1015 + "1.0 2.0 12345\n")
    cut_plain = write("cut_plain.xyz", "0 0 0\n1.0 2.0 12345\n")
    tabs = write("tabs.xyz", "\n".join("\t" + r.replace(" ", "\t") + "\r" for r in rows) + "\n")
    bom = os.path.join(work, "bom.xyz")
    with open(bom, "wb") as fh:
        fh.write(b"\xef\xbb\xbf" + ("\n".join(rows) + "\n").encode())
    m_plain = mobility_of(plain)
    assert m_plain.shape == (30, 30), m_plain.shape
    for p in (blanks, tabs, bom):
        m = mobility_of(p)
        assert m.shape == m_plain.shape and np.array_equal(m, m_plain), p
    m_cut, m_cut_plain = mobility_of(cut), mobility_of(cut_plain)
    assert np.array_equal(m_cut, m_cut_plain), "a bead after 1015 blanks read differently"
    long_bad = write("long_bad.xyz", "0 0 0\n" + " " * 2000 + "1.0 2.0 3.0 4.0\n")
    refused("knotflow-mobility", [mobility, long_bad], [long_bad, "line 2", "fourth item '4.0'"])
    refused("knotflow-kf", kf(long_bad), [long_bad + ":2:", "fourth item '4.0'"])
    bad_tab = write("bad_tab.xyz", "0 0 0\n1\t2\tx\n")
    refused("knotflow-mobility", [mobility, bad_tab], ["line 2", "'x'"])
    print("G: beads after 1015 and 4000 blanks, tabs, carriage returns and a byte-order mark read as "
          "the plain file (same mobility matrix); a long line's fourth item refused")

# ---- H: a small file declaring (10^8, 59, 3) frames
if "H" in SECTIONS:
    huge = path("huge.h5")
    with h5py.File(huge, "w") as f:
        f.attrs["status"] = "finished"
        t = f.create_dataset("frames/time", shape=(10**8,), maxshape=(None,), chunks=(4,), dtype="f8")
        t[:4] = np.arange(4) * 0.5
        r = f.create_dataset("frames/positions", shape=(10**8, 59, 3), maxshape=(None, 59, 3),
                             chunks=(1, 59, 3), dtype="f8")
        for k in range(4):
            r[k] = np.array([(math.cos(i), math.sin(i), 0.1 * i) for i in range(59)])
    size = os.path.getsize(huge)
    assert size < 200_000, size
    refused("knotflow-analyze", [analyze, huge, "--closures", "10"], [huge, "declares shape (100000000"])
    refused("knotflow-kf", kf(huge, "--closures", "10"), [huge, "declares shape (100000000"])
    sweep = path("report_sweep")
    os.makedirs(sweep)
    shutil.copy(huge, os.path.join(sweep, "huge.h5"))
    good_scene = scene("good.nml", "shape = 'straight', n_beads = 8", sweep)
    r = run([knotflow, good_scene])
    assert r.returncode == 0, r.stderr
    r = run([python, "-c", "import sys; from knotflow_tools.cli import main_report; "
             "sys.exit(main_report(sys.argv[1:]))", sweep, "--closures", "10", "--no-movie",
             "--no-viewer"])
    assert r.returncode == 0, r.stderr
    with open(os.path.join(sweep, "report", "report.md"), encoding="utf-8") as fh:
        md = fh.read()
    assert "huge.h5" in md and "declares shape" in md, md
    good = [n for n in os.listdir(sweep) if n.endswith(".h5") and n != "huge.h5"]
    assert len(good) == 1 and good[0][:-3] in md, (good, md)
    print(f"H: a {size}-byte file declaring (10^8, 59, 3) frames refused by knotflow-analyze and "
          "knotflow-kf; knotflow-report reports the good case and lists the bad one")

# ---- S: special files
if "S" in SECTIONS:
    fifo = path("fifo.xyz")
    os.mkfifo(fifo)
    refused("knotflow-mobility", [mobility, fifo], [fifo, "FIFO"])
    refused("knotflow-kf", kf(fifo), [fifo, "FIFO"])
    sc = scene("devzero.nml", "shape = 'file', coordinate_file = '/dev/zero'", path("out_devzero"))
    refused("knotflow", [knotflow, sc], ["/dev/zero", "character device"])
    sc = scene("fifo_coords.nml", f"shape = 'file', coordinate_file = '{fifo}'", path("out_fifo"))
    refused("knotflow", [knotflow, sc], [fifo, "FIFO"])
    fifo_scene = path("fifo.nml")
    os.mkfifo(fifo_scene)
    refused("knotflow", [knotflow, fifo_scene], [fifo_scene, "FIFO"])
    out = path("out_case_fifo")
    os.makedirs(out)
    sc = write("case_fifo.nml", "&chain shape = 'straight', n_beads = 8 /\n&integrator t_end = 0.1 /\n"
                                f"&output directory = '{out}', frame_interval = 0.1 /\n")
    # the case file's name: run once elsewhere, then plant a FIFO under that name
    probe = path("out_probe")
    r = run([knotflow, write("probe.nml", open(sc).read().replace(out, probe))])
    assert r.returncode == 0, r.stderr
    case_name = [n for n in os.listdir(probe) if n.endswith(".h5")][0]
    os.mkfifo(os.path.join(out, case_name))
    refused("knotflow", [knotflow, sc], [case_name, "FIFO"])
    print("S: /dev/zero and FIFOs (coordinate file, scene, case file) refused by type, none hung")

# ---- R: a resume checks the frames it keeps before it continues
if "R" in SECTIONS:
    out = path("out_resume")
    sc = write("resume.nml", "&chain shape = 'straight', n_beads = 8 /\n&hydro model = 'none' /\n"
                             "&integrator t_end = 300.0 /\n"
                             f"&output directory = '{out}', case_name = 'r', frame_interval = 1.0 /\n")
    proc = subprocess.Popen([knotflow, sc], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    case_file = os.path.join(out, "r.h5")
    deadline = TIMEOUT
    while deadline > 0:
        time.sleep(0.5)
        deadline -= 0.5
        try:
            with h5py.File(case_file, "r", locking=False) as f:
                if f["frames/time"].shape[0] >= 5:
                    break
        except (OSError, KeyError):
            pass
    proc.kill()
    proc.wait()
    with h5py.File(case_file, "r+") as f:
        status = f.attrs["status"]
        assert (status.decode() if isinstance(status, bytes) else str(status)).strip() == "running"
        f["frames/positions"][1, 3, 0] = np.nan
    r = run([knotflow, sc])
    assert "r.h5 is damaged (a frame it keeps is bad" in r.stdout and "frame 1" in r.stdout, r.stdout
    assert "resuming" not in r.stdout, r.stdout
    print("R: a resume whose kept frame 1 holds a NaN is refused before it continues "
          "(moved aside and computed again)")
