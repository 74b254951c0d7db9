"""The serial build: configure knotflow with -DKNOTFLOW_WITH_MPI=OFF and -DKNOTFLOW_WITH_OPENMP=OFF
into a temporary directory, build the library and `knotflow` only (-j2), and check that
  - the build prints no compiler warning and the program links neither MPI nor OpenMP (libgomp);
  - `knotflow SCENE.nml` (no mpirun) runs every case of a 2-case sweep in one process;
  - its trajectories are the same, frame by frame and bit for bit, as those of the MPI build's
    knotflow on 2 ranks for the same scene (same compiler and flags; one BLAS thread each).
Usage: check_serial_build.py CMAKE SOURCE_DIR BUILD_TYPE FORTRAN_COMPILER GENERATOR WITH_FFTW
                             MPIEXEC "MPIEXEC_FLAGS" MPI_KNOTFLOW WORK_DIR FYPP
(FYPP: the fypp the main build uses to generate kf_h5.f90, passed on as -DKNOTFLOW_FYPP.)
"""
import json
import os
import shlex
import shutil
import subprocess
import sys
import time

import h5py
import numpy as np

(cmake, source, build_type, fortran, generator, with_fftw, mpiexec, flags, mpi_exe,
 work, fypp) = sys.argv[1:12]
flags = shlex.split(flags)
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
build = os.path.join(work, "build")
env = dict(os.environ, OPENBLAS_NUM_THREADS="1")


def run(cmd, **kw):
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, **kw)
    assert p.returncode == 0, "%s failed (%d):\n%s\n%s" % (cmd, p.returncode, p.stdout, p.stderr)
    return p


t0 = time.time()
run([cmake, "-S", source, "-B", build, "-G", generator, "-DKNOTFLOW_WITH_MPI=OFF",
     "-DKNOTFLOW_WITH_OPENMP=OFF", "-DKNOTFLOW_BUILD_TESTS=OFF", "-DCMAKE_BUILD_TYPE=" + build_type,
     "-DCMAKE_Fortran_COMPILER=" + fortran, "-DKNOTFLOW_WITH_FFTW=" + with_fftw,
     "-DKNOTFLOW_FYPP=" + fypp])
out = run([cmake, "--build", build, "-j", "2", "--target", "knotflow"])
log = out.stdout + out.stderr
assert "Warning" not in log and "warning:" not in log, "compiler warnings in the serial build:\n" + log
serial_exe = os.path.join(build, "bin", "knotflow")
print("serial build: %.1f s" % (time.time() - t0))
ldd = shutil.which("ldd")
if ldd:
    libs = run([ldd, serial_exe]).stdout
    assert "libmpi" not in libs, "the serial knotflow links MPI:\n" + libs
    assert "libgomp" not in libs, "the knotflow built without OpenMP links libgomp:\n" + libs
version = run([serial_exe, "--version"]).stdout
assert version.startswith("knotflow "), version


def scene(name):
    path = os.path.join(work, name + ".nml")
    with open(path, "w") as f:
        f.write("""&chain shape = 'straight', n_beads = 8 /
&forces spring_k = 500.0, bending_a = 1.0 /
&hydro model = 'rpy' /
&integrator t_end = 3.0 /
&output directory = '%s', frame_interval = 0.5, progress_interval = 0.0 /
&sweep bending_a = 0.5, 2.0 /
""" % os.path.join(work, name))
    return path


serial = run([serial_exe, scene("serial")], timeout=300)
assert "on 1 rank(s)" in serial.stdout, serial.stdout
parallel = run([mpiexec, "-n", "2"] + flags + [mpi_exe, scene("mpi")], timeout=300)
summary = json.load(open(os.path.join(work, "serial", "summary.json")))
cases = [c["case"] for c in summary["cases"]]
assert len(cases) == 2 and all(c["status"] == "finished" and c["rank"] == 0 for c in summary["cases"]), summary
for name in cases:
    with h5py.File(os.path.join(work, "serial", name + ".h5")) as s, \
            h5py.File(os.path.join(work, "mpi", name + ".h5")) as m:
        assert s.attrs["status"] in (b"finished", "finished")
        ts, tm = s["frames/time"][:], m["frames/time"][:]
        rs, rm = s["frames/positions"][:], m["frames/positions"][:]
        assert abs(ts[-1] - 3.0) < 1e-12 and len(ts) == 7, ts
        # the chain moved in the flow (identical trajectories of a chain at rest would prove little)
        assert np.abs(rs[-1] - rs[0]).max() > 1e-3
        assert np.array_equal(ts, tm), (ts, tm)
        assert np.array_equal(rs, rm), "case %s: max |serial - MPI| = %g" % (name, np.abs(rs - rm).max())
print("serial knotflow: %d cases in one process, trajectories identical to the MPI build's (%.1f s in all)"
      % (len(cases), time.time() - t0))
