"""Write failures and damaged case files.

1. A write that fails in the middle of a run (the file size limit, `ulimit -f`, stands for a
   full disk): the case fails with the operating system's reason ('File too large'), exit
   status 3, FAILED in the summary, and the file is not marked finished. Run again without the
   limit, the case resumes from its last complete checkpoint and finishes: every frame once,
   the frames before the failure exactly those of an uninterrupted run, the rest equal to it to
   integration tolerance.
2. Damaged files are moved aside (renamed '<file>.damaged', never deleted) with a message and
   the case computed again, to the uninterrupted run's frames: damage inside the positions
   (caught by the Fletcher-32 checksums), a finished file whose frames do not match its
   checkpoint (what a full disk used to leave), a truncated file, a file that is not HDF5.
3. New case files have the Fletcher-32 filter on their chunked datasets; no temporary summary
   file is left behind.
Usage: check_write_integrity.py KNOTFLOW WORKDIR
"""
import os
import resource
import shutil
import signal
import subprocess
import sys

import h5py
import numpy as np

exe, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
T_END = 60.0
# Singleton MPI start-up keeps its PMIx store in files: the hash store needs none, so the file
# size limit only meets the case file.
ENV = dict(os.environ, PMIX_MCA_gds="hash")


def scene(name):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write("""&chain shape = 'trefoil', orientation = 'c' /
&integrator t_end = %g /
&output directory = '%s', case_name = 'c', frame_interval = 1.0, progress_interval = 1000.0 /
""" % (T_END, os.path.join(work, name)))
    return path


def run(path, file_limit=None):
    def limit():
        if file_limit is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (file_limit, file_limit))
    return subprocess.run([exe, path], capture_output=True, text=True, timeout=300, env=ENV,
                          preexec_fn=limit)


def case_file(name):
    return os.path.join(work, name, "c.h5")


def frames(name):
    with h5py.File(case_file(name), "r") as h:
        status = h.attrs["status"]
        status = status.decode() if isinstance(status, bytes) else status
        return status, h["frames/time"][:], h["frames/positions"][:]


def finished_like_reference(name, exact_before=None):
    status, t, r = frames(name)
    assert status == "finished", status
    assert np.array_equal(t, t_ref), (t, t_ref)
    if exact_before is not None:
        k = int(exact_before) + 1
        assert np.array_equal(r[:k], r_ref[:k]), "frames before the failure differ"
    dev = np.abs(r - r_ref).max()
    assert dev < 1e-6, dev
    return dev


ref = scene("reference")
out = run(ref)
assert out.returncode == 0, (out.stdout, out.stderr)
_, t_ref, r_ref = frames("reference")
size = os.path.getsize(case_file("reference"))
with h5py.File(case_file("reference"), "r") as h:
    for name in ("frames/positions", "frames/time", "frames/observables/rg", "frames/integrator/steps"):
        assert h[name].fletcher32, name + " has no checksum filter"
assert not [f for f in os.listdir(os.path.join(work, "reference")) if f.endswith(".tmp")]
checks = 2

# 1. a write fails half-way: reported with the OS reason, not finished; the rerun resumes
limited = scene("limited")
out = run(limited, file_limit=size * 3 // 4)   # past frame 0, which alone takes about half
text = out.stdout + out.stderr
assert out.returncode == 3, (out.returncode, text)
assert "Segmentation" not in text and "Backtrace" not in text, text
assert "File too large" in text, text
assert "write failed: " in text and "not marked finished" in text, text
assert "resumes it from its last complete checkpoint (t = " in text, text
summary = open(os.path.join(work, "limited", "summary.txt")).read()
assert "FAILED" in summary and "File too large" in summary, summary
try:
    status, t, _ = frames("limited")
    assert status != "finished", status
except OSError:
    pass        # cut short: HDF5 cannot open it as it is; the rerun extends it
t_fail = float(text.split("last complete checkpoint (t = ")[1].split(")")[0])
assert 0.0 < t_fail < T_END, t_fail
out = run(limited)
assert out.returncode == 0, (out.stdout, out.stderr)
assert "resuming at t = " in out.stdout, out.stdout
t_resumed = float(out.stdout.split("resuming at t = ")[1].split()[0])
assert t_resumed == t_fail, (t_resumed, t_fail)
dev = finished_like_reference("limited", exact_before=t_fail)
print("write failure at t = %g ('File too large'), resumed and finished, max deviation %.1e" % (t_fail, dev))
checks += 4


def damaged(name, spoil, fragment):
    os.makedirs(os.path.join(work, name))
    shutil.copy(case_file("reference"), case_file(name))
    spoil(case_file(name))
    out = run(scene(name))
    assert out.returncode == 0, (name, out.stdout, out.stderr)
    assert "is damaged (" in out.stdout and "moved to " + case_file(name) + ".damaged" in out.stdout, out.stdout
    assert fragment in out.stdout, (fragment, out.stdout)
    assert os.path.exists(case_file(name) + ".damaged"), name
    finished_like_reference(name)


def flip_positions(path):
    with h5py.File(path, "r") as h:
        info = h["frames/positions"].id.get_chunk_info(1)
    with open(path, "r+b") as f:
        f.seek(info.byte_offset + info.size // 2)
        b = bytearray(f.read(16))
        f.seek(info.byte_offset + info.size // 2)
        f.write(bytes(x ^ 0x5A for x in b))


def zero_frames(path):
    with h5py.File(path, "a") as h:
        h["frames/positions"][...] = 0.0


def truncate(path):
    os.truncate(path, os.path.getsize(path) * 6 // 10)


def garbage(path):
    with open(path, "wb") as f:
        f.write(b"this is not an HDF5 file\n" * 100)


damaged("flipped", flip_positions, "checksum mismatch")
damaged("zeros", zero_frames, "is not its last frame")
damaged("truncated", truncate, "")
damaged("garbage", garbage, "not an HDF5 file")
checks += 4
print("write integrity: %d checks passed (Fletcher-32 on, write failure reported and resumed, "
      "damaged data, zeroed frames, truncated and non-HDF5 files moved aside and recomputed)" % checks)
