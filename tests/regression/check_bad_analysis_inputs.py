"""A corpus of bad analysis inputs: each refused cleanly by knotflow-analyze and by the Python
knot tool (knotflow-kf), never a crash, a traceback or a number computed from bad data.

For every input: a non-zero exit status (knotflow-kf: 2), exactly one line on stderr that
names the file and contains the expected fragment (the problem), nothing on stdout from
knotflow-analyze, and an HDF5 input left byte for byte as it was (no /analysis written).
Two unfinished case files are accepted instead, analysed up to the frames their newest
checkpoint counts (never a frame that was being written): the count is checked.

Usage: check_bad_analysis_inputs.py KNOTFLOW_ANALYZE PYTHON TOOLS_SRC WORKDIR
"""
import hashlib
import math
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

analyze, python, tools_src, work = sys.argv[1:5]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
env = dict(os.environ, PYTHONPATH=tools_src)


def trefoil(n=59, k=0):
    """An open torus trefoil of n beads, turned by 0.3 k about z."""
    c, s = math.cos(0.3 * k), math.sin(0.3 * k)
    out = []
    for i in range(n):
        t = 2 * math.pi * (i + 1) / 60
        x, y, z = (2 + math.cos(3 * t)) * math.cos(2 * t), (2 + math.cos(3 * t)) * math.sin(2 * t), math.sin(3 * t)
        out.append((c * x - s * y, s * x + c * y, z))
    return np.array(out)


POS = np.stack([trefoil(k=k) for k in range(4)])
TIME = np.arange(4) * 0.5


def path(name):
    return os.path.join(work, name)


def case(name, time=TIME, positions=POS, status="finished", extra=None):
    with h5py.File(path(name), "w") as f:
        f.attrs["status"] = status
        if time is not None:
            f.create_dataset("frames/time", data=time, maxshape=(None,), chunks=True)
        if positions is not None:
            f.create_dataset("frames/positions", data=positions,
                             maxshape=(None,) + positions.shape[1:], chunks=True)
        if extra:
            extra(f)


def text(name, rows):
    with open(path(name), "w") as f:
        f.write("".join(rows))


def xyz_rows(r):
    return ["%r %r %r\n" % tuple(map(float, p)) for p in r]


def with_nan(p, k, i, c):
    p = p.copy()
    p[k, i, c] = np.nan
    return p


def time_with(k, value):
    t = TIME.copy()
    t[k] = value
    return t


def damaged_chunk(f):
    del f["frames/positions"]
    f.create_dataset("frames/positions", data=POS, maxshape=(None, 59, 3), chunks=(2, 59, 3),
                     fletcher32=True)


def lzf_positions(f):
    del f["frames/positions"]
    f.create_dataset("frames/positions", data=POS, maxshape=(None, 59, 3), chunks=(2, 59, 3),
                     compression="lzf")


def huge_declared(f):
    """frames/positions declared (10^8, 59, 3) with 4 frames written: a small file."""
    del f["frames/positions"]
    ds = f.create_dataset("frames/positions", shape=(10**8, 59, 3), maxshape=(None, 59, 3),
                          chunks=(1, 59, 3), dtype="f8")
    ds[:4] = POS


# (file, how to make it, fragment of knotflow-analyze's message, fragment of knotflow-kf's)
CORPUS = [
    ("missing.h5", None, "does not exist", "no such file"),
    ("empty.h5", lambda: text("empty.h5", []), "an empty file, not HDF5", "an empty file, not HDF5"),
    ("words.h5", lambda: text("words.h5", ["this is not HDF5\n"] * 50), "not an HDF5 file", "not an HDF5 file"),
    ("directory.h5", lambda: os.mkdir(path("directory.h5")), "is a directory", "it is a directory"),
    ("truncated.h5", None, "truncated or damaged", "truncated or damaged"),
    ("no_frames.h5", lambda: h5py.File(path("no_frames.h5"), "w").close(), "no /frames group", "no /frames group"),
    ("frames_dataset.h5", None, "'/frames/time' not found", "no /frames group"),
    ("no_positions.h5", lambda: case("no_positions.h5", positions=None), "'/frames/positions' not found",
     "no dataset /frames/positions"),
    ("no_time.h5", lambda: case("no_time.h5", time=None), "'/frames/time' not found", "no dataset /frames/time"),
    ("positions_group.h5", lambda: case("positions_group.h5", positions=None,
                                        extra=lambda f: f.create_group("frames/positions")),
     "cannot open dataset '/frames/positions'", "no dataset /frames/positions"),
    ("positions_rank2.h5", lambda: case("positions_rank2.h5", positions=POS[:, :, 0]), "has rank 2, expected 3",
     "/frames/positions has 2 dimensions, expected 3"),
    ("two_columns.h5", lambda: case("two_columns.h5", positions=POS[:, :, :2]),
     "/frames/positions has shape (4, 59, 2), expected (frames, beads, 3)",
     "/frames/positions has shape (4, 59, 2), expected (frames, beads, 3)"),
    ("one_bead.h5", lambda: case("one_bead.h5", positions=POS[:, :1]), "holds 1 bead(s) per frame",
     "holds 1 bead(s) per frame"),
    ("string_positions.h5", lambda: case("string_positions.h5", positions=None, extra=lambda f: f.create_dataset(
        "frames/positions", data=np.full((4, 59, 3), b"x"))), "holds strings, not numbers", "not numbers"),
    ("short_time.h5", lambda: case("short_time.h5", time=TIME[:3]), "different lengths (3 and 4 frames)",
     "different lengths (3 and 4 frames)"),
    ("no_frame.h5", lambda: case("no_frame.h5", time=TIME[:0], positions=POS[:0]), "no complete frame",
     "no complete frame"),
    ("nan.h5", lambda: case("nan.h5", positions=with_nan(POS, 2, 5, 1)),
     "frame 2 (t = 1.00000) holds 1 non-finite coordinates", "frame 2 (t = 1): 1 non-finite coordinates"),
    ("inf_time.h5", lambda: case("inf_time.h5", time=time_with(3, np.inf)), "a non-finite time",
     "a non-finite time"),
    ("repeated_time.h5", lambda: case("repeated_time.h5", time=time_with(2, 0.5)),
     "frame 2 (t = 0.500000) is not after frame 1", "frame 2 (t = 0.5) is not after frame 1"),
    ("damaged_chunk.h5", None, "checksum mismatch", "checksum mismatch"),
    ("two_columns.xyz", lambda: text("two_columns.xyz", ["%r %r\n" % (float(p[0]), float(p[1])) for p in POS[0]]),
     "line 1: expected three numbers", ":1: expected 3 numbers, got 2"),
    ("word.xyz", lambda: text("word.xyz", xyz_rows(POS[0][:7]) + ["1.0 abc 2.0\n"] + xyz_rows(POS[0][8:])),
     "line 8: item 2 'abc' is not a number", ":8: not a number: item 2 'abc'"),
    ("nan.xyz", lambda: text("nan.xyz", xyz_rows(POS[0][:3]) + ["1.0 nan 2.0\n"] + xyz_rows(POS[0][4:])),
     "line 4: item 2 'nan' is not a number", ":4: not a number: item 2 'nan'"),
    ("inf.xyz", lambda: text("inf.xyz", xyz_rows(POS[0][:3]) + ["1.0 2.0 1e999\n"] + xyz_rows(POS[0][4:])),
     "line 4: item 3 '1e999' is not a number", ":4: non-finite coordinate"),
    ("comma.xyz", lambda: text("comma.xyz", xyz_rows(POS[0][:5]) + ["0 0 1,5\n"] + xyz_rows(POS[0][6:])),
     "line 6: item 3 '1,5' is not a number", ":6: not a number: item 3 '1,5'"),
    ("four.xyz", lambda: text("four.xyz", xyz_rows(POS[0][:2]) + [" " * 3000 + "1 2 3 4\n"]),
     "line 3: expected three numbers 'x y z', found a fourth item '4'", ":3: expected 3 numbers, found a fourth"),
    ("control.xyz", lambda: text("control.xyz", xyz_rows(POS[0][:2]) + ["1 2 3\x0b\n"]),
     "item 3 '3<0x0B>' is not a number", "item 3 '3<0x0B>'"),
    ("huge_declared.h5", lambda: case("huge_declared.h5", extra=huge_declared),
     "declares shape (100000000, 59, 3)", "declares shape (100000000, 59, 3)"),
    ("fifo.h5", lambda: os.mkfifo(path("fifo.h5")), "is a FIFO (named pipe)", "is a FIFO (named pipe)"),
    # issue 37: a filter this HDF5 library lacks, and a file another process holds open for
    # writing, were called "truncated or damaged"
    ("missing_filter.h5", None, "it needs the HDF5 filter 'lzf' (id 32008), which this HDF5 library does not have",
     "it needs the HDF5 filter 'lzf' (id 32008), which this HDF5 library does not have"),
    ("being_written.h5", lambda: case("being_written.h5"),
     "it is open in another process, which holds its HDF5 file lock",
     "it is open for writing in another process, which holds its HDF5 file lock"),
    ("comments_only.xyz", lambda: text("comments_only.xyz", ["# nothing\n", "\n"]), "contains no points",
     "no coordinates"),
    # knotflow-kf calls the library's knot code (knotflow.knots): the same message, with the file
    ("one_bead.xyz", lambda: text("one_bead.xyz", ["1 2 3\n"]), "the chain has 1 bead(s), at least 2",
     "the chain has 1 bead(s), at least 2"),
]


def make_special():
    case("truncated.h5")
    os.truncate(path("truncated.h5"), os.path.getsize(path("truncated.h5")) * 6 // 10)
    with h5py.File(path("frames_dataset.h5"), "w") as f:
        f["frames"] = np.zeros(3)
    case("damaged_chunk.h5", extra=damaged_chunk)
    with h5py.File(path("damaged_chunk.h5"), "r") as f:
        info = f["frames/positions"].id.get_chunk_info(1)
    with open(path("damaged_chunk.h5"), "r+b") as fh:
        fh.seek(info.byte_offset + 100)
        fh.write(b"\x7f" * 8)
    # LZF (id 32000) turned into id 32008 (bitshuffle), which neither h5py nor the library has
    case("missing_filter.h5", extra=lzf_positions)
    with open(path("missing_filter.h5"), "r+b") as fh:
        data = bytearray(fh.read())
        k = data.find(b"lzf\0")
        assert data[k - 8:k - 6] == b"\x00\x7d", data[k - 12:k + 4]
        fh.seek(k - 8)
        fh.write(b"\x08\x7d")


def digest(p):
    if not os.path.isfile(p):
        return None
    with open(p, "rb") as fh:
        return hashlib.sha256(fh.read()).hexdigest()


make_special()
for name, make, _, _ in CORPUS:
    if make:
        make()
# another process holds being_written.h5 open for writing (HDF5's exclusive lock) meanwhile
holder = subprocess.Popen([python, "-c", "import h5py, sys; f = h5py.File(sys.argv[1], 'r+'); "
                           "print('open', flush=True); sys.stdin.read()", path("being_written.h5")],
                          stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
assert holder.stdout.readline().strip() == "open"

checked = 0
for name, _, frag_analyze, frag_kf in CORPUS:
    p = path(name)
    before = digest(p)
    for tool, cmd, frag in (("knotflow-analyze", [analyze, p, "--closures", "10"], frag_analyze),
                            ("knotflow-kf", [python, "-m", "knotflow_tools.cli", p, "--closures", "10"], frag_kf)):
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=env)
        lines = r.stderr.strip().splitlines()
        assert r.returncode != 0, (tool, name, r.stdout, r.stderr)
        if tool == "knotflow-kf":
            assert r.returncode == 2, (tool, name, r.returncode, r.stderr)
        else:
            assert r.stdout == "", (tool, name, r.stdout)
        assert len(lines) == 1, (tool, name, r.stderr)
        assert lines[0].startswith(tool + ": error: "), (tool, name, lines[0])
        # knotflow-analyze's coordinate mode passes the chain, not its file, to the knot
        # analysis, so that one message cannot name the file
        named = not (tool == "knotflow-analyze" and name == "one_bead.xyz")
        assert (name in lines[0] or not named) and frag in lines[0], (tool, name, frag, lines[0])
        assert "Traceback" not in r.stderr and "Backtrace" not in r.stderr, (tool, name, r.stderr)
        assert digest(p) == before, (tool, name, "the input was changed")
        checked += 1
holder.stdin.close()
holder.wait(timeout=60)
print("%d bad analysis inputs, each refused by both tools (%d runs): one error line naming "
      "the file and the problem, non-zero exit status, the input untouched" % (len(CORPUS), checked))

# unfinished cases: analysed up to the frames the newest checkpoint counts
for name, slots in (("running_slots.h5", True), ("running_legacy.h5", False)):
    p = path(name)
    case(name, time=np.arange(5) * 0.5, positions=np.stack([trefoil(k=k) for k in range(5)]), status="running")
    with h5py.File(p, "a") as f:       # killed while frame 4 was written: the checkpoints count 4
        if slots:
            f.attrs["schema_version"] = np.int32(3)
            f["checkpoint/slot0/nframes"] = np.int64(4)
            f["checkpoint/slot1/nframes"] = np.int64(3)
        else:
            f["checkpoint/nframes"] = np.int64(4)
    r = subprocess.run([analyze, p, "--closures", "10"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and "4 frames (4 new)" in r.stdout, (name, r.stdout, r.stderr)
    with h5py.File(p, "r") as f:
        assert len(f["analysis/knots/kf"]) == 4, name
    r = subprocess.run([python, "-c", "from knotflow_tools import io; print(io.read_case(%r).nframes)" % p],
                       capture_output=True, text=True, timeout=120, env=env)
    assert r.returncode == 0 and r.stdout.strip() == "4", (name, r.stdout, r.stderr)
print("unfinished cases (checkpoint slots, older single checkpoint): 4 of 5 frames analysed by both")
