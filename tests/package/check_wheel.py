"""The knotflow wheel: `pip wheel` of the source tree (pyproject.toml, scikit-build-core driving
the project's CMake) gives a wheel whose package loads the library it carries.

    python3 check_wheel.py SOURCE_DIR WORK_DIR BUILD_LIBRARY

Builds the wheel into WORK_DIR/dist (pip fetches scikit-build-core and fypp from the package
index into an isolated build environment), unpacks it into WORK_DIR/site, and runs a mobility
there with no KNOTFLOW_LIBRARY: the library must be the wheel's own, and the matrix equal bit
for bit to the one of BUILD_LIBRARY (this build's). Exit status 0 ok, 1 failure.
"""

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

SNIPPET = """
import sys
import numpy as np
import knotflow, knotflow._library as L
r = np.array([[0.0, 0.0, 0.0], [1.05, 0.0, 0.0], [1.6, 0.9, 0.2], [0.3, 1.4, -0.6]])
print(L.loaded_path().resolve())
sys.stdout.write(knotflow.mobility(r).tobytes().hex() + "\\n")
"""


def mobility_run(site: str | None, library: str | None) -> list[str]:
    dropped = ("KNOTFLOW_LIBRARY", "LD_LIBRARY_PATH", "PYTHONPATH")
    env = {k: v for k, v in os.environ.items() if k not in dropped}
    if site:
        env["PYTHONPATH"] = site
    if library:
        env["KNOTFLOW_LIBRARY"] = library
    done = subprocess.run([sys.executable, "-c", SNIPPET], capture_output=True, text=True, env=env,
                          cwd="/", check=False)
    if done.returncode != 0:
        raise SystemExit(f"FAIL: the mobility run failed: {done.stderr}")
    return done.stdout.split("\n")[:2]


def main(source: str, work: str, build_library: str) -> int:
    shutil.rmtree(work, ignore_errors=True)
    dist, site = Path(work) / "dist", Path(work) / "site"
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", source, "--no-deps", "-w", str(dist)],
                          capture_output=True, text=True, check=False)
    if done.returncode != 0:
        print(done.stdout[-4000:], done.stderr[-4000:])
        print("FAIL: pip wheel failed")
        return 1
    wheels = sorted(dist.glob("knotflow-*.whl"))
    if len(wheels) != 1:
        print(f"FAIL: expected one knotflow wheel in {dist}, found {wheels}")
        return 1
    with zipfile.ZipFile(wheels[0]) as z:
        names = set(z.namelist())
        z.extractall(site)
    for needed in ("knotflow/__init__.py", "knotflow/_library.py", "knotflow/libknotflow_capi.so"):
        if needed not in names:
            print(f"FAIL: {wheels[0].name} has no {needed}")
            return 1
    path, matrix = mobility_run(str(site), None)
    if Path(path) != (site / "knotflow" / "libknotflow_capi.so").resolve():
        print(f"FAIL: the wheel's package loaded {path}, not its own library")
        return 1
    _, expected = mobility_run(str(site), build_library)
    if matrix != expected:
        print("FAIL: the wheel's mobility differs from this build's")
        return 1
    print(f"ok: {wheels[0].name} ({wheels[0].stat().st_size} bytes) loads its own library; "
          "mobility equal to this build's")
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
