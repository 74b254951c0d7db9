"""Writers that cannot be redirected, emptied or made to lose a run (issue 37, causes A, C, D, E).

A  Symbolic links planted where knotflow writes: `out/summary.txt` and `out/summary.txt.tmp`
   pointing to a victim file (a 2-case sweep into `out`), `D/<case>.nml` and `D/<case>.nml.tmp`
   (--write-scenes D), a link at the write probe's name `.knotflow_write_probe`: every victim
   keeps its content and the files written are regular files; a dangling link at a case file's
   name fails that case (exit 3, naming the link), nothing is created where it points. A dangling link at the lock
   file `.knotflow.lock` is refused (exit 2) and creates nothing.
E  A full disk (a 200 kB tmpfs filled up when run as root, else a file size limit of 100 bytes,
   `ulimit -f`): a rerun of a finished sweep exits 3 naming summary.txt and the operating
   system's reason, and leaves summary.txt and summary.json exactly as they were; --write-scenes
   exits 2 naming the scene file, and the old scene files are unchanged.
C  An interrupted case whose file another process holds open (h5py, read-only and read-write:
   HDF5's file lock), and (as root, run as the user nobody) a file of mode 0444: the case fails
   (exit 3) saying why, the file is not changed, not moved aside, and the case is not computed
   again; with the file free, a rerun resumes it from its checkpoint.
D  knotflow-analyze killed (SIGKILL through strace) at every write of an analysis: every rerun
   (with and without --force, alternately) exits 0 with /analysis equal to the uninterrupted
   analysis, and between the kill and the rerun the case file is the one before (untouched) or
   the analysed one, whole.
S  SIGTERM and SIGINT (a scheduler's time limit, Ctrl-C) during a 2-case sweep: knotflow stops
   each running case after its current frame, marks the others not started, prints a closing
   line saying so and exits with status 75 (resubmit); the same command then resumes and ends
   with every frame equal, bit for bit, to an uninterrupted run. Two signals in a row end it at
   once, with status 75 too, and the rerun still ends equal.
R  knotflow-analyze on a file whose frame 2 was rewritten after its analysis (a straight chain
   in place of a knotted one): the stored k_f of that frame is not reused but computed again
   (a line says so), equal to an analysis from scratch (--force); the other frames are reused.
Usage: check_writers.py KNOTFLOW KNOTFLOW_ANALYZE WORKDIR [PARTS]   (PARTS: e.g. 'CD'; default ACDERS)
"""
import hashlib
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile

import h5py
import numpy as np

exe, analyze, work = (os.path.abspath(a) if os.sep in a else a for a in sys.argv[1:4])
parts = sys.argv[4] if len(sys.argv) > 4 else "ACDERS"
if os.path.ismount(os.path.join(work, "full")):
    subprocess.run(["umount", os.path.join(work, "full")], check=False)
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
ENV = dict(os.environ, PMIX_MCA_gds="hash", OPENBLAS_NUM_THREADS="1")


def path(*parts):
    return os.path.join(work, *parts)


def write(name, text):
    with open(path(name), "w") as f:
        f.write(text)
    return path(name)


def run(args, limit=None, user=None, timeout=300):
    def preexec():
        if limit is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    cmd = list(args)
    if user is not None:
        cmd = ["setpriv", "--reuid=%d" % user, "--regid=%d" % user, "--clear-groups"] + cmd
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=ENV, cwd=work,
                          preexec_fn=preexec)


def content(p):
    with open(p, "rb") as f:
        return f.read()


def md5(p):
    return hashlib.md5(content(p)).hexdigest()


def sweep(name, directory):
    return write(name, """&chain shape = 'straight', n_beads = 8 /
&integrator t_end = 1.0 /
&output directory = '%s', frame_interval = 0.5 /
&sweep bending_a = 1.0, 2.0 /
""" % directory)


# ---- A: planted links
victim = write("victim.txt", "VICTIM\n")


def part_a():
    os.makedirs(path("out"))
    os.symlink("../victim.txt", path("out", "summary.txt"))
    os.symlink("../victim.txt", path("out", "summary.txt.tmp"))
    os.symlink("../victim.txt", path("out", ".knotflow_write_probe"))
    os.symlink("../created_by_link.h5", path("out", "A1.00.h5"))   # dangling
    sc = sweep("a.nml", path("out"))
    r = run([exe, sc])
    # the case whose file is a link fails, naming it; the other runs; the summary is written
    assert r.returncode == 3, (r.returncode, r.stdout, r.stderr)
    assert "FAILED A1.00: case file %s not used: it is a symbolic link" % path("out", "A1.00.h5") in r.stdout, r.stdout
    assert content(victim) == b"VICTIM\n", content(victim)
    assert not os.path.exists(path("created_by_link.h5")), "a case file was created through a link"
    assert os.path.islink(path("out", "A1.00.h5")), "the link was changed"
    for name in ("summary.txt", "summary.json", "A2.00.h5"):
        assert not os.path.islink(path("out", name)) and os.path.isfile(path("out", name)), name
    assert b"A2.00" in content(path("out", "summary.txt"))
    os.remove(path("out", "A1.00.h5"))
    os.makedirs(path("scenes"))
    for name in ("A1.00.nml", "A1.00.nml.tmp", "A2.00.nml"):
        os.symlink("../victim.txt", path("scenes", name))
    r = run([exe, sc, "--write-scenes", path("scenes")])
    assert r.returncode == 0, (r.returncode, r.stdout, r.stderr)
    assert content(victim) == b"VICTIM\n", content(victim)
    for name in ("A1.00.nml", "A2.00.nml"):
        assert not os.path.islink(path("scenes", name)), name
        assert content(path("scenes", name)).startswith(b"! case " + name[:-4].encode()), name
    leftovers = [n for n in os.listdir(path("out")) + os.listdir(path("scenes")) if n.endswith(".tmp")
                 and not os.path.islink(path("out", n)) and not os.path.islink(path("scenes", n))]
    assert leftovers == [], leftovers
    # a dangling link at the directory's lock file: refused, nothing created where it points
    os.makedirs(path("out_lock"))
    os.symlink("../created_by_lock_link", path("out_lock", ".knotflow.lock"))
    r = run([exe, sweep("lock.nml", path("out_lock"))])
    assert r.returncode == 2 and "cannot create the lock file" in r.stderr, (r.returncode, r.stderr)
    assert not os.path.exists(path("created_by_lock_link")), "a lock file was created through a link"
    print("A: links at summary.txt(.tmp), the write probe, a case file and written scenes: replaced, "
          "never written through; a dangling link at the lock file refused")


# ---- E: a full disk
def part_e():
    full = path("full")
    os.makedirs(full)
    mounted = os.geteuid() == 0 and subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=200k", "tmpfs", full], capture_output=True).returncode == 0
    try:
        sc = sweep("e.nml", os.path.join(full, "out"))
        r = run([exe, sc])
        assert r.returncode == 0, (r.returncode, r.stdout, r.stderr)
        r = run([exe, sc, "--write-scenes", os.path.join(full, "scenes")])
        assert r.returncode == 0, (r.returncode, r.stdout, r.stderr)
        for name in ("A1.00.nml", "A2.00.nml"):   # old scene files, to be kept as they are
            with open(os.path.join(full, "scenes", name), "a") as f:
                f.write("! an older copy\n")
        kept = {p: content(p) for p in [os.path.join(full, "out", "summary.txt"),
                                        os.path.join(full, "out", "summary.json"),
                                        os.path.join(full, "scenes", "A1.00.nml"),
                                        os.path.join(full, "scenes", "A2.00.nml")]}
        if mounted:
            fd = os.open(os.path.join(full, "filler"), os.O_WRONLY | os.O_CREAT)
            try:
                while True:
                    os.write(fd, b"\0" * 1024)
            except OSError:
                pass
            os.close(fd)
            limit, reason, how = None, "No space left on device", "a full 200 kB tmpfs"
        else:
            limit, reason, how = 100, "File too large", "a file size limit of 100 bytes (not root: no tmpfs)"
        r = run([exe, sc], limit=limit)
        assert r.returncode == 3, (r.returncode, r.stdout, r.stderr)
        assert "cannot write '%s/out/summary.txt': %s" % (full, reason) in r.stderr, r.stderr
        assert "summary in" not in r.stdout, r.stdout
        r = run([exe, sc, "--write-scenes", os.path.join(full, "scenes")], limit=limit)
        assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
        assert "cannot write '%s/scenes/A1.00.nml': %s" % (full, reason) in r.stderr, r.stderr
        for p, data in kept.items():
            assert content(p) == data, (p, "changed on a full disk")
        tmp = [n for d in ("out", "scenes") for n in os.listdir(os.path.join(full, d)) if ".tmp" in n]
        assert tmp == [], tmp
        print("E: %s: the summary and --write-scenes fail naming the file and '%s'; the old files "
              "unchanged, no temporary file left" % (how, reason))
    finally:
        if mounted:
            subprocess.run(["umount", full], check=False)


# ---- C: a case file in use by another process, or not writable
case_dir = path("busy")
scene_c = write("c.nml", """&chain shape = 'trefoil', orientation = 'c' /
&integrator t_end = 40.0 /
&output directory = '%s', case_name = 'c', frame_interval = 1.0, progress_interval = 0.0 /
""" % case_dir)
case_file = os.path.join(case_dir, "c.h5")


def interrupted():
    """Start the case and kill it after its third frame: an interrupted case with a checkpoint."""
    shutil.rmtree(case_dir, ignore_errors=True)
    p = subprocess.Popen([exe, scene_c], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                         env=ENV)
    n = 0
    for line in p.stdout:
        if ": t = " in line:
            n += 1
            if n == 3:
                p.send_signal(signal.SIGKILL)
                break
    p.wait()
    with h5py.File(case_file, "r") as h:
        status = h.attrs["status"]
    assert (status.decode() if isinstance(status, bytes) else status) == "running", status


def not_touched(r, words, file=None, directory=None):
    file, directory = file or case_file, directory or case_dir
    assert r.returncode == 3, (r.returncode, r.stdout, r.stderr)
    assert "FAILED c: case file %s not used: %s" % (file, words) in r.stdout, r.stdout
    assert "nothing was changed" in r.stdout, r.stdout
    assert "damaged" not in r.stdout and "computing the case again" not in r.stdout, r.stdout
    assert sorted(n for n in os.listdir(directory) if n.startswith("c.h5")) == ["c.h5"], os.listdir(directory)


def part_c():
    for mode in ("r", "r+"):
        interrupted()
        holder = h5py.File(case_file, mode)
        try:
            before = md5(case_file)
            r = run([exe, scene_c])
            not_touched(r, "it is open in another process, which holds its HDF5 file lock")
            assert md5(case_file) == before, "the case file changed"
        finally:
            holder.close()
        r = run([exe, scene_c])
        assert r.returncode == 0, (r.returncode, r.stdout, r.stderr)
        assert "resuming at t = " in r.stdout, r.stdout
    print("C: a case file open in h5py (read-only and read-write): the case fails saying so, the file "
          "unchanged and kept; closed, the rerun resumes it")
    if os.geteuid() == 0 and shutil.which("setpriv"):
        interrupted()
        nobody = 65534
        # nobody must reach the program, the scene and the case directory, and the build tree may
        # sit where nobody cannot (/root is 0700 on a fresh Debian): copies of the three in a
        # directory every user can enter
        shared = tempfile.mkdtemp(prefix="kf-writers-nobody-")
        try:
            os.chmod(shared, 0o755)
            exe_n = os.path.join(shared, "knotflow")
            shutil.copy2(exe, exe_n)
            dir_n = os.path.join(shared, "busy")
            shutil.copytree(case_dir, dir_n)
            with open(scene_c) as f:
                text = f.read().replace("'%s'" % case_dir, "'%s'" % dir_n)
            scene_n = os.path.join(shared, "c.nml")
            with open(scene_n, "w") as f:
                f.write(text)
            for root, dirs, files in os.walk(dir_n):
                for n in dirs + files + [""]:
                    os.chown(os.path.join(root, n), nobody, nobody)
            case_n = os.path.join(dir_n, "c.h5")
            os.chmod(case_n, 0o444)
            before = md5(case_n)
            r = run([exe_n, scene_n], user=nobody)
            not_touched(r, "it cannot be written (Permission denied)", case_n, dir_n)
            assert md5(case_n) == before, "the case file changed"
            # a scene nobody cannot reach is refused with the system's reason, not "not found"
            hidden = os.path.join(shared, "hidden")
            os.mkdir(hidden, 0o700)
            scene_h = os.path.join(hidden, "c.nml")
            shutil.copy(scene_n, scene_h)
            r = run([exe_n, scene_h], user=nobody)
            assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
            assert "%s: cannot be opened: " % scene_h in r.stderr and "Permission denied" in r.stderr, r.stderr
        finally:
            shutil.rmtree(shared, ignore_errors=True)
        print("C: a case file of mode 0444 (run as nobody): the case fails saying so, the file kept; a scene "
              "it cannot reach: refused with the reason")
    else:
        print("C: the read-only file is checked only as root (run as the user nobody): skipped")


# ---- D: knotflow-analyze killed while it writes /analysis
def part_d():
    strace = shutil.which("strace")
    shutil.rmtree(case_dir, ignore_errors=True)
    scene_d = write("d.nml", """&chain shape = 'trefoil', orientation = 'c' /
    &integrator t_end = 3.0 /
    &output directory = '%s', case_name = 'c', frame_interval = 1.0 /
    """ % case_dir)
    r = run([exe, scene_d])
    assert r.returncode == 0, (r.returncode, r.stdout, r.stderr)
    plain = path("plain.h5")
    shutil.copy(case_file, plain)
    ref = path("analysed.h5")
    shutil.copy(plain, ref)
    ANALYZE = [analyze, "--closures", "40"]
    r = run(ANALYZE + [ref])
    assert r.returncode == 0, (r.returncode, r.stdout, r.stderr)


    def kf(p):
        with h5py.File(p, "r") as h:
            return h["analysis/knots/kf"][()], h["analysis/shape/mode"][()]


    kf_ref = kf(ref)
    if strace is None:
        print("D: strace is not installed: the kills at writes are skipped")
    else:
        target = path("d.h5")
        shutil.copy(plain, target)
        traced = run(["strace", "-f", "-o", path("trace.txt"), "-e", "trace=pwrite64,write,rename"]
                     + ANALYZE + [target])
        if traced.returncode != 0:
            print("D: strace cannot trace here: the kills at writes are skipped")
        else:
            with open(path("trace.txt")) as f:
                trace = f.read()
            writes = trace.count("pwrite64(")
            renames = trace.count("rename(")
            points = [("pwrite64", k) for k in range(1, writes + 1)] + [("rename", 1)]
            states = {}
            for i, (call, k) in enumerate(points):
                for start in (plain, ref):   # a first analysis, and one replacing /analysis
                    shutil.copy(start, target)
                    before = md5(target)
                    killed = run(["strace", "-f", "-o", os.devnull, "-e", "trace=%s" % call, "-e",
                                  "inject=%s:signal=KILL:when=%d" % (call, k)] + ANALYZE + ["--force", target])
                    assert killed.returncode in (-9, 137), (call, k, killed.returncode, killed.stderr[-300:])
                    now = md5(target)
                    if now == before:
                        states["untouched"] = states.get("untouched", 0) + 1
                    else:
                        assert np.array_equal(kf(target)[0], kf_ref[0]), (call, k, "neither the old file nor the new")
                        states["analysed"] = states.get("analysed", 0) + 1
                    force = ["--force"] if (i % 2) else []
                    again = run(ANALYZE + force + [target])
                    assert again.returncode == 0, (call, k, force, again.stdout, again.stderr)
                    got = kf(target)
                    assert np.array_equal(got[0], kf_ref[0]) and np.array_equal(got[1], kf_ref[1]), (call, k)
            print("D: knotflow-analyze killed at each of its %d HDF5 writes (pwrite64) and at its rename (%d in "
                  "a run), from an unanalysed and an analysed file: the file was then %s; every rerun "
                  "(--force or not) wrote the whole /analysis"
                  % (writes, renames, ", ".join("%s %d times" % kv for kv in sorted(states.items()))))


def part_s():
    def scene(name):
        return write(name + ".nml", """&chain shape = 'trefoil', orientation = 'c' /
&integrator t_end = 12.0 /
&output directory = '%s', frame_interval = 1.0, progress_interval = 0.0 /
&sweep bending_a = 1.0, 2.0 /
""" % path(name))

    def frames(name):
        out = {}
        for case in ("A1.00", "A2.00"):
            with h5py.File(path(name, case + ".h5"), "r") as h:
                status = h.attrs["status"]
                status = status.decode() if isinstance(status, bytes) else status
                out[case] = (status, h["frames/time"][()], h["frames/positions"][()])
        return out

    r = run([exe, scene("stop_ref")])
    assert r.returncode == 0, (r.returncode, r.stdout, r.stderr)
    reference = frames("stop_ref")
    for name, signals in (("stop_term", [signal.SIGTERM]), ("stop_int", [signal.SIGINT]),
                          ("stop_twice", [signal.SIGTERM, signal.SIGTERM])):
        sc = scene(name)
        p = subprocess.Popen([exe, sc], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                             env=ENV, cwd=work)
        lines, n = [], 0
        for line in p.stdout:
            lines.append(line)
            if ": t = " in line:
                n += 1
                if n == 3:
                    for sig in signals:
                        p.send_signal(sig)
        p.wait(timeout=120)
        out = "".join(lines)
        assert p.returncode == 75, (name, p.returncode, out)
        if len(signals) == 1:
            word = "SIGTERM" if signals[0] == signal.SIGTERM else "SIGINT"
            assert ("knotflow: stopped by %s: 1 case(s) stopped after their last frame (checkpoint "
                    "written), 1 not started; run the same command again to go on (exit status 75)"
                    % word) in out, out
            assert "case A1.00 stopped: stopped by %s at t = " % word in out, out
            with open(path(name, "summary.txt")) as f:
                assert [ln.split()[3] for ln in f if not ln.startswith("#")] == ["stopped", "stopped"]
        r = run([exe, sc])
        assert r.returncode == 0, (name, r.returncode, r.stdout, r.stderr)
        assert "case A1.00: resuming at t = " in r.stdout, r.stdout
        got = frames(name)
        for case, (status, t, pos) in reference.items():
            assert got[case][0] == "finished", (name, case, got[case][0])
            assert np.array_equal(got[case][1], t) and np.array_equal(got[case][2], pos), (name, case)
    print("S: SIGTERM, SIGINT, and two SIGTERMs: exit status 75 with a closing line; the rerun "
          "resumes and ends equal to the uninterrupted run bit for bit")


def part_r():
    d = path("rewritten")
    os.makedirs(d)
    sc = write("r.nml", """&chain shape = 'trefoil', orientation = 'c' /
&integrator t_end = 3.0 /
&output directory = '%s', case_name = 'c', frame_interval = 1.0 /
""" % d)
    r = run([exe, sc])
    assert r.returncode == 0, (r.returncode, r.stdout, r.stderr)
    f = os.path.join(d, "c.h5")
    ANALYZE = [analyze, "--closures", "40"]
    r = run(ANALYZE + [f])
    assert r.returncode == 0 and "4 frames (4 new)" in r.stdout, (r.stdout, r.stderr)
    with h5py.File(f, "r+") as h:
        old_kf = h["analysis/knots/kf"][()]
        pos = h["frames/positions"]
        n = pos.shape[1]
        line = np.zeros((n, 3))
        line[:, 0] = np.arange(n, dtype=float)
        pos[2] = line
    r = run(ANALYZE + [f])
    assert r.returncode == 0, (r.stdout, r.stderr)
    assert "k_f stored for 1 frame(s) whose time or positions changed since: computed again" in r.stdout, r.stdout
    assert "4 frames (1 new)" in r.stdout, r.stdout
    with h5py.File(f, "r") as h:
        kf_reused = h["analysis/knots/kf"][()]
    g = path("rewritten_force.h5")
    shutil.copy(f, g)
    r = run(ANALYZE + ["--force", g])
    assert r.returncode == 0, (r.stdout, r.stderr)
    with h5py.File(g, "r") as h:
        kf_scratch = h["analysis/knots/kf"][()]
    assert old_kf[2] > 0 and kf_reused[2] == 0.0, (old_kf, kf_reused)
    assert np.array_equal(kf_reused, kf_scratch), (kf_reused, kf_scratch)
    print("R: a frame rewritten after its analysis: its stored k_f (%.3g) dropped and computed again "
          "(%.3g, as from scratch); the other 3 frames reused" % (old_kf[2], kf_reused[2]))


for letter in parts:
    {"A": part_a, "C": part_c, "D": part_d, "E": part_e, "R": part_r, "S": part_s}[letter]()
print("check_writers: all passed")
